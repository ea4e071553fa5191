"""Encoder excursion: whether a recording moved each motor's encoder by more than its quantisation.

A motor of small pulley ratios turns little for a large joint swing: with ratios of 0.01 a swing of tens of degrees is
about 5 counts of a 4096-count encoder, and a fit to that recording sees mostly the encoder's steps. What decides is
the Fisher information of the selection (``alpes-dyn identifiability``); the encoder's excursion is its first-order
figure, read off the recording itself at no cost: the encoder's noise is fixed in counts (its quantisation, step /
sqrt(12), and the design's 0.5 count), while every parameter's signature in the reading scales with the motion, so a
parameter's standard error goes as 1 / excursion.

On a small finger whose encoder's counts per revolution are lowered to shrink its excursion (the 2-joint finger
of ``tests/test_urdf_identify.py``), a spring's standard error grows as the inverse of the excursion until, a few
tens of counts down, the fit loses its way and its springs come out far off. :data:`MIN_EXCURSION_COUNTS` lies in
that gap, below the excursion of the thumb's ab/adduction on the documented experiment (friction only, no spring)
and far below that of the Alpes fingers' flexion. :func:`small_excursions` names each motor below it
(:func:`~alpes_dyn.estimation.experiments.experiment.experiment` and
:func:`~alpes_dyn.estimation.experiments.experiment.model_experiment` warn with it, ``alpes-dyn experiment`` and
``identify`` print it); whether a selection is identified from a given experiment is the Fisher information's to say.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from ...errors import AlpesDynWarning, InputError

__all__ = ["MIN_EXCURSION_COUNTS", "SmallExcursionWarning", "encoder_excursions", "small_excursions",
           "excursion_report", "warn_small_excursions"]

MIN_EXCURSION_COUNTS = 30.0
"""Counts peak to peak below which a motor's recorded encoder is named (the module doc: between the excursions where
the fit still converged, with springs' standard errors of a few percent, and those where it did not)."""


class SmallExcursionWarning(AlpesDynWarning):
    """A recording moved a motor's encoder by fewer counts than :data:`MIN_EXCURSION_COUNTS` (one per motor)."""


def encoder_excursions(recording: Any) -> np.ndarray:
    """(m,) counts: each motor's encoder excursion, peak to peak over the recording (its ``encoder`` (N, m) in
    counts; samples that are not finite left out, NaN for a motor without any).

    Parameters
    ----------
    recording : Recording
        The recording (its ``encoder`` (N, m), counts, and ``motor_names``).

    Returns
    -------
    numpy.ndarray, shape (m,)
        The excursions, counts.

    Raises
    ------
    InputError
        ``recording`` has no encoder counts (N, motors).
    """
    enc = np.asarray(getattr(recording, "encoder", None), dtype=float)
    if enc.ndim != 2:
        raise InputError(f"recording: expected a Recording with encoder counts (N, motors), got "
                         f"{type(recording).__name__}")
    out = np.full(enc.shape[1], np.nan)
    for j in range(enc.shape[1]):  # a few motors: the columns, not the samples
        col = enc[np.isfinite(enc[:, j]), j]
        if col.size:
            out[j] = float(col.max() - col.min())
    return out


def small_excursions(recording: Any, threshold: float = MIN_EXCURSION_COUNTS) -> list[str]:
    """One line per motor whose encoder moved by less than ``threshold`` counts peak to peak over ``recording``,
    naming the motor, its excursion and what to change; empty when every encoder moved enough.

    Parameters
    ----------
    recording : Recording
        The recording (its ``encoder`` (N, m), counts, and ``motor_names``).
    threshold : float, optional
        The least excursion, counts peak to peak, >= 0 (default :data:`MIN_EXCURSION_COUNTS`).

    Returns
    -------
    list of str
        One line per motor below ``threshold``.

    Raises
    ------
    InputError
        ``threshold`` is not a number >= 0.
    """
    return _lines(recording, encoder_excursions(recording), threshold)


def _lines(recording: Any, ex: np.ndarray, threshold: float) -> list[str]:
    """:func:`small_excursions`' lines from the excursions ``ex`` (m,) of ``recording`` already computed."""
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) or not np.isfinite(threshold) \
            or threshold < 0:
        raise InputError(f"threshold: expected a number of counts >= 0, got {threshold!r}")
    names = list(getattr(recording, "motor_names", ())) or [str(j) for j in range(ex.size)]
    return [f"motor {name}: its encoder moved {e:g} counts peak to peak over the recording (below {threshold:g}): a "
            f"fit sees mostly its quantisation (standard errors grow as 1 / excursion); a larger pulley ratio, a finer "
            f"encoder or a wider swing moves it more" for name, e in zip(names, ex) if not e >= threshold]


def excursion_report(recording: Any, threshold: float = MIN_EXCURSION_COUNTS) -> dict[str, Any]:
    """What ``alpes-dyn experiment`` and ``identify`` print of ``recording``: ``encoder_excursion_counts`` (each
    motor's, by name), ``small_excursions`` (:func:`small_excursions`' lines) and ``min_excursion_counts``.

    Parameters
    ----------
    recording : Recording
        The recording (its ``encoder`` (N, m), counts, and ``motor_names``).
    threshold : float, optional
        The least excursion, counts peak to peak, >= 0 (default :data:`MIN_EXCURSION_COUNTS`).

    Returns
    -------
    dict
        ``encoder_excursion_counts``, ``small_excursions``, ``min_excursion_counts``.
    """
    ex = encoder_excursions(recording)
    lines = _lines(recording, ex, threshold)
    return {"encoder_excursion_counts": {str(n): None if not np.isfinite(e) else float(e)
                                         for n, e in zip(recording.motor_names, ex)},
            "small_excursions": lines, "min_excursion_counts": float(threshold)}


def warn_small_excursions(recording: Any, threshold: float = MIN_EXCURSION_COUNTS) -> list[str]:
    """:func:`small_excursions`, each line also issued as a :class:`SmallExcursionWarning`; returns the lines.

    Parameters
    ----------
    recording : Recording
        The recording (its ``encoder`` (N, m), counts, and ``motor_names``).
    threshold : float, optional
        The least excursion, counts peak to peak, >= 0 (default :data:`MIN_EXCURSION_COUNTS`).

    Returns
    -------
    list of str
        One line per motor below ``threshold``.

    Raises
    ------
    InputError
        ``threshold`` is not a number >= 0.
    """
    lines = small_excursions(recording, threshold)
    for line in lines:
        warnings.warn(SmallExcursionWarning(line), stacklevel=3)
    return lines
