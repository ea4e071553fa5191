"""The identification experiment's slow stiction ramp (issue 50): after the excitation, in its last orientation and
the same run, ``stick_seconds`` of a slow, undithered triangle of the motor torque about the excitation's bias -- up
by the swing in a quarter, down by twice it in a half, back in a quarter -- through which the joints stick and slip
in turn. The excitation's dither keeps the joints sliding (on MuJoCo's stiff stick-slip finger3 at 3 x F_s, 0.6 %
of its samples stuck), where the smooth friction law predicts the encoder best; an observer that must hold a stuck
joint is judged where joints stick. The recording marks the ramp's samples ``held_out``
(:mod:`~alpes_dyn.estimation.experiments.held_out`): the fit leaves them out, ``identify``'s observer check and its
choice of the observer's friction law (:mod:`~alpes_dyn.estimation.identification.law_choice`) are judged on them.

The swing is ``stick_swing`` times each motor's breakaway torque (the largest F_s_j / |S_kj| of its joints, the
nominal file's, as the dither's: :func:`~alpes_dyn.estimation.experiments.multisine.dither_amplitude`; 8 by default,
as the realism study's validation ramp, ``alpes_dyn.studies.realism_friction.RAMP_TORQUE``), within the design's
limits: the torque within ``tau_max``, and the ramp run on the nominal finger keeping its joints ``margin`` inside
their ranges (the swing shrunk by 15 % until it does, as the multisine's amplitudes are); none on a motor of
springless joints (nothing but friction holds them, as for the dither). ``alpes-dyn experiment --rig auto`` checks
the whole record, the ramp's samples with the rest, on the finger as simulated.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from ...model.robot import Model
from .multisine import dither_amplitude

__all__ = ["RAMP_SHAPE", "STICK_SECONDS", "stick_swing", "stick_ramp", "held_out_rows", "with_ramp"]

RAMP_SHAPE: tuple[tuple[float, ...], tuple[float, ...]] = ((0.0, 0.25, 0.75, 1.0), (0.0, 1.0, -1.0, 0.0))
"""The ramp's triangle: (fractions of the ramp's time, multiples of the swing), linearly between."""

STICK_SECONDS = 6.0
"""s: the ramp's length advised where the joints' dry friction sticks (``alpes-dyn experiment --stick-seconds``,
whose default 0 records none; the realism study's
validation ramp's, ``alpes_dyn.studies.realism_friction.RAMP_SECONDS``: 1.3 mN m/s on finger3's nominal file, the
joints stick and slip in turn). :class:`~alpes_dyn.estimation.experiments.design.ExperimentDesign`'s own default is
0 (no ramp: a design built in code records what it did before)."""

SHRINKS = 30
"""The swing shrunk by 15 % at most this many times (to 0.8 % of it) to keep the joints in range."""


def stick_swing(model: Model, design: Any, bias: np.ndarray) -> np.ndarray:
    """Each motor's swing of the stiction ramp before the range check (module docstring), N m: ``stick_swing``
    breakaway torques, at most what ``tau_max`` leaves beyond ``bias``.

    Parameters
    ----------
    model : Model
        The finger the experiment is designed on (its F_s, N m, S and ``tau_max``).
    design : ExperimentDesign
        The design (its ``stick_swing``, times the breakaway torque).
    bias : numpy.ndarray, shape (m,)
        The torque the ramp swings about, N m.

    Returns
    -------
    numpy.ndarray, shape (m,)
        The swings, N m (0 on the motors of springless joints and without friction).
    """
    breakaway = dither_amplitude(model, dataclasses.replace(design, dither=1.0))
    swing = float(design.stick_swing) * breakaway
    if model.params is not None:
        swing = np.minimum(swing, np.maximum(float(model.params.tau_max) - np.abs(np.asarray(bias, dtype=float)), 0))
    return swing


def stick_ramp(model: Model, design: Any, bias: np.ndarray,
               in_range: Callable[[np.ndarray], bool] | None = None) -> np.ndarray:
    """The stiction ramp's motor torque, (``design.stick_samples``, m) N m: the triangle of :data:`RAMP_SHAPE` of
    :func:`stick_swing` about ``bias``, its last sample back at the bias, the swing shrunk by 15 % (at most
    :data:`SHRINKS` times) until ``in_range`` accepts it.

    Parameters
    ----------
    model : Model
        The finger the experiment is designed on.
    design : ExperimentDesign
        The design (``stick_seconds``, ``stick_swing``, ``dt``).
    bias : numpy.ndarray, shape (m,)
        The torque the ramp swings about (the last orientation's bias), N m.
    in_range : callable or None, optional
        ``in_range(u)``: whether the ramp's torque u (n, m) keeps the nominal finger's joints in range (default
        None: not checked).

    Returns
    -------
    numpy.ndarray, shape (design.stick_samples, m)
    """
    n = design.stick_samples
    if n == 0:
        return np.zeros((0, len(bias)))
    tri = np.interp(np.arange(1, n + 1) / max(n, 1), *RAMP_SHAPE)
    swing = stick_swing(model, design, bias)
    bias = np.asarray(bias, dtype=float)[None, :]
    for _ in range(SHRINKS):  # a few shrinks at most
        u = bias + tri[:, None] * swing[None, :]
        if in_range is None or in_range(u):
            return u
        swing = 0.85 * swing
    return bias + tri[:, None] * swing[None, :]


def held_out_rows(design: Any) -> np.ndarray:
    """(N+1 + ``design.stick_samples``,) bool: the samples of the recorded experiment that are the stiction ramp's,
    its recording's ``held_out`` column.

    Parameters
    ----------
    design : ExperimentDesign
        The design.

    Returns
    -------
    numpy.ndarray of bool
    """
    return np.concatenate([np.zeros(design.n_samples, bool), np.ones(design.stick_samples, bool)])


def with_ramp(design: Any, t: np.ndarray, seg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The excitation's sample times ``t`` (N+1,) s and orientation segments ``seg`` (N+1,) with the ramp's samples
    after them (in the last orientation): (times, segments, gravity (N+1+n, 3) m/s^2, :func:`held_out_rows`).

    Parameters
    ----------
    design : ExperimentDesign
        The design (``dt``, ``orientations``, ``stick_samples``).
    t : numpy.ndarray, shape (N+1,)
        The excitation's times, s.
    seg : numpy.ndarray of int, shape (N+1,)
        Its orientation per sample.

    Returns
    -------
    tuple of numpy.ndarray
    """
    n = design.stick_samples
    seg = np.concatenate([seg, np.full(n, seg[-1])]).astype(int)
    return (design.dt * np.arange(t.size + n), seg, np.asarray(design.orientations, dtype=float)[seg],
            held_out_rows(design))
