"""alpes_dyn: dynamics, observability and state estimation of the Alpes Instruments robotic hand.

Start with :meth:`alpes_dyn.Model.alpes`::

    import alpes_dyn as ad
    finger = ad.Model.alpes("finger3")          # torsional springs, no friction, no rotor inertia
    A = finger.inertia_matrix([0.1, 0.2, 0.3])   # (3, 3) kg m^2
"""

from .model.description import MODELS, example_robot_urdf, layout, urdf_string, write_urdfs
from .errors import AlpesDynError, InputError, ModelError, RecordingError
from .model.extras import SPRING_MODELS, JointExtras
from .model.robot import Model
from .analysis import observability
from .analysis.observability import ObservabilityReport, check_observability
from .model.params import HandParams, load_params
from .symbolic.statespace import StateSpace
from .model.transmission import Transmission

from ._version import __version__

__all__ = [
    "AlpesDynError", "InputError", "ModelError", "RecordingError", "Model", "JointExtras", "Transmission", "HandParams",
    "StateSpace", "check_observability", "observability", "ObservabilityReport", "load_params", "urdf_string", "layout",
    "write_urdfs", "example_robot_urdf", "MODELS", "SPRING_MODELS",
]
