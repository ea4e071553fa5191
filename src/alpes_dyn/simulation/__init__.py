"""The simulation floor: integrators (RK4, SUNDIALS), the C code generator of batched step loops,
the identification's compiled sensitivities and the on-disk build cache."""

from .integrate import *  # noqa: F401,F403  (the old module's public names)
from .integrate import __all__ as _public

__all__ = list(_public)


def __getattr__(name: str) -> object:
    """Names of the old ``alpes_dyn.simulation`` module not re-exported here: forwarded with a DeprecationWarning."""
    from .._moved import forward

    if name.startswith("__"):
        raise AttributeError(name)
    last = None
    for module in ('integrate', 'codegen'):
        try:
            return forward("simulation", module, name)
        except AttributeError as exc:
            last = exc
    raise last  # type: ignore[misc]
