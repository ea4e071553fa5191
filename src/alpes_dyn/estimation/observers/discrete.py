"""The observers' discrete model: z_{k+1} = F(z_k, w_k), the state space stepped over one sample period.

Three friction laws (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`, ``friction_law=``):

* ``"smooth"``: the state space's right-hand side, its dry friction F_s tanh(v / v_s) (eq. 2.6-2.7), integrated by
  ``substeps`` classical RK4 steps per period;
* ``"stick"``: ``substeps`` steps of the time-stepping Coulomb law (:mod:`alpes_dyn.simulation.stick`: the dry
  friction resolved over each step, a joint under a net torque below F_s held at rest, semi-implicit Euler), the law
  of MuJoCo's ``frictionloss``. On a model without dry friction (F_s = 0 everywhere) it is the smooth law's RK4;
* ``"lugre"``: the LuGre law (:mod:`alpes_dyn.model.friction`, the model's file's sigma0 and sigma1, else the
  defaults), its bristle deflections z (rad, one per joint, ``bristle_<joint>``) the last n entries of the state,
  ``substeps`` split steps per period (the bristles relaxed exactly, then RK4:
  :func:`~alpes_dyn.symbolic.lugre.lugre_substep`; :func:`~alpes_dyn.simulation.lugre.lugre_substeps`). A stuck
  joint is a bristle deflected by less than F_s / sigma0: the filter's Gaussian holds it.

Either way the model may carry gains and disturbance torques as constant states (``parameters``).
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import casadi as cs
import numpy as np

from ...model.stops import JointStops
from ...errors import InputError, ModelError
from ...simulation.integrate import _check_dt, _n_known_inputs, joint_accelerations, rk4_expression
from ...model.friction import LuGre, lugre_of
from ...simulation.stick import check_friction_law, stick_step_expression
from ...symbolic.lugre import lugre_substep
from ...symbolic.lifted import lift_constants
from ...symbolic.statespace import StateSpace

__all__ = ["PARAMETERS", "DISTURBANCE_PREFIX", "DiscreteModel"]

PARAMETERS: tuple[str, ...] = ("input_gain", "spring_gain")
DISTURBANCE_PREFIX = "disturbance_"
"""``disturbance_<motor>``: an additive torque on that motor, N m, estimated as a random-walk state (motor inputs
only): what the model leaves unexplained (:mod:`alpes_dyn.estimation.observers.replay`)."""


class DiscreteModel:
    """z_{k+1} = F(z_k, w_k), y_k = h(z_k): the discretised state space, optionally with gains.

    Parameters
    ----------
    system : StateSpace
        The continuous state space (eq. 3.3); its output is the measurement.
    dt : float
        Sample period, s.
    parameters : Sequence[str], optional
        Names from :data:`PARAMETERS` (or ``disturbance_<motor>``, :data:`DISTURBANCE_PREFIX`) appended to the
        state as constants (z = [x; theta]); default none.
    substeps : int, optional
        Steps per sample period, in [1, 64] (default 1).
    friction_law : str, optional
        ``"smooth"`` (default: RK4 on the smooth sign), ``"stick"`` (the time-stepping Coulomb law,
        :mod:`alpes_dyn.simulation.stick`) or ``"lugre"`` (a bristle state per joint); see the module docstring.
    stops : JointStops or None, optional
        The joints' end stops in the model (:class:`~alpes_dyn.model.stops.JointStops`, e.g.
        ``JointStops.of(model)``: a stiff unilateral spring-damper at each end of the range); default None: none
        (eq. 3.3).

    Attributes
    ----------
    nz, nx, nw, ny: sizes of z, x = [q; qd], w = [u; F] and y.
    names: names of z's entries. friction_law: the law used (``"smooth"`` where the model has no dry friction).
    law: the :class:`~alpes_dyn.model.friction.LuGre` law of ``"lugre"`` (else None); nb: its bristle states (n or 0),
        z's last entries.
    values: (np,) the model's numbers in the right-hand side, one per use (:func:`~alpes_dyn.symbolic.lifted.
        lift_constants`): masses, inertias, lengths, springs, friction, ratios and the constants among them.
    step_p: ``casadi.Function`` (z, w, p) -> z_next (SX), the step with those numbers as the input p (np,): its
        code is the model's structure, the same for a model of other values.
    step: ``casadi.Function`` (z, w) -> z_next (SX), ``step_p`` at p = ``values``.
    output: ``casadi.Function`` z -> y (SX).
    """

    def __init__(self, system: StateSpace, dt: float, parameters: Sequence[str] = (), substeps: int = 1,
                 friction_law: str = "smooth", stops: JointStops | None = None) -> None:
        if not isinstance(substeps, (int, np.integer)) or isinstance(substeps, bool) or not 1 <= substeps <= 64:
            raise InputError(f"substeps: expected an integer in [1, 64], got {substeps!r}")
        self.substeps = int(substeps)
        if not isinstance(system, StateSpace):
            raise InputError(f"system: expected a StateSpace, got {type(system).__name__}")
        check_friction_law(friction_law)
        if stops is not None and not isinstance(stops, JointStops):
            raise InputError(f"stops: expected a JointStops or None, got {type(stops).__name__}")
        self.system, self.stops = system, stops
        self.dt = _check_dt(dt)
        params = tuple(parameters)
        motors = system.model.transmission.motor_names if system.model.transmission is not None else ()
        disturbances = tuple(f"{DISTURBANCE_PREFIX}{mn}" for mn in motors) if system.input == "motor" else ()
        for p in params:
            if p not in PARAMETERS and p not in disturbances:
                extra = f", or {', '.join(disturbances)}" if disturbances else ""
                raise ModelError(f"unknown parameter {p!r} (expected one of {', '.join(PARAMETERS)}{extra})")
        if len(set(params)) != len(params):
            raise ModelError(f"parameters: repeated name in {params}")
        if "spring_gain" in params and not system.model.extras.has_spring:
            raise ModelError("parameter 'spring_gain': the model has no spring")
        self.parameters = params
        n = system.n
        self.nx = 2 * n
        self.friction_law = friction_law if np.any(system.model.extras.coulomb) else "smooth"
        self.law = (lugre_of(system.model) or LuGre()) if self.friction_law == "lugre" else None
        self.nb = n if self.law is not None else 0
        self.nz = self.nx + len(params) + self.nb
        self.nw = _n_known_inputs(system)
        self.ny = system.n_outputs
        self.names = system.state_names + params + tuple(f"bristle_{j}" for j in system.model.joint_names[:self.nb])
        z = cs.SX.sym("z", self.nz)
        w = cs.SX.sym("w", self.nw)
        h = self.dt / self.substeps
        # the model's numbers (masses, inertias, springs, friction, ratios) lifted out of the right-hand side (or of
        # one step of the stick law) into the input p, one entry per use (symbolic.lifted): the step's code is then
        # the model's structure, and a model of other values shares its compiled library; lifted before cse, which
        # would merge equal values
        if self.friction_law == "stick":
            one, self.values = lift_constants(cs.Function("stick", [z, w], [self._stick(z, w, h)]))
        elif self.law is not None:
            one, self.values = lift_constants(cs.Function("lugre", [z, w], [self._lugre(z, w, h)]))
        else:
            one, self.values = lift_constants(cs.Function("rhs", [z, w], [self._rhs(z, w)]))
        p = cs.SX.sym("p", self.values.size)
        # the common subexpressions merged once, in the right-hand side or the stick step (milliseconds), not in the
        # step that calls it 4 x substeps times (the step's cse costs seconds on a large finger for the same
        # instructions: each call is already one node per instruction of its merged expression)
        merged = cs.Function("one", [z, w, p], [cs.cse(one(z, w, p))])
        advance: Callable[[Any], Any] = (
            (lambda x: merged(x, w, p)) if self.friction_law in ("stick", "lugre")
            else (lambda x: rk4_expression(lambda y, u: merged(y, u, p), x, w, h)))
        self.substep_p = cs.Function("substep", [z, w, p], [advance(z)], ["z", "w", "p"], ["z_next"])
        """One of the ``substeps`` steps of :attr:`step_p` (the C export loops over it: the code of one step, not of
        ``substeps`` unrolled)."""
        self.rhs_p = merged if self.friction_law == "smooth" else None
        """The right-hand side z' = f(z, w, p) that each RK4 stage of :attr:`substep_p` evaluates (None for the stick
        and LuGre laws, whose steps are not plain RK4: ``merged`` is then the whole substep)."""
        zn = z
        for _ in range(self.substeps):  # the smooth friction is fast: several RK4 steps per sample
            zn = advance(zn)
        self.step_p = cs.Function("step", [z, w, p], [zn], ["z", "w", "p"], ["z_next"])
        self.step = cs.Function("step", [z, w], [self.step_p(z, w, cs.DM(self.values))], ["z", "w"], ["z_next"])
        self.output = cs.Function("h", [z], [system.h_function(z[: self.nx])], ["z"], ["y"])

    def _torques(self, z: cs.SX, w: cs.SX) -> tuple[cs.SX, cs.SX, cs.SX, Any]:
        """(q, v, the joint torques of the inputs with the gains and disturbances (n,) N m, the contact force or
        None)."""
        ss = self.system
        n = ss.n
        q, v = z[:n], z[n: 2 * n]
        th = {p: z[self.nx + i] for i, p in enumerate(self.parameters)}
        a = th.get("input_gain", 1.0)
        u = w[: ss.n_inputs]
        motors = ss.model.transmission.motor_names if any(p.startswith(DISTURBANCE_PREFIX) for p in th) else ()
        d = [th.get(f"{DISTURBANCE_PREFIX}{mn}", 0.0) for mn in motors]
        if motors:  # an additive torque per motor (N m), a random-walk state
            u = u + cs.vertcat(*d)
        tau = a * ss.input_torque(q, u, v)
        if self.stops is not None:  # the end stops' torque back into the range (model.stops)
            tau = tau + self.stops.torque(q, v, cs)
        if "spring_gain" in th:  # the model applies k (q - q_rest); the gain b makes it b k (q - q_rest)
            tau = tau + (1.0 - th["spring_gain"]) * ss.model.extras.spring_torque(q, cs)
        F = a * w[ss.n_inputs:] if ss.force else None
        return q, v, tau, F

    def _rhs(self, z: cs.SX, w: cs.SX) -> cs.SX:
        q, v, tau, F = self._torques(z, w)
        qdd = joint_accelerations(self.system, q, v, tau, F)
        return cs.vertcat(v, qdd, cs.SX.zeros(len(self.parameters)))

    def _lugre(self, z: cs.SX, w: cs.SX, h: float) -> cs.SX:
        """z after one split step of h s of the LuGre law (:func:`~alpes_dyn.symbolic.lugre.lugre_substep`; the
        parameters carried over, the bristles z's last n entries)."""
        n, rest = self.system.n, z[self.nx: self.nz - self.nb]

        def torques(q: cs.SX, v: cs.SX) -> tuple[cs.SX, Any]:
            return self._torques(cs.vertcat(q, v, rest), w)[2:]

        q, v, zb = lugre_substep(self.system, self.law, z[:n], z[n: self.nx], z[self.nz - self.nb:], torques, h)
        return cs.vertcat(q, v, rest, zb)

    def _stick(self, z: cs.SX, w: cs.SX, h: float) -> cs.SX:
        """z after one step of h s of the stick law (the parameters carried over)."""
        q, v, tau, F = self._torques(z, w)
        x = stick_step_expression(self.system, cs.vertcat(q, v), tau, F, h)
        return cs.vertcat(x, z[self.nx:])
