"""The identification experiment run on the hand itself, through the
:class:`~alpes_dyn.bench.interface.HardwareInterface`: designed on the nominal model, trimmed and guarded on the
finger, with no truth anywhere (:func:`run_experiment`); and the designed torque alone, for a user who plays it
with their own tools (:func:`designed_torque`, :func:`write_torque_profile`).

:func:`run_experiment`, in order (one orientation, one run; turn the hand and run again for another, the runs
joined: :func:`~alpes_dyn.estimation.experiments.turned.run_turned`):

1. the excitation designed on the nominal model as :mod:`alpes_dyn.estimation.experiments.experiment` designs it
   (:class:`~alpes_dyn.estimation.experiments.design.ExperimentDesign`: the multisine's bias and amplitude, the
   dither), and its target: the nominal finger's encoder reading at rest under the bias (mid-range);
2. the hand's :class:`~alpes_dyn.estimation.experiments.calibration.Calibration` (made here if not given): its rest
   and usable range; the guard band is the range less ``margin`` counts at each end (default the design's joint
   ``margin`` through the pulley ratios: 196 counts on finger3), narrowed (a finger of one motor) to the counts
   between which the joints themselves, which no sensor reads, keep the design's ``margin`` from their own stops
   on every finger of the tolerance family (:func:`~alpes_dyn.estimation.experiments.joint_stops.joint_band`: a
   joint can reach its stop while the encoder is still inside the calibrated range);
3. the bias trimmed on the hand by iterated holds (:func:`_trim`): the bias and the dither held for ``hold`` s, the
   encoder's mean over the hold's second half read, the bias corrected by the calibrated curve's torque difference
   between the target and that mean, until the mean is within ``tolerance`` counts of the target. Why holds and not
   a continuous integral on the encoder error: the target is a static rest (what the design and the fits were made
   with), which a hold measures once the finger has settled (the dither keeps its joints sliding through their dry
   friction); the multisine's lowest line (0.3 Hz) would pass through any integral fast enough to settle in
   seconds, and palm up the finger sits close to its fold, where its compliance is 6 times the unloaded one and its
   slowest mode a few tenths of a second: an integral acting on it can ring with that mode, a hold only reads after
   it. The calibrated curve, not a constant slope, gives the correction: the compliance changes by a factor of 10
   over the range. The bias is kept below a fold the calibration found by 1.25 times the excitation's peak (the rule
   of :func:`~alpes_dyn.estimation.experiments.trim._trimmed_bias`); with ``design.trim_bias`` off (or a given
   ``torque_bias``) the nominal bias is used as it is;
4. the multisine's amplitude brought up in ``stages`` (fractions of the design's), each ``stage_seconds`` long
   (the record's first seconds replayed): after each, the encoder's swing per N m of the multisine measured there
   predicts the full swing, and the amplitude stops where 1.25 times it would leave the guard band (the result's
   ``amplitude_scale``); and the bias is corrected again, by the calibrated curve, for the difference between the
   hand's mean reading over the stage's second half and the nominal finger's under the same excitation about the
   nominal bias (simulated through every stage so far): the trim's target under the multisine is the designed
   trajectory's mean, which for a finger near its fold is not its static rest;
5. the record: the design's ``duration`` at that amplitude, the bias frozen (no feedback in the recorded torque:
   it stays on the multisine's lines, which the fit's errors in variables take), the guard on; then the finger
   relaxed (the command ramped to 0 N m).

Guarded throughout (:class:`~alpes_dyn.estimation.experiments.hand_session.HandSession`): an encoder leaving the
guard band or a missed period stops the excitation, relaxes the finger and raises
:class:`~alpes_dyn.estimation.experiments.hand_session.GuardTripped`.

A motor whose joints have no spring (the thumb's ab/adduction, ``Model.alpes("thumb")``'s second motor) is held
relaxed, at 0 N m, through the whole run: no bias, no multisine, no dither, and the calibration does not ramp it
(:func:`~alpes_dyn.estimation.experiments.calibration.calibrate`). With no spring there is no static rest to trim
the bias about nor a torque-to-counts curve to trim it with: any steady torque above its joint's friction runs the
joint to a stop (the simulated experiment holds it mid-range by a bias on the nominal model alone:
:mod:`alpes_dyn.estimation.experiments.experiment`); relaxed, it rests where its friction or its stop holds it (the
MuJoCo stand-in's on its 0 degree stop, beside the palm). Its guard band is its rest plus and minus the margin: the
thumb's flexion dragging the ab/adduction off its rest trips the guard. The thumb's flexion is then recorded as a
finger's is, the ab/adduction's encoder beside it (its mass and friction are not among the thumb's default fitted
parameters, :data:`~alpes_dyn.estimation.identification.identification.THUMB_PARAMETERS`: the encoders barely see
them).

The recording (:class:`~alpes_dyn.estimation.experiments.recording.Recording`, the CSV that ``alpes-dyn identify``
reads): ``t`` the ticks from the record's first (k times the period; the readings' own time stamps are what the guard
checks), ``encoder_<motor>`` the counts read at each tick, ``torque_<motor>`` the torque measured over the period
that follows it (read at the next tick), N m.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ...bench.interface import HardwareInterface
from ...errors import InputError
from ...fileio import atomic_path, check_outputs
from ...model.robot import Model
from .calibration import Calibration, calibrate
from .design import ExperimentDesign, _checked_design
from .experiment import _excitation, _simulate
from .hand_session import GuardTripped, HandSession, SessionLog
from .joint_stops import joint_band
from .multisine import _motor_groups, _profiles, dither_amplitude
from .recording import Recording, write_recording
from .trim import _mean_equilibrium, _reading

__all__ = ["OnHandResult", "run_experiment", "designed_torque", "write_torque_profile", "roomier", "STAGES",
           "ROOM_SHARE"]

STAGES: tuple[float, ...] = (0.25, 0.5, 1.0, 1.0)
"""The multisine's amplitude steps before the record, fractions of the design's amplitude (the last repeated: a
second correction of the bias at the full amplitude)."""

START_SHARE = 0.5
"""The trim's first hold: the calibrated torque of this share of the way from the guard band's lower end to the target. The ramp that
made the curve had no dither, whose sliding carries the finger further (on the MuJoCo stand-in's finger3 the torque
of the target reads past the guard band), so the trim comes from below."""

STEP_GAIN = 0.7
"""The share of the curve's correction each hold applies (the finger's compliance grows towards its fold: a whole
step from below overshoots)."""

ROOM_SHARE = 0.5
"""A run whose ``amplitude_scale`` is below this share of the designed amplitude is too small a record to trust the
masses of (their standard errors grow as the amplitude falls; on the MuJoCo stand-in's finger3 palm up, a run
with little room gave a fit that called itself adequate with its masses and springs well off): turn the hand (hung
fingers down, where the springs are not held near a fold by gravity), run again, and keep the run with more room
(:func:`roomier`)."""

FOLD_PEAKS = 1.25
"""The bias is held this many excitation peaks below a fold, and the predicted swing times this inside the band."""


@dataclass
class OnHandResult:
    """What :func:`run_experiment` did.

    Attributes
    ----------
    recording : Recording
        The record (encoder counts, measured torque; no true angles: the hand's are unknown).
    bias : numpy.ndarray
        (m,) the bias the record ran at, N m (trimmed on the hand).
    nominal_bias : numpy.ndarray
        (m,) the bias designed on the nominal model, N m.
    target : numpy.ndarray
        (m,) the encoder's target at rest, counts (the nominal finger's reading under the nominal bias, moved
        inside the guard band if it was not).
    rest_counts : numpy.ndarray
        (m,) the encoder's mean over the last hold before the multisine, counts.
    amplitude_scale : float
        The fraction of the design's multisine amplitude recorded (1: all of it).
    holds : list of tuple
        (bias (m,), mean counts (m,)) of each trim hold.
    held_below_fold : bool
        Whether the bias was capped below a fold the calibration found.
    calibration : Calibration
        The calibration used.
    log : SessionLog
        Everything read and written during the run.
    record_rows : slice
        The log's rows of the record.
    stages : list of tuple
        (bias (m,), scale, the hand's mean counts (m,), the nominal's mean counts (m,)) of each amplitude stage.
    """

    recording: Recording
    bias: np.ndarray
    nominal_bias: np.ndarray
    target: np.ndarray
    rest_counts: np.ndarray
    amplitude_scale: float
    holds: list
    held_below_fold: bool
    calibration: Calibration
    log: SessionLog
    record_rows: slice
    stages: list

    def to_dict(self) -> dict:
        """The run's figures as plain JSON types (N m, counts)."""
        return {"bias_nm": self.bias.tolist(), "nominal_bias_nm": self.nominal_bias.tolist(),
                "target_counts": self.target.tolist(), "rest_counts": self.rest_counts.tolist(),
                "amplitude_scale": self.amplitude_scale, "trim_holds": len(self.holds),
                "held_below_fold": self.held_below_fold, "samples": self.recording.n_samples}


def roomier(a: OnHandResult, b: OnHandResult) -> OnHandResult:
    """Of two runs of the experiment (e.g. palm up and hung), the one that recorded the larger share of the designed
    amplitude (``a`` where they are equal): the rule :data:`ROOM_SHARE` asks for.

    Parameters
    ----------
    a, b : OnHandResult
        Two runs on the same hand.

    Returns
    -------
    OnHandResult
        ``a`` or ``b``.

    Raises
    ------
    InputError
        Where either is not an :class:`OnHandResult`.
    """
    for name, r in (("a", a), ("b", b)):
        if not isinstance(r, OnHandResult):
            raise InputError(f"{name}: expected an OnHandResult, got {type(r).__name__}")
    return b if b.amplitude_scale > a.amplitude_scale else a


def _one_orientation(design: ExperimentDesign) -> np.ndarray:
    if len(design.orientations) != 1:
        raise InputError("orientations: the experiment on the hand runs in one orientation; turn the hand and run "
                         "again for another (join the recordings with join_runs)")
    return np.asarray(design.orientations[0], dtype=float)


def designed_torque(nominal: Model, design: ExperimentDesign | None = None
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The experiment's torque as designed on ``nominal`` alone (no trim: no finger to trim it on).

    Parameters
    ----------
    nominal : Model
        The finger (with motors) the excitation is designed on.
    design : ExperimentDesign or None, optional
        The design, one orientation (default: the documented one).

    Returns
    -------
    t : numpy.ndarray
        (N,) s, from 0 at the design's ``dt``.
    u : numpy.ndarray
        (N, m) motor torque, N m, u[k] held over [t_k, t_k+1): the nominal bias, the multisine and the dither.
    target : numpy.ndarray
        (m,) the nominal finger's encoder reading at rest under the bias, counts (what a trim on the hand aims at).

    Examples
    --------
    >>> from alpes_dyn import Model
    >>> t, u, target = designed_torque(Model.alpes("finger3", friction=True))
    >>> u.shape, float(t[1]), round(float(target[0]))
    ((4001, 1), 0.001, 3072)
    """
    design = _checked_design(design)
    g = _one_orientation(design)
    if not isinstance(nominal, Model) or nominal.transmission is None:
        raise InputError(f"nominal: expected an alpes_dyn Model with motors, got {type(nominal).__name__}")
    bias, amp, dither = _on_hand_excitation(nominal, design)
    t = design.dt * np.arange(design.n_samples)
    u = _profiles(design, t, bias, amp, dither)
    step = 2 * np.pi / nominal.transmission.counts_per_rev
    target = np.atleast_1d(_reading(nominal, _mean_equilibrium(nominal, bias, g))) / step
    return t, u, target


def write_torque_profile(path: str | Path, t: np.ndarray, u: np.ndarray, motor_names: Sequence[str]) -> Path:
    """Write the torque profile as CSV (atomically): a header ``t,torque_<motor>,...``, one row per sample; ``t``
    in s (uniform, the rate 1 / dt), ``torque_<motor>`` in N m, held from that row's time to the next. The
    recording's ``torque_<motor>`` columns are the same quantity.

    Parameters
    ----------
    path : str or pathlib.Path
        The CSV file written.
    t : numpy.ndarray, shape (N,)
        The sample times, s.
    u : numpy.ndarray, shape (N, m)
        The motor torques, N m.
    motor_names : sequence of str
        The motors' names, one per column of ``u``.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    cols = ["t"] + [f"torque_{n}" for n in motor_names]
    data = np.column_stack([np.asarray(t, dtype=float), np.asarray(u, dtype=float)])
    with atomic_path(path, "torque profile") as tmp, open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(",".join(cols) + "\n")
        f.write("\n".join(",".join(map(repr, row)) for row in data.tolist()) + "\n")
    return Path(path)


def _check_sprung(model: Model) -> None:
    if not isinstance(model, Model) or model.transmission is None:
        raise InputError(f"nominal: expected an alpes_dyn Model with motors, got {type(model).__name__}")
    _, sprung, free = _motor_groups(model)
    if not sprung:
        names = ", ".join(model.transmission.motor_names[k] for k in free)
        raise InputError(f"nominal: motor {names} drives joints without springs (no rest to trim about); the "
                         "experiment on the hand trims motors against return springs (a finger, the thumb's flexion)")


def _held(model: Model) -> np.ndarray:
    """(m,) bool: the motors held relaxed through the experiment, those whose joints have no spring (the module
    docstring)."""
    held = np.zeros(model.transmission.n_motors, dtype=bool)
    held[_motor_groups(model)[2]] = True
    return held


def _on_hand_excitation(nominal: Model, design: ExperimentDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(bias, multisine amplitude, dither amplitude) (m,), N m, as designed on ``nominal``
    (:func:`~alpes_dyn.estimation.experiments.experiment._excitation`), each 0 on a held motor (:func:`_held`)."""
    bias, amp = _excitation(nominal, design)
    keep = ~_held(nominal)
    return bias * keep, amp * keep, dither_amplitude(nominal, design) * keep


def _checked_run(hw: HardwareInterface, nominal: Model, design: ExperimentDesign | None,
                 calibration: Calibration | None, path: str | Path | None) -> ExperimentDesign:
    design = _checked_design(design)
    _one_orientation(design)
    _check_sprung(nominal)
    if not isinstance(hw, HardwareInterface):
        raise InputError(f"hw: expected a HardwareInterface, got {type(hw).__name__}")
    if tuple(hw.motor_names) != tuple(nominal.transmission.motor_names):
        raise InputError(f"hw: its motors {', '.join(hw.motor_names)} are not the model's "
                         f"{', '.join(nominal.transmission.motor_names)}")
    if not math.isclose(float(hw.period), design.dt, rel_tol=1e-9):
        raise InputError(f"design: dt {design.dt:g} s is not the hand's period {hw.period:g} s")
    if calibration is not None and (not isinstance(calibration, Calibration)
                                    or calibration.motor_names != tuple(hw.motor_names)):
        raise InputError("calibration: expected a Calibration of the hand's motors "
                         f"({', '.join(hw.motor_names)})")
    if path is not None:
        check_outputs([("path", path)], extensions={"path": ("csv",)})
    return design


def run_experiment(hw: HardwareInterface, nominal: Model, design: ExperimentDesign | None = None,
                   calibration: Calibration | None = None, *, path: str | Path | None = None,
                   margin: float | None = None, stages: Sequence[float] = STAGES, stage_seconds: float = 2.0,
                   hold: float = 1.0, max_holds: int = 6, tolerance: float = 50.0) -> OnHandResult:
    """Run the identification experiment on the hand ``hw`` (the module docstring), write its recording.

    Parameters
    ----------
    hw : HardwareInterface
        The hand: its motors those of ``nominal``, its period the design's ``dt``.
    nominal : Model
        The model the experiment is designed on (e.g. ``Model.alpes("finger3", friction=True)``).
    design : ~alpes_dyn.estimation.experiments.design.ExperimentDesign, optional
        The design (default the documented one); one orientation (the gravity the hand is in).
    calibration : Calibration, optional
        The hand's calibration (default: :func:`~alpes_dyn.estimation.experiments.calibration.calibrate` first).
    path : str or Path, optional
        Write the recording there (CSV).
    margin : float, optional
        The guard band's margin inside the calibrated range, counts (default the design's joint ``margin``, rad,
        through each motor's pulley ratios).
    stages, stage_seconds : sequence of float, float
        The amplitude steps (fractions in (0, 1], increasing) and each one's length, s.
    hold, max_holds, tolerance : float, int, float
        The trim: each hold's length (s), the most holds, and the encoder's tolerance about its target (counts).

    Returns
    -------
    OnHandResult
        Raises :class:`~alpes_dyn.estimation.experiments.hand_session.GuardTripped` (the finger relaxed) where the
        guard stopped the run; :class:`~alpes_dyn.InputError` for bad settings, before the hand moves.
    """
    design = _checked_run(hw, nominal, design, calibration, path)
    st = np.asarray(stages, dtype=float)
    if st.ndim != 1 or st.size == 0 or not (np.all(np.isfinite(st)) and np.all(np.diff(st) >= 0) and st[0] > 0
                                            and st[-1] <= 1):
        raise InputError(f"stages: expected non-decreasing fractions in (0, 1], got {list(stages)!r}")
    for name, v, lo in (("stage_seconds", stage_seconds, 0.1), ("hold", hold, 0.1), ("tolerance", tolerance, 0.0)):
        if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v > lo):
            raise InputError(f"{name}: expected a number above {lo:g}, got {v!r}")
    cal = calibration if calibration is not None else calibrate(hw, nominal)
    g = _one_orientation(design)
    t_design, _, target_nominal = designed_torque(nominal, design)
    bias0, amp, dither = _on_hand_excitation(nominal, design)
    held = _held(nominal)
    low, high = _band(nominal, design, cal, margin)
    low, high = _joint_guard(nominal, design, g, float(hw.tau_max), low, high)
    target = np.where(held, cal.rest, np.clip(target_nominal, low + 0.3 * (high - low), high - 0.3 * (high - low)))
    peak = np.max(np.abs(_profiles(design, t_design, np.zeros_like(bias0), amp, dither)), axis=0)
    cap = np.minimum(np.where(np.isfinite(cal.fold_torque), cal.fold_torque - FOLD_PEAKS * peak, np.inf),
                     float(hw.tau_max) - peak)  # the excitation within [0, tau_max] about any bias in [peak, cap]
    cap[held] = 0.0  # a held motor's bias stays 0 N m through the trim and the stages
    s = HandSession(hw, low, high)
    trim = design.trim_bias and design.torque_bias is None
    start = low + START_SHARE * (target - low)  # from below: the dither lets the finger slide further up
    bias = np.clip(cal.torque_at(start), peak, cap) if trim else bias0.copy()
    if np.any(bias - peak < 0) or np.any(bias + peak > hw.tau_max):
        raise InputError(f"design: the excitation about the bias {bias.tolist()} N m (peak {peak.tolist()} N m) leaves "
                         f"the driver's [0, {hw.tau_max:g}] N m")
    s.ramp_to(np.maximum(bias, 0.0), 1.0)
    clock = _Clock(design, s, amp, dither, bias0)
    holds = _trim(s, clock, cal, target, bias, peak, cap, hold, max_holds if trim else 1, tolerance)
    bias, rest = holds[-1][0], holds[-1][1]
    bias, scale, stage_log = _stages(s, clock, nominal, cal, bias, rest, low, high, st, stage_seconds, peak,
                             (peak, cap) if trim else None, hold)
    if not scale > 0.0:  # the dither alone fills the band: a record without multisine identifies nothing
        s.relax()
        raise GuardTripped("guard: no room for the multisine in the guard band (the stages' swing, the dither's "
                           "alone, leaves it at any amplitude); the excitation was stopped and the finger relaxed to "
                           "0 N m", "stop", float(s.log().t[-1]), s.counts.copy(), s.log())
    clock.k = 0
    rows = s.run(clock.commands(bias, scale, design.n_samples))
    s.relax()
    held = s.held_torque(rows)
    rec = Recording(t=design.dt * np.arange(design.n_samples), encoder=s.log().counts[rows], torque=held,
                    motor_names=tuple(hw.motor_names), joint_names=nominal.joint_names,
                    gravity=None if np.array_equal(g, nominal.gravity) else np.repeat(g[None], design.n_samples, 0))
    if path is not None:
        write_recording(rec, path)
    return OnHandResult(rec, bias, bias0, target, rest, scale, holds, bool(np.any(bias >= cap - 1e-12)), cal,
                        s.log(), rows, stage_log)


def _band(nominal: Model, design: ExperimentDesign, cal: Calibration, margin: float | None
          ) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) (m,) counts: the calibrated range less ``margin`` counts at each end (default the design's joint
    margin through the pulley ratios); InputError where nothing is left."""
    tr = nominal.transmission
    if margin is None:
        mc = np.abs(np.asarray(tr.S, dtype=float)).sum(axis=1) * design.margin * tr.counts_per_rev / (2 * np.pi)
    elif isinstance(margin, bool) or not (isinstance(margin, (int, float)) and math.isfinite(margin) and margin >= 0):
        raise InputError(f"margin: expected a number of counts >= 0, got {margin!r}")
    else:
        mc = np.full(tr.n_motors, float(margin))
    low, high = cal.low + mc, cal.high - mc
    held = _held(nominal)  # guarded about its rest: its joint dragged by more than the margin trips the guard
    low[held], high[held] = cal.rest[held] - mc[held], cal.rest[held] + mc[held]
    if np.any(high <= low):
        raise InputError(f"margin: {mc.tolist()} counts at each end leave nothing of the calibrated range "
                         f"[{cal.low.tolist()}, {cal.high.tolist()}] counts")
    return low, high


def _joint_guard(nominal: Model, design: ExperimentDesign, g: np.ndarray, tau_max: float, low: np.ndarray,
                 high: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The guard band narrowed to the counts between which the joints keep the design's ``margin`` from their own
    stops (:func:`~alpes_dyn.estimation.experiments.joint_stops.joint_band`, a finger of one motor); InputError
    naming the joints where nothing is left."""
    if nominal.transmission.n_motors != 1:
        return low, high  # the joints' band is a finger's (one motor): the hand's experiment runs chain by chain
    jl, jh, who = joint_band(nominal, g, design.margin, tau_max)
    low, high = np.maximum(low, jl), np.minimum(high, jh)
    if np.any(high <= low):
        raise InputError(f"margin: the joints' stops ({who[0]} below, {who[1]} above, {math.degrees(design.margin):.3g} "
                         f"degrees inside them) and the calibrated range leave no encoder counts for the excitation")
    return low, high


class _Clock:
    """The excitation's time axis: the record's first tick is t = 0 (the multisine from its designed phase, the
    recorded torque the designed one but for the bias), and so is each amplitude stage's (each replays the record's
    first ticks: the design checked its amplitude on the nominal finger over the record's window only, and the
    multisine's crest elsewhere in its 10 s period can be higher -- the nominal finger driven through the 2 s before
    the window went past its fold). :meth:`commands` of the next K ticks at a bias and a multisine scale, the dither
    at full."""

    def __init__(self, design: ExperimentDesign, s: HandSession, amp: np.ndarray, dither: np.ndarray,
                 bias0: np.ndarray) -> None:
        self.design, self.s, self.amp, self.dither, self.bias0, self.k = design, s, amp, dither, bias0, 0

    def commands(self, bias: np.ndarray, scale: float, n: int) -> np.ndarray:
        t = self.design.dt * (self.k + np.arange(n))
        self.k += n
        return _profiles(self.design, t, bias, self.amp * scale, self.dither)

    def multisine(self, rows: slice, bias: np.ndarray) -> np.ndarray:
        """(K, m) the multisine part of the commands written at ``rows``, the last ones (the dither taken off)."""
        n = rows.stop - rows.start
        t = self.design.dt * (self.k - n + np.arange(n))
        return self.s.log().command[rows] - _profiles(self.design, t, bias, np.zeros_like(bias), self.dither)


def _trim(s: HandSession, clock: _Clock, cal: Calibration, target: np.ndarray, bias: np.ndarray, floor: np.ndarray,
          cap: np.ndarray, hold: float, max_holds: int, tolerance: float) -> list:
    """The iterated holds of the module docstring: [(bias (m,), mean counts (m,)), ...], the last the bias kept."""
    n = max(2, int(round(hold / s.period)))
    holds = []
    for _ in range(max_holds):  # a few holds of a second each
        rows = s.run(clock.commands(bias, 0.0, n))
        mean = s.log().counts[rows][n // 2:].mean(axis=0)
        holds.append((bias.copy(), mean))
        if np.all(np.abs(mean - target) <= tolerance):
            break
        new = np.clip(bias + STEP_GAIN * (cal.torque_at(target) - cal.torque_at(mean)), floor, cap)
        if np.allclose(new, bias, rtol=0, atol=1e-9):
            break  # held at the cap (a fold) or at 0: nothing more to gain
        bias = new
    return holds


def _stages(s: HandSession, clock: _Clock, nominal: Model, cal: Calibration, bias: np.ndarray, rest: np.ndarray,
            low: np.ndarray, high: np.ndarray, stages: np.ndarray, seconds: float, peak: np.ndarray,
            bounds: tuple[np.ndarray, np.ndarray] | None, hold: float) -> tuple[np.ndarray, float, list]:
    """Bring the multisine up stage by stage (the module docstring, step 4), on the ticks just before the record
    (every stage runs, at the smaller of its step and the amplitude found to fit), the bias corrected after each
    where ``bounds`` (floor, cap) are given (:func:`_running_correction`); (bias, the scale the record runs at,
    [(bias, scale, hand's mean counts, nominal's mean counts), ...] per stage)."""
    s.arm()
    n = min(max(2, int(round(seconds / s.period))), clock.design.n_samples)
    last = s.log().counts[-max(2, int(round(hold / s.period)) // 2):]
    swing_dither = np.max(np.abs(last - rest), axis=0)
    ms_peak = np.maximum(peak - clock.dither, 0.0)  # the multisine's own peak over the record (N m)
    allowed, out, excitation = 1.0, [], []
    for a in stages:  # three or four steps
        clock.k = 0  # each stage replays the record's first ticks: the excitation the design checked
        scale = min(float(a), allowed)
        rows = s.run(clock.commands(bias, scale, n))
        counts = s.log().counts[rows]
        torque = np.max(np.abs(clock.multisine(rows, bias)), axis=0)
        mid = counts[n // 2:].mean(axis=0)
        room = np.minimum(high - mid, mid - low)
        swing = np.maximum(np.max(np.abs(counts - mid), axis=0) - swing_dither, 0.0)
        full = np.where(torque > 0, swing / np.maximum(torque, 1e-300), 0.0) * ms_peak * (clock.amp > 0)
        fit = np.where(full > 0, (room / FOLD_PEAKS - swing_dither) / np.maximum(full, 1e-300), np.inf)
        allowed = min(allowed, float(np.clip(np.min(fit), 0.0, 1.0)))
        excitation.append(s.log().command[rows] - bias)
        ref = _nominal_mean(nominal, clock, np.concatenate(excitation), n)
        out.append((bias.copy(), scale, mid, ref))
        if bounds is not None:
            bias = np.clip(bias + STEP_GAIN * (cal.torque_at(ref) - cal.torque_at(mid)), *bounds)
    return bias, min(float(stages[-1]), allowed), out


def _nominal_mean(nominal: Model, clock: _Clock, excitation: np.ndarray, n: int) -> np.ndarray:
    """(m,) counts: the nominal finger's mean encoder reading over the second half of the last ``n`` ticks of
    ``excitation`` (K, m), N m, every stage's so far about the nominal bias, from its rest under the first torque
    (the stages before spend its transient): what the hand's mean over the same ticks is trimmed to -- the designed
    trajectory's, not the static rest's: under the multisine the mean reading of a finger close to its fold moves
    off its rest (by a visible share of the range on the MuJoCo stand-in's finger3)."""
    design = clock.design
    u = excitation + clock.bias0
    k = u.shape[0]
    g = np.asarray(design.orientations[0], dtype=float)
    x = _simulate(nominal, design, u, np.repeat(g[None], k, 0), np.zeros(k, dtype=int))
    y = np.asarray(_reading(nominal, x[k - n + n // 2:, : nominal.n].T), dtype=float).reshape(-1, n - n // 2).T
    return y.mean(axis=0) * nominal.transmission.counts_per_rev / (2 * np.pi)
