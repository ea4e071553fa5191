"""Is an observer consistent on a recording without true joints? Its normalised innovation squared (NIS) against
its chi-square band: the one consistency test a user can run on the hand.

The innovation of the measurement y_k+1 (m encoders, rad) is i_k = y_k+1 - h(F(z_k|k, w_k)), the encoder against
the filter's one-step prediction, and the filter claims its covariance S_k = H P_pred,k H^T + R (H = dh/dz at the
prediction, P_pred,k of :func:`~alpes_dyn.estimation.observers.consistency.predicted_covariance`). Its NIS

    nu_k = i_k^T S_k^-1 i_k

is chi-square with m degrees of freedom, and the innovations are white, when the filter is consistent (Bar-Shalom,
Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, Sec. 5.4.2). The average over M
samples is then chi-square with m M degrees of freedom over M. A filter that is not is seen twice here: its NIS
above the band (its covariance too small for the errors it makes: over-confident) or below it (cautious). The
encoder's quantisation leaves the innovation of a right filter a little correlated from sample to sample at 1 kHz
(the finger moves less than a count in a few samples); the band counts the samples as the normalised innovations'
own autocorrelation says, M_eff = M / (1 + 2 sum_{l=1..L} r(l)^2) (the variance of an average of squares of a
Gaussian sequence whose lag-l correlation is r(l); the same match of two moments as
:func:`~alpes_dyn.estimation.observers.consistency.nees`'s), with L = ``lags``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...checks import as_float_array
from ...errors import InputError
from .ahead import predicted_ahead
from .consistency import Banded, chi2_band
from .observers import Estimate

__all__ = ["Nis", "nis", "NIS_LAGS"]

NIS_LAGS = 25
"""Lags of the normalised innovations' autocorrelation that count the NIS's independent samples."""


@dataclass
class Nis(Banded):
    """The NIS of an observer over a run (see the module docstring).

    Attributes
    ----------
    value: the time-averaged NIS over the samples used (m for a consistent filter).
    low, high: its band at ``level``: [chi2 quantiles of m M_eff degrees of freedom] / M_eff.
    dof: m, the measurements. samples: M, the innovations used (every one after ``start``).
    effective: M_eff, the independent samples they count for.
    per_output: (m,) time average of i_j^2 / S_jj (1 for a consistent filter).
    innovation_rms: (m,) the innovations' RMS, rad. reported_rms: (m,) sqrt of the mean S_jj, rad: what the
    filter claims they are.
    level: the band's probability. start: the first time used, s.
    """

    value: float
    low: float
    high: float
    dof: int
    samples: int
    effective: float
    per_output: np.ndarray
    innovation_rms: np.ndarray
    reported_rms: np.ndarray
    level: float
    start: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return {"value": self.value, "band": [self.low, self.high], "level": self.level, "dof": self.dof,
                "samples": self.samples, "effective_samples": self.effective, "start_s": self.start,
                "per_output": self.per_output.tolist(), "innovation_rms": self.innovation_rms.tolist(),
                "reported_rms": self.reported_rms.tolist(), "verdict": self.verdict}


def nis(estimate: Estimate, measurement: Any, filter: Any, inputs: Any, *, start: float = 0.0,
        level: float = 0.95, lags: int | None = None, horizon: int = 1, stride: int = 1) -> Nis:
    """The time-averaged NIS of ``filter``'s run ``estimate`` on ``measurement`` and its band (module docstring).

    Parameters
    ----------
    estimate : Estimate
        The filter's :class:`~alpes_dyn.estimation.observers.observers.Estimate` (N samples).
    measurement : array_like, shape (N, m)
        What the filter read, in its output's units (the encoders in rad, as
        :attr:`~alpes_dyn.estimation.observers.replay.RecordingEstimate.measurement`).
    filter : KalmanFilter
        The :class:`~alpes_dyn.estimation.observers.observers.KalmanFilter` that made ``estimate``.
    inputs : array_like, shape (N-1, nw)
        Its known inputs, row k held from sample k to k+1.
    start : float, optional
        The first time used, s from the estimate's first sample (after the filter's transient; default 0).
    level : float, optional
        The band's probability, in (0, 1) (default 0.95).
    lags : int or None, optional
        L, the autocorrelation's lags counted (module docstring); default None: :data:`NIS_LAGS`, at most a
        quarter of the predictions (a short run's).
    horizon : int, optional
        Samples ahead of the prediction (default 1: the innovation). Further ahead, the measurement predicted from
        z_k|k without update and its covariance propagated as the filter's prediction does: an error the encoder
        does not see at once (the split of joints it reads the sum of) reaches it through the dynamics.
    stride : int, optional
        One prediction every ``stride`` samples (default 1).

    Returns
    -------
    Nis
        The average, its band and the per-output figures.

    Raises
    ------
    InputError
        Naming the argument: ``measurement`` or ``inputs`` of another shape or not finite, ``start`` past the
        run, ``level``, ``lags``, ``horizon`` or ``stride`` out of range.
    """
    if not isinstance(estimate, Estimate):
        raise InputError(f"estimate: expected an Estimate, got {type(estimate).__name__}")
    N = estimate.z.shape[0]
    y = as_float_array(measurement, "measurement", "(N, m) measurements")
    if y.ndim != 2 or y.shape != (N, filter.model.ny) or not np.isfinite(y).all():
        raise InputError(f"measurement: expected ({N}, {filter.model.ny}) finite values, got shape {y.shape}")
    W = as_float_array(inputs, "inputs", f"({N - 1}, {filter.nw}) known inputs")
    if W.shape != (N - 1, filter.nw) or not np.isfinite(W).all():
        raise InputError(f"inputs: expected ({N - 1}, {filter.nw}) finite known inputs, got shape {W.shape}")
    if isinstance(level, bool) or not isinstance(level, (int, float, np.floating)) or not 0 < level < 1:
        raise InputError(f"level: expected a probability in (0, 1), got {level!r:.40}")
    dt = float(estimate.t[1] - estimate.t[0])
    k0 = int(round(start / dt)) if isinstance(start, (int, float, np.floating)) and np.isfinite(start) else -1
    if not 0 <= k0 < N - 2:
        raise InputError(f"start: expected a time in [0, {estimate.t[-1] - estimate.t[0]:g}) s, got {start!r:.40}")
    for x, name in ((horizon, "horizon"), (stride, "stride")):
        if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or not 1 <= x < (N - 1 - k0) // 4:
            raise InputError(f"{name}: expected an integer from 1 to {(N - 1 - k0) // 4 - 1}, got {x!r:.40}")
    starts = np.arange(k0, N - horizon, stride)
    if lags is None:
        lags = max(1, min(NIS_LAGS, starts.size // 4))
    if isinstance(lags, bool) or not isinstance(lags, (int, np.integer)) or not 1 <= lags < starts.size // 2:
        raise InputError(f"lags: expected an integer from 1 to {starts.size // 2 - 1}, got {lags!r:.40}")
    yp, S = predicted_ahead(filter, estimate.z, W, starts, int(horizon), estimate.P)
    i = y[starts + horizon] - yp
    r = np.linalg.solve(np.linalg.cholesky(S), i[:, :, None])[:, :, 0]  # whitened: unit variance when consistent
    eps = np.sum(r**2, axis=1)
    M, m = eps.size, y.shape[1]
    rc = r - r.mean(axis=0)
    acf = np.array([np.sum(rc[l:] * rc[:M - l], axis=0) for l in range(1, lags + 1)]) / np.sum(rc**2, axis=0)
    m_eff = M / (1.0 + 2.0 * float(np.mean(np.sum(acf**2, axis=0))))
    low, high = chi2_band(m, m_eff, level)
    Sd = np.diagonal(S, axis1=1, axis2=2)
    return Nis(value=float(eps.mean()), low=low, high=high, dof=m, samples=int(M), effective=float(m_eff),
               per_output=np.mean(i**2 / Sd, axis=0), innovation_rms=np.sqrt(np.mean(i**2, axis=0)),
               reported_rms=np.sqrt(np.mean(Sd, axis=0)), level=float(level), start=float(k0 * dt))
