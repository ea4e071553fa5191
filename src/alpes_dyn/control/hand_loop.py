"""The closed loops of the whole hand grasping a cylinder, one per flexion motor, MuJoCo as the plant.

:func:`run_hand_control` runs the same loops on the whole hand grasping the cylinder of the MJCF's
``"cylinder"`` scene: one controller, one EKF and one set of sensors per flexion motor (the four fingers
and the thumb, :func:`chain_model`), the contact normal the cylinder's at the estimated fingertip
(:func:`cylinder_normal`), the thumb's ab/adduction held by a PD on its encoder
(:class:`HandControlScenario`, :class:`HandControlResult`). Like the finger's, a composition of blocks run by
:func:`~alpes_dyn.simulation.loop.run_loop`: the plant, its sensors and effects, and the user's step,
:class:`~alpes_dyn.control.hand_step.HandForceStep` (every chain's EKF, compensation and controller, the
ab/adduction's PD), the one step object of the simulation and of the bench.

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
from ..model.mjcf import joint_permutation, load_mujoco, mjcf_string
from ..model.params import HandParams
from ..estimation.observers.scenario import static_equilibrium
from ..simulation.loop import Block, Source, run_loop
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, ForceSensor, TorqueSensor
from .controller import CONTROLLERS
from .finger_loop import (_SAMPLE_ARRAYS, ControlResult, ControlScenario, _check_effects, _compensation,
                          _effect_signals, _metrics, _plant_and_params)
from .hand_grasp import HAND_GAINS, HAND_LEVELS, cylinder_in_chain, cylinder_normal  # noqa: F401 (re-exported)
from .hand_step import HandForceStep
from .realism_loop import Compensation, effects_mjcf_kwargs, plant_gravity, rotor_rest


@dataclass(frozen=True)
class HandControlScenario:
    """Settings of :func:`run_hand_control` (SI units): the hand grasping the cylinder, one force loop per motor.

    The plant: MuJoCo stepping the hand's MJCF with the ``"cylinder"`` scene (:data:`~alpes_dyn.model.mjcf.CYLINDER`,
    fixed and frictionless), contact and joint stops on, joint friction on, palm down (the fingers flex with
    gravity toward the cylinder under the palm), at ``dt / substeps``; its parameters ``plant_params``
    (default: the controller's). Each chain (:func:`hand_chains`) has its own loop of :class:`.ForceController`
    (``controller``, :func:`~alpes_dyn.control.hand_grasp.hand_gains`, then ``gains``), its own EKF on its own encoder (the
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
    """One chain of the hand: the controller's model, its joints' MuJoCo names, its reference (N, one per sample),
    its rest q0 (rad: the plant's, set in ``d.qpos``) and the plant's side of the effects
    (:func:`~alpes_dyn.control.finger_loop._effect_signals`, every name suffixed with the chain's)."""
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
    ramp = np.clip((t - sc.step_time) / sc.ramp_s, 0.0, 1.0) if sc.ramp_s > 0 else (t >= sc.step_time).astype(float)
    return dict(name=c, model=m, n=m.n, names=tuple(names), F_ref=a + (b - a) * ramp, levels=(a, b), z0=q0,
                effects=_effect_signals(sc, m, p, suffix=f"_{c}", controller=False))


class _HandStepBlock(Block):
    """A :class:`~alpes_dyn.control.hand_step.HandForceStep` as a block: each chain's reference, encoder counts,
    torque reading (a period signal: the previous period's) and fingertip force, and the ab/adduction's counts in;
    each chain's command ``tau_<c>``, estimate ``z_<c>`` and force fed back ``F_fb_<c>``, and the ab/adduction's
    command ``u_abd`` out."""

    name = "hand_step"

    def __init__(self, step: HandForceStep, torque: Sequence[str]) -> None:
        self.step, cs = step, step.chains
        self.refs, self.counts = [f"F_ref_{c}" for c in cs], [f"y_{c}" for c in (*cs, "abd")]
        self.torque, self.forces = list(torque), [f"F_meas_{c}" for c in cs]
        self.inputs = (*self.refs, *self.counts, *self.torque, *self.forces)
        self.outputs = (*(f"{k}_{c}" for k in ("tau", "z", "F_fb") for c in cs), "u_abd")

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.step.reset()

    def output(self, k: int, u: Any) -> dict[str, Any]:
        st = self.step
        vec = lambda names: np.array([float(np.asarray(u[x]).reshape(-1)[0]) for x in names])  # noqa: E731
        torque = np.append(vec(self.torque), 0.0)  # the ab/adduction's is not read
        force = None if st.kind == "sensorless" else vec(self.forces)
        cmd = st.step(vec(self.counts), torque, force, vec(self.refs))
        out: dict[str, Any] = {"u_abd": float(cmd[-1])}
        for i, (c, s) in enumerate(st.chain_steps.items()):
            out[f"tau_{c}"], out[f"z_{c}"], out[f"F_fb_{c}"] = float(cmd[i]), s.state, s.force_estimate
        return out


def _hand_step(sc: HandControlScenario) -> HandForceStep:
    """The scenario's :class:`~alpes_dyn.control.hand_step.HandForceStep`: its settings, its EKFs without the
    file's friction (the hand loop's own design), the ab/adduction's target at once (no ramp)."""
    return HandForceStep(sc.params, sc.controller, dt=sc.dt, thumb_abduction=sc.thumb_abduction,
                         abduction_kp=sc.abduction_kp, abduction_kd=sc.abduction_kd,
                         abduction_filter_s=sc.abduction_filter_s, abduction_ramp_s=0.0, gains=sc.gains,
                         compensation=_compensation(sc), compiled=sc.compiled, torque_noise=sc.torque_noise,
                         encoder_noise_counts=sc.encoder_noise_counts, force_noise=sc.force_noise,
                         force_resolution=sc.force_resolution, force_filter_s=sc.force_filter_s,
                         observer_friction=False, force=sc.force)


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
    step = _hand_step(sc)  # the user's step: every chain's EKF, compensation and controller, the ab/adduction's PD
    C = [_chain(p, pp, mj, d, c, sc, levels[c], t) for c in chains]  # the plant starts at rest, each chain
    d.qpos[mj.joint("thumb_abd").qposadr[0]] = 0.0
    mujoco.mj_forward(mj, d)
    names = [c["name"] for c in C]
    fx = [c["effects"] for c in C]
    plant = MujocoPlant(mj, d, substeps=sc.substeps, actuators={**{fx[i]["applied"]: c for i, c in enumerate(names)},
                                                                "u_abd": "thumb_abduction"},
                        joints={**{f"q_{c}": C[i]["names"] for i, c in enumerate(names)}, "q_abd": ["thumb_abd"]},
                        sensors={**{f"q_m_{c}": f"encoder_{c}" for c in names}, "q_m_abd": "encoder_thumb_abduction",
                                 **{f"F_touch_{c}": f"flexiforce_{c}" for c in names}},
                        period_sensors={f"tau_applied_{c}": f"torque_{c}" for c in names})
    cpr = C[0]["model"].transmission.counts_per_rev
    # the sensors' noise, drawn in this order: the encoders (the chains', the ab/adduction's), torques, forces
    blocks = [Source("references", **{f"F_ref_{c['name']}": c["F_ref"] for c in C}), plant]
    blocks += [Encoder(f"q_m_{c}", f"y_{c}", cpr, noise_counts=sc.encoder_noise_counts, rng=rng, counts=True,
                       offset=fx[i]["offset"] if i < len(C) else 0.0) for i, c in enumerate((*names, "abd"))]
    blocks += [TorqueSensor(f"tau_applied_{c}", fx[i]["reading"], noise=sc.torque_noise, rng=rng,
                            timing="period", gain=fx[i]["gain"]) for i, c in enumerate(names)]
    blocks += [ForceSensor(f"F_touch_{c}", f"F_meas_{c}", noise=sc.force_noise, resolution=sc.force_resolution,
                           rng=rng) for c in names]
    blocks.append(_HandStepBlock(step, [f["torque"] for f in fx]))
    for f in fx:
        blocks += f["blocks"]
    log = run_loop(blocks, N, sc.dt)
    return HandControlResult(scenario=sc, t=t, chains=_chain_results(sc, C, log, t, p.tau_max),
                             q_abduction=log["q_abd"][:, 0], wall_s=log.wall_s)
