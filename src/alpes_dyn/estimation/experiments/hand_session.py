"""A guarded session on the hand: every command written and every reading logged through the
:class:`~alpes_dyn.bench.interface.HardwareInterface`, each reading checked by the guard, the finger relaxed before
anything is raised.

The guard (:class:`HandSession`) trips on a reading

* whose encoder count leaves the guard band [low, high] of its motor (a margin inside the usable range that
  :func:`~alpes_dyn.estimation.experiments.calibration.calibrate` found: the excitation is stopped before the
  finger reaches a stop; the low side from :meth:`HandSession.arm` on, since a run starts from the relaxed rest
  below it), or
* whose time stamp comes more than :data:`MAX_GAP` periods after the previous one (the loop missed its period: a
  late command has held over a longer period than designed, and a recording with a gap is not one run).

On a trip the command is ramped from the last one written to the rest torque (0 N m: a cable only pulls, so
relaxed) over :data:`RELAX_SECONDS`, the readings still logged, and :class:`GuardTripped` is raised, carrying the
reason, the reading that tripped and the whole log. Never silently: a guarded run either completes or raises.

Timing: ``r_0 = read(); write(u_0); r_1 = read(); ...`` (the interface's). The log's row k holds the reading r_k
and the command u_k written after it; the torque *measured* over [t_k, t_k+1), the current that u_k drew, is the
one read at r_(k+1) (:meth:`HandSession.held_torque`): what a recording's ``torque_<motor>`` row k holds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...bench.interface import HardwareInterface, Reading
from ...errors import AlpesDynError, InputError

__all__ = ["MAX_GAP", "RELAX_SECONDS", "GuardTripped", "HandSession", "SessionLog"]

MAX_GAP = 1.5
"""A reading more than this many periods after the previous one trips the guard (the loop missed its period)."""

RELAX_SECONDS = 0.05
"""The ramp from the last command to the rest torque after a trip or at the end of a run, s: short, since a finger
running away towards its stop (past its fold) goes on while the torque is still above what holds it; 50 ms at its
speed must lie within the guard's margin (a step to 0 would let the springs snap it back at once)."""


@dataclass
class SessionLog:
    """Everything a session read and wrote, one row per tick.

    Attributes
    ----------
    t : numpy.ndarray
        (K,) the readings' time stamps, s.
    counts : numpy.ndarray
        (K, m) encoder counts.
    torque : numpy.ndarray
        (K, m) measured motor torque at each reading, N m.
    force : numpy.ndarray
        (K,) fingertip force, N (NaN without a sensor).
    command : numpy.ndarray
        (K, m) the command written after each reading, N m (NaN after the last reading: none written).
    """

    t: np.ndarray
    counts: np.ndarray
    torque: np.ndarray
    force: np.ndarray
    command: np.ndarray


class GuardTripped(AlpesDynError, RuntimeError):
    """The guard stopped a run on the hand (the finger relaxed first): ``reason`` is ``"stop"`` (an encoder left
    its guard band) or ``"period"`` (a missed period); ``t`` (s) and ``counts`` (m,) the reading that tripped;
    ``log`` the :class:`SessionLog` up to the end of the relaxing ramp."""

    def __init__(self, message: str, reason: str, t: float, counts: np.ndarray, log: SessionLog) -> None:
        super().__init__(message)
        self.reason, self.t, self.counts, self.log = reason, t, counts, log


class HandSession:
    """The guarded session on ``hw``.

    Parameters
    ----------
    hw : HardwareInterface
        The hand (its first reading is taken here).
    low, high : array_like or None
        (m,) the guard band of each motor's encoder, counts; None: no position guard (the calibration's ramps,
        which look for the range's ends themselves). The time-stamp guard is always on.
    """

    def __init__(self, hw: HardwareInterface, low: np.ndarray | None = None, high: np.ndarray | None = None) -> None:
        if not isinstance(hw, HardwareInterface):
            raise InputError(f"hw: expected a HardwareInterface (read, write, close, period, motor_names, "
                             f"counts_per_rev, tau_max), got {type(hw).__name__}")
        self.hw = hw
        self.m = len(hw.motor_names)
        self.period = float(hw.period)
        self.low = None if low is None else np.asarray(low, dtype=float).reshape(self.m)
        self.high = None if high is None else np.asarray(high, dtype=float).reshape(self.m)
        self._t: list[float] = []
        self._counts: list[np.ndarray] = []
        self._torque: list[np.ndarray] = []
        self._force: list[float] = []
        self._command: list[np.ndarray] = []
        self.last_command = np.zeros(self.m)
        self._log(self._read())
        self.armed = False  # the low side of the band: from arm() on

    def _read(self) -> Reading:
        r = self.hw.read()
        counts = np.asarray(r.counts, dtype=float).reshape(self.m)
        if not np.isfinite(counts).all() or not math.isfinite(float(r.t)):
            raise InputError(f"read: the hand returned a reading that is not finite (t {r.t!r}, counts "
                             f"{counts.tolist()!r})")
        return Reading(float(r.t), counts, np.asarray(r.torque, dtype=float).reshape(self.m), float(r.force))

    def _log(self, r: Reading) -> None:
        self._t.append(r.t)
        self._counts.append(r.counts)
        self._torque.append(r.torque)
        self._force.append(r.force)

    @property
    def k(self) -> int:
        """The index of the current reading in the log."""
        return len(self._t) - 1

    @property
    def counts(self) -> np.ndarray:
        """(m,) the current reading's encoder counts."""
        return self._counts[-1]

    def log(self) -> SessionLog:
        """The session's :class:`SessionLog` so far."""
        cmd = np.full((len(self._t), self.m), np.nan)
        if self._command:
            cmd[: len(self._command)] = np.array(self._command)
        return SessionLog(np.array(self._t), np.array(self._counts).reshape(-1, self.m),
                          np.array(self._torque).reshape(-1, self.m), np.array(self._force), cmd)

    def step(self, command: np.ndarray, guarded: bool = True) -> Reading:
        """Write ``command`` (m,), N m, read the next tick and check it (unless not ``guarded``: the relaxing
        ramp). Raises :class:`GuardTripped` after relaxing the finger.

        Parameters
        ----------
        command : numpy.ndarray, shape (m,)
            The motor torque command, N m.
        guarded : bool, optional
            Check each reading against the guard (default True; False: the relaxing ramp).

        Returns
        -------
        Reading
            The next tick's reading.
        """
        u = np.asarray(command, dtype=float).reshape(self.m)
        self.hw.write(u)
        self._command.append(u)
        self.last_command = u
        r = self._read()
        self._log(r)
        if guarded:
            self._check(r)
        return r

    def run(self, commands: np.ndarray, guarded: bool = True) -> slice:
        """:meth:`step` through the rows of ``commands`` (K, m), N m; the log's rows at which they were written (the
        reading each followed: row r holds the counts at t_r and the command held over [t_r, t_r+1)).

        Parameters
        ----------
        commands : numpy.ndarray, shape (K, m)
            The commands, N m, one a tick.
        guarded : bool, optional
            Check each reading against the guard (default True; False: the relaxing ramp).

        Returns
        -------
        slice
            The log's rows.
        """
        start = self.k
        for u in np.asarray(commands, dtype=float).reshape(-1, self.m):  # the loop of the bench: one tick a row
            self.step(u, guarded)
        return slice(start, self.k)

    def ramp_to(self, target: np.ndarray, seconds: float, guarded: bool = True) -> slice:
        """Ramp the command linearly from the last one written to ``target`` (m,), N m, over ``seconds``.

        Parameters
        ----------
        target : numpy.ndarray, shape (m,)
            The command at the ramp's end, N m.
        seconds : float
            The ramp's duration, s (at least one period).
        guarded : bool, optional
            Check each reading against the guard (default True; False: the relaxing ramp).

        Returns
        -------
        slice
            The log's rows (:meth:`run`'s).
        """
        n = max(1, int(round(seconds / self.period)))
        w = np.arange(1, n + 1)[:, None] / n
        return self.run(self.last_command[None] * (1 - w) + np.asarray(target, dtype=float)[None] * w, guarded)

    def arm(self) -> None:
        """Guard the low side of the band from now on; :class:`GuardTripped` at once (the finger relaxed) where an
        encoder is below it."""
        self.armed = True
        r = Reading(self._t[-1], self._counts[-1], self._torque[-1], self._force[-1])
        low = np.flatnonzero(r.counts < self.low)
        if low.size:
            j = int(low[0])
            self._trip("stop", f"motor {self.hw.motor_names[j]}: encoder at {r.counts[j]:g} counts is below the "
                               f"guard band's {self.low[j]:g} before the excitation: no room for it (held below a "
                               "fold?)", r)

    def relax(self) -> None:
        """Ramp the command to the rest torque (0 N m) over :data:`RELAX_SECONDS`, unguarded."""
        self.ramp_to(np.zeros(self.m), RELAX_SECONDS, guarded=False)

    def _check(self, r: Reading) -> None:
        gap = r.t - self._t[-2]
        if not gap <= MAX_GAP * self.period:
            self._trip("period", f"the loop missed its period: a reading {gap * 1e3:.3g} ms after the previous one "
                                 f"(period {self.period * 1e3:g} ms, at most {MAX_GAP:g} periods)", r)
        if self.low is None:
            return
        out = np.flatnonzero(((r.counts < self.low) & self.armed) | (r.counts > self.high))
        if out.size:
            j = int(out[0])
            self._trip("stop", f"motor {self.hw.motor_names[j]}: encoder at {r.counts[j]:g} counts left the guard "
                               f"band [{self.low[j]:g}, {self.high[j]:g}] (a margin inside the calibrated range and the joints' "
                               f"stops) at "
                               f"t = {r.t:.4g} s", r)

    def _trip(self, reason: str, text: str, r: Reading) -> None:
        self.relax()
        raise GuardTripped(f"guard: {text}; the excitation was stopped and the finger relaxed to 0 N m", reason,
                           r.t, r.counts, self.log())

    def held_torque(self, rows: slice) -> np.ndarray:
        """(len(rows), m) N m: the torque measured over each period [t_k, t_k+1) of the log's ``rows`` (those of
        :meth:`run`), read at the next tick (the module docstring).

        Parameters
        ----------
        rows : slice
            The log's rows (those :meth:`run` returns).

        Returns
        -------
        numpy.ndarray, shape (len(rows), m)
            The torques, N m.
        """
        return np.array(self._torque[rows.start + 1: rows.stop + 1]).reshape(-1, self.m)
