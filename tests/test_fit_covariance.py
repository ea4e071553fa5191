"""The fit's covariance robust to a coloured residual (issue 50, alpes_dyn.estimation.identification.robust_covariance):
on a linear regression with AR(1) noise the HAC sandwich gives the known covariance of the least-squares estimate
where the classical one is too small by the known factor; on white noise both agree; on a fit of the library's own
simulator (a white residual) the robust standard errors are the classical ones to 30 %, and the fit reports the
larger with which one it is."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.identification.identification import identify
from alpes_dyn.estimation.identification.robust_covariance import correlation_window, hac, reported_covariance
from alpes_dyn.model.params import load_params

T = 4000


def _design(T: int, rng: np.random.Generator) -> np.ndarray:
    """(T, 3) regressors: a constant, a slow sine (three periods), a white one."""
    t = np.arange(T)
    return np.column_stack([np.ones(T), np.sin(2 * np.pi * 3 * t / T), rng.standard_normal(T)])


def _ar1(phi: float, T: int, rng: np.random.Generator) -> np.ndarray:
    """Stationary AR(1) noise of unit innovation variance."""
    e = rng.standard_normal(T)
    e[0] /= np.sqrt(1 - phi**2)
    return lfilter([1.0], [1.0, -phi], e)


def _true_covariance(X: np.ndarray, phi: float) -> np.ndarray:
    """The exact covariance of the OLS estimate under stationary AR(1) noise (unit innovations):
    (X'X)^-1 X' Sigma X (X'X)^-1 with Sigma_ij = phi^|i-j| / (1 - phi^2), Sigma X by the filter run both ways."""
    fwd = lfilter([1.0], [1.0, -phi], X, axis=0)
    bwd = lfilter([1.0], [1.0, -phi], X[::-1], axis=0)[::-1]
    SX = (fwd + bwd - X) / (1 - phi**2)
    B = np.linalg.inv(X.T @ X)
    return B @ (X.T @ SX) @ B


def _ols(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(estimate, classical covariance s^2 (X'X)^-1, robust covariance (HAC sandwich, the window from the
    residual)) of y on X."""
    B = np.linalg.inv(X.T @ X)
    beta = B @ X.T @ y
    r = y - X @ beta
    classical = B * (r @ r) / (len(y) - X.shape[1])
    h = (X * r[:, None]) @ B  # each sample's influence on the estimate
    return beta, classical, hac(h, correlation_window(r))


def test_the_sandwich_gives_the_known_covariance_under_ar1_noise():
    """phi = 0.7, 4000 samples, 40 draws: the robust standard errors (their mean variance) within 25 % of the exact
    ones, and of the Monte Carlo spread of the estimates (within its own sampling error); the classical ones too
    small on the constant and the slow sine by sqrt((1 - phi) / (1 + phi)) = 0.42 (15 %), right on the white
    regressor, where the colour averages out."""
    rng = np.random.default_rng(50)
    phi = 0.7
    X = _design(T, rng)
    true_sd = np.sqrt(np.diag(_true_covariance(X, phi)))
    draws = [_ols(X, X @ np.array([1.0, 0.5, -0.3]) + _ar1(phi, T, rng)) for _ in range(40)]
    beta = np.array([d[0] for d in draws])
    robust = np.sqrt(np.mean([np.diag(d[2]) for d in draws], axis=0))
    classical = np.sqrt(np.mean([np.diag(d[1]) for d in draws], axis=0))
    np.testing.assert_allclose(robust / true_sd, 1.0, atol=0.25)
    np.testing.assert_allclose(beta.std(axis=0) / true_sd, 1.0, atol=0.35)  # the reference's own check (40 draws)
    factor = np.sqrt((1 - phi) / (1 + phi))
    np.testing.assert_allclose(classical[:2] / true_sd[:2], factor, rtol=0.15)
    assert classical[2] / true_sd[2] == pytest.approx(1.0, abs=0.15)
    # draw by draw too: every draw's robust errors within 40 % of the exact ones
    each = np.sqrt(np.array([np.diag(d[2]) for d in draws])) / true_sd
    assert np.all(np.abs(each - 1.0) < 0.4)


def test_on_white_noise_the_sandwich_is_the_classical_covariance():
    """White noise, one draw of 4000 samples: a short window (<= 8 samples) and the robust standard errors within
    15 % of the classical ones, both within 15 % of the exact sigma (X'X)^-1."""
    rng = np.random.default_rng(51)
    X = _design(T, rng)
    _, classical, robust = _ols(X, X @ np.array([1.0, 0.5, -0.3]) + rng.standard_normal(T))
    r = rng.standard_normal(T)
    assert correlation_window(r) <= 8
    exact = np.sqrt(np.diag(np.linalg.inv(X.T @ X)))
    np.testing.assert_allclose(np.sqrt(np.diag(robust)) / np.sqrt(np.diag(classical)), 1.0, atol=0.15)
    np.testing.assert_allclose(np.sqrt(np.diag(classical)) / exact, 1.0, atol=0.15)


def test_the_window_and_the_bartlett_sum():
    """The window grows with the residual's colour (AR(1) 0.7: tau = 5.7, the window 5 tau to a few samples);
    the Bartlett sum equals its definition lag by lag; the reported covariance takes each larger variance; bad
    inputs are typed errors naming the field."""
    rng = np.random.default_rng(52)
    w = correlation_window(_ar1(0.7, 20000, rng))
    assert 20 <= w <= 45
    two = np.column_stack([rng.standard_normal(20000), _ar1(0.9, 20000, rng)])
    assert correlation_window(two) > correlation_window(two[:, 0]) + 30  # the more coloured channel decides
    h = rng.standard_normal((300, 3))
    M = 7
    ref = h.T @ h
    for lag in range(1, M + 1):
        g = h[lag:].T @ h[:-lag]
        ref += (1 - lag / (M + 1)) * (g + g.T)
    np.testing.assert_allclose(hac(h, M), ref, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(hac(h, 0), h.T @ h, rtol=1e-12)
    c, r = np.diag([4.0, 1.0]), np.array([[2.0, 1.0], [1.0, 3.0]])
    P, larger = reported_covariance(c, r)
    np.testing.assert_allclose(np.diag(P), [4.0, 3.0])
    assert list(larger) == [False, True] and np.all(np.linalg.eigvalsh(P) > 0)
    with pytest.raises(InputError, match="^lags:"):
        hac(h, -1)
    with pytest.raises(InputError, match="^residual:"):
        correlation_window(np.array([1.0, np.nan, 2.0, 3.0, 4.0]))


def test_a_fit_of_the_own_simulator_reports_the_larger_and_says_which(tmp_path):
    """finger3 +-20 % (seed 731), 2 s of the experiment with its sensors: a white residual, so the robust standard
    errors are the classical ones within 30 %; the reported std is the larger of the two, parameter by parameter;
    the JSON and the parameter file say which one each parameter's is."""
    design = ExperimentDesign(duration=2.0)
    rec = experiment("finger3", perturbed_params(spread=0.2, seed=731), design, seed=731)
    res = identify(ad.Model.alpes("finger3", friction=True), rec, excitation=design.lines, progress=False)
    se = res.standard_errors
    assert res.converged and se is not None
    np.testing.assert_allclose(se.robust / se.classical, 1.0, atol=0.3)
    np.testing.assert_allclose(res.std, np.maximum(se.classical, se.robust), rtol=1e-12)
    assert se.method.window <= 20  # the residual's colour: a few samples
    out = res.to_dict()
    for k, name in enumerate(res.names):
        entry = out["parameters"][name]
        assert entry["std_from"] == ("robust" if se.robust[k] > se.classical[k] else "classical")
        assert entry["std"] == pytest.approx(max(entry["std_classical"], entry["std_robust"]))
    assert out["standard_errors"]["rule"] == "max(classical, robust) per parameter"
    assert out["standard_errors"]["window_samples"] == se.method.window
    p = load_params(res.write(tmp_path / "ident.toml", base=load_params()))
    assert p.identification["finger"]["standard_errors"].startswith("std = max(classical, robust)")
