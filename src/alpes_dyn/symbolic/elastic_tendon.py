"""The series-elastic, pull-only tendon with each motor's rotor as a state of its own (issue 16; report eq. 2.8).

The rigid tendon ties the rotor to the joints, theta_m = S q (Section 3, eq. 3.13), and its rotor inertia J_m
enters the joints' mass matrix as S^T diag(J_m) S. A real cable stretches: the elastic-joint model of Spong (1987),
with the cable as the spring, makes the rotor angle theta_m (m,) a coordinate of its own. The state is

    x = [q (n); theta_m (m); qd (n); thetad_m (m)]        (2 (n + m),  rad and rad/s)

and, with the cable's stretch measured on the motor shaft, phi = theta_m - S q (rad of motor shaft),

    T_m = k_m max(phi - delta, 0) + c_m dphi/dt          the cable's pull on the rotor, N m (per motor)
    (A + I_a) qdd = S^T T_m - C qd - G(q) - friction     the joints (eq. 2.10 with Gamma = S^T T_m)
    J_m thetadd_m = tau_m - T_m                           each rotor (eq. 2.8's I_a, on its own coordinate)
    y = theta_m                                           the encoder measures the rotor

k_m = k_t r_m^2 (N m/rad) is the cable's stiffness k_t (N/m) seen on a motor shaft of radius r_m, c_m = c_t r_m^2
its damping and delta >= 0 a dead band (rad of motor shaft: a cable with play is slack below it). Below the dead
band the cable pushes nothing (pull only); the damping acts on the stretch rate, slack or not, as MuJoCo's tendon
damper does, so that this model and the MJCF export (:func:`~alpes_dyn.model.mjcf.mjcf_string` with
``tendon_stiffness``: a rotor hinge coupled to the joints through a fixed tendon with a one-sided spring) are the
same system (tested against MuJoCo: accelerations, tension, trajectories).

Its two limits are the library's other tendons (both tested):

* rigid, k_m -> infinity: theta_m = S q and the rotor's inertia on the joints is S^T diag(J_m) S (``Model.alpes(...,
  rotor_inertia=True)``, :attr:`~alpes_dyn.Model.rotor_matrix`), every entry of a chain's block;
* quasi-static, the rotor's mode far above the motion: T_m = tau_m and the encoder reads S q + tau_m / k_m, the
  compliance C = 1 / k_m of :attr:`~alpes_dyn.Transmission.tendon_compliance` that identification fits (the
  fit keeps that limit: the rotor's mode, ~200 Hz on the realism benchmark's cable, would ask a 5 kHz state in the
  EKF and the fit, and the quasi-static cable with the torque held before each reading leaves the residual at the
  sensor floor on MuJoCo's elastic plants).
"""

from __future__ import annotations

import dataclasses
from typing import Any

import casadi as cs
import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..model.robot import Model
from ..model.tendon import ElasticTendon, _per_motor
from .dynamics import SymbolicDynamics

__all__ = ["ElasticTendon", "SeriesElasticSystem"]


def _joints_only(model: Model) -> Model:
    """``model`` without its rotors on the joints (J_m S^T S): the same URDF and spec, each motor's rotor_inertia 0
    (the series-elastic system carries the rotors as states)."""
    if not model._rotor:
        return model
    spec = model.spec
    bare = dataclasses.replace(spec, motors=tuple(dataclasses.replace(m, rotor_inertia=0.0) for m in spec.motors))
    return Model(model.urdf, bare, gravity=model.gravity, name=model.name, layout=model.layout, params=model.params,
                 spring=model.spring, check_inertia=model.check_inertia)


class SeriesElasticSystem:
    """A tendon-driven :class:`~alpes_dyn.Model` whose cables stretch and whose rotors move on their own (see the
    module docstring for the equations; state x (2 (n + m),), input tau_m (m,), N m, output theta_m (m,)).

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with motors (``model.transmission``). Its rotors leave the joints: a model built with them
        there (a spec's ``rotor_inertia``, ``Model.alpes(..., rotor_inertia=True)``: J_m S^T S) is rebuilt without
        (:attr:`model`), each J_m becoming its rotor's own inertia.
    tendon : ElasticTendon
        The :class:`ElasticTendon` of its motors.
    rotor_inertia : float or array_like of shape (m,) or None, optional
        J_m > 0 of each motor, kg m^2 (eq. 2.8's I_a); default None: the model's ``transmission.rotor_inertia``
        (a spec's ``rotor_inertia``), or on an Alpes model the parameter file's J_m.
    smooth : bool, optional
        True (default): the Coulomb sign of the joints' friction as tanh (differentiable; the symbolic path's law) in both the
        numeric and the symbolic right-hand side, so that the two are the same function; False: the sign itself
        (numeric only).

    Raises
    ------
    InputError
        A model without motors, with curved ratios or sheath friction, a tendon of another number of motors, or a
        rotor inertia that is not > 0, named.
    """

    def __init__(self, model: Model, tendon: ElasticTendon, rotor_inertia: Any = None, smooth: bool = True) -> None:
        if not isinstance(model, Model):
            raise InputError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
        if not isinstance(tendon, ElasticTendon):
            raise InputError(f"tendon: expected an ElasticTendon, got {type(tendon).__name__}")
        tr = model.transmission
        if tr is None:
            raise InputError(f"model: {model.name!r} has no motors: a series-elastic tendon links motors to joints")
        if tr.curved:
            raise InputError(f"model: {model.name!r}'s ratios change with q (ratio_curve); the series-elastic tendon "
                             "is built for constant ratios")
        if tr.has_capstan:  # nothing silently dropped: the sheath's friction on an elastic cable is not built
            raise InputError(f"model: {model.name!r}'s tendons have sheath friction (capstan); the series-elastic "
                             "tendon is built without it (its tension is the cable's, not the motor's torque)")
        if tendon.n_motors != tr.n_motors:
            raise InputError(f"tendon: expected {tr.n_motors} motors' values ({', '.join(tr.motor_names)}), "
                             f"got {tendon.n_motors}")
        if rotor_inertia is not None:
            J = _per_motor(rotor_inertia, tr.n_motors, "rotor_inertia", "kg m^2", True)
        elif np.any(tr.rotor_inertia != 0) or model.params is None:
            J = np.asarray(tr.rotor_inertia, dtype=float)
        else:  # an Alpes model built without its rotor on the joints: the parameter file's J_m
            J = np.full(tr.n_motors, float(model.params.J_m))
        if not np.all(J > 0):
            bad = [nm for nm, j in zip(tr.motor_names, J) if not j > 0]
            raise InputError(f"rotor_inertia: the rotor is a state of the series-elastic tendon and needs J_m > 0 "
                             f"(kg m^2); motor {bad[0]!r} has {J[tr.motor_names.index(bad[0])]:g}")
        if not isinstance(smooth, (bool, np.bool_)):
            raise InputError(f"smooth: expected True or False, got {smooth!r}")
        self.model, self.tendon, self.smooth = _joints_only(model), tendon, bool(smooth)
        self.n, self.m = model.n, tr.n_motors
        self.S = np.asarray(tr.S, dtype=float)
        self.rotor_inertia = J
        self._f: cs.Function | None = None

    @property
    def n_states(self) -> int:
        return 2 * (self.n + self.m)

    def __repr__(self) -> str:
        return f"SeriesElasticSystem({self.model.name!r}, n={self.n} joints, m={self.m} rotors)"

    def split(self, x: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(q, theta_m, qd, thetad_m) of a state x (2 (n + m),).

        Parameters
        ----------
        x : array_like, shape (2 (n + m),)
            The state [q; theta_m; qd; thetad_m], rad and rad/s.
        """
        x = as_float_array(x, "x", "rad and rad/s")
        if x.shape != (self.n_states,) or not np.isfinite(x).all():
            raise InputError(f"x: expected {self.n_states} finite numbers [q; theta_m; qd; thetad_m], got shape "
                             f"{x.shape}")
        n, m = self.n, self.m
        return x[:n], x[n: n + m], x[n + m: 2 * n + m], x[2 * n + m:]

    def _torque(self, u: Any) -> np.ndarray:
        u = as_float_array(u, "u", "motor torques (N m)")
        u = u.reshape(1) if u.ndim == 0 and self.m == 1 else u
        if u.shape != (self.m,) or not np.isfinite(u).all():
            raise InputError(f"u: expected {self.m} finite motor torques (N m), got shape {u.shape}")
        return u

    def tension(self, x: Any) -> np.ndarray:
        """T_m (m,), N m: each cable's pull on its rotor (r_m times the cable's tension in N).

        Parameters
        ----------
        x : array_like, shape (2 (n + m),)
            The state [q; theta_m; qd; thetad_m], rad and rad/s.
        """
        q, th, v, w = self.split(x)
        return self.tendon.tension(th - self.S @ q, w - self.S @ v)

    def encoder(self, x: Any) -> np.ndarray:
        """y = theta_m (m,), rad: what each motor's encoder reads.

        Parameters
        ----------
        x : array_like, shape (2 (n + m),)
            The state [q; theta_m; qd; thetad_m], rad and rad/s.
        """
        return self.split(x)[1].copy()

    def f(self, x: Any, u: Any) -> np.ndarray:
        """xdot (2 (n + m),) at state x under motor torques u (m,), N m: Pinocchio's ABA for the joints under
        S^T T_m, each rotor's J_m thetadd_m = tau_m - T_m.

        Parameters
        ----------
        x : array_like, shape (2 (n + m),)
            The state [q; theta_m; qd; thetad_m], rad and rad/s.
        u : array_like, shape (m,)
            Motor torques tau_m, N m.
        """
        q, th, v, w = self.split(x)
        u = self._torque(u)
        T = self.tendon.tension(th - self.S @ q, w - self.S @ v)
        qdd = self.model.forward_dynamics(q, v, self.S.T @ T, smooth=self.smooth)
        return np.concatenate([v, w, qdd, (u - T) / self.rotor_inertia])

    def f_function(self) -> cs.Function:
        """``casadi.Function`` ``f(x, u) -> xdot`` (SX; the same right-hand side as :meth:`f`, the joints from
        :class:`~alpes_dyn.symbolic.dynamics.SymbolicDynamics`), built once."""
        if self._f is None:
            n, m = self.n, self.m
            x, u = cs.SX.sym("x", self.n_states), cs.SX.sym("u", m)
            q, th, v, w = x[:n], x[n: n + m], x[n + m: 2 * n + m], x[2 * n + m:]
            S = cs.DM(self.S)
            T = self.tendon.tension(th - cs.mtimes(S, q), w - cs.mtimes(S, v), cs)
            qdd = SymbolicDynamics(self.model).forward_dynamics(q, v, cs.mtimes(S.T, T), smooth=self.smooth)
            wdd = (u - T) / cs.DM(self.rotor_inertia)
            self._f = cs.Function("series_elastic", [x, u], [cs.vertcat(v, w, qdd, wdd)], ["x", "u"], ["xdot"])
        return self._f

    def equilibrium(self, u: Any, q0: Any = None) -> np.ndarray:
        """The rest state x (2 (n + m),) under constant motor torques u >= 0 (m,), N m: the joints where the rigid
        model rests under S^T u (:meth:`Model.static_equilibrium <alpes_dyn.Model.static_equilibrium>`, from ``q0``),
        each cable pulling T_m = u, so stretched by delta + u / k_m: theta_m = S q + delta + u / k_m (the quasi-static
        encoder reading S q + C u, C = 1 / k_m, beyond the dead band). A cable pulls only: u < 0 has no rest.

        Parameters
        ----------
        u : array_like, shape (m,)
            Constant motor torques, N m, >= 0.
        q0 : array_like, shape (n,), optional
            The Newton start for the joints, rad (default None: zeros).

        Raises
        ------
        InputError
            A negative torque, or no equilibrium found.
        """
        u = self._torque(u)
        if np.any(u < 0):
            raise InputError(f"u: a pull-only cable holds no negative motor torque, got {u.tolist()!r} N m")
        q0 = np.zeros(self.n) if q0 is None else self.model.vector(q0, "q0", self.n)
        q = self.model.static_equilibrium(self.S.T @ u, q0)
        th = self.S @ q + self.tendon.dead_band + u / self.tendon.stiffness
        return np.concatenate([q, th, np.zeros(self.n + self.m)])

    def simulate(self, x0: Any, u: Any, dt: float, substeps: int = 4) -> np.ndarray:
        """States (N+1, 2 (n + m)) from x0 under the motor torques u (N, m), u[k] held on [t_k, t_k+1) (N m),
        sampled every ``dt`` s: RK4 with ``substeps`` steps per sample, the N samples in one CasADi
        ``mapaccum`` call (no Python loop over time). The rotor's mode sqrt(k_m / J_m) needs
        dt / substeps <= 2.8 / sqrt(k_m / J_m) (RK4's stability); a step beyond that is refused.

        Parameters
        ----------
        x0 : array_like, shape (2 (n + m),)
            The initial state [q; theta_m; qd; thetad_m], rad and rad/s.
        u : array_like, shape (N, m)
            Motor torques, N m, u[k] held on [t_k, t_k+1) ((N,) for one motor).
        dt : float
            The sample period, s.
        substeps : int, optional
            RK4 steps per sample (default 4).

        Returns
        -------
        numpy.ndarray, shape (N+1, 2 (n + m))
            The states at t_0 .. t_N.

        Raises
        ------
        InputError
            Bad inputs, a step unstable on the rotor's mode, or a simulation that diverges.
        """
        x0 = np.concatenate(self.split(x0))
        U = as_float_array(u, "u", "motor torques (N m)")
        U = U[:, None] if U.ndim == 1 and self.m == 1 else U
        if U.ndim != 2 or U.shape[1] != self.m or U.shape[0] < 1 or not np.isfinite(U).all():
            raise InputError(f"u: expected (N, {self.m}) finite motor torques (N m), got shape {U.shape}")
        if not (isinstance(dt, (int, float, np.floating)) and not isinstance(dt, bool) and np.isfinite(dt) and dt > 0):
            raise InputError(f"dt: expected a positive number of seconds, got {dt!r}")
        if not isinstance(substeps, (int, np.integer)) or isinstance(substeps, bool) or substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {substeps!r}")
        h = float(dt) / int(substeps)
        fastest = float(np.sqrt(np.max(self.tendon.stiffness / self.rotor_inertia)))
        if h * fastest > 2.8:
            raise InputError(f"substeps: RK4 steps of {h:g} s are unstable on the rotor's mode "
                             f"({fastest / (2 * np.pi):.4g} Hz); take at least {int(np.ceil(dt * fastest / 2.8))}")
        f = self.f_function()
        x, uk = cs.MX.sym("x", self.n_states), cs.MX.sym("u", self.m)
        xk = x
        for _ in range(int(substeps)):  # the step's expression, written out once (not a loop over time)
            k1 = f(xk, uk)
            k2 = f(xk + 0.5 * h * k1, uk)
            k3 = f(xk + 0.5 * h * k2, uk)
            k4 = f(xk + h * k3, uk)
            xk = xk + (h / 6.0) * (k1 + 2 * k2 + 2 * k3 + k4)
        step = cs.Function("series_elastic_step", [x, uk], [xk])
        X = np.asarray(step.mapaccum(U.shape[0])(x0, U.T)).T
        if not np.isfinite(X).all():
            raise InputError("u: the simulation diverged (non-finite state): torques or states out of the model's "
                             "range")
        return np.vstack([x0, X])
