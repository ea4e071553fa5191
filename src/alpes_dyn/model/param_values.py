"""One parameter-file value checked against its schema entry (:mod:`alpes_dyn.model.params`): a number, a list of
numbers, names, a unit vector, or the friction law's name (:data:`~alpes_dyn.model.friction.FRICTION_MODELS`)."""

from __future__ import annotations

import math
import re
from typing import Any

import numpy as np

from ..errors import ModelError
from ..limits import check_not_subnormal
from .friction import check_law, check_observer_law

__all__ = ["check_value"]

_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}")


def check_value(name: str, value: Any, length: int | None, kind: str) -> Any:
    """``value`` of field ``name`` checked.

    Parameters
    ----------
    name : str
        The field's name ("section.field"), as errors name it.
    value : object
        The value as the TOML file holds it (a number, a list of numbers or of strings).
    length : int or None
        The number of entries; None: a scalar.
    kind : str
        ``"pos"`` (> 0), ``"nonneg"`` (>= 0), ``"any"`` (finite), ``"unit"`` (a unit vector), ``"str"`` (unique
        names), ``"law"`` (a friction law's name) or ``"observer_law"`` (an observer's friction law's name).

    Returns
    -------
    float or numpy.ndarray or tuple of str or str
        The value as read: a float, an array, a tuple of names, the law's name.

    Raises
    ------
    ModelError
        A value not of its kind or length, naming ``name``.
    """
    if kind == "law":  # a name from FRICTION_MODELS
        return check_law(value, name)
    if kind == "observer_law":  # a name from OBSERVER_LAWS
        return check_observer_law(value, name)
    if kind == "str":
        if not (isinstance(value, list) and len(value) == length and all(isinstance(v, str) and v for v in value)):
            raise ModelError(f"{name}: value must be a list of {length} non-empty strings (got {value!r})")
        if len(set(value)) != len(value):
            raise ModelError(f"{name}: names must be unique (got {value!r})")
        bad = next((v for v in value if not _NAME.fullmatch(v)), None)
        if bad is not None:  # a name goes into URDF/MJCF attributes, joint names and CSV column names
            raise ModelError(f"{name}: {bad[:40]!r} is not a name: letters, digits and '_', starting with a letter")
        return tuple(value)
    if length is None:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ModelError(f"{name}: value must be a number (got {value!r})")
        arr = np.array([float(value)])
    else:
        if not isinstance(value, list) or len(value) != length:
            raise ModelError(f"{name}: value must be a list of {length} numbers (got {value!r})")
        if any(isinstance(v, bool) or not isinstance(v, (int, float)) for v in value):
            raise ModelError(f"{name}: value must be a list of {length} numbers (got {value!r})")
        arr = np.array(value, dtype=float)
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{name}: value must be finite (got {value!r})")
    if kind == "pos" and np.any(arr <= 0):
        i = int(np.argmax(arr <= 0))
        raise ModelError(f"{name}: value must be > 0 (got {arr[i]:g} at index {i})")
    if kind == "nonneg" and np.any(arr < 0):
        i = int(np.argmax(arr < 0))
        raise ModelError(f"{name}: value must be >= 0 (got {arr[i]:g} at index {i})")
    if kind == "unit":
        scale = float(np.max(np.abs(arr)))  # (the norm of a component of 1e300 would overflow)
        norm = scale * float(np.linalg.norm(arr / scale)) if scale > 0 else 0.0
        if not math.isclose(norm, 1.0, rel_tol=1e-9):
            raise ModelError(f"{name}: value must be a unit vector (norm {norm:g})")
        for x in arr:
            check_not_subnormal(float(x), name, "", ModelError)
    return float(arr[0]) if length is None else arr
