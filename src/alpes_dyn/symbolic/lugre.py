"""The symbolic dynamics with a bristle state per joint: eq. 3.3 with the LuGre friction of
:mod:`alpes_dyn.model.friction` in place of the smooth sign.

The state is x = [q; qd; z] (3n): z (rad) the joints' bristle deflections, and

    z'  = qd - sigma0 |qd| z / F_s                                   (L1, g = F_s)
    qdd = (A + I_a)^-1 (tau + J^T F - C qd - G - k (q - q_rest) - sigma0 z - sigma1 z' - F_v qd)   (eq. 3.3, L2)

the mass matrix solved by :func:`~alpes_dyn.symbolic.dynamics.block_solve` as in the smooth law's forward dynamics.
"""

from __future__ import annotations

from typing import Any

import casadi as cs

from ..model.friction import LuGre, lugre_rate, lugre_torque
from .dynamics import block_solve
from .statespace import StateSpace

__all__ = ["lugre_derivatives"]


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
