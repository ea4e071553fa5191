"""The recorded torque as the observer reads it: read earlier by the torque sensor's lag (:func:`advanced`, a delay
``identify`` fits), averaged over a few samples for the laws that decide stick or slip from it (:func:`averaged`,
:func:`default_torque_window`). :func:`~alpes_dyn.estimation.observers.replay.estimate_recording` and ``identify``'s
observer check read every recording through them."""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ...model.robot import Model
from ..experiments.recording import Recording

__all__ = ["MAX_DELAY", "advanced", "STICK_TORQUE_WINDOW", "averaged", "default_torque_window"]

MAX_DELAY = 100
"""The longest torque delay taken, samples (0.1 s at 1 kHz: beyond, it is a wrong clock, not a filter)."""


def advanced(recording: Recording, samples: int) -> Recording:
    """``recording`` with its torque read ``samples`` whole samples earlier: row k of the torque is row k + samples
    of the recorded one, the last ``samples`` rows repeat the last (the applied torque of a sensor that lags by
    ``samples``: :class:`~alpes_dyn.bench.effects.PlantEffects` ``torque_delay``), run by run where the recording
    has several. The recording itself for 0.

    Parameters
    ----------
    recording : Recording
        The recording.
    samples : int
        The torque sensor's lag, whole samples from 0 to :data:`MAX_DELAY`.

    Returns
    -------
    Recording
        A copy with the torque advanced (``recording`` itself for 0).

    Raises
    ------
    InputError
        ``torque_delay``: ``samples`` not a whole number in range, or not fewer than the recording's samples.
    """
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 0 <= samples <= MAX_DELAY:
        raise InputError(f"torque_delay: expected a whole number of samples from 0 to {MAX_DELAY}, got {samples!r}")
    if samples == 0:
        return recording
    if samples >= recording.n_samples:
        raise InputError(f"torque_delay: {samples} samples, the recording has {recording.n_samples}")
    b = recording.run_starts()  # a recording of several runs: each run's own torque, its last rows repeating its last
    last = np.repeat(b[1:] - 1, np.diff(b))
    tau = recording.torque[np.minimum(np.arange(recording.n_samples) + samples, last)]
    return dataclasses.replace(recording, torque=tau)

STICK_TORQUE_WINDOW = 10
"""Samples of the causal moving average of the recorded torque that the ``stick`` and ``lugre`` laws' observers
read by default (:func:`averaged`): the law decides stick or slip from the torque, and a white torque noise as large
as F_s (0.5 mN m on the Alpes finger) makes it slip where the joint holds (the LuGre bristle creeps under a torque
that jitters, and the estimate drifts several times further off than with the torque averaged); averaged over
10 samples (10 ms at 1 kHz) its noise is about a third, for a lag of 4.5 samples on a motion of a few hertz."""


def averaged(recording: Recording, samples: int) -> Recording:
    """``recording`` with its torque replaced by the causal moving average of its last ``samples`` rows (before the
    recording, the mean of its first ``samples`` rows: the hand at rest when it starts, the observer's first rest
    state found under that mean): what the observer reads, its white noise divided by sqrt(``samples``). The
    recording itself for 1.

    Parameters
    ----------
    recording : Recording
        The recording.
    samples : int
        The window of the moving average, whole samples from 1 to :data:`MAX_DELAY`.

    Returns
    -------
    Recording
        A copy with the torque averaged (``recording`` itself for 1).

    Raises
    ------
    InputError
        ``torque_window``: ``samples`` not a whole number in range.
    """
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or not 1 <= samples <= MAX_DELAY:
        raise InputError(f"torque_window: expected a whole number of samples from 1 to {MAX_DELAY}, got {samples!r}")
    if samples == 1:
        return recording
    tau = recording.torque
    padded = np.concatenate([np.repeat(tau[:samples].mean(axis=0, keepdims=True), samples, axis=0), tau])
    c = np.cumsum(padded, axis=0)
    return dataclasses.replace(recording, torque=(c[samples:] - c[:-samples]) / samples)


def default_torque_window(model: Model, friction_law: str) -> int:
    """The window of :func:`averaged` by default: 1 where ``model``'s file holds ``friction.observer_law`` (its
    law and model error chosen by ``identify``'s check on the torque as recorded), else :data:`STICK_TORQUE_WINDOW`
    with the stick and LuGre laws, 1 with the smooth law.

    Parameters
    ----------
    model : Model
        The observer's model (its parameter file's ``friction.observer_law``).
    friction_law : str
        The observer's law, one of :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`.

    Returns
    -------
    int
        The window, samples.
    """
    if getattr(model.params, "observer_law", None) is not None:
        return 1
    return STICK_TORQUE_WINDOW if friction_law in ("stick", "lugre") else 1
