"""A fit over several runs started from its runs fitted one by one (issue 51: four runs of one finger in about four
times one run's time, not a cold fit of the whole record): :func:`~alpes_dyn.estimation.identification.long_record.runs_start`
against references computed another way: each run fitted alone by :func:`identify` (the start's parameters are
their log-mean), and the whole record fitted from the model's own response (the start switched off: the same
problem, so the same minimum)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.experiments.recording import join_runs
from alpes_dyn.estimation.identification import identification as ident
from alpes_dyn.estimation.identification import long_record

TRUE = perturbed_params(spread=0.2, seed=3)
LINES = ExperimentDesign().lines


@pytest.fixture(scope="module")
def runs():
    """finger2 +-20 % (seed 3), the documented sensors, three runs of 1 s with noise seeds 1-3."""
    design = ExperimentDesign(duration=1.0)
    return [experiment("finger2", TRUE, design, seed=s) for s in (1, 2, 3)]


def _fit(model, rec):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return ident.identify(model, rec, progress=False, excitation=LINES)


def test_the_runs_start_is_the_runs_fitted_alone_and_the_fit_the_same_minimum(runs, monkeypatch):
    monkeypatch.setattr(long_record, "RUNS_START", 0.0)  # (3 s of runs: started from the runs at any length)
    finger2 = ad.Model.alpes("finger2", friction=True)
    alone = [_fit(finger2, r) for r in runs]
    seen = {}
    real = long_record.runs_start

    def spy(pb, solver, excitation, rest):
        start, its = real(pb, solver, excitation, rest)
        seen["glob"], seen["theta0"], seen["p"] = start[2].copy(), pb.theta0.copy(), pb.p
        return start, its
    monkeypatch.setattr(long_record, "runs_start", spy)
    whole = _fit(finger2, join_runs(runs))
    assert whole.converged
    # the start: every run's own parameters, log-averaged (each run's fit by identify on that run alone, its last
    # sample kept: K and m within 2e-5, the dry friction, flat near its minimum, within 2e-3)
    ref = np.mean([np.log(r.values / seen["theta0"]) for r in alone], axis=0)
    assert np.abs(seen["glob"][:seen["p"]] - ref)[:4].max() < 1e-4
    assert np.abs(seen["glob"][:seen["p"]] - ref).max() < 5e-3
    # the same problem from the model's own response (the runs' start off): the same minimum
    monkeypatch.setattr(long_record, "runs_start", lambda *a: (None, 0))
    cold = _fit(finger2, join_runs(runs))
    assert cold.converged
    # (K and m within 3e-5; the dry friction, flat near the minimum, within a fifth of its standard error)
    assert np.abs(whole.values / cold.values - 1)[:4].max() < 1e-4
    assert np.all(np.abs(whole.values - cold.values) < 0.2 * whole.std)
    assert np.abs(whole.values[:4] / np.r_[TRUE.finger.K[:2], TRUE.finger.m[:2]] - 1).max() < 0.01
