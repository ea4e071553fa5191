"""Figures of the closed loops (PNG, written whole or not at all; matplotlib): a finger's force, motor torque and
joints (:func:`plot_control`), the hand's forces per chain and motor torques (:func:`plot_hand_control`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..fileio import atomic_path
from .finger_loop import ControlResult
from .hand_loop import HandControlResult


def _save_figure(fig: Any, plt: Any, path: str) -> None:
    """Lay ``fig`` out and write it to ``path`` (PNG, whole or not at all); close it."""
    fig.tight_layout()
    try:
        with atomic_path(path, "--plot") as tmp:
            fig.savefig(tmp, dpi=110)
    finally:
        plt.close(fig)


def plot_hand_control(result: HandControlResult, path: str) -> None:
    """Write a figure (PNG): per chain, the F_z reference and MuJoCo's force; the motor torques. Needs matplotlib.

    Parameters
    ----------
    result : HandControlResult
        The run.
    path : str
        The PNG file."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("--plot: matplotlib is not installed (pip install matplotlib)") from None
    n = len(result.chains)
    fig, axes = plt.subplots(n + 1, 1, figsize=(9, 1.6 * (n + 1) + 0.8), sharex=True)
    for i, (ax, (c, r)) in enumerate(zip(axes, result.chains.items())):
        ax.plot(r.t, r.F_ref, "k--", lw=1.0)
        ax.plot(r.t, r.F_true, color=f"C{i}", lw=1.0)
        ax.set_ylim(0.0, 1.5 * float(np.max(r.F_ref)))
        ax.set_ylabel(f"{c}\nF_z [N]")
        axes[-1].plot(r.t, r.tau_cmd, color=f"C{i}", lw=0.8, label=c)
    axes[0].set_title(f"the hand on the cylinder, {result.scenario.controller} loops (dashed: references)", fontsize=9)
    axes[-1].axhline(next(iter(result.chains.values())).tau_max, color="gray", ls=":", lw=0.8)
    axes[-1].set_ylabel("tau_m [N m]")
    axes[-1].set_xlabel("time [s]")
    axes[-1].legend(loc="upper left", fontsize=7, ncol=n)
    _save_figure(fig, plt, path)


def plot_control(result: ControlResult, path: str) -> None:
    """Write a figure (PNG): F_z reference, MuJoCo's and the fed-back force; motor torque; joints true and
    estimated (degrees). Needs matplotlib.

    Parameters
    ----------
    result : ControlResult
        The run.
    path : str
        The PNG file."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("--plot: matplotlib is not installed (pip install matplotlib)") from None
    r = result
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax = axes[0]
    ax.plot(r.t, r.F_ref, "k--", lw=1.2, label="reference")
    ax.plot(r.t, r.F_hat, color="C1", lw=0.6, alpha=0.7, label="fed back")
    ax.plot(r.t, r.F_true, color="C0", lw=1.2, label="MuJoCo touch sensor")
    ax.set_ylabel("F_z [N]")
    ax.legend(loc="upper right", fontsize=8, ncol=3)
    where = r.scenario.model_name + ("" if r.block is None else f", {r.block.frame}")
    ax.set_title(f"{where}, {r.scenario.controller} controller: force RMSE {r.force_rmse:.3f} N", fontsize=9)
    ax = axes[1]
    ax.plot(r.t, r.tau_cmd, color="C2", lw=1.0, label="command")
    ax.axhline(r.tau_max, color="gray", ls=":", lw=0.8, label="tau_max")
    ax.set_ylabel("tau_m [N m]")
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[2]
    for i, j in enumerate(r.joint_names):
        ax.plot(r.t, np.degrees(r.q_true[:, i]), color=f"C{i}", lw=1.2, label=f"{j} true")
        if np.isfinite(r.q_hat[:, i]).any():
            ax.plot(r.t, np.degrees(r.q_hat[:, i]), "--", color=f"C{i}", lw=1.0, label=f"{j} EKF")
    ax.set_ylabel("q [deg]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right", fontsize=8, ncol=2)
    _save_figure(fig, plt, path)
