"""The MuJoCo stand-in for a hand on the bench: a :class:`~alpes_dyn.bench.interface.HardwareInterface` on a
MuJoCo finger (or the hand) with a real hand's effects, its truth hidden behind the interface.

:class:`MujocoHand` is the reference hand that the tests and benchmarks drive as a user drives their own: its
parameters (the "true" finger, drawn by the caller) and its state stay private; what it shows is what a driver
shows -- the encoder counts, the motor torque read from the current, the fingertip force, every
:attr:`~MujocoHand.period`.

The plant (:mod:`alpes_dyn.bench.mujoco_plant`), in one of two scenes:

* ``"free"``: the finger (or the hand's five chains) moving freely (joint stops on, contact off; RK4 at 0.1 ms),
  as :func:`~alpes_dyn.control.plants.mujoco_recording` records a finger; no force sensor (the force reads NaN);
* ``"block"`` (a finger): the finger palm down over the block of the force loop (contact on, MuJoCo's joint
  friction, at 0.25 ms), as :func:`~alpes_dyn.control.finger_loop.run_control` presses it; the FlexiForce reads
  MuJoCo's touch sensor;
* ``"cylinder"`` (the hand): the hand palm down over the fixed, frictionless cylinder that
  :func:`~alpes_dyn.control.hand_loop.run_hand_control` grasps (contact on, MuJoCo's joint friction, at 0.25 ms;
  :func:`~alpes_dyn.bench.mujoco_plant.cylinder_plant`); each flexion chain's fingertip has its FlexiForce: the
  force is read as (5,) N, the chains in the motors' order (index, middle, ring, little, thumb).

The thumb's ab/adduction motor (the hand's and the thumb's ``thumb_abduction``) drives its joint through a gear, both
ways: it takes commands in [-tau_max, tau_max] (:attr:`MujocoHand.both_ways`,
:func:`~alpes_dyn.bench.interface.check_command`), every other motor, a cable's, in [0, tau_max]. Its joint has no
spring: at 0 N m it is left to its friction and its stops, and a motor that only pulled could not hold it against
the thumb's own contact (on the cylinder the thumb's pad pushes it from 35 to 59 degrees).

The effects (:class:`~alpes_dyn.bench.effects.PlantEffects`, default a real hand's:
:func:`~alpes_dyn.bench.effects.real_hand_effects`) and the sensors, as the library's own runs have them:

* the driver: the motor gives command / (1 + e) for the command (its torque constant e off, e the effects'
  ``torque_constant_error``);
* the encoder: the rotor's (series-elastic tendon) or the motor's angle plus ``encoder_noise_counts`` counts of
  Gaussian noise, quantised to ``counts_per_rev`` counts per revolution, its zero ``encoder_offset`` counts off;
* the torque: (1 + e) times the torque the motor applied over a period plus ``torque_noise`` N m of white noise,
  read at the tick that ends the period, ``torque_delay`` whole periods late (the reading at tick k is of the
  period [t_(k-1-d), t_(k-d)); before the first command, of the motor at rest, 0 N m);
* the force (block and cylinder scenes): MuJoCo's touch sensor plus ``force_noise`` N of noise, quantised to
  4.4 / 1024 N
  (a 10-bit reading of a 4.4 N FlexiForce), >= 0.

The sensors' noise comes from one generator seeded by ``seed``, drawn tick by tick (the torque's as the period
ends, then the encoder's, then the force's): the same seed and the same commands give the same readings.

The hand starts at rest: the free finger on its springs in the plant's gravity, motor off, each series-elastic
rotor holding the cable's tension (its slack taken up, :func:`~alpes_dyn.bench.mujoco_plant.initial_qpos`); the
block scene's finger hanging on its springs, the cable just slack (:func:`~alpes_dyn.bench.mujoco_plant.rotor_rest`);
or at the joint angles ``q0``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections import deque
from typing import Any, Sequence

import numpy as np

from ..errors import InputError, ModelError
from ..model.mjcf import HANGING_TILT, joint_permutation, palm_down_params
from ..model.params import HandParams
from ..simulation.plants import MujocoPlant
from ..simulation.sensors import Encoder, ForceSensor, TorqueSensor
from .effects import PlantEffects, _number, real_hand_effects
from .interface import Reading, check_command
from .mujoco_plant import (as_params, block_plant, cylinder_plant, free_plant, initial_qpos, passive_callback,
                           passive_forces,
                           plant_model)

__all__ = ["MujocoHand", "scoring_truth", "HAND_MODELS", "SCENES", "PERIOD", "SUBSTEPS"]

HAND_MODELS: tuple[str, ...] = ("finger2", "finger3", "hand", "thumb")
"""The models the stand-in is built for: a finger, the hand's five chains (the free and cylinder scenes), or the
thumb's chain alone (its flexion and ab/adduction motors; the free scene)."""
SCENES: tuple[str, ...] = ("free", "block", "cylinder")
"""The stand-in's scenes (module docstring)."""
PERIOD = 1e-3
"""The stand-in's sample period, s (the hand's 1 kHz loop)."""
SUBSTEPS = {"free": 10, "block": 4, "cylinder": 4}
"""MuJoCo steps per period of each scene (RK4 at 0.1 ms as the recordings', the force loops' 0.25 ms)."""
RIGS: dict[str, float] = {"level": 0.0, "hanging": HANGING_TILT}
"""The free scene's orientations: rad about the joints' axes from the file's palm-up gravity (``hanging``: fingers
down, :data:`~alpes_dyn.model.mjcf.HANGING_TILT`), the effects' tilt on top of it."""
SETTLE_S = 1.0
"""s: how long the free finger rests, motor off, before the first tick (its default start)."""


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise ModelError("the MuJoCo stand-in needs mujoco (pip install 'alpes_dyn[mujoco]')") from None
    return mujoco


def _checked(model: Any, params: Any, effects: Any, scene: Any, seed: Any,
             noises: dict[str, Any]) -> PlantEffects | None:
    """One-line :class:`~alpes_dyn.InputError` naming the bad argument of :class:`MujocoHand`; the effects checked."""
    if model not in HAND_MODELS:
        raise InputError(f"model: the MuJoCo stand-in is built for {', '.join(HAND_MODELS)}, got {model!r}")
    if scene not in SCENES:
        raise InputError(f"scene: expected one of {', '.join(SCENES)}, got {scene!r}")
    if scene == "block" and model in ("hand", "thumb"):
        raise InputError(f"scene: the block scene is a finger's (finger2, finger3); the {model}'s is free"
                         + (" or cylinder" if model == "hand" else " (its force loop: the hand's cylinder)"))
    if scene == "cylinder" and model != "hand":
        raise InputError(f"scene: the cylinder scene is the hand's, got model {model!r} (a finger's: free or block)")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    for name, v in noises.items():
        if not (_number(v) and v >= 0):
            raise InputError(f"{name}: expected a non-negative number, got {v!r}")
    if params is not None and not isinstance(params, (HandParams, str, os.PathLike)):
        raise InputError(f"params: expected HandParams or the path of a parameter file, got {type(params).__name__}")
    if isinstance(effects, str) and effects == "real":
        return real_hand_effects()
    if effects is not None and not isinstance(effects, PlantEffects):
        raise InputError(f"effects: expected a PlantEffects, None (none) or 'real' (a real hand's), got {effects!r}")
    return None if effects is None else effects.check()


class MujocoHand:
    """A :class:`~alpes_dyn.bench.interface.HardwareInterface` on a MuJoCo finger (module docstring).

    Parameters
    ----------
    model : str
        ``finger2``, ``finger3``, ``hand`` or ``thumb`` (:data:`HAND_MODELS`; the hand in the free and cylinder
        scenes, the thumb's chain in the free scene).
    params : HandParams or str or path, optional
        The finger's true parameters, or the path of their file (default the shipped file); kept private.
    effects : PlantEffects or None or "real"
        The plant's effects: ``"real"`` (default) a real hand's (:func:`~alpes_dyn.bench.effects.real_hand_effects`),
        None or ``PlantEffects()`` none.
    scene : str
        ``"free"`` (default), ``"block"`` (a finger) or ``"cylinder"`` (the hand) (:data:`SCENES`).
    seed : int
        Seed of the sensors' noise.
    q0 : sequence of float, optional
        Initial joint angles, rad (at rest, qd = 0); default the rest of the module docstring.
    encoder_noise_counts, torque_noise, force_noise : float
        The sensors' noise: counts (0.5), N m (5e-4), N (0.005).
    rig : str
        The free scene's orientation (:data:`RIGS`): ``"level"`` (palm up, the file's gravity) or ``"hanging"``
        (fingers down); a real hand's tilt on top of it.

    Attributes
    ----------
    period : float
        :data:`PERIOD`, s.
    motor_names : tuple of str
        The motors: a finger's one; the hand's six (index, middle, ring, little, thumb, thumb_abduction); the
        thumb's two (thumb, thumb_abduction).
    counts_per_rev : int
        Encoder counts per motor revolution.
    tau_max : float
        The motor's limit, N m (the commands lie in [0, tau_max]).
    model, scene : str
        As given.
    closed : bool
        Whether :meth:`close` was called (a write is then refused).
    both_ways : tuple of bool
        Per motor: whether it pushes both ways (the thumb's ab/adduction, a gear), its commands then in
        [-tau_max, tau_max].

    Raises
    ------
    InputError
        A bad argument (one line naming it).
    ModelError
        MuJoCo missing, or an unreadable parameter file.
    """

    def __init__(self, model: str = "finger3", params: HandParams | str | os.PathLike | None = None, *,
                 effects: PlantEffects | str | None = "real", scene: str = "free", seed: int = 0,
                 q0: Sequence[float] | None = None, encoder_noise_counts: float = 0.5, torque_noise: float = 5e-4,
                 force_noise: float = 0.005, rig: str = "level") -> None:
        e = _checked(model, params, effects, scene, seed, {"encoder_noise_counts": encoder_noise_counts,
                                                           "torque_noise": torque_noise, "force_noise": force_noise})
        self._mujoco = _mujoco()
        p, sub = as_params(params), SUBSTEPS[scene]
        if rig not in RIGS or (rig != "level" and scene != "free"):
            raise InputError(f"rig: expected one of {', '.join(RIGS)} (the free scene; the block scene is palm down), "
                             f"got {rig!r}")
        if RIGS[rig]:  # the hand turned on its rig: the effects' tilt on top of the rig's
            e = dataclasses.replace(e or PlantEffects(), tilt=(e or PlantEffects()).tilt + RIGS[rig])
        e0 = e or PlantEffects()
        if scene == "free":
            truth = plant_model(model, p, e0)
            at_rest = np.zeros(truth.transmission.n_motors)  # the motor off
            mj, d, truth = free_plant(truth, model, p, e0, None, PERIOD / sub, "rk4", q0, at_rest)
            self._passive = passive_forces(mj, truth, e0)
            if q0 is None:
                self._settle(mj, d, truth, p, e0)
        elif scene == "block":
            mj, d, truth = block_plant(model, palm_down_params(p), e, None, PERIOD / sub, q0)
            self._passive = None
        else:
            if q0 is not None:
                raise InputError("q0: the cylinder scene starts at the hand's rest (give no q0)")
            mj, d, truth = cylinder_plant(palm_down_params(p), e, PERIOD / sub)
            self._passive = None
        tr = truth.transmission
        motors = list(tr.motor_names)
        m = len(motors)
        self.model, self.scene, self.period = model, scene, PERIOD
        self.motor_names, self.counts_per_rev, self.tau_max = tuple(motors), int(tr.counts_per_rev), float(p.tau_max)
        self.both_ways = tuple(mn.endswith("abduction") for mn in motors)
        self.closed = False
        self._data, self._k, self._gain = d, 0, 1.0 + e0.torque_constant_error
        self._joints = joint_permutation(mj, truth.joint_names)  # qpos of the joints, for scoring_truth
        self._rng = np.random.default_rng(seed)
        touch = {"F": "flexiforce_finger"} if scene == "block" else {}  # the finger's chain
        if scene == "cylinder":  # each flexion chain's fingertip, in the motors' order
            touch = {"F": [f"flexiforce_{c}" for c in motors if c != "thumb_abduction"]}
        # mj_step's position sensors are those of the state before its last integration: recomputed at the tick
        self._plant = MujocoPlant(mj, d, substeps=sub, nstep=True, sample_sensors=True,
                                  sensors={"q_m": [f"encoder_{mn}" for mn in motors], **touch},
                                  actuators={"tau": motors}, period_sensors={"tau": [f"torque_{mn}" for mn in motors]})
        self._encoder = Encoder("q_m", "counts", tr.counts_per_rev, noise_counts=encoder_noise_counts, counts=True,
                                offset=e0.encoder_offset, shape=(m,))
        self._torque = TorqueSensor("tau", "tau_meas", noise=torque_noise, gain=self._gain, shape=(m,))
        self._force = ForceSensor("F", "F_meas", noise=force_noise) if scene != "free" else None
        # the torque readings of the last d + 1 periods, the oldest read now (before the start: the motor at rest)
        self._torques = deque([self._measured_torque(np.zeros(m))] * (e0.torque_delay + 1))
        self._reading = self._sense()

    def _settle(self, mj: Any, d: Any, truth: Any, p: HandParams, e: PlantEffects) -> None:
        """The free finger left to rest, motor off, for :data:`SETTLE_S` before the first tick: the rest the
        springs and gravity find may lie beyond a joint stop (palm up), where the stop holds the finger; the
        joints start clipped into their range and MuJoCo settles them against the stops. Each series-elastic rotor
        is then put back where its cable is just taut, at rest (a frictionless rotor on a slack cable would
        otherwise drift on, where a real motor's friction holds it)."""
        mujoco = self._mujoco
        perm = joint_permutation(mj, truth.joint_names)
        d.qpos[perm] = np.clip(d.qpos[perm], truth.lower, truth.upper)
        d.ctrl[:] = 0.0
        with passive_callback(self._passive):
            mujoco.mj_forward(mj, d)
            mujoco.mj_step(mj, d, nstep=int(round(SETTLE_S / mj.opt.timestep)))
        d.time = 0.0
        d.qpos[:] = initial_qpos(mj, truth, perm, d.qpos[perm].copy(), np.zeros(truth.transmission.n_motors), p, e)
        d.qvel[:] = 0.0
        mujoco.mj_forward(mj, d)

    @property
    def t(self) -> float:
        """The current tick's time, s."""
        return self._k * self.period

    def _measured_torque(self, applied: np.ndarray) -> np.ndarray:
        return self._torque.measure(applied, self._torque.std * self._rng.standard_normal(applied.shape))

    def _sense(self) -> Reading:
        """The reading at the current tick: the encoder's noise drawn, then the force's."""
        out = self._plant.output(self._k, {})
        q_m = np.asarray(out["q_m"], dtype=float)
        counts = self._encoder.measure(q_m, self._encoder.std * self._rng.standard_normal(q_m.shape))
        force: Any = math.nan
        if self.scene == "block":
            force = float(self._force.measure(out["F"], self._force.std * self._rng.standard_normal()))
        elif self.scene == "cylinder":
            F = np.asarray(out["F"], dtype=float)
            force = self._force.measure(F, self._force.std * self._rng.standard_normal(F.shape))
        return Reading(self.t, counts, self._torques[0].copy(), force)

    def read(self) -> Reading:
        """The sensors at the current tick (the same reading until the next :meth:`write`)."""
        r = self._reading
        return Reading(r.t, r.counts.copy(), r.torque.copy(), np.copy(r.force) if np.ndim(r.force) else r.force)

    def write(self, command: Sequence[float]) -> None:
        """Apply ``command`` over the current period: MuJoCo steps the period; the next tick's sensors are read.

        Parameters
        ----------
        command : sequence of float
            (m,) motor torques, N m, in [0, :attr:`tau_max`] ([-tau_max, tau_max] for :attr:`both_ways`:
            :func:`~alpes_dyn.bench.interface.check_command`).

        Raises
        ------
        InputError
            Naming ``command`` (or ``write`` once closed).
        ModelError
            MuJoCo diverged.
        """
        if self.closed:
            raise InputError("write: the MuJoCo stand-in is closed")
        u = check_command(command, len(self.motor_names), self.tau_max, self.both_ways)
        applied = u / self._gain if self._gain != 1.0 else u  # the driver's constant (1 + e) times the true one
        with passive_callback(self._passive):
            out = self._plant.update(self._k, {"tau": applied})
        if not np.isfinite(self._data.qpos).all():
            raise ModelError("the MuJoCo stand-in diverged (NaN in its state)")
        self._torques.append(self._measured_torque(np.asarray(out["tau"], dtype=float)))
        self._torques.popleft()
        self._k += 1
        self._reading = self._sense()

    def close(self) -> None:
        """Relax the hand (the motor's control at 0) and refuse further writes."""
        self._data.ctrl[:] = 0.0
        self.closed = True


def scoring_truth(hw: MujocoHand) -> tuple[np.ndarray, float]:
    """The stand-in's truth at its current tick: the joint angles (rad, (n,) in its model's joint order) and the
    contact force (N, MuJoCo's touch sensor without the FlexiForce's noise and quantisation; (5,) in the cylinder
    scene; NaN in the free scene).

    For the tests and benchmarks that score an estimate or a force loop (or check that no stop was reached) against
    the truth they drew; nothing that runs on a hand calls it (a real hand has no such reading). Raises
    :class:`~alpes_dyn.InputError` for anything but a :class:`MujocoHand`.

    Parameters
    ----------
    hw : MujocoHand
        The stand-in.

    Returns
    -------
    q : numpy.ndarray, shape (n,)
        The joint angles, rad.
    force : float or numpy.ndarray
        The contact force, N (a float in the block scene, (5,) in the cylinder scene, NaN in the free scene).
    """
    if not isinstance(hw, MujocoHand):
        raise InputError(f"hw: the truth is the MuJoCo stand-in's, got {type(hw).__name__}")
    force: Any = math.nan
    if hw.scene == "block":
        force = float(np.asarray(hw._plant.output(hw._k, {})["F"]).sum())
    elif hw.scene == "cylinder":
        force = np.asarray(hw._plant.output(hw._k, {})["F"], dtype=float).copy()
    return np.asarray(hw._data.qpos[hw._joints], dtype=float).copy(), force
