"""The fitted parameters' covariance robust to a coloured residual (issue 50): a HAC sandwich.

The classical covariance of a least-squares fit, s^2 (J'J)^-1 (here the parameters' block of the undamped KKT
inverse of the multiple-shooting problem, scaled by the residual variance s^2), holds where the residual is white.
Where the model misses an effect (stick-slip friction on a smooth friction law), the residual can be coloured, and
the errors of the parameters several times those standard errors (issue 50: MuJoCo stick-slip, RMS of
error / sigma 3.3). The sandwich replaces the white residual's s^2 J'J in the middle by the long-run covariance of
the gradient's contributions:

    delta rho = -Z' J' delta r,   P_robust = sum_(|l| <= M) w_l Gamma_l,   Gamma_l = sum_t h_t h_(t-l)',

with Z the KKT inverse's parameter columns (nodes and parameters, continuity kept: the same reduction to the
parameters as the classical covariance's), h_t = Z' J_t' r_t (p,) the influence of sample t's residual on the
parameters, and Bartlett's weights w_l = 1 - |l| / (M + 1) (Newey & West 1987: positive semi-definite). On a
white residual it is the classical covariance again (Z' J'J Z = the KKT inverse's block, C Z = 0), to its
sampling error.

The window M, from the residual's autocorrelation (:func:`correlation_window`): Sokal's automatic window (Sokal
1989; the integrated autocorrelation time tau(W) = 1 + 2 sum_(k=1..W) rho(k) of each encoder's residual, W the
smallest lag with W >= :data:`WINDOW_C` tau(W)), the largest over the encoders, at most a fifth of the record
(:data:`MAX_WINDOW_FRACTION`: a window the length of the record estimates nothing, the h_t summing to 0 at the
optimum). White: W = 5 samples; an AR(1) residual of coefficient 0.7: about 30.

The series h_t is per sample (:func:`influence`): from the fit's Jacobian J, or, where a long record holds it compact
(:mod:`~alpes_dyn.estimation.identification.normal_blocks`), from one more pass over its chunks (the same numbers,
for the cost of one Gauss-Newton iteration's Jacobian).

What a fit reports (:func:`reported_covariance`): each parameter's variance the larger of the classical and the
robust one. Not the robust alone: on a white residual the sandwich is the classical covariance plus its sampling
error (a sum of squares of the data instead of s^2 times a model's matrix: within a few percent of it on fits of
the library's own simulator) and Bartlett's weights bias it low; the classical is what the sensor noise alone
leaves, a floor. Where the residual is coloured the robust one is the larger (several times on a MuJoCo stick-slip
fit whose residual is correlated over many samples, where the errors measured in robust standard errors are
closer to 1 than in classical ones).

What it cannot see: a model error that leaves the residual white at the sensor floor. On MuJoCo's stick-slip
finger3 palm up the fits called adequate have a friction well off with a short residual window; the sandwich is
then the classical covariance and their friction errors stay several standard errors (springs and masses are
covered). No covariance of the residual covers an error the residual does not show.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import InputError

__all__ = ["WINDOW_C", "MAX_WINDOW_FRACTION", "correlation_window", "hac", "RobustCovariance", "influence",
           "robust_covariance", "reported_covariance"]

WINDOW_C = 5.0
"""Sokal's constant c of :func:`correlation_window`: the window at least c integrated autocorrelation times."""
MAX_WINDOW_FRACTION = 0.2
"""The longest window, as a fraction of the series (module doc)."""


def correlation_window(residual: np.ndarray, c: float = WINDOW_C, max_fraction: float = MAX_WINDOW_FRACTION) -> int:
    """The Bartlett window M (samples) for a residual's autocorrelation: Sokal's automatic window (module doc).

    Parameters
    ----------
    residual : (N,) or (N, m) array
        The residual, one column per channel (means removed here); NaN not allowed.
    c : float
        Sokal's constant: the smallest W with W >= c tau(W).
    max_fraction : float
        The window at most this fraction of N.

    Returns
    -------
    int
        The largest channel's window, 1 to max(1, floor(max_fraction N)). Raises :class:`~alpes_dyn.InputError` for
        fewer than 4 samples or a value that is not finite.
    """
    e = np.asarray(residual, dtype=float)
    e = e[:, None] if e.ndim == 1 else e.reshape(e.shape[0], -1)
    n = e.shape[0]
    if n < 4 or not np.all(np.isfinite(e)):
        raise InputError(f"residual: expected at least 4 finite samples, got {n} (or a value not finite)")
    cap = max(1, int(max_fraction * n))
    e = e - e.mean(axis=0)
    nfft = 1 << (2 * n - 1).bit_length()
    f = np.fft.rfft(e, nfft, axis=0)
    acov = np.fft.irfft(f * f.conj(), nfft, axis=0)[: cap + 1]  # (cap + 1, m): lags 0..cap
    best = 1
    for j in range(e.shape[1]):  # a loop over the channels (two or three encoders)
        if acov[0, j] <= 0:
            continue  # a channel without residual: no colour
        tau = 1.0 + 2.0 * np.cumsum(acov[1:, j] / acov[0, j])  # tau(W) for W = 1..cap
        ok = np.nonzero(np.arange(1, cap + 1) >= c * tau)[0]
        best = max(best, int(ok[0]) + 1 if ok.size else cap)
    return min(best, cap)


def hac(h: np.ndarray, lags: int) -> np.ndarray:
    """The Bartlett-weighted long-run covariance of a series: sum_(|l| <= lags) (1 - |l| / (lags + 1)) Gamma_l, with
    Gamma_l = sum_t h_t h_(t-l)' (a sum, not a mean: the covariance of sum_t h_t).

    Parameters
    ----------
    h : (T, p) array
        The series (its mean not removed: at a least-squares optimum the influences sum to 0).
    lags : int
        The window M >= 0 (0: White's heteroscedasticity-consistent sum h'h).

    Returns
    -------
    (p, p) array, symmetric positive semi-definite. Raises :class:`~alpes_dyn.InputError` for a negative window.
    """
    h = np.asarray(h, dtype=float)
    if isinstance(lags, bool) or not isinstance(lags, (int, np.integer)) or lags < 0:
        raise InputError(f"lags: expected a non-negative integer, got {lags!r}")
    # Bartlett's sum is that of the moving sums S_t = h_t-M + ... + h_t (h zero outside the series):
    # sum_t S_t S_t' = sum_l (M + 1 - |l|) Gamma_l, so O(T p^2) for any window
    T, M = h.shape[0], int(lags)
    C = np.concatenate([np.zeros((1, h.shape[1])), np.cumsum(h, axis=0)])  # C_i = h_0 + ... + h_i-1
    t = np.arange(T + M)
    S = C[np.minimum(t + 1, T)] - C[np.maximum(t - M, 0)]
    out = S.T @ S / (M + 1.0)
    return 0.5 * (out + out.T)


@dataclass
class RobustCovariance:
    """The HAC sandwich of a fit (module doc): ``covariance`` (p, p) of the fitted rho (log theta / theta_0, the
    additive ones scaled), ``window`` the Bartlett window, samples (:func:`correlation_window` of the residual)."""

    covariance: np.ndarray
    window: int

    def describe(self) -> str:
        """One line: the method and its window."""
        return f"HAC sandwich, Bartlett window {self.window} samples from the residual's autocorrelation"

    def to_dict(self) -> dict[str, Any]:
        return {"method": "HAC sandwich (Newey-West, Bartlett weights)", "window_samples": self.window,
                "window_rule": f"Sokal: W >= {WINDOW_C:g} tau_int(W) of each encoder's residual, at most "
                               f"{MAX_WINDOW_FRACTION:g} of the record"}


def influence(pb: Any, e: Any, Z: np.ndarray) -> np.ndarray:
    """The influences h (N + 1, p) of the residuals on the parameters, delta rho = -sum_t h_t (module doc).

    Parameters
    ----------
    pb : :class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`
    e : :class:`~alpes_dyn.estimation.identification.shooting_algebra.Evaluation`
        The fit's evaluation with its Jacobians: J, or a compact Jacobian's (``J`` None, ``point`` where it was
        taken: one more pass over its chunks, as
        :func:`~alpes_dyn.estimation.identification.normal_blocks.remainders` makes).
    Z : (nz + nc, p) array
        The undamped KKT system's solutions for the parameters' unit vectors (``pb.unit_p``).

    Returns
    -------
    (N + 1, p) array: one row per sample of the recording, the rows of its encoders, its camera and its interval's
    torque correction summed.
    """
    S, nb, nv, nz, p = pb.n_int, pb.nb, pb.nv, pb.nz, pb.p
    Zl, Zg = Z[:nv].reshape(S, nb, p), Z[nv:nz]
    L1, ny, cam = pb.L + 1, pb.ny, pb.n if pb.Qm is not None else 0
    h = np.zeros((pb.N + 1, p))

    def add(sl: slice, J_c: np.ndarray, x_c: Any = None) -> None:
        W = np.einsum("skd,sdp->skp", J_c[:, :, :nb], Zl[sl]) + J_c[:, :, nb:] @ Zg  # (s, R, p)
        W *= e.r[sl, :, None]
        s_ = W.shape[0]  # the rows' layout (module shooting): encoders (L+1) ny, camera (L+1) n, torque corrections
        G = W[:, :L1 * ny].reshape(s_, L1, ny, p).sum(axis=2)
        if cam:
            G += W[:, L1 * ny:L1 * (ny + cam)].reshape(s_, L1, cam, p).sum(axis=2)
        G[:, 0] += W[:, L1 * (ny + cam):].sum(axis=1)  # an interval's torque correction: at its first sample
        np.add.at(h, pb.kk[sl].reshape(-1), G.reshape(-1, p))  # (an interval's end: the next's start, its row 0)
    if e.J is not None:
        add(slice(None), e.J)
    else:  # compact (module normal_blocks): J not held
        pb.evaluate(*e.point, sink=add)
    return h


def robust_covariance(pb: Any, e: Any, Z: np.ndarray, s2: float, residual: np.ndarray) -> RobustCovariance:
    """The HAC sandwich covariance of a fit's rho (module doc), in the classical covariance's space (the
    parameters' block, continuity kept).

    Parameters
    ----------
    pb : ShootingProblem
        The fit's :class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`.
    e : Evaluation
        The fit's evaluation with its Jacobians, as :func:`influence` takes it.
    Z : numpy.ndarray, shape (nz + nc, p)
        The undamped KKT system's solutions for the parameters' unit vectors (``pb.unit_p``).
    s2 : float
        The residual variance of the classical covariance: the line corrections' prior (global residuals) enters
        as there, s2 Z_g' diag(prior) Z_g.
    residual : (N + 1, m) array
        The encoder residual, counts (for the window, :func:`correlation_window`).

    Returns
    -------
    :class:`RobustCovariance`; the sum scaled by (residuals / degrees of freedom) as the classical s2 is.
    """
    h = influence(pb, e, Z)
    window = correlation_window(residual)
    n_res = pb.dof + (pb.nz - pb.nc + int(pb.cut.sum()) * pb.nx)  # residuals, as ShootingProblem.dof counts them
    Zg = Z[pb.nv:pb.nz]
    P = hac(h, window) * (n_res / pb.dof) + s2 * (Zg.T * pb.prior) @ Zg
    return RobustCovariance(P, int(window))


def reported_covariance(classical: np.ndarray, robust: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The covariance a fit reports (module doc): ``robust`` plus, on its diagonal, what ``classical`` has more
    (positive semi-definite; each variance max(classical, robust)).

    Parameters
    ----------
    classical : numpy.ndarray, shape (p, p)
        The classical covariance of the fitted rho (log theta / theta_0, the additive ones scaled).
    robust : numpy.ndarray, shape (p, p)
        The HAC sandwich covariance of rho (:func:`robust_covariance`), the same space.

    Returns
    -------
    covariance : numpy.ndarray, shape (p, p)
        The covariance reported.
    larger : numpy.ndarray, shape (p,)
        bool: where the robust variance is the larger.
    """
    vc, vr = np.diag(classical), np.diag(robust)
    larger = vr > vc
    return robust + np.diag(np.where(larger, 0.0, vc - vr)), larger
