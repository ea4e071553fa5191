"""Conversion of user input to numbers, with typed one-line errors (shared by every module)."""

from __future__ import annotations

import math
import numbers
import re

import numpy as np

from .errors import InputError

__all__ = ["as_float_array", "as_positive_float", "one_of", "URDF_DECIMAL", "urdf_number_problem"]

URDF_DECIMAL = re.compile(r"\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
"""A URDF number as urdfdom (Pinocchio's URDF parser) reads it, a C++ stream's ``>>`` that must reach the end:
decimal digits, an optional exponent, leading blanks (not trailing ones, nor Python's ``1_0``, ``nan``, ``inf``,
hexadecimal)."""


def urdf_number_problem(text: str) -> str | None:
    """Why urdfdom would not read ``text`` as one finite number (``None`` if it would): the words of an error
    message after the attribute's name, e.g. ``"has a blank after the number"``. Pinocchio builds a link whose
    ``<inertial>`` urdfdom could not read as massless, without an error: its numbers are checked before.

    Parameters
    ----------
    text : str
        An attribute's text.

    Returns
    -------
    str or None
        The problem in words, or None.
    """
    if URDF_DECIMAL.fullmatch(text):
        return None if math.isfinite(float(text)) else "is not a finite number"
    if URDF_DECIMAL.fullmatch(text.rstrip()):
        return "has a blank after the number (URDF readers refuse it: remove it)"
    return "is not a finite number (write a decimal number, e.g. 0.5 or -1.2e-2)"


def one_of(x: object, allowed: tuple[str, ...], name: str, error: type[Exception] = InputError) -> str:
    """``x`` if it is one of the names ``allowed``, else ``error`` naming ``name`` and listing them in one line.

    Parameters
    ----------
    x : object
        The value read.
    allowed : tuple of str
        The names accepted.
    name : str
        The field or argument the error names.
    error : type of Exception, optional
        The error raised (default :class:`~alpes_dyn.errors.InputError`; a parameter file's field:
        :class:`~alpes_dyn.errors.ModelError`).

    Returns
    -------
    str
        ``x``.

    Raises
    ------
    Exception
        ``error``: ``x`` not a string among ``allowed``.
    """
    if not isinstance(x, str) or x not in allowed:
        raise error(f"{name}: expected one of {', '.join(allowed)}, got {x!r:.40}")
    return x


def _describe(x: object) -> str:
    return f"{x!r:.80}" if not isinstance(x, np.ndarray) else f"an array of {x.dtype} {x.shape}"


def as_float_array(x: object, name: str, expected: str) -> np.ndarray:
    """``x`` as a float array (no copy when it already is one).

    Only real numbers are accepted: complex values (whose imaginary part a float conversion would
    drop), masked arrays with masked entries (whose mask it would drop), booleans (``True`` is not 1.0
    here), strings (``"1"`` is not a number either, nor a list of them), None and other objects are refused; an
    integer too large for a float too.

    Parameters
    ----------
    x : object
        The value: a number, a sequence or an array of real numbers.
    name : str
        The field the error names.
    expected : str
        What was expected, in the error's words (e.g. ``"joint angles"``).

    Returns
    -------
    numpy.ndarray
        ``x`` as floats, of its shape.

    Raises
    ------
    InputError
        ``"<name>: expected <expected>, got ..."`` for anything else.
    """
    if isinstance(x, (str, bytes)):
        raise InputError(f"{name}: expected {expected}, got a string {x!r:.60}")
    if isinstance(x, np.ma.MaskedArray) and np.ma.is_masked(x):  # np.asarray would drop the mask, not the values
        raise InputError(f"{name}: masked values are not supported (give the values, or NaN where they are missing)")
    try:
        a = np.asarray(x)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name}: expected {expected}, got {_describe(x)}") from None
    kind = a.dtype.kind
    if kind in "fiu":
        return a.astype(float, copy=False)
    if kind == "c" or (kind == "O" and any(isinstance(v, complex) for v in a.reshape(-1))):
        raise InputError(f"{name}: complex values are not supported, got {_describe(x)}")
    if kind == "b" or (kind == "O" and any(isinstance(v, (bool, np.bool_)) for v in a.reshape(-1))):
        raise InputError(f"{name}: expected {expected}, got booleans {_describe(x)}")
    if kind == "O" and all(isinstance(v, numbers.Real) for v in a.reshape(-1)):
        try:
            return a.astype(float)
        except (OverflowError, TypeError, ValueError):
            raise InputError(f"{name}: expected {expected}, got a number too large for a float") from None
    raise InputError(f"{name}: expected {expected}, got {_describe(x)}")


def as_positive_float(x: object, name: str, unit: str = "s") -> float:
    """``x`` as a finite positive float (a time step, a duration): not a bool, a string or complex.

    Parameters
    ----------
    x : object
        The value.
    name : str
        The field the error names.
    unit : str, optional
        Its unit, in the error's words (default ``"s"``).

    Returns
    -------
    float
        The value.

    Raises
    ------
    InputError
        Not a positive finite real number, naming ``name``.
    """
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, numbers.Real):
        raise InputError(f"{name}: expected a positive number of {unit}, got {_describe(x)}")
    try:
        v = float(x)
    except (OverflowError, ValueError):
        raise InputError(f"{name}: expected a positive number of {unit}, got a number too large") from None
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name}: expected a positive finite number of {unit}, got {v!r}")
    return v
