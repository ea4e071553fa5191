"""The ``creep`` law's friction solved with the dynamics (eq. C1 of :class:`~alpes_dyn.model.friction.Creep`).

The friction tau_f = clip(a (qdd + b qd), -F_s, F_s) depends on the acceleration it produces: M qdd = r - tau_f
(r every torque but the dry friction's). MuJoCo solves it as one Huber cost per joint; its dual is a quadratic
programme in the forces alone, over the box |tau_f| <= F_s:

    minimise 1/2 f^T Q f - c^T f,   Q = M^-1 + diag(1 / a),   c = M^-1 r + b qd,                       (C2)

whose optimum inside the box is a (qdd + b qd) with qdd = M^-1 (r - f) (each joint in its band), on the box's face
F_s sign (each joint sliding). Q is positive definite, so one assignment of the joints with dry friction to
{-F_s, band, +F_s} meets the optimality conditions (the band's forces within the box, each sliding joint's gradient
(Q f - c)_j of the sign that holds it on its face): :func:`creep_friction` writes every assignment (3^k for k joints
with dry friction, each a solve of the band's joints) and keeps the one that does -- exact, where an iteration on
the assignment can cycle and leave a share of an identification experiment's samples off, however many passes
it makes. Beyond :data:`MAX_ENUMERATED` joints with dry friction in
one block of M the assignments are too many; :func:`creep_friction` refuses them (:class:`~alpes_dyn.ModelError`).
"""

from __future__ import annotations

import itertools
from typing import Any

import casadi as cs
import numpy as np

from ..errors import ModelError
from .tree_sparsity import block_solve

__all__ = ["MAX_ENUMERATED", "band_inertia", "creep_friction"]

MAX_ENUMERATED = 4
"""The most joints with dry friction whose assignments :func:`creep_friction` writes (3^4 = 81 solves)."""


def band_inertia(M0: Any, kappa: Any) -> cs.SX:
    """a_j = kappa / (M0^-1)_jj (n,), kg m^2: the band's added inertia of eq. C1.

    Parameters
    ----------
    M0 : casadi.SX
        (n, n) the joints' inertia matrix at the reference pose (q = 0), kg m^2.
    kappa : float or casadi scalar
        The band inertia in units of the joint's own (:data:`~alpes_dyn.model.friction.CREEP_KAPPA`).
    """
    n = M0.shape[0]
    e = cs.DM.eye(n)
    return kappa / cs.vertcat(*[block_solve(cs.SX(M0), e[:, j])[j] for j in range(n)])


def creep_friction(M: cs.SX, r: cs.SX, v: cs.SX, coulomb: Any, a: cs.SX, rate: Any, dry: Any) -> cs.SX:
    """The dry friction tau_f (n,), N m, of eq. C1 with M qdd = r - tau_f: the optimum of eq. C2.

    Parameters
    ----------
    M : casadi.SX
        (n, n) the inertia matrix at q, kg m^2.
    r : casadi.SX
        (n,) every torque on the joints but the dry friction's (input, bias, springs, viscous), N m.
    v : casadi.SX
        (n,) the joints' velocities, rad/s.
    coulomb : casadi.SX or casadi.DM
        (n,) F_s, N m.
    a : casadi.SX
        (n,) the band's added inertia (:func:`band_inertia`), kg m^2.
    rate : float or casadi scalar
        The band's rate b, 1/s.
    dry : array_like of bool
        (n,) the joints with dry friction (the others get none).

    Returns
    -------
    casadi.SX
        (n,) tau_f, N m (the friction torque opposing the motion: subtracted from r).

    Raises
    ------
    ModelError
        More than :data:`MAX_ENUMERATED` joints with dry friction.
    """
    n = M.shape[0]
    D = [int(j) for j in np.flatnonzero(np.asarray(dry, dtype=bool))]
    if len(D) > MAX_ENUMERATED:
        raise ModelError(f"friction.law: the creep law solves at most {MAX_ENUMERATED} joints with dry friction "
                         f"together, the model has {len(D)}")
    if not D:
        return cs.SX.zeros(n)
    e = cs.DM.eye(n)
    Minv = cs.horzcat(*[block_solve(M, e[:, j]) for j in D])  # (n, k): the columns of M^-1 of the dry joints
    Minv_r = block_solve(M, r)
    Q = Minv[D, :] + cs.diag(1.0 / a[D])
    c = Minv_r[D] + rate * v[D]
    Fs = coulomb[D]
    k = len(D)
    out = cs.fmin(cs.fmax(block_solve(Q, c), -Fs), Fs)  # (a rounding tie that meets no assignment: the band's, clipped)
    for signs in reversed(list(itertools.product((0, 1, -1), repeat=k))):  # the all-band assignment checked first
        free = [i for i in range(k) if signs[i] == 0]
        held = [i for i in range(k) if signs[i] != 0]
        f = cs.SX.zeros(k)
        for i in held:
            f[i] = signs[i] * Fs[i]
        ok = 1
        if free:
            rhs = c[free] - (cs.mtimes(Q[free, held], f[held]) if held else 0)
            ff = block_solve(Q[free, free], rhs)
            for m_, i in enumerate(free):
                f[i] = ff[m_]
                ok = cs.logic_and(ok, cs.fabs(ff[m_]) <= Fs[i])
        g = cs.mtimes(Q, f) - c
        for i in held:
            ok = cs.logic_and(ok, signs[i] * g[i] <= 0)
        out = cs.if_else(ok, f, out)
    tau = cs.SX.zeros(n)
    for m_, j in enumerate(D):
        tau[j] = out[m_]
    return tau
