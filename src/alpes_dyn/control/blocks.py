"""Control blocks of :func:`alpes_dyn.simulation.loop.run_loop`: the force loop, the sensorless force estimate,
the contact force as the observer's known input, a PD on an encoder.

* :class:`ForceLoop`: a :class:`~alpes_dyn.control.controller.ForceController` -- reference, force fed back,
  estimated joints (and the contact normal) in, the motor torque command out;
* :class:`SensorlessForce`: the contact force from the estimated joints and the measured motor torque
  (:func:`~alpes_dyn.control.controller.static_contact_force`, the static balance), low-passed;
* :func:`force_input`: a :class:`~alpes_dyn.simulation.loop.Function` writing -F n (3,), the contact force the
  EKF takes as a known input (the fingertip presses along the object's normal n);
* :class:`EncoderPD`: a PD on an encoder reading (the thumb's ab/adduction held at an angle).
"""

from __future__ import annotations

import math

from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ..model.robot import Model
from ..simulation.loop import Block, Function
from .controller import ForceController, static_contact_force

__all__ = ["ForceLoop", "SensorlessForce", "force_input", "EncoderPD"]


def _fraction(x: Any, name: str) -> float:
    if isinstance(x, bool) or not isinstance(x, (int, float, np.integer, np.floating)) or not 0.0 < x <= 1.0:
        raise InputError(f"{name}: expected a number in (0, 1], got {x!r}")
    return float(x)


class ForceLoop(Block):
    """A force controller as a block: ``command`` (N m) = ``controller.update(reference, force, q_hat[, normal])``.

    Parameters
    ----------
    controller : ForceController
        The :class:`~alpes_dyn.control.controller.ForceController` (its state advances each sample).
    reference, force : str, optional
        The signals of F_ref and of the force fed back, N (default ``"F_ref"``, ``"F_fb"``).
    estimate : str or None, optional
        The observer's estimate's signal (its first ``n`` entries are q_hat, rad), or None (default: the ``pi``
        baseline, no q_hat).
    normal : str or None, optional
        A signal of the contact normal (3,), or None (default: the controller's own).
    command : str, optional
        The torque command's signal, N m (default ``"tau"``).
    name : str, optional
        The block's name (default ``"controller"``).

    Raises
    ------
    InputError
        ``controller`` is not a ForceController.
    """

    def __init__(self, controller: ForceController, *, reference: str = "F_ref", force: str = "F_fb",
                 estimate: str | None = None, normal: str | None = None, command: str = "tau",
                 name: str = "controller") -> None:
        if not isinstance(controller, ForceController):
            raise InputError(f"controller: expected a ForceController, got {type(controller).__name__}")
        self.ctl, self.name, self.n = controller, name, controller.model.n
        self.reference, self.force, self.estimate, self.normal = reference, force, estimate, normal
        self.inputs = tuple(s for s in (reference, force, estimate, normal) if s is not None)
        self.outputs = (command,)

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        q_hat = None if self.estimate is None else u[self.estimate][: self.n]
        if self.normal is None:
            tau = self.ctl.update(float(u[self.reference]), u[self.force], q_hat)
        else:
            tau = self.ctl.update(float(u[self.reference]), u[self.force], q_hat, normal=u[self.normal])
        return {self.outputs[0]: tau}


class SensorlessForce(Block):
    """The contact force without a force sensor: F_est = the static balance of the measured motor torque at the
    estimated joints (:func:`~alpes_dyn.control.controller.static_contact_force`), low-passed:
    ``F[k] = F[k-1] + alpha (max(F_est, 0) - F[k-1])``, N (``F[-1] = 0``).

    Parameters
    ----------
    model : Model
        The controller's model.
    alpha : float
        The low-pass's weight, dt / (tau_f + dt).
    estimate : str, optional
        The observer's estimate's signal (q_hat its first n entries).
    torque : str, optional
        The motor torque's reading's signal (the previous period's, N m: one motor's, a float, or every motor's,
        (m,)).
    normal : str or sequence of float, optional
        The contact normal (3,): a signal name, or a constant vector.
    force : str, optional
        The signal written, N.
    name : str, optional
        The block's name.
    tip : str or None, optional
        The contact frame (None: the model's default tip).
    scale : float, optional
        F_est divided by it (a calibration against the fingertip sensor, > 0; 1: none).
    """

    def __init__(self, model: Model, alpha: float, *, estimate: str = "z", torque: str = "tau_meas",
                 normal: str | Sequence[float] = (0.0, 0.0, 1.0), force: str = "F_fb", name: str = "sensorless",
                 tip: str | None = None, scale: float = 1.0) -> None:
        if not isinstance(model, Model):
            raise InputError(f"model: expected an alpes_dyn.Model, got {type(model).__name__}")
        if isinstance(scale, bool) or not isinstance(scale, (int, float)) or not (math.isfinite(scale) and scale > 0):
            raise InputError(f"scale: expected a positive number, got {scale!r}")
        self.scale = float(scale)
        self.model, self.alpha, self.name = model, _fraction(alpha, "alpha"), name
        self.estimate, self.torque, self.tip = estimate, torque, tip
        self._motors = len(model.transmission.motor_names) if model.transmission is not None else 1
        self._normal_signal = normal if isinstance(normal, str) else None
        self._normal = None if isinstance(normal, str) else np.asarray(normal, dtype=float)
        self.inputs = (estimate, torque) + ((normal,) if isinstance(normal, str) else ())
        self.outputs = (force,)

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.F = 0.0

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        normal = self._normal if self._normal_signal is None else u[self._normal_signal]
        return {self.outputs[0]: self.sample(u[self.estimate][: self.model.n], u[self.torque], normal)}

    def sample(self, q_hat: np.ndarray, tau: Any, normal: Any = None) -> float:
        """One sample of the filtered estimate, N: from q_hat (n,) rad, the motor torque (a number, or (m,) N m)
        and the normal; the filter's state advances (:meth:`start` clears it).

        Parameters
        ----------
        q_hat : ndarray
            (n,) the estimated joint angles, rad.
        tau : float or ndarray
            The motor torque (a number, or (m,) N m).
        normal : array_like or None, optional
            (3,) the contact normal (None: the constant one given).

        Returns
        -------
        float
            N.
        """
        tau = np.array([tau]).reshape(-1)
        if tau.shape[0] != self._motors:  # a scalar before the first period's reading: every motor at it
            tau = np.broadcast_to(tau, (self._motors,))
        F_est = static_contact_force(self.model, q_hat, tau, self._normal if normal is None else normal,
                                     self.tip) / self.scale
        self.F += self.alpha * (max(F_est, 0.0) - self.F)
        return self.F


def force_input(force: str, output: str, normal: str | Sequence[float], name: str = "force_input") -> Function:
    """A block writing ``output`` = -F n (3,), N: the contact force along the normal, the fingertip pressing on
    the object: the EKF's force input.

    Parameters
    ----------
    force : str
        The signal of the contact force F, N.
    output : str
        The signal written, -F n, shape (3,), N.
    normal : str or sequence of float
        The contact normal: a signal's name, or a constant (3,) vector.
    name : str, optional
        The block's name (default ``"force_input"``).

    Returns
    -------
    Function
        The block.

    Raises
    ------
    InputError
        A constant ``normal`` is not 3 numbers.
    """
    if isinstance(normal, str):
        return Function(lambda **u: -u[force] * u[normal], (force, normal), output, name=name)
    n = np.asarray(normal, dtype=float)
    if n.shape != (3,):
        raise InputError(f"normal: expected 3 numbers, got shape {n.shape}")
    return Function(lambda **u: -u[force] * n, (force,), output, name=name)


class EncoderPD(Block):
    """A PD on an encoder reading: u = kp (target - y / ratio) - kd v, clipped to [-u_max, u_max] N m, v the
    reading's difference quotient low-passed with weight ``alpha`` (v_0 = 0; the first sample has no difference).

    Parameters
    ----------
    target : float
        The joint angle aimed at, rad.
    kp : float
        The proportional gain, N m/rad.
    kd : float
        The derivative gain, N m s/rad.
    alpha : float
        The velocity low-pass's weight, dt / (tau_f + dt), in (0, 1].
    ratio : float, optional
        Motor angle per joint angle (default 1).
    u_max : float, optional
        The command's bound, N m (default inf: none).
    reading : str, optional
        The signal read, the encoder's angle y, rad of motor (default ``"y"``).
    command : str, optional
        The signal written, the command u, N m (default ``"u"``).
    angle : str or None, optional
        A signal of the joint angle y / ratio (rad), written too (default None: not written).
    name : str, optional
        The block's name (default ``"pd"``).

    Raises
    ------
    InputError
        ``alpha`` is not in (0, 1].
    """

    def __init__(self, target: float, kp: float, kd: float, alpha: float, *, ratio: float = 1.0,
                 u_max: float = np.inf, reading: str = "y", command: str = "u", angle: str | None = None,
                 name: str = "pd") -> None:
        self.target, self.kp, self.kd, self.ratio, self.u_max = target, kp, kd, ratio, u_max
        self.alpha, self.name = _fraction(alpha, "alpha"), name
        self.inputs = (reading,)
        self.outputs = (command,) + ((angle,) if angle else ())

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.dt, self._prev, self._v = dt, None, 0.0

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        y = u[self.inputs[0]] / self.ratio
        if self._prev is not None:
            self._v += self.alpha * ((y - self._prev) / self.dt - self._v)
        self._prev = y
        c = self.kp * (self.target - y) - self.kd * self._v
        out = {self.outputs[0]: min(max(c, -self.u_max), self.u_max)}
        if len(self.outputs) > 1:
            out[self.outputs[1]] = y
        return out
