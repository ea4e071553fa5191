"""The grasp's calibration on the plant: the force each chain of the hand holds on the cylinder before it slides
(:func:`grasp_limits`), the references kept under it (:func:`grasp_levels`), and the sensorless force's one-point
calibration against the fingertip sensor (:func:`force_scale_of`).

Runs of :func:`run_hand_control` (and of
:func:`~alpes_dyn.control.finger_loop.run_control`) read back; one concept: what a run on the plant says of the
levels and the force scale to use.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import InputError
from .finger_loop import ControlResult
from .hand_loop import HAND_LEVELS, HandControlResult, HandControlScenario, run_hand_control

__all__ = ["GRASP_PROBE_TOP", "GRASP_PROBE_RAMP_S", "GRASP_MARGIN", "grasp_limits", "grasp_levels", "force_scale_of"]

#: :func:`grasp_limits`' ramp: each chain's reference from its first level of :data:`HAND_LEVELS` to
#: ``GRASP_PROBE_TOP`` times its second, over ``GRASP_PROBE_RAMP_S`` s (0.25-0.45 N/s on the fingers).
GRASP_PROBE_TOP, GRASP_PROBE_RAMP_S = 2.5, 2.0
#: :func:`grasp_levels`: the references kept under this fraction of the force a chain holds.
GRASP_MARGIN = 0.8


def grasp_limits(params: Any = None, plant_params: Any = None, effects: Any = None, compensation: Any = None,
                 seed: int = 0) -> dict[str, float]:
    """The force (N) each chain's pad holds on the cylinder before it slides around it, measured on the plant:
    the sensor loops of :func:`run_hand_control` (controller's parameters ``params``, the plant's
    ``plant_params``, ``effects``, ``compensation``, ``seed``) with each reference ramped from its first level
    of :data:`HAND_LEVELS` to :data:`GRASP_PROBE_TOP` times its second over :data:`GRASP_PROBE_RAMP_S` s; a chain's
    limit is the reference where its MuJoCo force (mean over 20 ms) first leaves 20 % of it on the ramp (the
    largest force the loop held; not the force's own peak, which the pad's slip can spike), the ramp's top where
    it never does.

    The cylinder is frictionless: a pad holds it only while the finger's springs and the tendon keep the contact
    normal within the pad, which depends on the finger's stiffness -- a hand drawn +-20 % per spring can let go
    below :data:`HAND_LEVELS` (an index finger of ``benchmarks/hand_control.py``'s draws at 0.3-0.4 N, the nominal
    hand's above them). What an experimenter does on the real hand with its FlexiForce sensors: one 4.8 s run.

    Parameters
    ----------
    params : HandParams, str or pathlib.Path, optional
        The controller's parameters (default: the shipped file), as :func:`run_hand_control` takes them.
    plant_params : HandParams, str or pathlib.Path, optional
        The plant's (MuJoCo's) parameters (default: the controller's).
    effects : PlantEffects, optional
        A real hand's effects on the plant (:class:`~alpes_dyn.bench.effects.PlantEffects`, e.g.
        :func:`~alpes_dyn.bench.effects.real_hand_effects`), as :func:`run_hand_control` takes them; default none.
    compensation : Compensation, optional
        What the controller compensates of them (:class:`~alpes_dyn.control.realism_loop.Compensation`).
    seed : int
        The sensors' noise draw (default 0).

    Returns
    -------
    dict of str to float
        The force each chain holds, N, by chain name.

    Raises
    ------
    InputError
        What :func:`run_hand_control` refuses of the arguments.
    """
    lv = {c: (a, GRASP_PROBE_TOP * b) for c, (a, b) in HAND_LEVELS.items()}
    sc = HandControlScenario(duration=HandControlScenario.step_time + GRASP_PROBE_RAMP_S + 0.25,
                             ramp_s=GRASP_PROBE_RAMP_S)
    res = run_hand_control("sensor", sc, levels=lv, params=params, plant_params=plant_params, effects=effects,
                           compensation=compensation, seed=seed)
    out = {}
    for c, r in res.chains.items():
        w = max(1, int(round(0.02 / sc.dt)))
        F = np.convolve(r.F_true, np.ones(w) / w, mode="same")
        left = np.nonzero((r.t >= sc.step_time) & (np.abs(F - r.F_ref) > 0.2 * r.F_ref))[0]
        out[c] = float(r.F_ref[left[0]]) if left.size else float(r.F_ref[-1])
    return out


def grasp_levels(limits: dict[str, float], margin: float = GRASP_MARGIN) -> dict[str, tuple[float, float]]:
    """The grasp scene's references for a hand: :data:`HAND_LEVELS`, a chain's two levels scaled down together where
    its second is above ``margin`` times what the chain holds.

    Parameters
    ----------
    limits : dict of str to float
        The force each chain holds, N, by chain name (:func:`grasp_limits`): one for every chain of
        :data:`HAND_LEVELS`.
    margin : float
        The fraction of its limit a chain's references stay under (default :data:`GRASP_MARGIN`).

    Returns
    -------
    dict of str to (float, float)
        (before, after) the step, N, by chain name.

    Raises
    ------
    InputError
        A chain missing from ``limits`` or its force not a positive finite number.
    """
    out = {}
    for c, (a, b) in HAND_LEVELS.items():
        if c not in limits or not (isinstance(limits[c], (int, float)) and math.isfinite(limits[c])
                                   and limits[c] > 0):
            raise InputError(f"limits: expected a positive force (N) for chain {c!r}, got {limits.get(c)!r}")
        s = min(1.0, margin * float(limits[c]) / b)
        out[c] = (a * s, b * s)
    return out


def force_scale_of(result: ControlResult | HandControlResult, previous: Any = 1.0) -> float | dict[str, float]:
    """The one-point calibration of the sensorless force against the fingertip sensor: from a ``sensorless`` run
    (:func:`~alpes_dyn.control.finger_loop.run_control`, or :func:`run_hand_control`: per chain), the mean force the
    loop estimated over the last 200 ms of its first level over the mean the FlexiForce read there, times
    ``previous`` (the :attr:`~alpes_dyn.control.realism_loop.Compensation.force_scale` the run had): the
    ``force_scale`` that makes the estimate read what the sensor reads. What it corrects is the torque constant's
    error (the estimate is the motor current through it, which the encoder cannot see: an identification scales
    every torque parameter with it, and the estimate with them by 1 + e) and whatever else is proportional to the
    force; it carries over the sensor's own accuracy (the plant's FlexiForce is noise and resolution only).

    Parameters
    ----------
    result : ControlResult or HandControlResult
        A ``sensorless`` run.
    previous : float or dict of str to float
        The ``force_scale`` the run had (default 1; per chain for a hand's run, a missing chain 1).

    Returns
    -------
    float or dict of str to float
        The new ``force_scale`` (per chain for a hand's run), within 0.5-2.

    Raises
    ------
    InputError
        A run of another controller, a sensor reading under 0.02 N before the step (no contact), or a ratio
        beyond 0.5-2 (the model is off).
    """
    def one(r: ControlResult, prev: float) -> float:
        sc = r.scenario
        if sc.controller != "sensorless":
            raise InputError(f"result: the calibration reads a sensorless run, got {sc.controller!r}")
        t1 = sc.step_times[0]
        k = (r.t >= t1 - 0.2) & (r.t < t1)
        F_s = float(np.mean(r.F_meas[k]))
        if not F_s > 0.02:
            raise InputError(f"result: the fingertip sensor reads {F_s:.3g} N before the step: no contact to "
                             "calibrate on")
        s = prev * float(np.mean(r.F_hat[k])) / F_s
        if not 0.5 <= s <= 2.0:
            raise InputError(f"result: the estimate reads {s:.3g} times the fingertip sensor: beyond a scale to "
                             "calibrate (0.5-2), the model is off")
        return s

    if isinstance(result, HandControlResult):
        return {c: one(r, float(previous.get(c, 1.0)) if isinstance(previous, dict) else float(previous))
                for c, r in result.chains.items()}
    return one(result, float(previous))
