"""A motor's spatial tendon as its geometry: the spec's ``path`` (issue 51, item 1).

Where a tendon's ratios are no polynomial of each joint (it touches, leaves or changes side of a wrapping geom inside
a joint's range, or a straight segment spans two joints), the spec carries the tendon itself: the motor angle is
s(q) = g (L(q) - L(0)) with L MuJoCo's tendon length, computed from

* ``frames``: the bodies the tendon's points ride on, each placed on its parent (``parent``, "" the world) at ``pos``
  (m) and ``quat`` (w, x, y, z), then turned by its hinges (``joints``: ``joint`` the model's joint, ``axis`` and
  ``anchor`` (m) in the body's frame, ``ref`` the angle (rad) at which the body is at rest: MuJoCo's qpos0);
* ``points``: in order, sites ``{ site, frame, pos }``, wrapping geoms ``{ geom, kind = "cylinder" | "sphere",
  frame, pos, quat, radius, side }`` between two sites (``side``: an optional ``{ frame, pos }`` side site, the side
  the tendon wraps on) and pulleys ``{ pulley = divisor }`` (the branches after one count 1 / divisor);
* ``gear`` (m of tendon to rad of motor: the actuator's gear).

Each straight or wrapped segment is MuJoCo's (:func:`~alpes_dyn.model.wrap.wrap_length`), so the ratios
rho(q) = ds/dq (by AD), their rate and the torques follow every switch of the path (:mod:`alpes_dyn.model.path_ratios`).
The spec's ``joints`` of such a motor are its ratios at q = 0 (as with a ``ratio_curve``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import ModelError

__all__ = ["PathFrame", "PathPoint", "SpatialPath", "spatial_path"]

KINDS = ("cylinder", "sphere")
"""The wrapping geoms represented (MuJoCo wraps on no other)."""


def _vec(value: Any, n: int, where: str, unit: bool = False) -> tuple[float, ...]:
    """``value`` as n finite floats (non-zero where ``unit``), or a ModelError naming ``where``."""
    ok = isinstance(value, Sequence) and not isinstance(value, (str, bytes)) and len(value) == n
    x = np.array(value, dtype=float) if ok and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                   for v in value) else None
    if x is None or not np.all(np.isfinite(x)) or (unit and not np.any(x)):
        raise ModelError(f"{where}: expected {n} finite numbers{' not all 0' if unit else ''}, got {value!r}")
    return tuple(float(v) for v in x)


def _positive(value: Any, where: str) -> float:
    """``value`` as a finite float > 0, or a ModelError naming ``where``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value) or value <= 0:
        raise ModelError(f"{where}: expected a finite number > 0, got {value!r}")
    return float(value)


def _table(value: Any, keys: Sequence[str], where: str) -> Mapping[str, Any]:
    """``value`` as a table of only ``keys``, or a ModelError naming ``where``."""
    if not isinstance(value, Mapping):
        raise ModelError(f"{where}: expected a table, got {value!r}")
    for k in value:
        if k not in keys:
            raise ModelError(f"{where}.{k}: unknown key (expected one of {', '.join(keys)})")
    return value


def _inline(value: Any) -> str:
    """``value`` (tables, arrays, names, numbers) as TOML inline text."""
    import json

    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_inline(v)}" for k, v in value.items()) + " }"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_inline(v) for v in value) + "]"
    if isinstance(value, str):
        return json.dumps(value)
    return repr(float(value))


def quat_matrix(quat: Sequence[float]) -> np.ndarray:
    """The rotation matrix (3, 3) of quaternion (w, x, y, z) (normalised first, as MuJoCo does)."""
    w, x, y, z = np.asarray(quat, dtype=float) / np.linalg.norm(quat)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


@dataclass(frozen=True)
class PathFrame:
    """A body the tendon rides on (module doc): ``name``, ``parent`` ("" the world), ``pos`` (3,) m, ``quat`` (4,)
    and ``joints``: ((joint name, axis (3,), anchor (3,) m, ref rad), ...) in MuJoCo's order."""

    name: str
    parent: str
    pos: tuple
    quat: tuple
    joints: tuple = ()

    @classmethod
    def from_table(cls, value: Any, where: str) -> "PathFrame":
        """A frame from its spec table.

        Parameters
        ----------
        value : dict
            The spec's table (parsed TOML).
        where : str
            Where the table is, as errors name it.

        Returns
        -------
        PathFrame
            The frame.

        Raises
        ------
        ModelError
            A field missing or not of its form, named.
        """
        t = _table(value, ("name", "parent", "pos", "quat", "joints"), where)
        name, parent = t.get("name"), t.get("parent", "")
        if not isinstance(name, str) or not name or not isinstance(parent, str):
            raise ModelError(f"{where}.name: expected a non-empty name and a parent name, got {name!r}, {parent!r}")
        raw = t.get("joints", [])
        if not isinstance(raw, list):
            raise ModelError(f"{where}.joints: expected an array of tables, got {raw!r}")
        joints = []
        for i, j in enumerate(raw):
            jt = _table(j, ("joint", "axis", "anchor", "ref"), f"{where}.joints[{i}]")
            if not isinstance(jt.get("joint"), str) or not jt["joint"]:
                raise ModelError(f"{where}.joints[{i}].joint: expected a joint name, got {jt.get('joint')!r}")
            axis = np.array(_vec(jt.get("axis"), 3, f"{where}.joints[{i}].axis", unit=True))
            ref = jt.get("ref", 0.0)
            if isinstance(ref, bool) or not isinstance(ref, (int, float)) or not np.isfinite(ref):
                raise ModelError(f"{where}.joints[{i}].ref: expected a finite angle (rad), got {ref!r}")
            joints.append((jt["joint"], tuple(axis / np.linalg.norm(axis)),
                           _vec(jt.get("anchor", [0.0, 0.0, 0.0]), 3, f"{where}.joints[{i}].anchor"), float(ref)))
        return cls(name, parent, _vec(t.get("pos"), 3, f"{where}.pos"),
                   _vec(t.get("quat", [1.0, 0.0, 0.0, 0.0]), 4, f"{where}.quat", unit=True), tuple(joints))

    def to_table(self) -> dict:
        """The spec's table of this frame."""
        return {"name": self.name, "parent": self.parent, "pos": list(self.pos), "quat": list(self.quat),
                "joints": [{"joint": j, "axis": list(a), "anchor": list(c), "ref": r} for j, a, c, r in self.joints]}


@dataclass(frozen=True)
class PathPoint:
    """A point of the tendon's path (module doc): ``kind`` "site", "cylinder", "sphere" or "pulley"; ``name``;
    ``frame``; ``pos`` (3,) m; ``quat`` (4,) (a geom's); ``radius`` m (a geom's) or the divisor (a pulley's);
    ``side``: (frame, pos) of a geom's side site, or None."""

    kind: str
    name: str = ""
    frame: str = ""
    pos: tuple = (0.0, 0.0, 0.0)
    quat: tuple = (1.0, 0.0, 0.0, 0.0)
    radius: float = 0.0
    side: tuple | None = None

    @classmethod
    def from_table(cls, value: Any, where: str) -> "PathPoint":
        """A point from its spec table.

        Parameters
        ----------
        value : dict
            The spec's table (parsed TOML).
        where : str
            Where the table is, as errors name it.

        Returns
        -------
        PathPoint
            The point.

        Raises
        ------
        ModelError
            A field missing or not of its form, named.
        """
        t = _table(value, ("site", "geom", "pulley", "kind", "frame", "pos", "quat", "radius", "side"), where)
        if "pulley" in t:
            return cls("pulley", radius=_positive(t["pulley"], f"{where}.pulley"))
        key = "site" if "site" in t else "geom"
        name, frame = t.get(key), t.get("frame", "")
        if not isinstance(name, str) or not name or not isinstance(frame, str):
            raise ModelError(f"{where}.{key}: expected a site, geom or pulley with its frame, got {dict(t)!r}")
        pos = _vec(t.get("pos"), 3, f"{where}.pos")
        if key == "site":
            return cls("site", name, frame, pos)
        if t.get("kind") not in KINDS:
            raise ModelError(f"{where}.kind: expected one of {', '.join(KINDS)}, got {t.get('kind')!r}")
        side = None
        if "side" in t:
            st = _table(t["side"], ("frame", "pos"), f"{where}.side")
            if not isinstance(st.get("frame", ""), str):
                raise ModelError(f"{where}.side.frame: expected a frame name, got {st.get('frame')!r}")
            side = (st.get("frame", ""), _vec(st.get("pos"), 3, f"{where}.side.pos"))
        return cls(t["kind"], name, frame, pos, _vec(t.get("quat", [1.0, 0.0, 0.0, 0.0]), 4, f"{where}.quat",
                                                     unit=True), _positive(t.get("radius"), f"{where}.radius"), side)

    def to_table(self) -> dict:
        """The spec's table of this point."""
        if self.kind == "pulley":
            return {"pulley": self.radius}
        if self.kind == "site":
            return {"site": self.name, "frame": self.frame, "pos": list(self.pos)}
        out = {"geom": self.name, "kind": self.kind, "frame": self.frame, "pos": list(self.pos),
               "quat": list(self.quat), "radius": self.radius}
        if self.side is not None:
            out["side"] = {"frame": self.side[0], "pos": list(self.side[1])}
        return out


@dataclass(frozen=True)
class SpatialPath:
    """A spatial tendon's geometry (module doc): ``gear``, ``frames`` (PathFrame, parents first) and ``points``
    (PathPoint, a site first and last, a geom between two sites)."""

    gear: float
    frames: tuple
    points: tuple

    def __post_init__(self) -> None:
        known = {""}
        for i, f in enumerate(self.frames):
            if f.parent not in known or f.name in known:
                raise ModelError(f"path.frames[{i}]: frame {f.name!r} repeated, or its parent {f.parent!r} not a "
                                 "frame before it")
            known.add(f.name)
        kinds = [p.kind for p in self.points]
        for i, p in enumerate(self.points):
            if p.frame not in known or (p.side is not None and p.side[0] not in known):
                raise ModelError(f"path.points[{i}].frame: {p.frame!r} is not one of the path's frames")
            geom = p.kind in KINDS
            if geom and not (0 < i < len(kinds) - 1 and kinds[i - 1] == kinds[i + 1] == "site"):
                raise ModelError(f"path.points[{i}]: the wrapping geom {p.name!r} must lie between two sites")
        sites = [k == "site" for k in kinds]
        if len(kinds) < 2 or not (sites[0] and sites[-1]):
            raise ModelError(f"path.points: expected a site first and last, got {kinds!r}")
        if isinstance(self.gear, bool) or not isinstance(self.gear, (int, float)) or not np.isfinite(self.gear) \
                or self.gear == 0:
            raise ModelError(f"path.gear: expected a finite non-zero number, got {self.gear!r}")

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The joints that move the path's frames, in the frames' order."""
        return tuple(dict.fromkeys(j[0] for f in self.frames for j in f.joints))

    @classmethod
    def from_table(cls, value: Any, where: str) -> "SpatialPath":
        """A path from the spec's ``path`` table of a motor.

        Parameters
        ----------
        value : dict
            The spec's ``path`` table (``gear``, ``frames``, ``points``).
        where : str
            The motor, as errors name it ("motor 'name'").

        Returns
        -------
        SpatialPath
            The path.

        Raises
        ------
        ModelError
            A field missing or not of its form, named.
        """
        t = _table(value, ("gear", "frames", "points"), f"{where}.path")
        for k in ("frames", "points"):
            if not isinstance(t.get(k), list):
                raise ModelError(f"{where}.path.{k}: expected an array of tables, got {t.get(k)!r}")
        frames = tuple(PathFrame.from_table(f, f"{where}.path.frames[{i}]") for i, f in enumerate(t["frames"]))
        points = tuple(PathPoint.from_table(p, f"{where}.path.points[{i}]") for i, p in enumerate(t["points"]))
        try:
            return cls(t.get("gear", 1.0), frames, points)
        except ModelError as exc:
            raise ModelError(f"{where}.{exc}") from None

    def to_toml(self) -> str:
        """The spec's ``path`` table as one TOML inline table (``path = ...``'s value)."""
        return _inline(self.to_table())

    def to_table(self) -> dict:
        """The spec's ``path`` table."""
        return {"gear": float(self.gear), "frames": [f.to_table() for f in self.frames],
                "points": [p.to_table() for p in self.points]}

    def length(self, angle: Mapping[str, Any]) -> Any:
        """The tendon's length L (m), a CasADi SX of the joint angles ``angle`` {joint name: SX} (MuJoCo's
        kinematics and ``mj_tendon``'s sum, its pulleys dividing the branches after them).

        Parameters
        ----------
        angle : mapping of str to casadi.SX
            {joint name: its angle, rad} for every joint of :attr:`joint_names`.

        Returns
        -------
        casadi.SX
            L, m.
        """
        import casadi as cs

        from .wrap import wrap_length

        pose = {"": (cs.DM.zeros(3), cs.DM.eye(3))}
        for f in self.frames:
            p, R = pose[f.parent]
            p, R = p + cs.mtimes(R, cs.DM(f.pos)), cs.mtimes(R, cs.DM(quat_matrix(f.quat)))
            for joint, axis, anchor, ref in f.joints:
                a, c, th = cs.DM(axis), cs.DM(anchor), angle[joint] - ref
                K = cs.skew(a)
                Rj = cs.DM.eye(3) + cs.sin(th) * K + (1 - cs.cos(th)) * cs.mtimes(K, K)
                p, R = p + cs.mtimes(R, c - cs.mtimes(Rj, c)), cs.mtimes(R, Rj)
            pose[f.name] = (p, R)
        at = lambda frame, pos: pose[frame][0] + cs.mtimes(pose[frame][1], cs.DM(pos))  # noqa: E731
        total, divisor, k, pts = 0, 1.0, 0, self.points
        while k < len(pts) - 1:
            a, b = pts[k], pts[k + 1]
            if "pulley" in (a.kind, b.kind):
                divisor = a.radius if a.kind == "pulley" else divisor
                k += 1
                continue
            if b.kind in KINDS:
                end = pts[k + 2]
                side = None if b.side is None else at(*b.side)
                R = cs.mtimes(pose[b.frame][1], cs.DM(quat_matrix(b.quat)))
                seg = wrap_length(at(a.frame, a.pos), at(end.frame, end.pos), at(b.frame, b.pos), R, b.radius,
                                  b.kind, side)
                k += 2
            else:
                seg = cs.norm_2(at(b.frame, b.pos) - at(a.frame, a.pos))
                k += 1
            total = total + seg / divisor
        return total


def spatial_path(value: Any, curved: bool, where: str) -> SpatialPath:
    """A motor's ``path`` (a :class:`SpatialPath` or its spec table) validated; ``curved``: the motor also has a
    ``ratio_curve`` (refused).

    Parameters
    ----------
    value : SpatialPath or dict
        The path, or its spec table.
    curved : bool
        The motor also has a ``ratio_curve`` (refused).
    where : str
        The motor, as errors name it.

    Returns
    -------
    SpatialPath
        The path.

    Raises
    ------
    ModelError
        A path with a ratio curve, or a table not of its form, naming ``where`` and the field.
    """
    if curved:
        raise ModelError(f"{where}.path: a motor has a path or a ratio_curve, not both")
    return value if isinstance(value, SpatialPath) else SpatialPath.from_table(value, where)
