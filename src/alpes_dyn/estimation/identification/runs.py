"""A recording of several runs in one fit (issue 39): each run its own initial state, the parameters shared.

A bench session records several excitation runs (the ``run`` column of
:class:`~alpes_dyn.estimation.experiments.recording.Recording`); between two runs the time may jump or restart and
the finger's state jumps. The multiple-shooting fit (:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`)
takes them as one problem whose intervals never straddle a run: every run starts on a shooting node, and the
continuity constraint into a run's first interval is cut (:attr:`~alpes_dyn.estimation.identification.kkt.Shape.cut`):
that node's state is free, as the record's first is. To lay the runs on the fit's regular grid of intervals of L
samples, each run but the last is cut to a whole number of intervals (:func:`aligned`: at most L - 1 samples of
each run's end, under one interval, 100 ms at the default, are not fitted). The torque's lines are each run's own
(:func:`~alpes_dyn.estimation.identification.torque_lines.torque_model`), the tendon's tension at a run's first sample
is under that sample's torque (no torque held before it), and the verdict's checks look at each run apart where
the order of the samples matters (the sensor floor's noise, :func:`encoder_noise`; the harmonics' spectrum).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ..experiments.recording import Recording

__all__ = ["aligned", "run_cuts", "split", "encoder_noise"]


def aligned(rec: Recording, L: int) -> Recording:
    """``rec`` with each run but the last cut to a whole number of intervals of ``L`` samples (its last samples
    dropped, fewer than L); ``rec`` itself where it is one run or already so.

    Parameters
    ----------
    rec : Recording
        The recording (one run or several).
    L : int
        The samples per shooting interval.

    Returns
    -------
    Recording
        The recording cut.

    Raises
    ------
    InputError
        Naming ``interval``: a run holds fewer than L samples (no whole interval).
    """
    b = rec.run_starts()
    if len(b) == 2:
        return rec
    n = np.diff(b)
    if np.any(n[:-1] < L) or n[-1] < 2:
        j = int(np.argmax(n < L))
        raise InputError(f"interval: {L} samples is longer than run {int(rec.run[b[j]])} ({int(n[j])} samples): "
                         "each run needs at least one whole shooting interval")
    keep = (n // L) * L
    keep[-1] = n[-1]
    if np.array_equal(keep, n):
        return rec
    return rec.take(np.concatenate([np.arange(a, a + k) for a, k in zip(b[:-1], keep)]))  # (a loop over the runs)


def run_cuts(rec: Recording, L: int, n_int: int) -> tuple[np.ndarray, np.ndarray]:
    """(cut (n_int - 1,) bool: interval j+1 starts a run; before (N+1,) int: the sample whose torque is held over
    the period before each sample, k - 1, or k itself at a run's first sample (its tension has seen no torque of
    that run before: :func:`~alpes_dyn.model.transmission.torque_before` within each run)) for ``rec`` cut into
    ``n_int`` intervals of ``L`` samples.

    Parameters
    ----------
    rec : Recording
        The recording (one run or several).
    L : int
        The samples per shooting interval.
    n_int : int
        The number of intervals.

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray]
        cut (n_int - 1,) bool and before (N+1,) int.

    Raises
    ------
    InputError
        Naming ``runs``: a run does not start on an interval (:func:`aligned` first).
    """
    b = rec.run_starts()
    starts = b[1:-1]
    if np.any(starts % L):
        raise InputError(f"runs: run {int(rec.run[starts[np.argmax(starts % L > 0)]])} does not start on a shooting "
                         f"node (every {L} samples): align the recording first (identification.runs.aligned)")
    cut = np.zeros(n_int - 1, dtype=bool)
    cut[starts // L - 1] = True
    before = np.maximum(np.arange(rec.n_samples) - 1, 0)
    before[starts] = starts
    return cut, before


def split(rec: Recording) -> list[Recording]:
    """The runs of ``rec``, each a :class:`~alpes_dyn.estimation.experiments.recording.Recording` of its own
    (without a ``run`` column); ``[rec]`` where it is one run.

    Parameters
    ----------
    rec : Recording
        The recording (one run or several).

    Returns
    -------
    list[Recording]
        Its runs, in order.
    """
    b = rec.run_starts()
    if len(b) == 2:
        return [rec]
    return [dataclasses.replace(rec.take(slice(a, z)), run=None) for a, z in zip(b[:-1], b[1:])]  # (a few runs)


def encoder_noise(rec: Recording, given: float | None) -> float | None:
    """The encoder's white noise beyond its quantisation, counts, for the sensor floor of a recording of several
    runs: ``given``, else estimated run by run (each run's fourth difference,
    :func:`~alpes_dyn.estimation.identification.adequacy.white_noise_level`: none across a jump between runs, which
    it would count as noise, setting the floor several times too high); None for one run (the floor's own
    estimate).

    Parameters
    ----------
    rec : Recording
        The recording (one run or several).
    given : float or None
        The noise given by the user, counts (None: estimated).

    Returns
    -------
    float or None
        The noise, counts.
    """
    from .adequacy import encoder_resolution, white_noise_level

    if given is not None or rec.n_runs == 1:
        return given
    b = rec.run_starts()
    n = np.diff(b) - 4  # fourth differences per run
    white2 = sum(k * white_noise_level(rec.encoder[a:z]) ** 2 for a, z, k in zip(b[:-1], b[1:], n)) / n.sum()
    quant = encoder_resolution(rec.encoder) / np.sqrt(12.0)
    return float(np.sqrt(max(float(np.mean(white2)) - quant**2, 0.0)))
