"""The arguments of a simulation checked and its inputs sampled: the step and duration (s), the SUNDIALS
tolerances, and the inputs held over each step (zero-order hold) from a constant, an array or a callable of time,
the contact force's F_z shorthand (eq. 2.13) included; every defect an :class:`~alpes_dyn.errors.InputError` naming
the argument. Read by :func:`~alpes_dyn.simulation.integrate.simulate`, the compiled rollouts and the observers."""

from __future__ import annotations

import math
from typing import Any, Callable, Sequence, Union

import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..limits import check_time_step, hot_magnitude_error

__all__: list[str] = []

InputLike = Union[None, float, Sequence[float], np.ndarray, Callable[[float], Any]]


def _tolerance(x: Any, name: str) -> float:
    """A SUNDIALS tolerance: a finite positive real number (not a bool, string or complex), else InputError."""
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a positive number, got {x!r:.60}")
    v = float(x)
    if not (math.isfinite(v) and v > 0):
        raise InputError(f"{name}: expected a positive finite number, got {v!r}")
    return v


def _check_dt(dt: Any) -> float:
    if isinstance(dt, (bool, np.bool_)):
        raise InputError(f"dt: expected a positive number of seconds, got {dt!r}")
    try:
        d = float(dt)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"dt: expected a positive number of seconds, got {dt!r:.60}") from None
    if isinstance(dt, (str, bytes, complex)):
        raise InputError(f"dt: expected a positive number of seconds, got {dt!r:.60}")
    if not math.isfinite(d) or d <= 0:
        raise InputError(f"dt: expected a positive finite number of seconds, got {dt!r}")
    return check_time_step(d)


def _n_steps(duration: Any, dt: float) -> int:
    if isinstance(duration, (bool, np.bool_, str, bytes, complex)):
        raise InputError(f"duration: expected a positive number of seconds, got {duration!r:.60}")
    try:
        T = float(duration)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"duration: expected a positive finite number of seconds, got {str(duration)[:60]}") from None
    if not math.isfinite(T) or T <= 0:
        raise InputError(f"duration: expected a positive finite number of seconds, got {duration!r}")
    if not T / dt < 2.0**53:
        raise InputError(f"duration: {T:g} s at dt = {dt:g} s is more than 2^53 steps")
    N = int(round(T / dt))
    if N < 1 or abs(N * dt - T) > 1e-9 * max(T, dt):
        raise InputError(f"duration: {T:g} s is not a whole number of steps dt = {dt:g} s")
    return N


def _finite(a: np.ndarray, name: str) -> np.ndarray:
    """``a`` if finite with every entry below :data:`~alpes_dyn.limits.MAX_HOT_MAGNITUDE`, else InputError."""
    if not np.isfinite(a).all():
        raise InputError(f"{name}: contains NaN or inf")
    err = hot_magnitude_error(a, name)
    if err is not None:
        raise err
    return a


def _sample(inputs: InputLike, t: np.ndarray, m: int, name: str) -> np.ndarray:
    """(N, m) zero-order-hold samples of ``inputs`` at the step starts ``t`` (N,)."""
    N = t.shape[0]
    if inputs is None:
        return np.zeros((N, m))
    if callable(inputs):
        rows = []
        for tk in t:  # a user's Python callable: sampled once per step
            try:
                v = as_float_array(inputs(float(tk)), name, f"{m} numbers").reshape(-1)
            except (TypeError, ValueError) as exc:
                raise InputError(f"{name}: the callable must return {m} numbers ({exc})") from None
            if v.shape != (m,):
                raise InputError(f"{name}: the callable returned {v.size} values at t = {tk:g} s, expected {m}")
            rows.append(v)
        return _finite(np.array(rows), f"{name}(t)")
    a = as_float_array(inputs, name, "an array of numbers or a callable of time")
    if a.ndim == 0 or a.shape == (m,):
        a = np.broadcast_to(a, (N, m)).copy()
    elif m == 1 and a.shape == (N,):
        a = a.reshape(N, 1)
    elif a.shape != (N, m):
        raise InputError(f"{name}: expected shape ({N}, {m}) (steps, inputs) or ({m},), got {a.shape}")
    return _finite(a, name)


def _sample_force(force: InputLike, t: np.ndarray, k: int = 3) -> np.ndarray:
    """(N, k) contact forces. k = 3 (one force): scalars / (N,) series / callables returning a scalar are F_z
    (eq. 2.13); several contacts (k = n_force): (k,), (N, k) or a callable returning k values."""
    N = t.shape[0]
    if k != 3:
        return _sample(force, t, k, "force")
    if callable(force):
        out = np.zeros((N, 3))
        for k, tk in enumerate(t):
            try:
                v = as_float_array(force(float(tk)), "force", "F_z or (Fx, Fy, Fz)").reshape(-1)
            except (TypeError, ValueError) as exc:
                raise InputError(f"force: the callable must return F_z or (Fx, Fy, Fz) ({exc})") from None
            if v.size == 1:
                out[k, 2] = v[0]
            elif v.size == 3:
                out[k] = v
            else:
                raise InputError(f"force: the callable returned {v.size} values at t = {tk:g} s, expected 1 or 3")
        return _finite(out, "force(t)")
    a = as_float_array(force, "force", "F_z or (Fx, Fy, Fz) numbers")
    if a.ndim == 0 or a.shape == (N,):
        out = np.zeros((N, 3))
        out[:, 2] = a
        return _finite(out, "force")
    if a.shape == (3,) or a.shape == (N, 3):
        return _finite(np.broadcast_to(a, (N, 3)).copy(), "force")
    raise InputError(f"force: expected F_z (scalar or ({N},)), (3,) or ({N}, 3), got shape {a.shape}")
