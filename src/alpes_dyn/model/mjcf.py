"""MJCF export: the Alpes models for MuJoCo, from the same parameter file as the URDF.

:func:`mjcf_string` writes the kinematics and inertias of :func:`~alpes_dyn.urdf_string` (same
bodies, joints, frames, COMs and inertias about the COM) plus what URDF cannot hold and MuJoCo can:

* joint springs: ``stiffness`` k_i with ``springref = 0`` (rest at q = 0), under the library's spring
  law (:func:`~alpes_dyn.model.extras.spring_stiffness`; torsional by default);
* joint stops: ``range`` = the parameter file's limits, ``limited`` (``limits=False`` drops them);
* rotor inertia (``rotor_inertia=True``): the motor's rotor J_m on its tendon, the fixed tendon's
  ``armature`` J_m / r_m^2 (kg on the tendon length l = r sum q_i, with q_m = l / r_m: MuJoCo adds
  armature J_l^T J_l, i.e. (r/r_m)^2 J_m on every entry of the chain's block, the library's
  S^T diag(J_m) S of eq. 2.8), and ``armature`` abduction_ratio^2 J_m on the thumb's ab/adduction
  joint, which its motor drives alone (as :meth:`Model.alpes <alpes_dyn.Model.alpes>`);
* friction (``friction=True``): ``damping`` F_v and ``frictionloss`` F_s (eq. 2.6; MuJoCo's dry
  friction is a constraint, the library's a smooth sign);
* one fixed tendon per flexion motor, length l = sum_i r q_i over the motor's joints, and a
  ``motor`` on it with gear 1/r_m: a motor torque tau_m pulls the cable with tau_m / r_m and gives
  r tau_m / r_m on each joint, the library's Gamma = S^T tau_m (:class:`~alpes_dyn.Transmission`);
  its ``ctrlrange`` is [0, tau_max]: a cable only pulls. The thumb's ab/adduction motor acts on its
  joint with gear ``abduction_ratio`` and ``ctrlrange`` [-tau_max, tau_max];
* sensors, per motor: ``encoder_<motor>`` (``actuatorpos`` = gear x tendon length = q_m, the
  encoder angle of eq. 3.13, rad), ``tendon_<motor>`` (``tendonpos``, m), ``torque_<motor>``
  (``actuatorfrc`` = tau_m, N m); per chain: ``flexiforce_<chain>`` (``touch`` at the fingertip
  pad site ``<tip>_pad``: the normal contact force, N, the FlexiForce sensor of Section 2.2);
* collision geoms: a capsule per phalanx (the URDF's cylinder radius), a box for the palm
  (hand only), contacts between the palm and the proximal phalanges excluded;
* a ``site`` at every tip frame (named as the URDF frame), for checks and rendering.

Effects of a real hand that the library's rigid model leaves out (each off by default: the text is then the
same, byte for byte), for plants "we did not write" (:mod:`alpes_dyn.control.plants`, ``benchmarks/realism.py``):

* ``stiction=tau``: stick-slip dry friction. MuJoCo's ``frictionloss`` = F_s is a constraint whose softness is
  ``solreffriction``; with MuJoCo's default (0.02 s) it is soft on this light finger (joint 3 reaches only
  0.70 F_s while sliding, and creeps at 0.4 rad/s under 0.8 F_s). A time constant tau of a fraction of a
  millisecond (:data:`STICTION_TIMECONST`, 0.5 ms) gives the full F_s while sliding, and an impedance
  close to 1 (``solimpfriction``, :data:`STICTION_IMPEDANCE`) real stick phases (the joint stays at rest,
  creeping by 1e-4 rad/s, while the torque is below F_s). MuJoCo has no Stribeck curve (no breakaway torque above F_s): stiction here is the
  frictionloss constraint alone. Written with ``damping`` F_v, as ``friction=True``;
* ``tendon_stiffness=k_t`` (N/m, with ``tendon_damping=c_t``, N s/m): a series-elastic tendon. Each flexion
  motor drives a rotor hinge ``<motor>_rotor`` of its own (``armature`` J_m, the rotor's inertia on the
  motor side, eq. 2.8's I_a), the motor actuator on that joint (gear 1, ``ctrlrange`` [0, tau_max]); the
  fixed tendon ``<motor>`` is the cable's stretch e = r_m theta_m - sum_i r q_i (m), with stiffness k_t,
  damping c_t and ``springlength="-1 0"``: MuJoCo's dead band makes the spring pull only (tension
  T = k_t max(e, 0): a slack cable pushes nothing; the damping c_t acts on de/dt slack or not; with
  ``tendon_dead_band=delta`` (m) the cable has play, ``springlength="-1 delta"``, T = k_t max(e - delta, 0)). Our own
  model of the same system: :class:`~alpes_dyn.symbolic.elastic_tendon.SeriesElasticSystem`. The joints
  get r T each, the rotor -r_m T. ``encoder_<motor>`` measures the rotor, ``tendon_<motor>`` the stretch e;
* ``tendon_rotor=True``: the rotor inertia on a rigid tendon, ``armature`` J_m / r_m^2 (kg) on each flexion
  tendon: MuJoCo adds it as J_m S^T S to the joints' mass matrix (every entry of the chain's block, not
  only the diagonal as ``rotor_inertia``'s N^2 J_m);
  with either rotor option the thumb's ab/adduction joint (a gear on the joint, no tendon) gets its
  rotor as ``armature`` abduction_ratio^2 J_m;
* ``tilt=angle`` (rad): the palm tilted in the finger's plane, gravity rotated about the base frame's y
  axis (the joint axes' line): :func:`tilted_gravity`.

Scenes (``scene=``): ``"block"`` (finger2/finger3) adds a fixed, frictionless box whose face meets
the fingertip at the configuration ``contact_q``, at an angle ``block_tilt`` to the distal phalanx
(the block pushes the fingertip along the face's normal n, :func:`block_normal`: F = -F_z n with
F_z >= 0 the FlexiForce reading); ``"cylinder"`` (hand) adds a
fixed, frictionless cylinder across the fingers, in front of the palm, that the hand can grasp (:data:`CYLINDER`). With the
parameter file's gravity (palm up) the fingers lift their own weight; ``palm_down=True`` reverses
it, the fingers then press down on the object, as in :mod:`alpes_dyn.control`.

Joint order: MuJoCo's qpos/qvel follow the bodies' depth-first order, the URDF's (and
:attr:`Model.joint_names <alpes_dyn.Model.joint_names>`) order too; :func:`joint_permutation`
checks it by name.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .description import check_model_name, layout, model_params
from ..checks import as_float_array
from ..errors import AlpesDynWarning, InputError, ModelError
from ..limits import check_physical
from .extras import spring_stiffness
from .friction import Creep
from .mjcf_export import STICTION_IMPEDANCE, check_stiction, creep_attributes, stiction_attributes
from .params import ChainParams, HandParams, load_params

__all__ = ["SCENES", "STICTION_TIMECONST", "STICTION_IMPEDANCE", "tilted_gravity", "mjcf_string", "load_mujoco", "joint_permutation", "contact_tip_position", "palm_down_params",
           "block_normal", "BLOCK_TILT",
           "BLOCK_CONTACT_Q", "CYLINDER"]

SCENES: tuple[str, ...] = ("none", "block", "cylinder")
#: Default configuration (rad) at which the block's lower face touches the fingertip pad.
BLOCK_CONTACT_Q: tuple[float, ...] = (0.9, 0.5, 0.5)
#: Angle (rad) between the distal phalanx at :data:`BLOCK_CONTACT_Q` and the block's face.
BLOCK_TILT: float = 0.15
#: The cylinder of the hand scene: centre (m, palm frame), radius (m), half-length (m); its axis is y. Frictionless
#: (``condim="1"``) like the block: the contact force is the normal force the FlexiForce reads. Placed where the four
#: fingertips and the thumb's (ab/adduction at 35 degrees) meet it with their pads before any other phalanx touches,
#: the hand palm down (see :func:`alpes_dyn.control.hand_loop.run_hand_control`).
#: Time constant (s) of MuJoCo's dry-friction constraint (``solreffriction``) that gives stick-slip on the finger.
STICTION_TIMECONST: float = 5e-4
#: The rotor bodies of the series-elastic tendon: a point mass (kg) and inertia (kg m^2) that MuJoCo needs for a
#: body, 1e-5 of the rotor's J_m = 1e-7 kg m^2 (the rotor's inertia is the joint's ``armature``).
_ROTOR_MASS, _ROTOR_INERTIA = 1e-6, 1e-12
CYLINDER = {"center": (0.01, 0.0, 0.08), "radius": 0.025, "half_length": 0.08}


def _f(x: float) -> str:
    return repr(float(x))


def _v(xs: Sequence[float]) -> str:
    return " ".join(_f(x) for x in xs)


def _params(params: HandParams | str | Path | None) -> HandParams:
    return params if isinstance(params, HandParams) else load_params(params)


def palm_down_params(params: HandParams) -> HandParams:
    """``params`` with gravity reversed: the hand turned palm down (the base frame's +z, toward which the
    fingers flex, points down), so that a finger presses on an object under it.

    Parameters
    ----------
    params : HandParams
        The parameters (not changed).

    Returns
    -------
    HandParams
        A copy with ``gravity`` negated, m/s^2.
    """
    import dataclasses

    return dataclasses.replace(params, gravity=-np.asarray(params.gravity, dtype=float))


def tilted_gravity(gravity: Sequence[float], tilt: float) -> np.ndarray:
    """Gravity (3,), m/s^2, in the base frame of a hand tilted by ``tilt`` (rad) in the finger's plane (x-z):
    R_y(tilt) g, the rotation about the base frame's y axis (the joints' axes are along -y). With the
    shipped palm-up gravity (0, 0, -g): (-g sin(tilt), 0, -g cos(tilt)). The same vector goes to
    :class:`~alpes_dyn.Model` (``Model.copy(gravity=...)``) for the same tilted hand.

    Parameters
    ----------
    gravity : sequence of float, shape (3,)
        Gravity in the untilted base frame, m/s^2.
    tilt : float
        The tilt about the base frame's y axis, rad.

    Returns
    -------
    numpy.ndarray, shape (3,)
        R_y(tilt) g, m/s^2.
    """
    g = np.asarray(gravity, dtype=float)
    c, s_ = math.cos(tilt), math.sin(tilt)
    return np.array([c * g[0] + s_ * g[2], g[1], -s_ * g[0] + c * g[2]])


HANGING_TILT = -math.pi / 2
"""The tilt (rad, :func:`tilted_gravity`) of a hand hung fingers down: the palm turned by -90 degrees about the
joints' axes from level, gravity along the fingers' length at q = 0 (+x of the base frame)."""


def hanging_gravity(gravity: Sequence[float]) -> np.ndarray:
    """Gravity (3,), m/s^2, in the base frame of the hand hung fingers down (:data:`HANGING_TILT`): the
    identification experiment's orientation for fingers whose springs cannot hold them mid-range palm up (gravity
    then pulls along the finger, its static equilibria do not
    fold; :mod:`alpes_dyn.estimation.experiments.experiment`)."""
    return tilted_gravity(gravity, HANGING_TILT)


def block_normal(contact_q: Sequence[float], tilt: float = BLOCK_TILT) -> np.ndarray:
    """Unit normal n (3,) of the block scene's face, base frame, pointing from the fingertip into the block:
    the pad's normal at ``contact_q`` turned back by ``tilt`` (rad) so that the fingertip's end, not
    the side of the distal phalanx, meets the face. The block pushes the finger with F = -F_z n.

    Parameters
    ----------
    contact_q : sequence of float, shape (n,)
        The planar chain's joint angles at contact, rad (their sum is the pad's direction).
    tilt : float, optional
        The angle between the distal phalanx and the face, rad (default :data:`BLOCK_TILT`).

    Returns
    -------
    numpy.ndarray, shape (3,)
        n = (-sin b, 0, cos b) with b = sum(contact_q) - tilt.
    """
    b = float(np.sum(np.asarray(contact_q, dtype=float))) - float(tilt)
    return np.array([-math.sin(b), 0.0, math.cos(b)])


def contact_tip_position(chain: ChainParams, q: Sequence[float]) -> np.ndarray:
    """Tip-frame position (x, z) of a planar chain at joint angles q (m), in the chain's base frame.

    Positive q turns +x toward +z (joint axes along -y), as in the URDF.

    Parameters
    ----------
    chain : ChainParams
        The chain; its phalanx lengths L (m), the first ``len(q)`` used.
    q : sequence of float, shape (n,)
        Joint angles, rad.

    Returns
    -------
    numpy.ndarray, shape (2,)
        (x, z) = (sum L cos(a), sum L sin(a)) with a the cumulative angles, m.
    """
    q = np.asarray(q, dtype=float)
    a = np.cumsum(q)
    L = chain.L[: q.shape[0]]
    return np.array([float(np.sum(L * np.cos(a))), float(np.sum(L * np.sin(a)))])


class _Writer:
    def __init__(self, p: HandParams, spring: str, friction: bool, rotor_inertia: bool, limits: bool,
                 stiction: float | None = None) -> None:
        self.p = p
        self.stiction = stiction
        self.spring = spring
        self.friction = friction
        self.rotor_inertia = rotor_inertia
        self.limits = limits
        self.lines: list[str] = []

    def joint(self, name: str, axis: Sequence[float], k: float, armature: float, lo: float, hi: float, ind: str,
              F_s: float | None = None, F_v: float | None = None, rotor: bool = False) -> str:
        """A hinge; friction F_s, F_v (default: the file's ``[friction]`` values); ``armature`` with
        ``rotor_inertia`` or ``rotor`` (the ab/adduction's rotor under a tendon-rotor option)."""
        attrs = [f'name="{name}"', 'type="hinge"', f'axis="{_v(axis)}"', 'pos="0 0 0"',
                 f'stiffness="{_f(k)}"', 'springref="0"']
        if self.limits:
            attrs += ['limited="true"', f'range="{_f(lo)} {_f(hi)}"']
        else:
            attrs += ['limited="false"']
        if (self.rotor_inertia or rotor) and armature > 0:
            attrs.append(f'armature="{_f(armature)}"')
        if self.friction:
            Fv = self.p.F_v if F_v is None else F_v
            Fs = self.p.F_s if F_s is None else F_s
            attrs += [f'damping="{_f(Fv)}"', f'frictionloss="{_f(Fs)}"']
            if self.stiction is not None:
                attrs.append(stiction_attributes(self.stiction))
            elif self.p.friction_law == "creep":  # the file's creep law: MuJoCo's soft constraint of its band
                attrs.append(creep_attributes(Creep(self.p.creep_kappa, self.p.creep_rate)))
        return f"{ind}<joint {' '.join(attrs)}/>\n"

    def chain(self, prefix: str, ch: ChainParams, n: int, K: np.ndarray, pos: Sequence[float], quat: Sequence[float],
              ind: str, rgba: str) -> str:
        """Nested bodies p1..pn of a planar chain, joints j1..jn, a tip site and a pad site."""
        p = self.p
        k = spring_stiffness(np.asarray(K[:n], dtype=float), self.spring, p.b, p.r)
        d, I_com = ch.com_from_joint, ch.I_com
        out = []
        cur = ind
        for i in range(n):
            bpos = pos if i == 0 else (ch.L[i - 1], 0.0, 0.0)
            bquat = f' quat="{_v(quat)}"' if i == 0 else ""
            out.append(f'{cur}<body name="{prefix}p{i + 1}" pos="{_v(bpos)}"{bquat}>\n')
            inner = cur + "  "
            out.append(self.joint(f"{prefix}j{i + 1}", (0, -1, 0), k[i], 0.0, p.finger_lower, p.finger_upper,
                                  inner, None if ch.F_s is None else float(ch.F_s[i]),
                                  None if ch.F_v is None else float(ch.F_v[i])))
            ixx = 0.5 * ch.m[i] * ch.radius**2
            out.append(f'{inner}<inertial pos="{_v((d[i], 0, 0))}" mass="{_f(ch.m[i])}" '
                       f'diaginertia="{_v((ixx, I_com[i], I_com[i]))}"/>\n')
            out.append(f'{inner}<geom name="{prefix}p{i + 1}" type="capsule" fromto="0 0 0 {_f(ch.L[i])} 0 0" '
                       f'size="{_f(ch.radius)}" rgba="{rgba}"/>\n')
            cur = inner
        out.append(f'{cur}<site name="{prefix}tip" pos="{_v((ch.L[n - 1], 0, 0))}" size="0.002" rgba="1 0 0 1"/>\n')
        out.append(f'{cur}<site name="{prefix}tip_pad" type="sphere" pos="{_v((ch.L[n - 1], 0, 0))}" '
                   f'size="{_f(1.25 * ch.radius)}" rgba="0.9 0.3 0.2 0.25"/>\n')
        for i in reversed(range(n)):
            out.append(f"{ind}{'  ' * i}</body>\n")
        return "".join(out)


_FINGER_RGBA = "0.75 0.75 0.8 1"


def mjcf_string(model: str, params: HandParams | str | Path | None = None, *, chain: str | None = None,
                spring: str = "torsional",
                friction: bool = False, rotor_inertia: bool = False, limits: bool = True, contact: bool = True,
                scene: str = "none", contact_q: Sequence[float] | None = None,
                block_friction: float = 0.0, block_tilt: float = BLOCK_TILT, palm_down: bool = False, timestep: float = 2.5e-4,
                stiction: float | None = None, tendon_stiffness: float | None = None, tendon_damping: float = 0.0,
                tendon_rotor: bool = False, tilt: float = 0.0, tendon_dead_band: float = 0.0) -> str:
    """MJCF text of ``model`` (``finger2``, ``finger3`` or ``hand``) built from ``params``.

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3``, ``hand`` or ``thumb``.
    params : HandParams or str or Path or None, optional
        A :class:`~alpes_dyn.HandParams`, a parameter file, or ``None`` (default) for the shipped one.
    chain : str or None, optional
        A finger model built from that finger of the hand (as :meth:`Model.alpes <alpes_dyn.Model.alpes>`);
        the hand uses each finger's own values (``[finger.<name>]``), everywhere: inertias, springs, friction.
    spring : str, optional
        The spring model (default ``"torsional"``), as :meth:`Model.alpes <alpes_dyn.Model.alpes>`, so that the
        MuJoCo model and ``Model.alpes(model, spring, friction, rotor_inertia, params)`` are the same system.
    friction : bool, optional
        Joint friction F_s, F_v (default False), as :meth:`Model.alpes <alpes_dyn.Model.alpes>`.
    rotor_inertia : bool, optional
        The motors' rotor inertia (default False), as :meth:`Model.alpes <alpes_dyn.Model.alpes>`.
    limits : bool, optional
        Joint stops (``range``, ``limited``) from the parameter file's limits (default True).
    contact : bool, optional
        Collisions (default True); ``False`` writes ``<flag contact="disable"/>``.
    scene : str, optional
        ``"none"`` (default), ``"block"`` (finger2/finger3: a fixed block on the fingertip pad at
        ``contact_q``) or ``"cylinder"`` (hand: a fixed cylinder across the fingers, :data:`CYLINDER`).
    contact_q : sequence of float or None, optional
        Joint angles (rad) at which the block touches the fingertip (default None: :data:`BLOCK_CONTACT_Q`).
    block_friction : float, optional
        Friction coefficient of the block (default 0: frictionless, ``condim="1"``, so the contact force is normal
        to the block, the report's no-sliding F = [0, 0, F_z] of eq. 2.13 in the block's frame).
    block_tilt : float, optional
        Angle (rad) between the distal phalanx there and the block's face (:func:`block_normal`; default
        :data:`BLOCK_TILT`).
    palm_down : bool, optional
        The hand turned over, gravity reversed (see :func:`palm_down_params`; default False): the fingers flex
        with gravity, toward an object under them, as in the block scene of :mod:`alpes_dyn.control`.
    timestep : float, optional
        MuJoCo's time step, s (default 2.5e-4, the estimation scenario's integration step).
    stiction : float or None, optional
        Time constant (s) of the dry-friction constraint (``solreffriction``), e.g. :data:`STICTION_TIMECONST`:
        stick-slip friction, F_s and F_v written as with ``friction=True``; default None: none.
    tendon_stiffness : float or None, optional
        k_t (N/m) of a series-elastic, pull-only tendon with its own rotor joint (module docstring); None
        (default): the rigid tendon (with a warning where the parameter file holds a tendon compliance C: its cable
        is k_t = 1 / (C r_m^2), refused if given otherwise).
    tendon_damping : float, optional
        c_t (N s/m) of the series-elastic tendon (default 0).
    tendon_rotor : bool, optional
        The rotor inertia J_m / r_m^2 as the rigid tendon's ``armature`` (J_m S^T S on the joints; default False).
    tilt : float, optional
        The palm tilted in the finger's plane, rad (:func:`tilted_gravity`; default 0); applied after
        ``palm_down``.
    tendon_dead_band : float, optional
        The cable's play, m (>= 0, with ``tendon_stiffness``; default 0): slack up to this stretch, the spring
        pulling k_t (e - dead band) beyond it (``springlength="-1 <dead band>"``). The same system as
        :class:`~alpes_dyn.symbolic.elastic_tendon.SeriesElasticSystem` with ``ElasticTendon.from_cable``.

    Returns
    -------
    str
        MJCF text, deterministic for given arguments.
    """
    _check_mjcf_arguments(model, spring, scene, timestep, block_friction, block_tilt, contact_q)
    p = model_params(model, _params(params), chain)
    tendon_stiffness = _file_cable(p, tendon_stiffness)
    if p.capstan > 0:  # nothing silently dropped: MuJoCo has no sheath friction
        warnings.warn(AlpesDynWarning(
            f"transmission.capstan: MuJoCo has no tendon-sheath friction; the file's (mu theta {p.capstan:g}) is not "
            "in this MJCF (the recording plant, alpes_dyn.control.plants, adds it by a passive-force callback)"),
            stacklevel=2)
    _check_effects(stiction, tendon_stiffness, tendon_damping, tendon_rotor, tilt, rotor_inertia, tendon_dead_band)
    if palm_down:
        p = palm_down_params(p)
    lay = layout(model, p)
    w = _Writer(p, spring, friction or stiction is not None, rotor_inertia, limits, stiction)
    rotor = tendon_rotor or tendon_stiffness is not None
    g = p.gravity if tilt == 0 else tilted_gravity(p.gravity, tilt)
    body: list[str] = ['  <worldbody>\n', '    <light name="top" pos="0.05 -0.3 0.4" dir="0 0.6 -0.8" diffuse="0.8 0.8 0.8"/>\n']
    excludes: list[tuple[str, str]] = []
    if model in ("finger2", "finger3"):
        body += _finger_bodies(w, p, 2 if model == "finger2" else 3, scene, contact_q, block_tilt, block_friction)
    else:
        body += _hand_bodies(w, p, model, spring, rotor, scene, excludes)
    if tendon_stiffness is not None:
        body += [_rotor_body(ch.name, p.J_m) for ch in lay.chains]
    body.append("  </worldbody>\n")
    parts = [_head(model, p, timestep, g, contact), *body]
    if excludes:
        parts.append("  <contact>\n" + "".join(f'    <exclude body1="{a}" body2="{b}"/>\n' for a, b in excludes)
                     + "  </contact>\n")
    tendons, actuators, sensors = _transmission(lay, p, tendon_stiffness, tendon_damping, tendon_dead_band,
                                                tendon_rotor or rotor_inertia)
    parts.append("  <tendon>\n" + "".join(tendons) + "  </tendon>\n")
    parts.append("  <actuator>\n" + "".join(actuators) + "  </actuator>\n")
    parts.append("  <sensor>\n" + "".join(sensors) + "  </sensor>\n")
    parts.append("</mujoco>\n")
    return "".join(parts)


def _check_mjcf_arguments(model: str, spring: str, scene: str, timestep: Any, block_friction: Any, block_tilt: Any,
                          contact_q: Any) -> None:
    """One-line errors for :func:`mjcf_string`'s model, spring law, scene and the scene's and MuJoCo's numbers."""
    from .extras import SPRING_MODELS

    check_model_name(model)
    if spring not in SPRING_MODELS:
        raise ModelError(f"unknown spring model {spring!r} (expected one of {', '.join(SPRING_MODELS)})")
    if scene not in SCENES:
        raise ModelError(f"unknown scene {scene!r} (expected one of {', '.join(SCENES)})")
    if scene == "block" and model in ("hand", "thumb"):
        raise ModelError(f"scene 'block' is for one finger (finger2, finger3), not {model!r}")
    if scene == "cylinder" and model != "hand":
        raise ModelError(f"scene 'cylinder' is for the hand, not {model!r}; a finger's scene is 'block'")
    if isinstance(timestep, bool) or not (isinstance(timestep, (int, float)) and _finite(timestep) and timestep > 0):
        raise InputError(f"timestep: expected a positive number of seconds, got {timestep!r:.60}")
    if isinstance(block_friction, bool) or not (isinstance(block_friction, (int, float)) and _finite(block_friction)
                                                and block_friction >= 0):
        raise InputError(f"block_friction: expected a friction coefficient >= 0, got {block_friction!r:.60}")
    if isinstance(block_tilt, bool) or not (isinstance(block_tilt, (int, float)) and _finite(block_tilt)):
        raise InputError(f"block_tilt: expected a finite angle in rad, got {block_tilt!r:.60}")
    check_physical(float(timestep), "timestep", "s", "pos")
    check_physical(float(block_friction), "block_friction", "-", "nonneg")
    check_physical(float(block_tilt), "block_tilt", "rad", "any")
    if contact_q is not None:
        as_float_array(contact_q, "contact_q", "joint angles in rad")  # not complex, bool or text
        if scene != "block":
            raise InputError(f"contact_q: places the block of scene='block'; the scene is {scene!r}")


def _head(model: str, p: HandParams, timestep: float, g: Sequence[float], contact: bool) -> str:
    """The document's opening: the model's name, the compiler, the option (time step, gravity ``g`` m/s^2, the
    contacts disabled where ``contact`` is off), the visual and the geoms' defaults."""
    opt = f'timestep="{_f(timestep)}" gravity="{_v(g)}" integrator="implicitfast"'
    option = f"  <option {opt}>\n    <flag contact=\"disable\"/>\n  </option>\n" if not contact else f"  <option {opt}/>\n"
    return (
        f'<mujoco model="alpes_{model}">\n'
        f"  <!-- Generated by alpes_dyn from {Path(p.path).name or 'parameters'}; do not edit. -->\n"
        '  <compiler angle="radian" autolimits="true" inertiafromgeom="auto" balanceinertia="false"/>\n'
        + option +
        '  <visual><global offwidth="800" offheight="600"/></visual>\n'
        "  <default>\n"
        '    <geom condim="3" friction="0.3 0.005 0.0001" solref="0.002 1" solimp="0.95 0.99 0.001"/>\n'
        "  </default>\n"
    )


def _finger_bodies(w: _Writer, p: HandParams, n: int, scene: str, contact_q: Any, block_tilt: float,
                   block_friction: float) -> list[str]:
    """The finger's chain of ``n`` phalanges at the origin and, in the block scene, the block whose face meets the
    fingertip pad at ``contact_q`` (rad) at ``block_tilt`` (rad) to the distal phalanx."""
    f = p.finger
    body = [w.chain("", f, n, f.K, (0, 0, 0), (1, 0, 0, 0), "    ", _FINGER_RGBA)]
    if scene == "block":
        cq = np.asarray(BLOCK_CONTACT_Q[:n] if contact_q is None else contact_q, dtype=float)
        if cq.shape != (n,) or not np.isfinite(cq).all():
            raise InputError(f"contact_q: expected {n} finite joint angles, got {np.asarray(contact_q).tolist()!r}")
        (x, z), nrm = contact_tip_position(f, cq), block_normal(cq, block_tilt)
        fz = np.array([nrm[0], nrm[2]])  # the face's normal, from the finger into the block
        fx = np.array([fz[1], -fz[0]])   # along the face, toward the fingertip's free end
        half = (0.035, 0.02, 0.01)
        c = np.array([x, z]) + (f.radius + half[2]) * fz + 0.015 * fx
        b = float(np.sum(cq)) - block_tilt
        quat = (math.cos(b / 2), 0.0, -math.sin(b / 2), 0.0)
        block_condim = 1 if block_friction == 0 else 3
        body.append(f'    <geom name="block" type="box" pos="{_v((c[0], 0.0, c[1]))}" quat="{_v(quat)}" '
                    f'size="{_v(half)}" condim="{block_condim}" friction="{_f(block_friction)} 0.005 0.0001" '
                    'priority="1" rgba="0.4 0.6 0.8 1"/>\n')
    return body


def _hand_bodies(w: _Writer, p: HandParams, model: str, spring: str, rotor: bool, scene: str,
                 excludes: list[tuple[str, str]]) -> list[str]:
    """The palm with the four fingers (``hand``; each with its own values) and the thumb on its ab/adduction joint
    (``rotor``: its rotor as armature), and in the cylinder scene the cylinder; the palm's contacts with the
    proximal phalanges appended to ``excludes``."""
    body = ['    <body name="palm">\n'
            '      <geom name="palm" type="box" pos="0 0 -0.012" size="0.045 0.036 0.012" rgba="0.6 0.6 0.65 1"/>\n']
    for name, (x, y) in zip(p.finger_names if model == "hand" else (), p.finger_xy):
        f3 = p.chain(name)  # the finger's own values where the file gives them
        body.append(w.chain(f"{name}_", f3, 3, f3.K, (x, y, 0.0), (1, 0, 0, 0), "      ", _FINGER_RGBA))
        excludes.append(("palm", f"{name}_p1"))
    t = p.thumb
    yaw = p.thumb_yaw
    quat = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
    rb = t.radius
    ib = 0.4 * p.thumb_base_mass * rb**2
    body.append(f'      <body name="thumb_base" pos="{_v(p.thumb_xyz)}" quat="{_v(quat)}">\n')
    body.append(w.joint("thumb_abd", p.abduction_axis, spring_stiffness(np.array([p.abduction_K]), spring, p.b,
                                                                        p.r)[0],
                        p.abduction_ratio**2 * p.J_m, p.abduction_lower, p.abduction_upper, "        ",
                        p.abduction_F_s, p.abduction_F_v, rotor))
    body.append(f'        <inertial pos="0 0 0" mass="{_f(p.thumb_base_mass)}" diaginertia="{_v((ib, ib, ib))}"/>\n')
    body.append(f'        <geom name="thumb_base" type="sphere" size="{_f(rb)}" contype="0" conaffinity="0" '
                f'rgba="{_FINGER_RGBA}"/>\n')
    body.append(w.chain("thumb_", t, 2, t.K, (0, 0, 0), (1, 0, 0, 0), "        ", _FINGER_RGBA))
    body.append("      </body>\n    </body>\n")
    excludes += [("palm", "thumb_base"), ("palm", "thumb_p1")]
    if scene == "cylinder":
        c = CYLINDER
        body.append(f'    <geom name="cylinder" type="cylinder" pos="{_v(c["center"])}" quat="0.7071067811865476 '
                    f'0.7071067811865476 0 0" size="{_f(c["radius"])} {_f(c["half_length"])}" condim="1" '
                    'friction="0 0.005 0.0001" priority="1" rgba="0.4 0.6 0.8 1"/>\n')
    return body


def _transmission(lay: Any, p: HandParams, tendon_stiffness: float | None, tendon_damping: float,
                  tendon_dead_band: float, rotor_armature: bool) -> tuple[list[str], list[str], list[str]]:
    """(tendons, actuators, sensors) in the Transmission's order, flexion motors then ab/adduction motors: a fixed
    tendon (with the rotor as ``armature`` where ``rotor_armature``) or the elastic cable to the motor's rotor per
    flexion motor, each motor's encoder, tendon and torque sensors, and each chain's FlexiForce."""
    tendons, actuators, sensors = [], [], []
    for ch in lay.chains:
        if tendon_stiffness is not None:
            tendons.append(_elastic_tendon(ch.name, ch.joints, p, tendon_stiffness, tendon_damping, tendon_dead_band))
            actuators.append(f'    <motor name="{ch.name}" joint="{ch.name}_rotor" gear="1" '
                             f'ctrlrange="0 {_f(p.tau_max)}"/>\n')
        else:
            coefs = "".join(f'      <joint joint="{j}" coef="{_f(p.r)}"/>\n' for j in ch.joints)
            arm = f' armature="{_f(p.J_m / p.r_m**2)}"' if rotor_armature and p.J_m > 0 else ""
            tendons.append(f'    <fixed name="{ch.name}"{arm}>\n{coefs}    </fixed>\n')
            actuators.append(f'    <motor name="{ch.name}" tendon="{ch.name}" gear="{_f(1.0 / p.r_m)}" '
                             f'ctrlrange="0 {_f(p.tau_max)}"/>\n')
        sensors += [f'    <actuatorpos name="encoder_{ch.name}" actuator="{ch.name}"/>\n',
                    f'    <tendonpos name="tendon_{ch.name}" tendon="{ch.name}"/>\n',
                    f'    <actuatorfrc name="torque_{ch.name}" actuator="{ch.name}"/>\n']
    for ch in lay.chains:
        if ch.abduction:
            mname = f"{ch.name}_abduction"
            actuators.append(f'    <motor name="{mname}" joint="{ch.abduction}" gear="{_f(p.abduction_ratio)}" '
                             f'ctrlrange="{_f(-p.tau_max)} {_f(p.tau_max)}"/>\n')
            sensors += [f'    <actuatorpos name="encoder_{mname}" actuator="{mname}"/>\n',
                        f'    <actuatorfrc name="torque_{mname}" actuator="{mname}"/>\n']
    for ch in lay.chains:
        sensors.append(f'    <touch name="flexiforce_{ch.name}" site="{ch.tip}_pad"/>\n')
    return tendons, actuators, sensors


def _file_cable(p: HandParams, tendon_stiffness: float | None) -> float | None:
    """``tendon_stiffness`` checked against the parameter file's cable where it holds a tendon compliance C
    (``transmission.tendon_compliance``, as ``alpes-dyn identify`` writes it: k_t = 1 / (C r_m^2)); both, differing,
    are refused (one cable, written once). Without ``tendon_stiffness`` the tendon stays rigid, with a warning: the
    compliance is the quasi-static stretch the encoder sees, and its cable's dynamics (the rotor's mode, undamped
    without a ``tendon_damping``) are a plant of their own, asked for with ``tendon_stiffness=k_t``."""
    C = float(p.tendon_compliance)
    if C <= 0:
        return tendon_stiffness
    k_file = 1.0 / (C * p.r_m**2)
    if tendon_stiffness is None:
        warnings.warn(AlpesDynWarning(
            f"transmission.tendon_compliance: the file's cable ({C:g} rad/(N m)) is written as a rigid tendon; its "
            f"series-elastic plant is tendon_stiffness={k_file:.6g} N/m with a tendon_damping (the command line's "
            f"--tendon-stiffness {k_file:.6g} --tendon-damping N_S_PER_M)"), stacklevel=3)
        return None
    if not (isinstance(tendon_stiffness, (int, float, np.integer, np.floating)) and not isinstance(tendon_stiffness, bool)
            and math.isclose(tendon_stiffness, k_file, rel_tol=1e-12)):
        raise InputError(f"tendon_stiffness: {tendon_stiffness!r} N/m differs from the parameter file's cable "
                         f"(transmission.tendon_compliance {C:g} rad/(N m): k_t = 1/(C r_m^2) = {k_file:.6g} N/m)")
    return tendon_stiffness


def _check_effects(stiction: float | None, tendon_stiffness: float | None, tendon_damping: float,
                   tendon_rotor: bool, tilt: float, rotor_inertia: bool, tendon_dead_band: float = 0.0) -> None:
    """The realism options of :func:`mjcf_string`: numbers in range, no rotor counted twice."""
    def number(x: object) -> bool:
        return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and _finite(x)

    check_stiction(stiction)
    if tendon_stiffness is not None and not (number(tendon_stiffness) and tendon_stiffness > 0):
        raise InputError(f"tendon_stiffness: expected a positive stiffness in N/m, got {tendon_stiffness!r}")
    if not (number(tendon_damping) and tendon_damping >= 0):
        raise InputError(f"tendon_damping: expected a damping >= 0 in N s/m, got {tendon_damping!r}")
    if tendon_damping > 0 and tendon_stiffness is None:
        raise InputError("tendon_damping: needs tendon_stiffness (the rigid tendon has no stretch to damp)")
    if not (number(tendon_dead_band) and tendon_dead_band >= 0):
        raise InputError(f"tendon_dead_band: expected a cable's play >= 0 in m, got {tendon_dead_band!r}")
    if tendon_dead_band > 0 and tendon_stiffness is None:
        raise InputError("tendon_dead_band: needs tendon_stiffness (the rigid tendon has no play)")
    if not isinstance(tendon_rotor, (bool, np.bool_)):
        raise InputError(f"tendon_rotor: expected True or False, got {tendon_rotor!r}")
    if not number(tilt) or abs(tilt) > math.pi:
        raise InputError(f"tilt: expected a finite angle in rad within [-pi, pi], got {tilt!r}")
    if tendon_stiffness is not None and tendon_rotor:
        raise InputError("tendon_rotor: the series-elastic tendon (tendon_stiffness) has its rotor already")
    if rotor_inertia and (tendon_rotor or tendon_stiffness is not None):
        raise InputError(f"rotor_inertia: the rotor would be counted twice (with "
                         f"{'tendon_rotor' if tendon_rotor else 'tendon_stiffness'})")
    for name, x, unit, kind in (("stiction", stiction, "s", "pos"), ("tendon_stiffness", tendon_stiffness, "N/m", "pos"),
                                ("tendon_damping", tendon_damping, "N s/m", "nonneg"),
                                ("tendon_dead_band", tendon_dead_band, "m", "nonneg"), ("tilt", tilt, "rad", "any")):
        if x is not None:  # an absurd magnitude (a stiffness of 1e300 N/m) or a subnormal number
            check_physical(float(x), name, unit, kind)


def _finite(x: object) -> bool:
    """Whether the real number ``x`` is finite (an integer too large for a float is not)."""
    try:
        return math.isfinite(x)  # type: ignore[arg-type]
    except OverflowError:
        return False


def _rotor_body(motor: str, J_m: float) -> str:
    """A flexion motor's rotor: a hinge ``<motor>_rotor`` with ``armature`` J_m on a point body (no geom)."""
    return (f'    <body name="{motor}_rotor" pos="0 0 0">\n'
            f'      <joint name="{motor}_rotor" type="hinge" axis="0 -1 0" pos="0 0 0" limited="false" '
            f'armature="{_f(J_m)}"/>\n'
            f'      <inertial pos="0 0 0" mass="{_f(_ROTOR_MASS)}" diaginertia="{_v((_ROTOR_INERTIA,) * 3)}"/>\n'
            "    </body>\n")


def _elastic_tendon(motor: str, joints: Sequence[str], p: HandParams, k_t: float, c_t: float,
                    dead_band: float = 0.0) -> str:
    """The cable's stretch e = r_m theta_m - sum r q_i as a fixed tendon, a spring k_t pulling only (dead band
    below e = ``dead_band``, m) and a damper c_t."""
    coefs = f'      <joint joint="{motor}_rotor" coef="{_f(p.r_m)}"/>\n'
    coefs += "".join(f'      <joint joint="{j}" coef="{_f(-p.r)}"/>\n' for j in joints)
    return (f'    <fixed name="{motor}" stiffness="{_f(k_t)}" damping="{_f(c_t)}" springlength="-1 {_f(dead_band)}">\n'
            f"{coefs}    </fixed>\n")


def load_mujoco(xml: str):
    """A ``mujoco.MjModel`` from MJCF text.

    Parameters
    ----------
    xml : str
        MJCF text.

    Returns
    -------
    mujoco.MjModel
        The compiled model.

    Raises
    ------
    ModelError
        One line: MuJoCo is missing (``pip install 'alpes_dyn[mujoco]'``) or rejects the text.
    """
    try:
        import mujoco
    except ImportError:
        raise ModelError("mujoco is not installed (pip install 'alpes_dyn[mujoco]')") from None
    try:
        return mujoco.MjModel.from_xml_string(xml)
    except Exception as exc:  # mujoco raises ValueError with a multi-line message
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ModelError(f"MJCF rejected by MuJoCo: {first}") from None


def joint_permutation(mj_model, joint_names: Sequence[str]) -> np.ndarray:
    """MuJoCo qpos index of each joint in ``joint_names`` (the library's order).

    Parameters
    ----------
    mj_model : mujoco.MjModel
        The MuJoCo model.
    joint_names : sequence of str
        The joints, in the library's order.

    Returns
    -------
    numpy.ndarray of int, shape (n,)
        The qpos address of each joint.

    Raises
    ------
    ModelError
        A joint the MuJoCo model does not have, named.
    """
    names = [mj_model.joint(k).name for k in range(mj_model.njnt)]
    try:
        return np.array([mj_model.jnt_qposadr[names.index(nm)] for nm in joint_names], dtype=int)
    except ValueError:
        missing = [nm for nm in joint_names if nm not in names]
        raise ModelError(f"MuJoCo model has no joint {missing[0]!r}") from None
