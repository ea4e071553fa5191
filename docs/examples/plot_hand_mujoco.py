"""
The hand on MuJoCo, with what a real hand has
=============================================

"Identifying the hand, one chain at a time" fits data from the library's own simulator, whose
structure is exactly the fitted model's. A real hand is not the model. Here two of the hand's five
chains -- the index (the four fingers share its structure) and the thumb (its ab/adduction and its
two flexion joints) -- are each a plant we did not write: the chain exported to MuJoCo
(:func:`~alpes_dyn.control.plants.mujoco_recording`: joint stops on, RK4 at 0.1 ms, the hand's
encoder and torque sensors at 1 kHz) -- with every effect of a real tendon-driven hand at once
(:func:`~alpes_dyn.studies.realism.cases`, ``"all"``):

* stick-slip dry friction (MuJoCo's ``frictionloss``, a stiff constraint: real stick phases);
* a series-elastic, pull-only cable with the motor's rotor on its own joint (the cable stretching by
  3 % of the tendon's travel under the experiment's mean tension; the rotor-on-cable mode near 200 Hz);
* the palm tilted 3 degrees in the finger's plane, which the recording does not say;
* the torque constant 5 % off (the recorded torque is 1.05 times the true one) and the encoder's
  zero 4 counts off.

The true hand is the shipped one with every chain's springs, masses and friction drawn +-20 % per
link (seed 5). For each of the two chains, :func:`~alpes_dyn.studies.realism.realism_case` records the
documented identification experiment on the plant, fits it as ``alpes-dyn identify`` does by default
(``--effects auto``: the tendon's compliance and the palm's tilt, then the stick-slip law and the
rotor where the fit's adequacy check asks for them; :func:`~alpes_dyn.estimation.identification.effects.fit_effects`)
from the nominal file, and runs the EKF (as ``alpes-dyn estimate --data``) on a fresh run of the plant
-- a torque the fit never saw -- with the identified file, and with the *true* file of the rigid model
(exact springs and masses, but neither the cable, the tilt nor the offset). The page fits two chains to
keep the documentation's build within its budget (each chain's rounds and observer checks take minutes
of processor time); ``benchmarks/realism.py --chains index,middle,ring,little,thumb`` prints the rows of
all five (the same draw: the middle, ring and little fingers' rows are the index's kind), with the rigid
model's fit beside.

The first run compiles the fit's sensitivity code for each model structure met (a few seconds each
on a quiet machine); the times printed are this build's, wall clock.
"""

import tempfile
import time
import warnings
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from alpes_dyn.model.stops import JointRangeWarning
from alpes_dyn.studies.realism import cases, hand_plant, realism_case, rig_design, tendon_stiffness

SEED = 5
warnings.simplefilter("ignore", JointRangeWarning)  # the design's check on our simulator; MuJoCo has stops
design = rig_design("level")  # the documented experiment, palm up
k_t, c_t, cable = tendon_stiffness(design)
print(f"cable k_t = {k_t:.3g} N/m, c_t = {c_t:.3g} N s/m, rotor mode {cable['rotor_mode_Hz']:.0f} Hz")
effects = cases(k_t, c_t)["all"]

rows = {}
folder = Path(tempfile.mkdtemp())
CHAINS = ("index", "thumb")  # two of the five (load_params().chain_names): a finger and the thumb
for chain in CHAINS:
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # each fit's verdict is in its row, printed below
        rows[chain] = realism_case("all", effects, SEED, design, folder, hand_plant(chain), rigid=False)
    print(f"{chain:7s} plant, fits and EKF runs in {time.perf_counter() - t0:.0f} s")

# %%
# What the fits found
# -------------------
# The worst error of each kind of parameter, up to the one common scale that the torque constant
# sets (it scales every parameter together: the encoder cannot see it), the residual against the
# sensor floor (0.58 counts), the effects the fit kept, and its own verdict: "adequate", or flagged
# with the reason. The thumb's ab/adduction sticks on most of its samples: its residual keeps the
# stick phases' colour, and the verdict says so (``identify`` then writes its file only with ``--force``).

print(f"{'chain':7s} {'K %':>5s} {'m %':>5s} {'F_s %':>6s} {'resid':>6s} {'fit s':>6s}  {'effects':31s} verdict")
for chain, r in rows.items():
    e = r["extended"]
    w = e["worst_error_common_scale_pct"]
    why = "" if e["adequacy"]["adequate"] else f" ({e['adequacy']['reasons'][0]})"
    print(f"{chain:7s} {w['K']:5.2f} {w['m']:5.2f} {w['F_s']:6.1f} {e['residual_counts']:6.3f} "
          f"{e['fit_seconds_total']:6.1f}  {'+'.join(e['effects']):31s} {e['verdict']}{why}")

# %%
# The joint observer on a run the fit never saw
# ---------------------------------------------
# RMSE after the first second, per joint: the EKF with the identified file (its fitted tilt and
# encoder zero, the cable's stretch taken off the reading) against the EKF with the true springs
# and masses on the rigid, level model.

labels, after, truefile = [], [], []
for chain, r in rows.items():
    n = len(r["ekf_rmse_deg"])
    names = ["ab/ad", "j1", "j2"][:n] if chain == "thumb" else [f"j{i + 1}" for i in range(n)]
    labels += [f"{chain}\n{j}" for j in names]
    after += r["ekf_rmse_deg"]
    truefile += r["ekf_true_file_rmse_deg"]
print("worst joint, identified file: "
      + ", ".join(f"{c} {max(r['ekf_rmse_deg']):.2f} deg" for c, r in rows.items()))

fig, ax = plt.subplots(figsize=(10.0, 3.4), layout="constrained")
x = np.arange(len(labels))
ax.bar(x - 0.2, truefile, 0.4, color="C3", label="true springs and masses, rigid level model")
ax.bar(x + 0.2, after, 0.4, color="C0", label="identified file (--effects auto)")
ax.axhline(0.5, color="gray", ls="--", lw=0.8, label="0.5 deg")
ax.set_yscale("log")
ax.set_xticks(x, labels, fontsize=7)
ax.set_ylabel("EKF RMSE after 1 s [deg]")
ax.set_title("The hand's chains on MuJoCo with stick-slip, an elastic cable and its rotor, a 3 deg tilt, "
             "K_t 5 % and the encoder 4 counts off", fontsize=9)
ax.legend(fontsize=8)
plt.show()
