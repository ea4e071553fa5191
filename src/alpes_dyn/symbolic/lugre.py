"""The symbolic dynamics with a bristle state per joint: eq. 3.3 with the LuGre friction of
:mod:`alpes_dyn.model.friction` in place of the smooth sign.

The state is x = [q; qd; z] (3n): z (rad) the joints' bristle deflections, and

    z'  = qd - sigma0 |qd| z / F_s                                   (L1, g = F_s)
    qdd = (A + I_a)^-1 (tau + J^T F - C qd - G - k (q - q_rest) - sigma0 z - sigma1 z' - F_v qd)   (eq. 3.3, L2)

the mass matrix solved by :func:`~alpes_dyn.symbolic.dynamics.block_solve` as in the smooth law's forward dynamics.
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as cs
import numpy as np

from ..model.friction import LuGre, lugre_rate, lugre_torque
from .dynamics import block_solve
from .statespace import StateSpace

__all__ = ["lugre_derivatives", "bristle_relaxed", "relax_exactly", "lugre_substep"]


def lugre_derivatives(ss: StateSpace, law: LuGre, q: cs.SX, v: cs.SX, z: cs.SX, tau: cs.SX, F: Any = None
                      ) -> tuple[cs.SX, cs.SX]:
    """(qdd (n,) rad/s^2, z' (n,) rad/s) of the module's equations.

    Parameters
    ----------
    ss : StateSpace
        The system: its model's springs, F_s (g of eq. L1) and F_v; its tip or contacts for ``F``.
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).
    q, v, z : casadi.SX
        (n,) rad, rad/s, rad.
    tau : casadi.SX
        (n,) N m, the joint torques of the inputs (:meth:`~alpes_dyn.symbolic.statespace.StateSpace.input_torque`).
    F : casadi.SX or None
        The contact force(s) of a state space with ``force=True`` (N), else None.
    """
    sym, ex = ss.sym, ss.sym.extras
    zdot = lugre_rate(z, v, ex.coulomb, law.sigma0, cs)
    passive = ex.spring_torque(q, cs) + lugre_torque(z, zdot, v, ex.viscous, law, cs)
    if F is not None and not ss._legacy_force:
        net = sym.net_torque(q, v, tau, passive, F, None, ss.contacts)
    else:
        net = sym.net_torque(q, v, tau, passive, F, ss.tip)
    return block_solve(sym.inertia_matrix(q), net), zdot


def bristle_relaxed(law: LuGre, coulomb: np.ndarray, z: cs.SX, v: cs.SX, h: float) -> cs.SX:
    """z after h seconds of eq. L1 at the velocity v held, exactly: z e^(-a h) + v (1 - e^(-a h)) / a with
    a = sigma0 |v| / F_s (v h where a h is tiny), (n,) rad; unconditionally stable however fast the bristle relaxes
    (a joint sliding at 20 rad/s relaxes it at 2e4 1/s), and a joint without dry friction keeps z = 0.

    Parameters
    ----------
    law : LuGre
        sigma0 (N m/rad).
    coulomb : numpy.ndarray, shape (n,)
        F_s, N m (g of eq. L1; 0: no bristle).
    z : casadi.SX, shape (n,)
        The bristle deflections at the step's start, rad.
    v : casadi.SX, shape (n,)
        The joint velocities held, rad/s.
    h : float
        The step, s.
    """
    Fs = np.asarray(coulomb, dtype=float)
    dry = Fs > 0
    inv = cs.DM(np.where(dry, 1.0 / np.where(dry, Fs, 1.0), 0.0))
    return relax_exactly(z, v, law.sigma0 * cs.fabs(v) * inv, cs.DM(dry.astype(float)), h)


def relax_exactly(z: cs.SX, v: cs.SX, a: cs.SX, dry: cs.DM, h: float) -> cs.SX:
    """z e^(-a h) + v (1 - e^(-a h)) / a, (n,) rad: eq. L1 over h seconds at the velocity v held, relaxing at the
    rate a (n,) 1/s (sigma0 |v| / F_s; symbols where the law's parameters are, e.g. fitted); 0 where ``dry`` (n,)
    is 0 (a joint without a bristle).

    Parameters
    ----------
    z : casadi.SX, shape (n,)
        The bristle deflections at the step's start, rad.
    v : casadi.SX, shape (n,)
        The joint velocities held, rad/s.
    a : casadi.SX, shape (n,)
        The relaxation rates, 1/s.
    dry : casadi.DM, shape (n,)
        1 on a joint with a bristle, 0 elsewhere.
    h : float
        The step, s.
    """
    ah = a * h
    small = ah < 1e-6
    safe = cs.if_else(small, 1.0, ah)
    phi = cs.if_else(small, h * (1.0 - 0.5 * ah), -h * cs.expm1(-safe) / safe)  # (1 - e^(-a h)) / a
    return dry * (z * cs.exp(-ah) + v * phi)


def lugre_substep(ss: StateSpace, law: LuGre, q: cs.SX, v: cs.SX, z: cs.SX,
                  torques: Callable[[cs.SX, cs.SX], tuple[cs.SX, Any]], h: float) -> tuple[cs.SX, cs.SX, cs.SX]:
    """One step of h seconds, split (Lie): the bristles relaxed exactly at the step's velocity
    (:func:`bristle_relaxed`), then one classical RK4 step of [q; qd] with z held at that value (eq. L2's
    sigma1 z' following qd within the step). ``torques(q, v)`` -> (tau (n,) N m, F or None), the inputs' joint
    torques at a stage.

    Parameters
    ----------
    ss : StateSpace
        The system (as :func:`lugre_derivatives`'s).
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).
    q : casadi.SX, shape (n,)
        Joint angles at the step's start, rad.
    v : casadi.SX, shape (n,)
        Joint velocities, rad/s.
    z : casadi.SX, shape (n,)
        Bristle deflections, rad.
    torques : callable
        (q, v) -> (tau (n,) N m, F or None): the inputs' joint torques and contact force at a stage.
    h : float
        The step, s.

    Returns
    -------
    tuple of casadi.SX
        (q+, qd+, z+) after h seconds.
    """
    n = ss.n
    zn = bristle_relaxed(law, ss.sym.extras.coulomb, z, v, h)

    def f(x: cs.SX) -> cs.SX:
        tau, F = torques(x[:n], x[n:])
        qdd, _ = lugre_derivatives(ss, law, x[:n], x[n:], zn, tau, F)
        return cs.vertcat(x[n:], qdd)

    x = cs.vertcat(q, v)
    k1 = f(x)
    k2 = f(x + 0.5 * h * k1)
    k3 = f(x + 0.5 * h * k2)
    k4 = f(x + h * k3)
    xn = x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return xn[:n], xn[n:], zn
