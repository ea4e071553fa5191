"""The ``creep`` law's friction solved with the dynamics (eq. C1 of :class:`~alpes_dyn.model.friction.Creep`).

The friction tau_f = clip(a (qdd + b qd), -F_s, F_s) depends on the acceleration it produces: M qdd = r - tau_f
(r every torque but the dry friction's). MuJoCo solves it as one Huber cost per joint; here a few solves of the
same size as the dynamics' find each joint's state (in the band or sliding) and the force:

1. every joint with dry friction in its band (s = 1);
2. (M + diag(s a)) qdd = r - s a b qd - (1 - s) c, each joint's band force a (qdd + b qd): where its |.| < F_s the
   joint is in its band (s = 1), else it slides (s = 0) at c = F_s sign(.); step 2 again (:data:`STAGES` solves in
   all), tau_f = s a (qdd + b qd) + (1 - s) c of the last, clipped to F_s.

Where every joint is in its band the first solve is exact; the next correct a joint in its band coupled (through M)
to one that slides (an active set: exact once the state stops changing).
"""

from __future__ import annotations

from typing import Any

import casadi as cs

from .tree_sparsity import block_solve

__all__ = ["STAGES", "band_inertia", "creep_friction"]

STAGES = 3
"""Solves of the joints' state (in the band or sliding): the first with every joint in its band, each next with the
state its predecessor's forces give (module docstring)."""


def band_inertia(M0: cs.SX, kappa: Any) -> cs.SX:
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
    return kappa / cs.vertcat(*[block_solve(M0, e[:, j])[j] for j in range(n)])


def creep_friction(M: cs.SX, r: cs.SX, v: cs.SX, coulomb: Any, a: cs.SX, rate: Any) -> cs.SX:
    """The dry friction tau_f (n,), N m, of eq. C1 with M qdd = r - tau_f (module docstring).

    Parameters
    ----------
    M : casadi.SX
        (n, n) the inertia matrix at q, kg m^2.
    r : casadi.SX
        (n,) every torque on the joints but the dry friction's (input, bias, springs, viscous), N m.
    v : casadi.SX
        (n,) the joints' velocities, rad/s.
    coulomb : casadi.SX or casadi.DM
        (n,) F_s, N m (0: no dry friction on that joint).
    a : casadi.SX
        (n,) the band's added inertia (:func:`band_inertia`), kg m^2.
    rate : float or casadi scalar
        The band's rate b, 1/s.

    Returns
    -------
    casadi.SX
        (n,) tau_f, N m (the friction torque opposing the motion: subtracted from r).
    """
    s, c = cs.DM.ones(a.shape[0]), cs.DM.zeros(a.shape[0])  # every joint in its band first
    for _ in range(STAGES):
        sa = s * a
        qdd = block_solve(M + cs.diag(sa), r - sa * rate * v - (1 - s) * c)
        band = a * (qdd + rate * v)  # each joint's force were it in its band
        f = sa * (qdd + rate * v) + (1 - s) * c
        s, c = cs.fabs(band) < coulomb, coulomb * cs.sign(band)  # a joint without dry friction: never in a band
    return cs.fmin(cs.fmax(f, -coulomb), coulomb)
