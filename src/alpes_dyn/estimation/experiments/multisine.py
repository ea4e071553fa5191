"""The experiment's torque signals: each motor's multisine and the dither on it
(:mod:`alpes_dyn.estimation.experiments.experiment` designs their bias and amplitudes).

The multisine: tau_b + a sum_i sin(2 pi f_i t + phi_i) / sqrt(n_f / 2) over the design's ``frequencies`` (Schroeder
phases, shifted between the motors of one chain); the dither: a sine at ``dither_frequency`` of
:func:`dither_amplitude` (``dither`` times the breakaway torque of the motor's joints; none on the motors of
springless joints).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...model.robot import Model

ExperimentDesign = Any  # alpes_dyn.estimation.experiments.experiment.ExperimentDesign (which imports this module)

__all__ = ["dither_amplitude"]


def _motor_groups(model: Model) -> tuple[list[np.ndarray], list[int], list[int]]:
    """Each motor's joints, the motors whose joints all have springs (a tendon against its return springs) and
    the others (a motor driving springless joints both ways, held at mid-range by its bias)."""
    S = model.transmission.S
    held = {model.joint_index(j) for j in model.springless_joints}
    joints = [np.flatnonzero(S[k]) for k in range(S.shape[0])]
    sprung = [k for k, js in enumerate(joints) if not held.intersection(js.tolist())]
    return joints, sprung, [k for k in range(S.shape[0]) if k not in sprung]


def _profile(design: ExperimentDesign, t: np.ndarray, bias: float, amp: float, motor: int = 0,
             n_motors: int = 1, dither: float = 0.0) -> np.ndarray:
    """One motor's multisine (len(t),), N m: Schroeder phases (a low crest factor), shifted by pi k i / m on
    line i for motor k of m (the motors of one chain excited at once, out of phase); plus the dither, ``dither``
    N m at ``design.dither_frequency`` (shifted by pi k / m)."""
    f = np.asarray(design.frequencies, dtype=float)
    k = np.arange(1, f.size + 1)
    phases = -np.pi * k * (k - 1) / f.size - np.pi * motor * k / n_motors
    s = np.sin(2 * np.pi * f[None, :] * t[:, None] + phases[None, :]).sum(axis=1)
    out = bias + amp * s / math.sqrt(f.size / 2)
    if dither:
        out = out + dither * np.sin(2 * np.pi * design.dither_frequency * t + np.pi * motor / n_motors)
    return out


def _profiles(design: ExperimentDesign, t: np.ndarray, bias: np.ndarray, amp: np.ndarray,
              dither: np.ndarray | None = None) -> np.ndarray:
    """(len(t), m): every motor's multisine, with its dither amplitude ``dither`` (m,), N m (default none)."""
    m = len(bias)
    d = np.zeros(m) if dither is None else np.asarray(dither, dtype=float)
    return np.column_stack([_profile(design, t, float(bias[k]), float(amp[k]), k, m, float(d[k])) for k in range(m)])


def dither_amplitude(model: Model, design: ExperimentDesign) -> np.ndarray:
    """The dither's amplitude per motor (m,), N m: ``design.dither`` times the largest breakaway torque of the
    motor's joints, max_j F_s_j / |S_kj| (their dry friction seen at the motor; the model's F_s, the nominal one
    for a designed experiment), so that every joint keeps sliding through its friction; 0 without friction.

    Why a dither: on a plant with stick-slip friction (MuJoCo's finger3, ``benchmarks/realism.py``) the multisine
    alone leaves the distal joint stuck for a large share of the samples, where no memoryless friction law matches
    it, and the fit's springs and the EKF on its file come out off. A fast dither of several breakaway torques keeps
    every joint sliding: a smaller amplitude or a lower frequency leaves the joint stuck longer, a larger one needs
    the multisine's share of the range lowered (``amplitude_fraction``) so that the finger's range holds the swing.
    The fits on such plants with the default design: ``benchmarks/results/realism.json`` (its summary).

    Not on a motor of springless joints (the thumb's ab/adduction; 0 there): nothing but their dry friction holds
    them where the design places them, and a dither that keeps them sliding lets any torque the design did not
    balance (a palm slightly tilted: a gravity torque below the joint's breakaway torque) carry them away onto a
    stop, and the fit with them does not converge.

    Parameters
    ----------
    model : Model
        The finger (its F_s, N m, and S).
    design : ExperimentDesign
        The design (its ``dither``, times the breakaway torque).

    Returns
    -------
    numpy.ndarray, shape (m,)
        The amplitudes, N m.
    """
    joints, _, free = _motor_groups(model)
    S = model.transmission.S
    out = np.zeros(S.shape[0])
    if design.dither <= 0:
        return out
    for k, js in enumerate(joints):
        if js.size and k not in free:
            out[k] = design.dither * float(np.max(model.extras.coulomb[js] / np.abs(S[k, js])))
    return out
