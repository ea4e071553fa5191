"""The closed loop of one finger pressing a block, MuJoCo as the plant, a controller of
:mod:`alpes_dyn.control.controller` on the hand's sensors.

:func:`run_control` runs the closed loop with MuJoCo as the plant (the MJCF of :mod:`alpes_dyn.model.mjcf`,
contact on, the block scene, joint friction on: ``pip install 'alpes_dyn[mujoco]'``); see
:class:`ControlScenario` for every setting and :class:`ControlResult` for the metrics. The same loop runs on any
tendon-driven robot given as a URDF + spec (a :class:`~alpes_dyn.Model` as ``model``): one motor pulls, a named tip
frame presses a block placed from the robot's own kinematics (:func:`~alpes_dyn.model.block_scene.place_block`),
MuJoCo steps the model's MJCF export (:func:`~alpes_dyn.model.block_scene.block_scene_mjcf`). The loop is a composition
of blocks run by :func:`~alpes_dyn.simulation.loop.run_loop`: the reference, the MuJoCo plant, the encoder, current
and FlexiForce sensors, the force controller and, for the model-based controllers, the EKF (and the sensorless
force estimate).
"""

from __future__ import annotations

import csv
import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..bench.effects import PlantEffects
from ..bench.mujoco_plant import block_plant
from ..errors import InputError, ModelError
from ..fileio import atomic_path
from ..limits import check_bytes, check_duration
from ..model.block_scene import BlockScene, block_scene_mjcf
from ..model.mjcf import joint_permutation, load_mujoco, palm_down_params
from ..model.robot import Model
from ..model.params import HandParams, load_params
from ..model.trust import check_trusted
from ..simulation.loop import Block, Delay, Function, Source, run_loop
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, ForceSensor, TorqueSensor
from .controller import CONTROLLERS, DEFAULT_LEVELS, REFERENCES, reference_profile
from .realism_loop import NO_COMPENSATION, Compensation, SampleLag, torque_constant_blocks
from .step import (_DEFAULT_F_MAX, CONTROL_MODELS, ForceStep, LoopDesign, alpes_design, finger3_contact, robot_design,  # noqa: F401
                   scaled_gains)


@dataclass(frozen=True)
class ControlScenario:
    """Settings of the closed loop of :func:`run_control` (all SI units).

    The plant: MuJoCo stepping the MJCF of ``model`` with the ``"block"`` scene (a fixed, frictionless
    block met by the fingertip at ``contact_q``, :func:`~alpes_dyn.model.mjcf.block_normal`), contact and joint
    stops on, joint friction on
    (damping F_v, frictionloss F_s of the parameter file), the hand palm down (gravity reversed: the
    finger flexes with gravity toward the block under it), at ``dt / substeps``; its parameters are
    ``plant_params`` (default: the controller's). The controller's model is
    ``Model.alpes(model, params)`` palm down, no friction (the report's eq. 2.11); the EKF's, the same with the
    file's friction (eq. 2.6-2.7; ``observer_friction=False``: frictionless as the controller's).

    Sensors, sampled every ``dt`` (1 kHz): the encoder as in the estimation scenario
    (``transmission.encoder_counts`` counts per motor revolution, plus ``encoder_noise_counts`` counts
    of Gaussian noise, then quantised); the motor torque plus ``torque_noise`` N m of white noise; the
    FlexiForce: MuJoCo's touch sensor plus ``force_noise`` N of noise, quantised to ``force_resolution``
    (a 10-bit reading of a 4.4 N -- 1 lb -- FlexiForce A201: 4.3 mN).

    The reference (:func:`.reference_profile`): ``levels`` (N) and a 1 Hz sine between ``sine[0]`` and
    ``sine[1]``; metrics over the levels after ``settle`` s (see :class:`ControlResult`). The sensorless
    loop low-passes its force estimate with ``force_filter_s``. ``gains`` override
    :data:`.DEFAULT_GAINS` (any :class:`.ForceController` field). ``compiled``: the EKF step in compiled C
    (cached; CasADi's virtual machine if no C compiler), the same numbers.

    Initial state: the finger at rest on its springs (static equilibrium, motor off); the EKF starts
    there too, with standard deviations 0.05 rad and 0.1 rad/s.

    **Any robot** (``model`` an :class:`~alpes_dyn.Model` built from a URDF and its spec): motor ``motor`` (its
    name; default the only motor, or the only one moving ``frame``) pulls and the tip frame ``frame`` (default the
    only tip that motor moves; the candidates are listed otherwise) presses the block of
    :func:`~alpes_dyn.model.block_scene.place_block`: at the frame's position at ``contact_q`` ((n,) rad, inside
    the joint ranges; default None: where the motor's free pull has covered 25 % of its joints' ranges), its
    face square to the direction the frame moves there as the motor pulls harder. The plant: MuJoCo stepping
    :func:`~alpes_dyn.model.block_scene.block_scene_mjcf` (the model's MJCF export, its spec's friction on, the
    spec's gravity; MuJoCo's ``implicitfast`` integrator as the Alpes scene's), the other motors' commands at 0;
    the sensors: ``encoder_<motor>``, ``torque_<motor>`` and the touch sensor ``touch_<frame>`` with the noises
    above. The controller's and the EKF's model: ``model`` without its spec's friction, as the Alpes loop's; the
    EKF's contact force acts at ``frame``. ``tau_max`` (N m): the motor's limit (a spec holds none; default twice
    the static-balance torque of the largest reference force, at least 1 N, at ``contact_q``). The gains of :data:`.DEFAULT_GAINS`
    (tuned on finger3) are scaled to the robot (:func:`scaled_gains`: kp and ki by its lever dtau_m/dF_z at the
    contact over finger3's, the approach rate by its motor torque at the contact over finger3's); ``gains`` then
    override them. ``params``, ``plant_params`` are the Alpes models' (refused here); the plant is the model.

    **A real hand's effects** (the Alpes fingers): ``effects`` a :class:`~alpes_dyn.bench.effects.PlantEffects` --
    stick-slip friction, the series-elastic tendon with its rotor and slack, the palm's tilt, the torque constant's
    error, the encoder's offset, the torque read late -- on the plant (:mod:`alpes_dyn.control.realism_loop`), and
    ``compensation`` a :class:`~alpes_dyn.control.realism_loop.Compensation`, what the controllers do about them
    (default with ``effects``: every compensation on; :data:`~alpes_dyn.control.realism_loop.NO_COMPENSATION` the rigid
    design). ``params`` is then typically an identified file (``alpes-dyn identify``), ``plant_params`` the truth.
    """

    model: Any = "finger3"
    controller: str = "sensor"
    reference: str = "step"
    duration: float = 3.0
    dt: float = 1e-3
    substeps: int = 4
    seed: int = 0
    levels: tuple[float, float, float] = DEFAULT_LEVELS
    sine: tuple[float, float, float] = (0.3, 0.8, 1.0)
    step_times: tuple[float, float] = (1.0, 2.0)
    settle: float = 0.5
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    force_noise: float = 0.005
    force_resolution: float = 4.4 / 1024
    contact_q: tuple[float, ...] | None = None  # None: BLOCK_CONTACT_Q on an Alpes finger, place_block's on a URDF
    force_filter_s: float = 0.01
    compiled: bool = True
    gains: dict = field(default_factory=dict, compare=False)  # overrides of DEFAULT_GAINS[controller]
    params: Any = field(default=None, compare=False)
    plant_params: Any = field(default=None, compare=False)
    frame: str | None = None
    motor: str | None = None
    tau_max: float | None = None
    effects: Any = field(default=None, compare=False)  # a PlantEffects: the plant's unmodelled effects (realism_loop)
    compensation: Any = field(default=None, compare=False)  # a Compensation (default: all on with effects)
    observer_friction: bool = True  # an Alpes finger's EKF runs its file's friction (ForceStep's observer_friction)
    force: bool = False  # a controller's file marked not trustworthy used anyway (model.trust.check_trusted)

    @property
    def robot(self) -> bool:
        """Whether ``model`` is any robot's :class:`~alpes_dyn.Model` (a URDF + spec) rather than an Alpes finger."""
        return isinstance(self.model, Model)

    @property
    def model_name(self) -> str:
        """The Alpes finger's name, or the Model's (its spec's or URDF's name)."""
        return self.model.name if self.robot else str(self.model)

    def check(self) -> None:
        if not self.robot and (not isinstance(self.model, str) or self.model not in CONTROL_MODELS):
            raise InputError(f"model: the control scenario is defined for one finger ({', '.join(CONTROL_MODELS)}) "
                             f"or a URDF + spec Model, got {self.model!r}")
        _check_effects(self.effects, self.compensation, self.robot)
        if self.robot:
            for name in ("params", "plant_params"):
                if getattr(self, name) is not None:
                    raise InputError(f"{name}: applies to the Alpes fingers; a URDF model's plant and controller are "
                                     "the model itself (its spec)")
            if self.tau_max is not None and not (isinstance(self.tau_max, (int, float)) and not isinstance(
                    self.tau_max, bool) and math.isfinite(self.tau_max) and self.tau_max > 0):
                raise InputError(f"tau_max: expected a positive motor torque limit in N m, got {self.tau_max!r}")
        else:
            for name in ("frame", "motor", "tau_max"):
                if getattr(self, name) is not None:
                    raise InputError(f"{name}: applies to a URDF + spec model; the Alpes finger presses with its "
                                     "fingertip, its motor and its tau_max are the parameter file's")
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.controller!r} "
                             f"(expected one of {', '.join(CONTROLLERS)})")
        if self.reference not in REFERENCES:
            raise InputError(f"reference: unknown reference {self.reference!r} (expected one of {', '.join(REFERENCES)})")
        if not (isinstance(self.duration, (int, float)) and math.isfinite(self.duration) and self.duration > 0):
            raise InputError(f"duration: expected a positive number of seconds, got {self.duration!r}")
        check_duration(self.duration, "duration")
        if not self.settle + _METRIC_WINDOW_S <= self.duration:
            raise InputError(f"duration: {self.duration:g} s leaves less than {_METRIC_WINDOW_S:g} s after the settling "
                             f"time {self.settle:g} s (the metrics' window)")
        if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt) and self.dt > 0):
            raise InputError(f"dt: expected a positive number of seconds, got {self.dt!r}")
        check_bytes(8.0 * self.duration / self.dt * _SAMPLE_ARRAYS, "duration",
                    f"{self.duration:g} s at dt = {self.dt:g} s")
        if self.substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {self.substeps!r}")


def _check_effects(effects: Any, compensation: Any, robot: bool) -> None:
    """``effects`` a PlantEffects or None, ``compensation`` a Compensation or None (only with effects), on an Alpes
    finger (one-line InputError naming the field)."""
    if effects is None:
        if compensation is not None:
            raise InputError("compensation: applies to a plant with effects (give effects)")
        return
    if robot:
        raise InputError("effects: the real hand's effects apply to the Alpes models (finger2, finger3, hand)")
    if not isinstance(effects, PlantEffects):
        raise InputError(f"effects: expected a PlantEffects, got {type(effects).__name__}")
    effects.check()
    if compensation is not None:
        if not isinstance(compensation, Compensation):
            raise InputError(f"compensation: expected a Compensation, got {type(compensation).__name__}")
        compensation.check()


_METRIC_WINDOW_S = 0.05
"""Shortest run after the settling time, s: the force RMSE needs samples (50 at 1 kHz)."""
_SAMPLE_ARRAYS = 64
"""Float64 values a closed-loop run keeps per sample (an upper bound: traces of forces, torques, q, q-hat)."""


@dataclass
class ControlResult:
    """One closed-loop run.

    Attributes
    ----------
    t: (N,) times, s. F_ref: (N,) reference, N. F_true: (N,) MuJoCo's touch sensor (noise-free), N.
    F_meas: (N,) the FlexiForce reading (noisy, quantised), N. F_hat: (N,) the force the controller fed
    back (F_meas, or the sensorless estimate), N. q_true, q_hat: (N, n) joints, rad (q_hat NaN for ``pi``).
    tau_cmd, tau_meas: (N,) motor torque command and its noisy measurement, N m.
    force_rmse: RMSE of F_true - F_ref after ``settle``, N. steady_state_error: worst over the constant
    levels (after ``settle``; for the ramp, the levels before and after it) of |mean(F_true) - F_ref| / F_ref
    over each level's last 200 ms (None for the sine). overshoot: worst over the steps of the excursion
    beyond the new level / step size (None unless step). rise_time_s: 10-90 % rise time of the up-step, s
    (None unless step). q_rmse_deg: (n,) RMSE of
    q_hat - q during contact (F_true > 0.05 N), deg (None for ``pi``). wall_s: wall time of the loop, s.
    saturated: fraction of samples with the command at 0 or tau_max.
    block: on a URDF model, the block's placement, a :class:`~alpes_dyn.model.block_scene.BlockScene` (frame,
        motor, contact_q, normal, lever); None on an Alpes finger.
    """

    scenario: ControlScenario
    t: np.ndarray
    F_ref: np.ndarray
    F_true: np.ndarray
    F_meas: np.ndarray
    F_hat: np.ndarray
    q_true: np.ndarray
    q_hat: np.ndarray
    tau_cmd: np.ndarray
    tau_meas: np.ndarray
    joint_names: tuple[str, ...]
    tau_max: float
    wall_s: float
    force_rmse: float = float("nan")
    steady_state_error: float | None = None
    overshoot: float | None = None
    rise_time_s: float | None = None
    q_rmse_deg: list[float] | None = None
    saturated: float = 0.0
    block: BlockScene | None = None  # a URDF model's block (None on an Alpes finger)

    @property
    def realtime_ratio(self) -> float:
        """Simulated time / wall time of the loop (> 1: faster than real time)."""
        return float(self.scenario.duration / self.wall_s)

    def to_dict(self) -> dict[str, Any]:
        """The JSON summary of ``alpes-dyn control --json``."""
        sc = self.scenario
        return {
            "controller": sc.controller, "plant": "mujoco", "model": sc.model_name, "reference": sc.reference,
            "force_rmse": self.force_rmse, "steady_state_error": self.steady_state_error, "overshoot": self.overshoot,
            "rise_time_s": self.rise_time_s, "q_rmse_deg": self.q_rmse_deg, "joints": list(self.joint_names),
            "duration_s": sc.duration, "dt_s": sc.dt, "seed": sc.seed, "tau_max_Nm": self.tau_max,
            "saturated_fraction": self.saturated, "realtime_ratio": self.realtime_ratio,
        } | ({} if self.block is None else {
            "frame": self.block.frame, "motor": self.block.motor, "contact_q": self.block.contact_q.tolist(),
            "normal": self.block.normal.tolist(), "lever_m": self.block.lever})

    def to_csv(self, path: str) -> None:
        """Write t, F_ref, F_z measured by MuJoCo's sensor, the FlexiForce reading, the force fed back, true
        and estimated q, motor torque command and measurement, one row per sample.

        Parameters
        ----------
        path : str
            The CSV file."""
        n = len(self.joint_names)
        head = (["t_s", "F_ref_N", "F_mujoco_N", "F_flexiforce_N", "F_feedback_N"]
                + [f"q_true_{j}_rad" for j in self.joint_names] + [f"q_hat_{j}_rad" for j in self.joint_names]
                + ["tau_cmd_Nm", "tau_meas_Nm"])
        rows = np.column_stack([self.t, self.F_ref, self.F_true, self.F_meas, self.F_hat, self.q_true[:, :n],
                                self.q_hat[:, :n], self.tau_cmd, self.tau_meas])
        with atomic_path(path, "--log") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            w.writerows([[f"{x:.9g}" for x in r] for r in rows])


def _metrics(res: ControlResult) -> None:
    sc = res.scenario
    t, F, R = res.t, res.F_true, res.F_ref
    k0 = t >= sc.settle
    res.force_rmse = float(np.sqrt(np.mean((F[k0] - R[k0]) ** 2)))
    res.saturated = float(np.mean((res.tau_cmd <= 0.0) | (res.tau_cmd >= res.tau_max)))
    contact = F > 0.05
    if sc.controller != "pi" and contact.any():
        err = np.degrees(res.q_hat[contact] - res.q_true[contact])
        res.q_rmse_deg = np.sqrt(np.mean(err**2, axis=0)).tolist()
    if sc.reference == "sine":
        return
    a, b, c = sc.levels
    t1, t2 = sc.step_times
    T = sc.duration
    segs = [(sc.settle, t1, a), (t1, t2, b), (t2, T, c)] if sc.reference == "step" else [(sc.settle, t1, a),
                                                                                           (t1 + 1.0, T, b)]
    segs = [(lo, min(hi, T), v) for lo, hi, v in segs if min(hi, T) - lo > 0.25]
    sse = []
    for lo, hi, v in segs:
        win = (t >= hi - 0.2) & (t < hi)
        sse.append(abs(float(np.mean(F[win])) - v) / v)
    res.steady_state_error = max(sse) if sse else None
    if sc.reference != "step" or T - t1 < 0.25:
        return
    over = []
    for lo, hi, prev, new in ((t1, min(t2, T), a, b), (t2, T, b, c)):
        k = (t >= lo) & (t < hi)
        if hi - lo < 0.25:
            continue
        seg = F[k]
        ex = float(seg.max()) - new if new > prev else new - float(seg.min())
        over.append(max(0.0, ex) / abs(new - prev))
    res.overshoot = max(over) if over else None  # both steps' segments under 0.25 s: nothing to measure
    k = (t >= t1) & (t < min(t2, T))
    F_up, t_up = F[k], t[k]
    lo, hi = a + 0.1 * (b - a), a + 0.9 * (b - a)
    if (F_up >= hi).any():
        res.rise_time_s = float(t_up[np.argmax(F_up >= hi)] - t_up[np.argmax(F_up >= lo)])


def _plant_and_params(sc: Any) -> tuple[Any, HandParams, HandParams]:
    """MuJoCo (one line naming the extra if it is missing), the controller's and the plant's parameters
    (the plant's default: the controller's), both turned palm down. The controller's file marked not trustworthy:
    :class:`~alpes_dyn.ModelError` naming it, unless ``sc.force`` (:func:`~alpes_dyn.model.trust.check_trusted`)."""
    mujoco = _mujoco()
    p = sc.params if isinstance(sc.params, HandParams) else load_params(sc.params)
    check_trusted(p, bool(getattr(sc, "force", False)))
    pp = sc.plant_params if isinstance(sc.plant_params, HandParams) else (
        load_params(sc.plant_params) if sc.plant_params is not None else p)
    return mujoco, palm_down_params(p), palm_down_params(pp)


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise ModelError("the control loop's plant needs mujoco (pip install 'alpes_dyn[mujoco]')") from None
    return mujoco


@dataclass
class _Setup:
    """What the loop needs of its robot: the controller's side (:class:`~alpes_dyn.control.step.LoopDesign`),
    MuJoCo's model and data (at the plant's initial state), the MuJoCo names (actuator, encoders, torque sensors,
    touch sensor)."""

    design: LoopDesign
    mj: Any
    data: Any
    actuator: str
    encoders: str | list[str]
    torques: str | list[str]
    touch: str


def _compensation(sc: Any) -> Compensation:
    """What the controller does about the plant's effects: ``sc.compensation`` (default every one) with effects,
    the rigid design (:data:`~alpes_dyn.control.realism_loop.NO_COMPENSATION`) without."""
    if sc.effects is None:
        return NO_COMPENSATION
    return Compensation() if sc.compensation is None else sc.compensation


def _alpes_setup(sc: ControlScenario) -> _Setup:
    """finger2/finger3 on the Alpes block scene, palm down (the loop of version 0.2, unchanged)."""
    _, p, pp = _plant_and_params(sc)
    design = alpes_design(sc.model, p, sc.controller, sc.contact_q, _compensation(sc), sc.gains,
                          observer_friction=sc.observer_friction)
    # the plant starts at rest: the finger hanging on its springs (in the plant's gravity), motor off
    mj, d, _ = block_plant(sc.model, pp, sc.effects, design.contact_q, sc.dt / sc.substeps)
    return _Setup(design, mj, d, "finger", "encoder_finger", "torque_finger", "flexiforce_finger")


def robot_control_settings(sc: ControlScenario) -> tuple[Model, BlockScene, float, dict[str, float]]:
    """What a URDF + spec robot's loop sets before MuJoCo (class doc): (the controller's model -- the robot without
    its spec's friction --, the block of :func:`~alpes_dyn.model.block_scene.place_block`, the motor limit tau_max
    (N m), the controller's gains) of :func:`~alpes_dyn.control.step.robot_design`; the C export's controller is
    built from them too (:func:`~alpes_dyn.control.cexport.robot_controller`)."""
    d = _robot_design(sc)
    return d.model, d.block, d.tau_max, d.gains


def _robot_design(sc: ControlScenario) -> LoopDesign:
    return robot_design(sc.model, sc.controller, frame=sc.frame, motor=sc.motor, contact_q=sc.contact_q,
                        F_max=max(_DEFAULT_F_MAX, *sc.levels, *sc.sine[:2]), tau_max=sc.tau_max, gains=sc.gains)


def _robot_setup(sc: ControlScenario) -> _Setup:
    """Any URDF + spec model: the block placed from its kinematics, the MJCF export plus the block (class doc)."""
    mujoco = _mujoco()
    robot: Model = sc.model
    design = _robot_design(sc)
    block = design.block
    mj = load_mujoco(block_scene_mjcf(robot, block, timestep=sc.dt / sc.substeps, integrator="implicitfast"))
    d = mujoco.MjData(mj)
    d.qpos[joint_permutation(mj, robot.joint_names)] = block.rest_q  # at rest: the springs and gravity, motors off
    mujoco.mj_forward(mj, d)
    motors = design.model.transmission.motor_names
    encoders = [f"encoder_{m}" for m in motors] if len(motors) > 1 else f"encoder_{motors[0]}"
    torques = [f"torque_{m}" for m in motors] if len(motors) > 1 else f"torque_{motors[0]}"
    return _Setup(design, mj, d, motors[design.motor], encoders, torques, f"touch_{design.frame}")


def _effect_signals(sc: Any, model: Model, params: HandParams | None, suffix: str = "",
                    controller: bool = True) -> dict[str, Any]:
    """The signal names and blocks of the plant's effects and of their compensation (:mod:`.realism_loop`): the
    applied torque's signal, the encoder's offset (counts), the torque reading's signal and gain, the observer's
    torque input and measurement, extra blocks, extra :class:`.ForceController` settings. ``suffix``: appended to
    every signal and block name (a chain's of the hand, ``"_index"``: :func:`~.hand_loop.run_hand_control`).
    ``controller=False``: the plant's side only (a :class:`~alpes_dyn.control.step.ForceStep` compensates)."""
    e = sc.effects
    sig = {k: k + suffix for k in ("tau", "tau_motor", "tau_meas", "tau_meas_raw", "tau_prev", "y", "y_obs")}
    out: dict[str, Any] = {"applied": sig["tau"], "offset": 0.0, "reading": sig["tau_meas"], "gain": 1.0,
                           "torque": sig["tau_meas"], "measurement": sig["y"], "blocks": [], "controller": {},
                           "force_scale": 1.0}
    if e is None:
        return out
    comp = _compensation(sc)
    out["force_scale"] = comp.scale_of(suffix[1:] or None)
    out.update(applied=sig["tau_motor"], offset=float(e.encoder_offset), gain=1.0 + float(e.torque_constant_error))
    blocks = torque_constant_blocks(e, sig["tau"], sig["tau_motor"], name="motor" + suffix)
    if e.torque_delay:
        out["reading"] = sig["tau_meas_raw"]
        blocks.append(SampleLag(sig["tau_meas_raw"], sig["tau_meas"], e.torque_delay, name="torque_delay" + suffix))
    out["blocks"] = blocks
    if not controller:
        return out
    if comp.command_input:  # the command held over the period before: what the reading shows, without its lag
        out["torque"] = sig["tau_prev"]
        blocks.append(Delay(sig["tau"], sig["tau_prev"], 0.0, name="command_held" + suffix))
    if comp.observer_compliance:
        off = comp.offset_of(params, suffix[1:] or "finger", model.chain)
        torque, y, tr = out["torque"], sig["y"], model.transmission
        out["measurement"] = sig["y_obs"]
        blocks.append(Function(lambda **u: comp.unstretched(tr, u[y], u[torque], off), (y, torque), sig["y_obs"],
                               name="unstretched" + suffix))
    out["controller"].update(comp.notch_settings(model, params, sc.dt))
    return out


class _StepBlock(Block):
    """A :class:`~alpes_dyn.control.step.ForceStep` as a block: the reference, the encoder's counts, the torque
    reading (a period signal: the previous period's) and the fingertip sensor's reading in; the command ``tau``
    (the pulling motor's, N m), the EKF's estimate ``z`` = [q_hat; qd_hat] and the force fed back ``F_fb`` out."""

    name = "force_step"
    outputs = ("tau", "z", "F_fb")

    def __init__(self, step: ForceStep, counts: str, torque: str, force: str, reference: str = "F_ref") -> None:
        self.step = step
        self.inputs = (reference, counts, torque, force)

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.step.reset()

    def output(self, k: int, u: Any) -> dict[str, Any]:
        st = self.step
        ref, counts, torque, force = self.inputs
        tau = u[torque]  # a scalar before the first period's reading (the loop's initial value): every motor's
        u_cmd = st.step(u[counts], tau if np.ndim(tau) else np.full(st.m, tau), u[force], u[ref])
        return {"tau": float(u_cmd[st.motor]), "z": st.state, "F_fb": st.force_estimate}


def run_control(controller: str = "sensor", scenario: ControlScenario | None = None, **overrides: Any) -> ControlResult:
    """Run the closed loop: MuJoCo plant, the hand's sensors, the EKF and a force controller.

    Parameters
    ----------
    controller : str, optional
        One of :data:`.CONTROLLERS`.
    scenario : ControlScenario or None, optional
        The settings (default :class:`ControlScenario`).
    **overrides
        Fields of the scenario replaced, e.g. ``run_control("sensor", reference="sine", duration=4.0,
        plant_params="plant.toml")``, or on any robot ``run_control("sensor", model=Model.from_urdf_file(urdf,
        spec), frame="fingertip")``.

    Returns
    -------
    ControlResult
        The traces and the metrics.

    Raises
    ------
    InputError: bad settings (a frame, a motor or a block that cannot be placed: one line naming it).
    ModelError: MuJoCo missing (one line naming the ``[mujoco]`` extra), an unreadable parameter file, or the
        controller's file marked not trustworthy (its reason; ``force=True`` runs it).
    """
    sc = dataclasses.replace(scenario or ControlScenario(), controller=controller, **overrides)
    sc.check()
    s = _robot_setup(sc) if sc.robot else _alpes_setup(sc)
    design = s.design
    model = design.model
    m = len(model.transmission.motor_names)
    n = model.n
    tr = model.transmission
    rng = np.random.default_rng(sc.seed)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    F_ref = reference_profile(sc.reference, t, sc.levels, sc.sine, sc.step_times)
    shape = () if m == 1 else (m,)
    kind = sc.controller
    fx = _effect_signals(sc, model, design.params, controller=False)
    step = ForceStep.from_design(design, kind, sc.dt, _compensation(sc), compiled=sc.compiled,
                                 force_filter_s=sc.force_filter_s, label=f"ekf_force_{sc.model_name}",
                                 noise={k: getattr(sc, k) for k in ("torque_noise", "encoder_noise_counts",
                                                                    "force_noise", "force_resolution")})
    blocks = [Source("reference", F_ref=F_ref),
              MujocoPlant(s.mj, s.data, substeps=sc.substeps, joints={"q": model.joint_names},
                          actuators={fx["applied"]: s.actuator}, sensors={"q_m": s.encoders, "F_touch": s.touch},
                          period_sensors={"tau_applied": s.torques}),
              # the sensors' noise, drawn in this order (the encoder's one row more than read: the old draw)
              Encoder("q_m", "counts", tr.counts_per_rev, noise_counts=sc.encoder_noise_counts, rng=rng, draws=N + 1,
                      shape=shape, offset=fx["offset"], counts=True),
              TorqueSensor("tau_applied", fx["reading"], noise=sc.torque_noise, rng=rng, timing="period", shape=shape,
                           gain=fx["gain"]),
              ForceSensor("F_touch", "F_meas", noise=sc.force_noise, resolution=sc.force_resolution, rng=rng),
              # the observer, the compensation, the sensorless estimate and the controller: the user's ForceStep
              _StepBlock(step, "counts", "tau_meas", "F_meas"),
              *fx["blocks"]]
    log = run_loop(blocks, N, sc.dt)
    q_hat = log["z"][:, :n] if kind != "pi" else np.full((N, n), np.nan)
    tau_meas = log["tau_meas"] if m == 1 else log["tau_meas"][:, design.motor]
    res = ControlResult(scenario=sc, t=t, F_ref=F_ref, F_true=log["F_touch"], F_meas=log["F_meas"],
                        F_hat=log["F_fb" if kind == "sensorless" else "F_meas"], q_true=log["q"], q_hat=q_hat,
                        tau_cmd=log["tau"], tau_meas=tau_meas, joint_names=model.joint_names,
                        tau_max=design.tau_max, wall_s=log.wall_s, block=design.block)
    _metrics(res)
    return res
