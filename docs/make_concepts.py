"""Draw the four pictures of the concepts page (``docs/user-guide/concepts.rst``) into ``docs/_static``:

* ``concept_model.png``: finger3 as the model sees it, its links, centres of mass, springs and the tendon, the
  lengths and the transmission ratio read from the shipped parameter file;
* ``concept_transmission.png``: one motor, one tendon over three joint pulleys: q_m = S q, Gamma = S^T tau_m;
* ``concept_fit.png``: multiple shooting: the record cut into intervals, each simulated from its own start, the
  defects closed as the fit converges;
* ``concept_observer.png``: the observer's loop: predict with the model, correct with the encoder.

Schematics (no measurement), drawn with matplotlib. Run from the repository's root:

    python docs/make_concepts.py
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle, FancyArrowPatch, FancyBboxPatch  # noqa: E402

import alpes_dyn as ad  # noqa: E402

OUT = Path(__file__).resolve().parent / "_static"
SIZE = (6.4, 3.2)


def _save(fig, name: str) -> None:
    fig.savefig(OUT / name, dpi=110, bbox_inches="tight")
    plt.close(fig)


def model_picture() -> None:
    """finger3 at a bent pose: links (L_i), centres of mass (s_i, m_i), springs K_i, the tendon along the joints."""
    p = ad.load_params()
    L, s = np.asarray(p.finger.L), np.asarray(p.finger.s)
    q = np.radians([25.0, 35.0, 30.0])
    ang = np.cumsum(-q)
    joints = np.vstack([[0.0, 0.0], np.cumsum(np.c_[L * np.cos(ang), L * np.sin(ang)], axis=0)])
    fig, ax = plt.subplots(figsize=SIZE)
    ax.add_patch(FancyBboxPatch((-0.03, -0.012), 0.025, 0.024, boxstyle="round,pad=0.002", color="0.75"))
    ax.text(-0.0175, -0.02, "palm", ha="center", fontsize=8)
    for i in range(3):
        a, b = joints[i], joints[i + 1]
        ax.plot(*np.c_[a, b], lw=7, color="#8fb3d9", solid_capstyle="round", zorder=1)
        com = a + s[i] / L[i] * (b - a)
        ax.plot(*com, "o", ms=7, color="k", zorder=3)
        ax.annotate(f"m{i + 1}", com, xytext=(8, -2), textcoords="offset points", fontsize=8)
        ax.add_patch(Circle(a, 0.0025, color="#d98f8f", zorder=2))
        ax.annotate(f"q{i + 1}, K{i + 1}", a, xytext=(-44, -4), textcoords="offset points", fontsize=8,
                    color="#a33")
        mid = (a + b) / 2
        ax.annotate(f"L{i + 1}", mid, xytext=(6, 8), textcoords="offset points", fontsize=8, color="#357")
    off = np.array([0.0, -0.006])
    ax.plot(*(joints[:-1] + off).T, "--", color="#444", lw=1)
    ax.annotate("tendon (moment arm r on each joint)", joints[1] + off, xytext=(10, -30),
                textcoords="offset points", fontsize=8, arrowprops={"arrowstyle": "->", "lw": 0.6})
    ax.text(joints[-1][0], joints[-1][1] - 0.012, "tip: force F (FlexiForce)", fontsize=8, ha="center")
    ax.set_title("The model: A(q) q'' + C(q, q') q' + G(q) + friction = S^T tau_m + J^T F", fontsize=9, pad=14)
    ax.set_aspect("equal")
    ax.axis("off")
    _save(fig, "concept_model.png")


def transmission_picture() -> None:
    """One motor pulley r_m, three joint pulleys r: the tendon's length change r sum(q) is the motor's r_m q_m."""
    r_m = ad.load_params().r_m
    ratio = ad.Model.alpes("finger3").transmission.S[0]
    fig, ax = plt.subplots(figsize=SIZE)
    ax.add_patch(Circle((0.0, 0.0), 0.35, fill=False, lw=2, color="#357"))
    ax.text(0.0, -1.0, f"motor + encoder\nr_m = {r_m * 1e3:g} mm\nangle q_m, torque tau_m", ha="center",
            fontsize=8)
    for i, x in enumerate((2.0, 3.2, 4.4)):
        ax.add_patch(Circle((x, 0.0), 0.25, fill=False, lw=2, color="#a33"))
        ax.text(x, -0.75, f"joint {i + 1}\nq{i + 1}", ha="center", fontsize=8)
    ax.plot([0.0, 4.4], [0.35, 0.25], color="#444", lw=1.2)
    ax.plot([0.0, 4.4], [-0.35, -0.25], color="#444", lw=1.2)
    ax.text(2.2, 0.75, f"q_m = S q,  S = r / r_m [1 1 1] = {np.array2string(ratio, precision=3)}\n"
            "Gamma = S^T tau_m: every joint gets r / r_m times the motor torque", ha="center", fontsize=8)
    ax.set_xlim(-0.8, 5.0)
    ax.set_ylim(-1.5, 1.3)
    ax.set_aspect("equal")
    ax.axis("off")
    ax.set_title("The transmission: one tendon, one motor, several joints", fontsize=9)
    _save(fig, "concept_transmission.png")


def fit_picture() -> None:
    """A recorded encoder signal; the model simulated from a start per interval: defects at the cuts before the
    fit (wrong parameters), none after."""
    t = np.linspace(0.0, 0.6, 601)
    rec = 0.3 * np.sin(2 * np.pi * 2.1 * t) + 0.12 * np.sin(2 * np.pi * 5.3 * t + 0.7)
    rng = np.random.default_rng(0)
    y = rec + 0.01 * rng.standard_normal(t.size)
    fig, axes = plt.subplots(1, 2, figsize=SIZE, sharey=True)
    for ax, scale, title in ((axes[0], 1.35, "start: wrong parameters"), (axes[1], 1.0, "converged")):
        ax.plot(t, y, ".", ms=1.5, color="0.6", label="recorded encoder")
        for k in range(6):
            seg = (t >= 0.1 * k) & (t <= 0.1 * (k + 1))
            ts = t[seg]
            model = rec[seg][0] + scale * (rec[seg] - rec[seg][0])
            ax.plot(ts, model, lw=1.6, color="#357", label="model, per interval" if k == 0 else None)
            ax.axvline(0.1 * k, color="0.85", lw=0.8)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("t [s]", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0].set_ylabel("encoder [rad]", fontsize=8)
    axes[0].legend(fontsize=7, loc="lower left")
    fig.suptitle("The fit: multiple shooting, parameters and interval starts fitted together", fontsize=9)
    _save(fig, "concept_fit.png")


def observer_picture() -> None:
    """The loop of an EKF: the model predicts the joints from the motor torque; the encoder corrects them."""
    fig, ax = plt.subplots(figsize=SIZE)
    boxes = {"hand": (0.2, 1.6, "the hand\n(joints q unmeasured)"),
             "predict": (2.6, 1.6, "predict\nx' = f(x, u)\nwith the model"),
             "correct": (2.6, 0.2, "correct\nwith y - h(x)\n(Kalman gain)"),
             "out": (5.0, 0.2, "q-hat and its\ncovariance P")}
    for x, yb, text in boxes.values():
        ax.add_patch(FancyBboxPatch((x, yb), 1.7, 0.9, boxstyle="round,pad=0.05", fc="#eef3f8", ec="#357"))
        ax.text(x + 0.85, yb + 0.45, text, ha="center", va="center", fontsize=8)

    def arrow(a, b, text, dx=0.0, dy=0.12):
        ax.add_patch(FancyArrowPatch(a, b, arrowstyle="->", mutation_scale=10, lw=1))
        ax.text((a[0] + b[0]) / 2 + dx, (a[1] + b[1]) / 2 + dy, text, fontsize=7, ha="center")

    arrow((1.9, 2.05), (2.6, 2.05), "u: motor torque")
    arrow((1.05, 1.6), (2.6, 0.65), "y: encoder", dx=-0.6, dy=-0.15)
    arrow((3.45, 1.6), (3.45, 1.1), "prior", dx=0.35, dy=0.0)
    arrow((4.3, 0.65), (5.0, 0.65), "")
    ax.add_patch(FancyArrowPatch((4.3, 0.9), (4.3, 2.05), connectionstyle="arc3,rad=0.6", arrowstyle="->",
                                 mutation_scale=10, lw=1, ls="--"))
    ax.text(4.95, 1.55, "next sample", fontsize=7)
    ax.set_xlim(0, 7)
    ax.set_ylim(0, 2.8)
    ax.axis("off")
    ax.set_title("The observer: the joints estimated from the motor's encoder and torque", fontsize=9)
    _save(fig, "concept_observer.png")


def main() -> None:
    OUT.mkdir(exist_ok=True)
    model_picture()
    transmission_picture()
    fit_picture()
    observer_picture()


if __name__ == "__main__":
    main()
