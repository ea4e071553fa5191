"""The MuJoCo plants of a finger with a real hand's effects: built, put at rest, their passive forces.

Two scenes, each the one the library's own runs use:

* the free finger (:func:`free_plant`, the recording plant of :func:`alpes_dyn.control.plants.mujoco_recording`):
  the finger exported by :func:`~alpes_dyn.model.mjcf.mjcf_string` (:func:`plant_mjcf`: joint stops on, contact
  off, RK4 at 0.1 ms by default), at rest under a motor torque, each series-elastic rotor holding the cable's
  static tension (:func:`initial_qpos`), the library's smooth friction law (without ``stiction``) and the tendons'
  sheath friction added by MuJoCo's passive callback (:func:`passive_forces`);
* the block (:func:`block_plant`, the plant of :func:`alpes_dyn.control.finger_loop.run_control`): the finger
  palm down over a fixed block met at a contact configuration, contact on, MuJoCo's joint friction (damping F_v,
  ``frictionloss`` F_s), its ``flexiforce_<chain>`` touch sensor; at rest with the motor off, each series-elastic
  rotor where the cable is just slack (:func:`rotor_rest`).

The effects' MJCF side (:func:`~alpes_dyn.bench.effects.effects_mjcf_kwargs`) is in both.
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from ..errors import InputError
from ..model.mjcf import BLOCK_CONTACT_Q, joint_permutation, load_mujoco, mjcf_string, tilted_gravity
from ..model.params import HandParams, Param, load_params, with_values
from ..model.robot import Model
from ..model.transmission import capstan_torque, capstan_velocity
from .effects import PlantEffects, effects_mjcf_kwargs, plant_gravity

__all__ = ["PLANT_MODELS", "INTEGRATORS", "as_params", "plant_mjcf", "plant_model", "initial_qpos", "plant_at_rest",
           "passive_forces", "free_plant", "rotor_rest", "block_plant"]

PLANT_MODELS: tuple[str, ...] = ("finger2", "finger3", "thumb")
"""The models a recording plant is built for: one chain, as the identification experiment."""
INTEGRATORS: tuple[str, ...] = ("rk4", "implicit", "implicitfast")


def as_params(params: HandParams | str | None) -> HandParams:
    """``params`` itself, or the parameter file at that path (None: the shipped file).

    Parameters
    ----------
    params : HandParams, str or None
        The parameters, or their file's path (None: the shipped file).

    Returns
    -------
    HandParams
    """
    return params if isinstance(params, HandParams) else load_params(params)


def plant_mjcf(model: str, params: HandParams | str | None = None, effects: PlantEffects | None = None,
               chain: str | None = None, timestep: float = 1e-4) -> str:
    """MJCF text of the plant: ``model`` from ``params`` with the MJCF side of ``effects`` (joint stops on,
    contact off: a finger moving freely; friction as :func:`passive_forces` says, MuJoCo's ``frictionloss`` and
    ``damping`` with ``stiction`` or ``soft_stiction``).

    Parameters
    ----------
    model : str
        ``"finger2"``, ``"finger3"`` or ``"thumb"`` (:data:`PLANT_MODELS`).
    params : HandParams, str or None, optional
        The parameters or their file (None: the shipped file).
    effects : PlantEffects or None, optional
        The plant's effects (None: none).
    chain : str or None, optional
        The hand's chain (None: the model's own).
    timestep : float, optional
        MuJoCo's step, s (default 0.1 ms).

    Returns
    -------
    str
        The MJCF text.
    """
    e = (effects or PlantEffects()).check()
    p = as_params(params)
    if p.capstan > 0:  # not in the MJCF: the plant's passive callback adds the sheath friction
        p = with_values(p, {"transmission.capstan": Param(0.0, "-", "assumed", "in the plant's callback", "sheath")})
    return mjcf_string(model, p, chain=chain, friction=e.soft_stiction, contact=False, timestep=timestep,
                       **effects_mjcf_kwargs(e))


def plant_model(model: str, params: HandParams | str | None = None, effects: PlantEffects | None = None,
                chain: str | None = None) -> Model:
    """The library's rigid model of the same finger (friction on), with the plant's tilted gravity: what the
    plant is without its other effects (its rest states, its smooth friction law).

    Parameters
    ----------
    model : str
        ``"finger2"``, ``"finger3"`` or ``"thumb"``.
    params : HandParams, str or None, optional
        The parameters or their file (None: the shipped file).
    effects : PlantEffects or None, optional
        The plant's effects (None: none; their ``tilt`` turns gravity).
    chain : str or None, optional
        The hand's chain (None: the model's own).

    Returns
    -------
    Model
    """
    e = (effects or PlantEffects()).check()
    m = Model.alpes(model, friction=True, params=as_params(params), chain=chain)
    return m if e.tilt == 0 else m.copy(gravity=tilted_gravity(m.gravity, e.tilt))


def initial_qpos(mj: Any, truth: Model, perm: np.ndarray, q0: np.ndarray, u0: np.ndarray, p: HandParams,
                 effects: PlantEffects) -> np.ndarray:
    """qpos of the plant at joint angles q0 (rad), at rest: each rotor (series-elastic tendon) turned so that the
    cable holds the motor torque u0 (the static tension T = tau_m / r_m, stretch T / k_t, plus the cable's slack).

    Parameters
    ----------
    mj : mujoco.MjModel
        The plant's MuJoCo model.
    truth : Model
        The library's model of the plant (:func:`plant_model`).
    perm : numpy.ndarray, shape (n,)
        The MuJoCo qpos index of each of ``truth``'s joints.
    q0 : numpy.ndarray, shape (n,)
        The joint angles, rad.
    u0 : numpy.ndarray, shape (m,)
        The motor torque held, N m.
    p : HandParams
        The plant's parameters.
    effects : PlantEffects
        The plant's effects.

    Returns
    -------
    numpy.ndarray, shape (nq,)
        MuJoCo's qpos.
    """
    qpos = mj.qpos0.copy()
    qpos[perm] = q0
    if effects.tendon_stiffness is not None:
        S = truth.transmission.S
        for k, mn in enumerate(truth.transmission.motor_names):
            if mn.endswith("abduction"):
                continue
            stretch = float(u0[k]) / (p.r_m * effects.tendon_stiffness) + effects.tendon_dead_band  # slack taken up
            qpos[mj.joint(f"{mn}_rotor").qposadr[0]] = float(S[k] @ q0) + stretch / p.r_m  # e = r_m theta - r sum q
    return qpos


def plant_at_rest(mj: Any, truth: Model, q0: Sequence[float] | None, u0: np.ndarray, p: HandParams,
                  effects: PlantEffects) -> Any:
    """The plant's MjData at joint angles ``q0`` (rad; default the rest of ``truth`` under the torque ``u0``, N m)
    at rest, its derived quantities computed (``mj_forward``); :class:`~alpes_dyn.InputError` naming ``q0``.

    Parameters
    ----------
    mj : mujoco.MjModel
        The plant's MuJoCo model.
    truth : Model
        The library's model of the plant (:func:`plant_model`).
    q0 : sequence of float or None
        The joint angles (n,), rad (None: the rest under ``u0``).
    u0 : numpy.ndarray, shape (m,)
        The motor torque held, N m.
    p : HandParams
        The plant's parameters.
    effects : PlantEffects
        The plant's effects.

    Returns
    -------
    mujoco.MjData
    """
    import mujoco

    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, truth.joint_names)
    if q0 is None:
        q_init = truth.static_equilibrium(None, np.zeros(truth.n), fixed=truth.springless_joints, tau_m=u0)
    else:
        q_init = np.asarray(q0, dtype=float)
        if q_init.shape != (truth.n,) or not np.isfinite(q_init).all():
            raise InputError(f"q0: expected {truth.n} finite joint angles (rad), got {np.asarray(q0).tolist()!r}")
    d.qpos[:] = initial_qpos(mj, truth, perm, q_init, u0, p, effects)
    mujoco.mj_forward(mj, d)
    return d


@contextmanager
def passive_callback(passive: Callable[[Any, Any], None] | None) -> Iterator[None]:
    """MuJoCo's process-wide ``mjcb_passive`` set to ``passive`` (:func:`passive_forces`) for the steps in the
    ``with`` block, the previous callback restored after (also on an error); nothing done where ``passive`` is None."""
    if passive is None:
        yield
        return
    import mujoco

    previous = mujoco.get_mjcb_passive()
    mujoco.set_mjcb_passive(passive)
    try:
        yield
    finally:
        mujoco.set_mjcb_passive(previous)


def passive_forces(mj: Any, truth: Model, e: PlantEffects) -> Callable[[Any, Any], None] | None:
    """MuJoCo's passive-force callback of what the free plant adds to MuJoCo at every RK4 stage (N m on
    ``truth``'s joints): the library's smooth friction law (without ``stiction`` or ``soft_stiction``: MuJoCo's own dry friction then) and
    the tendons' sheath friction where ``truth`` has one (``capstan``: S^T of the capstan's loss at the actuators'
    torque, d.ctrl, and the motor velocity S qd); None where there is nothing to add. The callback is MuJoCo's
    process-wide ``mjcb_passive``: its user sets it around its steps and restores the previous one.

    Parameters
    ----------
    mj : mujoco.MjModel
        The plant's MuJoCo model.
    truth : Model
        The library's model of the plant (:func:`plant_model`).
    e : PlantEffects
        The plant's effects.

    Returns
    -------
    callable or None
        ``passive(m, d)``, adding to ``d.qfrc_passive``; None.

    Raises
    ------
    InputError
        The sheath friction (``capstan``) with an elastic tendon.
    """
    ex, tr = truth.extras, truth.transmission
    sheath = tr is not None and tr.has_capstan
    if sheath and e.tendon_stiffness is not None:
        raise InputError("capstan: the MuJoCo plant puts the tendons' sheath friction on a rigid tendon (its tension "
                         "the motor's torque); with tendon_stiffness the tension is the cable's")
    if e.mujoco_friction and not sheath:
        return None
    dofs = np.array([mj.jnt_dofadr[mj.joint(j).id] for j in truth.joint_names])
    smooth = not e.mujoco_friction
    if sheath:  # the law's constants once (the callback runs at every RK4 stage)
        S, m, mu, v_c = tr.S, tr.n_motors, tr.capstan, capstan_velocity(tr.S, ex.smooth_velocity)

    def passive(_m, dd) -> None:  # the library's laws, at every RK4 stage
        v = dd.qvel[dofs]
        if smooth:
            dd.qfrc_passive[dofs] -= ex.coulomb * np.tanh(v / ex.smooth_velocity) + ex.viscous * v
        if sheath:
            u = dd.ctrl[:m]
            dd.qfrc_passive[dofs] -= (u - capstan_torque(u, S @ v, mu, v_c)) @ S

    return passive


def free_plant(truth: Model, model: str, p: HandParams, e: PlantEffects, chain: str | None, timestep: float,
               integrator: str, q0: Sequence[float] | None, u0: np.ndarray,
               gravity: np.ndarray | None = None) -> tuple[Any, Any, Model]:
    """The free finger: (MjModel, MjData at rest, the library's model of it) -- ``model`` (``chain``) of ``p`` with
    the effects ``e`` at MuJoCo step ``timestep`` (s) with ``integrator`` (:data:`INTEGRATORS`), at joint angles
    ``q0`` (rad; default its rest under the motor torque ``u0``, N m), in ``gravity`` (3,) m/s^2 if given (default
    the MJCF's: the effects' tilt in it). ``truth``: :func:`plant_model` of the same (returned in ``gravity``).

    Parameters
    ----------
    truth : Model
        The library's model of the plant (:func:`plant_model`).
    model : str
        ``"finger2"``, ``"finger3"`` or ``"thumb"``.
    p : HandParams
        The plant's parameters.
    e : PlantEffects
        The plant's effects.
    chain : str or None
        The hand's chain (None: the model's own).
    timestep : float
        MuJoCo's step, s.
    integrator : str
        One of :data:`INTEGRATORS`.
    q0 : sequence of float or None
        The joint angles (n,), rad (None: the rest under ``u0``).
    u0 : numpy.ndarray, shape (m,)
        The motor torque held, N m.
    gravity : numpy.ndarray, shape (3,), or None, optional
        The gravity, m/s^2 (None: the MJCF's).

    Returns
    -------
    tuple
        (MjModel, MjData, Model).
    """
    import mujoco

    mj = load_mujoco(plant_mjcf(model, p, e, chain, timestep))
    mj.opt.integrator = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                         "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}[integrator]
    if gravity is not None:  # the rest (q0's default) found in this gravity
        mj.opt.gravity[:] = gravity
        truth = truth.copy(gravity=np.asarray(gravity, dtype=float))
    return mj, plant_at_rest(mj, truth, q0, u0, p, e), truth


def rotor_rest(mj: Any, d: Any, motors: list[str], model: Model, q0: np.ndarray, effects: PlantEffects | None) -> None:
    """Each series-elastic rotor of ``motors`` (its MuJoCo joint ``<motor>_rotor``) where the cable is just slack at
    joint angles ``q0`` (rad): theta = S q0 (the stretch e = r_m theta - r sum q at 0, the slack still to take up).

    Parameters
    ----------
    mj : mujoco.MjModel
        The plant's MuJoCo model.
    d : mujoco.MjData
        Its data (qpos set in place).
    motors : list of str
        The motors' names.
    model : Model
        The library's model (its S).
    q0 : numpy.ndarray, shape (n,)
        The joint angles, rad.
    effects : PlantEffects or None
        The plant's effects (without ``tendon_stiffness``: nothing done).
    """
    if effects is None or effects.tendon_stiffness is None:
        return
    S = model.transmission.S
    for k, mn in enumerate(motors):
        d.qpos[mj.joint(f"{mn}_rotor").qposadr[0]] = float(S[k] @ q0)


def block_plant(model: str, p: HandParams, effects: PlantEffects | None, contact_q: Sequence[float] | None,
                timestep: float, q0: Sequence[float] | None = None) -> tuple[Any, Any, Model]:
    """The block scene of the force loop: (MjModel, MjData at rest, the library's model of the plant in the plant's
    gravity) -- ``model`` (finger2, finger3) of ``p`` (palm down: :func:`~alpes_dyn.model.mjcf.palm_down_params`)
    over the block met at ``contact_q`` (rad; None: :data:`~alpes_dyn.model.mjcf.BLOCK_CONTACT_Q`), contact on,
    MuJoCo's joint friction, ``effects`` (None: none), at MuJoCo step ``timestep`` (s); at joint angles ``q0`` (rad;
    default the finger hanging on its springs in the plant's gravity, motor off), each series-elastic rotor where the
    cable is just slack (:func:`rotor_rest`); :class:`~alpes_dyn.InputError` naming ``q0``.

    Parameters
    ----------
    model : str
        ``"finger2"`` or ``"finger3"``.
    p : HandParams
        The plant's parameters.
    effects : PlantEffects or None
        The plant's effects (None: none).
    contact_q : sequence of float or None
        The joint angles where the block is met, rad (None: :data:`~alpes_dyn.model.mjcf.BLOCK_CONTACT_Q`).
    timestep : float
        MuJoCo's step, s.
    q0 : sequence of float or None, optional
        The initial joint angles (n,), rad (None: the rest on the springs, motor off).

    Returns
    -------
    tuple
        (MjModel, MjData, Model).
    """
    import mujoco

    truth = Model.alpes(model, params=p)
    cq = tuple(BLOCK_CONTACT_Q[: truth.n] if contact_q is None else contact_q)
    fx = {} if effects is None else effects_mjcf_kwargs(effects)
    mj = load_mujoco(mjcf_string(model, p, friction=True, scene="block", contact_q=cq, timestep=timestep, **fx))
    d = mujoco.MjData(mj)
    truth = truth.copy(gravity=plant_gravity(truth.gravity, effects))
    if q0 is None:
        q_init = truth.static_equilibrium(np.zeros(truth.n))
    else:
        q_init = np.asarray(q0, dtype=float)
        if q_init.shape != (truth.n,) or not np.isfinite(q_init).all():
            raise InputError(f"q0: expected {truth.n} finite joint angles (rad), got {np.asarray(q0).tolist()!r}")
    d.qpos[joint_permutation(mj, truth.joint_names)] = q_init
    rotor_rest(mj, d, list(truth.transmission.motor_names), truth, q_init, effects)
    mujoco.mj_forward(mj, d)
    return mj, d, truth



def cylinder_plant(p: HandParams, effects: PlantEffects | None, timestep: float) -> tuple[Any, Any, Model]:
    """The hand's grasp scene: (MjModel, MjData at rest, the library's model of the hand in the plant's gravity) --
    the hand of ``p`` (palm down: :func:`~alpes_dyn.model.mjcf.palm_down_params`) over the fixed, frictionless
    cylinder of :data:`~alpes_dyn.model.mjcf.CYLINDER`, contact on, MuJoCo's joint friction, ``effects`` (None: none),
    at MuJoCo step ``timestep`` (s); the scene of :func:`~alpes_dyn.control.hand_loop.run_hand_control`. At rest:
    each flexion chain hanging on its springs in the plant's gravity (:func:`~alpes_dyn.model.hand_chains.chain_model`,
    motor off), its series-elastic rotor where the cable is just slack (:func:`rotor_rest`), the thumb's
    ab/adduction at 0."""
    import dataclasses

    import mujoco

    from ..model.hand_chains import chain_model, hand_chains

    fx = {} if effects is None else effects_mjcf_kwargs(effects)
    mj = load_mujoco(mjcf_string("hand", p, friction=True, scene="cylinder", timestep=timestep, **fx))
    d = mujoco.MjData(mj)
    pg = dataclasses.replace(p, gravity=plant_gravity(p.gravity, effects))
    for c in hand_chains(p):
        plant = chain_model(pg, c, 0.0)
        q0 = plant.static_equilibrium(np.zeros(plant.n))
        d.qpos[joint_permutation(mj, [f"{c}_{j}" for j in plant.joint_names])] = q0
        rotor_rest(mj, d, [c], plant, q0, effects)
    d.qpos[mj.joint("thumb_abd").qposadr[0]] = 0.0
    mujoco.mj_forward(mj, d)
    truth = Model.alpes("hand", params=p)
    return mj, d, truth.copy(gravity=plant_gravity(truth.gravity, effects))
