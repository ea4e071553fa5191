"""What one force step is made of: :class:`StepParts`, the settings of a built
:class:`~alpes_dyn.control.step.ForceStep` (:meth:`ForceStep.parts <alpes_dyn.control.step.ForceStep.parts>`).

A code generator (:mod:`alpes_dyn.control.cstep`), a user's own port of the step, or a whole hand's step
(:mod:`alpes_dyn.control.hand_step`) reads these and nothing private: the models, the EKF and its prior, the
compensation's constants, the sensorless estimate's filter and a fresh controller with the step's settings. The
order of the operations that use them is :mod:`alpes_dyn.control.step`'s module docstring.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..model.robot import Model
from .controller import ForceController

__all__ = ["StepParts"]


@dataclass(frozen=True)
class StepParts:
    """The settings of one force step (not its state: the controller is a fresh one, the EKF's prior is the rest).

    Attributes
    ----------
    model : Model
        The controller's model (n joints, m motors).
    observer_friction : bool
        The EKF's model carries the parameter file's friction (eq. 2.6-2.7).
    kind : str
        The controller: ``"sensor"``, ``"sensorless"`` or ``"pi"``.
    dt : float
        The period, s.
    motor : int
        The index of the pulling motor (the others are commanded 0).
    motor_names : tuple of str
        The m motors.
    tau_max : float
        The motor limit, N m.
    rad_per_count : float
        rad of the motor per encoder count (2 pi / counts per revolution).
    encoder_offset : float
        rad of the motor: the encoder's zero taken off the reading before the EKF (with ``unstretch``).
    tendon_compliance : numpy.ndarray
        (m,) rad/(N m): C, the tendon's stretch C tau_m taken off the reading (zeros for a rigid tendon).
    unstretch : bool
        The EKF measures the encoder less ``encoder_offset`` and C tau_m,k-1 (the compensation's
        ``observer_compliance``); otherwise the reading in rad as it is.
    command_input : bool
        The EKF's motor torque is the command held over the last period (else the torque reading).
    normal : numpy.ndarray
        (3,) the contact normal the step was built with (base frame, unit length).
    controller : ForceController
        A fresh controller with the step's settings (gains, notch, limit).
    ekf : object or None
        The EKF (:func:`~alpes_dyn.control.step.force_ekf`; its ``filter_step_p``, its model, its C export by
        :func:`~alpes_dyn.estimation.cexport.cexport.c_sources`); None for ``"pi"``.
    z0 : numpy.ndarray
        (nz,) the EKF's prior [q; qd] (rad, rad/s; nz = 2n) in the filter's coordinates, with the LuGre law's
        bristles (rad; nz = 3n) after them; NaN (2n) for ``"pi"``.
    P0 : numpy.ndarray
        (nz * nz,) its covariance, column-major; NaN for ``"pi"``.
    sensorless_alpha : float or None
        The sensorless estimate's low-pass weight dt / (tau_f + dt) (None: no sensorless estimate).
    force_scale : float
        The compensation's ``force_scale`` (the force sensor's N into the parameter file's torque units): the
        sensorless estimate's static force is divided by it, the EKF's force input (the sensor's reading, the
        sensorless estimate) multiplied by it.
    """

    model: Model
    observer_friction: bool
    kind: str
    dt: float
    motor: int
    motor_names: tuple
    tau_max: float
    rad_per_count: float
    encoder_offset: float
    tendon_compliance: np.ndarray
    unstretch: bool
    command_input: bool
    normal: np.ndarray
    controller: ForceController
    ekf: Any
    z0: np.ndarray
    P0: np.ndarray
    sensorless_alpha: float | None
    force_scale: float

    @property
    def sensorless_scale(self) -> float:
        """Deprecated name of :attr:`force_scale` (kept for one release; a :class:`DeprecationWarning` naming the
        new one)."""
        warnings.warn("StepParts.sensorless_scale is now StepParts.force_scale; the old name goes in the next "
                      "release", DeprecationWarning, stacklevel=2)
        return self.force_scale

    @property
    def n(self) -> int:
        """The number of joints."""
        return int(self.model.n)

    @property
    def m(self) -> int:
        """The number of motors."""
        return len(self.motor_names)
