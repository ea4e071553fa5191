"""The closed loops of the whole hand grasping a cylinder, one per flexion motor, MuJoCo as the plant.

:func:`run_hand_control` runs the same loops on the whole hand grasping the cylinder of the MJCF's
``"cylinder"`` scene: one controller, one EKF and one set of sensors per flexion motor (the four fingers
and the thumb, :func:`chain_model`), the contact normal the cylinder's at the estimated fingertip
(:func:`cylinder_normal`), the thumb's ab/adduction held by a PD on its encoder
(:class:`HandControlScenario`, :class:`HandControlResult`). Like the finger's, a composition of blocks run by
:func:`~alpes_dyn.simulation.loop.run_loop`, the EKFs of the four fingers in one
:class:`~alpes_dyn.estimation.observers.blocks.ObserverBank` (one compiled call per sample).

"""

from __future__ import annotations

import csv
import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ..fileio import atomic_path
from ..limits import check_bytes, check_duration
from ..model.hand_chains import _rotation, chain_frame, chain_model, hand_chains  # noqa: F401 (their home: model)
from ..model.mjcf import CYLINDER, joint_permutation, load_mujoco, mjcf_string
from ..model.robot import Model
from ..estimation.observers.blocks import Observer, ObserverBank
from ..model.params import HandParams
from ..estimation.observers.scenario import static_equilibrium
from ..simulation.loop import Delay, Function, Source, run_loop
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, ForceSensor, TorqueSensor
from .blocks import EncoderPD, ForceLoop, SensorlessForce, force_input
from .controller import CONTROLLERS, DEFAULT_GAINS, ForceController, _normal
from .finger_loop import (_SAMPLE_ARRAYS, ControlResult, ControlScenario, _check_effects, _effect_signals, _metrics,
                          _plant_and_params)
from .realism_loop import Compensation, effects_mjcf_kwargs, plant_gravity, rotor_rest
from .step import force_ekf


#: Default references of :func:`run_hand_control` per chain, N: (before, after) the step at ``step_time``.
#: Within what each fingertip holds on the :data:`~alpes_dyn.model.mjcf.CYLINDER` (the five motor torques ramped from 0
#: to 0.05 N m over 4 s, palm down: the fingers' pads slide around the cylinder beyond 0.47-0.65 N, the thumb's
#: beyond 1.48 N).
HAND_LEVELS: dict[str, tuple[float, float]] = {
    "index": (0.25, 0.4), "middle": (0.2, 0.35), "ring": (0.3, 0.4), "little": (0.25, 0.35), "thumb": (0.4, 0.7),
}
#: :class:`.ForceController` settings of the hand's loops over :data:`.DEFAULT_GAINS` (then the scenario's
#: ``gains``): a slower approach (15 mN m/s; at 30 mN m/s the fingertips reach the cylinder faster and bounce on
#: it for 0.3 s) and, for the model-based loops, a 40 ms prefilter, the shortest of {25, 30, 40, 50} ms with the
#: fingers' overshoots near 10 % on :data:`HAND_LEVELS` (one noise draw): with 25 ms (the block's) the middle
#: finger's pad slips on the curved surface at the up-step and its force falls to 0 (overshoot 175 %), with 30 ms 18 %; with
#: 40 ms 7-10.5 %, 10-90 % rise 77-97 ms.
HAND_GAINS: dict[str, float] = {"approach_rate": 0.015, "prefilter_s": 0.04}


def cylinder_normal(model: Model, q: np.ndarray, center: Sequence[float], axis: Sequence[float] = (0.0, 1.0, 0.0),
                    tip: str | None = None) -> np.ndarray:
    """Unit normal n (3,) of a cylinder's surface at the fingertip, the model's base frame: from the tip frame
    (the centre of the fingertip's rounded end) toward the cylinder's axis, the direction the fingertip
    presses in.

    Parameters
    ----------
    model : Model
        The chain's model.
    q : ndarray
        (n,) joint angles, rad.
    center, axis : sequence of float
        A point of the cylinder's axis, m, and its direction (base frame).
    tip : str or None, optional
        The fingertip's frame (default: the model's first tip)."""
    a = _normal(axis)
    d = np.asarray(center, dtype=float) - model.fingertip_position(q, tip)
    d = d - a * (d @ a)
    nd = float(np.linalg.norm(d))
    if not nd > 0:
        raise InputError("q: the fingertip is on the cylinder's axis; the normal is undefined")
    return d / nd


def cylinder_in_chain(params: HandParams, chain: str, abduction: float) -> tuple[np.ndarray, np.ndarray]:
    """(a point of the cylinder's axis (3,) m, its direction (3,)) of :data:`~alpes_dyn.model.mjcf.CYLINDER` in a
    chain's base frame (:func:`~alpes_dyn.model.hand_chains.chain_frame`; the thumb at ``abduction`` rad).

    Parameters
    ----------
    params : HandParams
        The hand's parameters (palm down).
    chain : str
        A chain of :func:`~alpes_dyn.model.hand_chains.hand_chains`.
    abduction : float
        The thumb's ab/adduction angle, rad.

    Returns
    -------
    tuple of numpy.ndarray
        The point and the direction.
    """
    R, pos = chain_frame(params, chain, abduction)
    return R.T @ (np.asarray(CYLINDER["center"], dtype=float) - pos), R.T @ np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class HandControlScenario:
    """Settings of :func:`run_hand_control` (SI units): the hand grasping the cylinder, one force loop per motor.

    The plant: MuJoCo stepping the hand's MJCF with the ``"cylinder"`` scene (:data:`~alpes_dyn.model.mjcf.CYLINDER`,
    fixed and frictionless), contact and joint stops on, joint friction on, palm down (the fingers flex with
    gravity toward the cylinder under the palm), at ``dt / substeps``; its parameters ``plant_params``
    (default: the controller's). Each chain (:func:`hand_chains`) has its own loop of :class:`.ForceController`
    (``controller``, :data:`.DEFAULT_GAINS` overridden by :data:`HAND_GAINS`, then by ``gains``), its own EKF on its own encoder (the
    model of :func:`chain_model`) and its own FlexiForce, with the sensors of :class:`.ControlScenario`
    (``encoder_noise_counts``, ``torque_noise``, ``force_noise``, ``force_resolution``), at 1 kHz; the
    contact normal of the feedforward and of the EKF's force input is the cylinder's at the estimated
    fingertip (:func:`cylinder_normal`).

    The thumb's ab/adduction starts at 0 (beside the palm); a PD on its encoder (``abduction_kp`` N m/rad,
    ``abduction_kd`` N m s/rad on the encoder's difference low-passed over ``abduction_filter_s`` s) brings it to
    ``thumb_abduction`` rad, where the thumb's pad faces the cylinder.

    References: ``levels[chain]`` = (before, after) the step at ``step_time`` s (default :data:`HAND_LEVELS`),
    the step a ramp over ``ramp_s`` s where ``ramp_s`` > 0 (the probe of
    :func:`~alpes_dyn.control.grasp_calibration.grasp_limits`; the metrics are the step's, measured from
    ``step_time``); metrics (per chain, as :class:`.ControlResult`) after ``settle`` s.

    ``effects``, ``compensation``: a real hand's effects on the plant and what the loops do about them, as
    :class:`.ControlScenario`'s (:mod:`alpes_dyn.control.realism_loop`), on the five flexion chains (the thumb's
    ab/adduction gear and its PD stay as they are; the slack and the cable are the flexion tendons').
    """

    controller: str = "sensor"
    duration: float = 3.5
    step_time: float = 2.5
    settle: float = 1.7
    ramp_s: float = 0.0
    levels: Any = field(default=None, compare=False)
    dt: float = 1e-3
    substeps: int = 4
    seed: int = 0
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    force_noise: float = 0.005
    force_resolution: float = 4.4 / 1024
    force_filter_s: float = 0.01
    thumb_abduction: float = math.radians(35.0)
    abduction_kp: float = 0.5
    abduction_kd: float = 0.01
    abduction_filter_s: float = 0.01
    compiled: bool = True
    gains: dict = field(default_factory=dict, compare=False)
    params: Any = field(default=None, compare=False)
    plant_params: Any = field(default=None, compare=False)
    effects: Any = field(default=None, compare=False)  # a PlantEffects (realism_loop), on every flexion chain
    compensation: Any = field(default=None, compare=False)  # a Compensation (default: all on with effects)
    force: bool = False  # a controller's file marked not trustworthy used anyway (model.trust.check_trusted)

    def check(self, chains: Sequence[str] | None = None) -> None:
        """The settings checked (:class:`~alpes_dyn.InputError` naming the first bad one).

        Parameters
        ----------
        chains : sequence of str or None, optional
            The hand's chains (:func:`hand_chains`), for the per-chain settings.
        """
        _check_effects(self.effects, self.compensation, False)
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.controller!r} "
                             f"(expected one of {', '.join(CONTROLLERS)})")
        for name in ("duration", "step_time", "settle", "ramp_s", "dt", "thumb_abduction", "abduction_kp",
                     "abduction_kd", "abduction_filter_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"{name}: expected a finite number, got {v!r}")
        for name in ("ramp_s", "abduction_kp", "abduction_kd", "abduction_filter_s"):
            if getattr(self, name) < 0:
                raise InputError(f"{name}: expected a number >= 0, got {getattr(self, name)!r}")
        if self.dt <= 0 or self.duration <= 0:
            raise InputError(f"{'dt' if self.dt <= 0 else 'duration'}: expected a positive number of seconds")
        check_duration(self.duration, "duration")
        check_bytes(8.0 * self.duration / self.dt * _SAMPLE_ARRAYS * 5, "duration",
                    f"{self.duration:g} s at dt = {self.dt:g} s")
        if not (0.0 <= self.settle and self.settle + 0.25 <= self.step_time and self.step_time + 0.25 <= self.duration):
            raise InputError(f"step_time: expected settle + 0.25 s <= step_time <= duration - 0.25 s (the metrics' "
                             f"windows), got settle {self.settle:g}, step_time {self.step_time:g}, duration "
                             f"{self.duration:g}")
        if self.step_time + self.ramp_s > self.duration:
            raise InputError(f"ramp_s: the ramp ends after the run (step_time {self.step_time:g} + ramp_s "
                             f"{self.ramp_s:g} > duration {self.duration:g} s)")
        if not isinstance(self.substeps, int) or isinstance(self.substeps, bool) or self.substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {self.substeps!r}")
        if chains is not None:
            lv = HAND_LEVELS if self.levels is None else self.levels
            if not isinstance(lv, dict):
                raise InputError(f"levels: expected a dict chain -> (before, after) in N, got {type(lv).__name__}")
            unknown = sorted(set(lv) - set(chains))
            if unknown:
                raise InputError(f"levels: unknown chain {unknown[0]!r} (expected {', '.join(chains)})")
            for c in chains:
                if c not in lv:
                    raise InputError(f"levels: no reference for chain {c!r}")
                v = np.asarray(lv[c], dtype=float) if np.ndim(lv[c]) == 1 else np.array([np.nan])
                if v.shape != (2,) or not np.isfinite(v).all() or (v <= 0).any():
                    raise InputError(f"levels: {c!r} expects two positive forces (before, after) in N, got {lv[c]!r}")


@dataclass
class HandControlResult:
    """One run of :func:`run_hand_control`.

    Attributes
    ----------
    t: (N,) times, s.
    chains: chain name -> the :class:`.ControlResult` of its loop, traces and metrics. Its ``scenario`` is a
        :class:`.ControlScenario` with the chain's levels (a, b, b), step times (step_time, duration) and
        ``model`` ``"finger3"`` for a finger, ``"finger2"`` for the thumb's chain model.
    q_abduction: (N,) the thumb's ab/adduction angle, rad.
    wall_s: wall time of the loop, s.
    """

    scenario: HandControlScenario
    t: np.ndarray
    chains: dict[str, ControlResult]
    q_abduction: np.ndarray
    wall_s: float

    @property
    def realtime_ratio(self) -> float:
        """Simulated time / wall time of the loop (> 1: faster than real time)."""
        return float(self.scenario.duration / self.wall_s)

    def table(self) -> list[dict[str, Any]]:
        """One row per chain: ``chain``, ``F_ref`` (the last level, N), ``F_held`` (mean MuJoCo force over the
        last 200 ms, N), ``steady_state_error``, ``overshoot`` (fractions), ``rise_time_s``, ``force_rmse`` (N),
        ``q_rmse_deg`` (the observer's worst joint during contact, deg; None for ``pi``), ``saturated``."""
        rows = []
        for c, r in self.chains.items():
            late = r.t >= r.t[-1] - 0.2 + 0.5 * (r.t[1] - r.t[0])
            rows.append({"chain": c, "F_ref": float(r.F_ref[-1]), "F_held": float(np.mean(r.F_true[late])),
                         "steady_state_error": r.steady_state_error, "overshoot": r.overshoot,
                         "rise_time_s": r.rise_time_s, "force_rmse": r.force_rmse,
                         "q_rmse_deg": None if r.q_rmse_deg is None else max(r.q_rmse_deg), "saturated": r.saturated})
        return rows

    def to_csv(self, path: str) -> None:
        """Write one row per sample: t, then per chain F_ref, F_z measured by MuJoCo's sensor, the FlexiForce
        reading, the force fed back, true and estimated q, motor torque command and measurement (columns
        prefixed by the chain's name), then the thumb's ab/adduction angle.

    Parameters
    ----------
    path : str
        The CSV file."""
        head, cols = ["t_s"], [self.t]
        for c, r in self.chains.items():
            head += [f"{c}_F_ref_N", f"{c}_F_mujoco_N", f"{c}_F_flexiforce_N", f"{c}_F_feedback_N"]
            head += [f"q_true_{j}_rad" for j in r.joint_names] + [f"q_hat_{j}_rad" for j in r.joint_names]
            head += [f"{c}_tau_cmd_Nm", f"{c}_tau_meas_Nm"]
            cols += [r.F_ref, r.F_true, r.F_meas, r.F_hat, r.q_true, r.q_hat, r.tau_cmd, r.tau_meas]
        head.append("q_thumb_abd_rad")
        cols.append(self.q_abduction)
        rows = np.column_stack(cols)
        with atomic_path(path, "--log") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            w.writerows([[f"{x:.9g}" for x in r] for r in rows])

    def to_dict(self) -> dict[str, Any]:
        """A JSON summary: the controller, the plant, per-chain metrics (:meth:`table`), the wall time."""
        sc = self.scenario
        return {"controller": sc.controller, "plant": "mujoco", "model": "hand", "scene": "cylinder",
                "duration_s": sc.duration, "dt_s": sc.dt, "seed": sc.seed, "chains": self.table(),
                "thumb_abduction_rad": sc.thumb_abduction, "realtime_ratio": self.realtime_ratio}


def _chain(p: HandParams, pp: HandParams, mj: Any, d: Any, c: str, sc: HandControlScenario,
           levels: Sequence[float], t: np.ndarray) -> dict[str, Any]:
    """One chain of the hand: the controller's model, its joints' MuJoCo names, the cylinder in its frame (m), its
    reference (N, one per sample) and its rest q0 (rad: the plant's, set in ``d.qpos``)."""
    e = sc.effects
    comp = Compensation() if sc.compensation is None else sc.compensation
    p_ctl = p if e is None else dataclasses.replace(p, gravity=comp.turned_gravity(p.gravity))
    m = chain_model(p_ctl, c, sc.thumb_abduction)
    names = [f"{c}_{j}" for j in m.joint_names]
    plant = chain_model(dataclasses.replace(pp, gravity=plant_gravity(pp.gravity, e)), c, sc.thumb_abduction)
    q0 = static_equilibrium(plant, np.zeros(m.n))
    d.qpos[joint_permutation(mj, names)] = q0
    rotor_rest(mj, d, [c], plant, q0, e)
    a, b = (float(x) for x in levels)
    center, axis = cylinder_in_chain(p, c, sc.thumb_abduction)
    ramp = np.clip((t - sc.step_time) / sc.ramp_s, 0.0, 1.0) if sc.ramp_s > 0 else (t >= sc.step_time).astype(float)
    return dict(name=c, model=m, n=m.n, names=tuple(names), center=center, axis=axis, F_ref=a + (b - a) * ramp,
                levels=(a, b), z0=q0)


def _chain_effects(ch: dict[str, Any], sc: HandControlScenario, p: HandParams) -> dict[str, Any]:
    """One chain's signals and blocks of the plant's effects and their compensation: the finger's
    (:func:`~alpes_dyn.control.finger_loop._effect_signals`), every name suffixed with the chain's."""
    return _effect_signals(sc, ch["model"], p, suffix=f"_{ch['name']}")


def _chain_loop(ch: dict[str, Any], sc: HandControlScenario, tau_max: float, gains: dict) -> list:
    """The blocks of one chain's loop: the cylinder's normal at the estimated fingertip, the sensorless force,
    the force controller and the EKF's force input (the previous sample's -F n)."""
    c, m, kind = ch["name"], ch["model"], sc.controller
    fx = ch["effects"]
    ctl = ForceController(kind, m, cylinder_normal(m, ch["z0"], ch["center"], ch["axis"]), sc.dt, tau_max, **gains,
                          **fx["controller"])
    if kind == "pi":
        return [ForceLoop(ctl, reference=f"F_ref_{c}", force=f"F_meas_{c}", command=f"tau_{c}", name=f"ctl_{c}"),
                *fx["blocks"]]
    F = f"F_fb_{c}" if kind == "sensorless" else f"F_meas_{c}"
    center, axis = ch["center"], ch["axis"]
    out = [Function(lambda **u: cylinder_normal(m, u[f"z_{c}"][: m.n], center, axis), (f"z_{c}",), f"normal_{c}",
                    name=f"normal_{c}"),
           ForceLoop(ctl, reference=f"F_ref_{c}", force=F, estimate=f"z_{c}", normal=f"normal_{c}",
                     command=f"tau_{c}", name=f"ctl_{c}"),
           force_input(F, f"w_F_{c}", f"normal_{c}", name=f"w_F_{c}"),
           Delay(f"w_F_{c}", f"w_F_prev_{c}", np.zeros(3), name=f"delay_{c}"), *fx["blocks"]]
    if kind == "sensorless":
        out.append(SensorlessForce(m, sc.dt / (sc.force_filter_s + sc.dt), estimate=f"z_{c}",
                                   torque=fx["torque"], normal=f"normal_{c}", force=F, name=f"sensorless_{c}",
                                   scale=fx["force_scale"]))
    return out


def _chain_ekf(ch: dict[str, Any], sc: HandControlScenario) -> Observer:
    """The EKF of one chain (known inputs its torque reading and the previous sample's force input, its encoder
    measured), started at the chain's rest with standard deviations 0.05 rad and 0.1 rad/s, not updated at t_0."""
    c, m = ch["name"], ch["model"]
    ekf, z0, P0 = force_ekf(m, sc.dt, sc.controller, torque_noise=sc.torque_noise, force_noise=sc.force_noise,
                            encoder_noise_counts=sc.encoder_noise_counts, force_resolution=sc.force_resolution)
    return Observer(ekf, z0, P0, known=(ch["effects"]["torque"], f"w_F_prev_{c}"),
                    measurement=ch["effects"]["measurement"], estimate=f"z_{c}", covariance=None, first_update=False,
                    label=f"ekf_force_hand_{m.name}", name=f"ekf_{c}")


def _chain_results(sc: HandControlScenario, C: list[dict[str, Any]], log: Any, t: np.ndarray,
                   tau_max: float) -> dict[str, ControlResult]:
    """Each chain's :class:`.ControlResult` (traces from the loop's log, metrics), by chain name."""
    N, kind, wall = t.shape[0], sc.controller, log.wall_s
    results = {}
    for ch in C:
        a, b = ch["levels"]
        csc = ControlScenario(model="finger2" if ch["n"] == 2 else "finger3", controller=sc.controller,
                              reference="step", duration=sc.duration, dt=sc.dt, substeps=sc.substeps, seed=sc.seed,
                              levels=(a, b, b), step_times=(sc.step_time, sc.duration), settle=sc.settle,
                              encoder_noise_counts=sc.encoder_noise_counts, torque_noise=sc.torque_noise,
                              force_noise=sc.force_noise, force_resolution=sc.force_resolution,
                              force_filter_s=sc.force_filter_s, compiled=sc.compiled, gains=sc.gains,
                              params=sc.params, plant_params=sc.plant_params)
        c = ch["name"]
        q_hat = log[f"z_{c}"][:, : ch["n"]] if kind != "pi" else np.full((N, ch["n"]), np.nan)
        r = ControlResult(scenario=csc, t=t, F_ref=ch["F_ref"], F_true=log[f"F_touch_{c}"], F_meas=log[f"F_meas_{c}"],
                          F_hat=log[f"F_fb_{c}" if kind == "sensorless" else f"F_meas_{c}"], q_true=log[f"q_{c}"],
                          q_hat=q_hat, tau_cmd=log[f"tau_{c}"], tau_meas=log[f"tau_meas_{c}"],
                          joint_names=ch["names"], tau_max=tau_max, wall_s=wall)
        _metrics(r)
        results[ch["name"]] = r
    return results


def run_hand_control(controller: str = "sensor", scenario: HandControlScenario | None = None,
                     **overrides: Any) -> HandControlResult:
    """The whole hand grasping the cylinder in MuJoCo: one force loop, one EKF per motor (issue 9, item 5).

    Each chain (the four fingers and the thumb's flexion) runs the loop of :func:`.run_control` on its own
    sensors -- encoder, motor torque, FlexiForce -- with its own :class:`.ForceController` and, for the
    model-based controllers, its own EKF on :func:`chain_model`; the contact normal is the cylinder's at the
    estimated fingertip (:func:`cylinder_normal`). The EKFs of chains with the same model (the four fingers)
    advance in one call of compiled code. See :class:`HandControlScenario` for the settings.

    Parameters
    ----------
    controller : str, optional
        One of :data:`.CONTROLLERS`.
    scenario : HandControlScenario or None, optional
        The settings (default :class:`HandControlScenario`).
    **overrides
        Fields of the scenario replaced.

    Returns
    -------
    HandControlResult
        The traces and the metrics.

    Raises
    ------
    InputError: bad settings. ModelError: MuJoCo missing (one line naming the ``[mujoco]`` extra) or an
    unreadable parameter file.
    """
    sc = dataclasses.replace(scenario or HandControlScenario(), controller=controller, **overrides)
    sc.check()
    mujoco, p, pp = _plant_and_params(sc)
    chains = hand_chains(p)
    sc.check(chains)
    if not p.abduction_lower <= sc.thumb_abduction <= p.abduction_upper:
        raise InputError(f"thumb_abduction: {sc.thumb_abduction:g} rad is outside the ab/adduction range "
                         f"[{p.abduction_lower:g}, {p.abduction_upper:g}] rad")
    levels = HAND_LEVELS if sc.levels is None else sc.levels
    fxm = {} if sc.effects is None else effects_mjcf_kwargs(sc.effects)
    mj = load_mujoco(mjcf_string("hand", pp, friction=True, scene="cylinder", timestep=sc.dt / sc.substeps, **fxm))
    d = mujoco.MjData(mj)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    rng = np.random.default_rng(sc.seed)
    kind = sc.controller
    gains = {**DEFAULT_GAINS[kind], **HAND_GAINS, **sc.gains}
    C = [_chain(p, pp, mj, d, c, sc, levels[c], t) for c in chains]  # the plant starts at rest, each chain
    for ch in C:
        ch["effects"] = _chain_effects(ch, sc, p)
    d.qpos[mj.joint("thumb_abd").qposadr[0]] = 0.0
    mujoco.mj_forward(mj, d)
    names = [c["name"] for c in C]
    plant = MujocoPlant(mj, d, substeps=sc.substeps, actuators={**{C[i]["effects"]["applied"]: c for i, c in enumerate(names)},
                                                                "u_abd": "thumb_abduction"},
                        joints={**{f"q_{c}": C[i]["names"] for i, c in enumerate(names)}, "q_abd": ["thumb_abd"]},
                        sensors={**{f"q_m_{c}": f"encoder_{c}" for c in names}, "q_m_abd": "encoder_thumb_abduction",
                                 **{f"F_touch_{c}": f"flexiforce_{c}" for c in names}},
                        period_sensors={f"tau_applied_{c}": f"torque_{c}" for c in names})
    cpr = C[0]["model"].transmission.counts_per_rev
    # the sensors' noise, drawn in this order: the encoders (the chains', the ab/adduction's), torques, forces
    blocks = [Source("references", **{f"F_ref_{c['name']}": c["F_ref"] for c in C}), plant]
    blocks += [Encoder(f"q_m_{c}", f"y_{c}", cpr, noise_counts=sc.encoder_noise_counts, rng=rng,
                       offset=C[i]["effects"]["offset"] if i < len(C) else 0.0) for i, c in enumerate((*names, "abd"))]
    blocks += [TorqueSensor(f"tau_applied_{c}", C[i]["effects"]["reading"], noise=sc.torque_noise, rng=rng,
                            timing="period", gain=C[i]["effects"]["gain"]) for i, c in enumerate(names)]
    blocks += [ForceSensor(f"F_touch_{c}", f"F_meas_{c}", noise=sc.force_noise, resolution=sc.force_resolution,
                           rng=rng) for c in names]
    blocks.append(EncoderPD(sc.thumb_abduction, sc.abduction_kp, sc.abduction_kd, sc.dt / (sc.abduction_filter_s + sc.dt),
                            ratio=p.abduction_ratio, u_max=p.tau_max, reading="y_abd", command="u_abd"))
    for ch in C:
        blocks += _chain_loop(ch, sc, p.tau_max, gains)
    if kind != "pi":  # one EKF per chain, those of the same model advanced in one call
        blocks.append(ObserverBank([_chain_ekf(ch, sc) for ch in C], compiled=sc.compiled))
    log = run_loop(blocks, N, sc.dt)
    return HandControlResult(scenario=sc, t=t, chains=_chain_results(sc, C, log, t, p.tau_max),
                             q_abduction=log["q_abd"][:, 0], wall_s=log.wall_s)
