"""Model adequacy of an identified model: does the model explain the recording, or only fit it?

A least-squares fit always converges to *something*; small standard errors say the data pin the
parameters down, not that the model's structure is right. On a plant with an effect the model lacks
(stick-slip friction, an elastic tendon, a rotor's inertia, a tilted palm) the fit lands on wrong
values with a green light. These tests follow the conventions of MATLAB's System Identification
Toolbox: ``resid`` (whiteness of the residual and its independence of the input) and ``compare``
(simulation on held-out data, fit %), see L. Ljung, *System Identification: Theory for the User*
(2nd ed., 1999), Sections 16.6 (residual analysis) and 16.5 (cross-validation).

Every test works on the encoder residual e_k = y_k - yhat_k in counts (y the recorded encoder, yhat
the model's reading S q on the fit's multiple-shooting trajectory, one column per encoder):

* **Whiteness** (:func:`whiteness`): the normalised autocorrelation r_ee(k) = R_ee(k) / R_ee(0) for
  lags k = 1..M (default M = 25) against the 99 % band +-2.58 / sqrt(N) of a white sequence, and the
  Ljung-Box statistic Q = N (N + 2) sum_k r_ee(k)^2 / (N - k), chi^2 with M degrees of freedom under
  whiteness (its p-value from :func:`scipy.stats.chi2.sf`).
* **Independence of the input** (:func:`cross_correlation`): r_eu(k) = R_eu(k) / sqrt(R_ee(0) R_uu(0))
  for k = -M..M with the recorded motor torque u (mean removed), against the same band (valid when e
  is white, MATLAB's convention).
* **The sensor floor** (:func:`sensor_floor`): what a right model leaves, per sample, in counts:
  sqrt(q^2 / 12 + sigma_n^2 + sigma_tau^2): the encoder's quantisation step q (read from the
  recording's own values), its white noise sigma_n beyond quantisation (estimated from the recording,
  model-free, by the fourth difference of the encoder, or given), and sigma_tau, what the torque noise
  the fit leaves explains (see :func:`alpes_dyn.estimation.identification.identification.identify`).
* **Validation** (:func:`fit_percent`, ``compare``): fit % = 100 (1 - ||y - yhat|| / ||y - mean y||)
  per encoder and NRMSE = ||y - yhat|| / ||y - mean y|| on a recording the fit did not see.
* **Signatures** (:func:`signatures`): the share of the residual explained by each known missing
  effect, measured as the encoder's response to that effect through the fitted model (a motor torque
  following the sign of the motor velocity: dry friction; the tension times that sign: the tendon's sheath
  friction (capstan); the velocity: viscous friction; the acceleration: a rotor's inertia on the tendon; an
  encoder reading ahead by the torque: an elastic tendon; a constant: an offset), in one joint regression
  (partial R^2).

The verdict (:func:`assess`, :class:`Adequacy`) is *not adequate* when the residual is coloured or
correlated with the input beyond the thresholds of :data:`THRESHOLDS` (measured on recordings of our
simulator with the model's own structure and with effects removed, see the identification guide), when
its RMS exceeds the floor by more than ``floor_ratio``, or when a validation's fit % is low.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping, Sequence

import numpy as np

from ...errors import AlpesDynWarning, InputError
from ...model.ratio_curve import encoder_angles, encoder_sensitivity
from .harmonics import NONLINEARITY, harmonic_ratio
from .responses import effect_responses, torque_explained  # noqa: F401 (re-exported: split for the module's length)

__all__ = ["AdequacyWarning", "compare", "THRESHOLDS", "Whiteness", "CrossCorrelation", "SensorFloor", "Validation", "Adequacy", "whiteness",
           "cross_correlation", "sensor_floor", "encoder_resolution", "white_noise_level", "fit_percent", "nrmse",
           "signatures", "assess", "SIGNATURES", "STATEFUL_FRICTION", "reversal_ratio", "range_exit", "JOINT_STOP", "RANGE_TOLERANCE"]

class AdequacyWarning(AlpesDynWarning):
    """An identification that did not converge or whose model is not adequate to the recording (one line)."""


BAND_99 = 2.5758293035489004  # the standard normal's 99.5 % quantile: the two-sided 99 % band

THRESHOLDS: dict[str, float] = {
    "lags": 25, "exact_counts": 0.05, "ljung_box_p": 1e-6, "max_acf_bands": 3.0, "max_xcorr_bands": 2.0,
    "floor_ratio": 1.15, "validation_fit_percent": 70.0, "signature_share": 0.02, "reversal_ratio": 2.0,
    "harmonic_ratio": 1.5, "drift_share": 0.5, "sheath_share": 0.1,
}
"""The verdict's thresholds.

``lags`` M; ``exact_counts``: a residual below this RMS (counts) is numerical, the fit exact (noise-free
data), and the other tests are skipped; coloured: the Ljung-Box p-value below ``ljung_box_p`` *or* some
|r_ee(k)| above ``max_acf_bands`` times the 99 % band (MATLAB's rule, every lag inside the band, rejects
white noise 22 % of the time over 25 lags; the multiple-shooting residual is not exactly white either:
its fitted start states take a little of it, and fits of our own simulator, the model exact, give small p-values
and lags somewhat outside the band); correlated with the input: some |r_eu(k)| above ``max_xcorr_bands``
bands; too large: residual RMS above ``floor_ratio`` times the sensor floor; a validation below
``validation_fit_percent`` %; a signature named, when the verdict is not adequate, where its effect
explains at least ``signature_share`` of the residual and at least half what the strongest one does
(the list is ordered, the most likely first); stick-slip named first where the residual's mean square
within 20 ms of the motor velocity's reversals exceeds ``reversal_ratio`` times its mean square elsewhere; a
nonlinearity shaped otherwise than in the model named (last) where the residual's power at the excitation's
harmonics and intermodulation products is over ``harmonic_ratio`` times its power elsewhere
(:func:`~alpes_dyn.estimation.identification.harmonics.harmonic_ratio`: white noise gives 1 within about 0.1); a
drift (a ramp of the offset or the torque's response to a ramp of the gain, each judged alone, the one explaining
more) named first from ``drift_share``, else where nothing else is (a rotor's misfit: 0.05); the tendon-sheath friction
(judged in the regression with the others, theirs without it) named first from ``sheath_share``, beside what the
others name (set between the shares of a plant with a sheath friction the model lacks and those of plants without
one, an elastic damped cable or a rotor the model lacks, well below)."""

JOINT_STOP = ("a joint stop (the fitted joints leave their range: the experiment drives the finger into a stop the "
              "model does not have; lower the excitation or trim its bias)")  # named first (range_exit)
RANGE_TOLERANCE = math.radians(1.0)  # rad: how far past a joint limit the fitted trajectory may go (range_exit)


def range_exit(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str]) -> str | None:
    """Where the fitted joint angles leave [lower - tol, upper + tol] (:data:`RANGE_TOLERANCE`). Joints without
    finite limits are not judged.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, n)
        The fitted joint angles, rad.
    lower : numpy.ndarray, shape (n,)
        The joints' lower limits, rad (-inf: none).
    upper : numpy.ndarray, shape (n,)
        The joints' upper limits, rad (inf: none).
    names : Sequence[str]
        (n,) the joints' names, for the phrases.

    Returns
    -------
    str or None
        One phrase per joint that leaves its range, joined by "; " ("q_1 down to -15.0 deg (limit 0)"), or None.
    """
    q = np.asarray(q, dtype=float)
    out = []
    for j, name in enumerate(names):
        lo, hi = float(lower[j]), float(upper[j])
        qmin, qmax = float(np.min(q[:, j])), float(np.max(q[:, j]))
        if math.isfinite(lo) and qmin < lo - RANGE_TOLERANCE:
            out.append(f"{name} down to {math.degrees(qmin):.1f} deg (limit {math.degrees(lo):.3g})")
        if math.isfinite(hi) and qmax > hi + RANGE_TOLERANCE:
            out.append(f"{name} up to {math.degrees(qmax):.1f} deg (limit {math.degrees(hi):.3g})")
    return "; ".join(out) or None


SIGNATURES: dict[str, str] = {
    "sign_velocity": "stick-slip / Coulomb friction (a torque following the sign of the motor velocity)",
    "tension_sign_velocity": "tendon-sheath friction, growing with the tension (a torque following |tau_m| times "
                             "the sign of the motor velocity: the capstan; --effects capstan)",
    "velocity": "viscous friction (a torque following the motor velocity)",
    "acceleration": "rotor inertia (a torque following the motor acceleration; or a wrong inertia)",
    "torque": "tendon elasticity (an encoder reading ahead of the joints by the motor torque)",
    "bias": "an encoder offset or a tilted palm (a constant bias of the residual)",
    "drift": "a drift of the encoder offset (a residual trending with time; --drift offset)",
    "gain_drift": "a drift of the torque constant (the response to the torque growing with time; --drift gain)",
    "torque_rate": "a torque delay (the recorded torque lagging the motor's: a torque following the torque's own "
                   "rate; --effects delay)",
}
"""Regressor name -> the likely missing effect it names."""
SHEATH = "tension_sign_velocity"  # the tendon-sheath friction's regressor (THRESHOLDS' sheath_share)
STATEFUL_FRICTION = ("a friction with a state (the residual at the velocity reversals or at the excitation's "
                     "harmonics: presliding before the joints slide, the LuGre law; --effects lugre)")
"""The likely missing effect :func:`assess` names where a memoryless friction's fit leaves its residual at the
reversals or the harmonics (before the nonlinearity of :data:`~.harmonics.NONLINEARITY`)."""


def _columns(x: np.ndarray, name: str, least: int = 10) -> np.ndarray:
    a = np.asarray(x, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2 or a.shape[0] < least:
        raise InputError(f"{name}: expected (N,) or (N, m) samples with N >= {least}, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise InputError(f"{name}: expected finite values")
    return a


def _check_lags(lags: int, n: int) -> int:
    if not isinstance(lags, (int, np.integer)) or isinstance(lags, bool) or not 1 <= lags < n // 2:
        raise InputError(f"lags: expected an integer from 1 to {n // 2 - 1}, got {lags!r}")
    return int(lags)


def _xcorr(a: np.ndarray, b: np.ndarray, lags: int) -> np.ndarray:
    """sum_k a_{k+l} b_k / N for l = -lags..lags (a, b (N,), means removed), by FFT."""
    n = a.shape[0]
    m = 1 << int(math.ceil(math.log2(2 * n)))
    full = np.fft.irfft(np.fft.rfft(a, m) * np.conj(np.fft.rfft(b, m)), m)
    return np.r_[full[m - lags:], full[: lags + 1]] / n


@dataclass
class Whiteness:
    """Whiteness of a residual (per column). acf: (M, m) r_ee(1..M); band: 2.58 / sqrt(N);
    ljung_box: (m,) Q; p_value: (m,) P(chi^2_M > Q); outside: (m,) lags outside the band."""

    acf: np.ndarray
    band: float
    ljung_box: np.ndarray
    p_value: np.ndarray
    outside: np.ndarray

    @property
    def max_acf(self) -> np.ndarray:
        """(m,) max_k |r_ee(k)|."""
        return np.max(np.abs(self.acf), axis=0)

    def to_dict(self) -> dict[str, Any]:
        return {"lags": int(self.acf.shape[0]), "band": self.band, "acf_lag1": _finite(self.acf[0]),
                "max_acf": _finite(self.max_acf), "ljung_box": _finite(self.ljung_box),
                "p_value": _finite(self.p_value), "lags_outside_band": [int(v) for v in self.outside]}


def whiteness(e: np.ndarray, lags: int = 25) -> Whiteness:
    """Residual autocorrelation test (MATLAB ``resid``; Ljung & Box 1978).

    r_ee(k) = sum_t e_t+k e_t / sum_t e_t^2 (means removed, the biased estimate); Q = N (N + 2)
    sum_{k=1..M} r_ee(k)^2 / (N - k), chi^2_M under whiteness.

    Parameters
    ----------
    e : numpy.ndarray, shape (N,) or (N, m)
        The residual, one column per encoder, counts (N >= 10, finite).
    lags : int, optional
        M, the lags tested, 1 to N // 2 - 1 (default 25).

    Returns
    -------
    Whiteness
        The autocorrelation (M, m), the 99 % band, the Ljung-Box Q, its p-value and the lags outside the band.

    Raises
    ------
    InputError
        ``e`` not (N,) or (N, m) finite samples with N >= 10, or ``lags`` out of range.
    """
    e = _columns(e, "residual")
    n, m = e.shape
    lags = _check_lags(lags, n)
    e = e - e.mean(axis=0)
    acf = np.zeros((lags, m))
    for j in range(m):  # a loop over encoders
        c = _xcorr(e[:, j], e[:, j], lags)[lags:]
        acf[:, j] = c[1:] / c[0] if c[0] > 0 else 0.0
    k = np.arange(1, lags + 1)[:, None]
    q = n * (n + 2) * np.sum(acf**2 / (n - k), axis=0)
    band = BAND_99 / math.sqrt(n)
    from scipy import stats  # here: importing scipy.stats takes a second, and every command imports this module

    return Whiteness(acf=acf, band=band, ljung_box=q, p_value=stats.chi2.sf(q, lags),
                     outside=np.sum(np.abs(acf) > band, axis=0))


@dataclass
class CrossCorrelation:
    """Residual-input cross-correlation. xcorr: (2M+1, m, nu) r_eu(k) for k = -M..M; band."""

    xcorr: np.ndarray
    band: float

    @property
    def max_xcorr(self) -> float:
        return float(np.max(np.abs(self.xcorr)))

    def to_dict(self) -> dict[str, Any]:
        lags = (self.xcorr.shape[0] - 1) // 2
        i = np.unravel_index(int(np.argmax(np.abs(self.xcorr))), self.xcorr.shape)
        return {"lags": int(lags), "band": self.band, "max_xcorr": _finite(self.max_xcorr),
                "at_lag": int(i[0] - lags), "lags_outside_band": int(np.sum(np.abs(self.xcorr) > self.band))}


def cross_correlation(e: np.ndarray, u: np.ndarray, lags: int = 25) -> CrossCorrelation:
    """r_eu(k) = sum_t e_t+k u_t / sqrt(sum e^2 sum u^2) (means removed), k = -M..M (MATLAB ``resid``);
    a positive lag: the residual after the input.

    Parameters
    ----------
    e : numpy.ndarray, shape (N,) or (N, m)
        The residual, one column per encoder, counts (N >= 10, finite).
    u : numpy.ndarray, shape (N,) or (N, nu)
        The input: the recorded motor torque, N m.
    lags : int, optional
        M, the largest lag either way, 1 to N // 2 - 1 (default 25).

    Returns
    -------
    CrossCorrelation
        r_eu (2M+1, m, nu) for k = -M..M and the 99 % band 2.58 / sqrt(N).

    Raises
    ------
    InputError
        ``e`` or ``u`` not finite (N,) or (N, k) samples with N >= 10, of different lengths, or ``lags`` out of
        range.
    """
    e, u = _columns(e, "residual"), _columns(u, "input")
    if u.shape[0] != e.shape[0]:
        raise InputError(f"input: expected {e.shape[0]} samples, got {u.shape[0]}")
    lags = _check_lags(lags, e.shape[0])
    e, u = e - e.mean(axis=0), u - u.mean(axis=0)
    out = np.zeros((2 * lags + 1, e.shape[1], u.shape[1]))
    for i in range(e.shape[1]):
        for j in range(u.shape[1]):
            den = math.sqrt(float(np.mean(e[:, i] ** 2) * np.mean(u[:, j] ** 2)))
            out[:, i, j] = _xcorr(e[:, i], u[:, j], lags) / den if den > 0 else 0.0
    return CrossCorrelation(xcorr=out, band=BAND_99 / math.sqrt(e.shape[0]))


def encoder_resolution(counts: np.ndarray) -> float:
    """The quantisation step of recorded encoder values.

    Parameters
    ----------
    counts : numpy.ndarray, shape (N,) or (N, m)
        The recorded encoder values, counts (N >= 10, finite).

    Returns
    -------
    float
        The step, counts: 1 for integer counts, the grid's step for values on a finer grid (down to 1/64, e.g.
        interpolated quarter counts), 0 for unquantised values.
    """
    y = _columns(counts, "encoder")
    for step in (1.0, 0.5, 0.25, 0.125, 1.0 / 16, 1.0 / 32, 1.0 / 64):
        if np.allclose(y / step, np.round(y / step), rtol=0, atol=1e-6):
            return step
    return 0.0


def white_noise_level(counts: np.ndarray) -> np.ndarray:
    """The standard deviation of the white part of each encoder column, model-free: the
    fourth difference d4 = y_k - 4 y_k+1 + 6 y_k+2 - 4 y_k+3 + y_k+4 of a white sequence has variance
    70 sigma^2, that of a motion sampled far above its bandwidth almost none (a 11 Hz sine of 1000
    counts at 1 kHz: 0.02 count). The RMS of d4, not a robust scale: d4 of integer counts is an
    integer, and its median absolute deviation was biased by 11 % (0.45 for 0.5 count of noise).
    Quantisation of a moving encoder included.

    Parameters
    ----------
    counts : numpy.ndarray, shape (N,) or (N, m)
        The recorded encoder values, counts (N >= 10, finite).

    Returns
    -------
    numpy.ndarray, shape (m,)
        The white noise's standard deviation per column, counts.
    """
    y = _columns(counts, "encoder")
    d4 = y[:-4] - 4 * y[1:-3] + 6 * y[2:-2] - 4 * y[3:-1] + y[4:]
    return np.sqrt(np.mean(d4**2, axis=0) / 70.0)


@dataclass
class SensorFloor:
    """What a right model leaves in the encoder residual, counts RMS per sample: ``total`` =
    sqrt(quantisation^2 + noise^2 + torque^2) with quantisation = step / sqrt(12), noise the encoder's
    white noise beyond it, torque what the torque noise explains."""

    step: float
    quantisation: float
    noise: float
    torque: float
    noise_source: str

    @property
    def total(self) -> float:
        return math.sqrt(self.quantisation**2 + self.noise**2 + self.torque**2)

    def to_dict(self) -> dict[str, Any]:
        return {"total": _finite(self.total), "step": _finite(self.step), "quantisation": _finite(self.quantisation),
                "noise": _finite(self.noise), "torque": _finite(self.torque), "noise_source": self.noise_source,
                "unit": "counts"}


def sensor_floor(counts: np.ndarray, torque_explained: float = 0.0, encoder_noise: float | None = None) -> SensorFloor:
    """The sensor floor of a recording's encoder (counts): its quantisation step from its own values
    (:func:`encoder_resolution`), its white noise beyond quantisation and what the torque noise explains.

    Parameters
    ----------
    counts : numpy.ndarray, shape (N,) or (N, m)
        The recorded encoder values, counts (N >= 10, finite).
    torque_explained : float, optional
        What the recorded torque's noise explains through the fitted model, counts RMS (default 0).
    encoder_noise : float or None, optional
        The encoder's white noise beyond quantisation, counts (default None: estimated, :func:`white_noise_level`,
        minus the quantisation's share).

    Returns
    -------
    SensorFloor
        The step, the quantisation (step / sqrt(12)), the noise, the torque's part and where the noise came from.

    Raises
    ------
    InputError
        ``counts`` not finite samples, or ``encoder_noise`` or ``torque_explained`` negative or not finite.
    """
    step = encoder_resolution(counts)
    quant = step / math.sqrt(12.0)
    if encoder_noise is None:
        white = float(np.sqrt(np.mean(white_noise_level(counts) ** 2)))
        noise, src = math.sqrt(max(white**2 - quant**2, 0.0)), "estimated from the recording (fourth difference)"
    else:
        if not (isinstance(encoder_noise, (int, float)) and math.isfinite(encoder_noise) and encoder_noise >= 0):
            raise InputError(f"encoder_noise: expected a non-negative number of counts, got {encoder_noise!r}")
        noise, src = float(encoder_noise), "given"
    if not (math.isfinite(torque_explained) and torque_explained >= 0):
        raise InputError(f"torque_explained: expected a non-negative number of counts, got {torque_explained!r}")
    return SensorFloor(step=step, quantisation=quant, noise=noise, torque=float(torque_explained), noise_source=src)


def fit_percent(y: np.ndarray, yhat: np.ndarray) -> np.ndarray:
    """MATLAB ``compare``'s fit: 100 (1 - ||y - yhat|| / ||y - mean(y)||) per column, %.

    Parameters
    ----------
    y : numpy.ndarray, shape (N,) or (N, m)
        The measured output (encoder counts; any unit, the same as ``yhat``'s).
    yhat : numpy.ndarray, shape of ``y``
        The model's output.

    Returns
    -------
    numpy.ndarray, shape (m,)
        The fit per column, % (100: perfect; 0: no better than the mean; negative: worse).

    Raises
    ------
    InputError
        As :func:`nrmse`.
    """
    return 100.0 * (1.0 - nrmse(y, yhat))


def nrmse(y: np.ndarray, yhat: np.ndarray) -> np.ndarray:
    """||y - yhat|| / ||y - mean(y)|| per column.

    Parameters
    ----------
    y : numpy.ndarray, shape (N,) or (N, m)
        The measured output (encoder counts; any unit, the same as ``yhat``'s), N >= 2.
    yhat : numpy.ndarray, shape of ``y``
        The model's output.

    Returns
    -------
    numpy.ndarray, shape (m,)
        The normalised RMS error per column (0: perfect; 1: no better than the mean).

    Raises
    ------
    InputError
        ``y`` or ``yhat`` not finite, of different shapes, or a column of ``y`` constant.
    """
    y, yhat = _columns(y, "y", 2), _columns(yhat, "yhat", 2)
    if y.shape != yhat.shape:
        raise InputError(f"yhat: expected shape {y.shape}, got {yhat.shape}")
    den = np.linalg.norm(y - y.mean(axis=0), axis=0)
    if np.any(den == 0):
        raise InputError("y: an encoder that never moves has no fit % (||y - mean y|| = 0)")
    return np.linalg.norm(y - yhat, axis=0) / den


def signatures(e: np.ndarray, responses: Mapping[str, np.ndarray]) -> dict[str, dict[str, float]]:
    """What each candidate missing effect explains of the residual: the residual regressed jointly on the
    effects' responses and a constant (``"bias"``).

    Parameters
    ----------
    e : numpy.ndarray, shape (N, m)
        The encoder residual, counts.
    responses : Mapping[str, numpy.ndarray]
        Effect name -> (N, m) the encoder's response, counts, to a unit of the effect through the fitted model
        (see :func:`~alpes_dyn.estimation.identification.identification.identify`).

    Returns
    -------
    dict[str, dict[str, float]]
        Per effect (and ``"bias"``) its ``share``, the partial R^2 (the fraction of the residual's sum of squares
        that the joint regression loses without that effect), and ``coefficient`` (counts per unit).
    """
    e = _columns(e, "residual").reshape(-1)
    names = [k for k in responses] + ["bias"]
    A = np.empty((e.size, len(names)), order="F")
    for i, k in enumerate(responses):  # a loop over the few effects
        A[:, i] = _columns(responses[k], k).reshape(-1)
    A[:, -1] = 1.0
    scale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    A /= scale
    sst = float(e @ e)
    out: dict[str, dict[str, float]] = {}
    if sst == 0:
        return {k: {"share": 0.0, "coefficient": 0.0} for k in names}
    # one QR of the regressors, A = Q R: the least squares of e on any subset of A's columns is that of Q'e on the
    # same columns of R (A_s = Q R_s: the same singular values, so lstsq's rank is the same) plus the part of e
    # outside A's span, the same for every subset. The long record's (N, k) copies are made once, not per subset
    # (the adequacy check's peak at 600 s: the subsets' copies, lstsq's own and the fitted values')
    Q, R = np.linalg.qr(A)
    del A
    qe = Q.T @ e
    outside = e - Q @ qe
    del Q
    base = float(outside @ outside)

    def sse(cols_: list[int]) -> tuple[float, np.ndarray]:
        c = np.linalg.lstsq(R[:, cols_], qe, rcond=None)[0]
        r = qe - R[:, cols_] @ c
        return base + float(r @ r), c

    full, coef = sse(list(range(len(names))))
    for i, k in enumerate(names):  # a loop over the few effects
        without, _ = sse([j for j in range(len(names)) if j != i])
        out[k] = {"share": max(without - full, 0.0) / sst, "coefficient": float(coef[i] / scale[i])}
    return out


@dataclass
class Validation:
    """A ``compare``-style validation on a held-out recording: fit % and NRMSE per encoder, residual RMS
    (counts) on the scored samples, after a prefix of ``prefix_s`` seconds where the initial state
    was estimated."""

    fit_percent: np.ndarray
    nrmse: np.ndarray
    residual_rms: float
    prefix_s: float
    samples: int
    recording_path: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"fit_percent": _finite(self.fit_percent), "nrmse": _finite(self.nrmse),
                "residual_rms": _finite(self.residual_rms), "prefix_s": self.prefix_s, "samples": self.samples,
                "recording": self.recording_path}


@dataclass
class Adequacy:
    """The verdict. adequate; reasons: why not (empty when adequate); likely_missing: the effects
    whose signature the residual shows (named where known, :data:`SIGNATURES`); the statistics; notes:
    tests not judged and why."""

    adequate: bool
    reasons: list[str]
    likely_missing: list[str]
    residual_rms: float
    floor: SensorFloor
    whiteness: Whiteness | None
    cross: CrossCorrelation | None
    signatures: dict[str, dict[str, float]] = field(default_factory=dict)
    validation: Validation | None = None
    notes: list[str] = field(default_factory=list)
    observer: Any = None
    """The observer's check of the identified file where it was judged
    (:class:`~alpes_dyn.estimation.identification.observer_check.ObserverCheck`), else None."""

    @property
    def floor_ratio(self) -> float:
        """Residual RMS over the sensor floor (inf when the floor is 0)."""
        f = self.floor.total
        return self.residual_rms / f if f > 0 else (0.0 if self.residual_rms == 0 else math.inf)

    def summary(self) -> str:
        """One line: the verdict and why."""
        if self.adequate:
            return f"model adequate (residual {self.residual_rms:.3g} counts, {self.floor_ratio:.2f}x the sensor floor)"
        miss = f"; likely missing: {', '.join(self.likely_missing)}" if self.likely_missing else ""
        return f"model NOT adequate: {'; '.join(self.reasons)}{miss}"

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (finite numbers only; an infinite ratio is None)."""
        return {"adequate": self.adequate, "reasons": list(self.reasons), "likely_missing": list(self.likely_missing),
                "residual_rms": _finite(self.residual_rms), "floor": self.floor.to_dict(),
                "floor_ratio": _finite(self.floor_ratio),
                "whiteness": self.whiteness.to_dict() if self.whiteness is not None else None,
                "cross_correlation": self.cross.to_dict() if self.cross is not None else None,
                "signatures": {k: {"share": _finite(v["share"]), "coefficient": _finite(v["coefficient"])}
                               for k, v in self.signatures.items()},
                "validation": self.validation.to_dict() if self.validation is not None else None,
                "notes": list(self.notes), "thresholds": dict(THRESHOLDS),
                "observer": None if self.observer is None else self.observer.to_dict()}


def _finite(x: Any) -> Any:
    """float / list of floats with every non-finite value None (JSON has no NaN)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0:
        v = float(a)
        return v if math.isfinite(v) else None
    return [v if math.isfinite(v) else None for v in a.reshape(-1).tolist()]


def reversal_ratio(e: np.ndarray, velocity: np.ndarray, window: int = 20) -> float:
    """Mean square of the residual within ``window`` samples of a motor velocity reversal (a sign change),
    over its mean square elsewhere (1 for a residual that does not care; stick-slip friction makes it
    large where the plant sticks and the model slides); per encoder, the largest.

    Parameters
    ----------
    e : numpy.ndarray, shape (N, m)
        The encoder residual, counts.
    velocity : numpy.ndarray, shape (N, m)
        The fitted motor velocity, rad/s (its sign changes are the reversals).
    window : int, optional
        Samples either side of a reversal counted as near it (default 20: 20 ms at 1 kHz).

    Returns
    -------
    float
        The largest ratio over the encoders, at least 1 (1 where an encoder has fewer than 10 samples near or
        away from a reversal).
    """
    e, v = _columns(e, "residual"), _columns(velocity, "velocity")
    best = 1.0
    for j in range(e.shape[1]):  # a loop over encoders
        flips = np.flatnonzero(np.sign(v[1:, j]) != np.sign(v[:-1, j]))
        near = np.zeros(e.shape[0], dtype=bool)
        if flips.size:
            d = np.zeros(e.shape[0] + 1)
            np.add.at(d, np.maximum(flips - window, 0), 1)
            np.add.at(d, np.minimum(flips + window + 1, e.shape[0]), -1)
            near = np.cumsum(d)[:-1] > 0
        if near.sum() >= 10 and (~near).sum() >= 10:
            inside, outside = float(np.mean(e[near, j] ** 2)), float(np.mean(e[~near, j] ** 2))
            if outside > 0:
                best = max(best, inside / outside)
    return best


def assess(e: np.ndarray, u: np.ndarray, floor: SensorFloor, regressors: Mapping[str, np.ndarray] | None = None,
           validation: Validation | None = None, thresholds: Mapping[str, float] | None = None,
           velocity: np.ndarray | None = None, range_exit: str | None = None,
           lines: Sequence[float] | None = None, dt: float | None = None,
           runs: Sequence[int] | None = None, stateful: bool = False) -> Adequacy:
    """The verdict on a fit's encoder residual.

    Parameters
    ----------
    e : numpy.ndarray, shape (N, m)
        The residual y - yhat, counts.
    u : numpy.ndarray, shape (N, nu)
        The recorded motor torque, N m.
    floor : SensorFloor
        The recording's sensor floor (:func:`sensor_floor`).
    regressors : Mapping[str, numpy.ndarray] or None, optional
        Name -> (N, m) the encoder's responses to candidate missing effects (keys of :data:`SIGNATURES`, see
        :func:`signatures`; the tendon-sheath friction's ``tension_sign_velocity`` is judged in the regression
        with the others, and theirs without it: it did not change what they name, e.g. a rotor's, whose
        acceleration lost a third of its share to it on finger3). Default None: no signature.
    validation : Validation or None, optional
        A held-out recording's :class:`Validation` (default None).
    thresholds : Mapping[str, float] or None, optional
        Overrides of :data:`THRESHOLDS` (default None).
    velocity : numpy.ndarray or None, optional
        (N, m) the fitted motor velocity, rad/s: the residual at its reversals (:func:`reversal_ratio`) names
        stick-slip friction first when above ``reversal_ratio`` (default None: not judged).
    range_exit : str or None, optional
        Where the fitted joints leave their range, which and how far (the caller's :func:`range_exit`): a reason
        of its own, and a joint stop named first among the likely missing effects (default None).
    lines : Sequence[float] or None, optional
        The excitation's frequencies, Hz: with ``dt``, the residual's power at their harmonics and
        intermodulation (:func:`~alpes_dyn.estimation.identification.harmonics.harmonic_ratio`, signature
        ``harmonics``) names a nonlinearity shaped otherwise than in the model, after the others, above
        ``harmonic_ratio`` (default None: not judged).
    dt : float or None, optional
        The sample time, s (default None).
    runs : Sequence[int] or None, optional
        The first sample of each part whose excitation restarts, then N (runs, a turned recording's
        orientations): the harmonics judged part by part (default None: one part).
    stateful : bool, optional
        The fitted model's friction has a state already (the LuGre law); else (default False) a residual at the
        reversals above ``reversal_ratio`` or a nonlinearity at the harmonics names a friction with a state too
        (:data:`STATEFUL_FRICTION`, after stick-slip).

    Returns
    -------
    Adequacy
        The verdict, its reasons, the likely missing effects and the statistics.

    Raises
    ------
    InputError
        ``e`` or ``u`` (or ``velocity``, a regressor) not finite samples of matching lengths.
    """
    th = {**THRESHOLDS, **(thresholds or {})}
    e = _columns(e, "residual")
    rms = float(np.sqrt(np.mean(e**2)))
    reasons: list[str] = []
    if rms < th["exact_counts"]:  # numerical residual (noise-free data): nothing left to explain
        if validation is not None and np.min(validation.fit_percent) < th["validation_fit_percent"]:
            reasons.append(f"validation fit {np.min(validation.fit_percent):.1f} % < {th['validation_fit_percent']:g} %")
        return Adequacy(not reasons, reasons, [], rms, floor, None, None, {}, validation)
    lags = int(th["lags"])
    w = whiteness(e, lags)
    x = cross_correlation(e, u, lags)
    # where the torque noise's response dominates the floor (a fit without the excitation's lines, the
    # torque noise given), even a right model leaves a coloured residual correlated with the measured
    # torque: then the floor alone decides
    white_floor = math.hypot(floor.quantisation, floor.noise)
    notes = []
    if floor.torque > white_floor:
        notes.append(f"whiteness and cross-correlation not judged: the torque noise explains {floor.torque:.3g} "
                     f"counts of the floor, more than the encoder's white {white_floor:.3g}")
    coloured = not notes and bool(np.any((w.p_value < th["ljung_box_p"]) | (w.max_acf > th["max_acf_bands"] * w.band)))
    if coloured:
        j = int(np.argmax(w.max_acf))
        reasons.append(f"residual coloured (autocorrelation up to {w.max_acf[j]:.2f} against a 99 % band of "
                       f"{w.band:.3f}; Ljung-Box p = {w.p_value[j]:.2g})")
    if not notes and x.max_xcorr > th["max_xcorr_bands"] * x.band:
        reasons.append(f"residual correlated with the motor torque ({x.max_xcorr:.2f} against a 99 % band of "
                       f"{x.band:.3f})")
    ratio = rms / floor.total if floor.total > 0 else math.inf
    if ratio > th["floor_ratio"]:
        reasons.append(f"residual {rms:.3g} counts RMS is {ratio:.2f}x the sensor floor {floor.total:.3g}")
    if validation is not None and np.min(validation.fit_percent) < th["validation_fit_percent"]:
        reasons.append(f"validation fit {np.min(validation.fit_percent):.1f} % < {th['validation_fit_percent']:g} %")
    regs = dict(regressors or {})  # the drifts' (a ramp of the offset, of the gain) judged alone: they take others' shares
    ramps = {k: regs.pop(k) for k in ("drift", "gain_drift") if k in regs}
    sheath = regs.pop(SHEATH, None)  # its share in the regression with the others, theirs without it
    sig = {**signatures(e, regs), **{k: signatures(e, {k: R})[k] for k, R in ramps.items()}}
    if sheath is not None:
        sig[SHEATH] = signatures(e, {**regs, SHEATH: sheath})[SHEATH]
    if velocity is not None:
        sig["reversals"] = {"share": reversal_ratio(e, velocity), "coefficient": 0.0}
    if lines is not None and len(lines) and dt is not None:
        sig["harmonics"] = {"share": harmonic_ratio(e, lines, dt, runs=runs), "coefficient": 0.0}
    if range_exit:
        reasons.append(f"the fitted joints leave their range ({range_exit})")
    missing: list[str] = []
    if reasons:
        ranked = sorted(((v["share"], k) for k, v in sig.items() if k in SIGNATURES and k not in ramps
                         and k != SHEATH), reverse=True)
        top = ranked[0][0] if ranked else 0.0
        missing = [SIGNATURES[k] for s, k in ranked if s >= max(th["signature_share"], 0.5 * top)
                   and (k != "torque_rate" or s == top)]  # a delay named where it explains the most: a rotor's
        # acceleration response is close to the torque's rate (a rotor mismatch named both)
        ramp = max(ramps, key=lambda k: sig[k]["share"], default=None)  # the offset's or the gain's, the stronger
        if ramp and sig[ramp]["share"] >= (th["drift_share"] if missing else th["signature_share"]):
            missing = [SIGNATURES[ramp]] + missing  # (THRESHOLDS' docstring)
        if sig.get(SHEATH, {}).get("share", 0.0) >= th["sheath_share"]:
            missing = [SIGNATURES[SHEATH]] + missing
        if "reversals" in sig and sig["reversals"]["share"] > th["reversal_ratio"]:
            stick = SIGNATURES["sign_velocity"]
            missing = [stick] + [m for m in missing if m != stick]
        if "harmonics" in sig and sig["harmonics"]["share"] > th["harmonic_ratio"]:
            missing.append(NONLINEARITY)
        if not stateful and (NONLINEARITY in missing or sig.get("reversals", {}).get("share", 0.0)
                             > th["reversal_ratio"]):
            missing.insert(missing.index(NONLINEARITY) if NONLINEARITY in missing else len(missing), STATEFUL_FRICTION)
        if range_exit:
            missing = [JOINT_STOP] + missing
    return Adequacy(not reasons, reasons, missing, rms, floor, w, x, sig, validation, notes)


def compare(sens: Any, theta: np.ndarray, x0: np.ndarray, U: np.ndarray, G: np.ndarray, y: np.ndarray,
            S: np.ndarray, step: float, prefix: int, recording_path: str = "") -> Validation:
    """MATLAB ``compare`` on a held-out recording: the identified model simulated open-loop on its
    measured torque, after its initial state is estimated on the first ``prefix`` samples only. Why not the
    fit's multiple shooting: restarting every 100 ms from states fitted to the data would hide a model that
    drifts; open-loop is what an observer's prediction or a controller's feedforward does between corrections.

    Parameters
    ----------
    sens : SensitivityModel
        The fit's :class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`.
    theta : numpy.ndarray, shape (p,)
        Its identified parameters, each in its unit.
    x0 : numpy.ndarray, shape (2n,)
        A first guess of the initial state [q; qd], rad and rad/s (the rest under U[0]).
    U : numpy.ndarray, shape (N, nu)
        The held-out recording's measured motor torque, N m.
    G : numpy.ndarray, shape (N, 3)
        The gravity vector per sample, m/s^2 (the recording's).
    y : numpy.ndarray, shape (N+1, m)
        The recorded encoders, counts.
    S : numpy.ndarray, shape (m, n), or RatioCurve
        The transmission from the joints to the encoders.
    step : float
        The encoder's resolution, rad per count.
    prefix : int
        Samples (>= 2) of the initial-state estimate, excluded from the score: with the start state unknown the
        finger's lightly damped modes would otherwise weigh on the score, and scoring the samples that fixed it
        would flatter the model (MATLAB estimates it the same way, its ``InitialCondition`` ``'e'``).
    recording_path : str, optional
        The held-out recording's path, for the report (default "").

    Returns
    -------
    Validation
        Fit % and NRMSE per encoder and the residual RMS (counts) on the samples after ``prefix``.
    """
    N = U.shape[0]
    nb = sens.nb
    C = np.zeros((1, sens.nu, nb)) if nb else None
    phi = np.zeros((1, N, nb)) if nb else None
    n = sens.n
    x = np.zeros(getattr(sens, "nx", 2 * n))  # a LuGre model's bristles (beyond [q; qd]) start relaxed, at 0
    x[: 2 * n] = np.asarray(x0, dtype=float)[: 2 * n]
    yp = y[: prefix + 1] * step
    mu = 1e-3
    for _ in range(10):  # Levenberg-Marquardt on the initial state alone, on the prefix
        xs, X = sens.run(x[None], U[None, :prefix], G[None, :prefix], theta, None if C is None else C,
                         basis=None if phi is None else phi[:, :prefix])
        r = (encoder_angles(S, xs[0, :, :n]) - yp).reshape(-1)
        A = encoder_sensitivity(S, xs[0, :, :n], X[0, :, :n, : 2 * n]).reshape(-1, 2 * n)
        H = A.T @ A
        d = -np.linalg.lstsq(H + mu * np.diag(np.diag(H) + 1e-300), A.T @ r, rcond=None)[0]
        d = np.concatenate([d, np.zeros(x.size - d.size)])  # the initial state's [q; qd] only
        xt, _ = sens.run((x + d)[None], U[None, :prefix], G[None, :prefix], theta, C,
                         basis=None if phi is None else phi[:, :prefix], sensitivities=False)
        if np.isfinite(xt).all() and np.sum((encoder_angles(S, xt[0, :, :n]) - yp) ** 2) < np.sum(r**2):
            x, mu = x + d, mu / 10
        else:
            mu *= 10
    xs, _ = sens.run(x[None], U[None], G[None], theta, C, basis=phi, sensitivities=False)
    yhat = encoder_angles(S, xs[0, :, :n]) / step
    if not np.isfinite(yhat).all():
        yhat = np.nan_to_num(yhat, nan=0.0, posinf=0.0, neginf=0.0)  # diverged: the fit % shows it
    ys, yh = y[prefix:], yhat[prefix:]
    return Validation(fit_percent=fit_percent(ys, yh), nrmse=nrmse(ys, yh),
                      residual_rms=float(np.sqrt(np.mean((ys - yh) ** 2))), prefix_s=0.0, samples=int(ys.shape[0]),
                      recording_path=recording_path)
