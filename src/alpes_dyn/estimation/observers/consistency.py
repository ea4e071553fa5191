"""Does an observer's reported uncertainty tell the truth? Each joint's standard deviation along a run, and the
normalised estimation error squared (NEES) against true joints with its chi-square band.

For an estimate q_hat_k of covariance P_k (its joints' block) and the true joints q_k, the NEES of a sample is

    eps_k = (q_hat_k - q_k)^T P_k^-1 (q_hat_k - q_k),

chi-square with n degrees of freedom when the filter is consistent (its error zero-mean with the covariance it
reports; Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, Sec. 5.4).
Its average over M independent samples is chi-square with n M degrees of freedom divided by M. A filter's errors
are not independent from one sample to the next: :func:`nees` takes one sample every ``every`` seconds (a coarse
decimation), and, given the filter and its inputs, counts them by the filter's own model of its error: the error
after sample k+1 is (I - K H) A_k times the error after sample k plus the step's noises, so the filter predicts the
correlation C_ba = Phi(k_b, k_a) P_a of its errors at two samples, and for Gaussian errors the covariance
2 tr(P_a^-1 C_ab P_b^-1 C_ba) of their NEES; the variance V of the average so predicted is that of a chi-square of
n M_eff degrees of freedom over M_eff for M_eff = 2 n / V (Satterthwaite's match of the first two moments; an
error that rings for a second, as a frictionless finger's internal mode does, is fewer independent samples than
its count). The band of the average: [chi2_{(1-level)/2}(n M_eff), chi2_{(1+level)/2}(n M_eff)]
/ M_eff. Above the band the filter is over-confident (its sigma too small), below it is cautious.

The count is the filter's belief about its own error. An error the filter does not model (a friction law that is not
the plant's: a bias that changes slowly) may be more correlated than it believes, and the band then too narrow.
:func:`measured_effective` counts the same samples from the series itself, its autocorrelation summed over the lags
up to Geyer's initial positive sequence (Geyer 1992, "Practical Markov chain Monte Carlo", Statist. Sci. 7:
M_eff = M / (1 + 2 sum_l rho_l)); :class:`Nees` holds it beside the filter's, per joint and in all (a check of
the band, not the band: it reads the true joints, which only a simulation has, and it is noisy on a short run).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...checks import as_float_array
from ...errors import InputError
from .observers import Estimate

__all__ = ["Banded", "Nees", "nees", "measured_effective", "joint_sigma", "predicted_covariance", "chi2_band",
           "NEES_EVERY"]

NEES_EVERY = 0.1
"""Default decimation of :func:`nees`, s: a filter's error at 1 kHz is correlated over tens of milliseconds (the
autocorrelation of finger3's normalised error falls low within the default decimation on the estimation scenario); what
remains beyond (a frictionless finger's internal mode rings for seconds) is counted by the filter's error model."""


class Banded:
    """A normalised statistic with its chi-square band (:func:`chi2_band`): ``value`` (1 for a consistent filter),
    ``low`` and ``high``, the band's ends. The base of :class:`Nees` and
    :class:`~alpes_dyn.estimation.observers.innovation.Nis`."""

    value: float
    low: float
    high: float

    @property
    def consistent(self) -> bool:
        """Whether the statistic lies in its band."""
        return bool(self.low <= self.value <= self.high)

    @property
    def verdict(self) -> str:
        """``"consistent"``, ``"over-confident"`` (above the band: the reported sigma too small) or ``"cautious"``
        (below it)."""
        return "consistent" if self.consistent else ("over-confident" if self.value > self.high else "cautious")


@dataclass
class Nees(Banded):
    """The NEES of an observer's joints over a run (see the module docstring).

    Attributes
    ----------
    value: the time-averaged NEES over the samples used (n for a consistent filter).
    low, high: its band at ``level`` (default 95 %): [chi2 quantiles of n M_eff degrees of freedom] / M_eff.
    dof: n, the joints. samples: M, the samples used (one every ``every`` s after ``start``).
    effective: M_eff, the independent samples the M count for (M without the filter).
    per_joint: (n,) time average of (q_hat_i - q_i)^2 / P_ii (1 for a consistent filter).
    level: the band's probability. every: the decimation, s. start: the first time used, s.
    measured: M_eff counted from the series of the NEES itself (:func:`measured_effective`, the module docstring).
    joint_measured: (n,) the same for each joint's (q_hat_i - q_i)^2 / P_ii.
    """

    value: float
    low: float
    high: float
    dof: int
    samples: int
    effective: float
    per_joint: np.ndarray
    level: float
    every: float
    start: float
    measured: float = float("nan")
    joint_measured: np.ndarray | None = None

    def joint_band(self) -> tuple[float, float]:
        """The band at ``level`` of one joint's NEES (:attr:`per_joint`, 1 for a consistent filter): chi2 of
        M_eff degrees of freedom over M_eff, the joints' M_eff (:attr:`effective`, an approximation: each joint's
        error may decorrelate at its own pace)."""
        from scipy.special import gammaincinv

        p = np.array([(1 - self.level) / 2, (1 + self.level) / 2])
        low, high = 2.0 * gammaincinv(self.effective / 2.0, p) / self.effective
        return float(low), float(high)

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``alpes-dyn estimate --json`` (its ``nees`` object)."""
        return {"value": self.value, "band": [self.low, self.high], "level": self.level, "dof": self.dof,
                "samples": self.samples, "effective_samples": self.effective, "every_s": self.every,
                "start_s": self.start, "per_joint": self.per_joint.tolist(), "verdict": self.verdict,
                "measured_effective_samples": self.measured,
                "joint_measured_effective_samples": None if self.joint_measured is None else
                self.joint_measured.tolist()}


def predicted_covariance(filt: Any, estimate: Estimate, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The filter's one-step prediction along its run, recomputed from its estimate: (A (N-1, nz, nz), P_pred
    (N-1, nz, nz)), A_k = dF/dz at (z_k, w_k) and P_pred,k = A_k P_k A_k^T + G Sigma_w G^T + Q (G = dF/dw), the
    covariance of z_k+1|k.

    Parameters
    ----------
    filt : KalmanFilter
        The filter that made ``estimate`` (a :class:`~alpes_dyn.estimation.observers.observers.KalmanFilter`).
    estimate : Estimate
        Its run: z (N, nz), P (N, nz, nz).
    W : numpy.ndarray, shape (N-1, nw)
        The known inputs, row k held from sample k to k+1.

    Returns
    -------
    A : numpy.ndarray, shape (N-1, nz, nz)
        dF/dz at (z_k, w_k).
    P_pred : numpy.ndarray, shape (N-1, nz, nz)
        The covariance of z_k+1|k.
    """
    from .ahead import linearised, predicted_step  # compiled (the VM's map over the samples without a compiler)

    N = W.shape[0]
    if getattr(filt, "looped", False):  # a large state: the step's run computed once with the NIS's
        _, P_pred, A, _ = predicted_step(filt, estimate.z, W, estimate.P)
        return A, P_pred
    A, G = linearised(filt, estimate.z, W)
    P = estimate.P
    return A, A @ P[:N] @ A.transpose(0, 2, 1) + G @ filt.Sw @ G.transpose(0, 2, 1) + filt.Q


def _error_transitions(filt: Any, estimate: Estimate, W: np.ndarray) -> np.ndarray:
    """(N-1, nz, nz) Phi_k: the filter's error after sample k+1 is Phi_k times its error after sample k, plus the
    noises of the step (its linearisation): Phi_k = (I - K_k+1 H) A_k = P_k+1 P_pred^-1 A_k, with A_k and P_pred
    of :func:`predicted_covariance` (the optimal gain's (I - K H) P_pred = P_k+1)."""
    A, P_pred = predicted_covariance(filt, estimate, W)
    return estimate.P[1: W.shape[0] + 1] @ np.linalg.solve(P_pred, A)


def _predicted_variance(Phi: np.ndarray, P: np.ndarray, k: np.ndarray, n: int) -> float:
    """Var of the mean of eps over the samples ``k`` under the filter's own model of its error: its errors at k_a
    and k_b > k_a correlated by C_ba = Phi(k_b, k_a) P_a (the transitions of :func:`_error_transitions`), and for
    Gaussian errors cov(eps_a, eps_b) = 2 tr(P_a^-1 C_ab P_b^-1 C_ba) (the joints' blocks)."""
    M, step = k.size, int(k[1] - k[0])
    T = np.broadcast_to(np.eye(Phi.shape[1]), (M - 1,) + Phi.shape[1:]).copy()
    for j in range(step):  # the transitions over one decimation interval, every interval at once
        T = Phi[k[:-1] + j] @ T
    Winv = np.linalg.inv(P[k, :n, :n])
    C = P[k[:-1]]  # C[a] = Phi(k_a+l, k_a) P_a, lag l = 0 first
    total = 2.0 * n * M
    for lag in range(1, M):  # a loop over the lags, every pair at that lag at once
        C = T[lag - 1: M - 1] @ C[: M - lag]
        Cq = C[:, :n, :n]
        total += 4.0 * np.einsum("aij,ajk,akl,ail->", Winv[lag:], Cq, Winv[: M - lag], Cq)
    return total / M**2


def nees(estimate: Estimate, true_q: Any, filter: Any = None, inputs: Any = None, *, start: float = 0.0,
         every: float = NEES_EVERY, level: float = 0.95) -> Nees:
    """The time-averaged NEES of the joints of ``estimate`` against ``true_q`` and its band (module docstring).

    Parameters
    ----------
    estimate : Estimate
        The observer's :class:`~alpes_dyn.estimation.observers.observers.Estimate` (N samples, its first n
        states the joints, rad).
    true_q : array_like, shape (N, n)
        The true joints, rad.
    filter : KalmanFilter or None, optional
        The filter that made ``estimate`` (a :class:`~alpes_dyn.estimation.observers.observers.KalmanFilter`):
        with ``inputs``, the band then counts the samples by the filter's own model of its error's correlation
        (module docstring). Without them (default None) the decimated samples are taken as independent.
    inputs : array_like, shape (N-1, nw), optional
        The filter's known inputs, row k the input held from sample k to k+1 (required with ``filter``).
    start : float, optional
        The first time used, s from the estimate's first sample (after the transient; default 0).
    every : float, optional
        One sample every ``every`` s (>= the sample period; default ``NEES_EVERY``).
    level : float, optional
        The band's probability, in (0, 1) (default 0.95).

    Returns
    -------
    Nees
        The average, its band and the per-joint averages.

    Raises
    ------
    InputError
        Naming the argument: ``true_q`` of another shape or not finite, ``start`` past the run, ``every`` or
        ``level`` out of range, fewer than two samples left, ``inputs`` of another shape.
    """
    if not isinstance(estimate, Estimate):
        raise InputError(f"estimate: expected an Estimate, got {type(estimate).__name__}")
    q = as_float_array(true_q, "true_q", "(N, n) joint angles in rad")
    N = estimate.z.shape[0]
    if q.ndim != 2 or q.shape[0] != N or not 1 <= q.shape[1] <= estimate.z.shape[1]:
        raise InputError(f"true_q: expected ({N}, n) joint angles, got shape {q.shape}")
    if not np.isfinite(q).all():
        raise InputError("true_q: contains NaN or inf")
    dt = float(estimate.t[1] - estimate.t[0]) if N > 1 else 0.0
    for x, name in ((start, "start"), (every, "every"), (level, "level")):
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)) \
                or not np.isfinite(x):
            raise InputError(f"{name}: expected a finite number, got {x!r:.40}")
    if not 0 < level < 1:
        raise InputError(f"level: expected a probability in (0, 1), got {level!r}")
    if not (dt > 0 and every >= dt * (1 - 1e-9)):
        raise InputError(f"every: expected at least the sample period {dt:g} s, got {every!r}")
    if not 0 <= start < estimate.t[-1] - estimate.t[0]:
        raise InputError(f"start: expected a time in [0, {estimate.t[-1] - estimate.t[0]:g}) s, got {start!r}")
    n = q.shape[1]
    k = np.arange(int(round(start / dt)), N, max(1, int(round(every / dt))))
    if k.size < 2:
        raise InputError(f"every: {every:g} s leaves {k.size} sample after {start:g} s (at least 2 needed)")
    e = estimate.z[k, :n] - q[k]
    P = estimate.P[k, :n, :n]
    eps = np.einsum("ki,ki->k", e, np.linalg.solve(P, e[:, :, None])[:, :, 0])
    m_eff = float(k.size)
    if filter is not None:
        W = as_float_array(inputs, "inputs", f"({N - 1}, {filter.nw}) known inputs")
        if W.shape != (N - 1, filter.nw) or not np.isfinite(W).all():
            raise InputError(f"inputs: expected ({N - 1}, {filter.nw}) finite known inputs, got shape {W.shape}")
        if estimate.z.shape[1] != filter.nz:
            raise InputError(f"filter: its {filter.nz} states are not the estimate's {estimate.z.shape[1]}")
        Phi = _error_transitions(filter, estimate, W)
        m_eff = min(m_eff, 2.0 * n / _predicted_variance(Phi, estimate.P, k, n))
    low, high = chi2_band(n, m_eff, level)
    r2 = e**2 / np.diagonal(P, axis1=1, axis2=2)
    return Nees(value=float(eps.mean()), low=float(low), high=float(high), dof=n, samples=int(k.size),
                effective=float(m_eff), per_joint=r2.mean(axis=0), level=float(level), every=float(every),
                start=float(start), measured=measured_effective(eps),
                joint_measured=np.array([measured_effective(x) for x in r2.T]))


def measured_effective(series: Any) -> float:
    """The independent samples a series of M counts for, measured from its own autocorrelation rho_l: M / (1 + 2
    sum_{l >= 1} rho_l) = M / (2 sum_j Gamma_j - 1), Gamma_j = rho_2j + rho_2j+1 summed over Geyer's initial
    positive sequence (while positive), within [1, M] (module docstring).

    Parameters
    ----------
    series : array_like, shape (M,)
        The samples in time order (e.g. the decimated NEES of :func:`nees`), M >= 2.

    Returns
    -------
    float
        The effective count, in [1, M]; M for a constant series.

    Raises
    ------
    InputError
        ``series`` not a finite (M,) array of at least two samples.
    """
    x = as_float_array(series, "series", "(M,) samples")
    if x.ndim != 1 or x.size < 2 or not np.isfinite(x).all():
        raise InputError(f"series: expected (M,) finite samples, M >= 2, got shape {x.shape}")
    M = x.size
    x = x - x.mean()
    var = float(np.dot(x, x))
    if var <= 0.0:
        return float(M)
    f = np.fft.rfft(x, 2 * M)  # the autocorrelation at every lag at once
    rho = np.fft.irfft(f * np.conj(f))[:M] / var  # rho_0 = 1 first
    pairs = rho[: M // 2 * 2].reshape(-1, 2).sum(axis=1)  # Gamma_j = rho_2j + rho_2j+1
    stop = int(np.argmax(pairs <= 0)) if np.any(pairs <= 0) else pairs.size
    tau = 2.0 * pairs[:stop].sum() - 1.0  # the variance inflation 1 + 2 sum rho_l
    if tau <= 1.0:  # anticorrelated (two samples always: rho_1 = -1/2, tau = 0): no fewer than its M samples
        return float(M)
    return float(np.clip(M / tau, 1.0, M))


def chi2_band(dof: int, samples: float, level: float) -> tuple[float, float]:
    """The band of the average of ``samples`` independent chi-square variables of ``dof`` degrees of freedom at
    probability ``level``: [chi2_{(1-level)/2}(dof M), chi2_{(1+level)/2}(dof M)] / M, M = ``samples``.

    Parameters
    ----------
    dof : int
        The degrees of freedom of each variable (the joints n of a NEES).
    samples : float
        M, the number of (effective) independent samples averaged; need not be whole.
    level : float
        The band's probability, in (0, 1).

    Returns
    -------
    tuple[float, float]
        The band's low and high ends.
    """
    from scipy.special import gammaincinv  # chi2.ppf(p, k) = 2 gammaincinv(k / 2, p) (scipy.stats: seconds to import)

    low, high = 2.0 * gammaincinv(dof * samples / 2.0, np.array([(1 - level) / 2, (1 + level) / 2])) / samples
    return float(low), float(high)


def joint_sigma(estimate: Estimate, n: int, start: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Each joint's reported standard deviation along the run after ``start`` s: (median (n,), worst (n,)), rad,
    of sqrt(P_ii) (:attr:`~alpes_dyn.estimation.observers.observers.Estimate.std`).

    Parameters
    ----------
    estimate : Estimate
        The observer's run (its first n states the joints, rad).
    n : int
        The number of joints.
    start : float, optional
        The first time used, s from the estimate's first sample (default 0).

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray]
        The median and the worst standard deviation of each joint, (n,) each, rad.
    """
    k0 = int(round(start / (estimate.t[1] - estimate.t[0]))) if estimate.t.size > 1 else 0
    sd = estimate.std[min(k0, estimate.t.size - 1):, :n]
    return np.median(sd, axis=0), sd.max(axis=0)
