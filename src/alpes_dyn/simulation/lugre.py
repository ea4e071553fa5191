"""Simulation with the LuGre friction (:mod:`alpes_dyn.model.friction`): the state [q; qd; z] stepped by a split step.

The law is stiff twice over: a sliding joint relaxes its bristle at the rate sigma0 |qd| / F_s (eq. L1: 2e4 1/s at
20 rad/s with the default sigma0 and the Alpes F_s), and a stuck joint oscillates on it at sqrt(sigma0 / I), damped
by sigma1 / I. Each step of h seconds (:func:`~alpes_dyn.symbolic.lugre.lugre_substep`) relaxes the bristles
exactly at the step's velocity, then takes one classical RK4 step of [q; qd] with them held: the first stiffness
costs nothing, whatever the speed; :func:`lugre_substeps` takes steps short enough for the second (h lambda <=
:data:`~alpes_dyn.simulation.integrate.RK4_REACH`). :func:`simulate_lugre` rolls a whole input record out in one
CasADi call (``mapaccum`` of the step: no Python loop over the samples).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as cs
import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..model.friction import LuGre, lugre_of
from ..model.robot import Model
from ..symbolic.lugre import lugre_substep
from ..symbolic.statespace import StateSpace
from .integrate import RK4_REACH, _check_dt, _n_known_inputs, as_statespace

__all__ = ["ACCURATE", "lugre_rate_bound", "lugre_substeps", "fit_substeps", "lugre_step_function", "LuGreResult",
           "simulate_lugre"]

def lugre_rate_bound(model: Model, law: LuGre) -> float:
    """lambda, 1/s: the fastest rate of the split step's RK4 part, the larger of the presliding mode's
    sqrt(eig(A^-1 sigma0)) and its damping eig(A^-1 (2 sigma1 + F_v)) (d(sigma1 z')/dqd is at most 2 sigma1 on a
    bristle within its presliding range; A the mass matrix with the rotors, at the joints' mid-range and at q = 0);
    0 without dry friction.

    Parameters
    ----------
    model : alpes_dyn.Model
        The model: its mass matrix with the rotors, its F_s and F_v.
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).

    Returns
    -------
    float
        lambda, 1/s.
    """
    ex = model.extras
    if not np.any(ex.coulomb > 0):
        return 0.0
    lo = np.where(np.isfinite(model.lower) & (np.abs(model.lower) < 1e3), model.lower, 0.0)
    hi = np.where(np.isfinite(model.upper) & (np.abs(model.upper) < 1e3), model.upper, 0.0)
    dry = (ex.coulomb > 0).astype(float)
    rate = 0.0
    for q in (0.5 * (lo + hi), np.zeros(model.n)):  # two configurations
        Li = np.linalg.inv(np.linalg.cholesky(model.inertia_matrix(q)))
        k = float(np.linalg.eigvalsh(Li @ np.diag(law.sigma0 * dry) @ Li.T).max())
        c = float(np.linalg.eigvalsh(Li @ np.diag(2 * law.sigma1 * dry + ex.viscous) @ Li.T).max())
        rate = max(rate, math.sqrt(max(k, 0.0)), c)
    return rate


def lugre_substeps(model: Model, law: LuGre, dt: float, minimum: int = 4) -> int:
    """Split steps per period ``dt`` (s) that keep h lambda <= RK4_REACH on :func:`lugre_rate_bound`; at least
    ``minimum`` (4: a step of 0.25 ms at 1 kHz, the smooth law's).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model: its mass matrix with the rotors, its F_s and F_v.
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).
    dt : float
        The sample period, s.
    minimum : int, optional
        The fewest steps (default 4).

    Returns
    -------
    int
        The split steps per period.
    """
    dt = _check_dt(dt)
    return max(int(minimum), int(math.ceil(dt * lugre_rate_bound(model, law) / RK4_REACH - 1e-9)))


ACCURATE = 2
"""The factor on :func:`lugre_substeps` of the steps a fit or a reference simulation takes: the split step's bristle
error is O(h), and it biases a fitted sigma0 and sigma1 where the plant's steps differ: fitted at fewer steps than
the plant took, they come out well off and the fit reaches the sensor floor only at its iteration cap; at as many
steps as the plant, close, in far fewer iterations. More steps cost the fit time in proportion."""


def fit_substeps(model: Model, dt: float, stiffest: float) -> int:
    """:data:`ACCURATE` times :func:`lugre_substeps` of ``model``'s LuGre law with its sigma0 times ``stiffest``
    (the upper end of a fit's range for it); 1 where the model's law is the smooth one (no bristles).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model (its friction law).
    dt : float
        The sample period, s.
    stiffest : float
        The factor on the law's sigma0 at the upper end of the fit's range (dimensionless).

    Returns
    -------
    int
        The split steps per period.
    """
    law = lugre_of(model)
    return 1 if law is None else ACCURATE * lugre_substeps(model, LuGre(stiffest * law.sigma0, law.sigma1), dt)


def lugre_step_function(ss: StateSpace, law: LuGre, dt: float, substeps: int = 1) -> cs.Function:
    """``step(x (3n,), w (m[+3],)) -> x_next``: ``substeps`` split steps (module docstring) of [q; qd; z] over
    ``dt`` s with the inputs w = [u; F] held (``ss``'s input torque, tip or contacts).

    Parameters
    ----------
    ss : StateSpace
        The system (its input torque, tip or contacts).
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).
    dt : float
        The sample period, s.
    substeps : int, optional
        Split steps per period, 1..1000 (default 1).

    Returns
    -------
    casadi.Function
        ``lugre_step(x, w) -> x_next``.

    Raises
    ------
    InputError
        A bad ``dt`` or ``substeps``.
    """
    dt = _check_dt(dt)
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or not 1 <= substeps <= 1000:
        raise InputError(f"substeps: expected an integer in [1, 1000], got {substeps!r}")
    n = ss.n
    x, w = cs.SX.sym("x", 3 * n), cs.SX.sym("w", _n_known_inputs(ss))

    def torques(q: cs.SX, v: cs.SX) -> tuple[cs.SX, Any]:
        return ss.input_torque(q, w[: ss.n_inputs], v), (w[ss.n_inputs:] if ss.force else None)

    one = cs.Function("one", [x, w], [cs.cse(cs.vertcat(*lugre_substep(ss, law, x[:n], x[n:2 * n], x[2 * n:],
                                                                        torques, dt / int(substeps))))])
    xn = x
    for _ in range(int(substeps)):  # unrolled once, when the step is built
        xn = one(xn, w)
    return cs.Function("lugre_step", [x, w], [xn], ["x", "w"], ["x_next"])


@dataclass
class LuGreResult:
    """A LuGre simulation: t (N+1,) s, q, qd (N+1, n) rad and rad/s, z (N+1, n) rad, the bristles."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    z: np.ndarray


def simulate_lugre(system: Model | StateSpace, x0: Any, inputs: Any, dt: float, law: LuGre | None = None, *,
                   z0: Any = None, substeps: int | None = None, input: str = "joint") -> LuGreResult:
    """Simulate ``system`` with the LuGre law over the input record ``inputs``.

    Parameters
    ----------
    system : Model or StateSpace
        The robot (its springs, F_s and F_v); a Model gets the state space of ``input``.
    x0 : array_like
        (2n,) [q; qd] at t = 0, rad and rad/s.
    inputs : array_like
        (N, m) (or (N,) for m = 1) inputs held over each period: joint torques (N m) or motor torques.
    dt : float
        Sample period, s.
    law : LuGre, optional
        sigma0 and sigma1; default the model's parameter file's (:func:`~alpes_dyn.model.friction.lugre_of`), else
        :class:`LuGre`'s defaults.
    z0 : array_like, optional
        (n,) initial bristle deflections, rad (default 0: unloaded).
    substeps : int, optional
        Split steps per period (default :func:`lugre_substeps`).
    input : str
        ``"joint"`` or ``"motor"``, the state space's input (for a Model).

    Returns
    -------
    LuGreResult

    Raises
    ------
    InputError
        A shape or value of ``x0``, ``z0``, ``inputs`` or ``substeps`` out of place, named.
    """
    ss = as_statespace(system, input=input)
    n, m = ss.n, ss.n_inputs
    law = law if law is not None else (lugre_of(ss.model) or LuGre())
    if not isinstance(law, LuGre):
        raise InputError(f"law: expected a LuGre, got {type(law).__name__}")
    x0 = ss.model.vector(x0, "x0", 2 * n)
    z0 = np.zeros(n) if z0 is None else ss.model.vector(z0, "z0", n)
    U = as_float_array(inputs, "inputs", "an array of inputs")
    U = U[:, None] if U.ndim == 1 and m == 1 else U
    if U.ndim != 2 or U.shape[1] != m or U.shape[0] < 1:
        raise InputError(f"inputs: expected shape (N, {m}), got {U.shape}")
    if not np.isfinite(U).all():
        raise InputError("inputs: contains NaN or inf")
    dt = _check_dt(dt)
    substeps = lugre_substeps(ss.model, law, dt) if substeps is None else substeps
    step = lugre_step_function(ss, law, dt, substeps)
    roll = step.mapaccum("lugre_roll", U.shape[0])
    X = np.array(roll(np.r_[x0, z0], U.T)).T
    X = np.vstack([np.r_[x0, z0], X])
    t = dt * np.arange(U.shape[0] + 1)
    return LuGreResult(t=t, q=X[:, :n], qd=X[:, n:2 * n], z=X[:, 2 * n:])
