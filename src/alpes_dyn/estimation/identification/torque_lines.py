"""How the shooting fit (:mod:`alpes_dyn.estimation.identification.shooting`) takes the recorded torque: as it is, or
projected on the excitation's lines with the projection's error fitted (errors in variables).

A recording of several runs (its ``run`` column, :class:`~alpes_dyn.estimation.experiments.recording.Recording`),
or turned between orientations (``alpes-dyn experiment --rig both``: each orientation its own run of the
excitation, its own bias, amplitudes and phases), is projected part by part
(:func:`~alpes_dyn.estimation.experiments.recording.excitation_parts`): each run on its own lines, their time from the run's own first sample, each run's
correction its own coefficients (the basis block-diagonal over the runs, held compact: each sample's row of its
own run's block, :attr:`TorqueModel.blocks` of them). Neither the excitation's phase nor the noise's projection
carries from one run to the next: a run may restart the excitation or start another.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ...checks import as_float_array
from ...errors import InputError
from ..experiments.recording import Recording, segment_starts

__all__ = ["TorqueModel", "torque_model", "line_basis", "CHOLESKY_QR_ROWS"]


def line_basis(t: np.ndarray, frequencies: Sequence[float], starts: Sequence[int] | None = None) -> np.ndarray:
    """(N, k (2 n_f + 1)): per segment (``starts``, sample indices of :func:`segment_starts`; default one segment)
    1, sin(2 pi f (t - t_a)), cos(2 pi f (t - t_a)) for f in ``frequencies`` (Hz), t_a the segment's first time,
    zero outside the segment.

    Parameters
    ----------
    t : numpy.ndarray, shape (N,)
        The sample times, s (evenly spaced).
    frequencies : Sequence[float]
        The excitation's lines, Hz (positive, below the Nyquist frequency).
    starts : Sequence[int] or None, optional
        The segments' first samples (default None: one segment).

    Returns
    -------
    numpy.ndarray, shape (N, k (2 n_f + 1))
        The basis, k the number of segments.

    Raises
    ------
    InputError
        Naming ``excitation``: frequencies not positive or not below the Nyquist frequency, or a segment too
        short for the lines (fewer than 4 samples per basis function).
    """
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


@dataclass
class TorqueModel:
    """How the fit takes the recorded torque (errors in variables). ``U`` (N, nu): the torque at the held samples
    (projected on the excitation's lines, or as recorded), ``U_last`` (1, nu) at the last sample; ``noise``:
    sigma_u, N m; with the lines (``lines``), ``Q`` (N, nphi) their orthonormal basis and ``Q_last`` (nphi,) at the
    last sample: the true torque is U + sigma_u Q c, c ~ N(0, I) fitted; without them and sigma_u > 0, a constant
    correction per interval (``eiv`` and not ``lines``). A :class:`ShootingProblem` keeps its own copy without
    ``Q`` (None: the basis lives on there, scaled and cut at the intervals; 91 MB at 600 s). ``blocks``: the runs
    whose lines are their own (a recording of several runs): ``Q``'s row k is the basis of sample k's run, the
    coefficients c those of every run in turn (:attr:`nlines` per motor)."""

    U: np.ndarray
    U_last: np.ndarray
    noise: float
    Q: np.ndarray | None = None
    Q_last: np.ndarray | None = None
    blocks: int = 1

    @property
    def eiv(self) -> bool:
        """The torque is corrected (errors in variables): sigma_u > 0."""
        return self.noise > 0

    @property
    def lines(self) -> bool:
        """The correction lies on the excitation's lines."""
        return self.eiv and self.Q_last is not None

    @property
    def nphi(self) -> int:
        """Number of basis functions of the lines (0 without them)."""
        return self.Q_last.shape[0] if self.lines else 0

    @property
    def nlines(self) -> int:
        """Number of line coefficients per motor: :attr:`nphi` for each of the :attr:`blocks` runs."""
        return self.nphi * self.blocks


CHOLESKY_QR_ROWS = 2**15
"""Rows (samples) of the lines' basis above which :func:`torque_model` orthonormalises it by Cholesky QR (33 s at
1 kHz; below, Householder's QR)."""


def _thin_qr(Phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Q (N, k) with orthonormal columns and R (k, k) upper triangular with a positive diagonal, Phi = Q R, by
    Cholesky QR twice (Fukaya et al. 2014: the second pass restores orthogonality to rounding for cond(Phi) up to
    ~1e7; the lines' basis is near orthogonal). Each pass one product Q' Q (k x k) and one triangular solve, the
    second in place: on a long record of the documented lines many times faster than Householder's QR (numpy.linalg.qr,
    whose R may have negative entries on its diagonal: the columns' signs are the only difference, which the fit's
    whitened line coefficients do not see) and one copy of Phi, Q, instead of three. Householder's where Phi has
    at most :data:`CHOLESKY_QR_ROWS` rows (there it is cheap, and the fits are as they were) or where the Cholesky
    factorisation fails (lines too close for the record's length: Phi near singular)."""
    import scipy.linalg as sla

    if Phi.shape[0] <= CHOLESKY_QR_ROWS:
        return np.linalg.qr(Phi)
    R, Qt = np.eye(Phi.shape[1]), Phi.T  # Q' (k, N), Fortran order
    for k in range(2):
        try:
            R1 = sla.cholesky(Qt @ Qt.T, lower=False, check_finite=False)  # Q'Q = R1' R1
        except np.linalg.LinAlgError:  # lines too close for the record's length: Householder's
            return np.linalg.qr(Phi)
        Qt = sla.solve_triangular(R1, Qt, trans="T", lower=False, overwrite_b=k > 0, check_finite=False)
        R = R1 @ R
    return Qt.T, R


def torque_model(rec: Recording, excitation: Sequence[float] | None, torque_noise: float | None) -> TorqueModel:
    """The :class:`TorqueModel` of a recording: with ``excitation`` (Hz) the measured torque projected on the lines,
    sigma_u (default) from what it has off them; without, the torque as it is, sigma_u 0 unless given.

    Parameters
    ----------
    rec : Recording
        The recording (one run or several; a turned hand's orientations each its own block of lines).
    excitation : Sequence[float] or None
        The excitation's lines, Hz (None: the torque as recorded).
    torque_noise : float or None
        sigma_u, the torque's noise, N m (None: estimated off the lines, or 0 without them).

    Returns
    -------
    TorqueModel
        The torque the fit takes and its noise.
    """
    if excitation is None:
        return TorqueModel(rec.torque[:-1], rec.torque[-1:], 0.0 if torque_noise is None else torque_noise)
    b = rec.run_starts()
    turns = segment_starts(rec.gravity)  # a hand turned between runs of the excitation: a block per orientation
    inner = [turns[(turns > a) & (turns < e)] - a for a, e in zip(b[:-1], b[1:])]  # each run's own turns
    k = (2 * np.size(excitation) + 1) * (1 + max(len(x) for x in inner))  # the basis' width: the most turned run's
    if len(b) == 2:
        U, Q, U_last, Q_last = _project(rec.t, rec.torque, excitation, inner[0], k)
    else:  # run by run, the basis block-diagonal (the module docstring); the runs' blocks laid in place
        N, nu = rec.n_samples - 1, rec.torque.shape[1]
        R = len(b) - 1
        U, Q = np.empty((N, nu)), np.empty((N, k))
        for r in range(R):  # a loop over the runs (a few)
            a, e = b[r], b[r + 1]
            U_r, Q_r, U_e, Q_e = _project(rec.t[a:e], rec.torque[a:e], excitation, inner[r], k)
            U[a:e - 1], Q[a:e - 1] = U_r, Q_r
            if r < R - 1:  # the run's last sample (held over no period of its own) from its lines too
                U[e - 1], Q[e - 1] = U_e[0], Q_e
        U_last, Q_last = U_e, Q_e
    blocks = len(b) - 1
    if torque_noise is None:  # what is off the lines is the noise: its standard deviation
        off_lines = rec.torque[:-1] - U
        used = (2 * np.size(excitation) + 1) * (len(b) - 1 + sum(len(x) for x in inner))  # the basis' columns
        torque_noise = float(np.sqrt(np.sum(off_lines**2) / (off_lines.size - used * U.shape[1])))
    return TorqueModel(U, U_last, torque_noise, Q, Q_last, blocks)


def _project(t: np.ndarray, torque: np.ndarray, excitation: Sequence[float], turns: np.ndarray, width: int):
    """One run's torque (N+1, nu) projected on the lines (Hz) at its times t (N+1,) s, each of its orientations
    (``turns``: the samples where the hand turned, from the run's start) on its own: (U (N, nu) at the held
    samples, Q (N, ``width``) the orthonormal basis there, zero-padded, U_last (1, nu) and Q_last (width,) at the
    last sample)."""
    Phi_all = line_basis(t, excitation, np.concatenate([[0], turns]).astype(int))
    Q, R_q = _thin_qr(Phi_all[:-1])  # (N, nphi): 1, sin, cos of each line, at the held samples
    coef = Q.T @ torque[:-1]
    Q_last = np.linalg.solve(R_q.T, Phi_all[-1])  # the basis at the last sample (Q = Phi R^-1)
    U, U_last, pad = Q @ coef, (Q_last @ coef)[None], width - Q.shape[1]
    return U, np.pad(Q, ((0, 0), (0, pad))), U_last, np.pad(Q_last, (0, pad))
