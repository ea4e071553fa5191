"""A sub-model of a URDF + spec robot: the branches a set of motors drives, the other branches removed.

``subtree_model(model, ["index"])`` (or :meth:`Model.subtree <alpes_dyn.model.robot.Model.subtree>`) keeps every
joint of the branches from the base that hold a joint those motors drive (on the Allegro hand the index finger:
its ab/adduction joint ``joint_0.0`` and its three flexion joints), and every motor that drives any of those joints
(the index tendon and ``index_abduction``); the other branches go from the URDF (their joints, links and every
link below them) and from the spec (their motors, their joints' springs, friction, armature and rest angles).

A *branch* is a movable joint whose parent link is the base (the root link or a link fixed to it) with every
joint below it. Why the removed branches cannot change the kept joints' dynamics on a fixed base:

* the mass matrix is block diagonal between branches: A_ij = S_i^T I^c_k S_j is non-zero only where one of
  joints i, j supports the other (k the lower one; composite-rigid-body algorithm), and two joints of two
  branches have no joint in common above them: their common ancestor is the base, which does not move;
* the bias torques of a kept joint, C(q, qd) qd + gravity (recursive Newton-Euler), are the projections of the
  spatial forces of the bodies below it, whose velocities and accelerations come from the joints above them: all
  in its own branch, and the base's motion, zero on a fixed base, is all a branch would see of another one;
* springs, friction and armature are per joint; a motor's rotor inertia J_m S_k^T S_k and its tendon's
  compliance couple only the joints that motor drives.

A floating base (the robot's own motion shared by every branch) is what would couple them; the models here are
fixed-base trees of 1-DoF joints (a URDF's floating or planar joint is refused when the model is built). What
could still couple two branches is therefore refused, as one line naming the motor and the shared joint: a
motor that drives joints of the kept branches and of a removed one (its tendon's torque and rotor inertia act on
both), and a URDF ``<mimic>`` joint and the joint it follows in different sets (the constraint carries one
branch's inertia onto the other's coordinates). :func:`closed_motors` gives the motors of the fewest branches
that nothing couples with the rest, whose sub-model is never refused (what ``identify --chain`` and ``estimate
--chain`` fit and observe on a URDF robot).

``tests/test_subtree.py`` checks the sub-model's A, bias and gravity torques and forward dynamics against the
full Pinocchio model's rows and columns of the kept joints at random states (1e-12).
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from typing import Any, Sequence

import numpy as np

from ..errors import ModelError
from .mimic import tree_model
from .spec import IDENTIFIED_TABLES, JOINT_TABLES, REST_TABLE, TransmissionSpec

__all__ = ["subtree_model", "branch_joints", "closed_motors", "subtree_spec", "subtree_urdf"]


def _motor_set(model: Any, motors: str | Sequence[str]) -> tuple[str, ...]:
    """``motors`` (one name or a sequence of names) checked against ``model``'s motors; ModelError naming the
    field."""
    if not all(hasattr(model, a) for a in ("spec", "motor_names", "joint_names", "mimic", "urdf")):
        # (an alpes_dyn Model by what this module reads of it: robot.py imports this module, not the other way)
        raise ModelError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
    if model.spec is None or not model.motor_names:
        raise ModelError(f"motors: model {model.name!r} has no spec with motors; a sub-model is chosen by the "
                         "motors that drive its branches")
    names = (motors,) if isinstance(motors, str) else motors
    if not isinstance(names, (list, tuple)) or not names or not all(isinstance(m, str) for m in names):
        raise ModelError(f"motors: expected a motor name or a non-empty list of motor names, got {motors!r:.80}")
    for m in names:
        if m not in model.motor_names:
            raise ModelError(f"motors: unknown motor {m!r} (motors: {', '.join(model.motor_names)})")
    return tuple(dict.fromkeys(names))


def _top_branch(pm: Any) -> dict[str, int]:
    """Each moving joint of the Pinocchio model ``pm`` by name -> the id of its branch's first joint (the
    joint whose parent is the fixed base, id 0)."""
    out = {}
    for jid in range(1, pm.njoints):
        top = jid
        while pm.parents[top] != 0:
            top = pm.parents[top]
        out[pm.names[jid]] = top
    return out


def _given_branches(model: Any, given: tuple[str, ...]) -> tuple[dict[str, int], set[int]]:
    """(:func:`_top_branch` of the whole tree, mimic joints included; the branches holding a joint the motors
    ``given`` drive)."""
    top = _top_branch(tree_model(model))
    spec_motors = {m.name: m for m in model.spec.motors}
    return top, {top[j] for m in given for j in spec_motors[m].joints}


def _branches(model: Any, motors: str | Sequence[str]) -> tuple[set[str], tuple[str, ...], tuple[str, ...]]:
    """(the kept joints of the whole tree, mimic joints included; the kept independent joints in
    ``model.joint_names`` order; the kept motors in ``model.motor_names`` order): :func:`branch_joints`."""
    given = _motor_set(model, motors)
    top, tops = _given_branches(model, given)
    kept = {j for j, t in top.items() if t in tops}
    label = ", ".join(given)
    for m in model.spec.motors:
        inside = [j for j in m.joints if j in kept]
        outside = [j for j in m.joints if j not in kept]
        if inside and outside:
            raise ModelError(f"motors {label}: motor {m.name!r} drives joint {inside[0]!r} of their branches and "
                             f"joint {outside[0]!r} of another branch; a sub-model would cut its tendon (name "
                             f"{m.name!r} too to keep both branches)")
    if model.mimic is not None:
        for mj in model.mimic.mimics:
            if (mj.name in kept) != (mj.primary in kept):
                inside, outside = (mj.name, mj.primary) if mj.name in kept else (mj.primary, mj.name)
                raise ModelError(f"motors {label}: mimic joint {mj.name!r} follows {mj.primary!r}, and joint "
                                 f"{inside!r} is in their branches, {outside!r} in another; a sub-model would "
                                 "cut the constraint")
    joints = tuple(j for j in model.joint_names if j in kept)
    kept_motors = tuple(m.name for m in model.spec.motors if any(j in kept for j in m.joints))
    return kept, joints, kept_motors


def closed_motors(model: Any, motors: str | Sequence[str]) -> tuple[str, ...]:
    """The motors (``model.motor_names`` order) of the fewest branches that hold the joints ``motors`` drive and
    that nothing couples with the others: the branches of ``motors``, then those of every motor driving one of
    their joints and of every mimic joint following one of them (or followed by one), until none is added; the whole
    robot's motors at worst. :func:`subtree_model` of them is never refused (``identify --chain`` and ``estimate
    --chain`` on a URDF: a chain whose tendon or mimic reaches into another branch takes that branch along).

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a spec.
    motors : str or sequence of str
        The motors' names (one name or several).

    Returns
    -------
    tuple of str
        The motors of the closed branches.

    Raises
    ------
    ModelError
        An unknown motor, named.
    """
    given = _motor_set(model, motors)
    top, tops = _given_branches(model, given)
    links = [set(m.joints) for m in model.spec.motors]
    links += [{mj.name, mj.primary} for mj in (model.mimic.mimics if model.mimic is not None else ())]
    grown = True
    while grown:
        grown = False
        for joints in links:
            ts = {top[j] for j in joints}
            if ts & tops and not ts <= tops:
                tops |= ts
                grown = True
    return tuple(m.name for m in model.spec.motors if any(top[j] in tops for j in m.joints))


def branch_joints(model: Any, motors: str | Sequence[str]) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(joints, motors) of the sub-model of ``motors``: every joint (``model.joint_names`` order) of the branches
    holding a joint those motors drive, and every motor (``model.motor_names`` order) that drives one of them.
    :class:`~alpes_dyn.ModelError` where a motor drives joints both in and out of those branches, or a mimic
    joint and the joint it follows are on different sides (the module doc).

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a spec.
    motors : str or sequence of str
        The motors' names (one name or several).

    Returns
    -------
    tuple of (tuple of str, tuple of str)
        The joints and the motors.
    """
    _, joints, kept_motors = _branches(model, motors)
    return joints, kept_motors


def subtree_urdf(urdf: str, joints: Sequence[str], all_joints: Sequence[str]) -> str:
    """The URDF text ``urdf`` with every movable joint of ``all_joints`` not in ``joints`` removed together
    with its child link and everything below it (joints, links, and the ``<transmission>`` and ``<gazebo>``
    elements that name them).

    Parameters
    ----------
    urdf : str
        The URDF text.
    joints : sequence of str
        The joints kept: whole branches (:func:`branch_joints`).
    all_joints : sequence of str
        Every movable joint of the URDF.

    Returns
    -------
    str
        The URDF text of the kept branches.
    """
    root = ET.fromstring(urdf)
    drop_joints = set(all_joints) - set(joints)
    children: dict[str, list[ET.Element]] = {}
    for j in root.findall("joint"):
        parent = j.find("parent")
        if parent is not None:
            children.setdefault(parent.get("link", ""), []).append(j)
    dead_links: set[str] = set()
    dead_joints: set[str] = set()
    stack = [j for j in root.findall("joint") if j.get("name") in drop_joints]
    while stack:
        j = stack.pop()
        if j.get("name") in dead_joints:
            continue
        dead_joints.add(j.get("name", ""))
        child = j.find("child")
        link = child.get("link", "") if child is not None else ""
        dead_links.add(link)
        stack += children.get(link, [])
    dead = dead_links | dead_joints
    for el in list(root):
        name = el.get("name")
        if (el.tag == "link" and name in dead_links) or (el.tag == "joint" and name in dead_joints):
            root.remove(el)
        elif el.tag == "gazebo" and el.get("reference") in dead:
            root.remove(el)
        elif el.tag == "transmission" and any(x.get("name") in dead for x in el.iter("joint")):
            root.remove(el)
    return ET.tostring(root, encoding="unicode")


def subtree_spec(spec: TransmissionSpec, joints: Sequence[str], motors: Sequence[str],
                 frames: Sequence[str]) -> TransmissionSpec:
    """``spec`` restricted to ``motors`` and ``joints``: their ``[[motor]]`` entries, the per-joint tables' and
    the rest angles' and the ``[stops]`` rows of those joints (its robot-wide values kept), the tips among ``frames`` (None where none is left), the
    ``[identified]`` section's rows of those joints and motors (its record kept).

    Parameters
    ----------
    spec : TransmissionSpec
        The whole robot's spec.
    joints : sequence of str
        The joints kept.
    motors : sequence of str
        The motors kept.
    frames : sequence of str
        The frames left in the sub-model's URDF (the tips kept among them).

    Returns
    -------
    TransmissionSpec
        The restricted spec.
    """
    keep_j, keep_m = set(joints), set(motors)
    tables = {t: {j: x for j, x in getattr(spec, t).items() if j in keep_j} for t in JOINT_TABLES + (REST_TABLE,)}
    tips = None
    if spec.tips is not None:
        tips = tuple(t for t in spec.tips if t in set(frames)) or None
    identified = None
    if spec.identified is not None:
        identified = {"record": dict(spec.identified["record"])}
        for t in IDENTIFIED_TABLES:
            rows = {k: v for k, v in (spec.identified.get(t) or {}).items()
                    if k in (keep_j if t in JOINT_TABLES else keep_m)}
            if rows:
                identified[t] = rows
    stops = None
    if spec.stops is not None:  # the robot-wide values, and the kept joints' own
        stops = {k: x for k, x in spec.stops.items() if k != "joints"}
        stops["joints"] = {j: dict(e) for j, e in spec.stops["joints"].items() if j in keep_j}
        stops = stops if len(stops) > 1 or stops["joints"] else None
    return dataclasses.replace(spec, motors=tuple(m for m in spec.motors if m.name in keep_m), tips=tips,
                               identified=identified, stops=stops, **tables)


def subtree_model(model: Any, motors: str | Sequence[str]) -> Any:
    """The sub-model of ``model`` (a :class:`~alpes_dyn.Model` with a spec) on the branches ``motors`` drive (the
    module doc): a new Model of the same class, its URDF without the other branches, its spec restricted
    (:func:`subtree_spec`), the same gravity, named ``<model name>[<motors>]``. Its joints are
    :func:`branch_joints`'s, in the full model's order; where they are all of them, the sub-model is the whole
    robot again. :class:`~alpes_dyn.ModelError` naming the motor and the joint for what would couple the kept
    branches with a removed one.

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a spec.
    motors : str or sequence of str
        The motors' names (one name or several).

    Returns
    -------
    alpes_dyn.Model
        The sub-model.

    Raises
    ------
    ModelError
        An unknown motor, or what would couple the kept branches with a removed one, naming the motor and the joint.
    """
    kept_full, joints, kept = _branches(model, motors)
    full = tree_model(model)
    urdf = subtree_urdf(model.urdf, tuple(kept_full), tuple(full.names[1:]))
    ids = {full.getJointId(j) for j in kept_full} | {0}  # the frames left: on a kept joint or on the base
    frames = [f.name for f in full.frames if f.parentJoint in ids]
    spec = subtree_spec(model.spec, joints, kept, frames)
    gravity = None if spec.gravity is not None else np.asarray(model.gravity, dtype=float)
    name = f"{model.name}[{','.join(_motor_set(model, motors))}]"
    sub = type(model)(urdf, spec, gravity, name=name[:200], spring=model.spring, check_inertia=model.check_inertia)
    if sub.joint_names != joints:  # the URDF parser's order is the full model's, restricted: a guard, not a case
        raise ModelError(f"sub-model: joints {sub.joint_names} are not the kept {joints}")
    return sub
