"""Physical bounds of the fitted parameters and the experiment adapted to the finger (issue 35).

Checked against independent references: the rules of :func:`~alpes_dyn.estimation.identification.bounds.unsupported` by
hand; the fit with a parameter not identified against a fresh fit that never had it; the compliance on MuJoCo plants
(a rigid cable: not identified; a series-elastic one: identified, positive, written); the adapted experiment's choice on
MuJoCo (the torque of the chosen design replayed on the MuJoCo finger keeps it in range where the palm-up one does
not).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError
from alpes_dyn.estimation.experiments.adapt import RANGE_MARGIN, adapted_experiment, range_excess
from alpes_dyn.estimation.identification.bounds import describe, held_value, physical_range, unsupported
from alpes_dyn.estimation.experiments.design import ExperimentDesign
from alpes_dyn.estimation.experiments.draws import perturbed_params
from alpes_dyn.estimation.experiments.experiment import experiment, experiment_torque
from alpes_dyn.estimation.identification.identification import identify
from alpes_dyn.model.params import Param, load_params, with_values


LINES = ExperimentDesign().lines
"""The excitation's lines (Hz): the fits take the measured torque on them (errors in variables), as the CLI does."""


def _why(**kw):
    base = dict(names=["p"], kinds=["K"], values=[1.0], std=[0.1], initial=[1.0], units=["u"])
    base.update({k: [v] for k, v in kw.items()})
    return unsupported(**base)


def test_the_rules_of_a_parameter_not_identified():
    """Below its bound (a negative compliance), run off to a bound (a mass at 1e-4 of its start), a 95 % interval
    reaching past 0, or supported; the rig's own parameters (tilt, offset) and an unseen one never flagged."""
    assert _why() == {}
    assert "below its physical bound 0" in _why(kinds="tendon_compliance", values=-0.05, std=0.03, initial=0.0)["p"]
    assert "an elastic tendon" in _why(kinds="tendon_compliance", values=-0.05, std=0.03, initial=0.0)["p"]
    assert "reaches past 0" in _why(kinds="tendon_compliance", values=0.05, std=0.03, initial=0.0)["p"]
    assert _why(kinds="tendon_compliance", values=0.07, std=0.03, initial=0.0) == {}  # 0.07 - 1.96 x 0.03 > 0
    assert "ran off to its bound" in _why(kinds="m", values=1e-4, std=1e-6, initial=1.0)["p"]
    assert "ran off to its bound" in _why(kinds="F_s", values=2e3, std=1.0, initial=1.0)["p"]
    assert "reaches past 0" in _why(kinds="F_s", values=1.0, std=0.6, initial=1.0)["p"]
    assert _why(kinds="F_s", values=1.0, std=0.5, initial=1.0) == {}
    assert _why(kinds="tilt", values=-3.0, std=10.0, initial=0.0) == {}
    assert _why(kinds="encoder_offset", values=-3.0, std=10.0, initial=0.0) == {}
    assert _why(kinds="K", values=1e-9, std=math.inf, initial=1.0) == {}  # not seen: identify leaves it at its start
    assert physical_range("tendon_compliance") == (0.0, math.inf, True)
    assert physical_range("m") == (0.0, math.inf, False) and physical_range("tilt")[0] == -math.inf
    assert held_value("tendon_compliance", -0.3, 0.2) == 0.0 and held_value("tendon_compliance", 0.1, 0.2) == 0.2
    assert describe({}) == "" and describe({"a": "why"}) == "not identified: a (why)"


@pytest.fixture(scope="module")
def rigid_recording():
    """A 1.5 s experiment on our simulator (rigid tendon): no compliance to find."""
    return experiment("finger2", perturbed_params(spread=0.2, seed=3), ExperimentDesign(duration=1.5), seed=3)


@pytest.fixture(scope="module")
def rigid_fit(rigid_recording):
    """K, m and the friction fitted on ``rigid_recording`` (the fit both tests below start from or compare with)."""
    return identify(ad.Model.alpes("finger2", friction=True), rigid_recording, "K,m,friction", progress=False,
                    excitation=LINES)


def test_a_compliance_the_data_do_not_support_is_held_and_never_written(rigid_recording, rigid_fit, tmp_path):
    """Fitted with the compliance, the simulator's rigid cable gives one the data cannot tell from 0: the result
    names it not identified (with the effect), the values kept are those of a fresh fit that never had it (to a
    tenth of their standard errors), and the file written holds no compliance."""
    model = ad.Model.alpes("finger2", friction=True)
    res = identify(model, rigid_recording, "K,m,friction,tendon_compliance", progress=False, excitation=LINES)
    assert list(res.not_identified) == ["tendon_compliance_finger"] and "tendon_compliance_finger" not in res.names
    assert "the data do not support an elastic tendon" in res.not_identified["tendon_compliance_finger"]
    assert "not identified: tendon_compliance_finger" in res.status() and "fitted again" in res.reason
    ref = rigid_fit
    assert ref.names == res.names and ref.not_identified == {}
    assert np.all(np.abs(res.values - ref.values) < 0.1 * ref.std)
    assert np.array_equal(res.initial, ref.initial)  # the start column is the first fit's start
    p = load_params(res.write(tmp_path / "ident.toml"))
    assert "transmission.tendon_compliance" not in p.raw and p.tendon_compliance == 0.0
    assert p.identification["finger"]["not_identified"][0].startswith("tendon_compliance_finger: ")


def test_the_fit_again_starts_from_the_first_fits_linearised_optimum(rigid_recording, rigid_fit):
    """held_start: the first fit moved to the linearised optimum with a parameter held (issue 39) predicts the fit
    with it held (a fresh fit of the others from the first's start) to a small part of the move, and the fit from
    there converges to the same values in fewer iterations."""
    from alpes_dyn.estimation.identification.held import held_start

    model = ad.Model.alpes("finger2", friction=True)
    first = rigid_fit
    assert first.solution.response.shape[1] == len(first.names)
    keep = [n for n in first.names if n != "F_v_1"]
    moved = held_start(first, {"F_v_1": 1e-4})  # the model's value (the fit found another)
    assert abs(first.values[first.names.index("F_v_1")] / 1e-4 - 1) > 0.05  # a real move
    assert moved.values[moved.names.index("F_v_1")] == pytest.approx(1e-4, rel=1e-12)
    fresh = identify(model, rigid_recording, keep, progress=False, excitation=LINES, start=first)
    warm = identify(model, rigid_recording, keep, progress=False, excitation=LINES, start=moved)
    k = [first.names.index(n) for n in keep]
    off = lambda v: np.linalg.norm((v[k] - fresh.values) / fresh.std)  # noqa: E731 (in standard errors)
    assert off(moved.values) < 0.2 * off(first.values)  # the linearisation: within a fifth of the move
    assert np.all(np.abs(warm.values - fresh.values) < 0.1 * fresh.std)
    assert warm.converged and warm.iterations < fresh.iterations
    assert held_start(first, {"F_v_1": 0.0}) is None and held_start(first, {}) is None  # a log-fitted bound: none


def test_a_held_start_whose_move_overflows_a_value_is_none():
    """held_start on a stand-in fit whose linearised move takes a log-fitted parameter past float64's range (a short
    record's flat direction: ``experiment --duration 0.1`` then identify): None (the fit again starts from the first
    fit), not a start holding inf that identify then refused as "start: F_v_1 = inf", naming an argument never
    given."""
    import dataclasses

    from alpes_dyn.estimation.identification.held import ShootingSolution, held_start

    @dataclasses.dataclass
    class Fit:  # what held_start reads of an IdentificationResult
        names: tuple
        values: np.ndarray
        solution: ShootingSolution

    def first(coupling):
        response = np.array([[0.0, 0.0], [1.0, 0.0], [coupling, 1.0]])  # node, then the two parameters' rows
        sol = ShootingSolution(nodes=np.zeros((1, 1)), offs=np.zeros((1, 0)), lines=np.zeros(0), samples=10,
                               response=response, additive=np.array([False, False]), scale=np.ones(2))
        return Fit(("K_1", "F_v_1"), np.array([0.04, 1e-4]), sol)

    moved = held_start(first(0.5), {"K_1": 0.08})
    assert moved.values == pytest.approx([0.08, 1e-4 * 2**0.5], rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning either
        assert held_start(first(1e4), {"K_1": 0.08}) is None


def test_a_negative_compliance_in_a_file_is_refused(tmp_path):
    """No file holds a compliance below 0 (a cable does not shorten under tension): the parameter set refuses it,
    naming the field, and so does the loader on a file edited by hand."""
    with pytest.raises(ModelError, match=r"transmission.tendon_compliance: value must be >= 0 \(got -0.1"):
        with_values(load_params(), {"transmission.tendon_compliance": Param(-0.1, "rad/(N m)", "assumed", "t", "c")})
    path = tmp_path / "neg.toml"
    from alpes_dyn.model.params import write_params

    write_params(with_values(load_params(), {"transmission.tendon_compliance": Param(0.1, "rad/(N m)", "assumed",
                                                                                     "t", "c")}), path)
    path.write_text(path.read_text().replace("tendon_compliance = { value = 0.1", "tendon_compliance = { value = -0.1"))
    with pytest.raises(ModelError, match="transmission.tendon_compliance: value must be >= 0"):
        load_params(path)


def test_the_compliance_on_mujoco_plants_rigid_and_elastic():
    """On MuJoCo (the finger exported, stepped by MuJoCo): a rigid cable's compliance is not identified and held;
    a series-elastic cable's (k_t = 1.2e4 N/m: C = 1 / (r_m^2 k_t) = 20.8 rad/(N m)) is identified, positive and
    within 5 % of that quasi-static value."""
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording

    p = load_params()
    design = ExperimentDesign(duration=2.0)
    t, u, x0 = experiment_torque("finger3", p, design)
    model = ad.Model.alpes("finger3", friction=True)
    rigid = mujoco_recording("finger3", p, u, design.dt, seed=4, q0=x0[:3])
    res = identify(model, rigid, "K,m,friction,tendon_compliance", progress=False, interval=0.05, excitation=LINES)
    assert "tendon_compliance_finger" in res.not_identified and res.converged
    k_t = 1.2e4
    elastic = mujoco_recording("finger3", p, u, design.dt, seed=4, q0=x0[:3],
                               effects=PlantEffects(tendon_stiffness=k_t, tendon_damping=20.0))
    res = identify(model, elastic, "K,m,friction,tendon_compliance", progress=False, interval=0.05, excitation=LINES)
    C = dict(zip(res.names, res.values)).get("tendon_compliance_finger")
    assert res.not_identified == {} and C == pytest.approx(1.0 / (p.r_m**2 * k_t), rel=0.05)


def test_range_excess_by_hand():
    q = np.array([[0.1, 0.5], [-0.2, 1.7]])
    lo, hi = np.array([0.0, 0.0]), np.array([1.0, 1.5])
    excess, j, extreme = range_excess(q, lo, hi, margin=0.05)
    assert j == 0 and excess == pytest.approx(0.25) and extreme == -0.2  # 0.05 - (-0.2) beats 1.7 - 1.45
    assert range_excess(np.array([[0.5, 0.5]]), lo, hi, 0.05)[0] == 0.0
    assert range_excess(np.array([[5.0]]), np.array([0.0]), np.array([np.inf]), 0.05)[0] == 0.0


def test_the_experiment_hangs_a_folding_finger_and_mujoco_agrees(tmp_path):
    """finger3 seed 11 folds palm up (its equilibria end below mid-range): the adapted experiment hangs it fingers
    down and says so; our run stays inside its range by the margin. Independently, the designs' torques replayed on
    the MuJoCo finger: palm up it goes past its 0 degree stop, hung it stays inside. A finger that does not fold
    (seed 5) runs the design as given: the recording is the plain experiment's, bit for bit."""
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.model.mjcf import HANGING_TILT

    truth = perturbed_params(spread=0.2, seed=11)
    design = ExperimentDesign(duration=2.0)
    rec, how = adapted_experiment("finger3", truth, design, seed=11, path=tmp_path / "r.csv")
    assert how.rig == "hanging" and how.amplitude_scale == 1.0 and how.excess_deg == 0.0
    assert "ran hung fingers down (as --rig hanging)" in how.note and how.tried[0][0] == "level"
    assert rec.gravity is not None and (tmp_path / "r.csv").exists()
    m = ad.Model.alpes("finger3", params=truth)
    assert range_excess(rec.true_q, m.lower, m.upper, RANGE_MARGIN)[0] == 0.0
    hung = ExperimentDesign(duration=2.0, orientations=(tuple(rec.gravity[0]),))
    for d, tilt, inside in ((design, 0.0, False), (hung, HANGING_TILT, True)):
        _, u, x0 = experiment_torque("finger3", truth, d)
        mj = mujoco_recording("finger3", truth, u, d.dt, q0=x0[:3], effects=PlantEffects(tilt=tilt))
        assert (range_excess(mj.true_q, m.lower, m.upper, 0.0)[0] == 0.0) == inside
    plain = experiment("finger3", perturbed_params(spread=0.2, seed=5), design, seed=5)
    same, how5 = adapted_experiment("finger3", perturbed_params(spread=0.2, seed=5), design, seed=5)
    assert how5.note == "" and how5.rig == "level" and len(how5.tried) == 1
    assert np.array_equal(same.encoder, plain.encoder) and np.array_equal(same.torque, plain.torque)
