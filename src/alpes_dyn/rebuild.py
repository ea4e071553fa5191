"""Objects that travel to other processes (Dask workers, ``multiprocessing``) by their description.

A model, a state space, an observer or a compiled roll-out holds Pinocchio data, CasADi functions and
loaded C libraries, none of which pickles. :class:`Rebuilt` pickles (and deep-copies) such an object as
the constructor call that made it; unpickling calls the constructor again, which finds its generated C
in the on-disk build cache (:mod:`alpes_dyn.simulation.buildcache`) instead of compiling it.
"""

from __future__ import annotations

from typing import Any

__all__ = ["Rebuilt"]


def _rebuild(cls: type, args: tuple, kwargs: dict[str, Any]) -> Any:
    return cls(*args, **kwargs)


class Rebuilt:
    """Mixin: ``pickle`` / ``copy.deepcopy`` as ``cls(*args, **kwargs)``, recorded by :meth:`_remember`."""

    _init: tuple[tuple, dict[str, Any]]

    def _remember(self, *args: Any, **kwargs: Any) -> None:
        """Record the constructor's arguments (call first thing in ``__init__``)."""
        self._init = (args, kwargs)

    def __reduce__(self) -> tuple:
        return (_rebuild, (type(self), *self._init))
