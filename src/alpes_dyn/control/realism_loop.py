"""Force control on a plant we did not write: the MuJoCo finger (or hand) with the effects of a real hand.

:func:`~alpes_dyn.control.finger_loop.run_control` and :func:`~alpes_dyn.control.hand_loop.run_hand_control` take
``effects`` (a :class:`~alpes_dyn.bench.effects.PlantEffects`): the plant is then the MJCF of
:func:`~alpes_dyn.model.mjcf.mjcf_string` with the MJCF side of the effects (stick-slip friction, the series-elastic
pull-only tendon with its rotor and the cable's slack, the rotor on the rigid tendon, the palm's tilt:
:func:`~alpes_dyn.bench.effects.effects_mjcf_kwargs`, :func:`~alpes_dyn.bench.effects.plant_gravity`,
:func:`~alpes_dyn.bench.mujoco_plant.rotor_rest`, importable from here as before) and the sensor side of them as
this module's blocks:

* the torque constant e off: the motor gives tau_cmd / (1 + e) for the command tau_cmd (the driver turns the
  command into a current with a constant (1 + e) times the true one), and the current sensor reads (1 + e) times
  what the motor gives, i.e. the command (plus noise): :func:`torque_constant_blocks`;
* the encoder's zero ``encoder_offset`` counts off (the :class:`~alpes_dyn.simulation.sensors.Encoder`'s offset);
* the torque read ``torque_delay`` whole samples late (:class:`SampleLag`, the realism study's definition: the
  reading at t_k is what the motor gave over the period ending d samples earlier); the command reaches the motor at
  once (a current loop much faster than 1 kHz).

The plant starts at rest, motor off: the finger hanging on its springs in the plant's (tilted) gravity, each
series-elastic rotor where the cable is just slack (the approach takes the slack up).

The controllers' side of the effects (:class:`Compensation`, on by default with ``effects``;
:data:`NO_COMPENSATION` is the rigid design; without the compensation, on a plant with every effect, the rigid
design's force loop rings at the cable's mode; the loops with it: ``benchmarks/results/force_realism.json``):

* ``notch``: the command through a notch at the cable's mode as identified, f_c = sqrt(1 / (C J_m)) / (2 pi) (the
  identified tendon compliance C on the file's rotor inertia J_m: about 200 Hz): the rotor on its elastic cable is a
  lightly damped mode that the force loop's proportional path (its set-point step and its feedback through a
  one-sample delay) excites;
* ``observer_compliance``: the EKF on the encoder with the identified tendon's stretch taken off, y - C tau_m,k-1
  (as ``alpes-dyn estimate --data`` does; the joints' estimate markedly closer), and
  ``encoder_offset`` (rad of motor; default the controller's parameter file's, as ``identify`` wrote it);
* ``command_input``: the EKF and the sensorless estimate take the command held over the last period (in the current
  sensor's units: what the reading shows, without its delay and its noise) as the motor torque, instead of the
  reading that lags by the torque delay -- a Smith-predictor-like use of the known actuator;
* ``tilt``: the controller's and the observer's gravity turned further by a palm's orientation (``tilt_x``,
  ``tilt_y``); the tilt ``identify`` fitted is already in its file's gravity (``environment.gravity``), which the
  controller's model takes.
* ``force_scale``: the sensorless estimate divided by its ratio to the fingertip sensor's reading, measured once
  (:func:`~alpes_dyn.control.grasp_calibration.force_scale_of`): the torque constant's error scales every
  identified torque parameter, and the estimate with them, by 1 + e (the encoder cannot see it) -- a floor of
  e / (1 + e) on the uncalibrated sensorless loop, which one press against the sensor removes.
  The EKF's force input is multiplied by it (the sensor's reading, or the estimate, in the file's torque units):
  fed the sensor's newtons against the file's torques 1 + e too large, the observer's joints took the missing
  e J^T F on their springs (the thumb's first joint visibly off in contact).

The identified torque delay (the file's ``transmission.torque_delay``) needs no block of its own: with
``command_input`` the observer and the sensorless estimate take the command, which the reading's lag does not
touch.

Tried and left out, each worse on the same plant: a smoothed Coulomb feedforward of the identified F_s, F_v on
the observer's velocities (more overshoot: the stick-slip the loop meets is the passive joints' redistribution as
the fingertip rolls on the block, which the tendon's single torque does not drive), a dither (more overshoot and
oscillation), a derivative of the force (unstable through the cable's mode), an integrator frozen while the joints
move (more overshoot, a large steady-state error). The PI's anti-windup is the controller's
conditional integration at the torque's limits.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Mapping

import numpy as np

# effects_mjcf_kwargs, plant_gravity, rotor_rest: the bench's, importable from here as before (not in __all__)
from ..bench.effects import PlantEffects, effects_mjcf_kwargs, plant_gravity  # noqa: F401
from ..bench.mujoco_plant import rotor_rest  # noqa: F401
from ..errors import InputError
from ..model.robot import Model
from ..simulation.loop import Block, Function

__all__ = ["Compensation", "SampleLag", "torque_constant_blocks", "NO_COMPENSATION"]


@dataclass(frozen=True)
class Compensation:
    """What the controllers do about the plant's effects (module docstring); each a switch.

    observer_compliance: the EKF takes the identified tendon stretch C tau_m,k-1 and ``encoder_offset`` (rad of
        motor) off the encoder's reading. command_input: the EKF and the sensorless estimate take the command as the
        motor torque (not the reading, late by the torque delay). notch: the command through a notch at the cable's
        mode identified, f_c = sqrt(1 / (C J_m)) / (2 pi) (the file's compliance C and rotor J_m; none with a rigid
        file), damping ratio ``notch_zeta``. tilt: (tilt_x, tilt_y) rad, a palm's orientation
        (:func:`~alpes_dyn.symbolic.parametric.tilted_gravity`): the controller's and the observer's gravity turned
        by it, on top of the file's (which holds the tilt ``identify`` fitted). encoder_offset: rad of the motor,
        or None (the default): the controller's file's (:meth:`~alpes_dyn.model.params.HandParams.encoder_offset_of`,
        as ``identify`` wrote it; 0 without). force_scale: the sensorless force estimate divided by it -- the
        ratio of that estimate to the fingertip sensor's reading, measured once on the plant
        (:func:`~alpes_dyn.control.grasp_calibration.force_scale_of`: the torque constant's error, which the encoder
        cannot see, scales the estimate), and the EKF's force input multiplied by it (the force in the file's
        torque units); a number, or for the hand a dict chain -> number (1 where a chain is missing); 1:
        uncalibrated.
    """

    observer_compliance: bool = True
    command_input: bool = True
    notch: bool = True
    notch_zeta: float = 0.7
    tilt: tuple[float, float] = (0.0, 0.0)
    encoder_offset: float | None = None
    force_scale: Any = field(default=1.0, compare=False)

    def check(self) -> "Compensation":
        for name in ("observer_compliance", "command_input", "notch"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"{name}: expected True or False, got {getattr(self, name)!r}")
        ranges = [("notch_zeta", self.notch_zeta, 0.05, 2.0)]
        if self.encoder_offset is not None:  # (None: the controller's file's)
            ranges.append(("encoder_offset", self.encoder_offset, -1.0, 1.0))
        for name, v, lo, hi in ranges:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and lo <= v <= hi):
                raise InputError(f"{name}: expected a number in [{lo:g}, {hi:g}], got {v!r}")
        scales = self.force_scale.values() if isinstance(self.force_scale, Mapping) else (self.force_scale,)
        for v in scales:
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and 0.5 <= v <= 2.0):
                raise InputError(f"force_scale: expected a number in [0.5, 2] (or a dict chain -> number), got {v!r}")
        t = np.asarray(self.tilt, dtype=float) if np.ndim(self.tilt) == 1 else np.array([np.nan])
        if t.shape != (2,) or not np.isfinite(t).all() or (np.abs(t) > 0.5).any():
            raise InputError(f"tilt: expected (tilt_x, tilt_y), two angles within 0.5 rad, got {self.tilt!r}")
        return self

    def scale_of(self, chain: str | None = None) -> float:
        """:attr:`force_scale` of a chain (None: the finger's, which takes one number).

        Parameters
        ----------
        chain : str or None, optional
            The hand's chain (default None: the finger's).

        Returns
        -------
        float
            The scale (1 for a chain the dict does not name).

        Raises
        ------
        InputError
            ``chain`` is None while :attr:`force_scale` is a dict.
        """
        if isinstance(self.force_scale, Mapping):
            if chain is None:
                raise InputError("force_scale: a finger's loop takes one number, got a dict")
            return float(self.force_scale.get(chain, 1.0))
        return float(self.force_scale)

    def cable_mode_hz(self, model: Model, params: Any) -> float | None:
        """f_c (Hz) of the notch: the identified cable (C of ``model``'s first motor) on the file's rotor J_m; None
        without the notch or with a rigid tendon.

        Parameters
        ----------
        model : Model
            The model (its transmission's tendon compliance C, rad/(N m)).
        params : HandParams
            The parameter file's values (its rotor inertia J_m, kg m^2).

        Returns
        -------
        float or None
            The cable mode's frequency, Hz.
        """
        C = float(model.transmission.tendon_compliance[0])
        if not self.notch or C <= 0:
            return None
        return math.sqrt(1.0 / (C * float(params.J_m))) / (2 * math.pi)

    def notch_settings(self, model: Model, params: Any, dt: float) -> dict[str, float]:
        """The :class:`~alpes_dyn.control.controller.ForceController` settings of the notch (``notch_hz``,
        ``notch_zeta``) at :meth:`cable_mode_hz` when it lies below the Nyquist frequency of the period ``dt`` (s)
        (0.45 / dt); none otherwise, or without ``params`` (a URDF robot: no rotor in a file).

        Parameters
        ----------
        model : Model
            The model.
        params : HandParams or None
            The parameter file's values (None: a URDF robot, no notch).
        dt : float
            The control period, s.

        Returns
        -------
        dict of str to float
            ``{"notch_hz": ..., "notch_zeta": ...}`` or empty.
        """
        f_c = None if params is None else self.cable_mode_hz(model, params)
        if f_c is None or not f_c < 0.45 / dt:
            return {}
        return {"notch_hz": f_c, "notch_zeta": self.notch_zeta}

    def unstretched(self, transmission: Any, y: Any, tau: Any, offset: float = 0.0) -> Any:
        """The encoder's reading y (rad of motor) without the encoder's zero ``offset`` (rad, :meth:`offset_of`)
        and without the tendon's stretch C tau (:meth:`~alpes_dyn.model.transmission.Transmission.unstretched`; tau
        the torque held over the period before the reading, N m): y - offset - C tau, what the rigid model's encoder
        would read.

        Parameters
        ----------
        transmission : Transmission
            The model's transmission.
        y : float or numpy.ndarray
            The encoder's reading, rad of motor (one per motor).
        tau : float or numpy.ndarray
            The motor torque held over the period before the reading, N m.
        offset : float, optional
            The encoder's zero, rad of motor (default 0).

        Returns
        -------
        float or numpy.ndarray
            y - offset - C tau, rad of motor.
        """
        return transmission.unstretched(y - offset, tau)

    def offset_of(self, params: Any, motor: str, chain: str | None = None) -> float:
        """The encoder zero (rad of the motor) taken off the reading: :attr:`encoder_offset`, or where None the
        controller's file's for ``motor`` (``params`` a HandParams, or None: 0).

        Parameters
        ----------
        params : HandParams or None
            The controller's parameter file's values (None: 0).
        motor : str
            The motor's name.
        chain : str or None, optional
            The hand's chain (default None: the finger's).

        Returns
        -------
        float
            The encoder zero, rad of motor.
        """
        if self.encoder_offset is not None:
            return float(self.encoder_offset)
        return 0.0 if params is None else float(params.encoder_offset_of(motor, chain))

    def turned_gravity(self, gravity: Any) -> np.ndarray:
        """``gravity`` (3,), m/s^2, turned by the identified palm orientation (:attr:`tilt`).

        Parameters
        ----------
        gravity : array_like, shape (3,)
            The gravity vector, m/s^2.

        Returns
        -------
        numpy.ndarray, shape (3,)
            The turned vector, m/s^2.
        """
        from ..symbolic.parametric import tilted_gravity as turn

        g = np.asarray(gravity, dtype=float)
        return g if not any(self.tilt) else np.asarray(turn(g, float(self.tilt[0]), float(self.tilt[1])), dtype=float)

    def turned(self, model: Model) -> Model:
        """``model`` in the identified palm orientation (:attr:`tilt`), or as it is when level.

        Parameters
        ----------
        model : Model
            The model.

        Returns
        -------
        Model
            A copy with the turned gravity (``model`` itself when level).
        """
        if not any(self.tilt):
            return model
        from ..symbolic.parametric import tilted_gravity as turn

        return model.copy(gravity=turn(model.gravity, float(self.tilt[0]), float(self.tilt[1])))


NO_COMPENSATION = Compensation(observer_compliance=False, command_input=False, notch=False)
"""The rigid design: today's controllers and EKF, blind to the effects."""


class SampleLag(Block):
    """A period signal seen ``samples`` whole periods late: ``output`` over period k is ``signal`` of period
    k - samples (the first ``samples`` periods repeat ``initial``). ``samples`` = 0 passes the signal through.

    Parameters
    ----------
    signal : str
        The period signal read.
    output : str
        The period signal written.
    samples : int
        The lag, whole periods, >= 0.
    initial : float or array_like, optional
        The value output over the first ``samples`` periods (default 0).
    name : str, optional
        The block's name (default ``"lag"``).

    Raises
    ------
    InputError
        ``samples`` is not a whole number >= 0.
    """

    def __init__(self, signal: str, output: str, samples: int, initial: Any = 0.0, name: str = "lag") -> None:
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 0:
            raise InputError(f"samples: expected a whole number >= 0, got {samples!r}")
        self.name, self.samples, self._x0 = name, int(samples), initial
        self.update_inputs, self.period_outputs = (signal,), (output,)
        self.initial = {output: initial}

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self._buf: deque = deque([self._x0] * self.samples)

    def update(self, k: int, u: Mapping[str, Any]) -> dict[str, Any]:
        x = u[self.update_inputs[0]]
        if self.samples == 0:
            return {self.period_outputs[0]: x}
        self._buf.append(x)
        return {self.period_outputs[0]: self._buf.popleft()}


def torque_constant_blocks(effects: PlantEffects | None, command: str, applied: str, name: str = "motor") -> list:
    """The motor as the driver drives it: ``applied`` = ``command`` / (1 + e), N m (e the torque constant's error;
    no block without one: the command is applied as it is, under the name ``applied``).

    Parameters
    ----------
    effects : PlantEffects or None
        The plant's effects (their ``torque_constant_error`` e; None: e = 0).
    command : str
        The signal of the torque commanded, N m.
    applied : str
        The signal of the torque applied, N m.
    name : str, optional
        The block's name (default ``"motor"``).

    Returns
    -------
    list of Block
        The block computing ``applied``.
    """
    e = 0.0 if effects is None else float(effects.torque_constant_error)
    gain = 1.0 / (1.0 + e)
    return [Function(lambda **u: gain * u[command], (command,), applied, name=name)]
