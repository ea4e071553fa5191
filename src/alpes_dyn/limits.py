"""Documented upper bounds on the sizes a user can ask for, checked before any work is done.

* Arrays: a run whose result arrays (trajectories, covariances, batches) would take more than
  :func:`max_bytes` -- 2 GiB by default, ``$ALPES_DYN_MAX_BYTES`` (bytes, e.g. ``8e9``) to change
  it -- is refused with an :class:`~alpes_dyn.InputError` that gives the estimate, instead of
  running for minutes and ending in a ``MemoryError`` (or the machine swapping). The estimate counts
  the float64 arrays the computation keeps (e.g. ``simulate``: the states, outputs and inputs, and
  the integrator's copy of the states).
* Random points of the generic rank and of the report's cross-check: at most :data:`MAX_POINTS`.
"""

from __future__ import annotations

import math
import os

from .errors import InputError

__all__ = ["MAX_POINTS", "DEFAULT_MAX_BYTES", "max_bytes", "check_bytes"]

MAX_POINTS = 10_000
"""Most random points for the observability rank and the report's dynamics cross-check."""

DEFAULT_MAX_BYTES = 2 * 1024**3
"""Default limit of the estimated size of a run's arrays, bytes (2 GiB)."""


def max_bytes() -> int:
    """The array size limit in bytes: ``$ALPES_DYN_MAX_BYTES`` if set, else :data:`DEFAULT_MAX_BYTES`."""
    env = os.environ.get("ALPES_DYN_MAX_BYTES")
    if env is None or not env.strip():
        return DEFAULT_MAX_BYTES
    try:
        value = float(env)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value >= 1):
        raise InputError(f"ALPES_DYN_MAX_BYTES: expected a number of bytes >= 1, got {env!r}")
    return int(value)


def _human(n: float) -> str:
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def check_bytes(nbytes: float, field: str, detail: str) -> None:
    """InputError naming ``field`` if ``nbytes`` (an estimate) exceeds :func:`max_bytes`.

    ``detail`` says what the size comes from, e.g. ``"1e+15 steps of 6 states"``.
    """
    limit = max_bytes()
    if not nbytes <= limit:
        raise InputError(f"{field}: {detail} would take about {_human(float(nbytes))} of arrays, over the limit of "
                         f"{_human(limit)} (set ALPES_DYN_MAX_BYTES to change it)")
