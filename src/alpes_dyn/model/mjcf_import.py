"""MJCF import: a MuJoCo model with fixed tendons as a URDF and a transmission spec (any tendon hand).

(:meth:`Model.from_mjcf <alpes_dyn.model.robot.Model.from_mjcf>`) compiles the MJCF with
MuJoCo itself (so defaults, classes, ``<include>`` and angle units are MuJoCo's), then writes what the library's
backends read:

* the **URDF** of the kinematic tree: one link per body with its inertial (mass, centre of mass, principal
  inertia and axes), one revolute joint per hinge (its axis and its range), a fixed joint for a body without joint, one fixed child link per site (a frame a
  fingertip or a sensor can name). A hinge placed off its body's origin (``pos``) moves the URDF link frame onto
  the joint axis: the same kinematics, the body's inertial and children expressed from there;
* the **spec**: one motor per actuator on a fixed tendon, q_m = gear * sum_i coef_i q_i, so the ratio of joint i
  is gear * coef_i, on a spatial tendon (sites, wrapping cylinders and spheres) q_m = gear * L(q), its ratios
  gear * dL/dq fitted as the spec's ``ratio_curve`` from MuJoCo's own tendon Jacobian over the joint ranges
  (:mod:`alpes_dyn.model.mjcf_spatial`; the fit's error said in one ``MjcfCurveWarning``, the worst tendon first,
  where it is not exact; a tendon whose path leaves, touches or changes side of its wrapping geom over a joint's range,
  or spans two joints, carried as its geometry, the motor's ``path``: :mod:`alpes_dyn.model.mjcf_path`), or
  on one joint (ratio gear) (the inverse of the export's mapping, :mod:`alpes_dyn.model.mjcf`); the joints' ``stiffness``
  (with ``springref``, the spring's rest angle: the spec's ``[rest_angle]`` where it is not 0), ``armature``,
  ``frictionloss`` (Coulomb) and ``damping`` (viscous); a joint limit's ``solreflimit`` in MuJoCo's direct form
  (-stiffness -damping, what the export writes for a spec's ``[stops]``) as the ``[stops]`` row k = -solref[0] / w,
  d = -solref[1] / w, w the joint's ``dof_invweight0`` (the library's spring-damper stop where the limit's impedance
  is small, as the export's 1e-4; a limit in the time-constant form gets no row: sized by the library);
  a hinge's ``ref`` (MuJoCo's angle where the body is as written) kept: the child frame is turned by -ref about the
  axis, so the URDF's angle is MuJoCo's and the range, ``springref`` and tendon lengths hold as written;
  gravity from ``<option gravity>``; the tips: the first site of each leaf body, or the leaf body's own frame where
  it has no site (the link's origin, on its joint's axis: a fingertip point needs a site).

What would change how the motors act and has no place in the spec is said in one :class:`MjcfImportWarning`
naming each field (:func:`not_imported`: a servo's ``gainprm``/``biasprm``, ``dyntype``, ``forcerange``, a tendon's
``range``, a body's ``gravcomp``, a tied joint's range; the actuators become torque motors on the same transmission), the geoms are listed by ``alpes-dyn
import`` only. MuJoCo Menagerie's Shadow Hand E3M5 ships as an example (:func:`example_mjcf_path`; tested against
MuJoCo on that MJCF). ``hold=`` welds hinges at their reference angle, the actuators on them dropped (e.g. a hand's
wrist: each finger then a branch of its own). What the library does not model is refused with one line naming it,
never dropped: free, ball and slide joints, a hinge without range, a body with several joints, actuators on sites, a tendon spring,
an armature on a tendon no actuator pulls, a muscle, a gear of 0, equality constraints other than a joint's linear
coupling to another (``<connect>`` and ``<weld>`` are refused as closed kinematic loops, the bodies named). A joint
equality ``<equality><joint joint1= joint2= polycoef="b a 0 0 0"/>`` is read as the URDF's ``<mimic>`` (a mimic
joint, :mod:`alpes_dyn.model.mimic`; the later joint of the tree follows, the equality inverted if need be, chains
composed), and the tied joint's rows of the spec are moved onto the joint it follows as the same energies
(:func:`~alpes_dyn.model.mjcf_equality.fold_couplings`: a fixed tendon's coef a coef, springs, armature, damping, friction); its own range is named
as not imported. An MJCF file must be a regular file within :data:`alpes_dyn.limits.MAX_TEXT_BYTES`, with bodies
nested at most :data:`~alpes_dyn.limits.MAX_URDF_DEPTH` deep, at most :data:`~alpes_dyn.limits.MAX_URDF_LINKS`
bodies and sites, and no NaN (checked before MuJoCo's parser reads it; MuJoCo's compile warnings are the import's,
never a ``MUJOCO_LOG.TXT`` in the working folder). Round trip (tested): ``mjcf_string(model)`` -> ``Model.from_mjcf`` gives the same A, C, G
and forward dynamics as the model exported, to 1e-12.
"""

from __future__ import annotations

import xml.sax.saxutils as su
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import AlpesDynWarning, ModelError
from ..fileio import read_bytes
from .mjcf_equality import fold_couplings, joint_couplings
from .spec import Motor, TransmissionSpec

__all__ = ["MjcfImportWarning", "example_mjcf_path", "mjcf_model", "mjcf_to_urdf", "not_imported", "tree_error"]


class MjcfImportWarning(AlpesDynWarning):
    """An MJCF field that changes the actuators' dynamics is not in the spec (e.g. a position servo's gain): the
    message names each field (:func:`not_imported`)."""


EXAMPLE_MJCF = {"shadow_hand": "shadow_hand/right_hand.xml"}
"""The MJCF files shipped with the package (:func:`example_mjcf_path`), each with its LICENSE and NOTICE."""


def example_mjcf_path(name: str = "shadow_hand") -> Path:
    """Path of an MJCF shipped with the package: ``"shadow_hand"``, MuJoCo Menagerie's Shadow Hand E3M5 (right
    hand; 24 hinges, 20 position actuators, 4 of them on fixed tendons coupling each finger's two distal joints),
    its kinematics and dynamics as published, meshes replaced by primitive geoms (Apache-2.0; the folder's NOTICE
    says what changed).

    Parameters
    ----------
    name : str, optional
        The example's name, a key of :data:`EXAMPLE_MJCF` (default ``"shadow_hand"``).

    Returns
    -------
    pathlib.Path
        The MJCF file's path.

    Raises
    ------
    ModelError
        An unknown name.
    """
    from importlib import resources

    if not isinstance(name, str) or name not in EXAMPLE_MJCF:
        raise ModelError(f"unknown example MJCF {name!r} (shipped: {', '.join(sorted(EXAMPLE_MJCF))})")
    return Path(str(resources.files("alpes_dyn") / "data")) / EXAMPLE_MJCF[name]


def tree_error(exc: ModelError) -> ModelError:
    """A refusal of the imported URDF (its message starting with ``URDF``, e.g. over
    :data:`~alpes_dyn.limits.MAX_URDF_JOINTS` hinges) said as the MJCF's (``mjcf: its tree ...``): the user gave an
    MJCF, not a URDF. Any other error as it is.

    Parameters
    ----------
    exc : ModelError
        The error the imported URDF raised.

    Returns
    -------
    ModelError
        The error to raise.
    """
    msg = str(exc)
    if not msg.startswith("URDF"):
        return exc
    return ModelError(f"mjcf: its tree (imported as a URDF): {msg[4:].lstrip(':').strip()}")


def mjcf_model(cls, mjcf: str | Path, hold: Sequence[str] = (), **kwargs):
    """``cls(urdf, spec, **kwargs)`` of :func:`mjcf_to_urdf` (``cls``: :class:`~alpes_dyn.model.robot.Model`), a
    refusal of the imported URDF said of the MJCF (:func:`tree_error`).

    Parameters
    ----------
    cls : type
        The model class to build, :class:`~alpes_dyn.model.robot.Model`.
    mjcf : str or Path
        MJCF text or the path of an MJCF file.
    hold : sequence of str, optional
        Hinges welded at their reference angle (:func:`mjcf_to_urdf`; default none).
    **kwargs
        Passed to ``cls``.

    Returns
    -------
    Model
        The model.

    Raises
    ------
    ModelError
        The MJCF or its imported tree refused, one line.
    """
    urdf, spec = mjcf_to_urdf(mjcf, hold)
    try:
        return cls(urdf, spec, **kwargs)
    except ModelError as exc:
        raise tree_error(exc) from None


def _mj():
    try:
        import mujoco
    except ImportError:  # pragma: no cover - mujoco is an extra
        raise ModelError("MJCF import needs MuJoCo: pip install 'alpes_dyn[mujoco]'") from None
    return mujoco


def _compile(mjcf: str | Path):
    """MuJoCo's compiled model of MJCF text (a string with a ``<``) or of a file (its folder resolves includes)."""
    mujoco = _mj()
    is_text = isinstance(mjcf, str) and "<" in mjcf
    if not is_text and not isinstance(mjcf, (str, Path)):
        raise ModelError(f"mjcf: expected MJCF text or the path of an MJCF file, got {type(mjcf).__name__}")
    if is_text and "<mujoco" not in mjcf:
        raise ModelError("mjcf: expected MJCF text containing a <mujoco> element, or the path of such a file")
    if not is_text and not Path(mjcf).is_file():
        raise ModelError(f"mjcf: {str(mjcf)!r} is not a file")
    # a regular file within the size limit, its bodies and sites within the URDF's, before MuJoCo's parser reads it
    _scan(mjcf if is_text else read_bytes(mjcf, "mjcf", ModelError))
    said: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(said.append)  # MuJoCo's warnings said here, not written to MUJOCO_LOG.TXT
    try:
        m = mujoco.MjModel.from_xml_string(mjcf) if is_text else mujoco.MjModel.from_xml_path(str(mjcf))
    except ValueError as exc:
        raise ModelError(f"mjcf: MuJoCo cannot compile it ({str(exc).splitlines()[0]})") from None
    finally:
        mujoco.set_mju_user_warning(previous)
    for text in said:
        if "nan" in text.lower():
            raise ModelError(f"mjcf: a number is NaN ({text.strip()})")
        import warnings

        warnings.warn(f"mjcf: MuJoCo: {text.strip()}", MjcfImportWarning, stacklevel=3)
    return m


def _no_nan(tag: str, attrib: dict) -> None:
    """:class:`~alpes_dyn.ModelError` naming the element and attribute where an MJCF number is NaN."""
    for key, value in attrib.items():
        if "nan" in value.lower() and any(w.lower().lstrip("+-") == "nan" for w in value.split()):
            who = f"<{tag} name={attrib['name']!r}>" if "name" in attrib else f"a <{tag}>"
            raise ModelError(f"mjcf: {who} {key}={value[:60]!r}: a number is NaN")


def _scan(text: "str | bytes") -> None:
    """MJCF text refused before MuJoCo compiles it where its bodies nest deeper than
    :data:`~alpes_dyn.limits.MAX_URDF_DEPTH` or its bodies and sites (each a URDF link) outnumber
    :data:`~alpes_dyn.limits.MAX_URDF_LINKS` (what the import's URDF would be refused on, said before MuJoCo's own
    parser runs out of depth or spends its time on a huge file), or where a number is NaN (:func:`_no_nan`). Text
    the XML parser cannot read is left to MuJoCo's message."""
    import xml.etree.ElementTree as ET

    from ..limits import MAX_URDF_DEPTH, MAX_URDF_LINKS

    parser = ET.XMLPullParser(events=("start", "end"))
    depth = links = 0
    step = 1 << 16
    try:
        for i in range(0, len(text), step):
            parser.feed(text[i:i + step])
            for event, el in parser.read_events():
                tag = el.tag if isinstance(el.tag, str) else ""
                if tag == "body":
                    depth += 1 if event == "start" else -1
                if event == "start" and tag in ("body", "site"):
                    links += 1
                if event == "start":
                    _no_nan(tag, el.attrib)
                if depth > MAX_URDF_DEPTH:
                    raise ModelError(f"mjcf: bodies nested over {MAX_URDF_DEPTH} deep, the limit (each body a link "
                                     "of the imported URDF's chain)")
                if links > MAX_URDF_LINKS:
                    raise ModelError(f"mjcf: over {MAX_URDF_LINKS} bodies and sites, the limit (each a link of the "
                                     "imported URDF)")
                if event == "end":
                    el.clear()
    except ET.ParseError:
        return


def _compile_held(mjcf: str | Path, hold: Sequence[str] = ()):
    """:func:`_compile`, with the hinges named in ``hold`` removed (MuJoCo's ``MjSpec``: each body welded to its
    parent at its pose as written, the joint's reference angle) with the actuators on them. A held joint that a
    tendon crosses or an equality names is refused (the tendon's length or the equality would change meaning)."""
    m = _compile(mjcf)
    if isinstance(hold, str) or not all(isinstance(j, str) for j in hold):
        raise ModelError(f"hold: expected a list of joint names, got {hold!r}")
    if not hold:
        return m
    mujoco = _mj()
    O = mujoco.mjtObj
    names = [_name(mujoco, m, O.mjOBJ_JOINT, j, "joint") for j in range(m.njnt)]
    for j in hold:
        if j not in names:
            raise ModelError(f"hold: unknown joint {j!r} (joints: {', '.join(names)})")
    ids = {names.index(j) for j in hold}
    for w in range(m.nwrap):
        if m.wrap_type[w] == mujoco.mjtWrap.mjWRAP_JOINT and int(m.wrap_objid[w]) in ids:
            t = int(np.searchsorted(m.tendon_adr, w, side="right") - 1)
            raise ModelError(f"hold: joint {names[int(m.wrap_objid[w])]!r} is on tendon "
                             f"{_name(mujoco, m, O.mjOBJ_TENDON, t, 'tendon')!r}; hold joints no tendon crosses")
    for e in range(m.neq):
        if {int(m.eq_obj1id[e]), int(m.eq_obj2id[e])} & ids and m.eq_type[e] == mujoco.mjtEq.mjEQ_JOINT:
            raise ModelError(f"hold: equality {_name(mujoco, m, O.mjOBJ_EQUALITY, e, 'equality')!r} names a held joint")
    is_text = isinstance(mjcf, str) and "<" in mjcf
    spec = mujoco.MjSpec.from_string(mjcf) if is_text else mujoco.MjSpec.from_file(str(mjcf))
    for a in list(spec.actuators):
        if a.trntype == mujoco.mjtTrn.mjTRN_JOINT and a.target in hold:
            spec.delete(a)
    for j in hold:
        spec.delete(spec.joint(j))
    try:
        return spec.compile()
    except ValueError as exc:
        raise ModelError(f"hold: MuJoCo cannot compile the MJCF with {', '.join(hold)} held "
                         f"({str(exc).splitlines()[0]})") from None


def _name(mujoco, m, kind, i: int, prefix: str) -> str:
    n = mujoco.mj_id2name(m, kind, i)
    return n if n else f"{prefix}{i}"


def _f(x) -> str:
    """A number as URDF text (Python's shortest round-trip repr of the float)."""
    return repr(float(x))


def _rpy(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw (R = Rz(y) Ry(p) Rx(r)) of a rotation matrix."""
    p = float(np.arcsin(np.clip(-R[2, 0], -1.0, 1.0)))
    if abs(np.cos(p)) > 1e-9:
        r, y = float(np.arctan2(R[2, 1], R[2, 2])), float(np.arctan2(R[1, 0], R[0, 0]))
    else:  # gimbal lock: yaw 0
        r, y = float(np.arctan2(-R[1, 2], R[1, 1])), 0.0
    return r, p, y


def _quat_mat(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _origin(p: np.ndarray, R: np.ndarray) -> str:
    r, pi, y = _rpy(R)
    return f'<origin xyz="{_f(p[0])} {_f(p[1])} {_f(p[2])}" rpy="{_f(r)} {_f(pi)} {_f(y)}"/>'


def _tendon_armature(m, t: int) -> float:
    return float(m.tendon_armature[t]) if hasattr(m, "tendon_armature") else 0.0


def _check_supported(mujoco, m) -> None:
    hinge = mujoco.mjtJoint.mjJNT_HINGE
    for j in range(m.njnt):
        if m.jnt_type[j] != hinge:
            kind = {0: "free", 1: "ball", 2: "slide"}.get(int(m.jnt_type[j]), str(m.jnt_type[j]))
            raise ModelError(f"mjcf: joint {_name(mujoco, m, mujoco.mjtObj.mjOBJ_JOINT, j, 'joint')!r} is a {kind} "
                             "joint; the library models fixed-base trees of hinges")
    counts = np.bincount(m.jnt_bodyid, minlength=m.nbody) if m.njnt else np.zeros(m.nbody, int)
    for b in range(m.nbody):
        if counts[b] > 1:
            raise ModelError(f"mjcf: body {_name(mujoco, m, mujoco.mjtObj.mjOBJ_BODY, b, 'body')!r} has "
                             f"{counts[b]} joints; one hinge per body is supported")
    joint_couplings(mujoco, m)
    _check_actuators(mujoco, m)
    for t in range(m.ntendon):
        tname = _name(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t, "tendon")
        if np.any(m.tendon_stiffness[t] != 0) or np.any(np.asarray(getattr(m, "tendon_stiffnesspoly", 0))[t] != 0):
            raise ModelError(f"mjcf: tendon {tname!r} has a stiffness; the spec holds rigid tendons only")
        driven = any(m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_TENDON and m.actuator_trnid[a, 0] == t
                     for a in range(m.nu))
        if _tendon_armature(m, t) != 0 and not driven:
            raise ModelError(f"mjcf: tendon {tname!r} has an armature but no actuator; a rotor belongs to a motor")
        damped = np.any(np.asarray(getattr(m, "tendon_dampingpoly", 0))[t] != 0) or np.any(m.tendon_damping[t] != 0)
        if damped or np.any(m.tendon_frictionloss[t] != 0):
            raise ModelError(f"mjcf: tendon {tname!r} has damping or friction; the spec holds them per joint only")


def _check_actuators(mujoco, m) -> None:
    """Muscles refused as such (their force-length-velocity law and activation are not a torque source)."""
    kinds = ((m.actuator_dyntype, mujoco.mjtDyn.mjDYN_MUSCLE), (m.actuator_gaintype, mujoco.mjtGain.mjGAIN_MUSCLE),
             (m.actuator_biastype, mujoco.mjtBias.mjBIAS_MUSCLE))
    for a in range(m.nu):
        if any(int(types[a]) == int(muscle) for types, muscle in kinds):
            raise ModelError(f"mjcf: actuator {_name(mujoco, m, mujoco.mjtObj.mjOBJ_ACTUATOR, a, 'motor')!r} is a "
                             "muscle; the library's motors are torque sources on their transmission (replace it by a "
                             "<motor> on the same tendon)")


def _named(mujoco, m, kind, ids, prefix: str) -> str:
    names = [_name(mujoco, m, kind, int(i), prefix) for i in ids]
    return ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")


_JOINT_EXTRAS = (
    ("jnt_stiffnesspoly", "stiffness", "a spring's terms beyond the linear one: the spec's spring is linear"),
    ("dof_dampingpoly", "damping", "a damper's terms beyond the linear one: the spec's viscous friction is linear"),
    ("jnt_springyield", "springyield", "a plastic spring's yield"),
    ("jnt_actfrclimited", "actuatorfrcrange", "a limit on the actuators' force at the joint"))
"""(MjModel field, MJCF attribute, what it is) of the joint fields :func:`not_imported` names where non-zero."""


def not_imported(m) -> list[str]:
    """What of a compiled MuJoCo model ``m`` (``mujoco.MjModel``) the URDF + spec do not hold, one line per kind,
    naming the MJCF field and the first elements that have it. The first lines (up to the one starting with
    ``geoms``) change how the motors act (:class:`MjcfImportWarning`): the spec's motors are torque sources
    (tau = S^T tau_m, the actuator's force taken as the motor torque), so a servo's gain and bias (``position``,
    ``velocity``, ``intvelocity`` and ``general`` actuators: ``gainprm``/``biasprm``), activation dynamics
    (``dyntype``), a force saturation (``forcerange``) and a tendon's length limit (``range``) are left to the
    user's controller or recorded torques; a body's ``gravcomp`` (MuJoCo's gravity compensation: the library's
    gravity acts on the whole mass), the range of a joint tied by a joint equality (the library's limits are
    those of the joint it follows), a joint's nonlinear ``stiffness`` and ``damping`` terms (MuJoCo 4's polynomials:
    the spec's are linear), ``springyield`` and ``actuatorfrcrange`` are named too. Collision geometry and the solver's options are never imported (the
    library's contact is its own, :mod:`alpes_dyn.model.contact`).

    Parameters
    ----------
    m : mujoco.MjModel
        The compiled MJCF.

    Returns
    -------
    list of str
        One line per kind not imported (empty: everything is).
    """
    mujoco = _mj()
    O = mujoco.mjtObj
    out = []
    gain = np.asarray(m.actuator_gainprm)[:, 0] if m.nu else np.zeros(0)
    servo = [a for a in range(m.nu) if m.actuator_biastype[a] != 0 or m.actuator_gaintype[a] != 0 or gain[a] != 1]
    if servo:
        kp = sorted({float(gain[a]) for a in servo})
        out.append(f"actuators {_named(mujoco, m, O.mjOBJ_ACTUATOR, servo, 'motor')}: a gain or bias (gainprm/biasprm: "
                   f"a servo, kp in {{{', '.join(f'{k:g}' for k in kp[:6])}}}); imported as torque motors on the same "
                   "transmission (the servo is the controller's)")
    dyn = [a for a in range(m.nu) if m.actuator_dyntype[a] != 0]
    if dyn:
        out.append(f"actuators {_named(mujoco, m, O.mjOBJ_ACTUATOR, dyn, 'motor')}: activation dynamics (dyntype) not "
                   "imported")
    lim = [a for a in range(m.nu) if m.actuator_forcelimited[a]]
    if lim:
        out.append(f"actuators {_named(mujoco, m, O.mjOBJ_ACTUATOR, lim, 'motor')}: forcerange (a torque "
                   "saturation) not imported")
    comp = [b for b in range(m.nbody) if getattr(m, "body_gravcomp", np.zeros(m.nbody))[b] != 0]
    if comp:
        out.append(f"bodies {_named(mujoco, m, O.mjOBJ_BODY, comp, 'body')}: gravcomp (MuJoCo's gravity compensation "
                   "of their weight) not imported: the library's gravity acts on their whole mass")
    try:
        tied = [j for j in joint_couplings(mujoco, m) if m.jnt_limited[j]]
    except ModelError:  # an equality the import refuses: said by the import
        tied = []
    if tied:
        out.append(f"joints {_named(mujoco, m, O.mjOBJ_JOINT, tied, 'joint')} (tied by a joint equality): range not "
                   "imported (the library's limits are those of the joints they follow)")
    for field, attr, what in _JOINT_EXTRAS:
        arr = np.asarray(getattr(m, field, np.zeros(0))).reshape(m.njnt, -1) if m.njnt else np.zeros((0, 1))
        has = [j for j in range(arr.shape[0]) if np.any(arr[j] != 0)]
        if has:
            out.append(f"joints {_named(mujoco, m, O.mjOBJ_JOINT, has, 'joint')}: {attr} ({what}) not imported")
    tlim = [t for t in range(m.ntendon) if m.tendon_limited[t]]
    if tlim:
        out.append(f"tendons {_named(mujoco, m, O.mjOBJ_TENDON, tlim, 'tendon')}: range (a tendon length limit) not "
                   "imported")
    if m.ngeom:
        out.append(f"geoms: {m.ngeom} collision/visual geoms and the contact options not imported (the library's "
                   "contact is its own)")
    return out


def mjcf_to_urdf(mjcf: str | Path, hold: Sequence[str] = ()) -> tuple[str, TransmissionSpec]:
    """The URDF text and the spec of an MJCF (text or path); see the module docstring. What changes the motors'
    action and is not imported (:func:`not_imported`) is said in one :class:`MjcfImportWarning`. ``hold``: hinges
    welded at their reference angle, with the actuators on them dropped (e.g. a hand's wrist, so that each finger
    is a branch of its own: :meth:`Model.subtree <alpes_dyn.model.robot.Model.subtree>`, ``--chain``).

    Parameters
    ----------
    mjcf : str or Path
        MJCF text (a string with ``<mujoco``) or the path of an MJCF file (its folder resolves includes).
    hold : sequence of str, optional
        Hinges welded at their reference angle, with the actuators on them dropped (default none).

    Returns
    -------
    tuple of (str, TransmissionSpec)
        The URDF text and the spec.

    Raises
    ------
    ModelError
        An MJCF that cannot be compiled or holds what is not modelled, one line.
    """
    import warnings

    mujoco = _mj()
    m = _compile_held(mjcf, hold)
    _check_supported(mujoco, m)
    lost = [x for x in not_imported(m) if not x.startswith("geoms")]
    if lost:
        warnings.warn("mjcf: not imported: " + "; ".join(lost), MjcfImportWarning, stacklevel=2)
    O = mujoco.mjtObj
    body = [_name(mujoco, m, O.mjOBJ_BODY, b, "body") for b in range(m.nbody)]
    body[0] = "world"
    jnt_of = {int(m.jnt_bodyid[j]): j for j in range(m.njnt)}
    # each body's URDF link frame: its MuJoCo frame shifted onto its joint's position (p_shift in the body frame)
    shift = np.zeros((m.nbody, 3))
    for b, j in jnt_of.items():
        shift[b] = m.jnt_pos[j]
    mimics = joint_couplings(mujoco, m)
    links, joints = ['<link name="world"/>'], []
    for b in range(1, m.nbody):
        R_i = _quat_mat(m.body_iquat[b])
        c = m.body_ipos[b] - shift[b]
        mass = float(m.body_mass[b])
        if mass > 0:
            I = R_i @ np.diag(m.body_inertia[b]) @ R_i.T
            inert = (f'<inertial><origin xyz="{_f(c[0])} {_f(c[1])} {_f(c[2])}"/><mass value="{_f(mass)}"/>'
                     f'<inertia ixx="{_f(I[0, 0])}" ixy="{_f(I[0, 1])}" ixz="{_f(I[0, 2])}" iyy="{_f(I[1, 1])}" '
                     f'iyz="{_f(I[1, 2])}" izz="{_f(I[2, 2])}"/></inertial>')
        else:
            inert = ""
        links.append(f'<link name="{su.escape(body[b])}">{inert}</link>')
        parent = int(m.body_parentid[b])
        R = _quat_mat(m.body_quat[b])
        p = m.body_pos[b] - shift[parent] + R @ shift[b]
        if b in jnt_of:  # a hinge's ref: MuJoCo's angle is ref where the body is as written (the URDF's is then 0)
            R = R @ _axis_rotation(m.jnt_axis[jnt_of[b]], -float(m.qpos0[m.jnt_qposadr[jnt_of[b]]]))
        org = _origin(p, R)
        if b in jnt_of:
            j = jnt_of[b]
            jname = _name(mujoco, m, O.mjOBJ_JOINT, j, "joint")
            ax = m.jnt_axis[j]
            if not m.jnt_limited[j]:
                raise ModelError(f"mjcf: joint {jname!r} has no range; the library's joints are revolute joints with "
                                 "limits (give it a range)")
            lo, hi = m.jnt_range[j]
            lim = f'<limit lower="{_f(lo)}" upper="{_f(hi)}" effort="1000" velocity="1000"/>'
            kind = "revolute"
            if j in mimics:
                j2, a, off = mimics[j]
                lim += (f'<mimic joint="{su.escape(_name(mujoco, m, O.mjOBJ_JOINT, j2, "joint"))}" '
                        f'multiplier="{_f(a)}" offset="{_f(off)}"/>')
            joints.append(f'<joint name="{su.escape(jname)}" type="{kind}"><parent link="{su.escape(body[parent])}"/>'
                          f'<child link="{su.escape(body[b])}"/>{org}<axis xyz="{_f(ax[0])} {_f(ax[1])} {_f(ax[2])}"/>'
                          f'{lim}</joint>')
        else:
            joints.append(f'<joint name="{su.escape(body[b])}_fixed" type="fixed"><parent '
                          f'link="{su.escape(body[parent])}"/><child link="{su.escape(body[b])}"/>{org}</joint>')
    sites = []
    for s in range(m.nsite):
        sname = _name(mujoco, m, O.mjOBJ_SITE, s, "site")
        b = int(m.site_bodyid[s])
        p = m.site_pos[s] - shift[b]
        links.append(f'<link name="{su.escape(sname)}"/>')
        joints.append(f'<joint name="{su.escape(sname)}_site" type="fixed"><parent link="{su.escape(body[b])}"/>'
                      f'<child link="{su.escape(sname)}"/>{_origin(p, _quat_mat(m.site_quat[s]))}</joint>')
        sites.append((sname, b))
    raw = bytes(m.names)
    model_name = raw[: raw.index(b"\0")].decode() or "mjcf"  # MuJoCo's name buffer starts with the model's name
    urdf = (f'<?xml version="1.0"?>\n<robot name="{su.escape(model_name)}">\n  '
            + "\n  ".join(links + joints) + "\n</robot>\n")
    spec = _spec(mujoco, m, sites, model_name)
    return urdf, spec


def _spatial_motor(mujoco, m, a: int, t: int, aname: str, gear: float) -> tuple[Motor, float, str]:
    """The motor of actuator ``a`` on spatial tendon ``t``: its ratios g dL/dq fitted as the spec's ``ratio_curve``
    (:func:`~alpes_dyn.model.mjcf_spatial.fit_spatial_tendon`), the fit's relative error and, where it is not exact
    (over :data:`~alpes_dyn.model.mjcf_spatial.TOLERANCE`), the line an :class:`MjcfCurveWarning` says. A tendon the
    form cannot follow (its path changes over a joint's range: a wrapping geom touched, left or wrapped on its other
    side; a segment over several joints) is carried as its path (:func:`_path_motor`), and so is a smooth tendon
    that the polynomials follow only to over ``TOLERANCE`` where its path can be carried (else the polynomial, the
    warning saying why its path is not)."""
    from .mjcf_spatial import TOLERANCE, fit_spatial_tendon

    names = [_name(mujoco, m, mujoco.mjtObj.mjOBJ_JOINT, j, "joint") for j in range(m.njnt)]
    fit = fit_spatial_tendon(mujoco, m, t, gear, names)
    if not fit.joints:
        raise ModelError(f"mjcf: actuator {aname!r}'s spatial tendon crosses no joint")
    rel = fit.error / fit.scale if fit.scale else 0.0
    tname = _name(mujoco, m, mujoco.mjtObj.mjOBJ_TENDON, t, "tendon")
    where = f"spatial tendon {tname!r} (actuator {aname!r})"
    if rel > TOLERANCE and fit.reason:  # no polynomial follows it: the tendon's geometry instead
        return _path_motor(mujoco, m, t, aname, gear, names, where), 0.0, ""
    note = ""
    if rel > TOLERANCE:  # smooth but not exact: its path where it can be carried, the polynomial (said) where not
        try:
            return _path_motor(mujoco, m, t, aname, gear, names, where), 0.0, ""
        except ModelError as e:
            note = (f"{where}: its ratios g dL/dq fitted as polynomials of each joint's angle, largest error "
                    f"{fit.error:.2g} rad/rad ({rel:.2g} of the largest ratio), motor angle g L(q) to "
                    f"{fit.length_error:.2g} rad, over the joint ranges (its path is not carried: {e})")
    return Motor(aname, fit.joints, rotor_inertia=_tendon_armature(m, t) / gear**2, ratio_curve=fit.curve), rel, note


def _path_motor(mujoco, m, t: int, aname: str, gear: float, names: list, where: str) -> Motor:
    """The motor of actuator ``aname`` on spatial tendon ``t`` as the tendon's path (:mod:`alpes_dyn.model.mjcf_path`),
    checked against MuJoCo at random states over the joints' box; its ``joints`` the ratios at q = 0."""
    from .mjcf_path import PATH_CHECKS, check_path, spatial_path
    from .mjcf_spatial import tendon_jacobian

    path = spatial_path(mujoco, m, t, gear, names, where)
    lo, hi = m.jnt_range[:, 0], m.jnt_range[:, 1]
    check_path(mujoco, m, t, path, names, lo + (hi - lo) * np.random.default_rng(0).random((PATH_CHECKS, m.njnt)),
               where)
    d = mujoco.MjData(m)
    d.qpos[:] = 0.0
    mujoco.mj_fwdPosition(m, d)
    J = gear * tendon_jacobian(m, d)[t][m.jnt_dofadr]
    joints = {names[j]: float(J[j]) for j in range(m.njnt) if J[j] != 0.0 and names[j] in path.joint_names}
    if not joints:
        raise ModelError(f"mjcf: {where}: its moment arms are all 0 at q = 0, where the spec's ratios are read")
    return Motor(aname, joints, rotor_inertia=_tendon_armature(m, t) / gear**2, path=path)


def _curve_warning(notes: list[tuple[float, str]]) -> None:
    """One :class:`MjcfCurveWarning` for the spatial tendons fitted with an error, the worst first."""
    import warnings

    from .mjcf_spatial import MjcfCurveWarning

    if notes:
        lines = [n for _, n in sorted(notes, key=lambda x: -x[0])]
        warnings.warn("mjcf: " + "; ".join(lines), MjcfCurveWarning, stacklevel=4)


def _spec(mujoco, m, sites: list[tuple[str, int]], model_name: str) -> TransmissionSpec:
    O = mujoco.mjtObj
    motors, notes = [], []
    for a in range(m.nu):
        aname = _name(mujoco, m, O.mjOBJ_ACTUATOR, a, "motor")
        gear = float(m.actuator_gear[a, 0])
        if not np.isfinite(gear) or gear == 0:
            raise ModelError(f"mjcf: actuator {aname!r} has gear {gear:g}; a motor's gear (its ratio) must be a "
                             "non-zero number")
        if m.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:  # a motor on one joint: q_m = gear q
            motors.append(Motor(aname, {_name(mujoco, m, O.mjOBJ_JOINT, int(m.actuator_trnid[a, 0]), "joint"): gear}))
            continue
        if m.actuator_trntype[a] != mujoco.mjtTrn.mjTRN_TENDON:
            raise ModelError(f"mjcf: actuator {aname!r} acts neither on a joint nor on a tendon; the spec's motors "
                             "pull fixed tendons")
        t = int(m.actuator_trnid[a, 0])
        adr, num = int(m.tendon_adr[t]), int(m.tendon_num[t])
        if m.wrap_type[adr] != mujoco.mjtWrap.mjWRAP_JOINT:  # a spatial tendon: its ratios fitted as curves of q
            motor, rel, note = _spatial_motor(mujoco, m, a, t, aname, gear)
            motors.append(motor)
            notes += [(rel, note)] if note else []
            continue
        ratios = {}
        for w in range(adr, adr + num):
            if m.wrap_type[w] != mujoco.mjtWrap.mjWRAP_JOINT:
                raise ModelError(f"mjcf: actuator {aname!r}'s tendon mixes joints and sites")
            jname = _name(mujoco, m, O.mjOBJ_JOINT, int(m.wrap_objid[w]), "joint")
            ratios[jname] = gear * float(m.wrap_prm[w])
        # the tendon's armature J_t acts on its length sum coef_i q_i: J_t coef coef^T = (J_t / gear^2) S^T S
        motors.append(Motor(aname, ratios, rotor_inertia=_tendon_armature(m, t) / gear**2))
    _curve_warning(notes)
    tables: dict[str, dict[str, float]] = {"stiffness": {}, "armature": {}, "coulomb": {}, "viscous": {}}
    stops: dict[str, dict[str, float]] = {}
    for j in range(m.njnt):
        jname = _name(mujoco, m, O.mjOBJ_JOINT, j, "joint")
        d = int(m.jnt_dofadr[j])
        for key, v in (("stiffness", m.jnt_stiffness[j]), ("armature", m.dof_armature[d]),
                       ("coulomb", m.dof_frictionloss[d]), ("viscous", m.dof_damping[d])):
            if v != 0:
                tables[key][jname] = float(v)
        rest = float(m.qpos_spring[m.jnt_qposadr[j]])
        if m.jnt_stiffness[j] != 0 and rest != 0:
            tables.setdefault("rest_angle", {})[jname] = rest
        if m.jnt_limited[j] and m.jnt_solref[j, 0] < 0:  # a stop in MuJoCo's direct form: the export's [stops]
            w = float(m.dof_invweight0[d])
            stops[jname] = {"stiffness": -float(m.jnt_solref[j, 0]) / w, "damping": -float(m.jnt_solref[j, 1]) / w}
    mimics = joint_couplings(mujoco, m)
    if mimics:
        jn = lambda j: _name(mujoco, m, O.mjOBJ_JOINT, j, "joint")  # noqa: E731
        motors = fold_couplings(motors, tables, stops, {jn(j1): (jn(j2), a, b) for j1, (j2, a, b) in mimics.items()})
    children = set(int(p) for p in m.body_parentid[1:])
    first_site: dict[int, str] = {}
    for sname, b in sites:
        first_site.setdefault(b, sname)
    # each leaf body's first site, or (no site: Menagerie's Shadow hand's distal phalanges) its own link frame
    tips = [first_site.get(b, _name(mujoco, m, O.mjOBJ_BODY, b, "body")) for b in range(1, m.nbody)
            if b not in children]
    return TransmissionSpec(motors=tuple(motors), gravity=tuple(float(g) for g in m.opt.gravity),
                            tips=tuple(tips) or None, name=model_name, stops={"joints": stops} if stops else None,
                            **tables)
