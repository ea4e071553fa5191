"""The model floor: the parameter file, transmission specs, the URDF/MJCF descriptions, joint extras
(springs, friction, rotor inertia), stops and :class:`Model` (Pinocchio's numeric dynamics).

``alpes_dyn.model`` was a module before version 0.2; its names stay importable from here."""

from .robot import *  # noqa: F401,F403  (the old module's public names)
from .robot import __all__ as _public

__all__ = list(_public)


def __getattr__(name: str) -> object:
    """Names of the old ``alpes_dyn.model`` module not re-exported here: forwarded with a DeprecationWarning."""
    from .._moved import forward

    if name.startswith("__"):
        raise AttributeError(name)
    last = None
    for module in ('robot',):
        try:
            return forward("model", module, name)
        except AttributeError as exc:
            last = exc
    raise last  # type: ignore[misc]
