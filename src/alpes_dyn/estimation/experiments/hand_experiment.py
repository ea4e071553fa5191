"""The whole hand in one experiment (issue 35): the six motors excited at once, one recording, fitted chain by chain.

With the palm fixed the hand's chains do not move one another: its mass matrix, gravity and springs are block
diagonal by chain (:meth:`~alpes_dyn.model.robot.Model.alpes`'s ``"hand"``; each finger's tendon moves its own three
joints, the thumb's two motors its three), so the hand driven by its six motors at once is its five chains each
driven by its own, side by side. :func:`hand_experiment` runs each chain's identification experiment
(:func:`~alpes_dyn.estimation.experiments.adapt.adapted_experiment`: a finger as ``finger3`` with that finger's own
values, the thumb as ``thumb``) over the same time base in one orientation of the hand, each with its own sensor noise,
and writes them as one recording of the hand's six encoders and torques and its fifteen joints
(:func:`hand_recording`). The orientation is the hand's, not a chain's: ``rig="auto"`` keeps the palm up where
every chain stays inside its range there with the full excitation, else hangs the whole hand fingers down (each
chain's excitation then scaled down where it still leaves its range: per motor, which the hand allows).

:func:`chain_recording` cuts the hand's recording back into a chain's, named as the chain's model names its motors
and joints, for :func:`~alpes_dyn.estimation.identification.identification.identify`
(``alpes-dyn identify --model hand`` fits every chain from the one file and writes one parameter file).
"""

from __future__ import annotations

import dataclasses
import warnings
from pathlib import Path
from typing import Sequence

import numpy as np

from ...errors import InputError, RecordingError
from ...fileio import check_outputs
from ...model.hand_chains import hand_chains
from ...model.params import HandParams, load_params
from ...model.robot import Model
from .adapt import AMPLITUDE_SCALES, RIGS, Adaptation, adapted_experiment
from .design import ExperimentDesign
from .recording import Recording, write_recording

__all__ = ["hand_chains", "chain_model_name", "chain_names", "chain_recording", "hand_recording", "hand_experiment"]


def chain_model_name(chain: str) -> str:
    """The one-chain model a chain of the hand is fitted as: ``"thumb"``, or ``"finger3"`` for a finger.

    Parameters
    ----------
    chain : str
        The hand's chain: a finger's name or ``"thumb"``.

    Returns
    -------
    str
    """
    return "thumb" if chain == "thumb" else "finger3"


def chain_names(chain: str) -> tuple[dict[str, str], dict[str, str]]:
    """(motor, joint) renamings from the chain's model to the hand's: a finger's ``finger`` -> ``<name>``, ``j1`` ->
    ``<name>_j1``...; the thumb's names are the hand's.

    Parameters
    ----------
    chain : str
        The hand's chain: a finger's name or ``"thumb"``.

    Returns
    -------
    motors : dict of str to str
        The model's motor name -> the hand's.
    joints : dict of str to str
        The model's joint name -> the hand's.
    """
    if chain == "thumb":
        return ({"thumb": "thumb", "thumb_abduction": "thumb_abduction"},
                {j: j for j in ("thumb_abd", "thumb_j1", "thumb_j2")})
    return {"finger": chain}, {f"j{i}": f"{chain}_j{i}" for i in (1, 2, 3)}


def _columns(rec: Recording, names: Sequence[str], wanted: Sequence[str], what: str) -> np.ndarray:
    index = {n: i for i, n in enumerate(names)}
    missing = [w for w in wanted if w not in index]
    if missing:
        raise RecordingError(f"recording: no {what} {', '.join(missing)} (a recording of the whole hand has "
                             f"{', '.join(names)})")
    return np.array([index[w] for w in wanted], dtype=int)


def chain_recording(rec: Recording, chain: str) -> Recording:
    """The columns of ``chain`` (a finger's name or ``"thumb"``) of a recording of the whole hand, named as the
    chain's model (:func:`chain_model_name`) names its motors and joints. The time base, the gravity columns (the
    hand's orientation, the same for every chain) and the true angles, where recorded, come along.

    Parameters
    ----------
    rec : Recording
        The recording of the whole hand.
    chain : str
        The chain: a finger's name or ``"thumb"``.

    Returns
    -------
    Recording
        The chain's columns.

    Raises
    ------
    RecordingError
        The recording lacks a motor or joint of the chain.
    """
    motors, joints = chain_names(chain)
    mi = _columns(rec, rec.motor_names, list(motors.values()), "motor")
    ji = _columns(rec, rec.joint_names, list(joints.values()), "joint")
    pick = (lambda a: None if a is None else a[:, ji].copy())
    return Recording(t=rec.t.copy(), encoder=rec.encoder[:, mi].copy(), torque=rec.torque[:, mi].copy(),
                     motor_names=tuple(motors), joint_names=tuple(joints), q=pick(rec.q),
                     gravity=None if rec.gravity is None else rec.gravity.copy(), true_q=pick(rec.true_q),
                     run=None if rec.run is None else rec.run.copy())


def hand_recording(chains: dict[str, Recording], hand: Model) -> Recording:
    """One recording of the whole ``hand`` from its chains' (``chains``: chain -> recording named as its model names
    it, :func:`chain_names`), in the hand's motor and joint order. Raises :class:`~alpes_dyn.errors.RecordingError`
    where the chains' time bases or orientations differ, or a chain of the hand is missing.

    Parameters
    ----------
    chains : dict of str to Recording
        Chain -> its recording, named as its model names it (:func:`chain_names`).
    hand : Model
        The whole hand (its motor and joint order).

    Returns
    -------
    Recording
    """
    t0 = next(iter(chains.values())).t
    enc = np.zeros((t0.size, len(hand.motor_names)))
    tau = np.zeros_like(enc)
    true_q = np.zeros((t0.size, hand.n))
    have_true = all(r.true_q is not None for r in chains.values())
    g0 = next(iter(chains.values())).gravity
    done_m, done_j = set(), set()
    for chain, rec in chains.items():
        if rec.t.shape != t0.shape or not np.array_equal(rec.t, t0):
            raise RecordingError(f"{chain}: its time base differs from the other chains' (one recording of the hand)")
        if (rec.gravity is None) != (g0 is None) or (g0 is not None and not np.array_equal(rec.gravity, g0)):
            raise RecordingError(f"{chain}: its orientation differs from the other chains' (one hand, one rig)")
        motors, joints = chain_names(chain)
        for k, mn in enumerate(rec.motor_names):
            i = hand.motor_names.index(motors[mn])
            enc[:, i], tau[:, i] = rec.encoder[:, k], rec.torque[:, k]
            done_m.add(motors[mn])
        for k, jn in enumerate(rec.joint_names):
            if have_true:
                true_q[:, hand.joint_index(joints[jn])] = rec.true_q[:, k]
            done_j.add(joints[jn])
    missing = [m for m in hand.motor_names if m not in done_m]
    if missing:
        raise RecordingError(f"hand recording: no chain drives {', '.join(missing)}")
    return Recording(t=t0.copy(), encoder=enc, torque=tau, motor_names=tuple(hand.motor_names),
                     joint_names=tuple(hand.joint_names), gravity=None if g0 is None else g0.copy(),
                     true_q=true_q if have_true else None)


def _chain_seeds(seed: int, n: int) -> list[int]:
    """``n`` independent sensor-noise seeds from one (each chain's encoders and torques its own noise)."""
    return [int(s) for s in np.random.SeedSequence(seed).generate_state(n, dtype=np.uint64) >> np.uint64(1)]


def hand_experiment(true_params: HandParams | str | Path | None = None, design: ExperimentDesign | None = None,
                    seed: int = 0, path: str | Path | None = None,
                    nominal_params: HandParams | str | Path | None = None,
                    rig: str = "auto") -> tuple[Recording, dict[str, Adaptation]]:
    """The identification experiment of the whole hand (the module docstring): every chain's, at once, in one
    orientation.

    Parameters
    ----------
    true_params : HandParams or str or Path or None, optional
        The hand as it is (each chain its own values), or its file.
    design : ~alpes_dyn.estimation.experiments.design.ExperimentDesign or None, optional
        Each chain's design (default: the documented one).
    seed : int, optional
        The sensor noise's seed (each chain's drawn from it).
    path : str or Path or None, optional
        Where to write the recording as CSV too.
    nominal_params : HandParams or str or Path or None, optional
        What the experimenter knows (default: the shipped file).
    rig : str, optional
        One of :data:`~alpes_dyn.estimation.experiments.adapt.RIGS`.

    Returns
    -------
    tuple of (Recording, dict)
        The recording of the six motors and each chain's :class:`~alpes_dyn.estimation.experiments.adapt.Adaptation`.
    """
    if rig not in RIGS:
        raise InputError(f"rig: expected one of {', '.join(RIGS)}, got {rig!r:.40}")
    if path is not None:
        check_outputs([("path", path)], [(name, f) for name, f in (("true_params", true_params),
                                                                   ("nominal_params", nominal_params))
                                         if isinstance(f, (str, Path))])
    p_true = true_params if isinstance(true_params, HandParams) else load_params(true_params)
    p_nom = nominal_params if isinstance(nominal_params, HandParams) else load_params(nominal_params)
    chains = hand_chains(p_nom)
    seeds = _chain_seeds(seed, len(chains))
    plans = [("level", ()), ("hanging", AMPLITUDE_SCALES)] if rig == "auto" else [(rig, AMPLITUDE_SCALES)]
    for k, (r, scales) in enumerate(plans):
        recs, how = {}, {}
        with warnings.catch_warnings(record=True) as caught:  # a plan given up says nothing
            warnings.simplefilter("always")
            for chain, s in zip(chains, seeds):
                recs[chain], how[chain] = adapted_experiment(
                    chain_model_name(chain), p_true, design, seed=s, nominal_params=p_nom,
                    chain=None if chain == "thumb" else chain, rig=r, scales=scales)
        if k == len(plans) - 1 or all(a.excess_deg == 0.0 for a in how.values()):
            break
        out = [c for c, a in how.items() if a.excess_deg > 0.0]  # the chains that make the whole hand hang
    if k > 0:
        why = f"the whole hand hung fingers down (as --rig hanging): palm up {', '.join(out)} left its range"
        how = {c: dataclasses.replace(a, note=why + (f"; {a.note}" if a.note else "")) for c, a in how.items()}
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    rec = hand_recording(recs, Model.alpes("hand", params=p_nom))
    if path is not None:
        write_recording(rec, path)
    return rec, how
