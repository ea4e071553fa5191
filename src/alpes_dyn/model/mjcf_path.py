"""An MJCF spatial tendon read as its geometry, the spec's ``path`` (:mod:`alpes_dyn.model.spatial_path`).

The import keeps the per-joint polynomials (:mod:`alpes_dyn.model.mjcf_spatial`) where they are exact; where they
cannot follow the tendon (it touches, leaves or changes side of a wrapping geom inside a joint's range, or a segment
spans two joints) it reads the tendon's sites, wrapping geoms, side sites and pulleys, and the bodies they ride on,
from the compiled MuJoCo model, and checks the result against MuJoCo's ``ten_length`` and ``ten_J``
(:func:`check_path`). Refused, the tendon and the element named: a side site inside its geom (MuJoCo then solves
for the path by Newton's method to 1e-6, no closed form), a body on the path moved by a joint other than a hinge.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError
from .spatial_path import PathFrame, PathPoint, SpatialPath

__all__ = ["PATH_CHECKS", "spatial_path", "check_path"]

PATH_CHECKS = 256
"""Random states over the joints' box (a fixed seed) at which the import checks a path against MuJoCo."""

AGREEMENT = 1e-9
"""The largest relative error of the path's length and ratios against MuJoCo's at which the import accepts it."""


def _frames(mujoco, m, bodies: set, joint_names: list, where: str) -> tuple[tuple, dict]:
    """The frames of ``bodies`` and their ancestors (parents first) and the frame name of each body id."""
    O = mujoco.mjtObj
    chain: set = set()
    for b in bodies:
        while b > 0:
            chain.add(b)
            b = int(m.body_parentid[b])
    names = {0: ""}
    for b in sorted(chain):  # MuJoCo numbers a parent before its children
        names[b] = mujoco.mj_id2name(m, O.mjOBJ_BODY, b) or f"body{b}"
    frames = []
    for b in sorted(chain):
        joints = []
        for j in range(int(m.body_jntadr[b]), int(m.body_jntadr[b]) + int(m.body_jntnum[b])):
            if m.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE:
                raise ModelError(f"mjcf: {where}: joint {joint_names[j]!r} on its path is not a hinge (only hinges "
                                 "move a spatial tendon's path in the spec): not imported")
            joints.append({"joint": joint_names[j], "axis": m.jnt_axis[j].tolist(), "anchor": m.jnt_pos[j].tolist(),
                           "ref": float(m.qpos0[m.jnt_qposadr[j]])})
        frames.append(PathFrame.from_table({"name": names[b], "parent": names[int(m.body_parentid[b])],
                                            "pos": m.body_pos[b].tolist(), "quat": m.body_quat[b].tolist(),
                                            "joints": joints}, where))
    return tuple(frames), names


def spatial_path(mujoco, m, t: int, gear: float, joint_names: list, where: str) -> SpatialPath:
    """The spatial tendon ``t`` of MuJoCo model ``m`` as a :class:`SpatialPath` of gear ``gear``.

    Parameters
    ----------
    mujoco : module
        The ``mujoco`` module.
    m : mujoco.MjModel
        The compiled model.
    t : int
        The tendon's id.
    gear : float
        The actuator's gear (rad of motor per m of tendon).
    joint_names : list of str
        The names of m's joints, in order.
    where : str
        The tendon and actuator as errors name them.

    Returns
    -------
    SpatialPath
        Its frames and points; :class:`~alpes_dyn.errors.ModelError` naming the element for a side site inside its
        geom or a path moved by a joint other than a hinge.
    """
    O, W = mujoco.mjtObj, mujoco.mjtWrap
    adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
    bodies, raw = set(), []
    for w in range(adr, adr + num):
        kind, obj = int(m.wrap_type[w]), int(m.wrap_objid[w])
        if kind == W.mjWRAP_PULLEY:
            raw.append(("pulley", float(m.wrap_prm[w])))
        elif kind == W.mjWRAP_SITE:
            bodies.add(int(m.site_bodyid[obj]))
            raw.append(("site", obj))
        else:
            side = int(round(float(m.wrap_prm[w])))
            bodies.add(int(m.geom_bodyid[obj]))
            if side >= 0:
                bodies.add(int(m.site_bodyid[side]))
            raw.append(("sphere" if kind == W.mjWRAP_SPHERE else "cylinder", obj, side))
    frames, names = _frames(mujoco, m, bodies, joint_names, where)
    points = []
    for item in raw:
        if item[0] == "pulley":
            points.append(PathPoint("pulley", radius=item[1]))
        elif item[0] == "site":
            s = item[1]
            points.append(PathPoint("site", mujoco.mj_id2name(m, O.mjOBJ_SITE, s) or f"site{s}",
                                    names[int(m.site_bodyid[s])], tuple(m.site_pos[s].tolist())))
        else:
            points.append(_geom(mujoco, m, item, names, where))
    return SpatialPath(float(gear), frames, tuple(points))


def _geom(mujoco, m, item: tuple, names: dict, where: str) -> PathPoint:
    """A wrapping geom's point; a side site inside the geom refused (where both ride on one body)."""
    kind, g, side = item
    gname = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}"
    radius = float(m.geom_size[g, 0])
    sd = None
    if side >= 0:
        sd = (names[int(m.site_bodyid[side])], tuple(m.site_pos[side].tolist()))
        if int(m.site_bodyid[side]) == int(m.geom_bodyid[g]):
            from .spatial_path import quat_matrix

            local = quat_matrix(m.geom_quat[g]).T @ (m.site_pos[side] - m.geom_pos[g])
            if np.linalg.norm(local) < radius:
                raise ModelError(_inside(mujoco, m, side, gname, where))
    return PathPoint(kind, gname, names[int(m.geom_bodyid[g])], tuple(m.geom_pos[g].tolist()),
                     tuple(m.geom_quat[g].tolist()), radius, sd)


def _inside(mujoco, m, side: int, gname: str, where: str) -> str:
    """The refusal of a side site inside its wrapping geom."""
    sname = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, side) or f"site{side}"
    return (f"mjcf: {where}: its side site {sname!r} is inside its wrapping geom {gname!r} (MuJoCo then finds the "
            "path by Newton's method to 1e-6, which has no closed form): not imported")


def check_path(mujoco, m, t: int, path: SpatialPath, joint_names: list, states: np.ndarray, where: str) -> float:
    """The path's largest relative error against MuJoCo's ``ten_length`` and ``ten_J`` at ``states`` (N, nq) (qpos
    of hinges); a :class:`~alpes_dyn.errors.ModelError` naming the tendon where it exceeds :data:`AGREEMENT` (or the
    side site where MuJoCo found it inside the geom: :func:`spatial_path`'s refusal).

    Parameters
    ----------
    mujoco : module
        The ``mujoco`` module.
    m : mujoco.MjModel
        The compiled model.
    t : int
        The tendon's id.
    path : SpatialPath
        The path read from it (:func:`spatial_path`).
    joint_names : list of str
        The names of m's joints, in order.
    states : numpy.ndarray, shape (N, nq)
        The hinges' qpos (rad) at which the path is compared.
    where : str
        The tendon and actuator as errors name them.

    Returns
    -------
    float
        The largest relative error of the length and the moment arms (at most :data:`AGREEMENT`).

    Raises
    ------
    ModelError
        The error exceeds :data:`AGREEMENT`, or a side site lies inside its geom.
    """
    import casadi as cs

    from .mjcf_spatial import tendon_jacobian

    q = cs.SX.sym("q", m.njnt)
    L = path.length({n: q[i] for i, n in enumerate(joint_names)})
    f = cs.Function("f", [q], [L, cs.jacobian(L, q)]).map(len(states))
    Ls, Js = (np.asarray(x) for x in f(np.asarray(states, dtype=float).T))
    d = mujoco.MjData(m)
    err = 0.0
    adr = int(m.tendon_adr[t])
    geoms = (mujoco.mjtWrap.mjWRAP_SPHERE, mujoco.mjtWrap.mjWRAP_CYLINDER)
    sides = [(int(m.wrap_objid[w]), int(round(float(m.wrap_prm[w])))) for w in range(adr, adr + int(m.tendon_num[t]))
             if int(m.wrap_type[w]) in geoms and m.wrap_prm[w] >= 0]
    for k, qk in enumerate(states):  # the import's check against MuJoCo, one state at a time
        d.qpos[:] = qk
        mujoco.mj_fwdPosition(m, d)
        for g, s in sides:  # a side site on another body than its geom's, inside it here
            if np.linalg.norm(d.geom_xmat[g].reshape(3, 3).T @ (d.site_xpos[s] - d.geom_xpos[g])) < m.geom_size[g, 0]:
                raise ModelError(_inside(mujoco, m, s, mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) or f"geom{g}",
                                         where))
        J = tendon_jacobian(m, d)[t][m.jnt_dofadr]
        scale = max(float(np.max(np.abs(J))), 1e-300)
        err = max(err, abs(Ls[0, k] - d.ten_length[t]) / max(abs(d.ten_length[t]), 1e-300),
                  float(np.max(np.abs(Js[:, k * m.njnt:(k + 1) * m.njnt].ravel() - J))) / scale)
    if not err <= AGREEMENT:
        raise ModelError(f"mjcf: {where}: its path as read ({len(path.points)} points) is {err:.2g} off MuJoCo's "
                         "length or moment arms (relative): not imported")
    return err
