"""The force loop on a hand through the hardware interface: :func:`run_on_bench`.

The one public step loop: at every tick, ``r = hw.read()``, ``u = step.step(r.counts, r.torque, r.force, F_ref)``,
``hw.write(u)`` -- a :class:`~alpes_dyn.control.step.ForceStep` closing the loop through any
:class:`~alpes_dyn.bench.interface.HardwareInterface` (a user's driver, the MuJoCo stand-in
:class:`~alpes_dyn.bench.mujoco_hand.MujocoHand`, a :class:`~alpes_dyn.bench.interface.Loopback`). A user whose
loop must do more at each tick writes these three lines in it (the "Your bench" page of the user guide).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..bench.interface import HardwareInterface
from ..errors import InputError
from ..limits import check_duration
from .step import ForceStep

__all__ = ["BenchRun", "run_on_bench"]


@dataclass
class BenchRun:
    """What :func:`run_on_bench` logged, one row per tick (N ticks).

    Attributes
    ----------
    t : numpy.ndarray
        (N,) the readings' time stamps, s (the driver's clock).
    F_ref : numpy.ndarray
        (N,) the force reference, N.
    counts, torque : numpy.ndarray
        (N, m) the encoder counts and the motor torque read, N m.
    force : numpy.ndarray
        (N,) the fingertip sensor's reading, N (NaN without a sensor).
    command : numpy.ndarray
        (N, m) the command written, N m.
    F_fb : numpy.ndarray
        (N,) the force the controller fed back, N (the sensorless estimate, or the sensor's reading).
    q_hat, q_std : numpy.ndarray
        (N, n) the EKF's joint estimate and its standard deviation, rad (NaN for ``"pi"``).
    period : float
        The hardware's sample period, s.
    missed : int
        Ticks whose time stamp came more than 1.5 periods after the one before (a loop that missed its period).
    wall_s : float
        Wall time of the run, s.
    """

    t: np.ndarray
    F_ref: np.ndarray
    counts: np.ndarray
    torque: np.ndarray
    force: np.ndarray
    command: np.ndarray
    F_fb: np.ndarray
    q_hat: np.ndarray
    q_std: np.ndarray
    period: float
    missed: int
    wall_s: float

    def force_rmse(self, after: float = 0.0, force: np.ndarray | None = None) -> float:
        """RMS of ``force`` minus F_ref over the ticks from ``after`` s on.

        Parameters
        ----------
        after : float, optional
            s, from the first tick's time.
        force : ndarray or None, optional
            The force, N (default the sensor's reading; e.g. a stand-in's true force).

        Returns
        -------
        float
            N.
        """
        F = self.force if force is None else np.asarray(force, dtype=float)
        k = (self.t - self.t[0]) >= after
        return float(np.sqrt(np.mean((F[k] - self.F_ref[k]) ** 2)))


def _reference(reference: Any, N: int, period: float) -> Callable[[int, float], float]:
    """k, t (s from the first tick) -> F_ref (N): from a number, an array of N values (one per tick) or a callable
    of t."""
    if callable(reference):
        return lambda k, t: reference(t)
    if isinstance(reference, (bool, np.bool_)):
        raise InputError(f"reference: expected a force in N, N values or a function of t, got {reference!r}")
    try:
        F = np.asarray(reference, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"reference: expected a force in N, N values or a function of t, got {reference!r}") from None
    if F.ndim == 0:
        F = np.full(N, float(F))
    if F.shape != (N,):
        raise InputError(f"reference: expected one force per tick ({N} values for the duration), got shape {F.shape}")
    if not np.isfinite(F).all():
        raise InputError("reference: expected finite forces in N")
    values = F.tolist()
    return lambda k, t: values[k]


def _check(hw: Any, step: Any, duration: Any) -> int:
    """The number of ticks; one-line InputError naming a mismatch between the hardware and the step."""
    if not isinstance(step, ForceStep):
        raise InputError(f"step: expected a ForceStep, got {type(step).__name__}")
    if not isinstance(hw, HardwareInterface):
        raise InputError(f"hw: expected a HardwareInterface (period, motor_names, counts_per_rev, tau_max, read, "
                         f"write, close), got {type(hw).__name__}")
    if not math.isclose(float(hw.period), step.dt, rel_tol=1e-9):
        raise InputError(f"period: the hardware's period {hw.period:g} s is not the step's dt {step.dt:g} s")
    if len(hw.motor_names) != step.m:
        raise InputError(f"motor_names: the hardware has {len(hw.motor_names)} motor(s), the step's model {step.m}")
    if int(hw.counts_per_rev) != int(step.counts_per_rev):
        raise InputError(f"counts_per_rev: the hardware's encoder has {hw.counts_per_rev} counts per revolution, the "
                         f"step's parameter file {step.counts_per_rev}")
    if step.tau_max > float(hw.tau_max) * (1 + 1e-12):
        raise InputError(f"tau_max: the step commands up to {step.tau_max:g} N m, above the hardware's limit "
                         f"{hw.tau_max:g} N m (give the step a tau_max, or a file with the driver's)")
    if isinstance(duration, (bool, np.bool_)) or not isinstance(duration, (int, float, np.integer, np.floating)) \
            or not (math.isfinite(duration) and duration > 0):
        raise InputError(f"duration: expected a positive number of seconds, got {duration!r}")
    check_duration(float(duration), "duration")
    return max(1, int(round(float(duration) / float(hw.period))))


def run_on_bench(hw: HardwareInterface, step: ForceStep, reference: Any, duration: float, *, reset: bool = True,
                 close: bool = True) -> BenchRun:
    """Close the force loop through ``hw`` for ``duration`` s: every tick read, :meth:`ForceStep.step`, write.

    Parameters
    ----------
    hw : HardwareInterface
        The hand (a user's driver, the MuJoCo stand-in, a loopback); its period must be ``step.dt``.
    step : ForceStep
        The loop's step, built once before (its compile is not in the loop).
    reference : float, array_like or callable
        F_ref, N: one number, one value per tick (round(duration / period) values), or a function of the time
        since the first tick (s).
    duration : float
        s; round(duration / period) ticks.
    reset : bool
        Start the step from its first sample (:meth:`ForceStep.reset`: the finger assumed at rest); False:
        continue where it was.
    close : bool
        :meth:`~alpes_dyn.bench.interface.HardwareInterface.close` the hand at the end (the motor relaxed), also
        when the loop stops on an error.

    Returns
    -------
    BenchRun
        The readings, the commands and the estimates, one row per tick.

    Raises
    ------
    InputError
        The hardware and the step disagree (period, motors, encoder, torque limit), a bad reference or duration,
        or a reading the step refuses (one line naming it).
    """
    N = _check(hw, step, duration)
    ref = _reference(reference, N, float(hw.period))
    if reset:
        step.reset()
    m, n = step.m, step.n
    log = {k: np.empty(N) for k in ("t", "F_ref", "force", "F_fb")}
    log.update(counts=np.empty((N, m)), torque=np.empty((N, m)), command=np.empty((N, m)), q_hat=np.empty((N, n)),
               q_std=np.empty((N, n)))
    t0 = time.perf_counter()
    try:
        first = None
        for k in range(N):
            r = hw.read()
            first = r.t if first is None else first
            F_ref = ref(k, r.t - first)
            u = step.step(r.counts, r.torque, r.force, F_ref)
            hw.write(u)
            log["t"][k], log["F_ref"][k], log["force"][k], log["F_fb"][k] = r.t, F_ref, r.force, step.force_estimate
            log["counts"][k], log["torque"][k], log["command"][k] = r.counts, r.torque, u
            log["q_hat"][k], log["q_std"][k] = step.estimate[0], step.std[0]
    finally:
        if close:
            hw.close()
    gaps = np.diff(log["t"])
    return BenchRun(**log, period=float(hw.period), missed=int(np.sum(gaps > 1.5 * float(hw.period))),
                    wall_s=time.perf_counter() - t0)
