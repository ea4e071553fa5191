"""The control floor: fingertip force controllers, their MuJoCo plants and scenes, the closed loops
of one finger and of the whole hand."""

from .force import *  # noqa: F401,F403  (the old module's public names)
from .force import __all__ as _public

__all__ = list(_public)


from .._moved import package_getattr  # noqa: E402

__getattr__ = package_getattr("control", ('force',))
