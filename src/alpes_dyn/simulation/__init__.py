"""The simulation floor: integrators (RK4, SUNDIALS), the C code generator of batched step loops,
the identification's compiled sensitivities and the on-disk build cache."""

from .integrate import *  # noqa: F401,F403  (the old module's public names)
from .integrate import __all__ as _public

__all__ = list(_public)


from .._moved import package_getattr  # noqa: E402

__getattr__ = package_getattr("simulation", ('integrate', 'codegen'))
