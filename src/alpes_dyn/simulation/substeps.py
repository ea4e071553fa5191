"""How many RK4 steps a sample period needs on a model with friction: the friction's fastest decay rate near rest
(:func:`friction_rate`, eq. 2.6-2.7 smoothed, the tendons' sheath friction included) and the substeps that keep RK4
within its real-axis stability (:func:`stable_substeps`)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..model.robot import Model
from ..model.transmission import capstan_loss, capstan_velocity
from .held_inputs import _check_dt

__all__ = ["RK4_REACH", "friction_rate", "stable_substeps"]

RK4_REACH = 2.5
"""h lambda kept below this on the friction's fastest decay rate lambda (RK4's real-axis stability ends at 2.78)."""


def friction_rate(model: Model, tension: Any = None) -> float:
    """lambda, 1/s: the fastest velocity decay the friction imposes near rest, the largest eigenvalue of
    A(q)^-1 D with D = diag(F_s / v_s + F_v) (the smooth sign's slope at qd = 0, eq. 2.6-2.7) and A the mass matrix
    with the rotor inertia, over q at the joint ranges' lower ends, middles and upper ends (0 without friction).
    ``tension``: the motors' largest torques |tau_m| (N m, (m,) or one for all; None: not counted): the tendons'
    sheath friction then adds its slope S^T diag((1 - exp(-mu theta)) |tau_m| / v_c) S
    (:func:`~alpes_dyn.model.transmission.capstan_torque`), which grows with the tension (with a strong sheath
    friction, the steps that suit the finger without it leave the simulation well off a fine-step reference).

    Parameters
    ----------
    model : Model
        The model (its extras' friction, its transmission's sheath friction).
    tension : float or array_like, optional
        The motors' largest torques |tau_m|, N m, (m,) or one for all; None (default): the sheath not counted.

    Returns
    -------
    float
        lambda, 1/s (0 without friction).
    """
    ex = model.extras
    D = np.diag(ex.coulomb / ex.smooth_velocity + ex.viscous)
    tr = model.transmission
    if tension is not None and tr is not None and tr.has_capstan:
        T = np.broadcast_to(np.abs(np.asarray(tension, dtype=float)), (tr.n_motors,))
        slope = capstan_loss(tr.capstan) * T / capstan_velocity(tr.S, ex.smooth_velocity)
        D = D + tr.S.T @ (slope[:, None] * tr.S)
    if not np.any(D > 0):
        return 0.0
    lo = np.where(np.isfinite(model.lower) & (np.abs(model.lower) < 1e3), model.lower, 0.0)
    hi = np.where(np.isfinite(model.upper) & (np.abs(model.upper) < 1e3), model.upper, 0.0)
    rate = 0.0
    for q in (lo, 0.5 * (lo + hi), hi, np.zeros(model.n)):  # a loop over four configurations
        A = model.inertia_matrix(q)
        L = np.linalg.cholesky(A)
        Li = np.linalg.inv(L)
        rate = max(rate, float(np.linalg.eigvalsh(Li @ D @ Li.T).max()))  # A^-1 D, symmetrised
    return rate


def stable_substeps(model: Model, dt: float, minimum: int = 4, tension: Any = None) -> int:
    """RK4 steps per sample period ``dt`` (s) for the model's friction: at least ``minimum`` (4, what the smooth
    law at v_s = 0.1 rad/s needs at 1 kHz) and enough that h lambda <= :data:`RK4_REACH` (:func:`friction_rate`,
    with the tendons' sheath friction at ``tension``, the motors' largest torques, N m, where given).
    A sharper sign (v_s = 0.02 rad/s, the stick-slip law of :data:`~alpes_dyn.model.extras.STICTION_VELOCITY`) on
    finger3 at 1 kHz: 15.

    Parameters
    ----------
    model : Model
        The model.
    dt : float
        The sample period, s (> 0).
    minimum : int
        The fewest steps (default 4).
    tension : float or array_like, optional
        The motors' largest torques, N m, for the sheath friction (:func:`friction_rate`).

    Returns
    -------
    int

    Raises
    ------
    InputError
        ``dt`` not a positive finite number of seconds.
    """
    dt = _check_dt(dt)
    return max(int(minimum), int(math.ceil(dt * friction_rate(model, tension) / RK4_REACH - 1e-9)))
