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
  most :data:`MAX_ORDER`, operation caps at most :data:`MAX_OPERATIONS`; at most :data:`MAX_ARGS` command-line arguments;
  seeds from 0 to :data:`MAX_SEED`; names (joints, links, frames, motors) of at most :data:`MAX_NAME` characters.
* The numeric hot paths (:class:`~alpes_dyn.Model`'s dynamics, a state space's and an observer's vectors): every entry
  of a vector below :data:`MAX_HOT_MAGNITUDE` (2^40, about 1.1e12) in magnitude, checked with one BLAS norm per
  vector (:func:`within_hot_magnitude`): an angle beyond it is known to worse than 2.4e-4 rad (float64's spacing
  there), so its sine and cosine are noise, and no robot's velocity, torque or force comes near it.
* Physical quantities (:data:`PHYSICAL_RANGES`, :func:`check_physical`): every number of a parameter file, of a
  spec and of a command-line option that has a unit lies within a range of magnitudes, by its unit: an angle of
  1e300 rad or a gear ratio of 1e300 is refused with one line naming the field and the range, as is a subnormal
  number such as 1e-320 (below the smallest normal float, 2.2e-308: write 0, or a physical value).
"""

from __future__ import annotations

import math
import numbers
import os

from scipy.linalg.blas import dnrm2 as _NRM2  # BLAS's norm: the hot paths' one-call check

from .errors import InputError

__all__ = ["MAX_POINTS", "DEFAULT_MAX_BYTES", "max_bytes", "check_bytes", "check_duration", "check_time_step", "MAX_TEXT_BYTES", "MAX_RECORDING_BYTES",
           "MAX_CSV_CELL", "MAX_CSV_ROWS", "MAX_URDF_LINKS", "MAX_URDF_DEPTH", "MAX_URDF_JOINTS", "MAX_TOML_DEPTH", "MAX_TOML_INT",
           "MAX_DURATION_S", "MIN_TIME_STEP_S", "MAX_ORDER", "MAX_OPERATIONS", "MAX_ARGS", "MAX_SEED", "MAX_NAME", "PHYSICAL_RANGES",
           "check_physical", "check_not_subnormal", "MAX_HOT_MAGNITUDE", "within_hot_magnitude"]

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

MAX_NAME = 128
"""Longest name of a joint, link, frame or motor, characters: a name becomes an MJCF name and a recording's column
(``encoder_<motor>``, ``true_q_<joint>``), whose cells are at most :data:`MAX_CSV_CELL` characters."""

MAX_HOT_MAGNITUDE = 2.0**40
"""Largest magnitude (exclusive) of an entry of a vector given to the numeric hot paths (q in rad or m, qd, Gamma,
a force, a state, a measurement): 2^40 = 1.0995e12. Float64's spacing at 2^40 is 2^-12 = 2.4e-4, so an angle there
is known to a quarter of a milliradian at best (at 2^53, not to 1 rad: its sine is noise); no robot's velocity
(rad/s), torque (N m) or force (N) comes near it."""

MAX_SEED = 2**63 - 1
"""Largest random seed (a seed is an integer from 0 to 2^63 - 1)."""

PHYSICAL_RANGES: dict[str, tuple[float, float]] = {
    "m": (1e-6, 100.0),  # lengths, radii, positions: 1 um to 100 m
    "kg": (1e-9, 1e4),
    "kg m^2": (1e-15, 1e4),
    "rad": (1e-12, 100.0),  # angles: joint angles, limits, yaws, offsets (16 turns either way)
    "deg": (1e-10, 180.0),
    "rad/s": (1e-9, 1e4),
    "m/s^2": (1e-9, 100.0),  # gravity: up to about 10 g
    "N m": (1e-12, 1e6),  # torques, Coulomb friction, noise
    "N": (1e-12, 1e6),
    "N m/rad": (1e-12, 1e6),  # springs
    "N m s/rad": (1e-15, 1e6),  # viscous friction
    "N/m": (1e-6, 1e12),  # a tendon's stiffness
    "N s/m": (1e-15, 1e9),
    "N m/A": (1e-9, 1e3),  # a motor's torque constant
    "rad/(N m)": (1e-12, 1e6),  # a tendon's compliance seen by the encoder
    "-": (1e-6, 1e6),  # ratios: gear and transmission ratios, relative spreads
    "counts/rev": (1.0, 1e9),
    "counts": (1e-9, 1e9),
    "s": (1e-9, 1e6),
    "Hz": (1e-6, 1e6),
    "samples": (1.0, 100.0),  # a sensor's delay in whole sample periods (0.1 s at 1 kHz: beyond, a wrong clock)
}
"""The accepted magnitudes of a physical quantity, by its unit: (smallest, largest) magnitude of a non-zero value.
A value must be finite, not subnormal and at most the largest in magnitude; a quantity that must be positive (a
length, a mass: a tiny one makes the mass matrix singular) is also refused at zero and below and under the smallest,
one that may be zero (a spring, a friction) below zero; a signed one (a position, an angle) only over the largest.
The ranges are wide on purpose (a 100 m link, a 10 t mass): they refuse what no robot has, not what this hand has
not."""

_SMALLEST_NORMAL = 2.2250738585072014e-308


def within_hot_magnitude(a) -> bool:
    """Whether float64 vector ``a`` is finite with its Euclidean norm below :data:`MAX_HOT_MAGNITUDE`: one BLAS
    ``dnrm2`` call (about as cheap as a dot product; its scaling never overflows, so no numpy warning either).
    True implies every entry is below the bound; False (a NaN, an inf, an entry at or over the bound, or rarely
    many entries whose norm only reaches it) sends the caller to its exact, slower check.

    Parameters
    ----------
    a : numpy.ndarray, shape (k,)
        A contiguous float64 vector.

    Returns
    -------
    bool
        Whether it is finite and below the bound.
    """
    return _NRM2(a) < MAX_HOT_MAGNITUDE


def hot_magnitude_error(a, name: str) -> InputError | None:
    """The :class:`~alpes_dyn.InputError` naming ``name`` and the first entry of finite vector ``a`` at or over
    :data:`MAX_HOT_MAGNITUDE`, or None when every entry is below it (the exact check behind
    :func:`within_hot_magnitude`)."""
    import numpy as np

    big = np.flatnonzero(np.abs(a) >= MAX_HOT_MAGNITUDE)
    if big.size == 0:
        return None
    i = int(big[0])
    at = f" (index {i})" if np.ndim(a) and np.size(a) > 1 else ""
    return InputError(f"{name}: {float(np.reshape(a, -1)[i]):g}{at} is over the numeric hot paths' bound of 2^40 = "
                      "1.1e12 in magnitude (docs: user guide, dynamics, 'Input bounds')")


def check_not_subnormal(x: float, field: str, unit: str = "", error: type[Exception] = InputError) -> float:
    """``x`` unless it is a subnormal number (0 < abs(x) < 2.2e-308, e.g. 1e-320).

    Parameters
    ----------
    x : float
        The value.
    field : str
        The field the error names.
    unit : str, optional
        Its unit, said in the error (default none; ``"-"``: dimensionless, not said).
    error : type, optional
        The exception class raised (default InputError).

    Returns
    -------
    float
        ``x``.

    Raises
    ------
    Exception
        ``error`` naming ``field`` for a subnormal ``x``.
    """
    if x != 0.0 and abs(x) < _SMALLEST_NORMAL:
        raise error(f"{field}: {x!r}{' ' + unit if unit and unit != '-' else ''} is a subnormal number (below "
                    "2.2e-308, the smallest normal float): write 0 or a physical value")
    return x


def check_physical(value: object, field: str, unit: str, kind: str = "any", error: type[Exception] = InputError):
    """``value`` (a float or an array of them, already finite) within the accepted range of its ``unit``
    (:data:`PHYSICAL_RANGES`), else ``error`` with one line naming ``field``, the value and the range.

    Parameters
    ----------
    value : float or numpy.ndarray
        The value(s), already finite.
    field : str
        The field the error names.
    unit : str
        Its unit, a key of :data:`PHYSICAL_RANGES` (a unit absent from the table checks only for subnormal numbers).
    kind : str, optional
        ``"pos"`` (> 0, in [smallest, largest]), ``"nonneg"`` (in [0, largest]) or ``"any"`` (default; either
        sign, at most the largest in magnitude).
    error : type, optional
        The exception class raised (default InputError).

    Returns
    -------
    float or numpy.ndarray
        ``value``.

    Raises
    ------
    Exception
        ``error`` with one line naming ``field``, the value and the range.
    """
    import numpy as np

    arr = np.atleast_1d(np.asarray(value, dtype=float)).reshape(-1)
    low, high = PHYSICAL_RANGES.get(unit, (0.0, math.inf))
    u = "" if unit in ("-", "") else f" {unit}"
    for i, x in enumerate(arr):
        x = float(x)
        at = f" (index {i})" if arr.size > 1 else ""
        check_not_subnormal(x, field + at, unit, error)
        small = kind == "pos" and abs(x) < low  # (a signed or a may-be-zero quantity may pass through zero)
        bad = (kind == "pos" and x <= 0) or (kind == "nonneg" and x < 0) or abs(x) > high or small
        if bad:
            if kind == "pos":
                rng = f"[{low:g}, {high:g}]{u}"
            elif kind == "nonneg":
                rng = f"[0, {high:g}]{u}"
            else:
                rng = f"[{-high:g}, {high:g}]{u}"
            raise error(f"{field}: {x:g}{u}{at} is outside the accepted range {rng} (docs: user guide, command line, "
                        "'Accepted ranges')")
    return value


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
    """``value`` as a finite duration in (0, :data:`MAX_DURATION_S`] s.

    Parameters
    ----------
    value : object
        The duration, s (a real number).
    field : str
        The field or option the error names.

    Returns
    -------
    float
        The duration, s.

    Raises
    ------
    InputError
        Not a finite number in that range, naming ``field``.
    """
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
    """``dt`` within [:data:`MIN_TIME_STEP_S`, :data:`MAX_DURATION_S`] s.

    Parameters
    ----------
    dt : float
        The time step, s (already a finite positive float).
    field : str, optional
        The field or option the error names (default ``"dt"``).

    Returns
    -------
    float
        ``dt``.

    Raises
    ------
    InputError
        ``dt`` outside the range, naming ``field``.
    """
    if not MIN_TIME_STEP_S <= dt <= MAX_DURATION_S:
        raise InputError(f"{field}: {dt:g} s is outside [{MIN_TIME_STEP_S:g}, {MAX_DURATION_S:g}] s, the time steps "
                         "accepted")
    return dt


def check_bytes(nbytes: float, field: str, detail: str) -> None:
    """InputError naming ``field`` if ``nbytes`` (an estimate) exceeds :func:`max_bytes`.

    Parameters
    ----------
    nbytes : float
        The estimated size of the arrays, bytes.
    field : str
        The field or option the error names.
    detail : str
        What the size comes from, e.g. ``"1e+15 steps of 6 states"``.

    Raises
    ------
    InputError
        ``nbytes`` over the limit, naming ``field``.
    """
    limit = max_bytes()
    if not nbytes <= limit:
        raise InputError(f"{field}: {detail} would take about {_human(float(nbytes))} of arrays, over the limit of "
                         f"{_human(limit)} (set ALPES_DYN_MAX_BYTES to change it)")
