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

The effects (:class:`~alpes_dyn.bench.effects.PlantEffects`: stick-slip, the series-elastic tendon with its rotor
and slack, the rotor on the rigid tendon, the palm's tilt, the torque constant's and the encoder's errors, the torque
read late) and the plant's MuJoCo side (:func:`~alpes_dyn.bench.mujoco_plant.plant_mjcf`,
:func:`~alpes_dyn.bench.mujoco_plant.plant_model`, its rest and its passive forces) are the bench's
(:mod:`alpes_dyn.bench.effects`, :mod:`alpes_dyn.bench.mujoco_plant`), importable from here as before. On a
recording: with ``tilt`` it has no ``gravity_*`` columns (the user does not know the tilt); with ``torque_delay`` d its
torque at t_k is what the motor gave at t_(k-d) (the first d rows repeat the first torque).

The tendons' sheath friction (capstan) where the plant's parameters hold ``transmission.capstan``: MuJoCo has none,
so the passive callback adds the library's law (:func:`~alpes_dyn.model.transmission.capstan_torque`) on the rigid
tendon, its tension the actuator's torque (refused with the series-elastic tendon, whose tension is the cable's).

The passive callback is MuJoCo's process-wide ``mjcb_passive``: :func:`mujoco_recording` sets it for its run and
restores the previous one (not thread-safe: one smooth-friction run at a time per process).
"""

from __future__ import annotations

import os
from typing import Any, Sequence

import numpy as np

# the bench's, importable from here as before (documented there: not in __all__)
from ..bench.effects import MAX_TORQUE_DELAY, PlantEffects, _number, delayed  # noqa: F401
from ..bench.mujoco_plant import (INTEGRATORS, PLANT_MODELS, as_params, free_plant, passive_callback,  # noqa: F401
                                  passive_forces, plant_mjcf, plant_model)
from ..errors import InputError, ModelError
from ..estimation.experiments.recording import Recording
from ..model.mjcf import joint_permutation, load_mujoco
from ..model.params import HandParams
from ..model.robot import Model
from ..simulation.loop import Source, run_loop
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, TorqueSensor

__all__ = ["mujoco_recording", "mjcf_recording"]


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


def mujoco_recording(model: str, true_params: HandParams | str | None, torque: np.ndarray, dt: float = 1e-3, *,
                     effects: PlantEffects | None = None, q0: Sequence[float] | None = None, seed: int = 0,
                     chain: str | None = None, timestep: float = 1e-4, integrator: str = "rk4",
                     encoder_noise_counts: float = 0.5, torque_noise: float = 5e-4,
                     gravity: np.ndarray | None = None) -> Recording:
    """Replay a motor torque on a MuJoCo plant of ``model`` with ``effects`` and record it as the hand's sensors do.

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3`` or ``thumb`` (:data:`~alpes_dyn.bench.mujoco_plant.PLANT_MODELS`).
    true_params : HandParams, str or None
        The plant's parameters (or their file; None: the defaults).
    torque : numpy.ndarray, shape (N+1, m) or (N+1,)
        The true motor torque, N m, torque[k] held on [t_k, t_k+1) (the last row is recorded only).
    dt : float, optional
        The sample period, s (default 1 ms).
    effects : PlantEffects or None, optional
        :class:`~alpes_dyn.bench.effects.PlantEffects` (default none: the library's own model structure, its
        smooth friction).
    q0 : sequence of float or None, optional
        The initial joint angles, rad (default the plant's rest under torque[0], as
        :func:`~alpes_dyn.bench.mujoco_plant.plant_model` finds it), at rest (qd = 0), each series-elastic rotor
        holding the cable's static tension.
    seed : int, optional
        The seed of the sensor noise (default 0).
    chain : str or None, optional
        The hand's chain simulated (None: the model's own).
    timestep : float, optional
        MuJoCo's step, s, a divisor of ``dt`` (default 0.1 ms).
    integrator : str, optional
        ``"rk4"`` (default), ``"implicit"`` or ``"implicitfast"``.
    encoder_noise_counts : float, optional
        The Gaussian noise's standard deviation, counts, added before the encoder's quantisation (default 0.5).
    torque_noise : float, optional
        The torque sensor's noise's standard deviation, N m (default 5e-4).
    gravity : numpy.ndarray, shape (N+1, 3), or None, optional
        The gravity the plant feels at each sample, m/s^2 (default its MJCF's, the ``tilt`` of ``effects`` in it):
        the hand turned where it changes (the state carries on; the sensors' noise of each orientation's run
        seeded apart); the recording holds no gravity columns (the rig's nominal orientations are the caller's to
        write).

    Returns
    -------
    Recording
        :class:`~alpes_dyn.estimation.experiments.recording.Recording`: ``encoder`` the plant's ``encoder_<motor>``
        sensor (the rotor with the elastic tendon) quantised, plus ``encoder_offset``; ``torque`` (1 +
        ``torque_constant_error``) x torque + noise; ``true_q`` MuJoCo's joint angles; no gravity columns.

    Notes
    -----
    Cost: the loop of :func:`~alpes_dyn.simulation.loop.run_loop` over the N samples, MuJoCo stepping each sample's
    substeps (``mj_step`` with ``nstep``); the smooth friction's Python callback at every substep costs more than
    MuJoCo's own step, so a plant with ``stiction`` (no callback) records more than twice as fast.
    """
    e = (effects or PlantEffects()).check()
    _check_recording_settings(model, seed, encoder_noise_counts, torque_noise)
    p = as_params(true_params)
    truth = plant_model(model, p, e, chain)
    m = truth.transmission.n_motors
    u = np.asarray(torque, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    sub = _check_run(model, u, dt, timestep, integrator, m)
    edges = _gravity_segments(gravity, u.shape[0])
    # the rest (q0's default) found in the first orientation
    mj, d, truth = free_plant(truth, model, p, e, chain, timestep, integrator, q0, u[0],
                              None if gravity is None else gravity[0])
    with passive_callback(passive_forces(mj, truth, e)):
        rec = _turned_run(mj, d, sub, u, dt, truth, None, seed, encoder_noise_counts, torque_noise, gravity, edges,
                          offset=e.encoder_offset, gain=1.0 + e.torque_constant_error)
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

    Stepped as written (its ``timestep``, which must divide ``dt``, its integrator, its friction: MuJoCo's
    ``frictionloss`` is stick-slip, not the library's smooth law). A mimic joint starts at its rule's value of the
    initial q.

    Parameters
    ----------
    mjcf : str or os.PathLike
        The MJCF text, or the path of its file -- e.g. what ``alpes-dyn mjcf --model ROBOT.urdf --spec ROBOT.toml
        -o plant.xml`` (:func:`~alpes_dyn.model.mjcf_export.model_mjcf`) writes: a motor actuator and an
        ``encoder_<motor>`` sensor per motor, the joints named as ``model``'s.
    model : Model
        The :class:`~alpes_dyn.Model` whose joints, motors and encoder resolution the recording names (the robot
        the MJCF was exported from); its static equilibrium under ``torque[0]`` is the initial state unless ``q0``
        is given.
    torque : numpy.ndarray, shape (N+1, m)
        The motor torque, N m, held over each period.
    dt : float, optional
        The sample period, s (default 1 ms).
    q0 : sequence of float or None, optional
        The initial joint angles, rad (default: the static equilibrium under ``torque[0]``).
    seed : int, optional
        The seed of the sensor noise, as :func:`mujoco_recording`'s (default 0).
    encoder_noise_counts : float, optional
        The encoder's noise, counts, as :func:`mujoco_recording`'s (default 0.5).
    torque_noise : float, optional
        The torque sensor's noise, N m, as :func:`mujoco_recording`'s (default 5e-4).
    gravity : numpy.ndarray, shape (N+1, 3), or None, optional
        The gravity the robot feels at each sample, m/s^2, as :func:`mujoco_recording`'s (default the MJCF's; the
        rest found in the first orientation; no gravity columns written: the rig's nominal orientations are the
        caller's).

    Returns
    -------
    Recording
        The :class:`~alpes_dyn.estimation.experiments.recording.Recording` (encoder counts, measured torque,
        MuJoCo's joint angles as ``true_q``), which
        :func:`~alpes_dyn.estimation.experiments.recording.write_recording` writes for ``alpes-dyn estimate
        --data``.
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
