"""MJCF export of any :class:`~alpes_dyn.Model`: a URDF + spec robot for MuJoCo (the inverse of :mod:`.mjcf_import`).

:func:`model_mjcf` (and :meth:`Model.to_mjcf <alpes_dyn.model.robot.Model.to_mjcf>`) writes what the model holds,
read from Pinocchio's model (so the URDF's fixed links are already merged into their moving parent) and from the
model's extras and transmission (the spec's, or the ``extras=`` given):

* the **kinematic tree**: the URDF's root link as a static body, then one body per joint, named as the joint's
  child link, placed at Pinocchio's joint placement (``pos``, ``quat``) so that the body frame is the joint
  frame; its ``inertial``: mass, centre of mass and the full inertia about it (``fullinertia``, the merged
  inertia of the link and of the fixed links under it);
* one ``hinge`` per revolute joint (``slide`` per prismatic one) at the body origin with the joint's axis;
  ``range`` = the URDF limits (``limited="true"`` with ``limits``, else ``limited="false"`` and no range); where
  the spec has a ``[stops]`` table, every limited joint's stop as :meth:`JointStops.of
  <alpes_dyn.model.stops.JointStops.of>` gives it (the table's values, the sized ones on the joints it leaves out):
  ``solreflimit="-k w -d w"`` (MuJoCo's direct form, stiffness and damping per unit of the joint's inverse weight
  w = (A(q=0)^-1)_ii, MuJoCo's ``dof_invweight0``) and ``solimplimit`` :data:`STOP_IMPEDANCE` (MuJoCo's least
  impedance d): the limit's force is then -(k p + d v) / (1 - d + d A_ii(q) w) -- k p + d v to 1e-4, the library's
  unilateral spring-damper (MuJoCo's constraint takes the share d = 1e-4 of the other torques on the joint too;
  without ``[stops]`` MuJoCo's default limit, as stiff as its solver makes it);
  ``stiffness`` k_i with ``springref`` q_rest,i (the spring's rest angle, rad: the spec's ``[rest_angle]``, 0 by
  default; MuJoCo's passive force -k (q - springref) is the library's spring law), ``armature`` (the joint-side
  inertia), ``frictionloss`` F_s (Coulomb: MuJoCo's dry friction is a constraint, the library's a sign or a
  smooth sign) and ``damping`` F_v (viscous);
* one **fixed tendon** per motor, named as the motor, with coefficient S_ki on each joint it drives: its length
  is the motor angle q_m = S q; its ``armature`` is the rotor inertia J_m, which MuJoCo adds as J_m S_k^T S_k,
  the library's :attr:`Model.rotor_matrix <alpes_dyn.Model.rotor_matrix>`;
* with ``tendon=`` (an :class:`~alpes_dyn.model.tendon.ElasticTendon`): series-elastic, pull-only cables instead,
  a rotor hinge ``<motor>_rotor`` per motor (``armature`` J_m) and the fixed tendon ``<motor>`` = theta_m - S_k q
  with the cable's stiffness, damping and play (:class:`~alpes_dyn.symbolic.elastic_tendon.SeriesElasticSystem`'s
  system: tested equal in MuJoCo), the motor on the rotor's hinge, ``encoder_<motor>`` on the rotor;
* a ``motor`` actuator on each tendon, gear 1: ctrl = tau_m gives the joints S^T tau_m (the spec holds no
  torque limit, so ``ctrlrange`` is unlimited: a pull-only cable needs ``ctrlrange="0 tau_max"`` by hand);
* one joint **equality** per mimic joint (:attr:`Model.mimic <alpes_dyn.Model.mimic>`): the URDF's
  q_k = a q_J + b as ``<joint joint1="k" joint2="J" polycoef="b a 0 0 0"/>``, as stiff as MuJoCo's soft
  constraints go (``solimp`` 0.9999, ``solref`` two time steps); the mimic joint a hinge of its own, with its
  URDF range and no spring, armature or friction (the spec names the joint it follows);
* sensors: ``encoder_<motor>`` (``tendonpos`` = q_m, rad), ``torque_<motor>`` (``actuatorfrc`` = tau_m, N m),
  and at each tip frame (:attr:`Model.tips <alpes_dyn.Model.tips>`) a site named as the frame, a sphere geom of
  radius ``tip_radius`` (mass-less: ``inertiafromgeom="false"``) and a ``touch`` sensor ``touch_<tip>`` (N);
* ``<option>``: the model's gravity, ``timestep`` (default 1e-4 s) and ``integrator`` (default ``RK4``);
  ``compiler angle="radian"``.

Not written, as MuJoCo has no such thing: the encoder resolution (``encoder_counts``: MuJoCo's sensors are not
quantised, :meth:`Transmission.quantize <alpes_dyn.Transmission.quantize>` is) and the smooth sign's v_s
(``smooth_velocity``). What MuJoCo cannot express is refused with a :class:`~alpes_dyn.ModelError` naming it: a
moving body without mass or with a singular inertia (MuJoCo needs both positive), an inertia that breaks the
triangle inequality (MuJoCo would have to change it, ``balanceinertia``), a joint neither revolute nor prismatic.

Round trip (tested): ``Model.from_mjcf(model_mjcf(m))`` has m's joints, S, rotor inertia, springs, armature,
friction and the same A, C, G and forward dynamics (to ~1e-15 relative) -- with ``limits`` (the import needs
ranges) and for revolute joints (the import refuses slides). A tip frame that is a moving link itself gets the
site ``<tip>_site`` (the import makes a link of each site).
"""

from __future__ import annotations

import math
import numbers
import xml.sax.saxutils as su
from typing import Any, Sequence

import numpy as np

from ..errors import InputError, ModelError
from .friction import creep_of, lugre_of
from .mimic import tree_model

__all__ = ["model_mjcf", "INTEGRATORS", "STOP_IMPEDANCE", "stop_solref", "creep_attributes"]

STOP_IMPEDANCE = 1e-4
"""MuJoCo's least constraint impedance (``mjMINIMP``): the ``solimplimit`` of a joint stop from the spec's ``[stops]``
table, which makes MuJoCo's soft limit a spring-damper to 1e-4 (the module doc)."""

INTEGRATORS: tuple[str, ...] = ("Euler", "implicit", "implicitfast", "RK4")
"""MuJoCo's integrators (``<option integrator>``)."""
_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
_MINVAL = 1e-15  # MuJoCo's mjMINVAL: the least mass and principal inertia of a moving body
_ROTOR_MASS = 1e-12  # kg and kg m^2 of a rotor hinge's body (MuJoCo needs a positive mass): its inertia is the armature


def _f(x: float) -> str:
    """A number as MJCF text (Python's shortest round-trip repr of the float)."""
    return repr(float(x))


def _v(xs: Sequence[float]) -> str:
    return " ".join(_f(x) for x in xs)


def _q(s: str) -> str:
    """An XML attribute value, quoted and escaped."""
    return su.quoteattr(s)


def _joint_kind(jm: Any, name: str) -> tuple[str, tuple[float, float, float]]:
    """(``"hinge"`` or ``"slide"``, its axis in the joint frame) of a Pinocchio joint model."""
    short = jm.shortname()
    for prefix, kind in (("JointModelR", "hinge"), ("JointModelP", "slide")):
        tail = short[len(prefix):]
        if short.startswith(prefix) and tail in _AXES:
            return kind, _AXES[tail]
    for prefix, kind in (("JointModelRevoluteUnaligned", "hinge"), ("JointModelPrismaticUnaligned", "slide")):
        if short == prefix:
            return kind, tuple(float(x) for x in jm.extract().axis)
    raise ModelError(f"MJCF export: joint {name!r} is a {short.removeprefix('JointModel')} joint; "
                     "only revolute (hinge) and prismatic (slide) joints are exported")


def _check_inertia(link: str, mass: float, I: np.ndarray) -> None:
    """What MuJoCo needs of a moving body's inertial (else it refuses to compile the model)."""
    e = np.linalg.eigvalsh(0.5 * (I + I.T))
    if not mass > _MINVAL:
        raise ModelError(f"MJCF export: link {link!r} moves but has mass {mass:g}; MuJoCo needs a positive mass "
                         "on every moving body (give the link a mass, or make its joint fixed)")
    if not e[0] > _MINVAL:
        raise ModelError(f"MJCF export: link {link!r} has a singular inertia (principal moments "
                         f"{', '.join(f'{x:g}' for x in e)}); MuJoCo needs positive principal moments on every "
                         "moving body")
    if e[0] + e[1] < e[2]:
        raise ModelError(f"MJCF export: link {link!r} has an inertia that breaks the triangle inequality (principal "
                         f"moments {', '.join(f'{x:g}' for x in e)}: {e[0] + e[1]:g} < {e[2]:g}); MuJoCo refuses it "
                         "(its balanceinertia would change the dynamics)")


def _quat(R: np.ndarray) -> tuple[float, float, float, float]:
    """MuJoCo's quaternion (w, x, y, z) of a rotation matrix."""
    import pinocchio as pin

    x, y, z, w = pin.Quaternion(np.asarray(R, dtype=float)).coeffs()
    return (float(w), float(x), float(y), float(z))


def _pose(M: Any) -> str:
    """``pos``/``quat`` attributes of a Pinocchio SE3 (quat left out for the identity)."""
    out = f'pos="{_v(M.translation)}"'
    if not np.array_equal(M.rotation, np.eye(3)):
        out += f' quat="{_v(_quat(M.rotation))}"'
    return out


def _body_names(model: Any) -> tuple[str, list[str]]:
    """(the root link's name, each joint's child link name) from Pinocchio's frames."""
    import pinocchio as pin

    pm = tree_model(model)
    frames = pm.frames
    root = next((f.name for f in frames if f.type == pin.FrameType.BODY and f.parentJoint == 0), "base")
    names = []
    for i in range(1, pm.njoints):
        jf = pm.getFrameId(pm.names[i], pin.FrameType.JOINT)
        child = next((f.name for f in frames if f.type == pin.FrameType.BODY and f.parentFrame == jf), None)
        names.append(child if child is not None else f"{pm.names[i]}_link")
    return root, names


def _joint_xml(model: Any, i: int, limits: bool, solref: dict[str, tuple[float, float]],
               stiction: float | None = None) -> str:
    """The ``<joint>`` of Pinocchio joint i (1-based): axis, range, spring, armature, friction (a mimic joint has
    none of the last four: the spec names the joint it follows); with ``stiction`` (s) a joint with dry friction
    gets ``solreffriction`` of that time constant."""
    pm = tree_model(model)
    name = pm.names[i]
    kind, axis = _joint_kind(pm.joints[i], name)
    k = i - 1
    attrs = [f"name={_q(name)}", f'type="{kind}"', 'pos="0 0 0"', f'axis="{_v(axis)}"']
    lo, hi = float(pm.lowerPositionLimit[k]), float(pm.upperPositionLimit[k])
    if limits and math.isfinite(lo) and math.isfinite(hi) and lo < hi:
        attrs += ['limited="true"', f'range="{_f(lo)} {_f(hi)}"']
        if name in solref:
            attrs += [f'solreflimit="{_f(solref[name][0])} {_f(solref[name][1])}"',
                      f'solimplimit="{_f(STOP_IMPEDANCE)} {_f(STOP_IMPEDANCE)} 0.001 0.5 2"']
    else:
        attrs.append('limited="false"')
    if name not in model.joint_names:  # a mimic joint
        return f"<joint {' '.join(attrs)}/>"
    ex, e = model.extras, model.joint_names.index(name)
    attrs += [f'stiffness="{_f(ex.stiffness[e])}"', f'springref="{_f(ex.rest[e]) if ex.rest[e] != 0 else "0"}"']
    lugre = lugre_of(model) is not None  # the dry friction is then a passive dcmotor's LuGre (_lugre_actuators)
    for attr, values in (("armature", ex.armature), ("frictionloss", ex.coulomb), ("damping", ex.viscous)):
        if values[e] != 0 and not (lugre and attr == "frictionloss"):
            attrs.append(f'{attr}="{_f(values[e])}"')
    if stiction is not None and ex.coulomb[e] != 0 and not lugre:
        attrs.append(stiction_attributes(stiction))
    elif creep_of(model) is not None and ex.coulomb[e] != 0:
        attrs.append(creep_attributes(creep_of(model)))
    return f"<joint {' '.join(attrs)}/>"


def creep_attributes(law: Any) -> str:
    """The ``<joint>`` attributes of the creep law (:class:`~alpes_dyn.model.friction.Creep`): MuJoCo's soft
    dry-friction constraint of impedance d = kappa / (1 + kappa) (``solimpfriction`` "d d 0.001": its added inertia
    d / (1 - d) / ``dof_invweight0``) and time constant 2 / (d b) (``solreffriction``, critically damped: its rate
    b = 2 / (d_max t_c)); MuJoCo's default constraint is the law's default.

    Parameters
    ----------
    law : ~alpes_dyn.model.friction.Creep
        The creep law: its ``kappa`` (the band's added inertia in units of the joint's own, -) and ``rate``
        (the band's rate b, 1/s).

    Returns
    -------
    str
        ``solreffriction="..." solimpfriction="..."``, the attributes to add to each ``<joint>``.
    """
    d = law.kappa / (1.0 + law.kappa)
    return f'solreffriction="{_f(2.0 / (d * law.rate))} 1" solimpfriction="{_f(d)} {_f(d)} 0.001"'


#: Impedance d of the dry-friction constraint that ``stiction`` writes (``solimpfriction``): a stuck joint creeps at
#: a velocity proportional to (1 - d) / d; MuJoCo's default 0.9 lets finger3's joint 3 creep at 0.012 rad/s under
#: 0.8 F_s after 0.1 s, 0.999 at 1.2e-4.
STICTION_IMPEDANCE: float = 0.999


def stiction_attributes(stiction: float) -> str:
    """The ``<joint>`` attributes of a real stick-slip, written by both MJCF writers: ``solreffriction`` of time
    constant ``stiction`` (s; critically damped) and ``solimpfriction`` of impedance :data:`STICTION_IMPEDANCE`."""
    d = _f(STICTION_IMPEDANCE)
    return f'solreffriction="{_f(stiction)} 1" solimpfriction="{d} {d} 0.001"'


def check_stiction(stiction: Any) -> None:
    """InputError unless ``stiction`` (the dry-friction constraint's time constant, s: ``solreffriction``) is None
    or a finite real number > 0 (a bool is not a number): the check of both MJCF writers' ``stiction``."""
    if stiction is None:
        return
    try:  # an integer too large for a float is not finite
        ok = isinstance(stiction, numbers.Real) and not isinstance(stiction, bool) and math.isfinite(stiction)
    except OverflowError:
        ok = False
    if not (ok and stiction > 0):
        raise InputError(f"stiction: expected a positive time constant in s (e.g. 0.0005), got {stiction!r}")


def stop_solref(model: Any) -> dict[str, tuple[float, float]]:
    """{joint: (solreflimit's two numbers)} of the stops the export writes: empty without a spec ``[stops]`` table;
    else every limited joint's -k w and -d w, k and d :meth:`JointStops.of <alpes_dyn.model.stops.JointStops.of>`'s
    (N m/rad, N m s/rad), w = (A(0)^-1)_ii (1/(kg m^2): MuJoCo's ``dof_invweight0``, the whole tree's mass matrix
    at qpos0 = 0 with armature and rotors, mimic joints as coordinates of their own).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model (its spec's ``[stops]`` table, its mass matrix at q = 0).

    Returns
    -------
    dict of str to tuple of (float, float)
        {joint: (-k w, -d w)}, MuJoCo's direct ``solreflimit`` form, 1/s^2 and 1/s.
    """
    import pinocchio as pin

    from .stops import JointStops

    spec = getattr(model, "spec", None)
    if spec is None or spec.stops is None:
        return {}
    stops = JointStops.of(model)
    pm = tree_model(model)
    M = pin.crba(pm, pm.createData(), np.zeros(pm.nq))
    M = np.triu(M) + np.triu(M, 1).T
    names = list(pm.names[1:])
    idx = [names.index(j) for j in model.joint_names]
    M[np.diag_indices(len(names))] -= pm.armature  # what crba added, then the model's own armature and rotors
    A = np.zeros((model.n, model.n))
    A[np.diag_indices(model.n)] = model.extras.armature
    A += model.rotor_matrix if model.transmission is not None else 0.0
    M[np.ix_(idx, idx)] += A
    w = np.diag(np.linalg.inv(M))[idx]
    k = np.broadcast_to(stops.stiffness, (model.n,))
    d = np.broadcast_to(stops.damping, (model.n,))
    limited = np.isfinite(stops.lower) | np.isfinite(stops.upper)
    return {j: (-float(k[i] * w[i]), -float(d[i] * w[i])) for i, j in enumerate(model.joint_names) if limited[i]}


def _equality(model: Any, timestep: float) -> list[str]:
    """One joint equality per mimic joint, q_mimic = b + a q_primary (``polycoef="b a 0 0 0"``, about qpos0 = 0),
    as stiff as MuJoCo's soft constraints go: impedance 0.9999 and the time constant 2 steps (MuJoCo's least)."""
    mimic = getattr(model, "mimic", None)
    if mimic is None:
        return []
    lines = [f'    <joint joint1={_q(m.name)} joint2={_q(m.primary)} polycoef="{_f(m.offset)} {_f(m.multiplier)} 0 0 0" '
             f'solref="{_f(2 * timestep)} 1" solimp="0.9999 0.9999 0.001 0.5 2"/>' for m in mimic.mimics]
    return ["  <equality>", *lines, "  </equality>"]


def _tips(model: Any, bodies: set[str], tip_radius: float) -> dict[int, list[str]]:
    """Per Pinocchio joint (0: the world), the site, geom and sensor name lines of the tips it carries."""
    pm = tree_model(model)
    out: dict[int, list[str]] = {}
    for tip in model.tips:
        fr = pm.frames[model.frame_id(tip)]
        site = f"{tip}_site" if tip in bodies else tip
        size = f' size="{_f(1.25 * tip_radius)}"' if tip_radius > 0 else ""  # else MuJoCo's default, 5 mm
        lines = [f"<site name={_q(site)} {_pose(fr.placement)}{size}/>"]
        if tip_radius > 0:
            lines.append(f'<geom name={_q(site)} type="sphere" size="{_f(tip_radius)}" '
                         f'pos="{_v(fr.placement.translation)}" rgba="0.8 0.3 0.3 1"/>')
        out.setdefault(int(fr.parentJoint), []).extend(lines)
    return out


def _tree(model: Any, limits: bool, tip_radius: float, stiction: float | None = None
          ) -> tuple[list[str], dict[str, str]]:
    """The ``<worldbody>`` lines (depth first, Pinocchio's joint order) and the site name of each tip."""
    pm = tree_model(model)
    root, names = _body_names(model)
    children: dict[int, list[int]] = {}
    for i in range(1, pm.njoints):
        children.setdefault(int(pm.parents[i]), []).append(i)
    tips = _tips(model, set(names), tip_radius)
    solref = stop_solref(model) if limits else {}
    # a root link named "world" (an imported MJCF's, a common URDF root) is MuJoCo's world body itself: no body of
    # that name (MuJoCo refuses a repeated 'world'), its frames and children placed in <worldbody>
    wrap = root != "world"
    lines = ["  <worldbody>"] + ([f"    <body name={_q(root)}>"] if wrap else [])

    def body(i: int, depth: int) -> None:
        ind = "  " * depth
        Y = pm.inertias[i]
        mass, c, I = float(Y.mass), np.asarray(Y.lever), np.asarray(Y.inertia)
        _check_inertia(names[i - 1], mass, I)
        lines.append(f"{ind}<body name={_q(names[i - 1])} {_pose(pm.jointPlacements[i])}>")
        lines.append(f"{ind}  {_joint_xml(model, i, limits, solref, stiction)}")
        lines.append(f'{ind}  <inertial pos="{_v(c)}" mass="{_f(mass)}" fullinertia="'
                     f'{_v((I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]))}"/>')
        lines.extend(f"{ind}  {s}" for s in tips.get(i, ()))
        for ch in children.get(i, ()):
            body(ch, depth + 1)
        lines.append(f"{ind}</body>")

    lines.extend(f"      {s}" for s in tips.get(0, ()))
    for i in children.get(0, ()):
        body(i, 3)
    lines += (["    </body>"] if wrap else []) + ["  </worldbody>"]
    sites = {t: (f"{t}_site" if t in names else t) for t in model.tips}
    return lines, sites


def _rotor_bodies(model: Any) -> list[str]:
    """One body per motor for the series-elastic tendon: a hinge ``<motor>_rotor`` (``armature`` J_m) on a body of
    the least mass and inertia MuJoCo takes (its rotor is the armature)."""
    tr = model.transmission
    return [f"    <body name={_q(motor + '_rotor')}>\n"
            f'      <joint name={_q(motor + "_rotor")} type="hinge" axis="0 0 1" limited="false" '
            f'armature="{_f(float(tr.rotor_inertia[k]))}"/>\n'
            f'      <inertial pos="0 0 0" mass="{_f(_ROTOR_MASS)}" diaginertia="{_v((_ROTOR_MASS,) * 3)}"/>\n'
            "    </body>" for k, motor in enumerate(tr.motor_names)]


def _elastic_tendons(model: Any, tendon: Any) -> tuple[list[str], list[str], list[str]]:
    """Tendons, actuators, sensors of the series-elastic tendon: the stretch phi = theta_m - S_k q (rad of motor
    shaft) as a fixed tendon with stiffness k_m, damping c_m and the dead band ``springlength="-1e6 delta"`` (pull
    only beyond the play), the motor on the rotor's hinge, its encoder on the rotor."""
    tr = model.transmission
    tendons, actuators, sensors = [], [], []
    for k, motor in enumerate(tr.motor_names):
        rotor = motor + "_rotor"
        coefs = f'\n      <joint joint={_q(rotor)} coef="1"/>' + "".join(
            f'\n      <joint joint={_q(model.joint_names[i])} coef="{_f(-tr.S[k, i])}"/>' for i in np.flatnonzero(tr.S[k]))
        tendons.append(f'    <fixed name={_q(motor)} stiffness="{_f(float(tendon.stiffness[k]))}" '
                       f'damping="{_f(float(tendon.damping[k]))}" springlength="-1e6 {_f(float(tendon.dead_band[k]))}">'
                       f"{coefs}\n    </fixed>")
        actuators.append(f'    <motor name={_q(motor)} joint={_q(rotor)} gear="1" ctrllimited="false"/>')
        sensors += [f"    <jointpos name={_q('encoder_' + motor)} joint={_q(rotor)}/>",
                    f"    <tendonpos name={_q('tendon_' + motor)} tendon={_q(motor)}/>",
                    f"    <actuatorfrc name={_q('torque_' + motor)} actuator={_q(motor)}/>"]
    return tendons, actuators, sensors


def _transmission(model: Any, sites: dict[str, str], tendon: Any = None) -> list[str]:
    """The ``<tendon>``, ``<actuator>`` and ``<sensor>`` sections (none without motors or tips)."""
    tr = model.transmission
    tendons, actuators, sensors = [], [], []
    if tendon is not None:
        tendons, actuators, sensors = _elastic_tendons(model, tendon)
    elif tr is not None:
        for k, motor in enumerate(tr.motor_names):
            J = float(tr.rotor_inertia[k])
            arm = f' armature="{_f(J)}"' if J != 0 else ""
            coefs = "".join(f'\n      <joint joint={_q(model.joint_names[i])} coef="{_f(tr.S[k, i])}"/>'
                            for i in np.flatnonzero(tr.S[k]))
            tendons.append(f"    <fixed name={_q(motor)}{arm}>{coefs}\n    </fixed>")
            actuators.append(f'    <motor name={_q(motor)} tendon={_q(motor)} gear="1" ctrllimited="false"/>')
            sensors += [f"    <tendonpos name={_q('encoder_' + motor)} tendon={_q(motor)}/>",
                        f"    <actuatorfrc name={_q('torque_' + motor)} actuator={_q(motor)}/>"]
    sensors += [f"    <touch name={_q('touch_' + t)} site={_q(s)}/>" for t, s in sites.items()]
    actuators += _lugre_actuators(model)
    out = []
    for tag, items in (("tendon", tendons), ("actuator", actuators), ("sensor", sensors)):
        if items:
            out += [f"  <{tag}>", *items, f"  </{tag}>"]
    return out


def _lugre_actuators(model: Any) -> list[str]:
    """The LuGre law of the model's file (:mod:`~alpes_dyn.model.friction`) as MuJoCo 4's: one passive ``dcmotor``
    (``input="none"``, no electrical branch: ``motorconst="0 0"``) per joint with dry friction, named
    ``lugre_<joint>``, its ``lugre`` = "sigma0 sigma1 F_s F_s 1" (static = Coulomb level: the Stribeck velocity is
    then moot; F_v stays the joint's ``damping``); none with the tanh law."""
    law = lugre_of(model)
    if law is None:
        return []
    ex = model.extras
    return [f'    <dcmotor name={_q("lugre_" + j)} joint={_q(j)} input="none" motorconst="0 0" resistance="1" '
            f'lugre="{_f(law.sigma0)} {_f(law.sigma1)} {_f(ex.coulomb[i])} {_f(ex.coulomb[i])} 1"/>'
            for i, j in enumerate(model.joint_names) if ex.coulomb[i] > 0]


def _check_args(timestep: Any, integrator: Any, tip_radius: Any) -> None:
    def number(x: Any) -> bool:
        return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and math.isfinite(x)

    if not (number(timestep) and timestep > 0):
        raise InputError(f"timestep: expected a positive number of seconds, got {timestep!r}")
    if integrator not in INTEGRATORS:
        raise InputError(f"integrator: expected one of {', '.join(INTEGRATORS)}, got {integrator!r}")
    if not (number(tip_radius) and tip_radius >= 0):
        raise InputError(f"tip_radius: expected a radius >= 0 in m, got {tip_radius!r}")


def _check_tendon(model: Any, tendon: Any) -> None:
    """``tendon`` fits ``model``: an ElasticTendon of its motors, each rotor with J_m > 0, its stiffness the model's
    quasi-static compliance where the model has one (one cable, written once)."""
    from .tendon import ElasticTendon

    if not isinstance(tendon, ElasticTendon):
        raise InputError(f"tendon: expected an ElasticTendon (or None: rigid tendons), got {type(tendon).__name__}")
    tr = model.transmission
    if tr is None or tendon.n_motors != tr.n_motors:
        raise InputError(f"tendon: expected the values of the model's {0 if tr is None else tr.n_motors} motors, "
                         f"got {tendon.n_motors}")
    if not np.all(tr.rotor_inertia > 0):
        k = int(np.flatnonzero(~(tr.rotor_inertia > 0))[0])
        raise InputError(f"tendon: the series-elastic tendon's rotor is a joint of its own and needs J_m > 0; motor "
                         f"{tr.motor_names[k]!r} has rotor_inertia {float(tr.rotor_inertia[k]):g}")
    if tr.elastic and not np.allclose(tendon.compliance, tr.tendon_compliance, rtol=1e-12, atol=0.0):
        raise InputError(f"tendon: its compliance 1/k_m {tendon.compliance.tolist()} differs from the model's "
                         f"tendon_compliance {tr.tendon_compliance.tolist()} (rad/(N m)); build it with "
                         "ElasticTendon.of(model)")


def model_mjcf(model: Any, *, limits: bool = True, timestep: float = 1e-4, integrator: str = "RK4",
               tip_radius: float = 0.005, tendon: Any = None, stiction: float | None = None) -> str:
    """MJCF text of ``model`` (any :class:`~alpes_dyn.Model`: a URDF with or without a spec, an Alpes model).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model; its tree, inertias, joint limits, springs, armature, friction, motors (fixed tendons and
        motor actuators), rotor inertia (tendon armature), tips and gravity are written (module doc).
    limits : bool, optional
        Joint ranges from the URDF limits, ``limited="true"`` (default True); ``False``: unlimited joints
        (then :meth:`Model.from_mjcf <alpes_dyn.Model.from_mjcf>` refuses the text: it needs ranges).
    timestep : float, optional
        MuJoCo's time step, s (default 1e-4).
    integrator : str, optional
        One of :data:`INTEGRATORS` (default ``"RK4"``).
    tip_radius : float, optional
        Radius (m) of the sphere geom at each tip, in the touch sensor's site (1.25 x as large; default 0.005);
        0: the site alone (MuJoCo's default size, 5 mm), no geom.
    tendon : ElasticTendon or None, optional
        An :class:`~alpes_dyn.model.tendon.ElasticTendon` of the model's motors: series-elastic, pull-only
        cables, each motor driving a rotor hinge ``<motor>_rotor`` of its own (``armature`` J_m, the spec's
        ``rotor_inertia``, > 0) coupled to its joints through the fixed tendon ``<motor>`` = theta_m - S_k q with
        stiffness k_m, damping c_m and the play as a dead band; ``encoder_<motor>`` reads the rotor,
        ``tendon_<motor>`` the stretch. The same system as
        :class:`~alpes_dyn.symbolic.elastic_tendon.SeriesElasticSystem` (tested against MuJoCo). A model with a
        tendon compliance needs it (``ElasticTendon.of(model)``: the quasi-static stretch is a sensor law MuJoCo
        cannot hold, the cable's dynamics are); default None: rigid tendons.
    stiction : float or None, optional
        Time constant (s) of MuJoCo's dry-friction constraint (``solreffriction``) on every joint with Coulomb
        friction, e.g. :data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST` (0.5 ms), with the impedance
        :data:`STICTION_IMPEDANCE` (``solimpfriction``, as the Alpes writer's): a real stick-slip, where MuJoCo's
        default (20 ms, 0.9) is soft on a light finger (it slides below F_s); default None: MuJoCo's default.

    Returns
    -------
    str: MJCF text, deterministic; :class:`~alpes_dyn.ModelError` if MuJoCo cannot express the model (module doc).
    """
    if not all(hasattr(model, a) for a in ("pin_model", "extras", "transmission", "tips", "gravity")):
        raise ModelError(f"model: expected an alpes_dyn.Model, got {type(model).__name__}")
    if model.transmission is not None and model.transmission.curved:
        raise ModelError(f"model: {model.name!r}'s ratios change with q (ratio_curve or path); the MJCF export writes "
                         "fixed tendons, whose ratios are constant")
    if not isinstance(limits, (bool, np.bool_)):
        raise InputError(f"limits: expected True or False, got {limits!r}")
    _check_args(timestep, integrator, tip_radius)
    tr = model.transmission
    if tendon is not None:
        _check_tendon(model, tendon)
    elif tr is not None and tr.elastic:  # nothing silently dropped: the quasi-static stretch has no MJCF form
        raise ModelError("tendon_compliance: an elastic tendon (y = S q + C tau_m) is a sensor law MuJoCo cannot "
                         "hold; export its cable's dynamics (tendon=ElasticTendon.of(model)) or rigid tendons")
    if tr is not None and tr.has_capstan:  # nor the sheath friction: MuJoCo has none
        raise ModelError("capstan: a tendon's sheath friction (mu theta) has no MJCF form (MuJoCo has no "
                         "tension-dependent tendon friction); export the spec without it")
    check_stiction(stiction)
    tree, sites = _tree(model, bool(limits), float(tip_radius), None if stiction is None else float(stiction))
    if tendon is not None:
        tree[-1:-1] = _rotor_bodies(model)  # before </worldbody>
    head = [f"<mujoco model={_q(model.name)}>",
            "  <!-- Generated by alpes_dyn.model.mjcf_export from a URDF + spec model; do not edit. -->",
            '  <compiler angle="radian" autolimits="true" inertiafromgeom="false" balanceinertia="false"/>',
            f'  <option timestep="{_f(timestep)}" gravity="{_v(model.gravity)}" integrator="{integrator}"/>']
    return "\n".join(head + tree + _equality(model, float(timestep)) + _transmission(model, sites, tendon)
                     + ["</mujoco>"]) + "\n"
