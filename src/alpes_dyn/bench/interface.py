"""The hardware interface: what the library asks of a hand on the bench, and a loopback that implements it.

A user's driver implements :class:`HardwareInterface` -- a small protocol, in the style of a MuJoCo model/data
pair: a fixed sample period, a :meth:`~HardwareInterface.read` of the sensors at the current tick and a
:meth:`~HardwareInterface.write` of the motor command that holds over the period that starts there. Everything
that must run on the hand (the calibration and the guarded identification experiment of
:mod:`alpes_dyn.estimation.experiments.on_hand`, the force loop of :class:`alpes_dyn.control.step.ForceStep`) drives the hand
through it and nothing else, so what CI runs against the MuJoCo stand-in
(:class:`alpes_dyn.bench.mujoco_hand.MujocoHand`) is what runs on the hand.

Timing (as :mod:`alpes_dyn.simulation.loop`'s): tick k is at t_k = t_0 + k ``period``. ``read()`` returns the
sensors at the current tick, ``write(command)`` applies ``command`` over [t_k, t_k+1) and moves on to tick k + 1
(a simulated hand steps its physics there; a real driver sends the command and waits for the next tick of its
clock). The sequence is therefore ``r0 = read(); write(u0); r1 = read(); write(u1); ...``; ``close()`` relaxes the
hand (zero command) and releases the driver.

Units: encoder counts per motor (``counts_per_rev`` counts per motor revolution, offset unknown), the motor
torque in N m (the current times the driver's torque constant: a reading in mA is a unit mistake that
:func:`alpes_dyn.bench.checks.check_reading` names), the fingertip's normal force in N (NaN without a sensor).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from ..errors import InputError

__all__ = ["Reading", "HardwareInterface", "Loopback", "check_command"]


@dataclass(frozen=True)
class Reading:
    """The sensors at one tick.

    Attributes
    ----------
    t : float
        Time stamp, s (the driver's clock; t_0 need not be 0).
    counts : numpy.ndarray
        (m,) encoder counts, one per motor (whole numbers held as floats).
    torque : numpy.ndarray
        (m,) motor torque, N m: the measured current times the torque constant.
    force : float or numpy.ndarray
        Fingertip normal force, N (``nan`` where the hand has no force sensor); the whole hand with a sensor on
        each flexion chain's fingertip: (5,), the chains in the motors' order.
    """

    t: float
    counts: np.ndarray
    torque: np.ndarray
    force: float = math.nan


@runtime_checkable
class HardwareInterface(Protocol):
    """What a hand on the bench offers the library (see the module docstring for the timing and units).

    Attributes
    ----------
    period : float
        The sample period, s (1e-3 for the hand's 1 kHz loop).
    motor_names : tuple of str
        The motors, in the order of the counts, torques and commands.
    counts_per_rev : int
        Encoder counts per motor revolution.
    tau_max : float
        The largest motor torque the driver accepts, N m (a cable only pulls: commands lie in [0, tau_max]).
    """

    period: float
    motor_names: tuple[str, ...]
    counts_per_rev: int
    tau_max: float

    def read(self) -> Reading:
        """The sensors at the current tick."""
        ...

    def write(self, command: Sequence[float]) -> None:
        """Apply ``command`` over the current period and move to the next tick.

        Parameters
        ----------
        command : sequence of float
            (m,) motor torques, N m, in [0, tau_max].

        Raises
        ------
        InputError
            A command of the wrong shape, not finite or out of range (nothing is clipped silently).
        """
        ...

    def close(self) -> None:
        """Relax the hand (zero command) and release the driver."""
        ...


def check_command(command: Sequence[float], m: int, tau_max: float,
                  both_ways: Sequence[bool] | None = None) -> np.ndarray:
    """``command`` as an (m,) array of motor torques (N m) in [0, ``tau_max``] (a cable only pulls), those of the
    motors marked ``both_ways`` in [-``tau_max``, ``tau_max``] (a gear: the thumb's ab/adduction).

    Parameters
    ----------
    command : sequence of float
        The motor torques, N m.
    m : int
        The motors.
    tau_max : float
        The largest torque a motor gives, N m.
    both_ways : sequence of bool or None, optional
        (m,) the motors that push both ways (default none).

    Returns
    -------
    ndarray
        (m,) N m.

    Raises
    ------
    InputError
        Naming ``command``: wrong shape, NaN or inf, negative (a cable only pulls), above ``tau_max``; naming
        ``both_ways``: not one flag per motor.
    """
    try:
        u = np.atleast_1d(np.asarray(command, dtype=float))
    except (TypeError, ValueError):
        raise InputError(f"command: expected {m} motor torque(s) in N m, got {command!r:.80}") from None
    if u.shape != (m,):
        raise InputError(f"command: expected {m} motor torque(s) in N m, got shape {u.shape}")
    if not np.isfinite(u).all():
        raise InputError(f"command: expected finite motor torques in N m, got {u.tolist()!r}")
    two = np.zeros(m, dtype=bool) if both_ways is None else np.asarray(both_ways, dtype=bool)
    if two.shape != (m,):
        raise InputError(f"both_ways: expected one flag per motor ({m}), got {both_ways!r:.80}")
    if ((u < 0) & ~two).any() or (np.abs(u) > tau_max * (1 + 1e-12)).any():
        raise InputError(f"command: motor torques must lie in [0, {tau_max:g}] N m (a cable only pulls; "
                         f"tau_max){'' if not two.any() else f', [-{tau_max:g}, {tau_max:g}] N m for a motor that pushes both ways'}, got {u.tolist()!r}")
    return u


@dataclass
class Loopback:
    """A :class:`HardwareInterface` for unit tests and dry runs: no physics, each reading computed from the
    commands written so far by ``respond`` (default: the counts stay at 0, the torque reads the last command,
    no force sensor).

    ``respond(k, commands)`` gets the tick k and the (k, m) commands written before it and returns
    ``(counts, torque, force)``. :attr:`commands` holds every command written, (k, m).
    """

    motor_names: tuple[str, ...] = ("finger",)
    period: float = 1e-3
    counts_per_rev: int = 4096
    tau_max: float = 0.05
    respond: object = None
    t0: float = 0.0
    _commands: list = field(default_factory=list, repr=False)
    closed: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.period, (int, float)) and math.isfinite(self.period) and self.period > 0):
            raise InputError(f"period: expected a positive sample period in s, got {self.period!r}")
        self.motor_names = tuple(self.motor_names)

    @property
    def commands(self) -> np.ndarray:
        """(k, m) every command written, N m."""
        return np.array(self._commands, dtype=float).reshape(-1, len(self.motor_names))

    def read(self) -> Reading:
        k = len(self._commands)
        m = len(self.motor_names)
        if self.respond is None:
            last = self._commands[-1] if self._commands else np.zeros(m)
            counts, torque, force = np.zeros(m), np.array(last, dtype=float), math.nan
        else:
            counts, torque, force = self.respond(k, self.commands)
        return Reading(self.t0 + k * self.period, np.asarray(counts, dtype=float).reshape(m),
                       np.asarray(torque, dtype=float).reshape(m), float(force))

    def write(self, command: Sequence[float]) -> None:
        """Record ``command`` (checked: :func:`check_command`) and move to the next tick.

        Parameters
        ----------
        command : sequence of float
            (m,) motor torques, N m, in [0, tau_max].
        """
        if self.closed:
            raise InputError("write: the loopback is closed")
        self._commands.append(check_command(command, len(self.motor_names), self.tau_max))

    def close(self) -> None:
        self.closed = True
