"""State observers: the passive joints q_1..q_n of a finger estimated from its motor encoder.

The report ends where this module begins (Conclusion: the finger is observable, "it is possible to
investigate the synthesis of an observer"). Two discrete-time observers of the report's system
(eq. 3.1, 3.3, 3.16), discretised by one classical RK4 step per sample period ``dt`` with the known
input held over the period (or several; or, with ``friction_law="stick"``, by steps of the time-stepping Coulomb law
that holds a joint at rest: :class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel`):

* :class:`ExtendedKalmanFilter` -- the EKF: state and covariance predicted through the RK4 step,
  its Jacobians with respect to the state and to the known input obtained by CasADi's automatic
  differentiation of the discretised model;
* :class:`UnscentedKalmanFilter` -- the UKF (Julier-Uhlmann, scaled sigma points, Wan-van der
  Merwe weights): 2 nz + 1 sigma points propagated through the same RK4 step.

Both can estimate, with the state, two uncertain gains as random-walk states (``parameters=``):

* ``"input_gain"`` a -- multiplies the known torques (S^T tau_m, and J^T F);
* ``"spring_gain"`` b -- multiplies the spring torques k q;

and, on a state space with motor inputs, a disturbance torque per motor, ``"disturbance_<motor>"`` d (N m,
added to the measured motor torque: tau = a S^T (u + d)).

If the observer's masses and inertias are (1 + d_m) times the true ones and its springs (1 + d_K)
times, dividing its dynamics by (1 + d_m) shows that the truth is exactly its model with
a = 1 + d_m and b = (1 + d_m) / (1 + d_K): these two gains remove the bias of a uniformly
mis-scaled model (:func:`true_gains`).

Measurements y_k = h(x(t_k)) (the motor encoder q_m = (r/r_m) sum q, Section 3), known inputs
w_k = [u_k; F_k] held on [t_k, t_k+1) (the measured motor torque, optionally the measured contact
force). Noise model: the known input carries white noise of covariance ``input_noise`` (it enters
the prediction through G = dF/dw), plus additive ``process_noise`` on the state, and
``measurement_noise`` on y.

Each filter step (predict with w_k, update with y_k+1) is one CasADi function of
s = [z; vec P]; :meth:`KalmanFilter.run` applies it N times in one call of CasADi's virtual
machine (``mapaccum``, the default) or of compiled C (``compiled=True``:
:class:`~alpes_dyn.simulation.integrate.CompiledStepLoop`, cached on disk), never in a Python loop.

Example (the default scenario of ``alpes-dyn estimate``, see :mod:`alpes_dyn.estimation.observers.scenario`)::

    from alpes_dyn.estimation.observers.scenario import run_estimation, plot_estimation
    res = run_estimation("ekf-params", mismatch=0.1, duration=5.0, seed=0)
    print(res.rmse)            # (3,) rad, RMSE of q_1..q_3 after the transient
    print(res.parameters)      # estimated and true gains
    plot_estimation(res, "estimate.png")
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ...checks import as_float_array
from ...errors import InputError, ModelError
from ...limits import check_bytes
from ...rebuild import Rebuilt
from ...simulation.integrate import CompiledStepLoop, CompilerError, _check_dt, _n_known_inputs, joint_accelerations, rk4_expression
from ...symbolic.lifted import lift_constants
from ...symbolic.statespace import StateSpace
from .covariance import chol_sym, predicted_covariance, updated_state
from .discrete import DISTURBANCE_PREFIX, PARAMETERS, DiscreteModel
from .friction_noise import with_friction_noise
from .ahead import kept_run
from .looped import LOOP_STATES, looped_functions
from .online_filter import OnlineFilter

__all__ = [
    "OBSERVERS", "PARAMETERS", "DiscreteModel", "KalmanFilter", "ExtendedKalmanFilter", "UnscentedKalmanFilter",
    "Estimate", "true_gains", "make_observer", "OnlineFilter",
]

OBSERVERS: tuple[str, ...] = ("ekf", "ukf", "ekf-params", "ukf-params")
def true_gains(mass_scale: float, spring_scale: float) -> dict[str, float]:
    """Gains a, b that make an observer's mis-scaled model exact.

    Parameters
    ----------
    mass_scale : float
        The observer's masses (and inertias) / the true ones.
    spring_scale : float
        The observer's springs / the true ones.

    Returns
    -------
    dict[str, float]
        ``{"input_gain": mass_scale, "spring_gain": mass_scale / spring_scale}``.
    """
    return {"input_gain": float(mass_scale), "spring_gain": float(mass_scale) / float(spring_scale)}


def _finite_number(x: Any, name: str) -> float:
    try:
        v = float(x)
    except (TypeError, ValueError):
        v = float("nan")
    if not np.isfinite(v):
        raise InputError(f"{name}: expected a finite number, got {x!r}")
    return v


MAX_VARIANCE = 1e12
"""Largest entry of a noise covariance or an initial covariance (squared units of a state or an output: rad^2,
(rad/s)^2, ...): a standard deviation of 10^6 is no prior at all."""


def _cov(value: Any, n: int, name: str) -> np.ndarray:
    """A covariance from variances (n,) or a matrix (n, n), checked symmetric positive semidefinite."""
    a = as_float_array(value, name, f"{n} variances or an ({n}, {n}) covariance")
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape == (n,):
        a = np.diag(a)
    if a.shape != (n, n):
        raise InputError(f"{name}: expected {n} variances or an ({n}, {n}) covariance, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise InputError(f"{name}: contains NaN or inf")
    big = float(np.abs(a).max()) if a.size else 0.0
    if big > MAX_VARIANCE:  # a variance of 1e300: squared units of a state, never that large
        raise InputError(f"{name}: an entry of {big:g} is over the limit of {MAX_VARIANCE:g} (a variance, in the "
                         "squared units of its state or output)")
    tiny = a[(a != 0) & (np.abs(a) < np.finfo(float).tiny)]
    if tiny.size:
        raise InputError(f"{name}: {float(tiny[0])!r} is a subnormal number (below 2.2e-308): write 0 or a "
                         "physical variance")
    if not np.allclose(a, a.T, rtol=1e-10, atol=1e-300):
        raise InputError(f"{name}: covariance must be symmetric")
    if np.linalg.eigvalsh(a).min() < -1e-12 * max(1.0, float(np.abs(a).max())):
        raise InputError(f"{name}: covariance must be positive semidefinite")
    return a


@dataclass
class Estimate:
    """The output of an observer run.

    Attributes
    ----------
    t: (N+1,) sample times, s.
    z: (N+1, nz) estimates [q; qd; theta] after each measurement update (rad, rad/s, -).
    P: (N+1, nz, nz) their covariances.
    names: names of z's entries.
    """

    t: np.ndarray
    z: np.ndarray
    P: np.ndarray
    names: tuple[str, ...]

    @property
    def std(self) -> np.ndarray:
        """(N+1, nz) standard deviations sqrt(diag P)."""
        return np.sqrt(np.maximum(np.diagonal(self.P, axis1=1, axis2=2), 0.0))


class KalmanFilter(Rebuilt):
    """Common machinery of the discrete Kalman filters (see :class:`ExtendedKalmanFilter`).

    Parameters
    ----------
    system : StateSpace
        The continuous state space; its input u (and F if ``force=True``) is the known input and
        its output the measurement, e.g. ``StateSpace(finger, input="motor", output="encoder")``.
    dt : float
        Sample period, s.
    process_noise : array_like
        Covariance per step of an additive noise on z (variances (nz,) or (nz, nz)); for the
        parameter states it is their random-walk variance per step.
    measurement_noise : array_like
        Covariance of the measurement noise, (p,) or (p, p), output units squared (rad^2).
    input_noise : array_like or None, optional
        Covariance of the known input's noise, (m[+3],) or square, N^2 m^2 (and N^2), default 0.
    parameters : sequence of str, optional
        Gains estimated with the state, from :data:`PARAMETERS`.
    substeps : int, optional
        Steps per sample period in the discretised model (default 1; use the simulation's with the
        smooth friction, whose time constant is a fraction of a millisecond).
    friction_law : {"smooth", "stick", "lugre"}, optional
        ``"smooth"`` (default; RK4 on F_s tanh(v / v_s)), ``"stick"`` (the time-stepping Coulomb law that holds a
        joint at rest under a net torque below F_s, :mod:`alpes_dyn.simulation.stick`) or ``"lugre"`` (a bristle
        state per joint appended to z, :mod:`alpes_dyn.model.friction`): the
        :class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel`'s.
    stops : JointStops or None, optional
        The joints' end stops in the model (:class:`~alpes_dyn.model.stops.JointStops`; default none, eq. 3.3): a
        joint the plant's stop holds is then held by the observer's model too.
    looped : bool or None, optional
        The EKF's step as loops over dense matrices (:mod:`~alpes_dyn.estimation.observers.looped`; run in compiled
        C where a compiler is found) instead of one unrolled expression; default (None) from
        :data:`~alpes_dyn.estimation.observers.looped.LOOP_STATES` states on. The UKF's is unrolled.
    compiled : bool, optional
        Run :meth:`run` in C generated by CasADi and compiled once per model structure and noise setting
        (the model's numbers are an input of the compiled step, :attr:`filter_step_p`: a model of other masses,
        springs or friction loads the same library; cached on disk, a few seconds of gcc; raises
        :class:`~alpes_dyn.simulation.integrate.CompilerError`
        without a C compiler): worth it for long or repeated runs. Default False: CasADi's
        virtual machine (slower per step, no build). Both give the same numbers.

    Attributes
    ----------
    model: the :class:`DiscreteModel`. names: names of z's entries. backend: ``"compiled"`` or ``"casadi"``.
    filter_step: ``casadi.Function`` s = [z; vec P], [w; y] -> s_next, one predict-update step; its covariance
        arithmetic in the order of :mod:`~alpes_dyn.estimation.observers.covariance` (the exported C's).
    filter_step_p: the same step with the model's numbers as a third input p (``model.values``): what the compiled
        loop and :meth:`online` run, so that the library is keyed on the model's structure (its joints,
        transmission, effects and the noise settings), never recompiled for other masses or springs.
    measurement: ``casadi.Function`` z -> (h (ny,), H = dh/dz (ny, nz), sparse), what the update evaluates.
    exact_loops: True when CasADi folded no constant product in that arithmetic (False if ``looped``, the step built
        as loops): the exported C's loops (:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`) give its numbers to the bit.
    """

    kind = "kalman"

    def __init__(self, system: StateSpace, dt: float, *, process_noise: Any, measurement_noise: Any,
                 input_noise: Any = None, parameters: Sequence[str] = (), compiled: bool = False,
                 substeps: int = 1, friction_law: str = "smooth", stops: Any = None, looped: bool | None = None
                 ) -> None:
        self._remember(system, dt, process_noise=process_noise, measurement_noise=measurement_noise,
                       input_noise=input_noise, parameters=parameters, compiled=compiled, substeps=substeps,
                       friction_law=friction_law, stops=stops, looped=looped)
        self.model = DiscreteModel(system, dt, parameters, substeps, friction_law, stops)
        mdl = self.model
        self.dt = mdl.dt
        self.names = mdl.names
        self.nz, self.nw, self.ny = mdl.nz, mdl.nw, mdl.ny
        self.Q = _cov(process_noise, mdl.nz, "process_noise")
        self.R = _cov(measurement_noise, mdl.ny, "measurement_noise")
        self.Sw = _cov(0.0 if input_noise is None else input_noise, mdl.nw, "input_noise")
        nz = mdl.nz
        self._p = cs.SX.sym("p", mdl.values.size)  # the model's numbers, an input of the compiled step
        self._folds: list[int] = []  # the products CasADi folded (covariance._mul)
        self._predict_fn: cs.Function | None = None  # built on first use (predict())
        if looped is not None and not isinstance(looped, bool):
            raise InputError(f"looped: expected True, False or None, got {looped!r}")
        if looped and self.kind != "ekf":
            raise InputError(f"looped: the EKF's step only; the {self.kind}'s is unrolled")
        self.looped = bool(self.kind == "ekf" and (looped if looped is not None else nz >= LOOP_STATES))
        fns = looped_functions(self) if self.looped else {}  # a large state: loops (estimation.observers.looped)
        step = fns.pop("filter_step_p", None)
        for name, fn in fns.items():  # measurement, _update, linearized(_p), _predict_fn
            setattr(self, name, fn)
        self._finish(step, compiled)

    def _finish(self, step: cs.Function | None, compiled: bool) -> None:
        """The step (``step``: the looped one, else built here unrolled), its loop and backend."""
        mdl, nz = self.model, self.model.nz
        if step is not None:
            self.exact_loops = False  # (the exported C's loops sum in other orders: its numbers to rounding)
            self._set_step(step, compiled)
            return
        z, P, y = cs.SX.sym("z", nz), cs.SX.sym("P", nz, nz), cs.SX.sym("y", mdl.ny)
        # the update built once, on symbols (where it folds a product, it folds it on any P: the folds come from
        # the constant entries of H and R), and called on the prediction's expressions in the step (the same
        # operations in the same order; building it twice costs seconds on a large state)
        self._update = cs.Function("update", [z, P, y], list(self._update_sym(z, P, y)), ["z", "P", "y"],
                                   ["z_upd", "P_upd"])
        # one step on s = [z; vec P] and [w; y], the prediction built from the expressions (so that the products
        # CasADi folds are seen: self.exact_loops, for the exported C)
        s = cs.SX.sym("s", nz + nz * nz)
        r = cs.SX.sym("wy", mdl.nw + mdl.ny)
        zp, Pp = self._predict_sym(s[:nz], cs.reshape(s[nz:], nz, nz), r[: mdl.nw])
        zu, Pu = self._update(zp, Pp, r[mdl.nw:])
        self.exact_loops = not self._folds
        out = cs.vertcat(zu, cs.vec(Pu))
        # no cse of the whole step: built from merged pieces, it has only a few more instructions than merged again,
        # and merging them costs seconds on a large finger (the build: benchmarks/results/observer_build.json)
        self._set_step(cs.Function(f"{self.kind}_step", [s, r, self._p], [out], ["s", "wy", "p"], ["s_next"]),
                       compiled)

    def _set_step(self, step: cs.Function, compiled: bool) -> None:
        """``filter_step_p`` = ``step``, ``filter_step`` at the model's numbers, the compiled loop if asked."""
        self.filter_step_p = step
        s, r = step.mx_in()[:2] if step.is_a("MXFunction") else step.sx_in()[:2]
        self.filter_step = cs.Function(step.name(), [s, r], [step(s, r, cs.DM(self.model.values))], ["s", "wy"],
                                       ["s_next"])
        self._loop: CompiledStepLoop | None = None
        self._online_loop: CompiledStepLoop | None = None  # built by online() for a filter that runs in the VM
        self.backend = "casadi"
        if compiled:
            self._loop = self._compiled_loop()
            self.backend = "compiled"

    def _compiled_loop(self) -> CompiledStepLoop:
        """The step in compiled C with the model's numbers as its input p: one library per model *structure*
        and noise setting, shared by every model of other values (masses, springs, ...; cached on disk)."""
        return CompiledStepLoop(self.filter_step_p, f"{self.kind}_{self.model.system.model.name}", threads=1,
                                vectorize=False, parameters=self.model.values)

    def _plain_looped_loop(self) -> CompiledStepLoop | None:
        """A looped filter's plain compiled step (the one :meth:`online` runs), for a record too long to keep its
        prediction (:data:`~.ahead.MAX_KEPT_BYTES`); None without a compiler."""
        if self._online_loop is None:
            try:
                self._online_loop = self._compiled_loop()
            except CompilerError:
                return None
        return self._online_loop

    # ------------------------------------------------------------------ symbolic pieces
    @property
    def _predict(self) -> cs.Function:
        """The time update, (z, P, w) -> (z_pred, P_pred), built on first use (:meth:`predict`; the step is
        built from the expressions)."""
        if self._predict_fn is None:
            z, P, w = cs.SX.sym("z", self.nz), cs.SX.sym("P", self.nz, self.nz), cs.SX.sym("w", self.nw)
            fp = cs.Function("predict", [z, P, w, self._p], list(self._predict_sym(z, P, w)))
            self._predict_fn = cs.Function("predict", [z, P, w], fp(z, P, w, cs.DM(self.model.values)),
                                           ["z", "P", "w"], ["z_pred", "P_pred"])
        return self._predict_fn

    def _predict_sym(self, z: cs.SX, P: cs.SX, w: cs.SX) -> tuple[cs.SX, cs.SX]:  # pragma: no cover - abstract
        raise NotImplementedError

    def _update_sym(self, z: cs.SX, P: cs.SX, y: cs.SX) -> tuple[cs.SX, cs.SX]:
        """Measurement update with a Joseph-form covariance (eq. of the linear Kalman filter), in the order of
        :func:`~alpes_dyn.estimation.observers.covariance.updated_state` (the exported C's)."""
        zs = cs.SX.sym("zs", self.nz)
        hs = self.model.output(zs)
        self.measurement = cs.Function("measurement", [zs], [hs, cs.jacobian(hs, zs)], ["z"], ["h", "H"])
        h, H = self.measurement(z)
        return updated_state(z, P, y, h, H, self.R, self._folds)

    # ------------------------------------------------------------------ numeric API
    def _z(self, z: Any, name: str = "z") -> np.ndarray:
        return self.model.system.model.vector(z, name, self.nz)

    def _P(self, P: Any, name: str = "P") -> np.ndarray:
        return _cov(P, self.nz, name)

    def predict(self, z: Any, P: Any, w: Any) -> tuple[np.ndarray, np.ndarray]:
        """Time update over one period with the known input.

        Parameters
        ----------
        z : array_like
            (nz,) the state estimate.
        P : array_like
            (nz, nz) its covariance.
        w : array_like
            (m[+3],) the known input held over the period (N m, N).

        Returns
        -------
        tuple of ndarray
            (z (nz,), P (nz, nz)).
        """
        w = self.model.system.model.vector(w, "w", self.nw)
        zp, Pp = self._predict(self._z(z), self._P(P), w)
        return np.array(zp).reshape(-1), np.array(Pp)

    def update(self, z: Any, P: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        """Measurement update.

        Parameters
        ----------
        z : array_like
            (nz,) the state estimate.
        P : array_like
            (nz, nz) its covariance.
        y : array_like
            (p,) the measurement (rad).

        Returns
        -------
        tuple of ndarray
            (z (nz,), P (nz, nz)).
        """
        y = self.model.system.model.vector(y, "y", self.ny)
        zu, Pu = self._update(self._z(z), self._P(P), y)
        return np.array(zu).reshape(-1), np.array(Pu)

    def step(self, z: Any, P: Any, w: Any, y: Any) -> tuple[np.ndarray, np.ndarray]:
        """One filter step: predict with w_k, then update with y_k+1.

        Parameters
        ----------
        z : array_like
            (nz,) the state estimate.
        P : array_like
            (nz, nz) its covariance.
        w : array_like
            (m[+3],) the known input w_k.
        y : array_like
            (p,) the measurement y_k+1.

        Returns
        -------
        tuple of ndarray
            (z (nz,), P (nz, nz)).
        """
        zp, Pp = self.predict(z, P, w)
        return self.update(zp, Pp, y)

    def online(self, z0: Any, P0: Any, y0: Any = None) -> "OnlineFilter":
        """A filter for a real-time loop: :meth:`OnlineFilter.step` is one call into compiled C per sample.

        Compiles the filter step on first use when the filter was not built with ``compiled=True`` (cached on
        disk). The same numbers as :meth:`run` on the same samples (tested to the last bit).

        Parameters
        ----------
        z0 : array_like
            (nz,) the prior mean at t_0.
        P0 : array_like
            (nz,) variances or (nz, nz) covariance of the prior.
        y0 : array_like or None, optional
            (p,) the first measurement, updated into the prior when given.

        Returns
        -------
        OnlineFilter
            The real-time filter.
        """
        if self._loop is None and self._online_loop is None:  # run() keeps its own backend
            self._online_loop = self._compiled_loop()
        z, P = self._z(z0, "z0"), self._P(P0, "P0")
        if y0 is not None:
            y0 = self.model.system.model.vector(y0, "y0", self.ny)
            z, P = self._update(z, P, y0)
        return OnlineFilter(self, np.array(z).reshape(-1), np.array(P))

    def run(self, z0: Any, P0: Any, W: Any, Y: Any) -> Estimate:
        """Filter a whole record.

        Parameters
        ----------
        z0 : array_like
            (nz,) the prior mean at t_0.
        P0 : array_like
            (nz,) variances or (nz, nz) covariance of the prior.
        W : array_like
            (N, m[+3]) known inputs, W[k] held on [t_k, t_k+1) (N m, N).
        Y : array_like
            (N+1, p) measurements at t_0 .. t_N (rad).

        Returns
        -------
        Estimate
            z (N+1, nz), P (N+1, nz, nz): z[k] uses Y[0..k].
        """
        z0, P0 = self._z(z0, "z0"), self._P(P0, "P0")
        W = as_float_array(W, "W", "an array of known inputs")
        Y = as_float_array(Y, "Y", "an array of measurements")
        if W.ndim == 1 and self.nw == 1:
            W = W[:, None]
        if Y.ndim == 1 and self.ny == 1:
            Y = Y[:, None]
        if W.ndim != 2 or W.shape[1] != self.nw or W.shape[0] < 1:
            raise InputError(f"W: expected shape (N, {self.nw}), got {W.shape}")
        N = W.shape[0]
        check_bytes(16.0 * (N + 1) * (self.nz + self.nz * self.nz), "W",
                    f"{N} samples of {self.nz} states and their covariance")
        if Y.shape != (N + 1, self.ny):
            raise InputError(f"Y: expected shape ({N + 1}, {self.ny}) (one more sample than W), got {Y.shape}")
        for a, name in ((W, "W"), (Y, "Y")):
            if not np.isfinite(a).all():
                raise InputError(f"{name}: contains NaN or inf")
        z, P = self._update(z0, P0, Y[0])
        s0 = np.concatenate([np.array(z).reshape(-1), np.array(P).reshape(-1, order="F")])
        WY = np.hstack([W, Y[1:]])
        # a looped filter: its compiled step keeping its prediction for the NEES and the NIS (None without a compiler
        # or on a record too long to keep it: then its plain compiled step, as online() runs it)
        S = kept_run(self, s0, WY, W) if self.looped else None
        loop = self._loop if not self.looped else (self._plain_looped_loop() if S is None else None)
        if S is None and loop is not None:
            S = loop.run(s0[None], WY[None])[0]
        elif S is None:
            # the step of the compiled loop, the model's numbers as its input: the same numbers as online(), to the bit
            S = np.vstack([s0, np.array(self.filter_step_p.mapaccum(N)(s0, WY.T, self.model.values)).T])
        nz = self.nz
        Z = S[:, :nz]
        Ps = S[:, nz:].reshape(N + 1, nz, nz).transpose(0, 2, 1)  # column-major vec(P)
        if not np.isfinite(S[-1]).all():
            raise InputError(f"{self.kind}: the filter diverged (non-finite estimate); check the noise settings")
        return Estimate(t=self.dt * np.arange(N + 1), z=Z, P=Ps, names=self.names)


class ExtendedKalmanFilter(KalmanFilter):
    """Extended Kalman filter of the RK4-discretised model (see :class:`KalmanFilter` for parameters).

    Prediction: z_k+1 = F(z_k, w_k), P_k+1 = A P A^T + G Sigma_w G^T + Q with A = dF/dz and
    G = dF/dw by CasADi automatic differentiation of the RK4 step. Update: the Kalman gain with
    H = dh/dz and a Joseph-form covariance. Attribute ``linearized``: ``casadi.Function`` (z, w) -> (z_next,
    A (sparse), N = the lower triangle of G Sigma_w G^T + Q); ``linearized_p`` the same of (z, w, p).

    Example
    -------
    >>> import alpes_dyn as ad
    >>> from alpes_dyn.symbolic.statespace import StateSpace
    >>> from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter
    >>> ss = StateSpace(ad.Model.alpes("finger3"), input="motor", output="encoder")
    >>> ekf = ExtendedKalmanFilter(ss, 1e-3, process_noise=[1e-10] * 3 + [1e-6] * 3,
    ...                            measurement_noise=[1e-7], input_noise=[1e-8])
    """

    kind = "ekf"

    def _predict_sym(self, z: cs.SX, P: cs.SX, w: cs.SX) -> tuple[cs.SX, cs.SX]:
        zs, ws, ps = cs.SX.sym("zs", self.nz), cs.SX.sym("ws", self.nw), cs.SX.sym("ps", self._p.numel())
        zn = self.model.step_p(zs, ws, ps)
        G = cs.jacobian(zn, ws)
        noise = cs.mtimes([G, cs.sparsify(cs.DM(self.Sw)), G.T]) + cs.sparsify(cs.DM(self.Q))
        self.linearized_p = cs.Function("linearized", [zs, ws, ps], [zn, cs.jacobian(zn, zs), cs.tril(noise)],
                                        ["z", "w", "p"], ["z_next", "A", "N"])
        self.linearized = cs.Function("linearized", [zs, ws], self.linearized_p(zs, ws, cs.DM(self.model.values)),
                                      ["z", "w"], ["z_next", "A", "N"])
        zn, A, N = self.linearized_p(z, w, self._p)
        return zn, predicted_covariance(A, N, P, self._folds)


class UnscentedKalmanFilter(KalmanFilter):
    """Unscented Kalman filter of the RK4-discretised model (see :class:`KalmanFilter` for parameters).

    Sigma points z +- sqrt(nz + lambda) L e_i (P = L L^T, lambda = alpha^2 (nz + kappa) - nz) go
    through the RK4 step; mean and covariance are their weighted sums (Wan & van der Merwe, 2000),
    plus G Sigma_w G^T + Q (G = dF/dw at the mean, by AD). The measurement is linear in the state
    for the encoder, so the update is the Kalman update of :class:`KalmanFilter`.

    Parameters
    ----------
    system : StateSpace
        The state space observed, as for :class:`KalmanFilter`.
    dt : float
        The sample period, s (> 0).
    alpha : float
        The sigma points' spread (default 1, > 0, finite).
    beta : float
        The prior's kurtosis term (default 2, optimal for Gaussians; finite).
    kappa : float
        The secondary scaling (default 0, finite; with alpha^2 (nz + kappa) > 0).
    **kwargs
        The keywords of :class:`KalmanFilter` (noises, parameters, ...).

    Raises
    ------
    InputError
        ``alpha``, ``beta`` or ``kappa`` not finite, ``alpha`` <= 0, alpha^2 (nz + kappa) <= 0, or what
        :class:`KalmanFilter` refuses.
    """

    kind = "ukf"

    def __init__(self, system: StateSpace, dt: float, *, alpha: float = 1.0, beta: float = 2.0,
                 kappa: float = 0.0, **kwargs: Any) -> None:
        self.alpha, self.beta, self.kappa = (_finite_number(x, name) for x, name in
                                             ((alpha, "alpha"), (beta, "beta"), (kappa, "kappa")))
        if not self.alpha > 0:
            raise InputError(f"alpha: expected a positive number, got {alpha!r}")
        super().__init__(system, dt, **kwargs)
        self._remember(system, dt, alpha=alpha, beta=beta, kappa=kappa, **kwargs)

    def _predict_sym(self, z: cs.SX, P: cs.SX, w: cs.SX) -> tuple[cs.SX, cs.SX]:
        n = self.model.nz
        lam = self.alpha**2 * (n + self.kappa) - n
        if not n + lam > 0:  # the sigma points' spread sqrt(n + lambda) and the weights 1 / (n + lambda)
            raise InputError(f"kappa: alpha^2 (nz + kappa) must be > 0 (nz = {n}, alpha = {self.alpha:g}, "
                             f"kappa = {self.kappa:g})")
        c = np.sqrt(n + lam)
        Wm = np.full(2 * n + 1, 0.5 / (n + lam))
        Wc = Wm.copy()
        Wm[0] = lam / (n + lam)
        Wc[0] = Wm[0] + 1.0 - self.alpha**2 + self.beta
        L = chol_sym(P)
        pts = [z] + [z + c * L[:, i] for i in range(n)] + [z - c * L[:, i] for i in range(n)]
        X = [self.model.step_p(p, w, self._p) for p in pts]
        zm = sum((Wm[i] * X[i] for i in range(2 * n + 1)), cs.SX.zeros(n))
        Pn = sum((Wc[i] * cs.mtimes(X[i] - zm, (X[i] - zm).T) for i in range(2 * n + 1)), cs.SX.zeros(n, n))
        G = cs.jacobian(self.model.step_p(z, w, self._p), w)
        Pn = Pn + cs.mtimes([G, cs.DM(self.Sw), G.T]) + cs.DM(self.Q)
        return zm, 0.5 * (Pn + Pn.T)


def make_observer(name: str, system: StateSpace, dt: float, **kwargs: Any) -> KalmanFilter:
    """An observer by name.

    Parameters
    ----------
    name : str
        ``"ekf"``, ``"ukf"``, ``"ekf-params"`` or ``"ukf-params"`` (the last two estimate both :data:`PARAMETERS`;
        any of them may add the ``disturbance_<motor>`` states in ``parameters``).
    system : StateSpace
        The state space observed.
    dt : float
        The sample period, s (> 0).
    **kwargs
        The filter's keywords (:class:`KalmanFilter`, :class:`UnscentedKalmanFilter`); ``process_noise`` with the
        friction's terms added (:func:`.with_friction_noise`).

    Returns
    -------
    KalmanFilter
        An :class:`ExtendedKalmanFilter` or :class:`UnscentedKalmanFilter`.

    Raises
    ------
    InputError
        An unknown name, a gain in ``parameters`` of an observer without ``-params``, or what the filter refuses.
    """
    if name not in OBSERVERS:
        raise InputError(f"unknown observer {name!r} (expected one of {', '.join(OBSERVERS)})")
    base, _, extra = name.partition("-")
    if extra:
        kwargs.setdefault("parameters", PARAMETERS)
    elif any(p in PARAMETERS for p in kwargs.get("parameters") or ()):
        raise InputError(f"observer {name!r} estimates no gain; use {name}-params")
    if "process_noise" in kwargs:
        kwargs["process_noise"] = with_friction_noise(system, dt, kwargs["process_noise"], kwargs.get("input_noise"),
                                                      kwargs.get("friction_law", "smooth"),
                                                      len(kwargs.get("parameters") or ()))
    cls = ExtendedKalmanFilter if base == "ekf" else UnscentedKalmanFilter
    return cls(system, dt, **kwargs)
