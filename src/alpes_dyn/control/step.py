"""One sample of the force loop, for a user's own 1 kHz loop: :class:`ForceStep`.

``ForceStep`` holds what closes the fingertip force loop on the hand's sensors, built once:

* the EKF with the contact force as a known input (:func:`force_ekf`; the known input [tau_m, -F n], the
  encoder measured; started at the finger's rest), its step compiled to C (or loaded from the cache) when the
  object is built, never inside :meth:`ForceStep.step`;
* the compensation of the identified effects (:class:`~alpes_dyn.control.realism_loop.Compensation`): the
  encoder's reading less the tendon's stretch C tau_m,k-1 and the encoder's offset, the command held over the
  last period as the observer's motor torque, the notch at the cable's mode, the palm's tilt;
* the sensorless force estimate (:class:`~alpes_dyn.control.blocks.SensorlessForce`) for ``"sensorless"``;
* the :class:`~alpes_dyn.control.controller.ForceController` with the tuned gains (:data:`.DEFAULT_GAINS`).

:func:`~alpes_dyn.control.finger_loop.run_control` runs the same object at every sample of its simulated loop,
so what a user runs on the hand is what the library's closed loop tests and measures. :meth:`ForceStep.parts` gives
its settings (:class:`~alpes_dyn.control.step_parts.StepParts`) to a code generator (:mod:`alpes_dyn.control.cstep`)
or a port; :class:`~alpes_dyn.control.hand_step.HandForceStep` holds one per flexion chain of the whole hand.

Timing (sample k at t_k, as :mod:`alpes_dyn.simulation.loop`'s and :mod:`alpes_dyn.bench.interface`'s): the
readings of tick k -- the encoder counts at t_k, the motor torque that the current sensor reports at t_k (what the
motor gave over [t_k-1, t_k)), the fingertip force at t_k -- go into ``step``, whose command is then held over
[t_k, t_k+1). Within one call: (1) the EKF's predict over [t_k-1, t_k] with the motor torque of that period (the
command returned at k-1 with ``command_input``, else the reading) and the contact force -s F n (the force sensor's
reading at t_k; the sensorless estimate of t_k-1; s the compensation's ``force_scale``: the force in the parameter
file's torque units, which the torque constant's error scales with every identified torque), then its update with
the encoder at t_k; no filter step at
k = 0 (the estimate is the rest state); (2) the sensorless estimate at t_k from q_hat and the same motor torque;
(3) the controller's command.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import InputError
from ..estimation.observers.blocks import step_caller
from ..estimation.observers.observers import make_observer
from ..estimation.observers.scenario import EstimationScenario, default_noise, static_equilibrium
from ..model.block_scene import BlockScene, place_block
from ..model.mjcf import BLOCK_CONTACT_Q, block_normal, palm_down_params
from ..model.trust import check_trusted
from ..model.params import HandParams, load_params
from ..model.friction import lugre_of
from ..model.robot import Model
from ..simulation.integrate import stable_substeps
from ..simulation.lugre import lugre_substeps
from ..simulation.stick import observer_friction_law
from ..symbolic.statespace import StateSpace
from .blocks import SensorlessForce
from .controller import CONTROLLERS, DEFAULT_GAINS, ForceController, _normal, static_motor_torque
from .realism_loop import Compensation
from .step_parts import StepParts

__all__ = ["ForceStep", "LoopDesign", "CONTROL_MODELS", "force_ekf", "alpes_design", "robot_design",
           "scaled_gains", "finger3_contact"]

CONTROL_MODELS: tuple[str, ...] = ("finger2", "finger3")

GAIN_NAMES: tuple[str, ...] = ("kp", "ki", "contact_threshold", "approach_rate", "prefilter_s", "loss_s", "onset_s",
                               "prefilter_order", "setpoint_weight", "release_s", "notch_hz", "notch_zeta")
"""The :class:`~alpes_dyn.control.controller.ForceController` settings a ``gains`` dict may set."""

_DIVERGED = 1e6
"""rad, rad/s: a joint estimate beyond it is a filter that diverged (:meth:`ForceStep.step` refuses it)."""

_DEFAULT_F_MAX = 1.0
"""N: the least force a URDF robot's default motor limit is sized for (twice the static torque of the larger of this
and the references' largest force), so that the limit leaves room above the default references (0.2 -> 0.6 -> 0.2 N
and the 0.8 N sine)."""


@dataclass(frozen=True)
class LoopDesign:
    """The controller's side of a force loop: its model (and the EKF's), the contact normal n (3,), base frame, the
    motor limit (N m), the controller's settings (gains), the motor's row of S, the contact frame (None: the
    model's default tip), the Alpes finger's parameters (palm down; None for a URDF robot), the contact
    configuration (rad), a URDF robot's block (None on an Alpes finger) and the EKF's model where it is not the
    controller's (an Alpes finger's with its file's friction, :func:`alpes_design`; None: ``model``)."""

    model: Model
    normal: np.ndarray
    tau_max: float
    gains: dict
    motor: int = 0
    frame: str | None = None
    params: HandParams | None = None
    contact_q: tuple[float, ...] = ()
    block: BlockScene | None = None
    observer_model: Model | None = None  # the EKF's model; None: ``model``


def alpes_design(name: str, params: HandParams, controller: str, contact_q: Sequence[float] | None,
                 compensation: Compensation, gains: dict, observer_friction: bool = True) -> LoopDesign:
    """finger2/finger3 pressing the block scene's face at ``contact_q`` (default :data:`BLOCK_CONTACT_Q`): the
    model of ``params`` (already oriented, e.g. palm down) turned by the compensation's tilt, the block's normal,
    the file's tau_max, :data:`.DEFAULT_GAINS` of ``controller`` overridden by ``gains``; with ``observer_friction``
    the EKF's model is the finger with the file's friction (its law, :func:`force_ekf`; F_s tanh(v / v_s) + F_v v,
    eq. 2.6-2.7, by default): the joints that friction holds in contact are then where the encoder's sum leaves
    them, not where a frictionless model would let them slide.

    Parameters
    ----------
    name : str
        ``"finger2"`` or ``"finger3"``.
    params : HandParams
        The finger's parameters, already oriented (e.g. palm down).
    controller : str
        The controller's kind, a key of :data:`.DEFAULT_GAINS`.
    contact_q : sequence of float or None
        The joint angles at the contact, rad (None: :data:`BLOCK_CONTACT_Q`).
    compensation : Compensation
        The loop's compensation (its tilt turns the model).
    gains : dict
        Overrides of :data:`.DEFAULT_GAINS` of ``controller``.
    observer_friction : bool, optional
        The EKF's model with the file's friction (default True).

    Returns
    -------
    LoopDesign
        The controller's side of the loop.
    """
    n = 2 if name == "finger2" else 3
    cq = tuple((BLOCK_CONTACT_Q if contact_q is None else contact_q)[:n])
    model = compensation.turned(Model.alpes(name, params=params))
    observer = compensation.turned(Model.alpes(name, friction=True, params=params)) if observer_friction else None
    return LoopDesign(model, block_normal(cq), params.tau_max, {**DEFAULT_GAINS[controller], **gains},
                      params=params, contact_q=cq, observer_model=observer)


@functools.lru_cache(maxsize=1)
def finger3_contact() -> tuple[float, float]:
    """(dtau_m/dF_z (m), the static motor torque at F_z = 0 (N m)) of finger3 (shipped parameters, palm down) at
    its block's contact (:data:`BLOCK_CONTACT_Q`): where the default gains were tuned (:data:`.DEFAULT_GAINS`)."""
    m = Model.alpes("finger3", params=palm_down_params(load_params(None)))
    q, S = np.asarray(BLOCK_CONTACT_Q, dtype=float), m.transmission.S[0]
    n = block_normal(q)
    return float(S @ (m.fingertip_jacobian(q).T @ n) / (S @ S)), static_motor_torque(m, q, 0.0, n)


def scaled_gains(controller: str, lever: float, tau_contact: float) -> dict[str, float]:
    """:data:`.DEFAULT_GAINS` of ``controller`` for a robot whose motor needs ``lever`` (m) N m per newton pressed
    and ``tau_contact`` (N m) to bring the tip to the block: kp and ki times lever / finger3's lever (the same
    force-to-force loop gain), the approach rate times tau_contact / finger3's (the same approach time, about
    0.4 s); the other settings (in newtons or seconds) as they are.

    Parameters
    ----------
    controller : str
        The controller's kind, a key of :data:`.DEFAULT_GAINS`.
    lever : float
        dtau_m/dF_z at the contact, m (N m per newton pressed).
    tau_contact : float
        The static motor torque bringing the tip to the block, N m.

    Returns
    -------
    dict of str to float
        The controller's settings.
    """
    lever3, tau3 = finger3_contact()
    defaults = {f.name: f.default for f in dataclasses.fields(ForceController)}
    gains = dict(DEFAULT_GAINS[controller])
    for g in ("kp", "ki"):
        gains[g] = lever / lever3 * gains.get(g, defaults[g])
    gains["approach_rate"] = max(tau_contact, 0.0) / tau3 * gains.get("approach_rate", defaults["approach_rate"])
    return gains


def robot_design(robot: Model, controller: str, *, frame: str | None = None, motor: str | None = None,
                 contact_q: Sequence[float] | None = None, F_max: float = _DEFAULT_F_MAX,
                 tau_max: float | None = None, gains: dict | None = None) -> LoopDesign:
    """Any URDF + spec robot pressing the block of :func:`~alpes_dyn.model.block_scene.place_block` with ``frame``
    pulled by ``motor``: the controller's model (the robot without its spec's friction), the block's normal, the
    motor limit (``tau_max``, default twice the static-balance torque of ``F_max`` N at the contact), the gains of
    :func:`scaled_gains` overridden by ``gains``. :class:`~alpes_dyn.InputError` for a block that cannot be placed
    or a contact the motor cannot press.

    Parameters
    ----------
    robot : Model
        The URDF + spec robot.
    controller : str
        The controller's kind, a key of :data:`.DEFAULT_GAINS`.
    frame : str or None, optional
        The frame pressing the block (None: :func:`~alpes_dyn.model.block_scene.place_block`'s default).
    motor : str or None, optional
        The motor pulling (None: place_block's default).
    contact_q : sequence of float or None, optional
        The joint angles at the contact, rad (None: place_block's default).
    F_max : float, optional
        The largest reference force, N, that sets the default ``tau_max`` (default 1).
    tau_max : float or None, optional
        The motor limit, N m (None: twice the static-balance torque of ``F_max``).
    gains : dict or None, optional
        Overrides of the scaled gains.

    Returns
    -------
    LoopDesign
        The controller's side of the loop.

    Raises
    ------
    InputError
        The block cannot be placed, or the motor cannot press it.
    """
    block = place_block(robot, frame, motor, contact_q)
    model = robot
    if robot.spec is not None and (robot.spec.coulomb or robot.spec.viscous):  # the controller's model: no friction
        spec = dataclasses.replace(robot.spec, coulomb={}, viscous={}, identified=None)
        model = Model(robot.urdf, spec, gravity=None if spec.gravity is not None else robot.gravity, name=robot.name,
                      check_inertia=robot.check_inertia)
    k, tip = block.motor_index, block.frame
    limit = tau_max if tau_max is not None else 2.0 * static_motor_torque(
        model, block.contact_q, F_max, block.normal, motor=k, tip=tip)
    if not limit > 0:
        raise InputError(f"tau_max: the static balance at contact_q needs no pulling torque ({limit:.3g} N m): "
                         "the block cannot be pressed by the motor (give tau_max, or another contact_q)")
    tau_contact = static_motor_torque(model, block.contact_q, 0.0, block.normal, motor=k, tip=tip)
    return LoopDesign(model, block.normal, float(limit), {**scaled_gains(controller, block.lever, tau_contact),
                                                          **(gains or {})},
                      motor=k, frame=tip, contact_q=tuple(block.contact_q.tolist()), block=block)


def force_ekf(model: Model, dt: float, controller: str, *, torque_noise: float, encoder_noise_counts: float,
              force_noise: float, force_resolution: float, tip: str | None = None) -> tuple[Any, np.ndarray, np.ndarray]:
    """The force loop's EKF: (the filter, its prior z0 = [q_rest; 0] (2n,), its prior variances (2n,)).

    Known input w = [tau_m (m,), -F n (3,)] (N m, N) with the variances ``torque_noise``^2 and, for the contact
    force, the FlexiForce's noise and quantisation (``force_noise``^2 + ``force_resolution``^2 / 12) with the
    ``"sensor"`` controller, (0.05 N)^2 for the sensorless estimate; the encoders measured (rad: the quantisation
    step^2 / 12 plus ``encoder_noise_counts`` counts of noise); the process noise of
    :func:`~alpes_dyn.estimation.observers.scenario.default_noise`. The prior: the finger at rest on its springs
    (motor off), standard deviations 0.05 rad and 0.1 rad/s. A model with friction is predicted with
    :func:`~alpes_dyn.simulation.integrate.stable_substeps` RK4 steps per period (at least 4: with one, the smooth
    law's slope F_s / v_s near rest puts the step outside RK4's stable reach, and a difference in a reading at
    rounding level grows to a visible error of the joint estimate within a fraction of a second). The friction law
    is the file's (:func:`~alpes_dyn.simulation.stick.observer_friction_law`, as ``estimate``'s): ``creep`` solved
    with the dynamics in each substep, ``lugre`` with the joints' bristle deflections z (n,) rad as the state's last
    entries (prior 0, standard deviation F_s / sigma0; :func:`~alpes_dyn.simulation.lugre.lugre_substeps` split
    steps per period).

    Parameters
    ----------
    model : Model
        The EKF's model (with friction: RK4 substeps).
    dt : float
        The sample period, s.
    controller : str
        The controller's kind (``"sensor"``: the FlexiForce's variance on the force input).
    torque_noise : float
        The motor torque's noise's standard deviation, N m.
    encoder_noise_counts : float
        The encoder's noise's standard deviation, counts.
    force_noise : float
        The FlexiForce's noise's standard deviation, N.
    force_resolution : float
        The FlexiForce's quantisation step, N.
    tip : str or None, optional
        The contact frame (None: the model's default tip).

    Returns
    -------
    ekf : observer
        The filter.
    z0 : numpy.ndarray, shape (nz,)
        Its prior [q_rest; 0] (rad and rad/s; nz = 2n), with the LuGre law's bristles [q_rest; 0; 0] (nz = 3n).
    P0 : numpy.ndarray, shape (nz,)
        Its prior variances, rad^2 and (rad/s)^2 (the bristles' (F_s / sigma0)^2, rad^2).
    """
    n, m = model.n, len(model.transmission.motor_names)
    step = 2 * np.pi / model.transmission.counts_per_rev
    ss = StateSpace(model, input="motor", output="encoder", force=True, tip=tip)
    est_sc = EstimationScenario(torque_noise=torque_noise, encoder_noise_counts=encoder_noise_counts)
    meas_var = step**2 / 12 + (encoder_noise_counts * step) ** 2
    noise = default_noise(est_sc, n, m, 0, meas_var)
    f_var = (force_noise**2 + force_resolution**2 / 12) if controller == "sensor" else 0.05**2
    noise["input_noise"] = [torque_noise**2] * m + [f_var] * 3
    law = observer_friction_law(model) if model.extras.has_friction else "smooth"
    lugre = lugre_of(model) if law == "lugre" else None
    substeps = (lugre_substeps(model, lugre, dt) if lugre is not None else stable_substeps(model, dt)) \
        if model.extras.has_friction else 1
    ekf = make_observer("ekf", ss, dt, substeps=substeps, friction_law=law, **noise)
    span = model.extras.coulomb[:ekf.model.nb] / (lugre.sigma0 if lugre is not None else 1.0)  # F_s / sigma0, rad
    z0 = np.concatenate([static_equilibrium(model, np.zeros(n)), np.zeros(n), np.zeros(span.size)])
    return ekf, z0, np.concatenate([[0.05**2] * n + [0.1**2] * n, span**2])


def _number(x: Any, name: str, what: str, positive: bool = False, nonneg: bool = False) -> float:
    """``x`` as a float: a finite real number (positive, or >= 0); :class:`~alpes_dyn.InputError` naming ``name``."""
    ok = not isinstance(x, (bool, np.bool_)) and isinstance(x, (int, float, np.integer, np.floating))
    if ok:
        x = float(x)
        ok = math.isfinite(x) and (not positive or x > 0) and (not nonneg or x >= 0)
    if not ok:
        kind = "a positive" if positive else "a non-negative" if nonneg else "a finite"
        raise InputError(f"{name}: expected {kind} number of {what}, got {x!r}")
    return x


class ForceStep:
    """One sample of the fingertip force loop: ``command = step.step(counts, torque, force, reference)``.

    Built once from what a user has (the finger, its parameter file, the controller's kind, the contact); the
    EKF's step is compiled (or loaded from the cache) here, not in :meth:`step`. The module docstring gives the
    timing: call :meth:`step` once per tick with that tick's readings and write the command it returns at once.

    Parameters
    ----------
    model : str or Model
        ``"finger2"`` or ``"finger3"`` (:data:`CONTROL_MODELS`), or a URDF + spec :class:`~alpes_dyn.Model` (one
        motor pulls a tip frame onto the block of :func:`~alpes_dyn.model.block_scene.place_block`, as
        :func:`~alpes_dyn.control.finger_loop.run_control` does).
    params : str, Path, HandParams or None
        The Alpes finger's parameter file (e.g. ``alpes-dyn identify``'s: its springs, masses, tendon compliance
        and rotor give the model, the EKF, the tendon's stretch and the notch); None: the shipped parameters.
        Refused for a URDF model (its spec is its parameters).
    controller : str
        ``"sensor"`` (the FlexiForce fed back), ``"sensorless"`` (the force estimated from the motor torque and
        q_hat) or ``"pi"`` (a PI on the FlexiForce alone, no model, no observer), :data:`.CONTROLLERS`.
    dt : float
        The sample period, s (1e-3: the hand's 1 kHz loop).
    contact_q : sequence of float or None
        Joint angles (rad) where the fingertip meets the object; the normal is the block scene's at them
        (:func:`~alpes_dyn.model.mjcf.block_normal`). None: :data:`~alpes_dyn.model.mjcf.BLOCK_CONTACT_Q` (a URDF
        model: :func:`~alpes_dyn.model.block_scene.place_block`'s).
    normal : sequence of float or None
        The object's surface normal n (3,), base frame, pointing from the fingertip into the object: given, it
        replaces the block scene's (the finger then presses another object).
    gains : dict or None
        Overrides of the tuned :data:`.DEFAULT_GAINS` of ``controller`` (any :class:`.ForceController` setting;
        a URDF model's are scaled to it first, :func:`scaled_gains`).
    compensation : Compensation or None
        What the loop does about a real hand's effects (:class:`~alpes_dyn.control.realism_loop.Compensation`:
        the tendon's stretch and the encoder's offset off the encoder, the command as the observer's torque, the
        notch at the cable's mode, the palm's tilt, the sensorless estimate's scale). None: every compensation on
        (``Compensation()``: with a rigid file -- no tendon compliance -- only the command input acts);
        :data:`~alpes_dyn.control.realism_loop.NO_COMPENSATION`: the rigid design.
    palm_down : bool
        The hand palm down (gravity reversed, the finger flexing toward an object under it), as the block scene
        of :func:`~alpes_dyn.control.finger_loop.run_control` and the MuJoCo stand-in; False: the file's gravity.
    compiled : bool
        The EKF's step in compiled C (cached; CasADi's virtual machine if no C compiler); False: CasADi's virtual
        machine (no compiler needed; the same numbers, slower).
    torque_noise, encoder_noise_counts, force_noise, force_resolution : float
        The sensors' noise the EKF assumes: N m on the motor torque, counts on the encoder, N and the N of one
        step on the fingertip force (the defaults: the simulated bench's, :class:`.ControlScenario`).
    force_filter_s : float
        The sensorless estimate's low-pass time constant, s.
    frame, motor : str or None
        A URDF model's contact frame and pulling motor, as :class:`.ControlScenario`'s.
    tau_max : float or None
        Its motor limit, N m.
    force : bool
        Use a parameter file marked not trustworthy (refused otherwise: :class:`~alpes_dyn.ModelError` with the
        reason the file records, :func:`~alpes_dyn.model.trust.check_trusted`).
    observer_friction : bool
        The Alpes finger's EKF runs the file's friction (its ``friction.law``: tanh, eq. 2.6-2.7, creep or LuGre,
        :func:`force_ekf`, :func:`alpes_design`; the controller's static balance stays frictionless, eq. 2.11).
        False: the frictionless model of version 0.2's loop.

    Attributes
    ----------
    model : Model
        The controller's (and the EKF's) model. ``m`` its motors, ``motor`` the pulling motor's index.
    controller : ForceController
        The controller (its state advances at each :meth:`step`).
    tau_max : float
        The motor limit, N m: every command lies in [0, tau_max].
    filter_step : callable or None
        The EKF's compiled step (s, wy) -> s_next, built once (None for ``"pi"``).
    nz : int
        The EKF's states: 2n ([q; qd]), 3n with the LuGre law's bristles (:func:`force_ekf`).

    Raises
    ------
    InputError
        An unknown model or controller, a bad setting (one line naming it). ModelError: an unreadable parameter
        file.
    """

    def __init__(self, model: Any = "finger3", params: Any = None, controller: str = "sensor", *, dt: float = 1e-3,
                 contact_q: Sequence[float] | None = None, normal: Sequence[float] | None = None,
                 gains: dict | None = None, compensation: Compensation | None = None, palm_down: bool = True,
                 compiled: bool = True, torque_noise: float = 5e-4, encoder_noise_counts: float = 0.5,
                 force_noise: float = 0.005, force_resolution: float = 4.4 / 1024, force_filter_s: float = 0.01,
                 frame: str | None = None, motor: str | None = None, tau_max: float | None = None,
                 observer_friction: bool = True, force: bool = False) -> None:
        robot = isinstance(model, Model)
        if not robot and (not isinstance(model, str) or model not in CONTROL_MODELS):
            raise InputError(f"model: the force step is defined for one finger ({', '.join(CONTROL_MODELS)}) "
                             f"or a URDF + spec Model, got {model!r}")
        comp = _checked_settings(controller, compensation, gains)
        if robot:
            if params is not None:
                raise InputError("params: applies to the Alpes fingers; a URDF model's parameters are its spec")
            design = robot_design(model, controller, frame=frame, motor=motor, contact_q=contact_q,
                                  tau_max=None if tau_max is None else _number(tau_max, "tau_max", "N m", True),
                                  gains=gains)
        else:
            for name, v in (("frame", frame), ("motor", motor), ("tau_max", tau_max)):
                if v is not None:
                    raise InputError(f"{name}: applies to a URDF + spec model; the Alpes finger presses with its "
                                     "fingertip, its motor and its tau_max are the parameter file's")
            _check_contact_q(contact_q, 2 if model == "finger2" else 3)
            p = params if isinstance(params, HandParams) else load_params(params)
            check_trusted(p, bool(force))
            design = alpes_design(model, palm_down_params(p) if palm_down else p, controller, contact_q, comp,
                                  dict(gains or {}), observer_friction=bool(observer_friction))
        if normal is not None:
            design = dataclasses.replace(design, normal=_normal(normal))
        noise = {k: _number(v, k, u, nonneg=True) for k, v, u in (
            ("torque_noise", torque_noise, "N m"), ("encoder_noise_counts", encoder_noise_counts, "counts"),
            ("force_noise", force_noise, "N"))}
        noise["force_resolution"] = _number(force_resolution, "force_resolution", "N", nonneg=True)
        self._build(design, controller, _number(dt, "dt", "seconds", positive=True), comp, noise,
                    _number(force_filter_s, "force_filter_s", "seconds", nonneg=True), bool(compiled),
                    f"ekf_force_{model.name if robot else model}")

    @classmethod
    def from_design(cls, design: LoopDesign, controller: str, dt: float, compensation: Compensation, *,
                    noise: dict, force_filter_s: float, compiled: bool, label: str) -> "ForceStep":
        """A step from a :class:`LoopDesign` (the settings already checked): what
        :func:`~alpes_dyn.control.finger_loop.run_control` builds from its scenario.

        Parameters
        ----------
        design : LoopDesign
            The loop's model, contact and limits.
        controller : str
            The controller's kind.
        dt : float
            The period, s.
        compensation : Compensation
            The effects' compensation.
        noise : dict
            The keyword arguments ``torque_noise``, ``encoder_noise_counts``, ``force_noise``, ``force_resolution``
            of :func:`force_ekf`.
        force_filter_s : float
            The sensorless estimate's low-pass time constant, s.
        compiled : bool
            The EKF's step compiled.
        label : str
            The compiled EKF's cache name.

        Returns
        -------
        ForceStep
            The step.
        """
        self = cls.__new__(cls)
        self._build(design, controller, dt, compensation, noise, force_filter_s, compiled, label)
        return self

    def _build(self, design: LoopDesign, kind: str, dt: float, comp: Compensation, noise: dict,
               force_filter_s: float, compiled: bool, label: str) -> None:
        """Everything a sample needs, built once: the controller's arguments, the EKF and its compiled step, the
        sensorless estimate, the compensation's constants."""
        _check_kind(kind)
        self.design, self.kind, self.dt, self.compensation = design, kind, float(dt), comp
        model = self.model = design.model
        tr = model.transmission
        self.n, self.m, self.motor = model.n, len(tr.motor_names), design.motor
        self.tau_max = float(design.tau_max)
        self.counts_per_rev = tr.counts_per_rev
        self._rad_per_count = 2 * np.pi / tr.counts_per_rev
        self._transmission = tr
        # the encoder's zero taken off the reading: the compensation's, else the file's (identify's encoder_offset)
        self._offset = comp.offset_of(design.params, tr.motor_names[design.motor], model.chain)
        self._normal = np.asarray(design.normal, dtype=float)
        tip = {} if design.frame is None else {"motor": design.motor, "tip": design.frame}
        self._controller_args = dict(kind=kind, model=model, normal=self._normal, dt=self.dt, tau_max=self.tau_max,
                                     **tip, **design.gains, **comp.notch_settings(model, design.params, self.dt))
        ForceController(**self._controller_args)  # the settings checked here, not at the first sample
        self.filter_step: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
        self.nz = 2 * self.n  # the EKF's states: [q; qd], and the LuGre law's bristles (force_ekf)
        if kind != "pi":
            ekf, z0, P0 = force_ekf(design.observer_model or model, self.dt, kind, tip=design.frame, **noise)
            self._ekf, self.nz = ekf, ekf.nz
            self._s0 = np.concatenate([np.array(ekf._z(z0, "z0")).reshape(-1),
                                       np.array(ekf._P(P0, "P0")).reshape(-1, order="F")])
            self.filter_step = self._compiled_c(ekf, label) if compiled and ekf.model.substeps > 1 else None
            if self.filter_step is None:  # the VM, or CasADi's code of the whole step, compiled and cached
                self.filter_step = step_caller(ekf.filter_step_p, label, compiled, ekf.model.values)
        self._force_scale = comp.scale_of()
        self._sensorless = None
        if kind == "sensorless":
            self._sensorless = SensorlessForce(model, self.dt / (force_filter_s + self.dt), normal=self._normal,
                                               tip=design.frame, scale=comp.scale_of())
        self.reset()

    @staticmethod
    def _compiled_c(ekf: Any, label: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray] | None:
        """The friction EKF's step from its C export (a loop over one substep: the code ``alpes-dyn codegen --step``
        writes), built once and cached; None without a C compiler."""
        from ..estimation.cexport.cexport import compiled_c_step

        return compiled_c_step(ekf, f"{label}_c")

    def reset(self) -> None:
        """Back to the first sample: the controller's state cleared (approach, integral, prefilter, notch), the
        EKF at its prior (the finger at rest), the sensorless estimate at 0, the last command 0."""
        self.controller = ForceController(**self._controller_args)
        self.k = 0
        self._n = self._normal.copy()  # the contact normal of the last sample (a step's ``normal`` replaces it)
        self._command = np.zeros(self.m)
        self._F_fb = 0.0
        if self.filter_step is not None:
            self._s = self._s0.copy()
            self._wy = np.empty(self.m + 3 + self.m)  # [tau_m; -F n; y]: the filter's known input and measurement
        if self._sensorless is not None:
            self._sensorless.start(0, self.dt, False)

    # ---------------------------------------------------------------- the sample
    def step(self, counts: Any, torque: Any, force: Any, reference: float, normal: Any = None) -> np.ndarray:
        """One sample: the readings of tick k in, the (m,) motor command (N m, in [0, tau_max]) to hold over
        [t_k, t_k+1) out (the pulling motor's; the others 0).

        Parameters
        ----------
        counts : array_like
            (m,) encoder counts at t_k (one motor: a number too).
        torque : array_like
            (m,) the motor torque the current sensor reports at t_k (the current times the torque constant), N m.
        force : float or None
            The fingertip sensor's normal force at t_k, N; not read by ``"sensorless"`` (None or NaN there).
        reference : float
            The force reference F_ref at t_k, N.
        normal : array_like or None
            (3,) the object's surface normal at the contact from this sample on (base frame, from the fingertip
            into the object, any length: normalised), for this sample's EKF input, sensorless estimate and
            controller -- what the C step takes at each call; None: the last one (at first the step's own).

        Raises
        ------
        InputError
            A reading of the wrong shape, not finite (NaN counts), a missing force for ``"sensor"``/``"pi"``, a zero
            ``normal``, an EKF that diverged on the readings (one line naming it; the step's state is left as it was).
        """
        y = self._vector(counts, "counts", "encoder counts") * self._rad_per_count
        tau_r = self._vector(torque, "torque", "motor torques in N m")
        if self.kind != "sensorless":
            if force is None or isinstance(force, (bool, np.bool_)) or not isinstance(
                    force, (int, float, np.integer, np.floating)) or not math.isfinite(force):
                raise InputError(f"force: the {self.kind} controller needs the fingertip force in N (a finite "
                                 f"number), got {force!r}")
        if isinstance(reference, (bool, np.bool_)) or not isinstance(
                reference, (int, float, np.integer, np.floating)) or not math.isfinite(reference):
            raise InputError(f"reference: expected a finite force reference in N, got {reference!r}")
        n_k = self._n if normal is None else _normal(normal)
        comp = self.compensation
        tau = self._command if comp.command_input else tau_r  # the motor torque over [t_k-1, t_k)
        q_hat, F_fb = None, force
        if self.filter_step is not None:
            if self.k > 0:
                wy, m = self._wy, self.m
                wy[:m] = tau
                # the force in the file's torque units: the sensor's N (the sensorless estimate's) times force_scale
                wy[m:m + 3] = -(F_fb if self.kind == "sensor" else self._F_fb) * self._force_scale * n_k
                wy[m + 3:] = comp.unstretched(self._transmission, y, tau, self._offset) if comp.observer_compliance else y
                s = self.filter_step(self._s, wy)
                if not (np.abs(s[:2 * self.n]) < _DIVERGED).all():  # NaN too
                    raise InputError(f"readings: the EKF diverged at sample {self.k} (joint estimate "
                                     f"{np.array2string(s[:self.n], precision=3)} rad): check the readings' units "
                                     "(counts, N m, N) and the parameter file; reset() to start again")
                self._s = s
            q_hat = self._s[:self.n]
            if self._sensorless is not None:
                F_fb = self._sensorless.sample(q_hat, tau, n_k)
        u = self.controller.update(float(reference), F_fb, q_hat, None if normal is None else n_k)
        self._n = n_k
        self._command = np.zeros(self.m)
        self._command[self.motor] = u
        self._F_fb = F_fb
        self.k += 1
        return self._command.copy()

    def _vector(self, x: Any, name: str, what: str) -> np.ndarray:
        """``x`` as an (m,) array of finite numbers (a number for one motor); InputError naming ``name``."""
        try:
            v = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name}: expected {self.m} {what}, got {x!r}") from None
        if v.shape == () and self.m == 1:
            v = v.reshape(1)
        if v.shape != (self.m,):
            raise InputError(f"{name}: expected {self.m} {what}, got shape {v.shape}")
        if not np.isfinite(v).all():
            raise InputError(f"{name}: expected finite {what}, got {v.tolist()!r}")
        return v

    # ---------------------------------------------------------------- what the step knows
    def parts(self) -> StepParts:
        """The step's settings, for a code generator or a port of the step (:class:`.StepParts`; not its state).

        Returns
        -------
        StepParts
            The models, the EKF and its prior, the compensation's constants, the sensorless filter, a fresh
            controller with the step's settings.
        """
        tr, sl, comp = self._transmission, self._sensorless, self.compensation
        filt = self.filter_step is not None
        nz = self.nz if filt else 2 * self.n
        return StepParts(
            model=self.model, observer_friction=self.design.observer_model is not None, kind=self.kind, dt=self.dt,
            motor=self.motor, motor_names=tuple(tr.motor_names), tau_max=self.tau_max,
            rad_per_count=float(self._rad_per_count), encoder_offset=float(self._offset),
            tendon_compliance=np.asarray(tr.tendon_compliance if tr.elastic else np.zeros(self.m), dtype=float),
            unstretch=bool(comp.observer_compliance), command_input=bool(comp.command_input),
            normal=self._normal.copy(), controller=ForceController(**self._controller_args),
            ekf=self._ekf if filt else None, z0=self._s0[:nz].copy() if filt else np.full(nz, np.nan),
            P0=self._s0[nz:].copy() if filt else np.full(nz * nz, np.nan),
            sensorless_alpha=None if sl is None else float(sl.alpha),
            force_scale=float(self._force_scale))

    @property
    def command(self) -> np.ndarray:
        """(m,) the last command returned, N m (zeros before the first sample)."""
        return self._command.copy()

    @property
    def state(self) -> np.ndarray:
        """[q_hat; qd_hat] (2n,) of the last sample (rad, rad/s); NaN for ``"pi"`` (no observer)."""
        if self.filter_step is None:
            return np.full(2 * self.n, np.nan)
        return self._s[:2 * self.n].copy()

    @property
    def estimate(self) -> tuple[np.ndarray, np.ndarray]:
        """(q_hat (n,) rad, qd_hat (n,) rad/s): the EKF's joint estimate at the last sample (NaN for ``"pi"``)."""
        z = self.state
        return z[:self.n], z[self.n:]

    @property
    def covariance(self) -> np.ndarray:
        """(2n, 2n) the EKF's covariance of [q; qd] at the last sample (rad^2, rad^2/s^2, rad^2/s); NaN for
        ``"pi"``."""
        if self.filter_step is None:
            return np.full((2 * self.n, 2 * self.n), np.nan)
        nz = self.nz
        return self._s[nz:].reshape(nz, nz, order="F")[:2 * self.n, :2 * self.n].copy()

    @property
    def std(self) -> tuple[np.ndarray, np.ndarray]:
        """(q standard deviations (n,) rad, qd's (n,) rad/s): the square roots of :attr:`covariance`'s diagonal."""
        s = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        return s[:self.n], s[self.n:]

    @property
    def force_estimate(self) -> float:
        """The contact force the controller fed back at the last sample, N: the sensorless estimate, or the
        fingertip sensor's reading (``"sensor"``, ``"pi"``); 0 before the first sample."""
        return float(self._F_fb)

    def __repr__(self) -> str:
        return (f"ForceStep({self.model.name!r}, controller={self.kind!r}, dt={self.dt:g}, tau_max={self.tau_max:g}, "
                f"sample {self.k})")


def _check_contact_q(contact_q: Any, n: int) -> None:
    """None, or at least ``n`` finite joint angles (rad; the first n are the finger's); InputError naming it."""
    if contact_q is None:
        return
    try:
        q = np.asarray(contact_q, dtype=float)
    except (TypeError, ValueError):
        q = np.array([np.nan])
    if q.ndim != 1 or q.shape[0] < n or not np.isfinite(q).all():
        raise InputError(f"contact_q: expected {n} finite joint angles in rad, got {contact_q!r}")


def _checked_settings(controller: Any, compensation: Any, gains: Any) -> Compensation:
    """A step's controller name, compensation (None: :class:`Compensation`'s defaults) and gains checked, each
    :class:`InputError` naming the argument; the compensation to use."""
    _check_kind(controller)
    comp = Compensation() if compensation is None else compensation
    if not isinstance(comp, Compensation):
        raise InputError(f"compensation: expected a Compensation, got {type(comp).__name__}")
    comp.check()
    if gains is not None and not isinstance(gains, dict):
        raise InputError(f"gains: expected a dict of ForceController settings, got {type(gains).__name__}")
    unknown = sorted(set(gains or {}) - set(GAIN_NAMES))
    if unknown:
        raise InputError(f"gains: unknown setting(s) {', '.join(map(repr, unknown))} (expected "
                         f"{', '.join(GAIN_NAMES)})")
    return comp


def _check_kind(kind: Any) -> None:
    if not isinstance(kind, str) or kind not in CONTROLLERS:
        raise InputError(f"controller: unknown controller {kind!r} (expected one of {', '.join(CONTROLLERS)})")
