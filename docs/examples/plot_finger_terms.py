r"""
A, G and J of a finger over its range
=====================================

The terms of the report's model of one finger (eq. 2.11),

.. math:: \mathbf A(\mathbf q)\ddot{\mathbf q} + \mathbf C(\mathbf q, \dot{\mathbf q})\dot{\mathbf q}
   + \mathbf G(\mathbf q) = \boldsymbol\Gamma + \mathbf J^T \mathbf F,

along a flexion of ``finger3`` from the stretched rest position q = 0 to its upper joint limits
(every joint bent by the same angle s, as a tendon closing a free finger roughly does): the
inertia matrix A(q), the gravity-and-spring torque G(q) under the three spring readings of
eq. 2.14, and the fingertip Jacobian J(q) against the report's closed form of Section 2.2.
"""

import matplotlib.pyplot as plt
import numpy as np

import alpes_dyn as ad
from alpes_dyn.model.reference import report_jacobian

finger = ad.Model.alpes("finger3")
s = np.linspace(0.0, 1.0, 91)[:, None] * finger.upper  # (91, 3): q(s) from 0 to the upper limits
angle = np.degrees(s[:, 0])
print(finger, "upper limits [rad]:", finger.upper)

# %%
# Inertia matrix A(q) (eq. 2.3)
# -----------------------------
# A is symmetric positive definite; its entries depend on q_2 and q_3 only (joint 1 turns the whole
# finger). A_33 is the constant I_3 of Table 1.2, the inertia of phalanx 3 about its own joint.

A = np.array([finger.inertia_matrix(q) for q in s])  # (91, 3, 3) kg m^2
fig, ax = plt.subplots(figsize=(6.4, 4.0))
for i, j in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]:
    ax.plot(angle, 1e6 * A[:, i, j], label=f"$A_{{{i + 1}{j + 1}}}$")
ax.set_xlabel("flexion of every joint, s [deg]")
ax.set_ylabel(r"$A_{ij}$ [$10^{-6}$ kg m$^2$]")
ax.legend(ncol=3, fontsize=8)
ax.set_title("finger3: inertia matrix along the flexion")
fig.tight_layout()
print("A_33 over the range: %.4g .. %.4g kg m^2; Table 1.2 I_3 = %.4g"
      % (A[:, 2, 2].min(), A[:, 2, 2].max(), finger.params.finger.I[2]))
print("smallest eigenvalue of A over the range: %.3g kg m^2" % np.linalg.eigvalsh(A).min())

# %%
# Gravity and springs G(q) (eq. 2.11, 2.14)
# -----------------------------------------
# G holds gravity (along -z: it opposes flexion, largest with the finger stretched) and the return
# springs. The default ``spring="torsional"`` reads the table's K_i in N m/rad as a torsional
# stiffness; ``spring="report"`` reads eq. 2.14 literally and its springs are invisible next to
# gravity, on top of the ``spring="none"`` curves (see the report's known inconsistencies in the
# user guide).

models = {sp: ad.Model.alpes("finger3", spring=sp) for sp in ("none", "report", "torsional")}
styles = {"torsional": dict(ls="-"), "report": dict(ls="--"), "none": dict(ls="-", lw=5, alpha=0.3)}
fig, axes = plt.subplots(1, 3, figsize=(9.6, 3.4), sharey=True)
for sp, m in models.items():
    G = np.array([m.gravity_torque(q) for q in s])  # (91, 3) N m
    for k, ax in enumerate(axes):
        ax.plot(angle, 1e3 * G[:, k], color=f"C{k}", label=f"spring={sp!r}", **styles[sp])
for k, ax in enumerate(axes):
    ax.set_title(f"$G_{k + 1}$")
    ax.set_xlabel("s [deg]")
    ax.grid(alpha=0.3)
axes[0].set_ylabel("torque [mN m]")
axes[0].legend(fontsize=7)
fig.tight_layout()
q_mid = s[45]
for sp, m in models.items():
    print(f"spring={sp!r:12s} spring torque at s = {angle[45]:.0f} deg: {m.spring_torque(q_mid)} N m")

# %%
# Fingertip Jacobian J(q) (Section 2.2, eq. 2.12)
# -----------------------------------------------
# Lines: Pinocchio (``finger.fingertip_jacobian``); dots: the report's closed form written
# independently in :func:`alpes_dyn.model.reference.report_jacobian`. The y row is zero: the finger
# moves in the x-z plane.

J = np.array([finger.fingertip_jacobian(q) for q in s])  # (91, 3, 3) m
Jr = np.array([report_jacobian(finger.params.finger.L, q) for q in s])
fig, axes = plt.subplots(1, 2, figsize=(9.6, 3.6), sharey=True)
for r, (row, ax) in enumerate(zip((0, 2), axes)):
    for k in range(3):
        ax.plot(angle, 1e3 * J[:, row, k], color=f"C{k}", label=f"column {k + 1} (joint {k + 1})")
        ax.plot(angle[::6], 1e3 * Jr[::6, row, k], "o", ms=4, color=f"C{k}", mfc="none")
    ax.set_title(f"row {'xz'[r]}: $\\partial {'xz'[r]}_{{tip}} / \\partial q_k$")
    ax.set_xlabel("s [deg]")
    ax.grid(alpha=0.3)
axes[0].set_ylabel("[mm/rad]")
axes[0].legend(fontsize=7)
fig.tight_layout()
print("max |J_pinocchio - J_report| over the range: %.2e m" % np.abs(J - Jr).max())
print("max |row y| = %.1e m" % np.abs(J[:, 1, :]).max())
plt.show()
