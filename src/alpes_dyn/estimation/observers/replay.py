"""The observer on a recording: the joints estimated from a recorded encoder and motor torque.

What a user does with the real hand (``alpes-dyn estimate --data REC.csv --params FILE``,
:func:`estimate_recording`): the recording (the CSV format of :mod:`alpes_dyn.estimation.experiments.recording`,
written by the hand's logger or by ``alpes-dyn experiment``) is played back into an observer of the
model -- typically the one identified from another recording (``alpes-dyn identify -o FILE``).

* Measurement y_k: the encoder, q_m = (2 pi / counts_per_rev) counts (Section 3, eq. 3.13), of
  variance q_step^2 / 12 (the quantisation) plus ``encoder_noise_counts`` squared.
* Known input w_k: the recorded motor torque, held on [t_k, t_k+1), with white noise of standard
  deviation ``torque_noise`` (default: estimated from the recording, sqrt(mean(diff(tau, 2)^2) / 6),
  which a white noise on a smooth excitation gives, the dither's 20 Hz included).
* Optionally (``disturbance=True``) one slowly varying torque per motor, d_j, added to the recorded
  torque (tau = S^T (u + d)) as a random-walk state of the observer: what identification leaves --
  a friction the smooth law does not hold, a torque constant a few percent off, a gravity load of a
  palm not level -- is absorbed there instead of in the joint estimates. Its random walk
  (``disturbance_walk``, N m per sqrt(s)) sets how fast it may move.
* Initial state: the static equilibrium under the first recorded torque (the hand at rest when the
  recording starts), joints without spring mid-range; covariance 0.5 rad, 1 rad/s (as the scenario).
* A recording with ``gravity_*`` columns sets the model's gravity when they are constant (a fixed
  orientation); a recording turned between a few orientations (``alpes-dyn experiment --rig both``: constant
  over each segment, :func:`~alpes_dyn.estimation.experiments.recording.segment_starts`) is run one orientation
  after the other, the filter carrying its estimate and covariance over each turn; gravity varying at every
  sample is refused (the observer has no gravity input).
* Where the recording has ``true_q_*`` columns (a simulated experiment, or a jig), the RMSE of each
  joint after ``transient`` seconds (default min(1 s, duration / 5)), as ``alpes-dyn estimate`` prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ...checks import as_float_array
from ...errors import InputError, RecordingError
from ...fileio import atomic_path
from ...limits import check_bytes, check_physical
from ...model.stops import JointStops
from ...model.trust import check_trusted
from ...model.robot import Model
from ...simulation.integrate import stable_substeps
from ...simulation.stick import check_friction_law, observer_friction_law
from ...simulation.lugre import lugre_substeps
from ...model.friction import LuGre, lugre_of
from ...symbolic.parametric import tilted_gravity
from ...symbolic.statespace import StateSpace
from ...simulation.loop import Function, run_loop
from .blocks import Observer, RecordingPlayback
from .observers import OBSERVERS, Estimate, make_observer
from ..experiments.recording import MAX_SEGMENTS, Recording, read_recording, segment_starts
from .scenario import held_mid_range, rest_with_held_joints
from .torque_reading import MAX_DELAY, STICK_TORQUE_WINDOW, advanced, averaged, default_torque_window

__all__ = ["RecordingEstimate", "estimate_recording", "recording_filter", "DISTURBANCE_WALK", "file_encoder_offsets"]

DISTURBANCE_WALK = 2e-4
"""Default random walk of the disturbance torque states, N m per sqrt(s): over a second a disturbance may move by
0.2 mN m, a tenth of the torque that holds a finger half-flexed, and follow stick-slip friction's breakaway
within tens of milliseconds."""


@dataclass
class RecordingEstimate:
    """An observer run on a recording.

    Attributes
    ----------
    t: (N,) s. estimate: the observer's :class:`Estimate` (z = [q; qd; d]).
    joint_names (n,), motor_names (m,). rmse: (n,) rad after the transient, or None (no ``true_q_*``).
    final_error: (n,) rad at the last sample, or None. disturbance: (N, m) N m, or None.
    settings: the noise levels and options used.
    filter: the observer run (its ``model.step`` the prediction,
        :mod:`~alpes_dyn.estimation.identification.observer_check`).
    measurement: (N, m) rad, the encoder as the observer read it (the zero and the tendons' stretch taken off).
    inputs: (N-1, m) N m, the torque the observer read, row k held from sample k to k+1 (``torque_delay`` applied).
    segments: the orientations run in turn (each its own filter; ``filter`` is the first's).
    """

    t: np.ndarray
    estimate: Estimate
    joint_names: tuple[str, ...]
    motor_names: tuple[str, ...]
    rmse: np.ndarray | None
    final_error: np.ndarray | None
    disturbance: np.ndarray | None
    settings: dict[str, Any]
    filter: Any = None
    measurement: np.ndarray | None = None
    inputs: np.ndarray | None = None
    segments: int = 1

    @property
    def q_hat(self) -> np.ndarray:
        """(N, n) estimated joint angles, rad."""
        return self.estimate.z[:, : len(self.joint_names)]

    def to_dict(self) -> dict[str, Any]:
        """The JSON summary of ``alpes-dyn estimate --data --json`` (rmse in rad per joint, as ``estimate``)."""
        n = len(self.joint_names)
        out: dict[str, Any] = {
            "joints": list(self.joint_names), "motors": list(self.motor_names), "samples": int(self.t.shape[0]),
            "duration_s": float(self.t[-1] - self.t[0]),
            "rmse": None if self.rmse is None else self.rmse.tolist(),
            "rmse_deg": None if self.rmse is None else np.degrees(self.rmse).tolist(),
            "final_error": None if self.final_error is None else self.final_error.tolist(),
            "final_q": self.q_hat[-1].tolist(), "final_q_std": self.estimate.std[-1, :n].tolist(),
        }
        if self.disturbance is not None:
            out["final_disturbance_Nm"] = self.disturbance[-1].tolist()
        out.update(self.settings)
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write t, q_hat_*, qd_hat_*, q_std_* (and d_hat_*) as CSV, atomically.

        Parameters
        ----------
        path : str or pathlib.Path
            The CSV file written: t in s, q_hat_* and q_std_* in rad, qd_hat_* in rad/s, d_hat_* in N m.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        n = len(self.joint_names)
        cols = {"t": self.t}
        cols.update({f"q_hat_{j}": self.estimate.z[:, i] for i, j in enumerate(self.joint_names)})
        cols.update({f"qd_hat_{j}": self.estimate.z[:, n + i] for i, j in enumerate(self.joint_names)})
        cols.update({f"q_std_{j}": self.estimate.std[:, i] for i, j in enumerate(self.joint_names)})
        if self.disturbance is not None:
            cols.update({f"d_hat_{mn}": self.disturbance[:, k] for k, mn in enumerate(self.motor_names)})
        data = np.column_stack(list(cols.values()))
        with atomic_path(path) as tmp:
            np.savetxt(tmp, data, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
        return Path(path)


def _nonnegative(x: Any, name: str, unit: str) -> float:
    """``x`` as a finite float >= 0 within its unit's accepted range (:func:`~alpes_dyn.limits.check_physical`)."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a non-negative number of {unit}, got {x!r}")
    try:
        v = float(x)
    except OverflowError:
        v = math.inf
    if not math.isfinite(v) or v < 0:
        raise InputError(f"{name}: expected a non-negative number of {unit}, got {x!r:.40}")
    return float(check_physical(v, name, unit, "nonneg"))


def _finite_vector(x: Any, n: int, name: str, unit: str) -> np.ndarray:
    """``x`` as (n,) finite floats (:func:`~alpes_dyn.checks.as_float_array`: no string, bool or complex)."""
    expected = f"{n} finite numbers ({unit})"
    a = as_float_array(x, name, expected).reshape(-1)
    if a.shape != (n,) or not np.isfinite(a).all():
        raise InputError(f"{name}: expected {expected}, got {np.asarray(x).tolist()!r}")
    return check_physical(a.copy(), name, unit, "any")


def _model_for(model: Model, rec: Recording) -> Model:
    """The model in the recording's orientation (constant ``gravity_*`` columns), else the model itself."""
    if rec.gravity is None:
        return model
    g = rec.gravity
    if np.max(np.abs(g - g[0])) > 1e-9 * max(1.0, float(np.abs(g).max())):
        raise RecordingError("recording: gravity_x,_y,_z vary over the recording; the observer takes one orientation "
                             f"at a time, held over at most {MAX_SEGMENTS} segments (split the recording where the "
                             "hand turns)")
    return model.copy(gravity=g[0])


def _piece(rec: Recording, a: int, b: int) -> Recording:
    """Samples a..b (both in) of ``rec``: one orientation of a turned recording, its last sample the next one's
    first (reached under this orientation's gravity: its gravity row is this one's)."""
    if a == 0 and b == rec.n_samples - 1:
        return rec
    piece = rec.take(slice(a, b + 1))
    if piece.gravity is not None:
        piece.gravity = np.repeat(piece.gravity[:1], b + 1 - a, axis=0)
    return piece


def _initial_state(model: Model, u0: np.ndarray) -> np.ndarray:
    """[q; 0]: the static equilibrium under the first torque, joints without spring mid-range (fixed there)."""
    try:
        q0 = rest_with_held_joints(model, u0)
    except InputError:  # no rest under this torque (a fold, a springless chain): start stretched, as the scenario
        q0 = held_mid_range(model)
    return np.concatenate([q0, np.zeros(model.n)])


def _replay_filter(m_obs: Model, observer: str, dt: float, substeps: int, torque_noise: float,
                   encoder_noise_counts: float, disturbance_walk: float, gains: tuple[str, ...], pars: tuple[str, ...],
                   u0: np.ndarray, compiled: bool, friction_law: str = "smooth",
                   stops: bool = False) -> tuple[Any, np.ndarray, np.ndarray]:
    """The observer of :func:`estimate_recording` and its prior: (filter, z0 (nz,), P0 (nz,) variances); ``u0`` (m,)
    the first recorded torque, N m (the rest state under it); ``compiled``: the filter in compiled C;
    ``friction_law``: the discrete model's (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`); ``stops``: the
    model's joint stops in it (:meth:`~alpes_dyn.model.stops.JointStops.of`)."""
    n, m = m_obs.n, m_obs.transmission.n_motors
    tr = m_obs.transmission
    step = 2 * np.pi / tr.counts_per_rev
    # the measurement's noise: the encoder's, and the torque noise through the tendon's stretch
    meas_var = step**2 / 12 + (encoder_noise_counts * step) ** 2 + (tr.tendon_compliance * torque_noise) ** 2
    lugre = friction_law == "lugre" and bool(np.any(m_obs.extras.coulomb))
    span = m_obs.extras.coulomb / (lugre_of(m_obs) or LuGre()).sigma0 if lugre else np.zeros(0)  # F_s / sigma0, rad
    ss = StateSpace(m_obs, input="motor", output="encoder")
    # the friction's terms (the smooth law's model error, the bristles' walk) added by make_observer
    Q = np.diag([1e-9**2] * n + [2e-4**2] * n + [2e-5**2] * len(gains) + [disturbance_walk**2 * dt] * len(pars))
    filt = make_observer(observer, ss, dt, compiled=compiled, parameters=gains + pars, substeps=substeps,
                         friction_law=friction_law, stops=JointStops.of(m_obs) if stops else None, process_noise=Q,
                         measurement_noise=list(meas_var * np.ones(m)),
                         input_noise=[torque_noise**2] * m)
    x0 = _initial_state(m_obs, u0)
    z0 = np.concatenate([x0, np.ones(len(gains)), np.zeros(len(pars) + span.size)])
    sd_q = (_rest_spread(m_obs, x0[:n], ss.B, torque_noise) if filt.model.friction_law in ("stick", "lugre")
            else np.full(n, 0.5))
    P0 = np.concatenate([sd_q**2, [1.0**2] * n, [0.2**2] * len(gains), [(10 * torque_noise + 1e-4) ** 2] * len(pars),
                         span**2])
    return filt, z0, P0


def _rest_spread(model: Model, q0: np.ndarray, B: np.ndarray, torque_noise: float) -> np.ndarray:
    """(n,) rad: the prior standard deviation of the joints at rest for the stick law, at most 0.5 rad (the smooth
    law's). Dry friction holds a finger anywhere the net torque is below F_s: |J dq| <= F_s about the frictionless
    rest q0 (J = dG/dq, springs and gravity), a box in dq whose extent on joint i is sum_j |J^-1_ij| F_s,j; the rest
    itself is found under a torque of noise ``torque_noise`` (N m, per motor through ``B`` (n, m)), J^-1 B sigma
    more. A prior as wide as the smooth law's would let the first breakaway throw the split (which a joint held by
    friction does not observe) by tens of degrees. Joints without spring keep 0.5 rad."""
    J = model.gravity_jacobian(q0)
    try:
        Ji = np.linalg.inv(J)
    except np.linalg.LinAlgError:
        return np.full(q0.size, 0.5)
    band = np.abs(Ji) @ model.extras.coulomb
    noise = np.abs(Ji @ B).sum(axis=1) * torque_noise
    sd = np.minimum(np.hypot(band, noise), 0.5)
    sd[~(model.extras.stiffness > 0)] = 0.5
    return np.where(np.isfinite(sd), sd, 0.5)


def _substeps(model: Model, dt: float, substeps: int | None, tension: Any = None, friction_law: str = "smooth"
              ) -> int:
    """The observer's steps per sample: ``substeps``, or by default as many as the friction's stiffness asks
    (:func:`~alpes_dyn.simulation.integrate.stable_substeps`: 4 for the smooth law at 1 kHz; with the tendons' sheath
    friction at ``tension``, the recording's largest torques, where given), 1 without friction; 1 with the ``stick``
    law, whose step resolves the dry friction implicitly (on finger3 at 1 kHz, 2 or 4 steps gave the same errors)."""
    if substeps is not None:
        return substeps
    if friction_law == "stick" and np.any(model.extras.coulomb):
        return 1
    if friction_law == "lugre" and np.any(model.extras.coulomb):
        return lugre_substeps(model, lugre_of(model) or LuGre(), dt, minimum=4)
    has_friction = bool(np.any(model.extras.coulomb) or np.any(model.extras.viscous))
    return stable_substeps(model, dt, tension=tension) if has_friction else 1


def recording_filter(model: Model, observer: str = "ekf", dt: float = 1e-3, *, torque_noise: float = 5e-4,
                     encoder_noise_counts: float = 0.0, substeps: int | None = None,
                     u0: Any = None) -> tuple[Any, np.ndarray, np.ndarray]:
    """The observer :func:`estimate_recording` runs on a recording of ``model``, without disturbance states. The C
    export of a URDF robot's observer (``alpes-dyn codegen``) is this filter.

    Parameters
    ----------
    model : Model
        The model, with motors (a URDF and its spec's ``[[motor]]`` tables).
    observer : str, optional
        One of :data:`~alpes_dyn.estimation.observers.observers.OBSERVERS` (default ``"ekf"``; ``*-params`` add
        the gains ``input_gain`` and ``spring_gain`` to the state).
    dt : float, optional
        The sample period, s (> 0; default 1e-3).
    torque_noise : float, optional
        The motor torques' noise, N m (default 5e-4).
    encoder_noise_counts : float, optional
        The encoders' noise, counts beyond the quantisation (default 0).
    substeps : int or None, optional
        As :func:`estimate_recording`'s (default None: as many as the model's friction asks, else 1).
    u0 : array_like, shape (m,), optional
        The motor torques, N m, whose rest is z0 (default None: zeros).

    Returns
    -------
    tuple
        (filter, z0 (nz,), P0 (nz,) variances).

    Raises
    ------
    InputError
        Naming the argument: a model without motors, an unknown observer, a non-positive ``dt``, a negative
        noise, ``u0`` of another size.
    """
    if not isinstance(model, Model) or model.transmission is None:
        raise InputError("model: expected an alpes_dyn Model with motors (a URDF and its spec's [[motor]] tables)")
    if observer not in OBSERVERS:
        raise InputError(f"observer: unknown observer {observer!r} (expected one of {', '.join(OBSERVERS)})")
    dt = _nonnegative(dt, "dt", "s")
    if not dt > 0:
        raise InputError(f"dt: expected a positive number of seconds, got {dt!r}")
    torque_noise = _nonnegative(torque_noise, "torque_noise", "N m")
    encoder_noise_counts = _nonnegative(encoder_noise_counts, "encoder_noise_counts", "counts")
    substeps = _substeps(model, dt, substeps)
    m = model.transmission.n_motors
    u0 = np.zeros(m) if u0 is None else _finite_vector(u0, m, "u0", "N m")
    gains = ("input_gain", "spring_gain") if observer.endswith("-params") else ()
    return _replay_filter(model, observer, dt, substeps, torque_noise, encoder_noise_counts, DISTURBANCE_WALK, gains,
                          (), u0, False)


def estimate_recording(recording: Recording | str | Path, model: Model, observer: str = "ekf", *,
                       torque_noise: float | None = None, encoder_noise_counts: float = 0.0,
                       disturbance: bool = False, disturbance_walk: float = DISTURBANCE_WALK,
                       transient: float | None = None, substeps: int | None = None,
                       compiled: bool = False, encoder_offset: Any = None,
                       tilt: Any = None, torque_delay: int | None = None, friction_law: str | None = None,
                       torque_window: int | None = None, force: bool = False, stops: bool = False) -> RecordingEstimate:
    """Run an observer on a recording (see the module docstring).

    Parameters
    ----------
    recording : Recording or str or Path
        The recording, or the path of its CSV (read for ``model``).
    model : Model
        The observer's model, e.g. ``Model.alpes("finger3", friction=True, params="ident.toml")``.
    observer : {"ekf", "ukf", "ekf-params", "ukf-params"}, optional
        The filter (the ``-params`` variants estimate two gains as well).
    torque_noise : float or None, optional
        The recorded torque's white noise, N m (default: estimated from the recording).
    encoder_noise_counts : float, optional
        The encoder's noise beyond the quantisation, counts.
    disturbance : bool, optional
        Estimate one additive torque per motor (N m) as a random walk of ``disturbance_walk``.
    disturbance_walk : float, optional
        That walk's intensity, N m per sqrt(s).
    transient : float or None, optional
        The start of the error metrics, s (default min(1 s, duration / 5)).
    substeps : int or None, optional
        Steps per sample (default with friction :func:`~alpes_dyn.simulation.integrate.stable_substeps`, 4 for the
        smooth sign at 1 kHz, 15 for the stick-slip law on finger3; 1 with ``friction_law="stick"`` or without
        friction).
    compiled : bool, optional
        The filter in compiled C (the same numbers).
    encoder_offset : array_like or None, optional
        (m,) rad, the encoders' zero as identified on this rig (``encoder_offset_<motor>`` of
        :func:`~alpes_dyn.estimation.identification.identification.identify`): taken off the reading. Default: the
        model's parameter file's (``encoder_offset`` of the chain's section, written by ``identify``), else 0.
    tilt : array_like or None, optional
        (tilt_x, tilt_y) rad, the palm's orientation as identified: the observer's gravity turned by it
        (:func:`~alpes_dyn.symbolic.parametric.tilted_gravity`). Default level. The palm's tilt identified is in
        the file's gravity (``environment.gravity``), which the model holds; ``tilt`` turns it further. The tendons'
        stretch C tau_m,k-1 (the model's ``tendon_compliance``, under the torque held before the reading) is always
        taken off the reading.
    torque_delay : int or None, optional
        Whole samples by which the recorded torque lags the motor's (as identified,
        :func:`~alpes_dyn.estimation.identification.effects.fit_effects` with ``delay``): the observer reads the
        torque of :func:`~.torque_reading.advanced` (a replay: the later samples are recorded). Default: the
        model's parameter file's ``transmission.torque_delay`` (written by ``identify``), else 0.
    friction_law : {"smooth", "stick", "lugre"} or None, optional
        The observer's dry friction (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`): ``"smooth"``
        F_s tanh(v / v_s), ``"stick"``, the time-stepping Coulomb law that holds a joint at rest
        (:mod:`alpes_dyn.simulation.stick`), or ``"lugre"``, a bristle state per joint
        (:mod:`alpes_dyn.model.friction`). Default: the parameter file's,
        :func:`~alpes_dyn.simulation.stick.observer_friction_law` (its ``friction.observer_law`` where it holds
        one, else ``"lugre"`` where it says ``friction.law = "lugre"``, else ``"smooth"``).
    torque_window : int or None, optional
        Samples of the causal moving average of the torque the observer reads (:func:`~.torque_reading.averaged`;
        its noise, given or estimated, divided by sqrt(``torque_window``)). Default
        :func:`~.torque_reading.default_torque_window`: 1 (the torque as recorded) where the file holds
        ``friction.observer_law`` (chosen by ``identify``'s check on the torque as recorded), else
        :data:`~.torque_reading.STICK_TORQUE_WINDOW` with the stick and LuGre laws, 1 with the smooth law.
    force : bool, optional
        Run on a model whose parameter file is marked not trustworthy (refused otherwise:
        :class:`~alpes_dyn.ModelError` with the reason the file records, :func:`~alpes_dyn.model.trust.check_trusted`).
    stops : bool, optional
        The joints' end stops in the observer's model (:meth:`~alpes_dyn.model.stops.JointStops.of`: a stiff
        spring-damper at each end of the URDF's range), for a hand whose joints reach their stops; default off.

    Returns
    -------
    RecordingEstimate
        The estimates; ``rmse`` (n,) rad where the recording has ``true_q_*``.
    """
    rec = _replay_recording(recording, model, observer)  # (the model checked first)
    if model.params is not None:
        check_trusted(model.params, force)
    if torque_delay is None:
        torque_delay = int(getattr(model.params, "torque_delay", 0))
    rec = advanced(rec, torque_delay)
    if friction_law is None:  # the parameter file's law
        friction_law = observer_friction_law(model)
    friction_law = check_friction_law(friction_law)
    window = default_torque_window(model, friction_law) if torque_window is None else torque_window
    raw_noise = _torque_noise(rec) if torque_noise is None else torque_noise
    rec = averaged(rec, window)
    encoder_noise_counts = _nonnegative(encoder_noise_counts, "encoder_noise_counts", "counts")
    disturbance_walk = _nonnegative(disturbance_walk, "disturbance_walk", "N m per sqrt(s)")
    for flag, name in ((disturbance, "disturbance"), (compiled, "compiled"), (stops, "stops")):
        if not isinstance(flag, (bool, np.bool_)):
            raise InputError(f"{name}: expected True or False, got {flag!r:.40}")
    N, dt = rec.n_samples, rec.dt
    duration = rec.duration
    t_start = min(1.0, 0.2 * duration) if transient is None else _nonnegative(transient, "transient", "s")
    if not t_start < duration:
        raise InputError(f"transient: {t_start:g} s must be shorter than the recording's {duration:g} s")
    torque_noise = _nonnegative(raw_noise, "torque_noise", "N m") / math.sqrt(window)
    edges = np.append(segment_starts(rec.gravity), N - 1)  # a recording turned between orientations: in turn
    m_obs, angles, offsets = _observer_model(model, _piece(rec, edges[0], edges[1]), tilt, encoder_offset)
    substeps = _substeps(m_obs, dt, substeps, np.abs(rec.torque).max(axis=0), friction_law)
    n, m = m_obs.n, m_obs.transmission.n_motors
    pars = tuple(f"disturbance_{mn}" for mn in m_obs.transmission.motor_names) if disturbance else ()
    gains = ("input_gain", "spring_gain") if observer.endswith("-params") else ()
    nz = 2 * n + len(pars) + len(gains) + (n if friction_law == "lugre" else 0)
    check_bytes(48.0 * N * (2 * (nz + nz * nz) + 2 * m + n), "recording", f"{N} samples for the observer")
    tr = m_obs.transmission
    parts: list[Estimate] = []
    for a, b in zip(edges[:-1], edges[1:]):  # a loop over the orientations (one, or the few a rig was turned to)
        piece = _piece(rec, a, b)
        m_i = m_obs if a == 0 else _observer_model(model, piece, tilt, encoder_offset)[0]
        f, z0, P0 = _replay_filter(m_i, observer, dt, substeps, torque_noise, encoder_noise_counts, disturbance_walk,
                                   gains, pars, piece.torque[0], compiled, friction_law, bool(stops))
        if parts:  # the hand turned: the filter carries on from its last estimate
            z0, P0 = parts[-1].z[-1], parts[-1].P[-1]
        else:
            filt = f
        parts.append(_played_back(piece, f, z0, P0, tr, offsets))
    est = parts[0] if len(parts) == 1 else Estimate(
        t=rec.t.copy(), z=np.concatenate([p.z[:-1] for p in parts[:-1]] + [parts[-1].z]),
        P=np.concatenate([p.P[:-1] for p in parts[:-1]] + [parts[-1].P]), names=filt.names)
    rmse, final = _errors(est, rec, t_start, n)
    dist = est.z[:, 2 * n + len(gains): 2 * n + len(gains) + len(pars)] if pars else None
    settings = {"observer": observer, "torque_noise_Nm": torque_noise, "encoder_noise_counts": encoder_noise_counts,
                "disturbance": bool(disturbance), "disturbance_walk": disturbance_walk if disturbance else None,
                "transient_s": t_start, "substeps": int(substeps), "dt_s": dt, "backend": filt.backend,
                "encoder_offset_rad": offsets.tolist(), "tilt_rad": angles,
                "tendon_compliance": tr.tendon_compliance.tolist(), "torque_delay_samples": int(torque_delay),
                "friction_law": filt.model.friction_law, "torque_window_samples": int(window)}
    return RecordingEstimate(t=rec.t.copy(), estimate=est, joint_names=m_obs.joint_names,
                             motor_names=m_obs.transmission.motor_names, rmse=rmse, final_error=final,
                             disturbance=dist, settings=settings, filter=filt,
                             measurement=_reading(rec, tr, offsets), inputs=rec.torque[:-1].copy(),
                             segments=len(parts))


def _replay_recording(recording: Recording | str | Path, model: Model, observer: str) -> Recording:
    """The recording (read for ``model`` from a path), checked to be of the model's motors and joints; the model
    (with a transmission) and the observer's name checked first."""
    if not isinstance(model, Model):
        raise InputError(f"model: expected an alpes_dyn.Model, got {type(model).__name__}")
    if model.transmission is None:
        raise InputError(f"model: {model.name!r} has no tendon transmission (no encoder to observe)")
    if observer not in OBSERVERS:
        raise InputError(f"observer: expected one of {', '.join(OBSERVERS)}, got {observer!r}")
    if not isinstance(recording, (Recording, str, Path)):
        raise InputError(f"recording: expected a Recording or a CSV path, got {type(recording).__name__}")
    rec = recording if isinstance(recording, Recording) else read_recording(recording, model)
    if tuple(rec.motor_names) != tuple(model.transmission.motor_names) or \
            tuple(rec.joint_names) != tuple(model.joint_names):
        raise RecordingError(f"recording: made for motors {list(rec.motor_names)} and joints {list(rec.joint_names)}, "
                             f"not the model's {list(model.transmission.motor_names)} and {list(model.joint_names)}")
    if rec.n_runs > 1:  # the states jump between runs: a filter would take the jump for a measurement
        raise RecordingError(f"recording: {rec.n_runs} runs (column 'run'); an observer runs on one: give one run's "
                             "rows")
    return rec


def _torque_noise(rec: Recording) -> float:
    """The recorded torque's white noise, N m, from its second difference."""
    # the second difference of a white noise has variance 6 sigma^2; the torque's own motion leaves (2 pi f dt)^2
    # of its amplitude there: 1.6 % at the dither's 20 Hz (the first difference left 13 %, 7 % too high a sigma)
    d2_tau = np.diff(rec.torque, n=2, axis=0)
    return float(np.sqrt(np.mean(d2_tau**2) / 6.0))


def file_encoder_offsets(model: Model) -> np.ndarray:
    """(m,) rad: the encoders' zeros the model's parameter file holds for its motors
    (:meth:`~alpes_dyn.model.params.HandParams.encoder_offset_of`: written by ``identify``), zeros without a file.

    Parameters
    ----------
    model : Model
        The model, with motors.

    Returns
    -------
    numpy.ndarray, shape (m,)
        The encoders' zeros, rad.
    """
    p = model.params
    return np.array([0.0 if p is None else p.encoder_offset_of(mn, model.chain)
                     for mn in model.transmission.motor_names])


def _observer_model(model: Model, rec: Recording, tilt: Any, encoder_offset: Any
                    ) -> tuple[Model, list[float] | None, np.ndarray]:
    """(the observer's model in the recording's orientation, turned by ``tilt``; the tilt angles as given, rad, or
    None; the encoders' zero (m,) rad)."""
    m_obs = _model_for(model, rec)
    angles = None
    if tilt is not None:
        angles = _finite_vector(tilt, 2, "tilt", "rad").tolist()
        m_obs = m_obs.copy(gravity=tilted_gravity(m_obs.gravity, angles[0], angles[1]))
    offsets = file_encoder_offsets(model) if encoder_offset is None else \
        _finite_vector(encoder_offset, model.transmission.n_motors, "encoder_offset", "rad")
    return m_obs, angles, offsets


def _reading(rec: Recording, tr: Any, offsets: np.ndarray) -> np.ndarray:
    """(N, m) rad: the recorded encoder as the observer reads it, the zero ``offsets`` and the tendons' stretch
    C tau_m,k-1 taken off (what :func:`_played_back`'s ``unstretched`` block gives it)."""
    from ...model.transmission import torque_before

    step = 2 * np.pi / tr.counts_per_rev
    return tr.unstretched(rec.encoder * step - offsets, torque_before(rec.torque))


def _played_back(rec: Recording, filt: Any, z0: np.ndarray, P0: np.ndarray, tr: Any, offsets: np.ndarray
                 ) -> Estimate:
    """The observer's estimate over the recording: the composition recording played back -> the encoder's zero
    and the tendons' stretch C tau_m,k-1 taken off -> observer, run by :func:`run_loop`."""
    step = 2 * np.pi / tr.counts_per_rev
    blocks = [RecordingPlayback(rec, encoder="counts", torque="tau", held="tau_held", before="tau_before"),
              Function(lambda counts, tau_before: tr.unstretched(counts * step - offsets, tau_before),
                       ("counts", "tau_before"), "y",
                       name="unstretched", vectorized=True),
              Observer(filt, z0, P0, known=("tau_held",), measurement="y")]
    log = run_loop(blocks, rec.n_samples - 1, rec.dt, final=True)
    return Estimate(t=rec.t.copy(), z=log["z"], P=log["P"], names=filt.names)


def _errors(est: Estimate, rec: Recording, t_start: float, n: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """(RMSE (n,) rad after ``t_start`` s, the last sample's error (n,) rad) against the recording's true joints;
    (None, None) without them."""
    if rec.true_q is None or not np.isfinite(rec.true_q).all():
        return None, None
    k0 = int(round(t_start / rec.dt))
    err = est.z[:, :n] - rec.true_q
    return np.sqrt(np.mean(err[k0:] ** 2, axis=0)), np.abs(err[-1])
