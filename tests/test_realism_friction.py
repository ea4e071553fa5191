"""The realism study's friction cases (issue 50, :mod:`alpes_dyn.studies.realism_friction`): the case table is what it
says -- each case's plant, built as the study builds it, holds in MuJoCo the dry friction, the constraint and the
other effects its row names -- and the validation torque and the standard scores are what their docstrings say."""

from __future__ import annotations

import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from alpes_dyn.bench.effects import CABLE_STIFFNESS, KT_ERROR, TILT_DEG, PlantEffects
from alpes_dyn.bench.mujoco_plant import passive_forces, plant_mjcf, plant_model
from alpes_dyn.estimation.experiments.draws import perturbed_params
from alpes_dyn.estimation.observers.scenario import EstimationScenario
from alpes_dyn.model.mjcf import load_mujoco
from alpes_dyn.studies.realism_friction import (CONSTRAINTS, FRICTION_CASE_NAMES, FRICTION_CASES, RAMP_SECONDS,
                                                RAMP_TORQUE, standard_scores, validation_torque)

SEED = 7


def test_the_table_is_eight_cases_each_constraint_and_scale_alone_and_with_every_effect():
    assert len(FRICTION_CASES) == 8 and len(set(FRICTION_CASE_NAMES)) == 8
    assert {(c.constraint, c.scale, c.others) for c in FRICTION_CASES} == {
        (k, s, o) for k in ("soft", "stiff") for s in (1.0, 3.0) for o in (False, True)}
    for c in FRICTION_CASES:  # the name says the row
        assert c.name == ("all_" if c.others else "") + c.constraint + ("_3x" if c.scale == 3.0 else "")


@pytest.mark.parametrize("case", FRICTION_CASES, ids=FRICTION_CASE_NAMES)
def test_each_case_plant_holds_its_friction_in_mujoco(case):
    """The plant MuJoCo compiles (plant_mjcf, as mujoco_recording builds it): frictionloss = scale x the draw's F_s
    (perturbed_params, drawn here independently), solreffriction the case's time constant (MuJoCo's 0.02 s default
    for soft, 0.5 ms for stiff), the impedance MuJoCo's default 0.9 (soft) or 0.999 (stiff), F_v as joint damping;
    no smooth law added by the callback; with every other effect the cable's rotor, the palm's tilt, the torque
    constant and the encoder's zero."""
    drawn = perturbed_params(spread=0.2, seed=SEED)
    true, e = case.true_params(SEED), case.effects()
    mj = load_mujoco(plant_mjcf("finger3", true, e))
    dofs = [mj.jnt_dofadr[mj.joint(f"j{i + 1}").id] for i in range(3)]
    np.testing.assert_allclose(mj.dof_frictionloss[dofs], case.scale * np.asarray(drawn.finger.F_s), rtol=1e-9)
    np.testing.assert_allclose(mj.dof_damping[dofs], drawn.finger.F_v, rtol=1e-9)
    np.testing.assert_allclose(mj.dof_solref[dofs], [CONSTRAINTS[case.constraint]] * 3, rtol=1e-12)
    np.testing.assert_allclose(mj.dof_solimp[dofs, 0], 0.9 if case.constraint == "soft" else 0.999, rtol=1e-12)
    assert passive_forces(mj, plant_model("finger3", true, e), e) is None  # MuJoCo's friction only
    rotors = [mj.joint(j).name for j in range(mj.njnt) if mj.joint(j).name.endswith("_rotor")]
    assert bool(rotors) == case.others
    tilt = math.degrees(math.atan2(-mj.opt.gravity[0], -mj.opt.gravity[2])) if case.others else 0.0
    if case.others:
        assert abs(abs(tilt) - TILT_DEG) < 1e-6
        assert e.tendon_stiffness == CABLE_STIFFNESS and e.torque_constant_error == KT_ERROR
        assert e.encoder_offset > 0 and e.torque_delay == 1 and e.tendon_dead_band > 0
    else:
        np.testing.assert_allclose(mj.opt.gravity, true.gravity, atol=1e-12)
        assert e == PlantEffects(**{"stiction": e.stiction, "soft_stiction": e.soft_stiction})


@pytest.mark.parametrize("case", [c for c in FRICTION_CASES if c.scale != 1.0], ids=lambda c: c.name)
def test_the_true_file_holds_the_scaled_friction(case, tmp_path):
    """A 3x case's true parameters written as a file and read back hold 3 x the draw's F_s (the file's entries, not
    only the arrays: the true file once held the 1x F_s)."""
    from alpes_dyn.model.params import load_params, write_params

    back = load_params(write_params(case.true_params(SEED), tmp_path / "true.toml"))
    drawn = perturbed_params(spread=0.2, seed=SEED)
    np.testing.assert_allclose(back.finger.F_s, case.scale * np.asarray(drawn.finger.F_s), rtol=1e-12)
    np.testing.assert_allclose(back.finger.K, drawn.finger.K, rtol=1e-12)


def test_validation_torque_is_the_scenario_then_a_slow_ramp():
    """The estimate scenario's 5 s (its bias and sines, recomputed here), then the triangle of RAMP_TORQUE about the
    bias over RAMP_SECONDS: continuous, at most RAMP_TORQUE off the bias, slow (4 RAMP_TORQUE / RAMP_SECONDS)."""
    dt = 1e-3
    u = validation_torque(dt, 1)[:, 0]
    sc = EstimationScenario()
    assert u.shape == (int(round((sc.duration + RAMP_SECONDS) / dt)) + 1,)
    t = dt * np.arange(5001)
    ref = sc.torque_bias + sum(a * np.sin(2 * np.pi * f * t) for a, f in zip(sc.torque_amplitudes,
                                                                              sc.torque_frequencies))
    np.testing.assert_allclose(u[:5001], ref, atol=1e-12)
    ramp = u[5000:] - sc.torque_bias
    assert abs(ramp[0]) < 1e-12 and abs(ramp[-1]) < 1e-12
    assert ramp.max() == pytest.approx(RAMP_TORQUE, rel=1e-3) and ramp.min() == pytest.approx(-RAMP_TORQUE, rel=1e-3)
    assert np.abs(np.diff(ramp)).max() <= 4 * RAMP_TORQUE / RAMP_SECONDS * dt * (1 + 1e-9)


def test_standard_scores_count_the_error_up_to_the_common_scale_in_standard_errors():
    truth = {"K_1": 2.0, "m_1": 1.0, "tilt_x": 0.0, "F_s_1": 0.5}
    values = {"K_1": 2.2 * 1.05, "m_1": 1.05, "tilt_x": 0.01, "F_s_1": 0.5 * 1.05}
    std = {"K_1": 0.1 * 1.05, "m_1": 0.01, "tilt_x": 0.001, "F_s_1": 0.0}
    z = standard_scores(values, std, truth, 1.05)
    assert set(z) == {"K_1", "m_1"}  # no truth (tilt) or no reported error (F_s_1): not scored
    assert z["K_1"] == pytest.approx(2.0) and z["m_1"] == pytest.approx(0.0, abs=1e-12)


BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _bench():
    """benchmarks/realism.py as a module (its folder on the path while it runs: it imports _friction)."""
    spec = importlib.util.spec_from_file_location("realism_bench", BENCH / "realism.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_benchmark_summarises_its_recorded_rows_again(tmp_path, capsys):
    """``realism.py --friction --from-log`` on the recorded rows (benchmarks/results/realism.friction.json) gives the
    recorded seeds and summary; a duplicated row counts once; bad arguments exit 2 with the option named."""
    rec = json.loads((BENCH / "results" / "realism.friction.json").read_text())["result"]
    log = tmp_path / "rows.jsonl"
    log.write_text("".join(json.dumps(r) + "\n" for r in rec["rows"] + rec["rows"][:1]))
    sys.path.insert(0, str(BENCH))
    try:
        bench = _bench()
        assert bench.main(["--friction", "--from-log", str(log), "--json"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["seeds"] == rec["seeds"] and len(out["rows"]) == len(rec["rows"])  # each case over its own draws
        assert {c: s for c, s in out["case_seeds"].items() if s} == rec["case_seeds"]
        for case, s in out["summary"].items():
            r = rec["summary"][case]
            assert (s["n"], s["adequate"], len(s["silent_misses"])) == (r["n"], r["adequate"], len(r["silent_misses"]))
            assert s["ekf_deg"]["worst"] == pytest.approx(r["ekf_deg"]["worst"], rel=1e-12)
            zn = [abs(v) for x in rec["rows"] if x["case"] == case and "error" not in x
                  for v in x.get("z_noise", {}).values()]  # the noise's standard errors alone, where recorded
            assert s["z_noise_within_3"] == (pytest.approx(np.mean([z <= 3 for z in zn])) if zn else None)
        for argv, needle in ((["--friction", "--cases", "slippery"], "--cases: unknown case 'slippery'"),
                             (["--friction", "--rig", "hanging"], "--rig: not with --friction"),
                             (["--friction", "--workers", "2"], "--workers: not with --friction")):
            with pytest.raises(SystemExit) as e:
                bench.main(argv)
            assert e.value.code == 2 and needle in capsys.readouterr().err
    finally:
        sys.path.remove(str(BENCH))
