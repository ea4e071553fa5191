"""Warm starts of the shooting fit: what a fit leaves to start another from (:class:`ShootingSolution`), the values it
starts from (:func:`start_values`), and the start of a fit again with parameters held, from the first fit's
linearisation (:func:`held_start`, issue 39).

Where a fitted parameter is not identified (:mod:`~alpes_dyn.estimation.identification.bounds`: a tendon compliance
whose 95 % interval reaches past 0, say), :func:`~alpes_dyn.estimation.identification.identification.identify` fits
again with it held. Started from the first fit's values and trajectory with only the held parameter moved, the
other parameters, the torque's line corrections and the trajectory all have to follow it, which the constrained
Gauss-Newton stage takes several iterations of the whole record to do (a sizeable share of a long record's fit).
At the first fit's optimum the move is known to first order: holding the parameters H at rho_H + delta is the
equality-constrained quadratic problem of the last Gauss-Newton step with E' z = delta added, whose solution is

    dz = Z_H (P_HH)^-1 delta,

Z_H the columns of the undamped KKT system's inverse for the parameters H (the variables' rows:
:attr:`~alpes_dyn.estimation.identification.held.ShootingSolution.response`, computed with the covariance at
no extra factorisation) and P_HH their rows of it (the covariance's block, unscaled). :func:`held_start` gives the
fit again that start; its stopping rule, continuity and the line search still decide (the whole fit runs where the
warm start does not converge: :meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.solve`).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ...errors import InputError

__all__ = ["held_start", "ShootingSolution", "start_values"]


@dataclass(frozen=True)
class ShootingSolution:
    """A fit's shooting variables at its end, to start another fit of the same recording from (a warm start):
    ``nodes`` (S, nx) the intervals' start states, ``offs`` (S, no) their torque corrections, ``lines`` (ncg,) the
    whitened line-coefficient corrections, ``samples`` the samples per interval (L) they were cut at, ``drift`` (nd,)
    the drift's knots (counts; empty without one). ``response`` (nz, p): how the optimum moves with each parameter
    held off it, to first order (the undamped KKT system's inverse applied to each parameter's unit vector: the
    variables' part), with ``additive`` (p,) and ``scale`` (p,) how the fit's variables map to the values
    (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.values`); None where not computed
    (:func:`held_start`)."""

    nodes: np.ndarray
    offs: np.ndarray
    lines: np.ndarray
    samples: int
    drift: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    response: np.ndarray | None = None
    additive: np.ndarray | None = None
    scale: np.ndarray | None = None


def start_values(theta0: np.ndarray, names: Sequence[str], additive: np.ndarray,
                 start: Mapping[str, float]) -> np.ndarray:
    """``theta0`` with the values of ``start`` (by parameter name) put in.

    Parameters
    ----------
    theta0 : numpy.ndarray, shape (p,)
        The starting parameters (the model's), each in its own unit.
    names : Sequence[str]
        (p,) the fitted parameters' names, ``theta0``'s order.
    additive : numpy.ndarray, shape (p,)
        bool: the parameters fitted additively (encoder offsets, tilt angles: any finite value), the others by
        their logarithm (a positive value).
    start : Mapping[str, float]
        The starting values by parameter name, in the parameters' units.

    Returns
    -------
    numpy.ndarray, shape (p,)
        A copy of ``theta0`` with ``start``'s values.

    Raises
    ------
    InputError
        ``start`` not a mapping, naming a parameter that is not fitted, or a value that is not a finite number
        (positive unless additive).
    """
    if not isinstance(start, Mapping):
        raise InputError(f"start: expected a mapping of parameter names to values (or an earlier "
                         f"IdentificationResult), got {type(start).__name__}")
    theta = theta0.copy()
    for name, v in start.items():
        if name not in names:
            raise InputError(f"start: {name!r} is not a parameter of this fit (fitted: {', '.join(names)})")
        k = list(names).index(name)
        ok = isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, (bool, np.bool_))
        if not ok or not math.isfinite(float(v)) or (not additive[k] and float(v) <= 0):
            need = "a finite number" if additive[k] else "a finite number > 0"
            raise InputError(f"start: {name} = {v!r}: expected {need}")
        theta[k] = float(v)
    return theta


def held_start(result: Any, held: Mapping[str, float]) -> Any | None:
    """``result`` (an :class:`~alpes_dyn.estimation.identification.fit_result.IdentificationResult`) moved to the
    linearised optimum with the parameters ``held`` (name -> the value each is held at, in its unit) at those
    values: its ``values`` and its ``solution``'s nodes, torque corrections, line corrections and drift moved by dz
    (the module docstring), to start ``identify(..., start=...)`` from. None where the result carries no response
    (:attr:`~alpes_dyn.estimation.identification.held.ShootingSolution.response`), a held value is not
    reachable in the fit's variables (a log-fitted one at or below 0: its bound, not a value), or the move (or a value it
    gives) is not finite.

    Parameters
    ----------
    result : IdentificationResult
        A fit's result, its ``solution`` carrying the optimum's response.
    held : Mapping[str, float]
        The parameters held, name -> the value each is held at, in its unit.

    Returns
    -------
    IdentificationResult or None
        A copy of ``result`` moved (its solution's response dropped), or None as above (also where ``held`` is
        empty).
    """
    sol = getattr(result, "solution", None)
    if sol is None or sol.response is None or not held:
        return None
    names = list(result.names)
    idx = [names.index(n) for n in held]
    v = np.asarray(result.values, dtype=float)
    delta = np.empty(len(idx))
    for j, (k, target) in enumerate(zip(idx, held.values())):  # a loop over the held parameters (one or two)
        if sol.additive[k]:
            delta[j] = (target - v[k]) / sol.scale[k]
        elif target > 0 and v[k] > 0:
            delta[j] = math.log(target / v[k])
        else:
            return None
    Z = sol.response
    nv, p = sol.nodes.size + sol.offs.size, v.size
    try:
        mu = np.linalg.solve(Z[nv + np.asarray(idx)][:, idx], delta)
    except np.linalg.LinAlgError:
        return None
    dz = Z[:, idx] @ mu
    if not np.isfinite(dz).all():
        return None
    drho, dn, ncg = dz[nv:nv + p], dz[:nv], sol.lines.size
    with np.errstate(over="ignore"):  # a log-fitted value moved past float64's range: not a start (None below)
        values = np.where(sol.additive, v + sol.scale * drho, v * np.exp(np.where(sol.additive, 0.0, drho)))
    if not np.isfinite(values).all():
        return None
    nb = sol.nodes.shape[1] + sol.offs.shape[1]
    local = dn.reshape(-1, nb)
    moved = dataclasses.replace(sol, nodes=sol.nodes + local[:, :sol.nodes.shape[1]],
                                offs=sol.offs + local[:, sol.nodes.shape[1]:],
                                lines=sol.lines + dz[nv + p:nv + p + ncg], drift=sol.drift + dz[nv + p + ncg:],
                                response=None)
    return dataclasses.replace(result, values=values, solution=moved)
