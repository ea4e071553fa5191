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

from dataclasses import dataclass
from typing import Any

import casadi as cs
import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..model.robot import Model
from .dynamics import SymbolicDynamics

__all__ = ["ElasticTendon", "SeriesElasticSystem"]


def _per_motor(x: Any, m: int, name: str, unit: str, positive: bool) -> np.ndarray:
    """``x`` as (m,) finite floats, each > 0 (``positive``) or >= 0; one number is every motor's."""
    if isinstance(x, (bool, np.bool_)):
        raise InputError(f"{name}: expected a number of {unit}, got {x!r}")
    a = as_float_array(x, name, f"numbers of {unit}")
    a = np.full(m, float(a)) if a.ndim == 0 else a
    if a.shape != (m,) or not np.isfinite(a).all() or not (np.all(a > 0) if positive else np.all(a >= 0)):
        raise InputError(f"{name}: expected {m} finite {'positive' if positive else 'non-negative'} numbers of "
                         f"{unit} (one per motor), got {np.atleast_1d(a).tolist()!r}")
    return a


@dataclass(frozen=True)
class ElasticTendon:
    """Each motor's cable, seen on the motor shaft (arrays (m,), one per motor of the model).

    Attributes
    ----------
    stiffness: k_m, N m/rad of motor shaft (> 0): ``k_t r_m^2`` for a cable of stiffness k_t (N/m) on a shaft of
        radius r_m (:meth:`from_cable`).
    damping: c_m, N m s/rad (>= 0).
    dead_band: delta, rad of motor shaft (>= 0): the stretch below which the cable is slack (0: taut at zero
        stretch, MuJoCo's ``springlength="-1 0"``).
    """

    stiffness: np.ndarray
    damping: np.ndarray
    dead_band: np.ndarray

    @classmethod
    def from_cable(cls, n_motors: int, cable_stiffness: Any, shaft_radius: float, cable_damping: Any = 0.0,
                   dead_band: Any = 0.0) -> "ElasticTendon":
        """The tendon of a cable of stiffness k_t (N/m, EA/L) and damping c_t (N s/m) wound on a motor shaft of
        radius r_m (m), with a dead band of ``dead_band`` m of cable: k_m = k_t r_m^2, c_m = c_t r_m^2,
        delta = dead_band / r_m. The same numbers as :func:`~alpes_dyn.model.mjcf.mjcf_string`'s
        ``tendon_stiffness`` and ``tendon_damping``."""
        if not isinstance(n_motors, (int, np.integer)) or isinstance(n_motors, bool) or n_motors < 1:
            raise InputError(f"n_motors: expected a positive integer, got {n_motors!r}")
        r = _per_motor(shaft_radius, 1, "shaft_radius", "m", True)[0]
        k_t = _per_motor(cable_stiffness, n_motors, "cable_stiffness", "N/m", True)
        c_t = _per_motor(cable_damping, n_motors, "cable_damping", "N s/m", False)
        band = _per_motor(dead_band, n_motors, "dead_band", "m", False)
        return cls(k_t * r**2, c_t * r**2, band / r)

    def __post_init__(self) -> None:
        k = as_float_array(self.stiffness, "stiffness", "numbers of N m/rad")
        m = 1 if k.ndim == 0 else k.shape[0]
        object.__setattr__(self, "stiffness", _per_motor(k, m, "stiffness", "N m/rad", True))
        object.__setattr__(self, "damping", _per_motor(self.damping, m, "damping", "N m s/rad", False))
        object.__setattr__(self, "dead_band", _per_motor(self.dead_band, m, "dead_band", "rad", False))

    @property
    def n_motors(self) -> int:
        return int(self.stiffness.shape[0])

    @property
    def compliance(self) -> np.ndarray:
        """(m,) C = 1 / k_m, rad/(N m): the quasi-static stretch per motor torque
        (:attr:`~alpes_dyn.Transmission.tendon_compliance`)."""
        return 1.0 / self.stiffness

    def tension(self, stretch: Any, rate: Any, xp: Any = np) -> Any:
        """T_m = k_m max(phi - delta, 0) + c_m dphi/dt (m,), N m on the motor shaft, for the stretch phi and its
        rate (numpy arrays or CasADi columns; ``xp`` numpy or casadi)."""
        k, c, band = self.stiffness, self.damping, self.dead_band
        if xp is not np:
            k, c, band = cs.DM(k), cs.DM(c), cs.DM(band)
        return k * xp.fmax(stretch - band, 0) + c * rate


class SeriesElasticSystem:
    """A tendon-driven :class:`~alpes_dyn.Model` whose cables stretch and whose rotors move on their own (see the
    module docstring for the equations; state x (2 (n + m),), input tau_m (m,), N m, output theta_m (m,)).

    Parameters
    ----------
    model: a model with motors (``model.transmission``), built *without* the rotor on its joints
        (``rotor_inertia=False``: here the rotor is a state, not an inertia of the joints).
    tendon: the :class:`ElasticTendon` of its motors.
    rotor_inertia: J_m > 0 of each motor (m,), kg m^2 (eq. 2.8's I_a); default the model's
        ``transmission.rotor_inertia`` (a spec's ``rotor_inertia``), or on an Alpes model the parameter file's J_m.
    smooth: the Coulomb sign of the joints' friction as tanh (differentiable; the symbolic path's law) in both the
        numeric and the symbolic right-hand side, so that the two are the same function; False: the sign itself
        (numeric only).
    """

    def __init__(self, model: Model, tendon: ElasticTendon, rotor_inertia: Any = None, smooth: bool = True) -> None:
        if not isinstance(model, Model):
            raise InputError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
        if not isinstance(tendon, ElasticTendon):
            raise InputError(f"tendon: expected an ElasticTendon, got {type(tendon).__name__}")
        tr = model.transmission
        if tr is None:
            raise InputError(f"model: {model.name!r} has no motors: a series-elastic tendon links motors to joints")
        if tendon.n_motors != tr.n_motors:
            raise InputError(f"tendon: expected {tr.n_motors} motors' values ({', '.join(tr.motor_names)}), "
                             f"got {tendon.n_motors}")
        if model._rotor:
            raise InputError("model: built with the rotor on its joints (rotor_inertia=True, J_m S^T S); the "
                             "series-elastic tendon makes the rotor a state of its own: build it without")
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
        self.model, self.tendon, self.smooth = model, tendon, bool(smooth)
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
        """(q, theta_m, qd, thetad_m) of a state x (2 (n + m),)."""
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
        """T_m (m,), N m: each cable's pull on its rotor (r_m times the cable's tension in N)."""
        q, th, v, w = self.split(x)
        return self.tendon.tension(th - self.S @ q, w - self.S @ v)

    def encoder(self, x: Any) -> np.ndarray:
        """y = theta_m (m,), rad: what each motor's encoder reads."""
        return self.split(x)[1].copy()

    def f(self, x: Any, u: Any) -> np.ndarray:
        """xdot (2 (n + m),) at state x under motor torques u (m,), N m: Pinocchio's ABA for the joints under
        S^T T_m, each rotor's J_m thetadd_m = tau_m - T_m."""
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
        encoder reading S q + C u, C = 1 / k_m, beyond the dead band). A cable pulls only: u < 0 has no rest."""
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
        dt / substeps <= 2.8 / sqrt(k_m / J_m) (RK4's stability); a step beyond that is refused."""
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
