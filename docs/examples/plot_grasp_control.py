"""
The hand grasping a cylinder, each finger holding its force
===========================================================

The whole hand in MuJoCo (the MJCF exported by :func:`alpes_dyn.mjcf.mjcf_string` with the
``"cylinder"`` scene: a fixed cylinder across the fingers, in front of the palm), each finger's
motor driven by its own force loop (:class:`alpes_dyn.control.ForceController`) on its fingertip's
FlexiForce reading, sampled at 1 kHz with noise and quantisation as in
:class:`alpes_dyn.control.ControlScenario`. The four fingers are asked for different forces, which
change at t = 2 s.

The loop per finger is the baseline PI (``"pi"``): the observer and the model-based feedforward of
the ``"sensor"`` controller are defined for one finger (``finger3``, see ``alpes-dyn control``). The
thumb's ab/adduction motor holds 60 degrees with a PD loop on its encoder; with the parameter file's
assumed thumb dimensions its tip does not reach this cylinder, so its flexion motor stays off.
"""

import matplotlib.pyplot as plt
import mujoco
import numpy as np

import alpes_dyn as ad
from alpes_dyn.control import ForceController
from alpes_dyn.mjcf import CYLINDER, joint_permutation, load_mujoco, mjcf_string

params = ad.load_params()
hand = ad.Model.alpes("hand", params=params)
mj = load_mujoco(mjcf_string("hand", params, scene="cylinder", friction=True, timestep=2.5e-4))
data = mujoco.MjData(mj)
fingers = list(params.finger_names)
dt, substeps, T = 1e-3, 4, 3.0
N = int(T / dt)
t = dt * np.arange(N)
targets = {"index": (0.3, 0.4), "middle": (0.4, 0.2), "ring": (0.2, 0.35), "little": (0.25, 0.3)}
ref = {f: np.where(t < 2.0, a, b) for f, (a, b) in targets.items()}
# a slow approach (12 mN m/s): the fingers reach the cylinder at about 25 mN m, without a hard impact
loops = {f: ForceController("pi", hand, np.array([0.0, 0.0, 1.0]), dt, params.tau_max, approach_rate=0.012)
         for f in fingers}
act = {name: mj.actuator(name).id for name in fingers + ["thumb", "thumb_abduction"]}
abd_q = mj.joint("thumb_abd").qposadr[0]
abd_v = mj.joint("thumb_abd").dofadr[0]
rng = np.random.default_rng(0)
F = {f: np.empty(N) for f in fingers}
tau = {f: np.empty(N) for f in fingers}
for k in range(N):
    for f in fingers:
        true = float(data.sensor(f"flexiforce_{f}").data[0])
        meas = max(0.0, round((true + 0.005 * rng.standard_normal()) / (4.4 / 1024)) * (4.4 / 1024))
        F[f][k] = true
        tau[f][k] = loops[f].update(float(ref[f][k]), meas, None)
        data.ctrl[act[f]] = tau[f][k]
    e = np.radians(60.0) - data.qpos[abd_q]
    data.ctrl[act["thumb_abduction"]] = np.clip(0.2 * e - 0.01 * data.qvel[abd_v], -params.tau_max, params.tau_max)
    data.ctrl[act["thumb"]] = 0.0
    for _ in range(substeps):
        mujoco.mj_step(mj, data)

for f in fingers:
    late = t >= T - 0.2
    print(f"{f:7s} asked {targets[f][1]:.2f} N, holds {np.mean(F[f][late]):.3f} N over the last 200 ms")

# %%
# Force traces
# ------------
# Palm up, a finger lifting its own weight on its springs snaps forward once its motor torque passes
# about 23 mN m (gravity's torque falls as the finger rises): the fingertips hit the cylinder and
# chatter on it for a fraction of a second (the spikes, clipped here at 1 N), then each loop settles
# on its reference and follows its change at t = 2 s.
fig, axes = plt.subplots(2, 1, figsize=(8.0, 5.6), sharex=True, layout="constrained")
for i, f in enumerate(fingers):
    axes[0].plot(t, ref[f], "--", color=f"C{i}", lw=1.0)
    axes[0].plot(t, F[f], color=f"C{i}", lw=1.2, label=f)
    axes[1].plot(t, tau[f], color=f"C{i}", lw=1.0)
axes[0].set_ylabel("fingertip force [N]")
axes[0].set_ylim(0.0, 1.0)
axes[0].legend(ncol=4, fontsize=8)
axes[1].axhline(params.tau_max, color="gray", ls=":", lw=0.8)
axes[1].set_ylabel("motor torque [N m]")
axes[1].set_xlabel("time [s]")
fig.suptitle("Four force loops on one hand (dashed: references)")

# %%
# The grasp, drawn from the kinematics
# ------------------------------------
# The final joint angles from MuJoCo, drawn with the library's forward kinematics
# (:meth:`alpes_dyn.Model.fingertip_position` on every phalanx frame): a side view (x, z).
perm = joint_permutation(mj, hand.joint_names)
q = data.qpos[perm].copy()
fig, ax = plt.subplots(figsize=(5.0, 4.2), layout="constrained")
import pinocchio as pin  # noqa: E402

pin.framesForwardKinematics(hand.pin_model, hand.pin_data, q)
for i, f in enumerate(fingers + ["thumb"]):
    names = [f"{f}_p{j}" for j in (1, 2, 3) if hand.pin_model.existFrame(f"{f}_p{j}")] + [f"{f}_tip"]
    pts = np.array([hand.pin_data.oMf[hand.pin_model.getFrameId(nm)].translation for nm in names])
    ax.plot(pts[:, 0], pts[:, 2], "-o", color=f"C{i}", lw=3, ms=3, label=f)
c = CYLINDER
ax.add_patch(plt.Circle((c["center"][0], c["center"][2]), c["radius"], color="0.7", alpha=0.6))
ax.plot([-0.045, 0.045], [-0.012, -0.012], color="0.4", lw=8, solid_capstyle="butt")
ax.set_aspect("equal")
ax.set_xlabel("x [m]")
ax.set_ylabel("z [m]")
ax.legend(fontsize=8, loc="upper left")
ax.set_title("final grasp, side view")
plt.show()
