"""The experiment's bias trimmed on the hand (alpes_dyn.estimation.experiments.trim): a finger within +-20 % of the
nominal values is held where it is no more compliant than the nominal finger at its design point, and its recording
stays in range."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, _excitation, experiment
from alpes_dyn.estimation.experiments import trim
from alpes_dyn.estimation.experiments.trim import _fold_torque, _trimmed_bias
from alpes_dyn.model.params import load_params, with_values
from alpes_dyn.model.stops import JointRangeWarning

PALM_UP = np.array([0.0, 0.0, -9.81])


@pytest.fixture(autouse=True)
def compliance_rule(monkeypatch):
    """The rule these tests are about, off by default (trim.MATCH_COMPLIANCE: its cost in the fits' precision)."""
    monkeypatch.setattr(trim, "MATCH_COMPLIANCE", True)


def _corner(k_factors: tuple[float, ...], m_factors: tuple[float, ...]):
    """The shipped file with the finger's K_i and m_i (I_i with them) times the given factors: a corner of the
    +-20 % box that perturbed_params(spread=0.2) draws from."""
    p = load_params()
    upd = {f"finger.{name}": dataclasses.replace(p.raw[f"finger.{name}"], value=value) for name, value in
           (("K", p.finger.K * np.array(k_factors)), ("m", p.finger.m * np.array(m_factors)),
            ("I", p.finger.I * np.array(m_factors)))}
    return with_values(p, upd)


def _reading_slope(model: ad.Model, tau: float, h: float = 1e-4) -> float:
    """d(S q)/d tau at the static equilibrium under the motor torque tau, N m: a central difference of
    Model.static_equilibrium (the trim's own routine not used), rad per N m."""
    S = model.transmission.S[0]
    q = [model.static_equilibrium(model.transmission.joint_torque(np.array([tau + s * h]))) for s in (1, -1)]
    return float(S @ (q[0] - q[1])) / (2 * h)


def test_a_box_corner_finger_stays_in_range():
    """The +-20 % box's corner with K_1 and m_2, m_3 low, K_2, K_3 and m_1 high folds (its static equilibria end,
    palm up) at 0.0214 N m, below the nominal's mid-range bias (0.0229 N m). Trimmed to the nominal's encoder
    reading it has no rest; held 1.25 multisine-and-dither peaks below the fold (the trim before 2026-12-03) it
    rested q_1 at -13 degrees, on its stop, and the excitation swung it to -22. Trimmed now where its compliance
    d(S q)/d tau is the nominal finger's at its design point (checked on Model.static_equilibrium), it rests and
    moves inside its range under the default design (our simulator, 2 s; no range warning), its multisine and
    dither shrunk (0 < scale < 1)."""
    truth_params = _corner((0.8, 1.2, 1.2), (1.2, 0.8, 0.8))
    nominal = ad.Model.alpes("finger3", friction=True)
    truth = ad.Model.alpes("finger3", friction=True, params=truth_params)
    design = ExperimentDesign(duration=2.0)
    bias, _ = _excitation(nominal, design)
    fold = _fold_torque(truth, lambda c: np.array([c]), PALM_UP, 0.2)
    assert 0.0212 < fold < 0.0216 < bias[0]
    trimmed, scale = _trimmed_bias(truth, nominal, bias, PALM_UP)
    assert trimmed[0] < fold and 0 < scale[0] < 1
    assert _reading_slope(truth, trimmed[0]) == pytest.approx(_reading_slope(nominal, bias[0]), rel=0.02)
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointRangeWarning)
        rec = experiment("finger3", truth_params, design, seed=1)
    q = rec.true_q
    assert np.all(q >= truth.lower) and np.all(q <= truth.upper)
    assert np.degrees(q[:, 0].min()) > 5  # not grazing the stop either


def test_a_finger_as_compliant_as_the_nominal_keeps_the_nominal_design():
    """The compliance rule leaves a finger that is stiffer than the nominal at the nominal's reading alone: the box
    corner with every spring 20 % stiff and every mass 20 % light is trimmed to the nominal's encoder reading,
    its multisine and dither whole (scale 1), and so is the nominal finger itself (its own bias back, to 1e-9 N m)."""
    nominal = ad.Model.alpes("finger3", friction=True)
    bias, _ = _excitation(nominal, ExperimentDesign(duration=1.0))
    same, scale = _trimmed_bias(nominal, nominal, bias, PALM_UP)
    assert same[0] == pytest.approx(bias[0], abs=1e-9) and scale[0] == 1.0
    stiff = ad.Model.alpes("finger3", friction=True, params=_corner((1.2,) * 3, (0.8,) * 3))
    trimmed, scale = _trimmed_bias(stiff, nominal, bias, PALM_UP)
    S = nominal.transmission.S[0]
    reading = float(S @ stiff.static_equilibrium(stiff.transmission.joint_torque(trimmed)))
    assert reading == pytest.approx(float(S @ nominal.static_equilibrium(nominal.transmission.joint_torque(bias))),
                                    abs=1e-6)
    assert scale[0] == 1.0


def test_a_folding_little_finger_is_held_below_its_fold_and_in_range():
    """A little finger with K_1 18 % soft snaps through (a fold of its static equilibria) at 0.0215 N m, below the
    nominal's mid-range bias: the rule holds it where its compliance is the nominal finger's, below the fold, and
    its 1 s recording stays on its branch and inside its range, with no range warning (without the rule the trim
    stops 1.25 multisine-and-dither peaks below the fold, where q_1 rests on its 0 degree stop:
    tests/test_chains.py)."""
    from alpes_dyn.estimation.experiments.experiment import perturbed_params

    nominal = load_params()
    true = perturbed_params(nominal, spread=0.2, seed=1, chains=nominal.chain_names)
    little = ad.Model.alpes("finger3", friction=True, params=true, chain="little")
    fold = _fold_torque(little, lambda c: np.array([c]), PALM_UP, 0.2)
    assert 0.0212 < fold < 0.0218
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointRangeWarning)
        rec = experiment("finger3", true, ExperimentDesign(duration=1.0), seed=1, chain="little")
    assert rec.torque[:, 0].mean() < fold  # its bias (the 20 Hz dither's peaks cross it, too fast to carry it over)
    q = np.degrees(rec.true_q)
    assert q.min() > 0 and q.max() < 90 and q[0, 0] > 5
