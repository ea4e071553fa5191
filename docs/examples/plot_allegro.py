"""
Your own robot: the Allegro hand with tendons
=============================================

Everything the library does for the Alpes hand works on any fixed-base URDF given a transmission
spec (:mod:`alpes_dyn.model.spec`). Here the Allegro hand of ``example-robot-data`` -- 16 joints, four
fingers -- is made tendon-driven by the spec shipped with the package
(``alpes_dyn/data/allegro_hand_spec.toml``): one tendon per finger over its three flexion joints
(ratios 2.0, 1.6, 1.2 from the palm out), one motor per ab/adduction joint, return springs on every
joint, rotor inertia and a little viscous friction. The same from the command line::

    alpes-dyn observability --model .../allegro_right_hand.urdf --spec allegro_hand_spec.toml \\
        --input motor --output encoder
"""

import matplotlib.pyplot as plt
import numpy as np

import alpes_dyn as ad
from alpes_dyn.estimation import make_observer
from alpes_dyn.model.stops import JointStops
from alpes_dyn.simulation import simulate
from alpes_dyn.model.spec import TransmissionSpec, example_spec_path
from alpes_dyn.symbolic.statespace import StateSpace

urdf = ad.example_robot_urdf("allegro_hand", "allegro_right_hand")
# The shipped spec's springs rest at 0 rad but two: the thumb's first joint (range [15, 80] deg) and joint_14.0,
# whose rest angles put the hand's rest with the motors off inside its ranges (the rule in the file's header).
spec = TransmissionSpec.from_toml(example_spec_path("allegro_hand").read_text(encoding="utf-8"))
hand = ad.Model.from_urdf_file(urdf, spec)
print(hand)
print("joints (Pinocchio's order):", ", ".join(hand.joint_names))
print("motors:", ", ".join(hand.motor_names))
print("S (motor x joint ratios), index tendon row:",
      {j: hand.transmission.S[0, hand.joint_index(j)] for j in ("joint_1.0", "joint_2.0", "joint_3.0")})

# %%
# Observability from the encoders
# -------------------------------
# Motor torques in, the 8 encoders out (4 tendons, 4 ab/adduction joints), 32 states. Each finger
# is a part of the tree (its own block of the mass matrix) and is analysed on its own too.

ss = StateSpace(hand, input="motor", output="encoder")
print(ad.check_observability(ss, points=6).to_text())

# %%
# Rest state, linearisation and python-control
# --------------------------------------------
# A grasp torque on every tendon; the rest state balances it against gravity and the springs, and
# the linearisation there goes straight to python-control (if installed).

u_grasp = np.array([0.04, 0.04, 0.04, 0.03, 0.0, 0.0, 0.0, 0.02])  # N m: tendons, then ab/adduction
x_eq = ss.equilibrium(u_grasp)
for j in ("joint_1.0", "joint_2.0", "joint_3.0"):
    print(f"  {j}: {np.degrees(x_eq[hand.joint_index(j)]):6.1f} deg at rest")
A, B, C, D = ss.linearize(x_eq, u_grasp)
lam = np.linalg.eigvals(A)
print(f"linearised: A {A.shape}, B {B.shape}, C {C.shape}; slowest mode {np.abs(lam).min():.1f} rad/s, "
      f"fastest {np.abs(lam).max():.0f} rad/s, largest real part {lam.real.max():.3f} 1/s")
try:
    sys_d = ss.to_control(x_eq, u_grasp, dt=1e-3)
    print(f"control.StateSpace: {sys_d.nstates} states, inputs {sys_d.input_labels[:2]}..., dt = {sys_d.dt} s")
except ad.ModelError as exc:  # python-control is an optional extra
    print(exc)

# %%
# Simulation and an observer
# --------------------------
# The hand starts still with its fingers stretched, each joint at 0 or, where 0 is out of its range (the
# thumb's first joint turns from 15 deg), just inside it; the tendons pull with a grasp torque plus a
# slow sine. An extended Kalman filter that sees only the 8 (quantised) encoders and the motor
# torques estimates all 16 joint angles. It starts away from the truth: every joint guessed 0.3 rad
# (17 deg) more flexed than it is. The first encoder sample corrects each tendon's sum of joints; how that sum splits
# over the joints comes from the dynamics, within about 0.1 s. The simulated hand has its joint stops (the index's
# first joint swings onto its stop near 0.34 s); the EKF's model has none, and its error grows a little there.

dt, T = 2e-3, 0.6
t = dt * np.arange(int(round(T / dt)))
U = u_grasp * (1 + 0.3 * np.sin(2 * np.pi * 2.0 * t))[:, None]
q_start = np.clip(np.zeros(16), hand.lower + 0.05, hand.upper - 0.05)  # rad, inside every joint's range
sim = simulate(ss, np.r_[q_start, np.zeros(16)], U, duration=T, dt=dt, stops=JointStops.of(hand))  # the joint stops
step = 2 * np.pi / hand.transmission.counts_per_rev
Y = hand.transmission.quantize(sim.y)
ekf = make_observer("ekf", ss, dt, process_noise=[1e-10] * 16 + [1e-4] * 16,
                    measurement_noise=[step**2 / 12] * 8)
z0 = np.r_[q_start + 0.3, np.zeros(16)]  # the guess: every joint 0.3 rad more flexed, still
est = ekf.run(z0, [0.3**2] * 16 + [1.0] * 16, U, Y)
err = np.degrees(np.abs(est.z[:, :16] - sim.x[:, :16])).max(axis=1)  # the worst joint at each sample
for k in (0, int(round(0.1 / dt)), len(sim.t) - 1):
    print(f"EKF: largest joint error at t = {sim.t[k]:.2f} s: {err[k]:.3f} deg (started {np.degrees(0.3):.1f} deg off)")

fig, axes = plt.subplots(1, 2, figsize=(9.0, 3.6), layout="constrained")
for k, j in enumerate(("joint_1.0", "joint_2.0", "joint_3.0")):
    i = hand.joint_index(j)
    axes[0].plot(sim.t, np.degrees(sim.x[:, i]), color=f"C{k}", lw=1.4, label=f"{j} true")
    axes[0].plot(sim.t, np.degrees(est.z[:, i]), color=f"C{k}", lw=1.0, ls="--", label=f"{j} EKF")
    axes[0].plot(0.0, np.degrees(z0[i]), "o", color=f"C{k}", mfc="none")  # the EKF's starting guess
axes[0].set_xlabel("time [s]")
axes[0].set_ylabel("index finger joint [deg]")
axes[0].legend(fontsize=7, ncol=2)
tips = [hand.fingertip_position(x[:16], "link_3.0_tip") for x in sim.x]
tips = np.array(tips)
axes[1].plot(1e3 * tips[:, 0], 1e3 * tips[:, 2], color="k")
axes[1].set_xlabel("index tip x [mm]")
axes[1].set_ylabel("index tip z [mm]")
axes[1].set_aspect("equal", adjustable="datalim")
fig.suptitle("Allegro hand with tendons: the index finger from its encoder alone")
