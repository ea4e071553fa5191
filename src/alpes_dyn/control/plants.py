"""Plants we did not write: a finger exported to MuJoCo with the effects of a real hand, and its recording.

The library's identification and observers are exact on data from its own simulator, whose model structure
is the fitted one. :func:`mujoco_recording` makes the data a user gets from a real hand instead: the
finger exported by :func:`~alpes_dyn.model.mjcf.mjcf_string` and stepped by MuJoCo (an independent engine;
joint stops on, RK4 at 0.1 ms by default), a motor torque replayed on it (e.g. the identification
experiment's, :func:`~alpes_dyn.estimation.experiments.experiment.experiment_torque`), read through the sensors of
:mod:`alpes_dyn.estimation.experiments.experiment` (the encoder quantised to ``counts_per_rev`` with 0.5 count of
Gaussian noise, the torque with 5e-4 N m of white noise, 1 kHz), into a
:class:`~alpes_dyn.estimation.experiments.recording.Recording` that :func:`~alpes_dyn.estimation.identification.identification.identify`
reads, with the true joint angles in ``true_q_*``.

The effects (:class:`PlantEffects`, each off by default):

* ``stiction``: stick-slip dry friction, MuJoCo's ``frictionloss`` F_s with a stiff constraint
  (:data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST`); off, the joints get the library's own smooth law
  F_s tanh(v / v_s) + F_v v (:class:`~alpes_dyn.model.extras.JointExtras`), added to MuJoCo's passive forces
  by a callback at every RK4 stage: the plant then has the fitted model's friction structure;
* ``tendon_stiffness`` / ``tendon_damping``: the series-elastic, pull-only tendon with a rotor per motor
  (its inertia J_m on the motor side); the encoder measures the rotor;
* ``tendon_rotor``: the rotor inertia on the rigid tendon (J_m S^T S on the joints' mass matrix);
* ``tilt``: the palm tilted in the finger's plane (rad); the recording has no ``gravity_*`` columns (the
  user does not know the tilt);
* ``torque_constant_error`` e: the recorded torque is (1 + e) times the true one (a torque constant e off);
* ``encoder_offset``: the encoder's zero off by this many counts;
* ``tendon_dead_band`` (m, with ``tendon_stiffness``): the cable's slack at the motor shaft, a dead band on the
  tendon's stretch (the cable pulls k_t max(e - delta, 0)): 0.5 degree of backlash at the shaft is
  ``r_m * radians(0.5)``;
* ``torque_delay``: the torque measured this many whole samples late (the current's filter and the bus): the
  recording's torque at t_k is what the motor gave at t_(k-d) (the first d rows repeat the first torque).

The tendons' sheath friction (capstan) where the plant's parameters hold ``transmission.capstan``: MuJoCo has none,
so the passive callback adds the library's law (:func:`~alpes_dyn.model.transmission.capstan_torque`) on the rigid
tendon, its tension the actuator's torque (refused with the series-elastic tendon, whose tension is the cable's).

The passive callback is MuJoCo's process-wide ``mjcb_passive``: :func:`mujoco_recording` sets it for its run and
restores the previous one (not thread-safe: one smooth-friction run at a time per process).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import InputError, ModelError
from ..estimation.experiments.recording import Recording
from ..model.mjcf import joint_permutation, load_mujoco, mjcf_string, tilted_gravity
from ..model.params import HandParams, Param, load_params, with_values
from ..model.robot import Model
from ..model.transmission import capstan_torque, capstan_velocity
from ..simulation.loop import Source, run_loop
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, TorqueSensor

__all__ = ["PLANT_MODELS", "INTEGRATORS", "MAX_TORQUE_DELAY", "PlantEffects", "delayed", "plant_mjcf", "plant_model",
           "mujoco_recording", "mjcf_recording"]

PLANT_MODELS: tuple[str, ...] = ("finger2", "finger3", "thumb")
"""The models a recording plant is built for: one chain, as the identification experiment."""
INTEGRATORS: tuple[str, ...] = ("rk4", "implicit", "implicitfast")


def _number(x: object) -> bool:
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool) and math.isfinite(x)


@dataclass(frozen=True)
class PlantEffects:
    """The unmodelled effects of a real hand on a MuJoCo plant (see the module docstring); SI units.

    stiction: time constant (s) of MuJoCo's dry-friction constraint, or None (the library's smooth law).
    tendon_stiffness: k_t (N/m) of a series-elastic tendon, or None (rigid). tendon_damping: c_t (N s/m).
    tendon_rotor: the rotor's inertia on the rigid tendon. tilt: rad, in the finger's plane.
    torque_constant_error: e, the recorded torque (1 + e) times the true one. encoder_offset: counts.
    tendon_dead_band: m, the cable's slack (with ``tendon_stiffness``). torque_delay: whole samples (>= 0) by which
    the recorded torque lags the applied one.
    """

    stiction: float | None = None
    tendon_stiffness: float | None = None
    tendon_damping: float = 0.0
    tendon_rotor: bool = False
    tilt: float = 0.0
    torque_constant_error: float = 0.0
    encoder_offset: float = 0.0
    tendon_dead_band: float = 0.0
    torque_delay: int = 0

    def check(self) -> "PlantEffects":
        """Numbers in range (:class:`~alpes_dyn.InputError` naming the field); the MJCF options are checked by
        :func:`~alpes_dyn.model.mjcf.mjcf_string`."""
        if not (_number(self.torque_constant_error) and -0.5 < self.torque_constant_error < 0.5):
            raise InputError(f"torque_constant_error: expected a fraction in (-0.5, 0.5), got "
                             f"{self.torque_constant_error!r}")
        if not (_number(self.encoder_offset) and abs(self.encoder_offset) <= 1e6):
            raise InputError(f"encoder_offset: expected a finite number of counts, got {self.encoder_offset!r}")
        if not (isinstance(self.torque_delay, (int, np.integer)) and not isinstance(self.torque_delay, bool)
                and 0 <= self.torque_delay <= MAX_TORQUE_DELAY):
            raise InputError(f"torque_delay: expected a whole number of samples from 0 to {MAX_TORQUE_DELAY}, got "
                             f"{self.torque_delay!r}")
        if self.tendon_dead_band and self.tendon_stiffness is None:
            raise InputError("tendon_dead_band: the cable's slack needs the series-elastic tendon (tendon_stiffness)")
        return self


MAX_TORQUE_DELAY = 100
"""The longest torque delay a plant takes, samples (0.1 s at 1 kHz: beyond, it is a wrong clock, not a filter)."""


def delayed(signal: np.ndarray, samples: int) -> np.ndarray:
    """``signal`` (N+1, ...) seen ``samples`` whole samples late: row k is row k - samples of ``signal``, the first
    ``samples`` rows repeat row 0 (what a sensor that lags by a fixed number of samples reads from a held start)."""
    if samples == 0:
        return signal
    out = np.empty_like(signal)
    out[samples:] = signal[:-samples]
    out[:samples] = signal[0]
    return out


def _params(params: HandParams | str | None) -> HandParams:
    return params if isinstance(params, HandParams) else load_params(params)


def plant_mjcf(model: str, params: HandParams | str | None = None, effects: PlantEffects | None = None,
               chain: str | None = None, timestep: float = 1e-4) -> str:
    """MJCF text of the plant: ``model`` from ``params`` with the MJCF side of ``effects`` (joint stops on,
    contact off: a finger moving freely; friction as the module docstring says)."""
    e = (effects or PlantEffects()).check()
    p = _params(params)
    if p.capstan > 0:  # not in the MJCF: mujoco_recording's passive callback adds the sheath friction
        p = with_values(p, {"transmission.capstan": Param(0.0, "-", "assumed", "in the plant's callback", "sheath")})
    return mjcf_string(model, p, chain=chain, friction=False, contact=False, timestep=timestep,
                       stiction=e.stiction, tendon_stiffness=e.tendon_stiffness, tendon_damping=e.tendon_damping,
                       tendon_rotor=e.tendon_rotor, tilt=e.tilt, tendon_dead_band=e.tendon_dead_band)


def plant_model(model: str, params: HandParams | str | None = None, effects: PlantEffects | None = None,
                chain: str | None = None) -> Model:
    """The library's rigid model of the same finger (friction on), with the plant's tilted gravity: what the
    plant is without its other effects (its rest states, its smooth friction law)."""
    e = (effects or PlantEffects()).check()
    m = Model.alpes(model, friction=True, params=_params(params), chain=chain)
    return m if e.tilt == 0 else m.copy(gravity=tilted_gravity(m.gravity, e.tilt))


def _check_run(model: str, u: np.ndarray, dt: float, timestep: float, integrator: str, m: int) -> int:
    """Substeps per sample; one-line errors for the run's settings."""
    if integrator not in INTEGRATORS:
        raise InputError(f"integrator: unknown integrator {integrator!r} (expected one of {', '.join(INTEGRATORS)})")
    if u.ndim != 2 or u.shape[1] != m or u.shape[0] < 2 or not np.isfinite(u).all():
        raise InputError(f"torque: expected finite motor torques of shape (N+1, {m}), got shape {u.shape}")
    if not (_number(dt) and 0 < dt <= 0.1):
        raise InputError(f"dt: expected a sample period in (0, 0.1] s, got {dt!r}")
    if not (_number(timestep) and 0 < timestep <= dt):
        raise InputError(f"timestep: expected a MuJoCo step in (0, dt] s, got {timestep!r}")
    sub = int(round(dt / timestep))
    if abs(sub * timestep - dt) > 1e-9 * dt:
        raise InputError(f"timestep: {timestep:g} s does not divide the sample period {dt:g} s")
    return sub


def _initial_state(mj, truth: Model, perm: np.ndarray, q0: np.ndarray, u0: np.ndarray, p: HandParams,
                   effects: PlantEffects) -> np.ndarray:
    """qpos of the plant at joint angles q0 (rad), at rest: each rotor (series-elastic tendon) turned so that the
    cable holds the motor torque u0 (the static tension T = tau_m / r_m, stretch T / k_t, plus the cable's slack)."""
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


def mujoco_recording(model: str, true_params: HandParams | str | None, torque: np.ndarray, dt: float = 1e-3, *,
                     effects: PlantEffects | None = None, q0: Sequence[float] | None = None, seed: int = 0,
                     chain: str | None = None, timestep: float = 1e-4, integrator: str = "rk4",
                     encoder_noise_counts: float = 0.5, torque_noise: float = 5e-4,
                     gravity: np.ndarray | None = None) -> Recording:
    """Replay a motor torque on a MuJoCo plant of ``model`` with ``effects`` and record it as the hand's sensors do.

    Parameters
    ----------
    model: ``finger2``, ``finger3`` or ``thumb`` (:data:`PLANT_MODELS`). true_params: the plant's parameters.
    torque: (N+1, m) true motor torque, N m, torque[k] held on [t_k, t_k+1) (the last row is recorded only).
    dt: sample period, s. timestep: MuJoCo's step, s (a divisor of dt; default 0.1 ms).
    effects: :class:`PlantEffects` (default none: the library's own model structure, its smooth friction).
    q0: initial joint angles (rad; default the plant's rest under torque[0], as :func:`plant_model` finds it),
        at rest (qd = 0), each series-elastic rotor holding the cable's static tension.
    seed: seed of the sensor noise. integrator: ``rk4`` (default), ``implicit`` or ``implicitfast``.
    encoder_noise_counts: Gaussian noise (counts) added before the encoder's quantisation. torque_noise: N m.
    gravity: (N+1, 3) m/s^2, the gravity the plant feels at each sample (default its MJCF's, the ``tilt`` of
        ``effects`` in it): the hand turned where it changes (the state carries on; the sensors' noise of each
        orientation's run seeded apart); the recording holds no gravity columns (the rig's nominal
        orientations are the caller's to write).

    Returns
    -------
    :class:`~alpes_dyn.estimation.experiments.recording.Recording`: ``encoder`` the plant's ``encoder_<motor>`` sensor
    (the rotor with the elastic tendon) quantised, plus ``encoder_offset``; ``torque`` (1 +
    ``torque_constant_error``) x torque + noise; ``true_q`` MuJoCo's joint angles; no gravity columns.
    Cost: the loop of :func:`~alpes_dyn.simulation.loop.run_loop` over the N samples, MuJoCo stepping each sample's
    substeps (``mj_step`` with ``nstep``); measured for the 4 s experiment on a loaded 2-core machine: 2.3 s with the smooth-friction
    callback, 0.9 s with ``stiction`` (no callback).
    """
    import mujoco  # load_mujoco below gives the one-line error when it is missing

    e = (effects or PlantEffects()).check()
    _check_recording_settings(model, seed, encoder_noise_counts, torque_noise)
    p = _params(true_params)
    truth = plant_model(model, p, e, chain)
    m = truth.transmission.n_motors
    u = np.asarray(torque, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    sub = _check_run(model, u, dt, timestep, integrator, m)
    mj = load_mujoco(plant_mjcf(model, p, e, chain, timestep))
    mj.opt.integrator = {"rk4": mujoco.mjtIntegrator.mjINT_RK4, "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
                         "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}[integrator]
    edges = _gravity_segments(gravity, u.shape[0])
    if gravity is not None:  # the rest (q0's default) found in the first orientation
        mj.opt.gravity[:] = gravity[0]
        truth = truth.copy(gravity=np.asarray(gravity[0], dtype=float))
    d = _plant_at_rest(mj, truth, q0, u[0], p, e)
    previous = mujoco.get_mjcb_passive()
    passive = _passive_forces(mj, truth, e)
    if passive is not None:
        mujoco.set_mjcb_passive(passive)
    try:
        rec = _turned_run(mj, d, sub, u, dt, truth, None, seed, encoder_noise_counts, torque_noise, gravity, edges,
                          offset=e.encoder_offset, gain=1.0 + e.torque_constant_error)
    finally:
        mujoco.set_mjcb_passive(previous)
    if e.torque_delay:  # the sensor's reading of sample k is the torque (and its noise) of sample k - d
        rec.torque = delayed(rec.torque, e.torque_delay)
    return rec


def _gravity_segments(gravity: np.ndarray | None, n_samples: int) -> np.ndarray:
    """Sample indices [0, a_1, ..., N]: where the plant's ``gravity`` (N+1, 3) changes (checked: finite, the
    record's length), 0 and the last sample around them; [0, N] without."""
    if gravity is None:
        return np.array([0, n_samples - 1])
    G = np.asarray(gravity, dtype=float)
    if G.shape != (n_samples, 3) or not np.isfinite(G).all():
        raise InputError(f"gravity: expected finite gravity vectors (m/s^2) of shape ({n_samples}, 3), one per "
                         f"sample, got shape {G.shape}")
    return np.concatenate([[0], np.flatnonzero(np.any(G[1:] != G[:-1], axis=1)) + 1, [n_samples - 1]])


def _turned_run(mj: Any, d: Any, sub: int, u: np.ndarray, dt: float, model: Model, actuators: list[str] | None,
                seed: int, encoder_noise_counts: float, torque_noise: float, gravity: np.ndarray | None,
                edges: np.ndarray, **sensors: float) -> Recording:
    """:func:`_sensed_run` segment by segment of constant ``gravity`` (``edges`` from :func:`_gravity_segments`):
    MuJoCo's gravity set to each segment's at its first sample (the hand turned: the state carries on), the sensors'
    noise of each segment seeded apart (``seed + 7919 i``); one segment: :func:`_sensed_run` itself."""
    parts = []
    for i, (a, b) in enumerate(zip(edges[:-1], edges[1:])):  # a loop over the orientations (one or two)
        if i:
            mj.opt.gravity[:] = gravity[a]
        parts.append(_sensed_run(mj, d, sub, u[a: b + 1], dt, model, actuators, seed + 7919 * i,
                                 encoder_noise_counts, torque_noise, **sensors))
    return parts[0] if len(parts) == 1 else _joined(parts, dt)


def _joined(parts: list[Recording], dt: float) -> Recording:
    """One recording of runs that follow each other (each one's first sample the last one's final state)."""
    cat = {f: np.concatenate([getattr(r, f)[:-1] for r in parts[:-1]] + [getattr(parts[-1], f)])
           for f in ("encoder", "torque", "true_q")}
    return Recording(t=dt * np.arange(cat["encoder"].shape[0]), motor_names=parts[0].motor_names,
                     joint_names=parts[0].joint_names, **cat)


def _sensed_run(mj: Any, d: Any, sub: int, u: np.ndarray, dt: float, model: Model, actuators: list[str] | None,
                seed: int, encoder_noise_counts: float, torque_noise: float, offset: float = 0.0,
                gain: float = 1.0) -> Recording:
    """The recording of MuJoCo (``mj``, ``d`` at the initial state) stepped ``sub`` substeps per sample under the
    torque ``u`` (N+1, m) held over each period ``dt``: ``model``'s joint angles as ``true_q``, its motors'
    ``encoder_<motor>`` sensors quantised with ``offset`` counts (the encoder's noise drawn first from ``seed``),
    the torque measured as ``gain`` x ``u`` + noise. ``actuators``: the MJCF's actuators in the motors' order (None:
    the MJCF's own order). ModelError where MuJoCo diverged."""
    tr, m = model.transmission, model.transmission.n_motors
    rng = np.random.default_rng(seed)  # the encoder's noise, then the torque's
    blocks = [Source("torque", tau=u),
              # mj_step's sensors are the state's before its last integration: recomputed at the sample's state
              MujocoPlant(mj, d, substeps=sub, nstep=True, sample_sensors=True, joints={"q": model.joint_names},
                          sensors={"q_m": [f"encoder_{mn}" for mn in tr.motor_names]}, actuators={"tau": actuators}),
              Encoder("q_m", "counts", tr.counts_per_rev, noise_counts=encoder_noise_counts, counts=True,
                      offset=offset, rng=rng, shape=(m,)),
              TorqueSensor("tau", "tau_meas", noise=torque_noise, gain=gain, rng=rng, shape=(m,))]
    log = run_loop(blocks, u.shape[0] - 1, dt, final=True)
    if not np.isfinite(log["q"]).all():
        raise ModelError("the MuJoCo plant diverged (NaN in its state): a smaller timestep or another integrator")
    return Recording(t=dt * np.arange(u.shape[0]), encoder=log["counts"], torque=log["tau_meas"],
                     motor_names=tr.motor_names, joint_names=model.joint_names, true_q=log["q"])


def mjcf_recording(mjcf: str | os.PathLike, model: Model, torque: np.ndarray, dt: float = 1e-3, *,
                   q0: Sequence[float] | None = None, seed: int = 0, encoder_noise_counts: float = 0.5,
                   torque_noise: float = 5e-4, gravity: np.ndarray | None = None) -> Recording:
    """Replay a motor torque on MuJoCo stepping an MJCF of any robot, and record it as :func:`mujoco_recording` does.

    ``mjcf``: the MJCF text, or the path of its file -- e.g. what ``alpes-dyn mjcf --model ROBOT.urdf --spec
    ROBOT.toml -o plant.xml`` (:func:`~alpes_dyn.model.mjcf_export.model_mjcf`) writes: a motor actuator and an
    ``encoder_<motor>`` sensor per motor, the joints named as ``model``'s. Stepped as written (its ``timestep``, which
    must divide ``dt``, its integrator, its friction: MuJoCo's ``frictionloss`` is stick-slip, not the library's
    smooth law). ``model``: the :class:`~alpes_dyn.Model` whose joints, motors and encoder resolution the recording
    names (the robot the MJCF was exported from); its static equilibrium under ``torque[0]`` is the initial state
    unless ``q0`` (rad) is given. ``torque`` (N+1, m), N m, held over each period; ``dt`` the sample period, s;
    ``seed``, ``encoder_noise_counts``, ``torque_noise`` as :func:`mujoco_recording`'s.

    Returns the :class:`~alpes_dyn.estimation.experiments.recording.Recording` (encoder counts, measured torque, MuJoCo's joint
    angles as ``true_q``), which :func:`~alpes_dyn.estimation.experiments.recording.write_recording` writes for ``alpes-dyn
    estimate --data``. A mimic joint starts at its rule's value of the initial q. ``gravity``: (N+1, 3) m/s^2, the
    gravity the robot feels at each sample, as :func:`mujoco_recording`'s (default the MJCF's; the rest found in the
    first orientation; no gravity columns written: the rig's nominal orientations are the caller's).
    """
    import mujoco  # load_mujoco below gives the one-line error when it is missing

    if not isinstance(model, Model) or model.transmission is None:
        raise InputError(f"model: expected an alpes_dyn Model with motors, got {type(model).__name__}")
    if isinstance(mjcf, os.PathLike) or (isinstance(mjcf, str) and not mjcf.lstrip().startswith("<")):
        from ..fileio import read_text

        mjcf = read_text(mjcf, "mjcf", InputError)
    if not isinstance(mjcf, str):
        raise InputError(f"mjcf: expected MJCF text or the path of its file, got {type(mjcf).__name__}")
    _check_recording_settings("finger3", seed, encoder_noise_counts, torque_noise)
    mj = load_mujoco(mjcf)
    tr = model.transmission
    u = np.asarray(torque, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    sub = _check_run("finger3", u, dt, float(mj.opt.timestep), "rk4", tr.n_motors)
    edges = _gravity_segments(gravity, u.shape[0])
    if gravity is not None:
        mj.opt.gravity[:] = gravity[0]
        model = model.copy(gravity=np.asarray(gravity[0], dtype=float))
    d = mujoco.MjData(mj)
    q_init = (model.static_equilibrium(None, np.zeros(model.n), fixed=model.springless_joints, tau_m=u[0])
              if q0 is None else np.asarray(q0, dtype=float))
    if q_init.shape != (model.n,) or not np.isfinite(q_init).all():
        raise InputError(f"q0: expected {model.n} finite joint angles (rad), got {np.asarray(q0).tolist()!r}")
    d.qpos[joint_permutation(mj, model.joint_names)] = q_init
    for mimic in model.mimic.mimics if model.mimic is not None else ():
        d.qpos[mj.joint(mimic.name).qposadr[0]] = mimic.multiplier * q_init[model.joint_index(mimic.primary)] \
            + mimic.offset
    mujoco.mj_forward(mj, d)
    return _turned_run(mj, d, sub, u, dt, model, list(tr.motor_names), seed, encoder_noise_counts, torque_noise,
                       gravity, edges)


def _check_recording_settings(model: str, seed: Any, encoder_noise_counts: Any, torque_noise: Any) -> None:
    """One-line errors for :func:`mujoco_recording`'s seed, sensor noises and model."""
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    for name, v in (("encoder_noise_counts", encoder_noise_counts), ("torque_noise", torque_noise)):
        if not (_number(v) and v >= 0):
            raise InputError(f"{name}: expected a non-negative number, got {v!r}")
    if model not in PLANT_MODELS:
        raise InputError(f"model: a recording plant is one chain ({', '.join(PLANT_MODELS)}), got {model!r}")


def _plant_at_rest(mj, truth: Model, q0: Sequence[float] | None, u0: np.ndarray, p: HandParams,
                   effects: PlantEffects):
    """The plant's MjData at joint angles ``q0`` (rad; default the rest of ``truth`` under the torque ``u0``, N m)
    at rest, its derived quantities computed (``mj_forward``)."""
    import mujoco

    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, truth.joint_names)
    if q0 is None:
        q_init = truth.static_equilibrium(None, np.zeros(truth.n), fixed=truth.springless_joints, tau_m=u0)
    else:
        q_init = np.asarray(q0, dtype=float)
        if q_init.shape != (truth.n,) or not np.isfinite(q_init).all():
            raise InputError(f"q0: expected {truth.n} finite joint angles (rad), got {np.asarray(q0).tolist()!r}")
    d.qpos[:] = _initial_state(mj, truth, perm, q_init, u0, p, effects)
    mujoco.mj_forward(mj, d)
    return d


def _passive_forces(mj, truth: Model, e: PlantEffects) -> Callable[[Any, Any], None] | None:
    """MuJoCo's passive-force callback of what the plant adds to MuJoCo at every RK4 stage (N m on ``truth``'s
    joints): the library's smooth friction law (without ``stiction``: MuJoCo's own dry friction then) and the tendons'
    sheath friction where ``truth`` has one (``capstan``: S^T of the capstan's loss at the actuators' torque, d.ctrl,
    and the motor velocity S qd); None where there is nothing to add."""
    ex, tr = truth.extras, truth.transmission
    sheath = tr is not None and tr.has_capstan
    if sheath and e.tendon_stiffness is not None:
        raise InputError("capstan: the MuJoCo plant puts the tendons' sheath friction on a rigid tendon (its tension "
                         "the motor's torque); with tendon_stiffness the tension is the cable's")
    if e.stiction is not None and not sheath:
        return None
    dofs = np.array([mj.jnt_dofadr[mj.joint(j).id] for j in truth.joint_names])
    smooth = e.stiction is None
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
