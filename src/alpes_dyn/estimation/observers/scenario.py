"""The default estimation scenario: a finger moved by its motor, its joints estimated from the encoder.

What is simulated (``alpes-dyn estimate``, :func:`run_estimation`), all seeded by ``seed``:

* the true finger: ``Model.alpes(model)`` -- torsional springs, no friction, no rotor inertia (the
  report's working model, eq. 2.11) -- integrated with RK4 at dt / 4 (0.25 ms);
* the motor torque (N m, per motor): a bias of 0.0222 N m that holds the finger half-flexed plus
  sines of 1.5, 0.5 and 0.2 mN m at 0.2, 0.7 and 3.1 Hz, so that the finger sweeps its range
  (q_1 between about -15 and 95 degrees: nothing damps the finger, the report's model
  has no friction, and no joint stop is modelled);
* the true finger starts at rest (qd = 0) near its static equilibrium under the initial torque
  (q_1..q_3 about 0.3, 0.8, 0.7 rad), each joint offset by a seeded draw uniform in +-0.1 rad, while
  the observer starts from the stretched rest position q = 0, qd = 0 (report, Conclusion);
* measurements at 1 kHz (dt = 1 ms): the motor encoder q_m = (r/r_m) sum q (Section 3), quantised
  to the model's ``transmission.counts_per_rev`` (4096 counts per motor revolution assumed in the
  parameter file, ``transmission.encoder_counts``: a 1024-line quadrature encoder), with an extra
  Gaussian noise of ``encoder_noise_counts`` (0.5) counts; the motor torque known to the observer
  is the true one plus a white noise of ``torque_noise`` (5e-4 N m: 1 % of a 0.05 N m full-scale
  motor current sensor, 2.5 % of the torque that holds the finger half-flexed);
* ``mismatch`` d: the observer's springs are (1 + d) times the true ones and its masses and
  inertias (1 - d) times (``mismatch_signs = (-1, 1)``, the worse case for a fixed |d|: the two
  errors add up in the spring-to-inertia ratio); ``observer_params`` gives the observer any other
  parameter set (the gains' true values are then unknown: NaN);
* the run: a composition of blocks (:func:`~alpes_dyn.simulation.loop.run_loop`): the torque profile, the true
  finger (:class:`~alpes_dyn.simulation.plants.SimulatorPlant`), the encoder and the current sensor (their noise
  drawn in that order from the seed's generator, after the initial offsets), the observer;
* error metrics after ``transient`` seconds (default min(1 s, duration / 5)): the RMSE of each q_i (rad), and the
  final error |q_hat - q| at the last sample.

One chain of the hand: ``chain`` (a finger's name) makes the finger model that finger of the files
(its ``[finger.<name>]`` values, in the truth's and the observer's file); ``model="thumb"`` is the thumb
(``friction=True``: its ab/adduction has no spring), whose flexion motor gets the torque above and whose
ab/adduction motor the sines times :data:`ABDUCTION_SCALE` without bias, its joint starting mid-range.
Note that a finger with soft springs may have no rest at the 0.0222 N m bias (a fold of its static
equilibria, see :mod:`alpes_dyn.estimation.experiments.experiment`): the scenario then fails with a one-line error.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ...errors import InputError
from ...fileio import atomic_path, check_output_path
from ...limits import check_bytes
from ...model.robot import Model
from .observers import OBSERVERS, PARAMETERS, Estimate, make_observer, true_gains
from ...model.params import HandParams, load_params
from ...simulation.integrate import stable_substeps
from ...simulation.loop import Source, run_loop
from ...simulation.plants import SimulatorPlant
from ...simulation.sensors import Encoder, TorqueSensor
from .blocks import Observer
from ...symbolic.statespace import StateSpace

SCENARIO_MODELS: tuple[str, ...] = ("finger2", "finger3")
ESTIMATION_MODELS: tuple[str, ...] = SCENARIO_MODELS + ("thumb",)
"""The models the estimation scenario runs on: a finger (the shared one, or a finger of the hand with
``chain``) or the thumb (``friction=True``: its ab/adduction has no spring)."""
ABDUCTION_SCALE = 0.2
"""The thumb's ab/adduction motor gets the scenario's sines times this, and no bias (palm up, gravity does not
load it): 0.3 mN m at most, below the joint's 0.5 mN m Coulomb friction, so that it creeps by degrees."""

__all__ = [
    "SCENARIO_MODELS", "ESTIMATION_MODELS", "EstimationScenario", "EstimationResult", "run_estimation", "mismatched_params",
    "plot_estimation", "check_plot_path", "static_equilibrium", "default_noise", "scenario_torque",
]


def _check_settings(sc: "EstimationScenario") -> None:
    """Types and ranges of the numeric settings (before any arithmetic with them)."""
    for name in ("duration", "dt", "mismatch", "transient", "q0_offset", "encoder_noise_counts", "torque_noise",
                 "torque_bias"):
        x = getattr(sc, name)
        if x is None and name == "transient":
            continue
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
            raise InputError(f"{name}: expected a number, got {x!r}")
        if isinstance(x, int) and abs(x) > 2**53:
            raise InputError(f"{name}: {str(x)[:20]}... is too large")
        if not np.isfinite(x):
            raise InputError(f"{name}: expected a finite number, got {x!r}")
    if not sc.dt > 0:
        raise InputError(f"dt: expected a positive number of seconds, got {sc.dt!r}")
    for name in ("q0_offset", "encoder_noise_counts", "torque_noise"):
        if getattr(sc, name) < 0:
            raise InputError(f"{name}: expected a number >= 0, got {getattr(sc, name)!r}")
    for name, low in (("substeps", 1), ("seed", 0)):
        x = getattr(sc, name)
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)) or x < low:
            raise InputError(f"{name}: expected an integer >= {low}, got {x!r}")


def mismatched_params(params: HandParams, mass_scale: float, spring_scale: float) -> HandParams:
    """``params`` with finger (each finger's own values too) and thumb masses and inertias times ``mass_scale``,
    springs times ``spring_scale``.

    Parameters
    ----------
    params : HandParams
        The hand's parameters.
    mass_scale : float
        The factor on the masses and inertias (the thumb base's mass too).
    spring_scale : float
        The factor on the springs (the ab/adduction spring too).

    Returns
    -------
    HandParams
        A copy with the scaled values.
    """
    def chain(c):
        return dataclasses.replace(c, m=c.m * mass_scale, I=c.I * mass_scale, K=c.K * spring_scale)

    return dataclasses.replace(params, finger=chain(params.finger), thumb=chain(params.thumb),
                               fingers={k: chain(c) for k, c in params.fingers.items()},
                               thumb_base_mass=params.thumb_base_mass * mass_scale,
                               abduction_K=params.abduction_K * spring_scale)


@dataclass(frozen=True)
class EstimationScenario:
    """Settings of the default estimation scenario (see the module docstring); all SI units."""

    model: str = "finger3"
    spring: str = "torsional"
    friction: bool = False
    duration: float = 5.0
    dt: float = 1e-3
    substeps: int = 4
    seed: int = 0
    mismatch: float = 0.0
    transient: float | None = None
    torque_bias: float = 0.0222
    torque_amplitudes: tuple[float, ...] = (0.0015, 0.0005, 0.0002)
    torque_frequencies: tuple[float, ...] = (0.2, 0.7, 3.1)
    q0_offset: float = 0.1
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    mismatch_signs: tuple[float, float] = (-1.0, 1.0)
    parameters: tuple[str, ...] = PARAMETERS
    params: Any = field(default=None, compare=False)
    observer_params: Any = field(default=None, compare=False)
    chain: str | None = None

    @property
    def transient_s(self) -> float:
        """Start of the error metrics, s: ``transient`` if set, else min(1 s, duration / 5)."""
        return float(self.transient) if self.transient is not None else min(1.0, 0.2 * float(self.duration))

    def check(self) -> None:
        if self.model not in ESTIMATION_MODELS:
            raise InputError(f"model: the estimation scenario is defined for one finger or the thumb "
                             f"({', '.join(ESTIMATION_MODELS)}), got {self.model!r}")
        if self.model == "thumb" and not self.friction:
            raise InputError("friction: the thumb's scenario needs friction=True (the command line's --friction; its "
                             "ab/adduction has no spring: without friction nothing holds it)")
        if self.spring != "torsional":
            raise InputError(f"spring: the scenario's torque profile is balanced by the torsional springs; "
                             f"got spring model {self.spring!r}")
        _check_settings(self)
        if not (np.isfinite(self.duration) and self.duration > 0):
            raise InputError(f"duration: expected a positive number of seconds, got {self.duration!r}")
        if not (np.isfinite(self.mismatch) and -0.5 < self.mismatch < 0.5):
            raise InputError(f"mismatch: expected a fraction in (-0.5, 0.5), got {self.mismatch!r}")
        if not 0 <= self.transient_s < self.duration:
            raise InputError(f"transient: {self.transient_s:g} s must be shorter than the duration {self.duration:g} s")
        if self.substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {self.substeps!r}")


@dataclass
class EstimationResult:
    """True and estimated trajectories of one observer run, and the error metrics.

    Attributes
    ----------
    t: (N+1,) times, s. x_true: (N+1, 2n) true [q; qd]. estimate: the observer's :class:`Estimate`.
    y: (N+1, p) encoder readings (rad of motor shaft). u_meas: (N, m) measured motor torques (N m).
    rmse: (n,) RMSE of each q_i after the transient, rad. final_error: (n,) |q_hat - q| at t_N, rad.
    parameters: estimated gains at t_N and their true values, by name.
    backend: ``"compiled"`` or ``"casadi"``. counts_per_rev: encoder resolution used.
    filter: the observer run (its known inputs ``u_meas``, :func:`~alpes_dyn.estimation.observers.consistency.nees`).
    """

    scenario: EstimationScenario
    observer: str
    t: np.ndarray
    x_true: np.ndarray
    estimate: Estimate
    y: np.ndarray
    u_meas: np.ndarray
    rmse: np.ndarray
    final_error: np.ndarray
    joint_names: tuple[str, ...]
    parameters: dict[str, dict[str, float]]
    backend: str
    counts_per_rev: float
    filter: Any = None

    @property
    def q_true(self) -> np.ndarray:
        return self.x_true[:, : len(self.joint_names)]

    @property
    def q_hat(self) -> np.ndarray:
        return self.estimate.z[:, : len(self.joint_names)]

    def to_dict(self) -> dict[str, Any]:
        """The JSON summary printed by ``alpes-dyn estimate --json``."""
        sc = self.scenario
        params = {k: {kk: (vv if np.isfinite(vv) else None) for kk, vv in v.items()}
                  for k, v in self.parameters.items()}
        return {
            "model": sc.model, "chain": sc.chain, "observer": self.observer, "rmse": self.rmse.tolist(),
            "rmse_deg": np.degrees(self.rmse).tolist(), "transient_s": sc.transient_s,
            "final_error": self.final_error.tolist(), "joints": list(self.joint_names),
            "duration_s": sc.duration, "dt_s": sc.dt, "seed": sc.seed, "mismatch": sc.mismatch,
            "parameters": params, "counts_per_rev": self.counts_per_rev,
            "encoder_noise_counts": sc.encoder_noise_counts, "torque_noise_Nm": sc.torque_noise,
            "backend": self.backend,
        }


def static_equilibrium(model: Model, tau: np.ndarray, q: np.ndarray | None = None, tol: float = 1e-12) -> np.ndarray:
    """Joint angles q (rad) where gravity and springs balance the joint torques: G(q) = tau (eq. 2.11).

    Kept for compatibility: :meth:`Model.static_equilibrium <alpes_dyn.Model.static_equilibrium>` (and
    :meth:`StateSpace.equilibrium <alpes_dyn.symbolic.statespace.StateSpace.equilibrium>` for a state and an input).

    Parameters
    ----------
    model : Model
        The model.
    tau : numpy.ndarray, shape (n,)
        The joint torques, N m.
    q : numpy.ndarray, shape (n,), optional
        The start of Newton's method, rad (default None: zeros).
    tol : float, optional
        Stop when max abs(G(q) - tau) < ``tol``, N m (default 1e-12).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The joint angles, rad.
    """
    return model.static_equilibrium(tau, q, tol)


def _torque(sc: EstimationScenario, t: np.ndarray, m: int, held: Sequence[int] = ()) -> np.ndarray:
    """(len(t), m) motor torque profile, N m; motor j's sines are phase-shifted by j radians. The motors
    ``held`` (of joints without spring: the thumb's ab/adduction) get no bias and the sines times
    :data:`ABDUCTION_SCALE`."""
    out = np.full((t.shape[0], m), sc.torque_bias)
    for j in range(m):
        scale = ABDUCTION_SCALE if j in held else 1.0
        if j in held:
            out[:, j] = 0.0
        for a, f in zip(sc.torque_amplitudes, sc.torque_frequencies):
            out[:, j] += scale * a * np.sin(2 * np.pi * f * t + j)
    return out


def scenario_torque(scenario: EstimationScenario, t: np.ndarray, m: int) -> np.ndarray:
    """(len(t), m) N m: the scenario's motor torque at the times ``t`` (s) on ``m`` motors, every motor biased (the
    profile ``run_estimation`` drives a finger with; a plant of the caller's replays it).

    Parameters
    ----------
    scenario : EstimationScenario
        The scenario (its torque bias, amplitudes and frequencies; motor j's sines phase-shifted by j rad).
    t : numpy.ndarray, shape (N,)
        The times, s.
    m : int
        The number of motors.

    Returns
    -------
    numpy.ndarray, shape (N, m)
        The motor torques, N m.
    """
    return _torque(scenario, np.asarray(t, dtype=float), int(m))


def _held_joints(model: Model) -> tuple[tuple[str, ...], list[int]]:
    """Joints without spring (the thumb's ab/adduction) and the motors that drive them."""
    joints = model.springless_joints
    idx = [model.joint_index(j) for j in joints]
    S = model.transmission.S
    return joints, [k for k in range(S.shape[0]) if np.any(S[k, idx] != 0)]


def held_mid_range(model: Model) -> np.ndarray:
    """q (n,), rad: 0, but the joints without spring (the thumb's ab/adduction) mid-range."""
    q = np.zeros(model.n)
    for j in model.springless_joints:
        i = model.joint_index(j)
        q[i] = 0.5 * (model.lower[i] + model.upper[i])
    return q


def rest_with_held_joints(model: Model, tau_m: np.ndarray) -> np.ndarray:
    """Joint angles q (n,), rad: the static equilibrium under the motor torques ``tau_m`` (m,), N m, the
    joints without spring held mid-range (:func:`held_mid_range`; eq. 2.11; raises
    :class:`~alpes_dyn.InputError` where there is no rest)."""
    return model.static_equilibrium(None, held_mid_range(model), fixed=model.springless_joints, tau_m=tau_m)


def default_noise(sc: EstimationScenario, n: int, m: int, n_params: int, meas_var: float) -> dict[str, Any]:
    """Observer noise settings for the scenario (the keyword arguments of a Kalman filter).

    Measurement: the encoder's quantisation plus its noise (``meas_var``, rad^2). Known input: the
    motor torque noise ``torque_noise`` squared on each of the m motors. Process noise per step: 1e-9 rad on q (numerical),
    2e-4 rad/s on qd (unmodelled accelerations, 0.2 rad/s^2 over a 1 ms step) and 2e-5 per step on
    each gain (a random walk: the gains may drift by 1e-3 in a second). With friction
    :func:`~alpes_dyn.estimation.observers.observers.make_observer` adds the smooth law's model error on qd
    (:func:`~alpes_dyn.estimation.observers.friction_noise.friction_process_noise`).

    Parameters
    ----------
    sc : EstimationScenario
        The scenario (its ``torque_noise``, N m).
    n : int
        The number of joints.
    m : int
        The number of motors (and of encoders).
    n_params : int
        The number of gains in the state.
    meas_var : float
        The measurement's variance per encoder, rad^2.

    Returns
    -------
    dict[str, Any]
        ``process_noise`` (2 n + n_params,), ``measurement_noise`` (m,) and ``input_noise`` (m,) variances.
    """
    Q = [1e-9**2] * n + [2e-4**2] * n + [2e-5**2] * n_params
    return {"process_noise": Q, "measurement_noise": [meas_var] * m, "input_noise": [sc.torque_noise**2] * m}


def _scenario_observer(sc: EstimationScenario, observer: str, p: HandParams, compiled: bool, n: int, m: int,
                       counts_per_rev: float) -> tuple[Any, np.ndarray, np.ndarray, float, float]:
    """The scenario's observer on its model, possibly mis-scaled, for the truth's encoder of ``counts_per_rev``:
    (filter, z0 (nz,), P0 (nz,) variances, mass_scale, spring_scale -- NaN for ``observer_params``)."""
    d = sc.mismatch
    mass_scale, spring_scale = 1.0 + sc.mismatch_signs[0] * d, 1.0 + sc.mismatch_signs[1] * d
    if sc.observer_params is not None:
        p_obs = sc.observer_params if isinstance(sc.observer_params, HandParams) else load_params(sc.observer_params)
        mass_scale = spring_scale = float("nan")
    else:
        p_obs = mismatched_params(p, mass_scale, spring_scale) if d != 0 else p
    obs_model = Model.alpes(sc.model, spring=sc.spring, friction=sc.friction, params=p_obs, chain=sc.chain)
    ss = StateSpace(obs_model, input="motor", output="encoder")
    pars = tuple(sc.parameters) if observer.endswith("-params") else ()
    n_params = len(pars)
    step = 2 * np.pi / counts_per_rev
    meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
    noise = default_noise(sc, n, m, n_params, meas_var)  # make_observer adds the smooth law's model error
    # with friction the observer's model needs the truth's RK4 substeps (h lambda of the smooth sign)
    filt = make_observer(observer, ss, sc.dt, compiled=compiled, parameters=pars,
                         substeps=max(sc.substeps, stable_substeps(obs_model, sc.dt)) if sc.friction else 1, **noise)
    z0 = np.concatenate([np.zeros(2 * n), np.ones(n_params)])
    P0 = np.array([0.5**2] * n + [1.0**2] * n + [0.2**2] * n_params)
    return filt, z0, P0, mass_scale, spring_scale



def run_estimation(observer: str = "ekf", scenario: EstimationScenario | None = None, *,
                   compiled: bool = False, **overrides: Any) -> EstimationResult:
    """Simulate the default scenario and run an observer on it.

    Parameters
    ----------
    observer : str, optional
        One of :data:`~alpes_dyn.estimation.observers.observers.OBSERVERS`.
    scenario : EstimationScenario or None, optional
        The settings (default :class:`EstimationScenario`).
    compiled : bool, optional
        Run the filter in compiled C (default: CasADi's virtual machine; the same numbers).
    **overrides
        Fields of the scenario replaced, e.g. ``run_estimation("ekf-params", mismatch=0.1, duration=5.0)``.

    Returns
    -------
    EstimationResult
        With the RMSE of each q_i after the transient (rad).
    """
    sc = dataclasses.replace(scenario or EstimationScenario(), **overrides)
    sc.check()
    if observer not in OBSERVERS:
        raise InputError(f"unknown observer {observer!r} (expected one of {', '.join(OBSERVERS)})")
    p = sc.params if isinstance(sc.params, HandParams) else load_params(sc.params)
    truth = Model.alpes(sc.model, spring=sc.spring, friction=sc.friction, params=p, chain=sc.chain)
    rng = np.random.default_rng(sc.seed)
    n, m = truth.n, truth.transmission.n_motors
    _, held_motors = _held_joints(truth)
    if not sc.duration / sc.dt < 2.0**53:
        raise InputError(f"duration: {sc.duration:g} s at dt = {sc.dt:g} s is more than 2^53 samples")
    N = int(round(sc.duration / sc.dt))
    if N < 2:
        raise InputError(f"duration: {sc.duration:g} s is shorter than two samples of dt = {sc.dt:g} s")
    if abs(N * sc.dt - sc.duration) > 1e-9 * sc.duration:
        raise InputError(f"duration: {sc.duration:g} s is not a whole number of samples dt = {sc.dt:g} s")
    # the arrays kept per sample (truth at dt / substeps, filter states and covariances), times 6 for the
    # copies CasADi and numpy make on the way
    nz = 2 * n + (len(sc.parameters) if observer.endswith("-params") else 0)
    check_bytes(48.0 * (N + 1) * (sc.substeps * (4 * n + 2 * m + 1) + 2 * (nz + nz * nz) + 4 * n + 3 * m), "duration",
                f"{sc.duration:g} s at dt = {sc.dt:g} s ({N} samples)")

    # the composition (alpes_dyn.simulation.loop): torque -> the true finger -> encoder, torque sensor -> observer
    t = sc.dt * np.arange(N + 1)
    u_true = _torque(sc, t[:-1], m, held_motors)
    # the joints without spring start mid-range (held there by hand)
    q0 = rest_with_held_joints(truth, u_true[0]) + rng.uniform(-sc.q0_offset, sc.q0_offset, size=n)
    sub = max(sc.substeps, stable_substeps(truth, sc.dt))  # a sharper friction sign asks for more
    filt, z0, P0, mass_scale, spring_scale = _scenario_observer(sc, observer, p, compiled, n, m,
                                                                        truth.transmission.counts_per_rev)
    blocks = [Source("torque", tau=np.concatenate([u_true, u_true[-1:]])),  # held: the last row for C u at t_N
              SimulatorPlant(truth, np.concatenate([q0, np.zeros(n)]), substeps=sub),  # no stop, as documented
              Encoder("q_m", "y", truth.transmission.counts_per_rev, noise_counts=sc.encoder_noise_counts, rng=rng,
                      shape=(m,)),
              TorqueSensor("tau", "u_meas", noise=sc.torque_noise, rng=rng, shape=(m,), timing="period"),
              Observer(filt, z0, P0, known=("u_meas",), measurement="y")]
    log = run_loop(blocks, N, sc.dt, final=True)
    x_true, y, u_meas = log["x"], log["y"], log["u_meas"]
    est = Estimate(t=filt.dt * np.arange(N + 1), z=log["z"], P=log["P"], names=filt.names)

    k0 = int(round(sc.transient_s / sc.dt))
    err = est.z[:, :n] - x_true[:, :n]
    rmse = np.sqrt(np.mean(err[k0:] ** 2, axis=0))
    gains = true_gains(mass_scale, spring_scale)
    params_out = {name: {"estimate": float(est.z[-1, 2 * n + i]), "true": gains.get(name, float("nan"))}
                  for i, name in enumerate(filt.model.parameters)}
    res = EstimationResult(scenario=sc, observer=observer, t=t, x_true=x_true, estimate=est, y=y, u_meas=u_meas,
                           rmse=rmse, final_error=np.abs(err[-1]), joint_names=truth.joint_names,
                           parameters=params_out, backend=filt.backend,
                           counts_per_rev=float(truth.transmission.counts_per_rev), filter=filt)
    return res


def check_plot_path(path: str) -> Path:
    """Validate a figure file name before a run (:class:`~alpes_dyn.InputError` naming ``--plot``): matplotlib
    installed, not empty, not a directory, an existing writable directory, a format matplotlib writes
    (by extension: .png, .pdf, .svg, ...).

    Parameters
    ----------
    path : str
        The figure's file name.

    Returns
    -------
    pathlib.Path
        The checked path.

    Raises
    ------
    InputError
        Naming ``--plot``.
    """
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError:
        raise InputError("--plot: matplotlib is not installed (pip install matplotlib)") from None
    return check_output_path(path, "--plot", sorted(FigureCanvasBase.get_supported_filetypes()))


def plot_estimation(result: EstimationResult, path: str) -> None:
    """Write a figure of the true and estimated q_i over time with the estimate's +-2 sigma band.

    One panel per joint (degrees), a vertical line at the end of the transient; needs matplotlib. The
    format follows the extension (PNG, PDF, SVG...); the file is written atomically (never partial).

    Parameters
    ----------
    result : EstimationResult
        The run of :func:`run_estimation`.
    path : str
        The figure's file name (checked by :func:`check_plot_path`).
    """
    dest = check_plot_path(path)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = len(result.joint_names)
    t = result.t
    sd = result.estimate.std[:, :n]
    fig, axes = plt.subplots(n + 1, 1, figsize=(9, 2.2 * (n + 1)), sharex=True)
    for i in range(n):
        ax = axes[i]
        qt, qh = np.degrees(result.q_true[:, i]), np.degrees(result.q_hat[:, i])
        ax.plot(t, qt, color="k", lw=1.2, label="true")
        ax.plot(t, qh, color="C0", lw=1.0, label=f"{result.observer} estimate")
        ax.fill_between(t, qh - 2 * np.degrees(sd[:, i]), qh + 2 * np.degrees(sd[:, i]), color="C0", alpha=0.25,
                        label="estimate +- 2 sigma")
        ax.axvline(result.scenario.transient_s, color="gray", ls="--", lw=0.8)
        ax.set_ylabel(f"q_{i + 1} ({result.joint_names[i]}) [deg]")
        ax.set_title(f"RMSE after {result.scenario.transient_s:g} s: {np.degrees(result.rmse[i]):.3f} deg", fontsize=9)
        if i == 0:
            ax.legend(loc="upper right", fontsize=8)
    ax = axes[n]
    err = np.degrees(result.q_hat - result.q_true)
    for i in range(n):
        ax.plot(t, err[:, i], lw=0.8, label=f"q_{i + 1}")
    band = 2 * np.degrees(sd).max(axis=1)
    ax.fill_between(t, -band, band, color="gray", alpha=0.2, label="+- 2 sigma (max over joints)")
    lim = max(1.0, 3 * float(np.degrees(result.rmse).max()))
    ax.set_ylim(-lim, lim)
    ax.axvline(result.scenario.transient_s, color="gray", ls="--", lw=0.8)
    ax.set_ylabel("error [deg]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right", fontsize=8, ncol=4)
    sc = result.scenario
    fig.suptitle(f"{sc.model}: joints from the motor encoder ({result.observer}, mismatch {sc.mismatch:g}, "
                 f"seed {sc.seed})", fontsize=10)
    fig.tight_layout()
    try:
        with atomic_path(dest, "--plot") as tmp:
            fig.savefig(tmp, dpi=110, format=dest.suffix.lower().lstrip("."))
    finally:
        plt.close(fig)
