"""The split step of :mod:`~alpes_dyn.simulation.lugre` with its sensitivities, for the fits: the LuGre law's
bristles z in the state x = [q; qd; z] (3n) of :class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`, F_s,
sigma0 and sigma1 among its parameters (:class:`~alpes_dyn.symbolic.parametric.ParametricDynamics`).

One substep of h seconds is two maps, each differentiated exactly:

    R: z <- z e^(-a h) + qd (1 - e^(-a h)) / a,   a = sigma0 |qd| / F_s    (eq. L1 at qd held, exactly)
    P: one classical RK4 step of [q; qd; z]' = [qd; qdd(q, qd, z); 0]       (eq. 3.3 with L2, z held)

P is :func:`~alpes_dyn.simulation.integrate.rk4_expression` of the law's right-hand side with z' = 0, the same
operations as :func:`~alpes_dyn.symbolic.lugre.lugre_substep`'s RK4 of [q; qd] with z held; its sensitivities the
variational RK4 (:func:`~alpes_dyn.simulation.sensitivity.variational_rk4_step`, exact for the discrete step). R's
are its Jacobian: X <- R_x X + [0 | R_p]. The bristles' stiffness costs nothing (R is exact at any a h); the
presliding mode sqrt(sigma0 / I) sets the substeps (:func:`~alpes_dyn.simulation.lugre.lugre_substeps`).
"""

from __future__ import annotations

from typing import Callable

import casadi as cs

from ..symbolic.lugre import relax_exactly
from ..symbolic.parametric import ParametricDynamics
from .variational import _rk4_calling, variational_rk4_step

__all__ = ["lugre_steps"]


def _then(first: cs.Function, second: cs.Function, name: str) -> cs.Function:
    """``second(first(s, w), w)`` as an MX function (each body once in the generated C)."""
    s = cs.MX.sym("s", first.size1_in(0))
    w = cs.MX.sym("w", first.size1_in(1))
    return cs.Function(name, [s, w], [second(first(s, w), w)])


def lugre_steps(pd: ParametricDynamics, x: cs.SX, w: cs.SX, tau: cs.SX, h: float
                ) -> tuple[cs.Function, Callable[[cs.SX], cs.Function]]:
    """(the plain substep ``(x, w) -> x+``, ``sens_of(directions)``: the substep with the sensitivities
    ``([x; vec X], w) -> [x+; vec X+]``, X = dx/d(x_0, directions) (3n x (3n + d), column-major)).

    Parameters
    ----------
    pd : ParametricDynamics
        The dynamics with the LuGre law (``pd.lugre`` not None).
    x : casadi.SX
        (3n,) the state [q; qd; z], rad, rad/s, rad.
    w : casadi.SX
        The step's inputs (the torque, gravity, theta, the corrections), held over the step.
    tau : casadi.SX
        (n,) the joint torques of the inputs, N m (an expression of ``x`` and ``w``).
    h : float
        The substep, s.
    """
    n = pd.n
    q, v, z = x[:n], x[n:2 * n], x[2 * n:]
    a, dry = pd.bristle_terms(v, pd.theta)
    relaxed = cs.vertcat(q, v, relax_exactly(z, v, a, dry, h))
    rhs = cs.vertcat(v, pd.forward_dynamics(q, v, tau, pd.theta, pd.g, z=z), cs.SX.zeros(n))
    plain = _then(cs.Function("relax", [x, w], [cs.cse(relaxed)]),
                  _rk4_calling(cs.Function("rhs", [x, w], [cs.cse(rhs)]), h, "step"), "lugre_step")

    def sens_of(directions: cs.SX) -> cs.Function:
        nx = 3 * n
        X = cs.SX.sym("X", nx, nx + directions.numel())
        dX = (cs.mtimes(cs.jacobian(relaxed, x), X)
              + cs.horzcat(cs.SX.zeros(nx, nx), cs.jacobian(relaxed, directions)))
        relax = cs.Function("relax_sens", [cs.vertcat(x, cs.vec(X)), w], [cs.cse(cs.vertcat(relaxed, cs.vec(dX)))])
        return _then(relax, variational_rk4_step(rhs, x, w, directions, h), "lugre_sens_step")

    return plain, sens_of
