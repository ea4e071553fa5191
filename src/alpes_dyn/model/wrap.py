"""MuJoCo's tendon wrapping over a cylinder or a sphere, in closed form (CasADi), every branch an ``if_else``.

A spatial tendon's segment site - geom - site (MuJoCo's ``mju_wrap``, engine_util_misc.c) goes straight from site to
site where that line misses the geom (or passes it on the side away from its side site), and otherwise leaves the
straight line at a tangent point t0, winds on the geom's surface and leaves it at a tangent point t1:

    l = |x0 - t0| + w + |t1 - x1|

w the arc (a great circle of the sphere; on a cylinder the arc of its cross-section, climbing along the axis as a
helix, so that the whole path is straight on the unrolled surface). The tangent points are the closed form of the 2D
problem in the geom's plane (the cylinder's cross-section, or the sphere's plane through x0, x1 and its centre): of
the two tangent pairs, the shorter that does not cross itself, and with a side site that lies within the angle of
the two end points (seen from the geom's centre), the pair that goes round on the side site's side; a line that misses
the geom stays straight unless such a side site lies across it. Written with MuJoCo's comparisons, so that the length
is MuJoCo's at every configuration on either side of every switch (touching or not, which side), and its derivative by
AD is MuJoCo's moment arm (the tangent points are stationary: the envelope theorem). The side site's rule is MuJoCo
4's as measured against its ``ten_length`` (MuJoCo 3's ``mju_wrap`` took the pair whose chord's midpoint is nearer
the side site, and wrapped a missing line whenever the side site was across it): on 17,720 random placements of the
end and side sites about a tilted cylinder and a sphere, lengths agree to 3e-16 m and moment arms to 1.2e-14
(``tests/test_spatial_path.py`` draws 1,500). The functions take CasADi SX columns.

Not represented: a side site inside the geom (MuJoCo then iterates Newton's method, ``wrap_inside``, to 1e-6: no
closed form; :func:`~alpes_dyn.model.mjcf_path.spatial_path` refuses it, naming the tendon and the geom).
"""

from __future__ import annotations

from typing import Any

import casadi as cs

__all__ = ["MINVAL", "wrap_length"]

MINVAL = 1e-15
"""MuJoCo's mjMINVAL: the smallest length or determinant its wrapping treats as non-zero."""


def _intersect(p1: Any, p2: Any, p3: Any, p4: Any) -> Any:
    """1 where the 2D segments p1-p2 and p3-p4 cross (MuJoCo's ``is_intersect``), else 0 (SX)."""
    det = (p4[1] - p3[1]) * (p2[0] - p1[0]) - (p4[0] - p3[0]) * (p2[1] - p1[1])
    safe = cs.if_else(cs.fabs(det) < MINVAL, 1.0, det)
    a = ((p4[0] - p3[0]) * (p1[1] - p3[1]) - (p4[1] - p3[1]) * (p1[0] - p3[0])) / safe
    b = ((p2[0] - p1[0]) * (p1[1] - p3[1]) - (p2[1] - p1[1]) * (p1[0] - p3[0])) / safe
    inside = cs.logic_and(cs.logic_and(a >= 0, a <= 1), cs.logic_and(b >= 0, b <= 1))
    return cs.logic_and(cs.fabs(det) >= MINVAL, inside)


def _root(x: Any) -> Any:
    """sqrt(x) where x > 0, else 1: a branch not taken (a point inside the circle) then gives neither a NaN nor an
    infinite derivative, which AD through ``if_else`` would carry into the branch taken (0 * NaN)."""
    return cs.sqrt(cs.if_else(x > 0, x, 1.0))


def _arc(p0: Any, p1: Any, second: Any, radius: float) -> Any:
    """The arc's length from tangent point p0 to p1 (2D) on a circle of ``radius`` (MuJoCo's ``length_circle``):
    the angle between them, taken the long way round where the turn's sign disagrees with the solution's
    (``second``: 1 for MuJoCo's second solution)."""
    cross = p0[1] * p1[0] - p0[0] * p1[1]
    angle = cs.atan2(cs.fabs(cross), p0[0] * p1[0] + p0[1] * p1[1])  # acos of the normalised dot, better conditioned
    flip = cs.if_else(second, cross > 0, cross < 0)
    return radius * cs.if_else(flip, 2 * cs.pi - angle, angle)


def _circle(end: Any, side: Any, radius: float) -> tuple[Any, Any, Any]:
    """MuJoCo's ``wrap_circle``: (1 where the path wraps, the arc's length, the tangent points (4,)) for the 2D end
    points ``end`` (4,) in the circle's frame and the side point ``side`` (2,) (None: no side site)."""
    e0, e1 = end[0:2], end[2:4]
    sqlen0, sqlen1, sqrad = cs.dot(e0, e0), cs.dot(e1, e1), radius * radius
    dif = e1 - e0
    dd = cs.dot(dif, dif)
    a = cs.fmin(cs.fmax(-cs.dot(dif, e0) / cs.if_else(dd < MINVAL, 1.0, dd), 0), 1)
    near = a * dif + e0
    missed = cs.dot(near, near) > sqrad
    between, turn = 0, 0
    if side is not None:  # the side site counts where it lies within the angle of the end points (MuJoCo 4's rule)
        turn = e0[0] * side[1] - e0[1] * side[0]  # its turn from x0: the way round the path wraps
        between = turn * (side[0] * e1[1] - side[1] * e1[0]) >= 0
        missed = cs.logic_and(missed, cs.logic_or(cs.dot(side, near) >= 0, cs.logic_not(between)))
    off = cs.logic_or(cs.logic_or(sqlen0 < sqrad, sqlen1 < sqrad), cs.logic_or(dd < MINVAL, missed))
    sq0, sq1 = _root(sqlen0 - sqrad), _root(sqlen1 - sqrad)
    sols, goods = [], []
    for sgn in (1, -1):
        s0 = cs.vertcat(e0[0] * sqrad + sgn * radius * e0[1] * sq0, e0[1] * sqrad - sgn * radius * e0[0] * sq0) / sqlen0
        s1 = cs.vertcat(e1[0] * sqrad - sgn * radius * e1[1] * sq1, e1[1] * sqrad + sgn * radius * e1[0] * sq1) / sqlen1
        good = -cs.dot(s0 - s1, s0 - s1)  # the shorter (without a side site, or one outside the ends' angle)
        goods.append(cs.if_else(_intersect(e0, s0, e1, s1), -10000.0, good))
        sols.append(cs.vertcat(s0, s1))
    first = cs.if_else(between, turn < 0, goods[0] > goods[1])  # with one between them: round its side
    pnt = cs.if_else(first, sols[0], sols[1])
    off = cs.logic_or(off, _intersect(e0, pnt[0:2], e1, pnt[2:4]))
    return cs.logic_not(off), _arc(pnt[0:2], pnt[2:4], cs.logic_not(first), radius), pnt


def _unit(v: Any) -> Any:
    """v / |v| (SX)."""
    return v / cs.norm_2(v)


def wrap_length(x0: Any, x1: Any, xpos: Any, xmat: Any, radius: float, kind: str, side: Any = None) -> Any:
    """The length of a tendon's segment from point x0 to point x1 (3,) over a wrapping geom (module doc), m.

    Parameters
    ----------
    x0, x1 : casadi.SX
        (3,) the segment's end points in the world frame, m.
    xpos, xmat : casadi.SX
        The geom's centre (3,), m, and orientation (3, 3) (its columns its axes in the world frame).
    radius : float
        The geom's radius, m (> 0).
    kind : str
        "cylinder" (wrapped about its z axis) or "sphere".
    side : casadi.SX or None
        (3,) the side site in the world frame, or None.

    Returns
    -------
    casadi.SX
        The length: straight where the path does not wrap, tangent - arc - tangent where it does (MuJoCo's).
    """
    p0, p1 = cs.mtimes(xmat.T, x0 - xpos), cs.mtimes(xmat.T, x1 - xpos)
    if kind == "sphere":
        ax0 = _unit(p0)
        ax1 = _unit(cs.cross(_unit(cs.cross(p0, p1)), ax0))
    else:
        ax0, ax1 = cs.DM([1.0, 0.0, 0.0]), cs.DM([0.0, 1.0, 0.0])
    d = cs.vertcat(cs.dot(p0, ax0), cs.dot(p0, ax1), cs.dot(p1, ax0), cs.dot(p1, ax1))
    sd = None
    if side is not None:
        s = cs.mtimes(xmat.T, side - xpos)
        sd = radius * _unit(cs.vertcat(cs.dot(s, ax0), cs.dot(s, ax1)))
    wraps, w, pnt = _circle(d, sd, radius)
    t0, t1 = ax0 * pnt[0] + ax1 * pnt[1], ax0 * pnt[2] + ax1 * pnt[3]
    if kind == "cylinder":
        l0, l1 = cs.norm_2(p0[0:2] - t0[0:2]), cs.norm_2(p1[0:2] - t1[0:2])
        total = l0 + w + l1
        z0 = p0[2] + (p1[2] - p0[2]) * l0 / total
        z1 = p0[2] + (p1[2] - p0[2]) * (l0 + w) / total
        w = cs.sqrt(w * w + (z1 - z0) * (z1 - z0))
        t0, t1 = cs.vertcat(t0[0:2], z0), cs.vertcat(t1[0:2], z1)
    wrapped = cs.norm_2(p0 - t0) + w + cs.norm_2(t1 - p1)
    too_close = cs.logic_or(cs.norm_2(p0) < MINVAL, cs.norm_2(p1) < MINVAL)
    return cs.if_else(cs.logic_and(wraps, cs.logic_not(too_close)), wrapped, cs.norm_2(x1 - x0))
