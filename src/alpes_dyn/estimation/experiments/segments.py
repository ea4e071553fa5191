"""The parts of a recording whose excitation restarts: its orientation segments (gravity columns that change a few
times: ``alpes-dyn experiment --rig both``) and its runs. Read by the fit (each part on its own lines), the
harmonics and the observer's check."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["MAX_SEGMENTS", "segment_starts", "excitation_parts"]


MAX_SEGMENTS = 16
"""At most this many orientation segments: gravity columns that change more often are a hand moving through its
orientations (an IMU's reading), one segment, the lines over the whole record."""


def segment_starts(gravity: np.ndarray | None) -> np.ndarray:
    """Sample indices (k,) where a segment of constant gravity starts, 0 first: each row of ``gravity`` (N+1, 3),
    m/s^2, that differs from the row before, where there are at most :data:`MAX_SEGMENTS` segments; [0] without
    gravity columns or where they change more often.

    Parameters
    ----------
    gravity : numpy.ndarray, shape (N+1, 3), or None
        The recording's gravity columns, m/s^2.

    Returns
    -------
    numpy.ndarray of int, shape (k,)
    """
    if gravity is None:
        return np.zeros(1, dtype=int)
    G = np.asarray(gravity, dtype=float)
    change = np.flatnonzero(np.any(G[1:] != G[:-1], axis=1)) + 1
    if change.size == 0 or change.size >= MAX_SEGMENTS:
        return np.zeros(1, dtype=int)
    return np.concatenate([[0], change])


def excitation_parts(rec: Any) -> np.ndarray:
    """(k+1,) the first sample of each part of ``rec`` whose excitation restarts -- each run
    (:meth:`~alpes_dyn.estimation.experiments.recording.Recording.run_starts`) and, within a run, each orientation of
    a hand turned between runs of the excitation (:func:`segment_starts`: ``alpes-dyn experiment --rig both``) --
    then the number of samples. The fit takes each part on its own lines, the harmonics and the observer's check
    part by part.

    Parameters
    ----------
    rec : Recording
        The recording.

    Returns
    -------
    numpy.ndarray of int, shape (k+1,)
    """
    return np.union1d(rec.run_starts(), segment_starts(rec.gravity)).astype(int)

