"""Documented upper bounds on the sizes a user can ask for, checked before any work is done.

* Arrays: a run whose result arrays (trajectories, covariances, batches) would take more than
  :func:`max_bytes` -- 2 GiB by default, ``$ALPES_DYN_MAX_BYTES`` (bytes, e.g. ``8e9``) to change
  it -- is refused with an :class:`~alpes_dyn.InputError` that gives the estimate, instead of
  running for minutes and ending in a ``MemoryError`` (or the machine swapping). The estimate counts
  the float64 arrays the computation keeps (e.g. ``simulate``: the states, outputs and inputs, and
  the integrator's copy of the states).
* Random points of the generic rank and of the report's cross-check: at most :data:`MAX_POINTS`.
* Input files, checked before they are parsed (:mod:`alpes_dyn.fileio`): a parameter file, spec or
  URDF of at most :data:`MAX_TEXT_BYTES`, a recording of at most :data:`MAX_RECORDING_BYTES`; a
  recording's cells of at most :data:`MAX_CSV_CELL` characters and at most :data:`MAX_CSV_ROWS`
  rows; a URDF of at most :data:`MAX_URDF_LINKS` links, :data:`MAX_URDF_JOINTS` moving joints and a kinematic
  tree of depth at most :data:`MAX_URDF_DEPTH` (counted before Pinocchio's parser sees it); TOML nested at most
  :data:`MAX_TOML_DEPTH` deep, its integers at most :data:`MAX_TOML_INT` in magnitude.
* Times and orders a user asks for: durations at most :data:`MAX_DURATION_S`, time steps in
  [:data:`MIN_TIME_STEP_S`, :data:`MAX_DURATION_S`], derivative orders at
  most :data:`MAX_ORDER`, operation caps at most :data:`MAX_OPERATIONS`; at most :data:`MAX_ARGS` command-line arguments.
"""

from __future__ import annotations

import math
import numbers
import os

from .errors import InputError

__all__ = ["MAX_POINTS", "DEFAULT_MAX_BYTES", "max_bytes", "check_bytes", "check_duration", "check_time_step", "MAX_TEXT_BYTES", "MAX_RECORDING_BYTES",
           "MAX_CSV_CELL", "MAX_CSV_ROWS", "MAX_URDF_LINKS", "MAX_URDF_DEPTH", "MAX_URDF_JOINTS", "MAX_TOML_DEPTH", "MAX_TOML_INT",
           "MAX_DURATION_S", "MIN_TIME_STEP_S", "MAX_ORDER", "MAX_OPERATIONS", "MAX_ARGS"]

MAX_POINTS = 10_000
"""Most random points for the observability rank and the report's dynamics cross-check."""

MAX_TEXT_BYTES = 16 * 1024**2
"""Largest parameter file, spec or URDF read, bytes (16 MiB; the shipped hand's URDF is 14 kB)."""

MAX_RECORDING_BYTES = 1024**3
"""Largest recording CSV read, bytes (1 GiB: hours of a hand's columns at 1 kHz)."""

MAX_CSV_CELL = 256
"""Longest cell of a recording, characters (a number or a column name)."""

MAX_CSV_ROWS = 20_000_000
"""Most rows of a recording (5.5 h at 1 kHz)."""

MAX_URDF_LINKS = 1000
"""Most ``<link>`` elements of a URDF (the Alpes hand has 21, the Allegro hand 21)."""

MAX_URDF_DEPTH = 100
"""Deepest kinematic chain of a URDF, joints from the root (a finger has 3, an arm about 7)."""

MAX_URDF_JOINTS = 200
"""Most moving joints (degrees of freedom) of a URDF (the Alpes hand has 14, a humanoid about 50): Pinocchio's
data takes memory and time growing with the square of the joints (a 1000-joint URDF asks for 16 GB)."""

MAX_TOML_DEPTH = 32
"""Deepest nesting of arrays and tables in a parameter file or spec."""

MAX_TOML_INT = 2**53
"""Largest integer magnitude in a parameter file or spec (exact as a float)."""

MAX_DURATION_S = 1e6
"""Longest simulated or recorded duration a user can ask for, s (the array limit usually comes first)."""

MIN_TIME_STEP_S = 1e-9
"""Shortest time step (integration, sampling, discretisation), s: below, t = k dt loses its digits (a subnormal
1e-320 s is printed back as 9.99989e-321 s); the longest is :data:`MAX_DURATION_S`."""

MAX_ARGS = 1000
"""Most command-line arguments of one ``alpes-dyn`` command (argparse's parsing grows faster than linearly)."""

MAX_ORDER = 1000
"""Highest derivative order of an observability or identifiability test."""

MAX_OPERATIONS = 50_000_000
"""Largest size cap (``max_operations``, CasADi operations) of one derivative order's function in the observability
and identifiability tests (25 times the default; a larger cap lets one order take hours and tens of GB)."""

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


def check_duration(value: object, field: str) -> float:
    """``value`` as a finite duration in (0, :data:`MAX_DURATION_S`] s, else InputError naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InputError(f"{field}: expected a number of seconds, got {type(value).__name__}")
    try:
        x = float(value)
    except (OverflowError, ValueError):
        raise InputError(f"{field}: expected a finite number of seconds, got {str(value)[:40]}") from None
    if not math.isfinite(x):
        raise InputError(f"{field}: expected a finite number of seconds, got {x!r}")
    if not x > 0:
        raise InputError(f"{field}: expected a positive number of seconds, got {x:g}")
    if x > MAX_DURATION_S:
        raise InputError(f"{field}: {x:g} s is over the limit of {MAX_DURATION_S:g} s")
    return x


def check_time_step(dt: float, field: str = "dt") -> float:
    """``dt`` (already a finite positive float) within [:data:`MIN_TIME_STEP_S`, :data:`MAX_DURATION_S`] s, else
    InputError naming ``field``."""
    if not MIN_TIME_STEP_S <= dt <= MAX_DURATION_S:
        raise InputError(f"{field}: {dt:g} s is outside [{MIN_TIME_STEP_S:g}, {MAX_DURATION_S:g}] s, the time steps "
                         "accepted")
    return dt


def check_bytes(nbytes: float, field: str, detail: str) -> None:
    """InputError naming ``field`` if ``nbytes`` (an estimate) exceeds :func:`max_bytes`.

    ``detail`` says what the size comes from, e.g. ``"1e+15 steps of 6 states"``.
    """
    limit = max_bytes()
    if not nbytes <= limit:
        raise InputError(f"{field}: {detail} would take about {_human(float(nbytes))} of arrays, over the limit of "
                         f"{_human(limit)} (set ALPES_DYN_MAX_BYTES to change it)")
