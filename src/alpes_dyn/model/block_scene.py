"""A block for a tip frame of any URDF + spec robot to press on, placed from the robot's own kinematics, and its MJCF.

The force-control loop of :mod:`alpes_dyn.control` needs an object the fingertip meets; on the Alpes fingers it is
the ``"block"`` scene of :mod:`.mjcf`. For any :class:`~alpes_dyn.Model` with a transmission, :func:`place_block`
puts a fixed box where one tip frame arrives when one motor pulls:

* **the contact configuration** q_c (rad): given (inside the joint ranges), or by default the static equilibrium
  G(q) = S_k^T tau_c (gravity and springs against motor k alone, the other motors off) at the motor torque tau_c
  at which the motor's joints have covered ``approach`` (default 25 %) of the way from their rest angles (the
  equilibrium with the motors off) toward their ranges' ends in the direction the tendon pulls them (the largest
  such fraction over the motor's joints; a joint without a finite end counts pi rad);
* **the contact normal** n (3,), base frame, pointing from the fingertip into the block: the direction in which
  the frame moves at q_c as the motor pulls harder, n = J(q_c) dq / |J(q_c) dq| with dq = H(q_c)^{-1} S_k^T and
  H = dG/dq (gravity and spring stiffness): the face is square to the tip's path, so the motor's torque presses
  the tip onto it (the block pushes the tip with F = -F_z n, F_z >= 0, as :mod:`alpes_dyn.control.controller`
  writes the static balance);
* **the box**: its near face, square to n, touches the tip's sphere (radius ``tip_radius``, the sphere of
  :func:`~alpes_dyn.model.mjcf_export.model_mjcf`) at q_c; half sizes ``half_width`` (default: half the distance
  from the motor's first joint to the tip at q_c, at least 2 cm) along the face and 1 cm across it.
  Frictionless (``condim="1"``: the contact force is the normal force the touch sensor reads) with the stiff
  contact of the Alpes scenes (``solref="0.002 1"``, ``solimp="0.95 0.99 0.001"``, ``priority="1"``).

:func:`block_scene_mjcf` is :func:`~alpes_dyn.model.mjcf_export.model_mjcf` of the model (its tip spheres are its
only collision geoms, with a touch sensor ``touch_<tip>`` each) plus the block in the world body.

What cannot be placed is refused with one line (:class:`~alpes_dyn.InputError`): an unknown or ambiguous frame or
motor (the candidates listed), a frame the motor does not move, a q_c outside the joint ranges, a rest
configuration outside them (the plant would start on a stop) or already at or past the face, a motor whose free motion never covers ``approach`` of its range.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..errors import InputError

__all__ = ["BlockScene", "place_block", "block_scene_mjcf", "motor_tips", "contact_frame_and_motor"]

_THICKNESS = 0.01  # the block's half size across its face, m
_MIN_HALF_WIDTH = 0.02  # m
_UNBOUNDED_RANGE = math.pi  # rad: the range counted for a joint without a finite end


@dataclass(frozen=True)
class BlockScene:
    """Where the block is. frame: the tip frame pressing; motor: the motor's name, motor_index its row of S;
    contact_q (n,): q_c, rad; tip_position (3,): the frame at q_c, m (base frame); normal (3,): n, unit;
    rest_q (n,): the equilibrium with the motors off, rad; center (3,), quat (4,) (w, x, y, z): the box's pose;
    half (3,): its half sizes, m; tip_radius: m; lever: dtau_m/dF_z at q_c, m (the motor torque per newton
    pressed, :func:`alpes_dyn.control.controller.static_motor_torque`'s slope)."""

    frame: str
    motor: str
    motor_index: int
    contact_q: np.ndarray
    tip_position: np.ndarray
    normal: np.ndarray
    rest_q: np.ndarray
    center: np.ndarray
    quat: tuple[float, float, float, float]
    half: tuple[float, float, float]
    tip_radius: float
    lever: float


def motor_tips(model: Any, motor: int) -> tuple[str, ...]:
    """The tips of ``model`` (:attr:`Model.tips <alpes_dyn.Model.tips>`) that motor ``motor`` moves: a joint the
    motor drives is among the tip's supporting joints.

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a transmission (a URDF and its spec).
    motor : int
        The motor's index, its row of the transmission's S.

    Returns
    -------
    tuple of str
        The names of the tip frames the motor moves, in the order of ``model.tips``.
    """
    pm = model.pin_model
    driven = {pm.getJointId(model.joint_names[i]) for i in np.flatnonzero(model.transmission.S[motor])}  # their ids
    return tuple(t for t in model.tips if driven & set(pm.supports[pm.frames[model.frame_id(t)].parentJoint]))


def contact_frame_and_motor(model: Any, frame: str | None, motor: str | None) -> tuple[str, int]:
    """(the tip frame, the motor's row of S) of a force loop, the defaults resolved.

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a transmission (a URDF and its spec).
    frame : str or None
        The tip frame (one of ``model.tips``); None: the only tip the motor moves.
    motor : str or None
        The motor's name; None: the only motor, or the only one moving ``frame``.

    Returns
    -------
    tuple of (str, int)
        The tip frame and the motor's index (row of S).

    Raises
    ------
    InputError
        No transmission, an unknown frame or motor, or no unique default (the candidates named).
    """
    tr = model.transmission
    if tr is None:
        raise InputError(f"spec: model {model.name!r} has no transmission; force control needs its motors (a URDF "
                         "--model with a --spec)")
    names = tuple(tr.motor_names)
    if frame is not None and frame not in model.tips:
        raise InputError(f"frame: {frame!r} is not a tip frame of {model.name!r} (tips: {', '.join(model.tips)}; "
                         "the spec's tips = [...] names others)")
    if motor is not None and motor not in names:
        raise InputError(f"motor: unknown motor {motor!r} (motors: {', '.join(names)})")
    if motor is None:
        cands = [k for k in range(len(names)) if frame is None or frame in motor_tips(model, k)]
        if len(cands) != 1:
            where = "" if frame is None else f" moving {frame!r}"
            raise InputError(f"motor: {model.name!r} has {len(cands)} motors{where} "
                             f"({', '.join(names[k] for k in cands) or 'none'}); name one")
        k = cands[0]
    else:
        k = names.index(motor)
    tips = motor_tips(model, k)
    if frame is None:
        if len(tips) != 1:
            raise InputError(f"frame: motor {names[k]!r} moves {len(tips)} tip frames "
                             f"({', '.join(tips) or 'none'}); name one")
        frame = tips[0]
    elif frame not in tips:
        raise InputError(f"frame: motor {names[k]!r} does not move {frame!r} (the tips it moves: "
                         f"{', '.join(tips) or 'none'})")
    return frame, k


def _equilibrium(model: Any, k: int, tau_m: float, q0: np.ndarray) -> np.ndarray:
    return model.static_equilibrium(model.transmission.S[k] * tau_m, q0)


def _default_contact_q(model: Any, k: int, rest: np.ndarray, approach: float) -> np.ndarray:
    """The equilibrium under motor k where its joints have covered ``approach`` of their way (module doc)."""
    S = model.transmission.S[k]
    joints = np.flatnonzero(S)
    end = np.where(S[joints] > 0, model.upper[joints], model.lower[joints])
    span = np.where(np.isfinite(end), end - rest[joints], np.sign(S[joints]) * _UNBOUNDED_RANGE)

    def covered(q: np.ndarray) -> float:
        return float(np.max((q[joints] - rest[joints]) / span))

    H = model.gravity_jacobian(rest)  # a first guess of the torque: the linearised equilibrium
    try:
        dq = np.linalg.solve(H, S)
    except np.linalg.LinAlgError:
        dq = np.linalg.lstsq(H, S, rcond=None)[0]
    slope = float(np.max(dq[joints] / span))
    hi = approach / slope if math.isfinite(slope) and slope > 0 else 1e-3
    lo, q_hi = 0.0, rest
    motor = model.transmission.motor_names[k]
    try:
        for _ in range(60):  # grow the torque until the joints cover the fraction
            q_hi = _equilibrium(model, k, hi, q_hi)
            if covered(q_hi) >= approach:
                break
            lo, hi = hi, 2.0 * hi
        else:
            raise InputError("")
    except InputError:
        raise InputError(f"contact_q: the block cannot be placed: motor {motor!r} never moves its joints "
                         f"{approach:.0%} of their ranges in static equilibrium (give contact_q)") from None
    q = q_hi
    for _ in range(50):  # bisection on the torque
        mid = 0.5 * (lo + hi)
        q_mid = _equilibrium(model, k, mid, q)
        if covered(q_mid) >= approach:
            hi, q = mid, q_mid
        else:
            lo = mid
        if hi - lo <= 1e-10 * hi:
            break
    return q


def _quat_z_to(n: np.ndarray) -> tuple[float, float, float, float]:
    """(w, x, y, z) of the rotation taking the z axis to the unit vector n."""
    import pinocchio as pin

    x, y, z, w = pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), n).coeffs()
    return (float(w), float(x), float(y), float(z))


def _rest(model: Any) -> np.ndarray:
    """The rest configuration (motors off) q (n,), rad, inside the joint ranges; :class:`~alpes_dyn.InputError` where
    there is none or a joint rests outside its range: every such joint counted, and where they have no spring (gravity
    alone places them: a published MJCF's position servos held them, and its import keeps those as torque motors) what
    the user gives them."""
    try:
        rest = model.static_equilibrium(np.zeros(model.n))
    except InputError as exc:
        raise InputError(f"spec: the rest configuration (motors off) cannot be found: {exc}") from None
    out = [i for i in range(model.n) if not model.lower[i] <= rest[i] <= model.upper[i]]
    if not out:
        return rest
    i, names = out[0], [model.joint_names[j] for j in out]
    more = f" (and {len(out) - 1} more: {', '.join(names[1:4])}{', ...' if len(out) > 4 else ''})" if len(out) > 1 else ""
    loose = sum(j in model.springless_joints for j in names)
    what = ("move the rest inside: the spec's [rest_angle], stiffer springs" if not loose else
            f"{'it has' if len(names) == 1 else f'{loose} of them have'} no spring: gravity alone places them, where "
            "a published MJCF's position servos held them, which its import keeps as torque motors; give each a "
            "spring in the spec: its [stiffness], a servo's kp times its gear squared, and a [rest_angle] inside "
            "its range")
    raise InputError(f"spec: the rest configuration (motors off) has joint {names[0]!r} at {rest[i]:.4g} rad, outside "
                     f"its range [{model.lower[i]:.4g}, {model.upper[i]:.4g}]{more}: the plant would start on its "
                     f"stop, which the controller's model does not hold ({what})")


def place_block(model: Any, frame: str | None = None, motor: str | None = None,
                contact_q: Sequence[float] | None = None, *, approach: float = 0.25, tip_radius: float = 0.005,
                half_width: float | None = None) -> BlockScene:
    """The block that ``frame`` presses when ``motor`` pulls (module doc): a :class:`BlockScene`.

    Parameters
    ----------
    model : alpes_dyn.Model
        A model with a transmission (a URDF and its spec).
    frame : str or None, optional
        The tip frame that presses the block (default None: :func:`contact_frame_and_motor`).
    motor : str or None, optional
        The motor that pulls (default None: :func:`contact_frame_and_motor`).
    contact_q : sequence of float, shape (n,), optional
        q_c, rad, the joint angles at contact, inside the joint ranges; default None: the equilibrium at
        ``approach`` (module doc).
    approach : float, optional
        The fraction in (0, 1) of the motor's joints' way to their ranges' ends at the default q_c (default 0.25).
    tip_radius : float, optional
        The tip sphere's radius, m (> 0: the sphere is what meets the block; default 0.005).
    half_width : float or None, optional
        The box's half size along its face, m (default None: half the distance from the motor's first joint to the
        tip at q_c, module doc).

    Returns
    -------
    BlockScene
        The block's placement, normal, rest configuration and lever.

    Raises
    ------
    InputError
        A bad ``approach``, ``tip_radius`` or ``contact_q``, a rest configuration outside the joint ranges, or a block
        that cannot be placed (the reason named).
    """
    frame, k = contact_frame_and_motor(model, frame, motor)
    for name, x, lo in (("approach", approach, 0.0), ("tip_radius", tip_radius, 0.0)):
        if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) or not x > lo \
                or (name == "approach" and not x < 1.0):
            raise InputError(f"{name}: expected a number in {'(0, 1)' if name == 'approach' else '(0, inf) m'}, "
                             f"got {x!r}")
    n_j, tr = model.n, model.transmission
    rest = _rest(model)
    if contact_q is None:
        q_c = _default_contact_q(model, k, rest, float(approach))
    else:
        try:
            q_c = np.asarray(contact_q, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"contact_q: expected {n_j} joint angles (rad), got {contact_q!r}") from None
        if q_c.shape != (n_j,) or not np.isfinite(q_c).all():
            raise InputError(f"contact_q: expected {n_j} finite joint angles (rad, {', '.join(model.joint_names)}), "
                             f"got {np.asarray(contact_q).tolist()!r}")
    out = [(j, q_c[i]) for i, j in enumerate(model.joint_names) if not model.lower[i] <= q_c[i] <= model.upper[i]]
    if out:
        j, v = out[0]
        i = model.joint_index(j)
        raise InputError(f"contact_q: the block cannot be placed: joint {j!r} at {v:.4g} rad is outside its range "
                         f"[{model.lower[i]:.4g}, {model.upper[i]:.4g}]")
    J = model.fingertip_jacobian(q_c, frame)
    try:
        dq = np.linalg.solve(model.gravity_jacobian(q_c), tr.S[k])
    except np.linalg.LinAlgError:
        raise InputError(f"contact_q: the block cannot be placed: dG/dq is singular at contact_q (a joint with no "
                         f"spring and no gravity torque: {', '.join(model.springless_joints) or 'none'})") from None
    v = J @ dq
    scale = float(np.linalg.norm(J, 2) * np.linalg.norm(dq))
    if not (np.isfinite(v).all() and np.linalg.norm(v) > 1e-9 * max(scale, 1e-300)):
        raise InputError(f"frame: motor {tr.motor_names[k]!r} does not move {frame!r} at contact_q (J dq = 0): "
                         "the block cannot be placed")
    n = v / np.linalg.norm(v)
    p_c = model.fingertip_position(q_c, frame)
    if float(n @ (model.fingertip_position(rest, frame) - p_c)) >= 0.0:
        raise InputError("contact_q: the block cannot be placed: the frame at rest (motors off) is already at or past "
                         "the block's face (choose a contact_q further along the motor's pull)")
    jc = int(np.flatnonzero(tr.S[k])[0])
    if half_width is None:  # half the distance from the motor's first joint to the tip, at q_c
        import pinocchio as pin

        data = model.pin_model.createData()
        pin.forwardKinematics(model.pin_model, data, q_c)
        half_width = max(_MIN_HALF_WIDTH, 0.5 * float(np.linalg.norm(p_c - data.oMi[model.pin_model.getJointId(model.joint_names[jc])].translation)))
    lever = float(tr.S[k] @ (J.T @ n) / (tr.S[k] @ tr.S[k]))
    center = p_c + (float(tip_radius) + _THICKNESS) * n
    return BlockScene(frame=frame, motor=tr.motor_names[k], motor_index=k, contact_q=q_c, tip_position=p_c,
                      normal=n, rest_q=rest, center=center, quat=_quat_z_to(n),
                      half=(float(half_width), float(half_width), _THICKNESS), tip_radius=float(tip_radius), lever=lever)


def block_scene_mjcf(model: Any, scene: BlockScene, *, timestep: float = 1e-4, integrator: str = "RK4") -> str:
    """MJCF text: :func:`~alpes_dyn.model.mjcf_export.model_mjcf` of ``model`` (joint limits on, tips of radius
    ``scene.tip_radius``) with the block of ``scene`` in the world body (module doc).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model the scene was placed for.
    scene : BlockScene
        The block (:func:`place_block`).
    timestep : float, optional
        MuJoCo's time step, s (default 1e-4).
    integrator : str, optional
        MuJoCo's integrator, one of :data:`~alpes_dyn.model.mjcf_export.INTEGRATORS` (default ``"RK4"``).

    Returns
    -------
    str
        The MJCF text.
    """
    from .mjcf_export import _v, model_mjcf

    xml = model_mjcf(model, timestep=timestep, integrator=integrator, tip_radius=scene.tip_radius)
    geom = (f'    <geom name="block" type="box" pos="{_v(scene.center)}" quat="{_v(scene.quat)}" '
            f'size="{_v(scene.half)}" condim="1" solref="0.002 1" solimp="0.95 0.99 0.001" priority="1" '
            'rgba="0.4 0.6 0.8 1"/>')
    head, sep, tail = xml.rpartition("  </worldbody>")
    return head + geom + "\n" + sep + tail
