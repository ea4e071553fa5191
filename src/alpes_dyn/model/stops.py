"""Joint stops: the mechanical end stops of the joints, and the check that a trajectory stays within them.

The report's model (eq. 2.10) has no joint stop, and neither has the library's default simulation:
nothing in eq. 2.10 keeps a joint within its range, so a finger driven hard enough turns past it
(0.02 N m on each hand motor for 1 s turns ``thumb_abd``, which has no spring, by more than 100 rad).
Two tools:

* :class:`JointStops` -- a stop modelled as a stiff unilateral spring-damper (a rubber end stop):
  outside [lower, upper] by a penetration p > 0 the joint feels ``max(0, k p - d v_in)`` back
  toward the range (v_in the velocity further into the stop), nothing inside. Smooth enough for
  RK4 and automatic differentiation; the default k = 2 N m/rad (50 times the stiffest finger
  spring: 1.4 degrees of penetration under 0.05 N m) and d = 4e-3 N m s/rad keep the stop's own
  mode (sqrt(k / I) ~ 1300 rad/s on a distal phalanx) stable for RK4 steps up to about 1 ms.
  Pass it to :func:`~alpes_dyn.simulation.integrate.simulate` as ``stops=``. Rigid stops with an impact law
  (MuJoCo's constraint solver) are what the MJCF export (:mod:`alpes_dyn.model.mjcf`) gives.
* :func:`check_range` -- whether a trajectory leaves the joint range; :func:`simulate` calls it
  when no stop is modelled and warns (:class:`JointRangeWarning`) or raises, per ``joint_range=``.

Why off by default: the report's model has no stop; the observers and the estimation scenario use
eq. 2.10 as it is, and a stiff stop makes the dynamics stiff (smaller RK4 steps).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..errors import AlpesDynWarning, InputError

__all__ = ["JointStops", "JointRangeWarning", "check_range", "JOINT_RANGE_MODES"]

JOINT_RANGE_MODES: tuple[str, ...] = ("warn", "error", "ignore")


class JointRangeWarning(AlpesDynWarning):
    """A simulated joint left its range [lower, upper] while no joint stop was modelled."""


@dataclass(frozen=True)
class JointStops:
    """Unilateral spring-damper end stops, per joint (arrays (n,), rad; k N m/rad; d N m s/rad)."""

    lower: np.ndarray
    upper: np.ndarray
    stiffness: float = 2.0
    damping: float = 4e-3

    @classmethod
    def of(cls, model: Any, stiffness: float = 2.0, damping: float = 4e-3) -> "JointStops":
        """Stops at a :class:`~alpes_dyn.Model`'s URDF limits (joints without finite limits get none)."""
        if not (np.isfinite(stiffness) and stiffness > 0):
            raise InputError(f"stiffness: expected a positive number of N m/rad, got {stiffness!r}")
        if not (np.isfinite(damping) and damping >= 0):
            raise InputError(f"damping: expected a number >= 0 of N m s/rad, got {damping!r}")
        lo, hi = model.lower, model.upper
        lo = np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.inf)
        hi = np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.inf)
        return cls(lo, hi, float(stiffness), float(damping))

    def torque(self, q: Any, v: Any, xp: Any = np) -> Any:
        """Stop torques (n,), N m, for joint angles q and velocities v (numpy arrays or CasADi columns)."""
        lo = np.where(np.isfinite(self.lower), self.lower, -1e30)
        hi = np.where(np.isfinite(self.upper), self.upper, 1e30)
        if xp is not np:
            lo, hi = xp.DM(lo), xp.DM(hi)
        k, d = self.stiffness, self.damping
        p_lo = xp.fmax(lo - q, 0)
        p_hi = xp.fmax(q - hi, 0)
        push_up = xp.fmax(k * p_lo - d * v * (p_lo > 0), 0)    # below the lower stop: pushes toward +q
        push_down = xp.fmax(k * p_hi + d * v * (p_hi > 0), 0)  # above the upper stop: pushes toward -q
        return push_up - push_down


def check_range(t: np.ndarray, q: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str],
                mode: str = "warn", tol: float = 1e-9) -> str:
    """Whether the trajectory q (N+1, n) at times t leaves [lower - tol, upper + tol].

    Returns "" if it stays within, else a one-line message naming the first joint to leave, when and
    how far; ``mode`` ``"warn"`` also issues a :class:`JointRangeWarning`, ``"error"`` raises
    :class:`~alpes_dyn.InputError`, ``"ignore"`` only returns the message.
    """
    if mode not in JOINT_RANGE_MODES:
        raise InputError(f"joint_range: expected one of {', '.join(JOINT_RANGE_MODES)}, got {mode!r}")
    out = (q < lower - tol) | (q > upper + tol)
    if not out.any():
        return ""
    k, j = np.argwhere(out)[0]
    worst = np.max(np.maximum(lower - q, q - upper), axis=0)
    jw = int(np.argmax(worst))
    msg = (f"joint {names[j]!r} left its range [{lower[j]:g}, {upper[j]:g}] rad at t = {t[k]:g} s (q = {q[k, j]:.4g} "
           f"rad) and no joint stop is modelled (worst: {names[jw]!r} {worst[jw]:.3g} rad outside; pass "
           "stops=JointStops.of(model) to simulate them)")
    if mode == "error":
        raise InputError(msg)
    if mode == "warn":
        warnings.warn(msg, JointRangeWarning, stacklevel=3)
    return msg
