"""alpes_dyn: dynamics, observability and state estimation of the Alpes Instruments robotic hand.

Start with :meth:`alpes_dyn.Model.alpes`::

    import alpes_dyn as ad
    finger = ad.Model.alpes("finger3")          # torsional springs, no friction, no rotor inertia
    A = finger.inertia_matrix([0.1, 0.2, 0.3])   # (3, 3) kg m^2
"""

from .description import MODELS, example_robot_urdf, layout, urdf_string, write_urdfs
from .errors import AlpesDynError, InputError, ModelError, RecordingError
from .extras import SPRING_MODELS, JointExtras
from .model import Model
from . import observability
from .observability import ObservabilityReport, check_observability
from .params import HandParams, load_params
from .statespace import StateSpace
from .transmission import Transmission

__version__ = "0.1.0"

__all__ = [
    "AlpesDynError", "InputError", "ModelError", "RecordingError", "Model", "JointExtras", "Transmission", "HandParams",
    "StateSpace", "check_observability", "observability", "ObservabilityReport", "load_params", "urdf_string", "layout",
    "write_urdfs", "example_robot_urdf", "MODELS", "SPRING_MODELS",
]
