"""The symbolic floor: CasADi expressions of the dynamics (ADAM or ``pinocchio.casadi``), the
parametric dynamics of identification and the state space x' = f(x, u), y = h(x) (eq. 3.1-3.3)."""

from .dynamics import *  # noqa: F401,F403  (the old module's public names)
from .dynamics import __all__ as _public

__all__ = list(_public)


from .._moved import package_getattr  # noqa: E402

__getattr__ = package_getattr("symbolic", ('dynamics',))
