"""The excitation's lines over a recording made of segments: the torque model's basis (errors in variables).

A multisine excitation puts the torque on a constant and a few lines f_1 .. f_L (Hz); the fit takes the true
torque to lie on them (:func:`~alpes_dyn.estimation.identification.shooting.torque_model`). A recording whose hand
was turned between two runs of the excitation (the palm up, then hung fingers down: piecewise-constant
``gravity_*`` columns, :class:`~alpes_dyn.estimation.experiments.design.ExperimentDesign`'s ``orientations``) holds
one multisine per orientation, each with its own bias, amplitudes and phases: one basis over the whole record
cannot hold them (the projection would deform the torque at each turn). :func:`line_basis` therefore gives each
segment its own block -- a constant, sin and cos of each line with the time from the segment's start -- zero
elsewhere; :func:`segment_starts` finds the segments from the gravity columns.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ...checks import as_float_array
from ...errors import InputError
from ..experiments.recording import MAX_SEGMENTS, segment_starts  # noqa: F401 (re-exported)

__all__ = ["MAX_SEGMENTS", "segment_starts", "line_basis"]

def line_basis(t: np.ndarray, frequencies: Sequence[float], starts: Sequence[int] | None = None) -> np.ndarray:
    """(N, k (2 n_f + 1)): per segment (``starts``, sample indices of :func:`segment_starts`; default one segment)
    1, sin(2 pi f (t - t_a)), cos(2 pi f (t - t_a)) for f in ``frequencies`` (Hz), t_a the segment's first time,
    zero outside the segment. InputError naming a segment too short for the lines (fewer than 4 samples per
    basis function)."""
    f = as_float_array(frequencies, "excitation", "frequencies in Hz").reshape(-1)
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise InputError(f"excitation: expected positive frequencies in Hz, got {frequencies!r}")
    t = np.asarray(t, dtype=float)
    fs = 1.0 / ((t[-1] - t[0]) / (t.shape[0] - 1))
    if np.any(f >= 0.5 * fs):
        raise InputError(f"excitation: frequencies must be below the Nyquist frequency {0.5 * fs:g} Hz")
    edges = np.append(np.asarray([0] if starts is None else starts, dtype=int), t.shape[0])
    width = 2 * f.size + 1
    Phi = np.zeros((t.shape[0], width * (edges.size - 1)))
    for i, (a, b) in enumerate(zip(edges[:-1], edges[1:])):  # a loop over the segments (a few)
        if width >= (b - a) // 4:
            where = "" if edges.size == 2 else f" in the segment from t = {t[a]:g} s (the gravity columns change there)"
            raise InputError(f"excitation: {f.size} frequencies are too many for {b - a} samples{where}")
        w = 2 * np.pi * f[None, :] * (t[a:b] - t[a])[:, None]
        Phi[a:b, i * width: (i + 1) * width] = np.hstack([np.ones((b - a, 1)), np.sin(w), np.cos(w)])
    return Phi
