"""The residual's power at the excitation's harmonics and intermodulation products: a model's nonlinearity
shaped otherwise than the plant's (issue 16).

A multisine excitation puts the torque on a few lines f_1 .. f_L (Hz). A plant that is linear about its
operating point answers on the same lines, and so does a model error that is linear; a nonlinearity the model
lacks or shapes otherwise -- dry friction reversing with the dither, a cable going slack, a dead band -- answers
also at the products a f_i + b f_j (|a| + |b| = 2 or 3: the second and third harmonics, sums and differences).
On MuJoCo's stick-slip finger fitted with the stick-slip law (``benchmarks/realism.py``, the hanging rig, seed
12), the residual's excess power sat at 3 x 20 Hz (the dither's third harmonic, 19 times the mean) and at 20 +
11.3 Hz (22 times): over every product, 2.0 times the power elsewhere, where white noise gives 0.83-1.11 (five
draws of the same length). :func:`harmonic_ratio` is that ratio; the adequacy check names the effect where it
is above :data:`~alpes_dyn.estimation.identification.adequacy.THRESHOLDS` ``harmonic_ratio``.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ...errors import InputError

__all__ = ["NONLINEARITY", "intermodulation", "harmonic_ratio"]

NONLINEARITY = ("a nonlinearity shaped otherwise than in the model (the residual's power at the excitation's "
                "harmonics and intermodulation products: dry friction at velocity reversals, a slack or dead-banded "
                "cable)")
"""The likely missing effect the adequacy check names where :func:`harmonic_ratio` is high."""


def intermodulation(lines: Sequence[float], nyquist: float, orders: Sequence[int] = (2, 3)) -> np.ndarray:
    """The products |a f_i + b f_j| (Hz) of the excitation's ``lines`` (Hz) whose order |a| + |b| is in
    ``orders`` (harmonics: i = j), below ``nyquist`` and above 0, not on a line, sorted, without repeats.

    Parameters
    ----------
    lines : Sequence[float]
        The excitation's frequencies, Hz (positive).
    nyquist : float
        The upper limit, Hz.
    orders : Sequence[int], optional
        The orders |a| + |b| kept, each at most 6 (|a|, |b| <= 3; default (2, 3)).

    Returns
    -------
    numpy.ndarray
        The products, Hz, sorted.

    Raises
    ------
    InputError
        Naming ``lines``: empty, not finite or not positive.
    """
    f = np.asarray(lines, dtype=float).ravel()
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise InputError(f"lines: expected positive frequencies in Hz, got {list(lines)!r}")
    a = np.arange(-3, 4)
    A, B = np.meshgrid(a, a, indexing="ij")
    keep = np.isin(np.abs(A) + np.abs(B), list(orders))
    prods = np.abs(A[keep][:, None, None] * f[None, :, None] + B[keep][:, None, None] * f[None, None, :])
    prods = np.unique(np.round(prods.ravel(), 9))
    on_line = np.any(np.abs(prods[:, None] - f[None, :]) < 1e-9, axis=1)
    return prods[(prods > 0) & (prods < nyquist) & ~on_line]


def harmonic_ratio(e: np.ndarray, lines: Sequence[float], dt: float, halfwidth: int = 1,
                   runs: Sequence[int] | None = None) -> float:
    """Mean periodogram power of the residual ``e`` ((N,) or (N, m), counts; sample time ``dt`` s) within
    ``halfwidth`` bins of the excitation's products (:func:`intermodulation`, two bins or more from a line and
    from 0 Hz), over its mean power at the other frequencies off the lines; per encoder, the largest. About 1
    for a white residual (its spread about 1/sqrt(number of bins)); large where the residual answers the
    excitation nonlinearly. 1.0 where the record is too short to hold both sets (fewer than 8 bins each).
    ``runs``: the first sample of each part whose excitation restarts, then N (the runs of a recording of several,
    :meth:`~alpes_dyn.estimation.experiments.recording.Recording.run_starts`; the orientations of a turned one,
    :func:`~alpes_dyn.estimation.experiments.recording.segment_starts`): the ratio of each part apart (no spectrum
    across a jump or a restart, whose jump spreads the lines' power over the products' bins), their mean weighted
    by the parts' lengths.

    Parameters
    ----------
    e : numpy.ndarray, shape (N,) or (N, m)
        The residual, counts.
    lines : Sequence[float]
        The excitation's frequencies, Hz.
    dt : float
        The sample time, s (> 0).
    halfwidth : int, optional
        The bins taken on each side of a product (default 1).
    runs : Sequence[int] or None, optional
        The first sample of each part whose excitation restarts, then N (default None: one part).

    Returns
    -------
    float
        The ratio (about 1 for a white residual).

    Raises
    ------
    InputError
        Naming ``dt`` or ``lines``.
    """
    e = np.asarray(e, dtype=float)
    e = e[:, None] if e.ndim == 1 else e
    if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
        raise InputError(f"dt: expected a positive time step in s, got {dt!r}")
    if runs is not None and len(runs) > 2:
        b = np.asarray(runs, dtype=int)
        ratios = [harmonic_ratio(e[a:z], lines, dt, halfwidth) for a, z in zip(b[:-1], b[1:])]  # (a few parts)
        return float(np.average(ratios, weights=np.diff(b)))
    n = e.shape[0]
    f = np.fft.rfftfreq(n, dt)
    df = f[1] if f.size > 1 else math.inf
    line_bins = np.rint(np.asarray(lines, dtype=float) / df).astype(int)
    near_line = np.zeros(f.size, dtype=bool)
    for k in line_bins:  # a loop over the excitation's lines (a few)
        near_line[max(k - 2, 0): k + 3] = True
    near_line[:3] = True
    prods = np.rint(intermodulation(lines, f[-1]) / df).astype(int)
    near = np.zeros(f.size, dtype=bool)
    for k in prods:  # a loop over the products (about a hundred)
        near[max(k - halfwidth, 0): k + halfwidth + 1] = True
    on, off = near & ~near_line, ~near & ~near_line
    if on.sum() < 8 or off.sum() < 8:
        return 1.0
    P = np.abs(np.fft.rfft(e - e.mean(axis=0), axis=0)) ** 2
    return float(np.max(P[on].mean(axis=0) / np.maximum(P[off].mean(axis=0), 1e-300)))
