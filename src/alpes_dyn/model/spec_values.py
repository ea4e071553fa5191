"""The values of a transmission spec (:mod:`alpes_dyn.model.spec`): a number in its physical range, a name, a motor's
``ratio_curve``, and the
``[stops]`` table (joint stops a user gives, robot-wide and per joint: read, placed in joint order, written)."""

from __future__ import annotations

import math
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ..errors import ModelError
from ..limits import MAX_NAME, check_physical
from .ratio_curve import MAX_CURVE_DEGREE

__all__ = ["STOPS_TABLE", "STOP_KEYS", "parse_stops", "stop_values", "stops_toml"]

STOPS_TABLE = "stops"
"""The joint stops' table of a spec: ``stiffness`` (N m/rad, > 0) and ``damping`` (N m s/rad, >= 0) for every
limited joint, and ``joints`` {joint: {stiffness, damping}} per joint (:mod:`alpes_dyn.model.spec`'s module doc)."""
STOP_KEYS: tuple[str, ...] = ("stiffness", "damping")


def _number(value: Any, name: str, low: float | None = None, strict: bool = False, unit: str = "") -> float:
    """``value`` as a finite float of the accepted range of its ``unit`` (:data:`alpes_dyn.limits.PHYSICAL_RANGES`;
    ``low``: 0.0 for a quantity that may be zero, with ``strict`` one that must be positive), else ModelError."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ModelError(f"{name}: expected a number, got {value!r}")
    try:
        x = float(value)
    except OverflowError:  # an integer of 400 digits
        raise ModelError(f"{name}: expected a finite number, got an integer of {len(str(abs(int(value))))} digits") from None
    if not math.isfinite(x):
        raise ModelError(f"{name}: expected a finite number, got {value!r}")
    if low is not None and (x <= low if strict else x < low):
        raise ModelError(f"{name}: expected a number {'>' if strict else '>='} {low:g}, got {x:g}")
    kind = "any" if low is None else "pos" if strict else "nonneg"
    check_physical(x, name, unit, kind, ModelError)
    return x


def _name(value: Any, name: str) -> str:
    """A name of the spec (motor, joint, frame, robot): a non-empty string without control characters (they
    become XML names in the MJCF export and CSV columns, where XML 1.0 cannot hold them at all)."""
    if not isinstance(value, str) or not value:
        raise ModelError(f"{name}: expected a non-empty string, got {value!r}")
    if len(value) > MAX_NAME:  # it becomes a recording's column (encoder_<motor>) and an MJCF name
        raise ModelError(f"{name}: {value[:40]!r}... has {len(value)} characters, over the limit of {MAX_NAME}")
    if any(ord(c) < 32 or 127 <= ord(c) < 160 for c in value):
        raise ModelError(f"{name}: {value!r} holds a control character; a name is printable text")
    return value


def _stop_numbers(value: Any, where: str) -> dict[str, float]:
    """``stiffness`` (N m/rad, > 0) and ``damping`` (N m s/rad, >= 0) of a ``[stops]`` table or entry."""
    out = {}
    for k, x in value.items():
        if k not in STOP_KEYS:
            raise ModelError(f"{where}.{k}: unknown key (expected {' or '.join(STOP_KEYS)})")
        out[k] = _number(x, f"{where}.{k}", 0.0, strict=k == "stiffness",
                         unit="N m/rad" if k == "stiffness" else "N m s/rad")
    return out


def parse_stops(value: Any) -> Mapping[str, Any] | None:
    """The ``[stops]`` table validated (module doc): {"stiffness", "damping" (robot-wide, optional), "joints": {joint:
    {"stiffness", "damping"}}}, or None.

    Parameters
    ----------
    value : mapping or None
        The spec's ``[stops]`` table as parsed (stiffness N m/rad, damping N m s/rad), or None (no table).

    Returns
    -------
    mapping or None
        The table, read-only, ``joints`` always present; None for None.

    Raises
    ------
    ModelError
        A table not of its form, an unknown key or a bad number, named.
    """
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise ModelError(f"stops: expected a table (stiffness, damping, joints), got {value!r}")
    joints = value.get("joints", {})
    out: dict[str, Any] = _stop_numbers({k: x for k, x in value.items() if k != "joints"}, "stops")
    if not isinstance(joints, Mapping):
        raise ModelError(f"stops.joints: expected a table joint name -> {{stiffness, damping}}, got {joints!r}")
    per: dict[str, Mapping[str, float]] = {}
    for j, entry in joints.items():
        _name(j, "stops.joints")
        if not isinstance(entry, Mapping) or not entry:
            raise ModelError(f"stops.joints.{j}: expected a table with stiffness and/or damping, got {entry!r}")
        per[j] = MappingProxyType(_stop_numbers(entry, f"stops.joints.{j}"))
    if not out and not per:
        raise ModelError("stops: an empty table; give stiffness, damping or joints (or leave [stops] out: sized to "
                         "the robot)")
    out["joints"] = MappingProxyType(per)
    return MappingProxyType(out)


def stop_values(stops: Mapping[str, Any] | None, joint_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """A ``[stops]`` table (:func:`parse_stops`'s) in ``joint_names`` order: stiffness (n,) N m/rad and damping (n,)
    N m s/rad, a joint's own value over the robot-wide one, NaN where the table gives none (all NaN for None).

    Parameters
    ----------
    stops : mapping or None
        The table (:func:`parse_stops`'s), or None.
    joint_names : sequence of str
        The model's joints (n), in its order.

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray)
        Stiffness (n,), N m/rad, and damping (n,), N m s/rad.
    """
    n = len(joint_names)
    out = {k: np.full(n, np.nan) for k in STOP_KEYS}
    if stops is not None:
        for k in STOP_KEYS:
            if k in stops:
                out[k][:] = stops[k]
        idx = {j: i for i, j in enumerate(joint_names)}
        for j, entry in stops["joints"].items():
            for k, x in entry.items():
                out[k][idx[j]] = x
    return out["stiffness"], out["damping"]


def stops_toml(stops: Mapping[str, Any] | None, key: Callable[[str], str]) -> list[str]:
    """The TOML lines of a ``[stops]`` table (none for None).

    Parameters
    ----------
    stops : mapping or None
        The table (:func:`parse_stops`'s), or None.
    key : callable
        Quotes a joint name as a TOML key (str -> str).

    Returns
    -------
    list of str
        The lines, starting with a blank one (empty for None).
    """
    if stops is None:
        return []
    out = ["", f"[{STOPS_TABLE}]"] + [f"{k} = {stops[k]!r}" for k in STOP_KEYS if k in stops]
    if stops["joints"]:
        out += ["", f"[{STOPS_TABLE}.joints]"] + [
            f"{key(j)} = {{ " + ", ".join(f"{k} = {x!r}" for k, x in e.items()) + " }"
            for j, e in stops["joints"].items()]
    return out


def _ratio_curve(value: Any, joints: Mapping[str, float], where: str) -> Mapping[str, tuple[float, ...]]:
    """A motor's ``ratio_curve`` validated: {joint of ``joints``: (c_1, ..., c_P)}, 1 <= P <= MAX_CURVE_DEGREE."""
    if not isinstance(value, Mapping):
        raise ModelError(f"{where}.ratio_curve: expected a table joint name -> [c_1, ..., c_P], got {value!r}")
    out = {}
    for j, c in value.items():
        _name(j, f"{where}.ratio_curve")
        if j not in joints:
            raise ModelError(f"{where}.ratio_curve.{j}: joint {j!r} is not one of the motor's joints "
                             f"({', '.join(joints)})")
        if isinstance(c, (str, bytes, Mapping)) or not isinstance(c, Sequence) or not 1 <= len(c) <= MAX_CURVE_DEGREE:
            raise ModelError(f"{where}.ratio_curve.{j}: expected a list of 1 to {MAX_CURVE_DEGREE} coefficients "
                             f"(of q^1, q^2, ...), got {c!r}")
        out[j] = tuple(_number(x, f"{where}.ratio_curve.{j}", unit="-") for x in c)
    return MappingProxyType(out)

