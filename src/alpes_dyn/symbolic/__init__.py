"""The symbolic floor: CasADi expressions of the dynamics (ADAM or ``pinocchio.casadi``), the
parametric dynamics of identification and the state space x' = f(x, u), y = h(x) (eq. 3.1-3.3)."""

from .dynamics import *  # noqa: F401,F403  (the old module's public names)
from .dynamics import __all__ as _public

__all__ = list(_public)


def __getattr__(name: str) -> object:
    """Names of the old ``alpes_dyn.symbolic`` module not re-exported here: forwarded with a DeprecationWarning."""
    from .._moved import forward

    if name.startswith("__"):
        raise AttributeError(name)
    last = None
    for module in ('dynamics',):
        try:
            return forward("symbolic", module, name)
        except AttributeError as exc:
            last = exc
    raise last  # type: ignore[misc]
