"""Time simulation of the state space x' = f(x, u[, F]) (report eq. 3.1, 3.3) and fast batched rollouts.

Two entry points:

* :func:`simulate` -- one trajectory, fixed-step RK4 or an adaptive/implicit CasADi integrator
  (``"cvodes"``: variable-order BDF; ``"idas"``: the same as a DAE), inputs given as arrays or as
  callables of time (joint or motor torques, the contact force F), friction with the smooth sign
  ``tanh(qd / v_s)`` (eq. 2.6-2.7).
* :class:`CompiledRollout` / :func:`compile_rollout` -- many trajectories at once: the RK4 step is
  generated as C by CasADi, wrapped in a small C driver that loops over steps, advances two
  trajectories per SIMD lane pair and splits the batch over POSIX threads, compiled once with
  the system C compiler (``$CC``, default gcc, ``-O3``) and cached on disk (directory
  ``$ALPES_DYN_CACHE``, default ``~/.cache/alpes_dyn``) under a hash of the generated source; the
  cache is checked before loading, locked while building and heals itself
  (:mod:`alpes_dyn.simulation.buildcache`).

The right-hand side is the state space's (eq. 3.3): A(q) + I_a, C qd + gravity, springs,
friction and J^T F from ``StateSpace.sym``, the mass matrix solved by the unrolled LDL^T of
:func:`alpes_dyn.symbolic.dynamics.block_solve` (fewer operations than a QR in generated code).

Inputs are held constant over each step (zero-order hold, as a sampled current loop does): the
input of step k, on [t_k, t_k + dt), is ``inputs[k]`` for an array and ``inputs(t_k)`` for a
callable. :func:`simulate` with ``method="rk4"`` (CasADi's virtual machine) and the compiled
rollout evaluate the same CasADi expression of one RK4 step, with the same operations in the
same order: they agree to the last bit in practice (to rounding in any case).
"""

from __future__ import annotations

import re
import sys
import weakref
from dataclasses import dataclass
from typing import Any, Sequence

import casadi as cs
import numpy as np

from .buildcache import CompilerError
from .codegen import CasadiStepLoop, CompiledStepLoop, cache_dir
from ..checks import as_float_array
from ..errors import InputError
from ..limits import check_bytes
from ..rebuild import Rebuilt
from ..model.robot import Model
from ..symbolic.statespace import StateSpace
from ..model.stops import JointStops, check_range, divergence_message
from .held_inputs import (InputLike, _check_dt, _finite, _n_steps, _sample, _sample_force,  # noqa: F401  (_check_dt:
                          _tolerance)  # importable from here, as before)
from .substeps import RK4_REACH, friction_rate, stable_substeps  # noqa: F401  (importable from here, as before)

__all__ = [
    "METHODS", "SimulationResult", "simulate", "rk4_expression", "rk4_step_function", "as_statespace", "CompiledRollout",
    "compile_rollout", "CompiledStepLoop", "cache_dir", "CompilerError", "joint_accelerations", "stable_substeps",
    "friction_rate",
]

METHODS: tuple[str, ...] = ("rk4", "cvodes", "idas")
BACKENDS: tuple[str, ...] = ("c", "casadi", "casadi-jit")
"""Backends of :class:`CompiledRollout`: the generated C driver, CasADi's virtual machine, CasADi's JIT."""



# ----------------------------------------------------------------------------- state space helpers
_SS_CACHE: "weakref.WeakKeyDictionary[Model, dict[tuple, StateSpace]]" = weakref.WeakKeyDictionary()


def as_statespace(system: Model | StateSpace, input: str = "joint", output: Any = "sum", force: bool = False,
                  smooth: bool = True) -> StateSpace:
    """``system`` itself if it is a :class:`~alpes_dyn.symbolic.statespace.StateSpace`, else a (cached) one of the model.

    The cache holds one state space per model and option set (string outputs only), because
    building the symbolic dynamics takes a fraction of a second.

    Parameters
    ----------
    system : Model or StateSpace
        The system.
    input : str
        The state space's input, ``"joint"`` (default) or ``"motor"`` (ignored for a state space, as the next).
    output : str or array_like
        Its output (default ``"sum"``).
    force : bool
        The contact force as an input (default False).
    smooth : bool
        The friction's sign as tanh (eq. 2.6-2.7; default True).

    Returns
    -------
    StateSpace

    Raises
    ------
    InputError
        A ``system`` that is neither.
    """
    if isinstance(system, StateSpace):
        return system
    if not isinstance(system, Model):
        raise InputError(f"system: expected an alpes_dyn Model or StateSpace, got {type(system).__name__}")
    if not isinstance(output, str):
        return StateSpace(system, input=input, output=output, force=force, smooth=smooth)
    key = (input, output, bool(force), bool(smooth))
    per_model = _SS_CACHE.setdefault(system, {})
    if key not in per_model:
        per_model[key] = StateSpace(system, input=input, output=output, force=force, smooth=smooth)
    return per_model[key]


def _n_known_inputs(ss: StateSpace) -> int:
    return ss.n_inputs + ss.n_force


def joint_accelerations(ss: StateSpace, q: cs.SX, v: cs.SX, tau: cs.SX, F: Any = None) -> cs.SX:
    """qdd of eq. 3.3 for joint torques ``tau``: the state space's symbolic forward dynamics
    (:meth:`SymbolicDynamics.forward_dynamics <alpes_dyn.symbolic.dynamics.SymbolicDynamics.forward_dynamics>`,
    the same expression as ``ss.f_expr``) with its tip and smooth-sign setting.

    Parameters
    ----------
    ss : StateSpace
        The state space.
    q, v, tau : casadi.SX
        Joint angles (n,) rad, velocities (n,) rad/s, torques (n,) N m.
    F : casadi.SX, optional
        The contact force(s), N (the state space's force input).

    Returns
    -------
    casadi.SX
        qdd (n,), rad/s^2.
    """
    if F is not None and not ss._legacy_force:
        return ss.sym.forward_dynamics(q, v, tau, F, None, ss.smooth, ss.contacts)
    return ss.sym.forward_dynamics(q, v, tau, F, ss.tip, ss.smooth)


def _rhs_function(ss: StateSpace, stops: JointStops | None = None) -> cs.Function:
    """f(x, w) = [qd; qdd] with w = [u; F] (F only when the state space has the contact force as input);
    ``stops`` adds the joint-stop torques (:mod:`alpes_dyn.model.stops`)."""
    w = cs.SX.sym("w", _n_known_inputs(ss))
    n = ss.n
    q, v = ss.x[:n], ss.x[n:]
    tau = ss.input_torque(q, w[: ss.n_inputs], v)
    if stops is not None:
        tau = tau + stops.torque(q, v, cs)
    qdd = joint_accelerations(ss, q, v, tau, w[ss.n_inputs:] if ss.force else None)
    return cs.Function("f", [ss.x, w], [cs.vertcat(v, qdd)], ["x", "w"], ["xdot"])


def rk4_expression(f: cs.Function, x: cs.SX, w: cs.SX, dt: float) -> cs.SX:
    """One classical Runge-Kutta step of x' = f(x, w), w held over the step: x + dt/6 (k1 + 2 k2 + 2 k3 + k4).

    Parameters
    ----------
    f : casadi.Function
        f(x, w) -> x'.
    x, w : casadi.SX
        The state and the held input.
    dt : float
        The step, s.

    Returns
    -------
    casadi.SX
        The state after the step.
    """
    k1 = f(x, w)
    k2 = f(x + 0.5 * dt * k1, w)
    k3 = f(x + 0.5 * dt * k2, w)
    k4 = f(x + dt * k3, w)
    return x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)


def rk4_step_function(system: StateSpace, dt: float, name: str = "rk4_step",
                      stops: JointStops | None = None) -> cs.Function:
    """One classical Runge-Kutta step of x' = f(x, w) with w held constant: ``step(x, w) -> x_next``.

    Parameters
    ----------
    system : StateSpace
        The state space; w = [u; F] has ``n_inputs`` (+3 with ``force=True``) entries.
    dt : float
        The step, s (> 0).
    name : str
        The function's name (default ``"rk4_step"``).
    stops : JointStops, optional
        Joint stops added to the dynamics (default none, eq. 3.3 as it is).

    Returns
    -------
    casadi.Function
        ``step(x (2n,), w (m[+3],)) -> x_next (2n,)``, an SX function (inlined expression), cached on the state
        space per ``dt``.

    Raises
    ------
    InputError
        ``dt`` not a positive finite number of seconds.
    """
    dt = _check_dt(dt)
    cache = system.__dict__.setdefault("_rk4_cache", {})
    key = (float(dt), name) if stops is None else (float(dt), name, tuple(stops.lower), tuple(stops.upper),
                                                   tuple(np.ravel(stops.stiffness)), tuple(np.ravel(stops.damping)))
    if key in cache:
        return cache[key]
    f = _rhs_function(system, stops)
    x = cs.SX.sym("x", system.n_states)
    w = cs.SX.sym("w", _n_known_inputs(system))
    xn = rk4_expression(f, x, w, dt)
    # common-subexpression elimination: the symbolic dynamics repeat sin/cos of the same angles
    step = cs.Function(name, [x, w], [cs.cse(xn)], ["x", "w"], ["x_next"])
    cache[key] = step
    return step


# ----------------------------------------------------------------------------- simulate
@dataclass
class SimulationResult:
    """A simulated trajectory.

    Attributes
    ----------
    t: (N+1,) times, s.
    x: (N+1, 2n) states [q, qd] (rad, rad/s).
    y: (N+1, p) outputs h(x) (rad).
    u: (N, m) inputs applied on each step (N m), zero-order hold.
    F: (N, 3) contact forces (N) or None.
    system: the :class:`~alpes_dyn.symbolic.statespace.StateSpace` simulated.
    method: integration method.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    u: np.ndarray
    F: np.ndarray | None
    system: StateSpace
    method: str

    @property
    def q(self) -> np.ndarray:
        """(N+1, n) joint angles, rad."""
        return self.x[:, : self.system.n]

    @property
    def v(self) -> np.ndarray:
        """(N+1, n) joint velocities, rad/s."""
        return self.x[:, self.system.n:]


def simulate(system: Model | StateSpace, x0: Sequence[float] | np.ndarray, inputs: InputLike = None,
             duration: float = 1.0, dt: float = 1e-3, method: str = "rk4", *, force: InputLike = None,
             input: str = "joint", output: Any = "sum", smooth: bool = True, rtol: float = 1e-10,
             atol: float = 1e-12, stops: JointStops | None = None, joint_range: str = "warn") -> SimulationResult:
    """Simulate x' = f(x, u[, F]) (eq. 3.3) from ``x0`` over ``duration`` seconds.

    Parameters
    ----------
    system : Model or StateSpace
        A :class:`~alpes_dyn.Model` (its state space is built with ``input``, ``output``, ``smooth``
        and ``force=force is not None``) or a :class:`~alpes_dyn.symbolic.statespace.StateSpace`.
    x0 : array_like
        Initial state [q; qd], (2n,), rad and rad/s.
    inputs : None, float, array_like or callable
        Joint torques Gamma (n) or motor torques tau_m (m), N m, per the state space's input:
        ``None`` (zero), a constant (m,), an array (N, m) with N = duration / dt, or a callable
        ``u(t) -> (m,)``. Held constant over each step.
    duration, dt : float
        Simulated time and step (the output grid), s; duration must be a whole number of steps.
    method : str
        ``"rk4"`` (fixed step, classical Runge-Kutta), ``"cvodes"`` (adaptive BDF, SUNDIALS) or
        ``"idas"`` (adaptive implicit DAE solver, SUNDIALS); the last two honour ``rtol``/``atol`` and
        restart wherever the held input changes (time-varying inputs: one run per constant stretch).
    force : None, float, array_like or callable
        Measured contact force at the state space's tip, N, base frame (eq. 2.9, 2.13): a scalar,
        an (N,) series or a callable returning F_z, or (3,), (N, 3), or a callable returning 3 values.
    input : str
        The state space's input built from a Model, ``"joint"`` (default) or ``"motor"`` (ignored for a
        StateSpace, as the next two).
    output : str or array_like
        Its output (default ``"sum"``).
    smooth : bool
        The friction's sign as tanh (default True).
    rtol, atol : float
        The SUNDIALS methods' relative and absolute tolerances (positive; default 1e-10, 1e-12).
    stops : JointStops, optional
        Joint stops (:class:`~alpes_dyn.model.stops.JointStops`, e.g. ``JointStops.of(model)``): stiff
        unilateral spring-dampers at the joint limits. Default ``None``: no stop, the report's model.
    joint_range : str
        Without stops, what happens if a joint leaves its URDF range: ``"warn"`` (default, a
        :class:`~alpes_dyn.model.stops.JointRangeWarning` naming the joint and the time), ``"error"``
        (:class:`~alpes_dyn.InputError`) or ``"ignore"``.

    Returns
    -------
    SimulationResult
        t (N+1,), x (N+1, 2n), y (N+1, p), u (N, m), F (N, 3) or None.

    Raises
    ------
    InputError
        Bad shapes, NaN, non-positive duration/dt, unknown method, a state space without force input given a
        force, an integrator failure, or arrays over the size limit (:mod:`alpes_dyn.limits`, 2 GiB by default).
    """
    ss, dt, rtol, atol = _simulation_setup(system, dt, method, force, input, output, smooth, rtol, atol, stops,
                                           joint_range)
    N = _n_steps(duration, dt)
    check_bytes(8.0 * (N + 1) * (2 * ss.n_states + ss.n_outputs + _n_known_inputs(ss)), "duration",
                f"{N} steps of {ss.n_states} states")
    x0 = ss.model.vector(x0, "x0", ss.n_states)
    t = dt * np.arange(N + 1)
    U = _sample(inputs, t[:-1], ss.n_inputs, "inputs")
    Fs = _sample_force(force, t[:-1], ss.n_force) if ss.force else None
    W = U if Fs is None else np.hstack([U, Fs])
    x = _trajectory(ss, x0, W, t, dt, method, rtol, atol, stops)
    if stops is None and joint_range != "ignore":  # here: the warning names simulate's caller
        m = ss.model
        check_range(t, x[:, : ss.n], m.lower, m.upper, m.joint_names, joint_range,
                    rest=np.where(m.extras.stiffness != 0, m.extras.rest, np.nan))
    y = np.array(ss.h_function.map(N + 1)(x[:, : 2 * ss.n].T)).T
    return SimulationResult(t=t, x=x, y=y, u=U, F=Fs, system=ss, method=method)


def _simulation_setup(system: Model | StateSpace, dt: float, method: str, force: InputLike, input: str, output: Any,
                      smooth: bool, rtol: float, atol: float, stops: JointStops | None, joint_range: str
                      ) -> tuple[StateSpace, float, float, float]:
    """(the state space simulated, dt s, rtol, atol): :func:`simulate`'s method, stops, range mode, force and
    step checked (the tolerances for the SUNDIALS methods only)."""
    if method not in METHODS:
        raise InputError(f"method: unknown integration method {method!r} (expected one of {', '.join(METHODS)})")
    if stops is not None and not isinstance(stops, JointStops):
        raise InputError(f"stops: expected a JointStops or None, got {type(stops).__name__}")
    check_range(np.zeros(1), np.zeros((1, 0)), np.zeros(0), np.zeros(0), (), joint_range)  # validates the mode
    ss = as_statespace(system, input, output, force is not None, smooth)
    if force is not None and not ss.force:
        raise InputError("force: this state space has no contact-force input (build it with force=True)")
    if force is None and ss.force:
        raise InputError("force: this state space has the contact force as an input; pass force=")
    dt = _check_dt(dt)
    if method != "rk4":
        rtol, atol = _tolerance(rtol, "rtol"), _tolerance(atol, "atol")
    return ss, dt, rtol, atol


def _trajectory(ss: StateSpace, x0: np.ndarray, W: np.ndarray, t: np.ndarray, dt: float, method: str, rtol: float,
                atol: float, stops: JointStops | None) -> np.ndarray:
    """(N+1, nx) states at the times ``t`` (s, steps of ``dt``) from ``x0`` under the held inputs W (N, inputs):
    RK4 (one compiled ``mapaccum``) or SUNDIALS; a non-finite state is an error naming its time."""
    N = t.size - 1
    if method == "rk4":
        step = rk4_step_function(ss, dt, stops=stops)
        X = np.array(step.mapaccum("rk4_traj", N)(x0, W.T))
    else:
        X = _integrate_sundials(ss, x0, W, t, method, rtol, atol, stops)
    x = np.vstack([x0, X.T])
    if not np.isfinite(x).all():
        k = int(np.argmax(~np.isfinite(x).all(axis=1)))
        m, tr = ss.model, ss.model.transmission
        raise InputError(divergence_message(t, x[:, : ss.n], k, m.lower, m.upper, m.joint_names,
                                            tr is not None and tr.curved))
    return x


def _integrate_sundials(ss: StateSpace, x0: np.ndarray, W: np.ndarray, t: np.ndarray, method: str,
                        rtol: float, atol: float, stops: JointStops | None = None) -> np.ndarray:
    """(nx, N) states at t[1:]: the input piecewise constant, the solver restarted wherever it changes.

    One SUNDIALS run over a grid with the input switching at the grid points fails its error test at the
    first jump ("CV_ERR_FAILURE" at t = dt, h ~ 1e-10: BDF's history spans the discontinuity); each run of
    equal input rows is integrated on its own, from the state where the previous one ended (the state space
    is autonomous: time enters through the input only)."""
    from ..fileio import native_stderr_to

    f = _rhs_function(ss, stops)
    w = cs.SX.sym("w", W.shape[1])
    dae = {"x": ss.x, "p": w, "ode": f(ss.x, w)}
    opts: dict[str, Any] = {"abstol": float(atol), "reltol": float(rtol), "max_num_steps": 1_000_000}
    N, dt = W.shape[0], float(t[1] - t[0])
    starts = np.r_[0, np.flatnonzero(np.any(W[1:] != W[:-1], axis=1)) + 1]
    ends = np.r_[starts[1:], N]
    runs: dict[int, cs.Function] = {}  # one integrator per run length (a sine input: length 1 only)
    X = np.empty((ss.n_states, N))
    x = np.asarray(x0, dtype=float)
    printed: list[str] = []  # SUNDIALS prints its reason ("the error test failed...") on fd 2: into the message
    for k0, k1 in zip(starts, ends):
        L = int(k1 - k0)
        try:
            with native_stderr_to(printed):
                if L not in runs:
                    runs[L] = cs.integrator(f"sim{L}", method, dae, 0.0, list(dt * np.arange(1, L + 1)), opts)
                xs = np.array(runs[L](x0=x, p=W[k0])["xf"]).reshape(ss.n_states, L)
        except RuntimeError as exc:
            why = next((ln.strip() for ln in printed if ln.strip()), "")  # its t is the run's own: dropped
            why = re.sub(r"^At t = [^,]*?(?: and h = [^,]*)?, ", "", why)
            code = str(exc).strip().splitlines()[-1] if str(exc).strip() else "failed"
            code = code.split('returned "', 1)[-1].split('"', 1)[0] if 'returned "' in code else code
            raise InputError(f"integrator {method} failed on [{t[k0]:g}, {t[k1]:g}] s ({code}"
                             f"{': ' + why.rstrip('.') if why else ''}); loosen rtol/atol, or use method='rk4'") from None
        X[:, k0:k1] = xs
        x = xs[:, -1]
    return X


class CompiledRollout(Rebuilt):
    """Batched fixed-step RK4 rollouts of a state space in compiled C, threaded over the batch.

    Parameters
    ----------
    system : StateSpace or Model
        A :class:`~alpes_dyn.symbolic.statespace.StateSpace` (or a Model, with ``input`` and ``force``).
    dt : float
        RK4 step, s, fixed at compile time.
    input : str
        A Model's state space input, ``"joint"`` (default) or ``"motor"``.
    force : bool
        A Model's state space with the contact force as an input (default False).
    threads : int, optional
        Worker threads, 1 to 64 (default: the CPUs this process may use).
    backend : str
        ``"c"``, ``"casadi"`` or ``"casadi-jit"`` (below).

    The step is :func:`rk4_step_function` (the one :func:`simulate` evaluates with
    ``method="rk4"``), compiled by :class:`CompiledStepLoop`: results equal :func:`simulate`'s to
    rounding. ``compile_seconds`` (0 when loaded from the cache) and ``library`` describe the build.
    ``backend``: ``"c"`` (default, the generated driver), ``"casadi"`` (CasADi's stock ``mapaccum`` + threaded
    ``map`` in its virtual machine: no compiler) or ``"casadi-jit"`` (the same JIT-compiled by CasADi, per
    process): :class:`~alpes_dyn.simulation.codegen.CasadiStepLoop`, the documented fallback.

    Raises
    ------
    InputError
        An unknown backend, a bad ``dt`` or ``threads``.
    CompilerError
        The C compiler failed (backend ``"c"``).
    """

    def __init__(self, system: Model | StateSpace, dt: float, *, input: str = "joint", force: bool = False,
                 threads: int | None = None, backend: str = "c") -> None:
        self._remember(system, dt, input=input, force=force, threads=threads, backend=backend)
        if backend not in BACKENDS:
            raise InputError(f"backend: expected one of {', '.join(BACKENDS)}, got {backend!r}")
        out: Any = "sum"
        if isinstance(system, Model) and system.transmission is None:
            out = np.eye(system.n)[:1]  # any output: a rollout returns states
        ss = as_statespace(system, input, out, force)
        self.system = ss
        self.dt = _check_dt(dt)
        self.nx = ss.n_states
        self.nw = _n_known_inputs(ss)
        step = rk4_step_function(ss, self.dt)
        self.backend = backend
        self._loop: CompiledStepLoop | CasadiStepLoop = (
            CompiledStepLoop(step, f"rollout_{ss.model.name}", threads) if backend == "c"
            else CasadiStepLoop(step, threads, jit=backend == "casadi-jit"))
        self.threads = self._loop.threads
        self.library, self.compiled, self.compile_seconds = (self._loop.library, self._loop.compiled,
                                                             self._loop.compile_seconds)

    def __repr__(self) -> str:
        return (f"CompiledRollout({self.system.model.name!r}, dt={self.dt:g}, states={self.nx}, inputs={self.nw}, "
                f"threads={self.threads})")

    def rollout(self, x0_batch: np.ndarray, U_batch: np.ndarray, F_batch: np.ndarray | None = None, *,
                progress: bool | None = None) -> np.ndarray:
        """Roll out B trajectories of N RK4 steps.

        Parameters
        ----------
        x0_batch : array_like
            (B, 2n) initial states [q; qd] (rad, rad/s); (2n,) is broadcast over the batch.
        U_batch : array_like
            (B, N, m) inputs per step, N m (zero-order hold); (N, m) is broadcast over x0_batch.
        F_batch : array_like, optional
            (B, N, 3) contact forces, N (base frame), when the state space has ``force=True``.
        progress : bool, optional
            Show a progress bar on stderr (default: when stderr is a terminal and B N >= 1e6).

        Returns
        -------
        numpy.ndarray
            (B, N+1, 2n) states, X[:, 0] = x0_batch.

        Raises
        ------
        InputError
            Shapes that do not match, a batch size that does not match, NaN or inf, a force given to a rollout
            without force input (or missing), arrays over the size limit, or a diverged rollout.
        """
        x0 = as_float_array(x0_batch, "x0_batch", "an array of states")
        U = as_float_array(U_batch, "U_batch", "an array of inputs")
        m = self.system.n_inputs
        if x0.ndim == 1:
            x0 = x0[None, :]
        if U.ndim == 2:
            U = U[None]
        if x0.ndim != 2 or x0.shape[1] != self.nx:
            raise InputError(f"x0_batch: expected shape (B, {self.nx}), got {np.shape(x0_batch)}")
        if U.ndim != 3 or U.shape[2] != m:
            raise InputError(f"U_batch: expected shape (B, N, {m}), got {np.shape(U_batch)}")
        N = U.shape[1]
        if N < 1:
            raise InputError("U_batch: needs at least one step")
        batched = [(x0, "x0_batch"), (U, "U_batch")]
        nf = self.system.n_force
        if self.system.force:
            if F_batch is None:
                raise InputError(f"F_batch: this rollout has the contact force as an input; pass (B, N, {nf})")
            F = as_float_array(F_batch, "F_batch", "an array of forces")
            if F.ndim == 2:
                F = F[None]
            if F.ndim != 3 or F.shape[1:] != (N, nf):
                raise InputError(f"F_batch: expected shape (B, {N}, {nf}), got {np.shape(F_batch)}")
            batched.append((F, "F_batch"))
        elif F_batch is not None:
            raise InputError("F_batch: this rollout has no contact-force input (build it with force=True)")
        B = max(a.shape[0] for a, _ in batched)
        for a, name in batched:
            if a.shape[0] not in (1, B):
                raise InputError(f"{name}: batch size {a.shape[0]} does not match {B}")
        check_bytes(8.0 * B * ((N + 1) * self.nx + N * self.nw), "U_batch", f"{B} trajectories of {N} steps")
        W = np.broadcast_to(U, (B, N, m))
        if self.system.force:
            W = np.concatenate([W, np.broadcast_to(F, (B, N, nf))], axis=2)
        W = _finite(np.ascontiguousarray(W, dtype=float), "U_batch")
        x0 = _finite(np.ascontiguousarray(np.broadcast_to(x0, (B, self.nx))), "x0_batch")
        if progress is None:
            progress = B * N >= 1_000_000 and sys.stderr.isatty()
        X = self._loop.run(x0, W, progress, f"rollout {self.system.model.name} B={B} N={N}")
        if not np.isfinite(X[:, -1]).all():
            raise InputError("rollout diverged (non-finite states); reduce dt or the inputs")
        return X

    __call__ = rollout


def compile_rollout(system: Model | StateSpace, dt: float, *, input: str = "joint", force: bool = False,
                    threads: int | None = None, backend: str = "c") -> CompiledRollout:
    """Build (or load from the cache) a :class:`CompiledRollout`.

    Parameters
    ----------
    system : StateSpace or Model
        The system.
    dt : float
        RK4 step, s.
    input : str
        A Model's state space input (default ``"joint"``).
    force : bool
        The contact force as an input (default False).
    threads : int, optional
        Worker threads (default: the CPUs this process may use).
    backend : str
        ``"c"`` (default), ``"casadi"`` or ``"casadi-jit"``.

    Returns
    -------
    CompiledRollout

    Raises
    ------
    InputError
        As :class:`CompiledRollout`.
    CompilerError
        The C compiler failed.
    """
    return CompiledRollout(system, dt, input=input, force=force, threads=threads, backend=backend)
