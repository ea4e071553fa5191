"""
The hand in a few configurations
================================

The 15-joint model of the Alpes hand (``Model.alpes("hand")``) drawn from its kinematics: for each
configuration q, Pinocchio's forward kinematics gives the placement of every joint and fingertip
frame in the palm frame, and each phalanx is drawn as a segment between them.

Conventions (see :doc:`/user-guide/hand`): the palm frame is at the middle of the palm, x toward
the fingers, z the palm normal toward which the fingers flex; a positive joint angle flexes.
"""

import matplotlib.pyplot as plt
import numpy as np
import pinocchio as pin
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import alpes_dyn as ad

hand = ad.Model.alpes("hand")
print(hand)
print("joints (Pinocchio order):", ", ".join(hand.joint_names))

# %%
# Joint and fingertip positions
# -----------------------------
# ``hand.layout.chains`` lists, for every tendon chain, its joints (proximal first) and its tip
# frame; the thumb also has its ab/adduction joint. ``pin.framesForwardKinematics`` fills
# ``pin_data.oMi`` (joint placements) and ``pin_data.oMf`` (frame placements) for one q.


def chain_points(model: ad.Model, q: np.ndarray) -> dict[str, np.ndarray]:
    """For each chain, the (k, 3) positions (m) of its joints then of its tip, in the palm frame."""
    pm, pd = model.pin_model, model.pin_data
    pin.framesForwardKinematics(pm, pd, q)
    out = {}
    for ch in model.layout.chains:
        joints = ([ch.abduction] if ch.abduction else []) + list(ch.joints)
        pts = [pd.oMi[pm.getJointId(j)].translation for j in joints]
        pts.append(pd.oMf[pm.getFrameId(ch.tip)].translation)
        out[ch.name] = np.array(pts)
    return out


def configuration(model: ad.Model, **angles: float) -> np.ndarray:
    """q from joint angles given by name, e.g. ``index_j1=0.5``; ``index=0.5`` sets the chain's joints."""
    q = np.zeros(model.n)
    for name, value in angles.items():
        for i, joint in enumerate(model.joint_names):
            if joint == name or (joint.startswith(name + "_j")):
                q[i] = value
    return q


p = hand.params
palm_corners = np.array(
    [[-0.045, -0.033, 0.0], [p.finger_xy[3, 0], -0.033, 0.0], [p.finger_xy[0, 0], 0.033, 0.0],
     [p.thumb_xyz[0], p.thumb_xyz[1], 0.0], [-0.045, 0.033, 0.0]]
)  # a drawing of the palm only: the model's palm is a frame without geometry
colors = {"index": "C0", "middle": "C1", "ring": "C2", "little": "C3", "thumb": "C4"}


def draw_hand(ax, model: ad.Model, q: np.ndarray, title: str) -> None:
    """Draw the palm, the phalanges and the joints of ``model`` at ``q`` on a 3D axis."""
    ax.add_collection3d(Poly3DCollection([palm_corners], facecolor="0.85", edgecolor="0.5"))
    for name, pts in chain_points(model, q).items():
        ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], "-", lw=5, color=colors[name], solid_capstyle="round",
                label=name)
        ax.plot(pts[:-1, 0], pts[:-1, 1], pts[:-1, 2], "o", ms=4, color="k")
        ax.plot(pts[-1:, 0], pts[-1:, 1], pts[-1:, 2], "o", ms=5, mfc="w", mec="k")
    ax.set_xlim(-0.05, 0.16)
    ax.set_ylim(-0.08, 0.13)
    ax.set_zlim(-0.02, 0.12)
    ax.set_box_aspect((0.21, 0.21, 0.14))
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    ax.tick_params(labelsize=7)
    ax.view_init(elev=28, azim=-128)
    ax.set_title(title, fontsize=10)


# %%
# A grasp
# -------
# Each finger flexes its three joints through one tendon; here the four fingers close around an
# object and the thumb swings toward them (ab/adduction) and flexes. (``configuration(hand, index=0.55)`` sets the three
# index joints to 0.55 rad.)

grasp = configuration(hand, index=0.55, middle=0.6, ring=0.65, little=0.7, thumb_abd=0.9, thumb=0.6)
fig = plt.figure(figsize=(6.4, 5.2))
ax = fig.add_subplot(projection="3d")
draw_hand(ax, hand, grasp, "grasp")
ax.legend(loc="upper left", fontsize=8)
fig.tight_layout()

tips = {tip: hand.fingertip_position(grasp, tip) for tip in hand.tips}
for tip, xyz in tips.items():
    print(f"{tip:11s} at {np.array2string(1000 * xyz, precision=1)} mm")

# %%
# Four configurations
# -------------------
# Stretched (q = 0, the rest position the springs return to), a pinch of the index and the thumb,
# a closed fist, and the thumb swung toward the fingers by its ab/adduction joint alone (the
# ab/adduction angle turns the thumb about the palm normal, from ``palm.thumb_yaw`` = 60 degrees
# toward the fingers' direction; positive angles close the hand, like the flexion joints).

configs = {
    "rest, q = 0": np.zeros(hand.n),
    "pinch (index and thumb)": configuration(hand, index=0.6, thumb=0.9),
    "fist": configuration(hand, index=1.3, middle=1.35, ring=1.4, little=1.45, thumb=1.2),
    "thumb ab/adduction 90 deg": configuration(hand, thumb_abd=np.pi / 2),
}
fig = plt.figure(figsize=(9.0, 7.6))
for k, (title, q) in enumerate(configs.items()):
    draw_hand(fig.add_subplot(2, 2, k + 1, projection="3d"), hand, q, title)
fig.tight_layout()

# %%
# The fingertip Jacobian of the grasp
# -----------------------------------
# The hand's tip Jacobians are (3, 15): a fingertip moves only with its own chain's joints.

J = hand.fingertip_jacobian(grasp, "index_tip")
moving = [j for j, col in zip(hand.joint_names, np.abs(J).sum(axis=0)) if col > 0]
print("index_tip moves with:", ", ".join(moving))
plt.show()
