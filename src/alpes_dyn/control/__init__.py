"""The control floor: fingertip force controllers, their MuJoCo plants and scenes, the closed loops
of one finger and of the whole hand."""

from .force import *  # noqa: F401,F403  (the old module's public names)
from .force import __all__ as _public

__all__ = list(_public)


def __getattr__(name: str) -> object:
    """Names of the old ``alpes_dyn.control`` module not re-exported here: forwarded with a DeprecationWarning."""
    from .._moved import forward

    if name.startswith("__"):
        raise AttributeError(name)
    last = None
    for module in ('force',):
        try:
            return forward("control", module, name)
        except AttributeError as exc:
            last = exc
    raise last  # type: ignore[misc]
