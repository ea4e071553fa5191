"""
The hand grasping a cylinder, each finger holding its force
===========================================================

The whole hand in MuJoCo (the MJCF of :func:`alpes_dyn.model.mjcf.mjcf_string` with the ``"cylinder"`` scene: a
fixed, frictionless cylinder, :data:`alpes_dyn.model.mjcf.CYLINDER`), palm down, each of its five flexion motors
driven by the ``"sensor"`` force loop of ``alpes-dyn control``: its own EKF estimates the chain's joints
q̂ from the motor encoder and the motor torque, a feedforward holds the reference through the static balance at
q̂ (eq. 2.11, J(q̂)ᵀ n with n the cylinder's normal at the estimated fingertip) and a PI acts on the measured
FlexiForce F_z. Everything is sampled at 1 kHz with the estimation scenario's quantisation and noise
(:class:`alpes_dyn.control.hand_loop.HandControlScenario`).

A finger's loop uses the ``finger3`` model: each finger of the hand is a ``finger3`` translated on the
palm (the tests check the hand's G(q), tip positions and Jacobians against the chain models). The thumb's
flexion loop uses a two-phalanx model with the parameter file's thumb values; a PD on the ab/adduction
encoder swings the thumb from beside the palm to 35 degrees, where its pad meets the cylinder.
:func:`alpes_dyn.control.hand_loop.run_hand_control` does all of this; here it runs once with the ``"sensor"``
loops and once with the baseline PI on F_z alone (``"pi"``), on the same noise draws.
"""

import ctypes.util
import os
import sys

if sys.platform.startswith("linux") and not os.environ.get("DISPLAY") and ctypes.util.find_library("EGL"):
    os.environ.setdefault("MUJOCO_GL", "egl")  # MuJoCo's offscreen renderer without a display (set before import)

import matplotlib.pyplot as plt
import numpy as np

import alpes_dyn as ad
from alpes_dyn.control import HAND_LEVELS, run_hand_control

res = run_hand_control("sensor")
base = run_hand_control("pi")
chains = list(res.chains)
print(f"{res.scenario.duration:g} s simulated in {res.wall_s:.1f} s (sensor loops), {base.wall_s:.1f} s (PI)")
print("chain    asked [N]  held [N]  steady-state  overshoot  rise [ms]  q-hat RMSE [deg] | PI: overshoot  "
      "rise [ms]  RMSE [N] vs sensor")
for row, b in zip(res.table(), base.table()):
    print(f"{row['chain']:7s}  {row['F_ref']:9.2f}  {row['F_held']:8.3f}  {100 * row['steady_state_error']:10.2f} %"
          f"  {100 * row['overshoot']:7.1f} %  {1e3 * row['rise_time_s']:9.0f}  {row['q_rmse_deg']:16.2f} |"
          f"  {100 * b['overshoot']:9.1f} %  {1e3 * b['rise_time_s']:9.0f}  {b['force_rmse']:.4f} vs "
          f"{row['force_rmse']:.4f}")

# %%
# Force traces
# ------------
# Each fingertip's force measured by MuJoCo's touch sensor (noise-free) against its reference (dashed), the
# sensor loop in colour and the PI baseline in grey. The fingers flex with gravity under a motor torque
# rising at 15 mN m/s and reach the cylinder at about 1.3 s (the thumb, shorter, at 0.6 s), bounce on it
# briefly, then each loop settles on its level; every reference steps up at 2.5 s.
fig, axes = plt.subplots(len(chains), 1, figsize=(8.0, 8.5), sharex=True, layout="constrained")
for i, (ax, c) in enumerate(zip(axes, chains)):
    r, b = res.chains[c], base.chains[c]
    ax.plot(b.t, b.F_true, color="0.6", lw=0.8, label="PI baseline")
    ax.plot(r.t, r.F_true, color=f"C{i}", lw=1.0, label="sensor loop")
    ax.plot(r.t, r.F_ref, "k--", lw=1.0, label="reference")
    ax.set_ylim(0.0, 1.3 * max(HAND_LEVELS[c]))
    ax.set_ylabel(f"{c}\nF_z [N]")
axes[0].legend(ncol=3, fontsize=8, loc="lower right")
axes[-1].set_xlabel("time [s]")
fig.suptitle("Five force loops on one hand: MuJoCo's fingertip forces")

# %%
# The observers during the grasp
# ------------------------------
# The true joint angles (MuJoCo, solid) and each chain's EKF estimate from its motor encoder, motor torque
# and FlexiForce (dashed). Before contact an encoder only sees the sum of a chain's joints (weighted by the
# pulleys); the springs and gravity make the split observable, and from contact on the measured force enters
# the EKF as a known input.
fig, axes = plt.subplots(len(chains), 1, figsize=(8.0, 8.5), sharex=True, layout="constrained")
for ax, c in zip(axes, chains):
    r = res.chains[c]
    for j, name in enumerate(r.joint_names):
        ax.plot(r.t, np.degrees(r.q_true[:, j]), color=f"C{j}", lw=1.2, label=f"{name.split('_')[1]} true")
        ax.plot(r.t, np.degrees(r.q_hat[:, j]), "--", color=f"C{j}", lw=1.0, label=f"{name.split('_')[1]} EKF")
    ax.set_ylabel(f"{c}\nq [deg]")
    ax.text(0.99, 0.06, f"RMSE in contact: {', '.join(f'{e:.2f}' for e in r.q_rmse_deg)} deg",
            transform=ax.transAxes, ha="right", fontsize=8)
axes[0].legend(ncol=6, fontsize=7, loc="upper left")
axes[-1].set_xlabel("time [s]")
fig.suptitle("Joint angles: MuJoCo (solid) and each chain's EKF (dashed)")

# %%
# The grasp
# ---------
# The final state of the sensor run, rendered by MuJoCo's offscreen renderer (EGL without a display) and
# turned so that the palm is on top; where no OpenGL context can be made, the same state is drawn from the
# library's kinematics instead.
import mujoco  # noqa: E402

from alpes_dyn.model.mjcf import CYLINDER, joint_permutation, load_mujoco, mjcf_string, palm_down_params  # noqa: E402

params = palm_down_params(ad.load_params())
mj = load_mujoco(mjcf_string("hand", params, scene="cylinder"))
data = mujoco.MjData(mj)
data.qpos[mj.joint("thumb_abd").qposadr[0]] = res.q_abduction[-1]
for c in chains:
    data.qpos[joint_permutation(mj, res.chains[c].joint_names)] = res.chains[c].q_true[-1]
mujoco.mj_forward(mj, data)
try:
    renderer = mujoco.Renderer(mj, 420, 560)
    images = []
    for azimuth, elevation in ((90.0, 0.0), (140.0, -25.0), (215.0, -30.0)):
        cam = mujoco.MjvCamera()
        cam.lookat[:], cam.distance, cam.azimuth, cam.elevation = (0.03, 0.0, 0.05), 0.22, azimuth, elevation
        renderer.update_scene(data, camera=cam)
        images.append(np.rot90(renderer.render(), 2))  # a camera rolled by 180 degrees: the palm on top
    renderer.close()
except Exception as exc:  # no OpenGL here: draw the kinematics
    print(f"MuJoCo's renderer is not available ({type(exc).__name__}); drawing the kinematics")
    images = None
if images is not None:
    fig, axes = plt.subplots(1, 3, figsize=(11.0, 3.0), layout="constrained")
    for ax, im, title in zip(axes, images, ("side view, along the cylinder", "oblique view", "from below the palm")):
        ax.imshow(im)
        ax.set_title(title, fontsize=9)
        ax.axis("off")
    fig.suptitle("The grasp at t = 3.5 s, rendered by MuJoCo")
else:
    hand = ad.Model.alpes("hand", params=params)
    q = data.qpos[joint_permutation(mj, hand.joint_names)].copy()
    fig, ax = plt.subplots(figsize=(5.0, 4.2), layout="constrained")
    for i, c in enumerate(chains):
        names = [f"{c}_p{j}" for j in (1, 2, 3) if hand.pin_model.existFrame(f"{c}_p{j}")] + [f"{c}_tip"]
        pts = np.array([hand.frame_placement(q, nm)[1] for nm in names])
        ax.plot(pts[:, 0], -pts[:, 2], "-o", color=f"C{i}", lw=3, ms=3, label=c)
    ax.add_patch(plt.Circle((CYLINDER["center"][0], -CYLINDER["center"][2]), CYLINDER["radius"], color="0.7"))
    ax.plot([-0.045, 0.045], [0.012, 0.012], color="0.4", lw=8, solid_capstyle="butt")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("-z [m] (palm down)")
    ax.legend(fontsize=8)
    ax.set_title("the grasp at t = 3.5 s, side view")
plt.show()
