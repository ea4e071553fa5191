"""MJCF joint equalities as the URDF's mimic joints: joint1 = b + a joint2 (:mod:`alpes_dyn.model.mimic`).

:func:`joint_couplings` reads MuJoCo's joint equalities (``<equality><joint joint1= joint2= polycoef="b a 0 0
0"/>``) as {tied joint: (joint it follows, a, b)}, the later joint of the tree the tied one (an equality that ties a
parent to its child inverted, q_parent = (q_child - b) / a), a joint tied to a tied joint composed onto the
independent one; every other equality is refused with one line naming it (``<connect>``/``<weld>`` as closed
kinematic loops, the bodies named). :func:`fold_couplings` moves a tied joint's rows of the spec onto the joint it
follows as the same energies and powers, so that the spec names independent joints only (what the library's mimic
model requires); :func:`own_joint_values` undoes it for values written back into the MJCF (``identify --mjcf``).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import ModelError

__all__ = ["fold_couplings", "joint_couplings", "own_joint_values"]


def _name(mujoco, m, kind, i: int, prefix: str) -> str:
    n = mujoco.mj_id2name(m, kind, i)
    return n if n else f"{prefix}{i}"


def joint_couplings(mujoco, m) -> dict[int, tuple[int, float, float]]:
    """{joint1: (joint2, a, b)} of the MJCF's joint equalities, joint1 = b + a joint2 (the URDF's ``<mimic>``):
    ``polycoef="b' a 0 0 0"`` about the joints' reference positions (qpos0), composed into b. Any other equality
    (connect, weld, tendon, a joint held alone, a polynomial of degree > 1, one inactive at start) is refused.

    Parameters
    ----------
    mujoco : module
        The ``mujoco`` module (imported by the caller).
    m : mujoco.MjModel
        The compiled MJCF.

    Returns
    -------
    dict of int to tuple of (int, float, float)
        {joint1 id: (joint2 id, a, b)}, each tied joint onto an independent one (chains composed), a dimensionless
        (for joints of one type), b rad (m for a slide joint).

    Raises
    ------
    ModelError
        An equality other than a linear joint coupling, a joint coupled twice, or a cycle, named.
    """
    out: dict[int, tuple[int, float, float]] = {}
    O = mujoco.mjtObj
    for e in range(m.neq):
        ename = _name(mujoco, m, O.mjOBJ_EQUALITY, e, "equality")
        if int(m.eq_type[e]) in (int(mujoco.mjtEq.mjEQ_CONNECT), int(mujoco.mjtEq.mjEQ_WELD)):
            kind = "connect" if int(m.eq_type[e]) == int(mujoco.mjtEq.mjEQ_CONNECT) else "weld"
            kind_obj = O.mjOBJ_BODY if m.eq_objtype[e] == O.mjOBJ_BODY else O.mjOBJ_SITE
            ends = " and ".join(repr(_name(mujoco, m, kind_obj, int(i), "body"))
                                for i in (m.eq_obj1id[e], m.eq_obj2id[e]))
            raise ModelError(f"mjcf: equality {ename!r} is a {kind} between {ends}: a closed kinematic loop; the "
                             "library models kinematic trees (a joint coupling joint1 = b + a joint2 is the only "
                             "equality imported), not closed linkages")
        if m.eq_type[e] != mujoco.mjtEq.mjEQ_JOINT:
            raise ModelError(f"mjcf: equality {ename!r} is not a joint equality; only joint equalities (a URDF "
                             "<mimic>, joint1 = b + a joint2) are modelled")
        j1, j2 = int(m.eq_obj1id[e]), int(m.eq_obj2id[e])
        c = np.asarray(m.eq_data[e, :5], dtype=float)
        j1name = _name(mujoco, m, O.mjOBJ_JOINT, j1, "joint")
        if j2 < 0 or np.any(c[2:] != 0) or not bool(m.eq_active0[e]):
            raise ModelError(f"mjcf: equality {ename!r} on joint {j1name!r} is not a linear coupling of two joints "
                             "active from the start (joint1 = b + a joint2: give joint2 and polycoef=\"b a 0 0 0\")")
        y0, x0 = float(m.qpos0[m.jnt_qposadr[j1]]), float(m.qpos0[m.jnt_qposadr[j2]])
        a, b = float(c[1]), float(c[0] + y0 - c[1] * x0)
        if j1 < j2 and a != 0:  # a joint tied to a later one (its child): the later follows (the URDF's order)
            j1, j2, a, b = j2, j1, 1.0 / a, -b / a
        if j1 in out:
            raise ModelError(f"mjcf: joint {_name(mujoco, m, O.mjOBJ_JOINT, j1, 'joint')!r} is coupled by two joint "
                             "equalities; one is modelled")
        out[j1] = (j2, a, b)
    for j1 in list(out):  # a joint tied to a tied joint: composed onto the independent one
        j2, a, b = out[j1]
        for _ in range(len(out)):
            if j2 not in out:
                break
            k, a2, b2 = out[j2]
            j2, a, b = k, a * a2, a * b2 + b
        if j2 in out or j2 == j1:
            raise ModelError(f"mjcf: joint {_name(mujoco, m, O.mjOBJ_JOINT, j1, 'joint')!r}'s joint equalities "
                             "form a cycle; tie each joint to one independent joint")
        out[j1] = (j2, a, b)
    return out


def fold_couplings(motors: list, tables: dict, stops: dict, fold: dict) -> list:
    """The spec's rows of joints tied by a joint equality (``fold`` {joint: (primary, a, b)}, q_joint = a q_primary
    + b) moved onto the joint they follow, as the same energies and powers on its coordinate: a motor's ratio
    rho -> a rho (added to the primary's), armature and viscous x a^2, Coulomb x |a|, a spring k (q - r) -> a^2 k
    about (r - b) / a, summed with the primary's own (stiffness and rest angle combined). The tied joint's own
    limit stop is left to its range (named in :func:`not_imported`). A spatial tendon over a tied joint is refused.
    ``tables`` and ``stops`` are changed in place; returns the motors.

    Parameters
    ----------
    motors : list of Motor
        The spec's motors (:class:`~alpes_dyn.model.spec.Motor`); a motor's ratios on a tied joint are moved.
    tables : dict
        The spec's joint tables {table: {joint: value}} (``stiffness`` N m/rad, ``armature`` kg m^2, ``viscous``
        N m s/rad, ``coulomb`` N m, ``rest_angle`` rad); changed in place.
    stops : dict
        The spec's limit stops {joint: ...}; the tied joints' entries are removed in place.
    fold : dict
        {joint: (primary, a, b)}: q_joint = a q_primary + b (b in rad).

    Returns
    -------
    list of Motor
        The motors, a tied joint's ratio moved onto its primary.

    Raises
    ------
    ModelError
        A spatial tendon (curved ratio) over a tied joint.
    """
    out = []
    for mo in motors:
        tied = [j for j in mo.joints if j in fold]
        bent = [j for j in tied if j in mo.ratio_curve] + [j for j in (mo.path.joint_names if mo.path else ()) if j in fold]
        if bent:
            raise ModelError(f"mjcf: actuator {mo.name!r}'s spatial tendon crosses joint {bent[0]!r}, which a joint "
                             f"equality ties to {fold[bent[0]][0]!r}; a curved ratio on a tied joint is not modelled")
        joints = dict(mo.joints)
        for j in tied:
            k, a, _ = fold[j]
            joints[k] = joints.get(k, 0.0) + a * joints.pop(j)
        out.append(dataclasses.replace(mo, joints=joints) if tied else mo)
    rest = tables.setdefault("rest_angle", {})
    for j, (k, a, b) in fold.items():
        for key, w in (("armature", a * a), ("viscous", a * a), ("coulomb", abs(a))):
            v = tables[key].pop(j, 0.0)
            if v * w:
                tables[key][k] = tables[key].get(k, 0.0) + w * v
        kj, rj = tables["stiffness"].pop(j, 0.0), rest.pop(j, 0.0)
        if kj * a:
            kk = tables["stiffness"].get(k, 0.0)
            K = kk + a * a * kj
            r = (kk * rest.get(k, 0.0) + a * kj * (rj - b)) / K
            tables["stiffness"][k] = K
            rest.pop(k, None)
            if r != 0:
                rest[k] = r
        stops.pop(j, None)
    if not rest:
        del tables["rest_angle"]
    return out


def own_joint_values(mujoco, m, joints: dict, rest: dict) -> dict:
    """The inverse of :func:`fold_couplings` for the values written back into the MJCF: ``joints`` {joint: {MJCF
    attribute: value}} of the spec's rows (``stiffness``, ``damping``, ``frictionloss``, ``armature``: on a joint
    others are tied to, the sums :func:`fold_couplings` made) as the joint's own attributes, the tied joints' own
    values as compiled in ``m`` taken off (a^2 for armature and damping, |a| for friction; a spring K about the spec's
    rest angle ``rest`` {joint: rad} less a^2 k_l about (r_l - b) / a gives the joint's own ``stiffness`` and
    ``springref``). Returns a new dict; :class:`~alpes_dyn.ModelError` where a value falls below what the tied joints
    hold (not written).

    Parameters
    ----------
    mujoco : module
        The ``mujoco`` module (imported by the caller).
    m : mujoco.MjModel
        The compiled MJCF.
    joints : dict
        {joint: {MJCF attribute: value}} of the spec's rows (``stiffness`` N m/rad, ``damping`` N m s/rad,
        ``frictionloss`` N m, ``armature`` kg m^2).
    rest : dict
        The spec's rest angles {joint: rad}.

    Returns
    -------
    dict
        A new {joint: {attribute: value}} with each joint's own values.

    Raises
    ------
    ModelError
        A value below what the tied joints hold, named.
    """
    O = mujoco.mjtObj
    tied: dict[str, list] = {}
    for j1, (j2, a, b) in joint_couplings(mujoco, m).items():
        tied.setdefault(_name(mujoco, m, O.mjOBJ_JOINT, j2, "joint"), []).append((j1, a, b))
    out = {j: dict(v) for j, v in joints.items()}
    for k, ties in tied.items():
        vals = out.get(k)
        if not vals:
            continue
        for attr, arr, w in (("damping", m.dof_damping, lambda a: a * a), ("frictionloss", m.dof_frictionloss, abs),
                             ("armature", m.dof_armature, lambda a: a * a)):
            if attr in vals:
                theirs = sum(w(a) * float(arr[m.jnt_dofadr[j]]) for j, a, _ in ties)
                vals[attr] = _own(k, attr, vals[attr], theirs)
        if "stiffness" in vals:
            K, r = vals["stiffness"], float(rest.get(k, 0.0))
            theirs = sum(a * a * float(m.jnt_stiffness[j]) for j, a, _ in ties)
            own = _own(k, "stiffness", K, theirs)
            vals["stiffness"] = own
            if own > 0:
                vals["springref"] = (K * r - sum(a * float(m.jnt_stiffness[j]) * (float(m.qpos_spring[
                    m.jnt_qposadr[j]]) - b) for j, a, b in ties)) / own
            else:
                vals.pop("springref", None)
    return out


def _own(joint: str, attr: str, total: float, theirs: float) -> float:
    """total - theirs, 0 where it is within rounding of 0; ModelError below."""
    own = total - theirs
    if abs(own) <= 1e-12 * max(abs(total), abs(theirs)):
        return 0.0
    if own < 0:
        raise ModelError(f"identified mjcf: joint {joint!r}'s {attr} {total:.6g} is below what the joints tied to it "
                         f"hold ({theirs:.6g}); not written")
    return own
