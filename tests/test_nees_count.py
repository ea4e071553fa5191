"""The NEES's count of independent samples checked against the series itself (issue 50 item 3): the measured count
of an autoregressive series against its closed form, and, on a plant that IS the observer's model (our simulator
with the file's smooth law, the torque sensor's noise), each joint's NEES in its band with the filter's count
matching the measured one. The band is the reference the friction study's over-confident joints are judged by."""

import numpy as np
import pytest

from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.consistency import measured_effective, nees


@pytest.mark.parametrize("phi", [0.0, 0.5, 0.8])
def test_the_measured_count_of_an_ar1_series_is_its_closed_form(phi):
    """An AR(1) x_k = phi x_k-1 + w_k: the variance of its mean is that of M (1 - phi) / (1 + phi) independent
    samples."""
    from scipy.signal import lfilter

    w = np.random.default_rng(9650).standard_normal(200_000)
    x = lfilter([1.0], [1.0, -phi], w)
    assert measured_effective(x) / x.size == pytest.approx((1 - phi) / (1 + phi), rel=0.08)


@pytest.mark.parametrize("series", [np.ones((10, 2)), [1.0], [1.0, np.nan, 2.0]])
def test_bad_input_is_named(series):
    with pytest.raises(InputError, match="^series:"):
        measured_effective(series)


def test_a_constant_series_counts_every_sample():
    assert measured_effective(np.full(7, 3.0)) == pytest.approx(7.0)


@pytest.mark.parametrize("series", [[0.3, 1.7], [1.0, -1.0] * 20, [2.0, 5.0, 1.0]])
def test_an_anticorrelated_series_counts_its_samples_without_a_division_by_zero(series):
    """Two samples always have rho_1 = -1/2 (1 + 2 sum rho_l = 0); an alternating series is more anticorrelated
    still: the variance of the mean is at most that of M independent samples, so the count is M, and no
    floating-point warning (the former M / 0 that the observer check of a 0.3 s record printed)."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert measured_effective(series) == pytest.approx(len(series))


def test_on_a_plant_that_is_the_model_each_joint_is_in_its_band_and_the_count_is_the_filters():
    """Our simulator with the file's smooth law (the model exact but for the torque sensor's 5e-4 N m noise): every
    joint's NEES in its band, and the count the filter predicts from its own error model within a factor 1.5 of the
    one the NEES series shows (the filter 36 of 41 samples, the series 41 on this draw)."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    r = run_estimation("ekf", duration=5.0, seed=9652, friction=True)
    v = nees(r.estimate, r.q_true, r.filter, r.u_meas, start=r.scenario.transient_s)
    lo, hi = v.joint_band()
    assert np.all((lo <= v.per_joint) & (v.per_joint <= hi)), v.to_dict()
    assert 1 / 1.5 <= v.measured / v.effective <= 1.5, v.to_dict()
    assert v.joint_measured.shape == (3,) and np.all(v.joint_measured <= v.samples)
    assert v.to_dict()["measured_effective_samples"] == pytest.approx(v.measured)
