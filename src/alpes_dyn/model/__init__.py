"""The model floor: the parameter file, transmission specs, the URDF/MJCF descriptions, joint extras
(springs, friction, rotor inertia), stops and :class:`Model` (Pinocchio's numeric dynamics).

``alpes_dyn.model`` was a module before version 0.2; its names stay importable from here."""

from .robot import *  # noqa: F401,F403  (the old module's public names)
from .robot import __all__ as _public
from .contact import *  # noqa: F401,F403
from .contact import __all__ as _contact

__all__ = list(_public) + list(_contact)


from .._moved import package_getattr  # noqa: E402

__getattr__ = package_getattr("model", ('robot',))
