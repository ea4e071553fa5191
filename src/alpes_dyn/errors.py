"""Typed errors of alpes_dyn. Every message is one line that names the faulty field or input."""

from __future__ import annotations

import re

_NUMPY_REPR = re.compile(r"\bnp\.(?:float|int|uint|complex|bool|str)_?(?:\d+)?\(([^()]*)\)")


def plain(text: str) -> str:
    """``text`` with numpy scalar reprs written as numbers: ``np.float64(0.1)`` -> ``0.1``."""
    return re.sub(r"\bnp\.(True|False)_", r"\1", _NUMPY_REPR.sub(r"\1", text))


class AlpesDynError(Exception):
    """Base class of every error raised on purpose by alpes_dyn. A message holding numpy scalar reprs
    (``np.float64(0.1)``, from ``{x!r}`` of a numpy value) is stored with plain numbers (``0.1``)."""

    def __init__(self, *args: object) -> None:
        if args and isinstance(args[0], str):
            args = (plain(args[0]), *args[1:])
        super().__init__(*args)


class AlpesDynWarning(UserWarning):
    """Base class of alpes_dyn's warnings; like :class:`AlpesDynError`, its message has plain numbers."""

    def __init__(self, *args: object) -> None:
        if args and isinstance(args[0], str):
            args = (plain(args[0]), *args[1:])
        super().__init__(*args)


class ModelError(AlpesDynError, ValueError):
    """A parameter file, URDF, model name, tip/frame name or model option is invalid."""


class InputError(AlpesDynError, ValueError):
    """A numeric input (vector, matrix, time step...) has the wrong shape or is not finite."""


class RecordingError(InputError):
    """A recording (CSV of an experiment) is missing a column, has wrong units, is too short or unexcited."""
