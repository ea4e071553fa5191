"""Effort control: the fingertip's normal force F_z tracked from what the hand measures.

The report is titled *Control in effort of a robotic hand*: its model carries the contact torque
J^T F (eq. 2.9-2.13), F measured by the fingertip's FlexiForce sensor. This module closes the loop.
The controller sees only the hand's sensors -- the motor encoder q_m (quantised, noisy), the motor
torque tau_m (from the current, noisy) and, if it uses it, the FlexiForce reading F_z (noisy,
quantised) -- and the joints q_hat estimated by the library's EKF (:mod:`alpes_dyn.estimation.observers.observers`).

Its pieces, one module each, every name re-exported here (``alpes_dyn.control.force.X`` is what it was):

* :mod:`alpes_dyn.control.controller` -- the static balance (:func:`~alpes_dyn.control.controller.static_motor_torque`,
  :func:`~alpes_dyn.control.controller.static_contact_force`) and the controllers
  (:data:`~alpes_dyn.control.controller.CONTROLLERS`, :class:`~alpes_dyn.control.controller.ForceController`,
  :func:`~alpes_dyn.control.controller.reference_profile`);
* :mod:`alpes_dyn.control.step` -- one sample of the force loop for a user's own 1 kHz loop
  (:class:`~alpes_dyn.control.step.ForceStep`: the observer, the effects' compensation and the tuned controller,
  built once), and :mod:`alpes_dyn.control.bench_loop` -- the loop closed through a hardware interface
  (:func:`~alpes_dyn.control.bench_loop.run_on_bench`);
* :mod:`alpes_dyn.control.finger_loop` -- one finger pressing a block, MuJoCo as the plant
  (:func:`~alpes_dyn.control.finger_loop.run_control`);
* :mod:`alpes_dyn.control.hand_loop` -- the whole hand grasping a cylinder, one loop per flexion motor
  (:func:`~alpes_dyn.control.hand_loop.run_hand_control`);
* :mod:`alpes_dyn.control.figures` -- their figures (:func:`~alpes_dyn.control.figures.plot_control`,
  :func:`~alpes_dyn.control.figures.plot_hand_control`).
"""

from __future__ import annotations

from ..estimation.observers.blocks import batch_step_caller as _batch_step_caller, step_caller as _step_caller  # noqa: F401
from .bench_loop import BenchRun, run_on_bench
from .blocks import SensorlessForce
from .controller import (CONTROLLERS, DEFAULT_GAINS, REFERENCES, ForceController, _normal,  # noqa: F401
                         reference_profile, static_contact_force, static_motor_torque)
from .figures import _save_figure, plot_control, plot_hand_control  # noqa: F401
from .finger_loop import (_METRIC_WINDOW_S, _SAMPLE_ARRAYS, CONTROL_MODELS, ControlResult,  # noqa: F401
                          ControlScenario, _metrics, _plant_and_params, run_control)
from .step import ForceStep
from .step_parts import StepParts
from .hand_loop import (HAND_GAINS, HAND_LEVELS, HandControlResult, HandControlScenario, _rotation,  # noqa: F401
                        chain_frame, chain_model, cylinder_normal, hand_chains, run_hand_control)
from .grasp_calibration import force_scale_of, grasp_levels, grasp_limits
from .hand_step import HandForceStep

__all__ = [
    "CONTROLLERS", "REFERENCES", "CONTROL_MODELS", "DEFAULT_GAINS", "static_motor_torque", "static_contact_force", "ForceController",
    "ControlScenario", "ControlResult", "run_control", "plot_control", "reference_profile",
    "HAND_LEVELS", "HAND_GAINS", "hand_chains", "chain_frame", "chain_model", "cylinder_normal", "HandControlScenario",
    "HandControlResult", "run_hand_control", "plot_hand_control", "grasp_limits", "grasp_levels", "force_scale_of",
    "ForceStep", "SensorlessForce", "run_on_bench", "BenchRun", "StepParts", "HandForceStep",
]
