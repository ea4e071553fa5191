"""The hand's calibration before the identification experiment: its rest, the usable range of its encoders and the
relation counts <-> motor torque at rest, found through the :class:`~alpes_dyn.bench.interface.HardwareInterface`
only (no model of the finger is trusted for them).

:func:`calibrate`, one motor at a time, the others relaxed (0 N m):

1. the rest: the command held at 0 N m for ``settle`` s (the cable slack, the springs and gravity alone), the median
   of the encoder over its second half;
2. a slow torque ramp from 0 at ``rate`` N m/s, the torque held while the encoder moves faster than ``speed``
   counts/s (quasi-static where the finger is most compliant: near its fold a small torque step moves it by
   hundreds of counts, and its slowest mode takes a few tenths of a second), up to ``safe_torque`` at most, stopped
   at the first knee, where the motion stops growing with the torque as it did: once the encoder has left the rest by
   :data:`MIN_MOVE_COUNTS`, the slope over the last :data:`KNEE_WINDOW` of the safe torque below
   :data:`KNEE_FRACTION` of the steepest one seen (a joint reached its stop, or the springs balance the pull). The
   encoder reads the joints' sum only, so the first joint's stop is the range's end: on the MuJoCo stand-in's
   finger3 (palm up) q_1 reaches its upper stop well below the safe torque, where the slope falls to a fraction,
   while the sum grows on up to the safe torque as q_2 and q_3 follow. The
   reading at the knee (or at the safe torque) is the usable range's upper end. Its lower end is the knee below the
   steepest slope, where a joint left its stop (:func:`_lower_end`, :data:`LIFT_FRACTION`), or the rest;
3. the ramp's curve (counts against torque, :data:`CURVE_POINTS` points) kept: the static relation the trim of
   :func:`~alpes_dyn.estimation.experiments.on_hand.run_experiment` starts from, and a fold found on it: palm up an
   Alpes finger's static equilibria can end where gravity's torque outgrows its springs', and the finger then snaps
   to its stops: the encoder growing by more than :data:`SNAP_FRACTION` of the range while the torque grows by
   less than :data:`FOLD_WINDOW` of the safe torque (the ramp holds its torque while the encoder runs, so a snap is
   a jump at one torque); its torque is where the experiment's bias must stay below. A steep but stable branch is no
   fold: on the MuJoCo stand-in's finger3 palm up, q_1 sweeps from stop to stop over a narrow band of torque, the
   same up and down (no hysteresis, no snap), which a narrower window took for a fold;
4. the command ramped back to 0 N m, four times as fast (at ``rate``: unhindered by the speed hold).

A motor whose joints have no spring (the thumb's ab/adduction) is not ramped: against no spring a torque above its
joint's friction runs the joint to a stop, so a ramp finds no static relation. Its rest is read as above and kept
as its whole range (``low = high = rest``), its curve flat at the rest with zero torque
(:meth:`Calibration.torque_at` reads 0 N m): the experiment holds it relaxed (:mod:`.on_hand`).

The ramp has no dither: rising, the finger's dry friction holds it back, so the curve reads fewer counts at a torque
than the finger rests at once a dither keeps its joints sliding (the experiment's trim starts below its target and
corrects on the hand, for that reason).

The :class:`Calibration` is plain data; :meth:`Calibration.save` and :func:`load_calibration` keep it as a small JSON
file. The encoder's counts are taken in the model's frame (q_m = 2 pi counts / counts_per_rev = S q, up to a few
counts of offset that the fit takes): a rest or range far outside what the model's joint ranges allow is refused
by name, as the recording's reader refuses it.
"""

from __future__ import annotations

import bisect
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...bench.interface import HardwareInterface
from ...errors import InputError, RecordingError
from ...fileio import atomic_path, read_bytes
from ...model.robot import Model
from .hand_session import HandSession
from .multisine import _motor_groups
from .recording import _check_encoder_columns

__all__ = ["Calibration", "calibrate", "load_calibration", "MIN_MOVE_COUNTS", "KNEE_WINDOW", "KNEE_FRACTION",
           "LIFT_FRACTION", "SNAP_FRACTION", "FOLD_WINDOW", "CURVE_POINTS"]

MIN_MOVE_COUNTS = 50.0
"""Counts the encoder must leave the rest by before the ramp may call the motion stopped (a slack cable's dead band
first moves nothing)."""
KNEE_WINDOW = 0.05
"""The window of the knee test, a fraction of the safe torque (2.5e-3 N m of the Alpes fingers' 0.05): the slope
is the encoder's growth over it."""
KNEE_FRACTION = 0.3
"""The upper knee: the slope over the last window below this share of the steepest seen on the ramp (a joint reached
its stop, or the springs balance the pull). Palm up, finger3's q_1 reaches its stop first and the slope falls to a
sixth. Hung fingers down (the MuJoCo stand-in turned) q_2 reaches its stop first and the slope falls by a third only
(q_1 and q_3 still move): this rule misses it and the range runs on to q_1's stop, while a larger share, which
catches it, ends the palm-up range early, on the slope's fall past the fold (a known limit: the calibration is for
the palm-up rig)."""
LIFT_FRACTION = 0.3
"""The lower knee: the last window below the steepest slope whose slope is under this share of it (a joint lifting
off its stop is a jump of the slope; a slope that grows smoothly, hung, keeps the rest as the lower end)."""
SNAP_FRACTION = 0.25
"""A fold: a window of :data:`FOLD_WINDOW` of the safe torque that moved the encoder by more than this share of the
usable range."""
FOLD_WINDOW = 0.002
"""The fold test's torque window, a fraction of the safe torque (1e-4 N m of the Alpes fingers' 0.05): a snap moves
the encoder at one held torque; the steepest stable branch (the MuJoCo stand-in's finger3 palm up, q_1 sweeping
from stop to stop) moves it by a small fraction of the range over the window."""
CURVE_POINTS = 200
"""Points of the counts <-> torque curve kept (bins of the ramp's torque, the counts averaged in each)."""


@dataclass(frozen=True)
class Calibration:
    """What :func:`calibrate` found, per motor (arrays (m,) in the order of ``motor_names``).

    Attributes
    ----------
    motor_names : tuple of str
        The hand's motors.
    rest : numpy.ndarray
        The encoder at rest, the motor relaxed (0 N m), counts.
    low : numpy.ndarray
        The usable range's lower end, counts: where the ramp's slope first rose above :data:`KNEE_FRACTION` of its
        steepest for good (a joint leaving its stop), or the rest.
    torque_low : numpy.ndarray
        The torque at ``low`` on the ramp, N m.
    high : numpy.ndarray
        The usable range's upper end, counts: where the motion stopped growing with the torque, or the reading
        at the safe torque.
    torque_high : numpy.ndarray
        The torque at which the ramp reached ``high``, N m.
    stop : numpy.ndarray
        (m,) bool: True where ``high`` is a stop (the motion stopped growing), False where the ramp reached the
        safe torque first.
    fold_torque : numpy.ndarray
        The torque at which the finger snapped on the ramp (a fold of its static equilibria), N m; NaN: none.
    safe_torque : float
        The largest torque the ramps could apply, N m.
    curve_torque, curve_counts : numpy.ndarray
        (P, m) the ramp's static relation: torque (N m) and mean encoder (counts) in each of P bins.
    """

    motor_names: tuple[str, ...]
    rest: np.ndarray
    low: np.ndarray
    torque_low: np.ndarray
    high: np.ndarray
    torque_high: np.ndarray
    stop: np.ndarray
    fold_torque: np.ndarray
    safe_torque: float
    curve_torque: np.ndarray
    curve_counts: np.ndarray

    def torque_at(self, counts: np.ndarray) -> np.ndarray:
        """(m,) N m: the torque at which each motor's ramp read ``counts`` (m,) counts, on the curve below its fold
        (its counts made non-decreasing; clipped to the curve's ends).

        Parameters
        ----------
        counts : numpy.ndarray, shape (m,)
            Each motor's encoder reading, counts.

        Returns
        -------
        numpy.ndarray, shape (m,)
            The torques, N m.
        """
        c = np.asarray(counts, dtype=float).reshape(len(self.motor_names))
        out = np.empty(c.size)
        for k in range(c.size):  # a loop over the motors (one to six)
            tau, cnt = self.curve_torque[:, k], np.maximum.accumulate(self.curve_counts[:, k])
            keep = ~(tau > self.fold_torque[k]) & np.isfinite(cnt)
            out[k] = float(np.interp(c[k], cnt[keep], tau[keep]))
        return out

    def to_dict(self) -> dict:
        """The calibration as plain JSON types (counts, N m)."""
        return {"motor_names": list(self.motor_names), "rest_counts": self.rest.tolist(),
                "low_counts": self.low.tolist(), "torque_low_nm": self.torque_low.tolist(),
                "high_counts": self.high.tolist(), "torque_high_nm": self.torque_high.tolist(),
                "stop": [bool(s) for s in self.stop], "safe_torque_nm": self.safe_torque,
                "fold_torque_nm": [None if not math.isfinite(v) else v for v in self.fold_torque.tolist()],
                "curve_torque_nm": self.curve_torque.tolist(), "curve_counts": self.curve_counts.tolist()}

    def save(self, path: str | Path) -> Path:
        """Write :meth:`to_dict` as JSON to ``path`` (atomically).

        Parameters
        ----------
        path : str or pathlib.Path
            The JSON file written.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        with atomic_path(path, "calibration") as tmp:
            tmp.write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="utf-8")
        return Path(path)


def load_calibration(path: str | Path) -> Calibration:
    """The :class:`Calibration` saved at ``path``; InputError naming the file and the field otherwise.

    Parameters
    ----------
    path : str or pathlib.Path
        The JSON file (:meth:`Calibration.save`'s).

    Returns
    -------
    Calibration

    Raises
    ------
    InputError
        The file unreadable or a field missing or malformed.
    """
    try:
        d = json.loads(read_bytes(path, "calibration", limit=1 << 20).decode("utf-8"))
        names = tuple(str(n) for n in d["motor_names"])
        arrays = {f: np.asarray(d[key], dtype=float) for f, key in
                  (("rest", "rest_counts"), ("low", "low_counts"), ("torque_low", "torque_low_nm"),
                   ("high", "high_counts"), ("torque_high", "torque_high_nm"))}
        fold = np.array([math.nan if v is None else float(v) for v in d["fold_torque_nm"]])
        curve_t, curve_c = np.asarray(d["curve_torque_nm"], dtype=float), np.asarray(d["curve_counts"], dtype=float)
        cal = Calibration(names, stop=np.asarray(d["stop"], dtype=bool), fold_torque=fold,
                          safe_torque=float(d["safe_torque_nm"]), curve_torque=curve_t, curve_counts=curve_c, **arrays)
    except (KeyError, TypeError, ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"calibration {str(path)!r}: not a calibration file ({type(exc).__name__}: "
                         f"{str(exc)[:80]})") from None
    m = len(names)
    if any(a.shape != (m,) for a in (*arrays.values(), fold)) or curve_t.shape != curve_c.shape \
            or curve_t.ndim != 2 or curve_t.shape[1] != m:
        raise InputError(f"calibration {str(path)!r}: expected one value per motor ({m}) and a curve of shape (P, {m})")
    return cal


def _checked(hw: HardwareInterface, model: Model, safe_torque: float | None, rate: float | None, settle: float
             ) -> tuple[float, float]:
    if not isinstance(model, Model) or model.transmission is None:
        raise InputError(f"model: expected an alpes_dyn Model with motors, got {type(model).__name__}")
    if not isinstance(hw, HardwareInterface):
        raise InputError(f"hw: expected a HardwareInterface, got {type(hw).__name__}")
    tr = model.transmission
    if tuple(hw.motor_names) != tuple(tr.motor_names):
        raise InputError(f"hw: its motors {', '.join(hw.motor_names)} are not the model's "
                         f"{', '.join(tr.motor_names)}")
    if not math.isclose(float(hw.counts_per_rev), float(tr.counts_per_rev)):
        raise InputError(f"hw: its encoders count {hw.counts_per_rev} a revolution, the model's "
                         f"{tr.counts_per_rev:g}")
    safe = float(hw.tau_max) if safe_torque is None else safe_torque
    if isinstance(safe, bool) or not (isinstance(safe, (int, float)) and 0 < safe <= float(hw.tau_max)):
        raise InputError(f"safe_torque: expected a torque in (0, {hw.tau_max:g}] N m (the driver's tau_max), "
                         f"got {safe_torque!r}")
    rate = safe / 8.0 if rate is None else rate
    if isinstance(rate, bool) or not (isinstance(rate, (int, float)) and 0 < rate <= safe / 0.5):
        raise InputError(f"rate: expected a ramp rate in (0, {safe / 0.5:g}] N m/s, got {rate!r}")
    if isinstance(settle, bool) or not (isinstance(settle, (int, float)) and 0.05 <= settle <= 60):
        raise InputError(f"settle: expected a hold in [0.05, 60] s, got {settle!r}")
    return float(safe), float(rate)


def calibrate(hw: HardwareInterface, model: Model, *, safe_torque: float | None = None, rate: float | None = None,
              settle: float = 0.5, speed: float = 500.0) -> Calibration:
    """Calibrate the hand on ``hw`` (the module docstring), one motor at a time.

    Parameters
    ----------
    hw : HardwareInterface
        The hand (its motors and encoder resolution those of ``model``).
    model : Model
        The nominal model: its motors' names and encoders; its joint ranges bound the plausible counts.
    safe_torque : float, optional
        The most torque a ramp applies, N m (default the driver's ``tau_max``).
    rate : float, optional
        The ramp's rate, N m/s (default ``safe_torque / 8``: 6.25e-3 N m/s on an Alpes finger, 8 s to the safe
        torque).
    settle : float
        The holds at 0 N m before each ramp and after it, s.
    speed : float
        The encoder's speed above which the ramp holds its torque, counts/s (default 500: 11 degrees a second of
        an Alpes finger's joint sum), so that the curve is the finger's rest even where it is most compliant.

    Returns
    -------
    Calibration
        Raises :class:`~alpes_dyn.errors.GuardTripped` where the loop missed its period (the finger relaxed),
        :class:`~alpes_dyn.errors.RecordingError` where the encoder's readings are not in the model's frame.
    """
    safe, rate = _checked(hw, model, safe_torque, rate, settle)
    if isinstance(speed, bool) or not (isinstance(speed, (int, float)) and math.isfinite(speed) and speed > 0):
        raise InputError(f"speed: expected a positive encoder speed in counts/s, got {speed!r}")
    s = HandSession(hw)
    m = s.m
    rest, low, t_low, high, t_high = (np.zeros(m) for _ in range(5))
    stop, fold = np.zeros(m, dtype=bool), np.full(m, np.nan)
    curves_t, curves_c = np.zeros((CURVE_POINTS, m)), np.zeros((CURVE_POINTS, m))
    free = set(_motor_groups(model)[2])
    for k in range(m):  # a loop over the motors, one ramp each
        rows = s.ramp_to(np.zeros(m), settle)
        held = s.log().counts[rows, k]
        rest[k] = float(np.median(held[held.size // 2:]))
        if k in free:  # held, not ramped (the module docstring): its range and curve are its rest
            low[k] = high[k] = rest[k]
            curves_c[:, k] = rest[k]
            continue
        tau, cnt, stop[k], knee = _ramp(s, k, safe, rate, rest[k], speed)
        high[k], t_high[k] = _upper_end(tau, cnt, knee, max(1, int(round(0.01 / s.period))))
        fold[k] = _fold(tau, cnt, safe, high[k] - rest[k])
        curves_t[:, k], curves_c[:, k] = _binned(tau, cnt)
        low[k], t_low[k] = _lower_end(curves_t[:, k], curves_c[:, k], KNEE_WINDOW * safe, rest[k])
        s.ramp_to(np.zeros(m), float(tau[-1]) / (4 * rate) if tau[-1] > 0 else settle)
    s.ramp_to(np.zeros(m), settle)
    try:
        _check_encoder_columns({n: np.array([rest[k], high[k]]) for k, n in enumerate(hw.motor_names)}, model)
    except RecordingError as exc:
        raise RecordingError(f"calibration: {exc}: the encoder's counts must be the model's (0 with every joint at "
                             "0); zero the driver's encoder so") from None
    return Calibration(tuple(hw.motor_names), rest, low, t_low, high, t_high, stop, fold, safe, curves_t, curves_c)


def _ramp(s: HandSession, k: int, safe: float, rate: float, rest: float, speed: float
          ) -> tuple[np.ndarray, np.ndarray, bool, int]:
    """Ramp motor ``k`` from 0 at ``rate`` N m/s, held while its encoder moves faster than ``speed`` counts/s, until
    its motion stops growing (the knee test of the module docstring, every 10 ticks) or the torque reaches ``safe``:
    (torque (K,), counts (K,), stopped, the knee's tick)."""
    u = np.zeros(s.m)
    tau, cnt = [], []
    dtau = rate * s.period
    window = KNEE_WINDOW * safe
    n_smooth = max(1, int(round(0.01 / s.period)))  # 10 ms of readings averaged against the encoder's noise
    n_speed = max(2, int(round(0.05 / s.period)))  # the encoder's speed over the last 50 ms
    steepest, i = 0.0, 0
    while True:  # the loop of the bench, one tick an iteration, until the test stops it
        i += 1
        fast = i > n_speed and abs(cnt[-1] - cnt[-n_speed]) > speed * (n_speed - 1) * s.period
        u[k] = u[k] if fast else min(safe, u[k] + dtau)
        s.step(u)
        tau.append(u[k])
        cnt.append(s.counts[k])
        if i % 10 or u[k] < window + dtau or fast:
            if u[k] >= safe:
                return np.array(tau), np.array(cnt), False, i - 1
            continue
        now = float(np.mean(cnt[-n_smooth:]))
        j = max(n_smooth - 1, bisect.bisect_left(tau, u[k] - window))  # the window's first tick
        before = float(np.mean(cnt[j - n_smooth + 1: j + 1]))
        slope = (now - before) / (u[k] - tau[j])
        steepest = max(steepest, slope)
        if now - rest > MIN_MOVE_COUNTS and slope < KNEE_FRACTION * steepest:
            return np.array(tau), np.array(cnt), True, j
        if u[k] >= safe:
            return np.array(tau), np.array(cnt), False, i - 1


def _upper_end(tau: np.ndarray, cnt: np.ndarray, knee: int, n_smooth: int) -> tuple[float, float]:
    """(counts, torque) of the usable range's upper end: the mean reading over the 10 ms before the ``knee``'s tick
    (the last one at the safe torque) and its torque."""
    return float(np.mean(cnt[max(0, knee - n_smooth + 1): knee + 1])), float(tau[knee])


def _lower_end(tau: np.ndarray, cnt: np.ndarray, window: float, rest: float) -> tuple[float, float]:
    """(counts, torque) of the usable range's lower end on the binned curve (P,), (P,): below the steepest slope
    (over ``window`` N m), the middle of the last window whose slope is under :data:`LIFT_FRACTION` of it (palm up,
    finger3's q_1 lies on its lower stop at first while q_2 and q_3 move, and the slope jumps several times over
    once it lifts off); the rest (0 N m) where the slope stays above it all the way."""
    w = max(1, int(np.searchsorted(tau, tau[0] + window)))
    if tau.size <= w:
        return rest, 0.0
    slope = (cnt[w:] - cnt[:-w]) / np.maximum(tau[w:] - tau[:-w], 1e-300)
    top = int(np.argmax(slope))
    flat = np.flatnonzero(slope[:top] < LIFT_FRACTION * slope[top])
    if flat.size == 0:
        return rest, 0.0
    i = int(flat[-1]) + w // 2  # the knee within the window, taken at its middle
    return float(cnt[i]), float(tau[i])


def _fold(tau: np.ndarray, cnt: np.ndarray, safe: float, span: float) -> float:
    """The torque (N m) at the start of the window of :data:`FOLD_WINDOW` of ``safe`` over which the ramp's reading
    grew the most, if it grew by more than :data:`SNAP_FRACTION` of ``span`` (a snap: a fold of the static
    equilibria); NaN otherwise."""
    if tau.size < 3 or not span > 0:
        return math.nan
    j = np.searchsorted(tau, tau - FOLD_WINDOW * safe)  # each sample's window start
    growth = cnt - cnt[j]
    i = int(np.argmax(growth))
    return float(tau[j[i]]) if growth[i] > SNAP_FRACTION * span else math.nan


def _binned(tau: np.ndarray, cnt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(P,), (P,): the ramp's torque cut into :data:`CURVE_POINTS` equal bins, each bin's mean torque and counts
    (empty bins take their neighbours' by interpolation)."""
    edges = np.linspace(0.0, float(tau[-1]), CURVE_POINTS + 1)
    b = np.clip(np.searchsorted(edges, tau, side="right") - 1, 0, CURVE_POINTS - 1)
    n = np.bincount(b, minlength=CURVE_POINTS)
    st = np.bincount(b, tau, CURVE_POINTS)
    sc = np.bincount(b, cnt, CURVE_POINTS)
    full = n > 0
    centres = 0.5 * (edges[:-1] + edges[1:])
    t_mean = np.where(full, st / np.maximum(n, 1), centres)
    c_mean = np.interp(t_mean, t_mean[full], sc[full] / n[full])
    return t_mean, c_mean
