"""A slow drift of the encoder offsets fitted with the parameters (issue 39: identify(drift="offset"), module drift):
its basis against the piecewise-linear function it stands for, and a fit of a recording whose encoder drifts by a
known ramp, with and without the drift."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.experiments.recording import Recording, join_runs
from alpes_dyn.estimation.identification.adequacy import SIGNATURES
from alpes_dyn.estimation.identification.drift import drift_basis, recorded_time
from alpes_dyn.estimation.identification.identification import identify


def _rec(t: np.ndarray) -> Recording:
    n = t.shape[0]
    return Recording(t=t, encoder=np.arange(n, dtype=float)[:, None], torque=np.zeros((n, 1)),
                     motor_names=("finger",), joint_names=("j1", "j2"))


def test_the_drift_basis_is_the_piecewise_linear_interpolant_of_its_knots():
    """40 s at 10 ms: ceil(40 / 15) = 3 segments, knots at 0, 13.33, 26.67, 40 s; H d equals numpy's interpolation
    of (0, d1, d2, d3) at every sample. Two runs, the second's clock restarted: the recorded time runs on."""
    t = 0.01 * np.arange(4001)
    H = drift_basis(_rec(t))
    d = np.array([3.0, -2.0, 7.5])
    assert H.shape == (4001, 3)
    assert np.allclose(H @ d, np.interp(t, [0.0, 40 / 3, 80 / 3, 40.0], np.r_[0.0, d]), atol=1e-12)
    a, b = _rec(0.01 * np.arange(200)), _rec(0.01 * np.arange(300))
    tau = recorded_time(join_runs([a, b]))
    assert np.allclose(tau, 0.01 * np.arange(500), atol=1e-12)
    assert drift_basis(_rec(0.01 * np.arange(401))).shape == (401, 1)  # 4 s: a ramp, 1 at the end
    assert np.allclose(drift_basis(_rec(0.01 * np.arange(401)))[:, 0], np.linspace(0, 1, 401))


def test_a_drifting_encoder_is_fitted_with_the_drift_and_named_without_it():
    """finger2 +-20 % (seed 3), 1 s, the documented sensors (seed 1), its encoder drifting by a ramp of 20 counts.
    With drift="offset": converged, adequate, the ramp back within 1 count (19.5 measured), K and m within 0.3 %
    (0.20 % measured; the issue asks 3 and 5 %). Without: the verdict is not adequate and names the drift first,
    and the masses are further off (1.1 % measured, 2026-12-05)."""
    true = perturbed_params(spread=0.2, seed=3)
    f = ad.Model.alpes("finger2", friction=True)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2]]
    rec = experiment("finger2", true, ExperimentDesign(duration=1.0), seed=1)
    rec = dataclasses.replace(rec, encoder=rec.encoder + np.round(20.0 * rec.t / rec.t[-1])[:, None])
    lines = ExperimentDesign().lines
    fit = identify(f, rec, progress=False, excitation=lines, drift="offset")
    err = np.abs(fit.values[:4] / truth - 1)
    assert fit.trustworthy and np.max(err) < 3e-3
    assert fit.drift["knots_s"] == pytest.approx([0.0, 1.0]) and fit.drift["counts"]["finger"][1] == pytest.approx(20.0, abs=1.0)
    with pytest.warns(Warning):
        plain = identify(f, rec, progress=False, excitation=lines)
    assert not plain.adequacy.adequate and plain.adequacy.likely_missing[0] == SIGNATURES["drift"]
    assert plain.drift is None and np.max(np.abs(plain.values[:4] / truth - 1)) > 2 * np.max(err)
