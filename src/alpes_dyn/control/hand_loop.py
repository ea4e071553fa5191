"""The closed loops of the whole hand grasping a cylinder, one per flexion motor, MuJoCo as the plant.

:func:`run_hand_control` runs the same loops on the whole hand grasping the cylinder of the MJCF's
``"cylinder"`` scene: one controller, one EKF and one set of sensors per flexion motor (the four fingers
and the thumb, :func:`chain_model`), the contact normal the cylinder's at the estimated fingertip
(:func:`cylinder_normal`), the thumb's ab/adduction held by a PD on its encoder
(:class:`HandControlScenario`, :class:`HandControlResult`).

"""

from __future__ import annotations

import csv
import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ..fileio import atomic_path
from ..limits import check_bytes, check_duration
from ..model.mjcf import joint_permutation, load_mujoco, mjcf_string
from ..model.robot import Model
from ..estimation.observers import make_observer
from ..model.params import HandParams
from ..estimation.scenario import default_noise, static_equilibrium, EstimationScenario
from ..symbolic.statespace import StateSpace
from .controller import CONTROLLERS, DEFAULT_GAINS, ForceController, _normal, static_contact_force
from .finger_loop import _SAMPLE_ARRAYS, ControlResult, ControlScenario, _batch_step_caller, _metrics, _plant_and_params


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
#: fingers' overshoots near 10 % on :data:`HAND_LEVELS` (seed 0): with 25 ms (the block's) the middle finger's pad
#: slips on the curved surface at the up-step and its force falls to 0 (overshoot 175 %), with 30 ms 18 %; with
#: 40 ms 7-10.5 %, 10-90 % rise 77-97 ms.
HAND_GAINS: dict[str, float] = {"approach_rate": 0.015, "prefilter_s": 0.04}


def _rotation(axis: Sequence[float], angle: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def hand_chains(params: HandParams) -> tuple[str, ...]:
    """The hand's flexion chains, one motor each: the fingers of the parameter file, then ``"thumb"``."""
    return (*params.finger_names, "thumb")


def chain_frame(params: HandParams, chain: str, abduction: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), p (3,)): orientation and position (m) of a chain's base frame -- its first flexion joint's
    frame at q = 0, the frame of a standalone finger model -- in the palm frame, the thumb at the
    ab/adduction angle ``abduction`` (rad). A finger's frame is the palm's, translated; the thumb's is
    turned by ``palm.thumb_yaw`` about z, then by ``abduction`` about ``thumb.abduction_axis``."""
    if chain in params.finger_names:
        x, y = params.finger_xy[list(params.finger_names).index(chain)]
        return np.eye(3), np.array([x, y, 0.0])
    if chain == "thumb":
        R = _rotation((0.0, 0.0, 1.0), params.thumb_yaw) @ _rotation(params.abduction_axis, float(abduction))
        return R, np.asarray(params.thumb_xyz, dtype=float).copy()
    raise InputError(f"chain: unknown chain {chain!r} (expected one of {', '.join(hand_chains(params))})")


def chain_model(params: HandParams, chain: str, abduction: float = 0.0) -> Model:
    """The controller's model of one chain of the hand: ``finger3`` for a finger; for the thumb's flexion
    chain (the ab/adduction held at ``abduction``, rad) a two-phalanx finger with the ``[thumb]`` table's
    values. Gravity is the parameter file's, expressed in the chain's base frame (R^T g,
    :func:`chain_frame`), so that the chain's G(q), J(q) and encoder are the hand's on its joints."""
    R, _ = chain_frame(params, chain, abduction)
    g = R.T @ np.asarray(params.gravity, dtype=float)
    if chain == "thumb":
        return Model.alpes("finger2", params=dataclasses.replace(params, finger=params.thumb, gravity=g))
    return Model.alpes("finger3", params=dataclasses.replace(params, gravity=g), chain=chain)  # the finger's own values


def cylinder_normal(model: Model, q: np.ndarray, center: Sequence[float], axis: Sequence[float] = (0.0, 1.0, 0.0),
                    tip: str | None = None) -> np.ndarray:
    """Unit normal n (3,) of a cylinder's surface at the fingertip, the model's base frame: from the tip frame
    (the centre of the fingertip's rounded end) toward the cylinder's axis, the direction the fingertip
    presses in. ``center``: a point of the axis, ``axis``: its direction (base frame, m)."""
    a = _normal(axis)
    d = np.asarray(center, dtype=float) - model.fingertip_position(q, tip)
    d = d - a * (d @ a)
    nd = float(np.linalg.norm(d))
    if not nd > 0:
        raise InputError("q: the fingertip is on the cylinder's axis; the normal is undefined")
    return d / nd


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

    References: ``levels[chain]`` = (before, after) the step at ``step_time`` s (default :data:`HAND_LEVELS`);
    metrics (per chain, as :class:`.ControlResult`) after ``settle`` s.
    """

    controller: str = "sensor"
    duration: float = 3.5
    step_time: float = 2.5
    settle: float = 1.7
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

    def check(self, chains: Sequence[str] | None = None) -> None:
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.controller!r} "
                             f"(expected one of {', '.join(CONTROLLERS)})")
        for name in ("duration", "step_time", "settle", "dt", "thumb_abduction", "abduction_kp", "abduction_kd",
                     "abduction_filter_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"{name}: expected a finite number, got {v!r}")
        for name in ("abduction_kp", "abduction_kd", "abduction_filter_s"):
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
        prefixed by the chain's name), then the thumb's ab/adduction angle."""
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


def run_hand_control(controller: str = "sensor", scenario: HandControlScenario | None = None,
                     **overrides: Any) -> HandControlResult:
    """The whole hand grasping the cylinder in MuJoCo: one force loop, one EKF per motor (issue 9, item 5).

    Each chain (the four fingers and the thumb's flexion) runs the loop of :func:`.run_control` on its own
    sensors -- encoder, motor torque, FlexiForce -- with its own :class:`.ForceController` and, for the
    model-based controllers, its own EKF on :func:`chain_model`; the contact normal is the cylinder's at the
    estimated fingertip (:func:`cylinder_normal`). The EKFs of chains with the same model (the four fingers)
    advance in one call of compiled code. See :class:`HandControlScenario` for the settings.

    Returns
    -------
    :class:`HandControlResult`.

    Raises
    ------
    InputError: bad settings. ModelError: MuJoCo missing (one line naming the ``[mujoco]`` extra) or an
    unreadable parameter file.
    """
    sc = dataclasses.replace(scenario or HandControlScenario(), controller=controller, **overrides)
    sc.check()
    mujoco, p, pp = _plant_and_params(sc)
    from ..model.mjcf import CYLINDER

    chains = hand_chains(p)
    sc.check(chains)
    if not p.abduction_lower <= sc.thumb_abduction <= p.abduction_upper:
        raise InputError(f"thumb_abduction: {sc.thumb_abduction:g} rad is outside the ab/adduction range "
                         f"[{p.abduction_lower:g}, {p.abduction_upper:g}] rad")
    levels = HAND_LEVELS if sc.levels is None else sc.levels
    mj = load_mujoco(mjcf_string("hand", pp, friction=True, scene="cylinder", timestep=sc.dt / sc.substeps))
    d = mujoco.MjData(mj)
    sd = d.sensordata
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    rng = np.random.default_rng(sc.seed)
    use_obs = sc.controller != "pi"
    gains = {**DEFAULT_GAINS[sc.controller], **HAND_GAINS, **sc.gains}
    center = np.asarray(CYLINDER["center"], dtype=float)

    # per chain: the controller's model, the plant's initial state, sensors, the cylinder in the chain's frame
    C = []
    for c in chains:
        m = chain_model(p, c, sc.thumb_abduction)
        R, pos = chain_frame(p, c, sc.thumb_abduction)
        names = [f"{c}_{j}" for j in m.joint_names]
        perm = joint_permutation(mj, names)
        q0 = static_equilibrium(chain_model(pp, c, sc.thumb_abduction), np.zeros(m.n))
        d.qpos[perm] = q0
        a, b = (float(x) for x in levels[c])
        C.append(dict(name=c, model=m, n=m.n, perm=perm, names=tuple(names), center=R.T @ (center - pos),
                      axis=R.T @ np.array([0.0, 1.0, 0.0]), F_ref=np.where(t < sc.step_time, a, b), levels=(a, b),
                      enc=mj.sensor(f"encoder_{c}").adr[0], frc=mj.sensor(f"torque_{c}").adr[0],
                      touch=mj.sensor(f"flexiforce_{c}").adr[0], act=mj.actuator(c).id, z0=q0))
    abd_q = mj.joint("thumb_abd").qposadr[0]
    abd_act = mj.actuator("thumb_abduction").id
    abd_enc = mj.sensor("encoder_thumb_abduction").adr[0]
    d.qpos[abd_q] = 0.0
    mujoco.mj_forward(mj, d)
    step = 2 * np.pi / C[0]["model"].transmission.counts_per_rev

    # observers: one EKF per chain, those of the same model advanced together
    groups: dict[str, list[int]] = {}
    callers = {}
    S: list[np.ndarray] = []
    if use_obs:
        est_sc = EstimationScenario(torque_noise=sc.torque_noise, encoder_noise_counts=sc.encoder_noise_counts)
        meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
        f_var = (sc.force_noise**2 + sc.force_resolution**2 / 12) if sc.controller == "sensor" else 0.05**2
        for i, ch in enumerate(C):
            n = ch["n"]
            ss = StateSpace(ch["model"], input="motor", output="encoder", force=True)
            noise = default_noise(est_sc, n, 1, 0, meas_var)
            noise["input_noise"] = [sc.torque_noise**2] + [f_var] * 3
            fstep = make_observer("ekf", ss, sc.dt, **noise).filter_step
            key = fstep.serialize()
            if key not in callers:
                callers[key] = _batch_step_caller(fstep, f"ekf_force_hand_{ch['model'].name}", sc.compiled)
            groups.setdefault(key, []).append(i)
            z0 = np.concatenate([static_equilibrium(ch["model"], np.zeros(n)), np.zeros(n)])
            P0 = np.diag([0.05**2] * n + [0.1**2] * n)
            S.append(np.concatenate([z0, P0.reshape(-1, order="F")]))
    ctls = [ForceController(sc.controller, ch["model"], cylinder_normal(ch["model"], ch["z0"], ch["center"], ch["axis"]),
                            sc.dt, p.tau_max, **gains) for ch in C]

    nc = len(C)
    out = {k: np.empty((nc, N)) for k in ("F_true", "F_meas", "F_hat", "tau", "tau_meas")}
    out_q = [np.empty((N, ch["n"])) for ch in C]
    out_qh = [np.full((N, ch["n"]), np.nan) for ch in C]
    q_abd = np.empty(N)
    enc_noise = sc.encoder_noise_counts * step * rng.standard_normal((nc + 1, N))
    trq_noise = sc.torque_noise * rng.standard_normal((nc, N))
    frc_noise = sc.force_noise * rng.standard_normal((nc, N))
    alpha = sc.dt / (sc.force_filter_s + sc.dt)
    a_v = sc.dt / (sc.abduction_filter_s + sc.dt)
    F_filt = np.zeros(nc)
    tau_meas_prev = np.zeros(nc)
    F_in_prev = np.zeros(nc)
    normals = [ctl.normal.copy() for ctl in ctls]
    y_abd_prev, v_abd = None, 0.0
    res = sc.force_resolution
    t_wall = time.perf_counter()
    for k in range(N):
        y = np.empty(nc)
        F_meas = np.empty(nc)
        for i, ch in enumerate(C):
            out_q[i][k] = d.qpos[ch["perm"]]
            F_true = float(sd[ch["touch"]])
            out["F_true"][i, k] = F_true
            F_meas[i] = max(0.0, round((F_true + frc_noise[i, k]) / res) * res)
            y[i] = round((float(sd[ch["enc"]]) + enc_noise[i, k]) / step) * step
        if use_obs and k > 0:
            for key, idx in groups.items():
                WY = np.stack([np.concatenate([[tau_meas_prev[i]], -F_in_prev[i] * normals[i], [y[i]]]) for i in idx])
                S_next = callers[key](np.stack([S[i] for i in idx]), WY)
                for j, i in enumerate(idx):
                    S[i] = S_next[j]
        for i, ch in enumerate(C):
            if use_obs:
                q_hat = S[i][: ch["n"]]
                out_qh[i][k] = q_hat
                normals[i] = cylinder_normal(ch["model"], q_hat, ch["center"], ch["axis"])
                if sc.controller == "sensorless":
                    F_est = static_contact_force(ch["model"], q_hat, np.array([tau_meas_prev[i]]), normals[i])
                    F_filt[i] += alpha * (max(F_est, 0.0) - F_filt[i])
                    F_fb = F_filt[i]
                else:
                    F_fb = F_meas[i]
                F_in_prev[i] = F_fb
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, q_hat, normal=normals[i])
            else:
                F_fb = F_meas[i]
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, None)
            d.ctrl[ch["act"]] = tau
            out["F_meas"][i, k], out["F_hat"][i, k], out["tau"][i, k] = F_meas[i], F_fb, tau
        # the thumb's ab/adduction: PD on its encoder
        y_abd = round((float(sd[abd_enc]) + enc_noise[nc, k]) / step) * step / p.abduction_ratio
        if y_abd_prev is not None:
            v_abd += a_v * ((y_abd - y_abd_prev) / sc.dt - v_abd)
        y_abd_prev = y_abd
        q_abd[k] = d.qpos[abd_q]
        u = sc.abduction_kp * (sc.thumb_abduction - y_abd) - sc.abduction_kd * v_abd
        d.ctrl[abd_act] = min(max(u, -p.tau_max), p.tau_max)
        for _ in range(sc.substeps):
            mujoco.mj_step(mj, d)
        for i, ch in enumerate(C):
            tau_meas_prev[i] = float(sd[ch["frc"]]) + trq_noise[i, k]
        out["tau_meas"][:, k] = tau_meas_prev
    wall = time.perf_counter() - t_wall

    results = {}
    for i, ch in enumerate(C):
        a, b = ch["levels"]
        csc = ControlScenario(model="finger2" if ch["n"] == 2 else "finger3", controller=sc.controller,
                              reference="step", duration=sc.duration, dt=sc.dt, substeps=sc.substeps, seed=sc.seed,
                              levels=(a, b, b), step_times=(sc.step_time, sc.duration), settle=sc.settle,
                              encoder_noise_counts=sc.encoder_noise_counts, torque_noise=sc.torque_noise,
                              force_noise=sc.force_noise, force_resolution=sc.force_resolution,
                              force_filter_s=sc.force_filter_s, compiled=sc.compiled, gains=sc.gains,
                              params=sc.params, plant_params=sc.plant_params)
        r = ControlResult(scenario=csc, t=t, F_ref=ch["F_ref"], F_true=out["F_true"][i], F_meas=out["F_meas"][i],
                          F_hat=out["F_hat"][i], q_true=out_q[i], q_hat=out_qh[i], tau_cmd=out["tau"][i],
                          tau_meas=out["tau_meas"][i], joint_names=ch["names"], tau_max=p.tau_max, wall_s=wall)
        _metrics(r)
        results[ch["name"]] = r
    return HandControlResult(scenario=sc, t=t, chains=results, q_abduction=q_abd, wall_s=wall)
