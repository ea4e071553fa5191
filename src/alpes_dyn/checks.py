"""Conversion of user input to numbers, with typed one-line errors (shared by every module)."""

from __future__ import annotations

import numpy as np

from .errors import InputError

__all__ = ["as_float_array"]


def as_float_array(x: object, name: str, expected: str) -> np.ndarray:
    """``x`` as a float array (no copy when it already is one).

    Complex values (whose imaginary part a float conversion would drop), strings and other
    non-numbers raise :class:`~alpes_dyn.InputError` ``"<name>: expected <expected>, got ..."``.
    """
    try:
        a = np.asarray(x)
        if a.dtype.kind != "c":
            return a.astype(float, copy=False) if a.dtype.kind in "fiub" else np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{name}: expected {expected}, got {x!r:.80}") from None
    raise InputError(f"{name}: complex values are not supported, got {x!r:.80}")
