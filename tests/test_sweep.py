"""Sweeps on Dask (alpes_dyn.studies.sweep): a local cluster gives the serial loop's rows, seed by seed."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from alpes_dyn.errors import InputError
from alpes_dyn.studies.sweep import robustness_draw, sweep


def test_local_cluster_equals_serial_loop():
    pytest.importorskip("distributed")
    opts = {"duration": 0.5, "fit": False}
    serial = sweep(robustness_draw, 3, seed=3, options=opts, serial=True)
    dask = sweep(robustness_draw, 3, seed=3, options=opts, workers=2)
    assert dask.backend == "dask" and dask.workers == 2 and serial.backend == "serial"
    assert [r["seed"] for r in dask.rows] == [3, 4, 5]
    assert dask.rows == serial.rows  # bit for bit: each draw seeded by its own seed only
    before = np.array([[r[f"rmse_deg_before_{i}"] for i in range(3)] for r in serial.rows])
    assert before.shape == (3, 3) and np.all(before > 0.05)  # the nominal file on fingers drawn 20 % off


def _has_module(name: str) -> bool:
    import sys

    return name in sys.modules


@pytest.mark.skipif(not __import__("sys").platform.startswith("linux"), reason="workers are forked on Linux only")
def test_local_cluster_workers_are_forked_with_this_process_modules():
    """local_client forks its workers on Linux: a module imported here only (a throw-away one) is in theirs, which a
    spawned worker would not have; they run their compiled loops on one thread (OMP_NUM_THREADS=1), and no
    statistical profiler samples them (its periodic callback absent, as the worker's config says), nor a worker
    the cluster restarts."""
    pytest.importorskip("distributed")
    import sys
    import types

    from alpes_dyn.studies.sweep import local_client

    sys.modules["alpes_test_only_here"] = types.ModuleType("alpes_test_only_here")
    client = local_client(2)
    try:
        assert client.gather([client.submit(_has_module, "alpes_test_only_here", pure=False) for _ in range(2)]) \
            == [True, True]
        assert set(client.run(lambda: __import__("os").environ.get("OMP_NUM_THREADS")).values()) == {"1"}
        assert set(client.run(lambda: __import__("dask").config.get("distributed.worker.profile.enabled")).values()) \
            == {False}
        profiled = lambda dask_worker: any("profile" in name for name in dask_worker.periodic_callbacks)  # noqa: E731
        assert set(client.run(profiled).values()) == {False}
        client.restart(timeout=120)  # a worker the cluster restarts (spawned) keeps the configuration
        assert set(client.run(profiled).values()) == {False}
    finally:
        client.close()
        client.cluster.close()
        del sys.modules["alpes_test_only_here"]


def test_rows_table_and_csv(tmp_path):
    def draw(seed):  # a closure does not travel to Dask, but runs serially
        return {"x": [seed, 2 * seed], "name": f"d{seed}", "v": np.float64(seed / 2)}

    res = sweep(draw, 3, seed=1, serial=True)
    assert res.rows[2] == {"seed": 3, "x_0": 3.0, "x_1": 6.0, "name": "d3", "v": 1.5}
    res.to_csv(tmp_path / "s.csv")
    lines = (tmp_path / "s.csv").read_text().splitlines()
    assert lines[0] == "seed,x_0,x_1,name,v" and lines[1] == "1,1.0,2.0,d1,0.5"
    assert res.table().splitlines()[0].split() == ["seed", "x_0", "x_1", "name", "v"]


def test_given_seeds_and_nested_rows():
    """seeds= runs exactly those seeds, in their order; flat=False keeps a draw's nested values, with its seed."""
    def draw(seed):
        return {"x": [seed, 2 * seed], "inner": {"y": seed + 0.5}}

    res = sweep(draw, seeds=[7, 2, 40], serial=True, flat=False)
    assert res.rows == [{"seed": 7, "x": [7, 14], "inner": {"y": 7.5}}, {"seed": 2, "x": [2, 4], "inner": {"y": 2.5}},
                        {"seed": 40, "x": [40, 80], "inner": {"y": 40.5}}]
    assert sweep(draw, seeds=(5,), serial=True).rows == [{"seed": 5, "x_0": 5.0, "x_1": 10.0, "inner": {"y": 5.5}}]


def _nested(seed: int) -> dict:
    return {"inner": {"y": seed + 0.5, "z": [seed, math.nan], "w": {"k": np.float64(2.5)}}, "x": [seed, 2 * seed]}


def test_nested_values_are_json_in_the_csv(tmp_path):
    """A dict in a row (and a list, in rows not flattened) is a CSV cell of JSON text that json.loads reads back to
    the same value (a non-finite number in it null, as in to_dict); never Python's repr."""
    flat = sweep(_nested, seeds=[3], serial=True)
    rows = list(csv.DictReader(open(flat.to_csv(tmp_path / "flat.csv"))))
    assert rows == [{"seed": "3", "inner": rows[0]["inner"], "x_0": "3.0", "x_1": "6.0"}]
    assert json.loads(rows[0]["inner"]) == {"y": 3.5, "z": [3, None], "w": {"k": 2.5}}
    nested = sweep(_nested, seeds=[4, 1], serial=True, flat=False)
    rows = list(csv.DictReader(open(nested.to_csv(tmp_path / "nested.csv"))))
    assert [json.loads(r["x"]) for r in rows] == [[4, 8], [1, 2]]
    assert json.loads(rows[1]["inner"]) == {"y": 1.5, "z": [1, None], "w": {"k": 2.5}}
    assert "nan" not in (tmp_path / "nested.csv").read_text().lower()
    obj = json.loads(json.dumps(nested.to_dict(), allow_nan=False))  # the JSON output: null at any depth too
    assert obj["rows"][0]["inner"] == {"y": 4.5, "z": [4, None], "w": {"k": 2.5}}


@pytest.mark.parametrize("kw, needle", [
    ({"draws": None, "seeds": [1, 1]}, "seeds: a seed is given twice"),
    ({"seeds": [1, 2]}, "seeds: give the seeds, or draws and seed, not both"),
    ({"draws": None, "seeds": []}, "seeds: expected 1 to 100000 integers"),
    ({"draws": None, "seeds": [1, -2]}, "seeds: expected an integer from 0"),
    ({"draws": None, "seeds": "12"}, "seeds: expected 1 to 100000 integers, got str"),
    ({"draws": None}, "draws: expected the number of draws"),
    ({"flat": "yes"}, "flat: expected True or False"),
    ({"draws": 0}, "draws: expected an integer from 1 to 100000"),
    ({"draws": True}, "draws: expected an integer"),
    ({"seed": -1}, "seed: expected an integer from 0"),
    ({"workers": 0}, "workers: expected an integer from 1 to 256"),
    ({"scheduler": "localhost"}, "scheduler: expected an address such as tcp://host:8786"),
])
def test_bad_sweep_arguments(kw, needle):
    args = {"draws": 2, **kw}
    with pytest.raises(InputError, match=needle.replace("(", r"\(")):
        sweep(robustness_draw, args.pop("draws"), **args)


def test_the_last_draw_may_have_the_largest_seed():
    """seed .. seed + draws - 1 reach 2^63 - 1, the largest seed of every command, and not beyond (was one short)."""
    from alpes_dyn.limits import MAX_SEED

    assert MAX_SEED == 2**63 - 1
    assert [r["seed"] for r in sweep(lambda s: {"x": 1.0}, 1, seed=MAX_SEED, serial=True).rows] == [MAX_SEED]
    assert [r["seed"] for r in sweep(lambda s: {"x": 1.0}, 3, seed=MAX_SEED - 2, serial=True).rows] == [
        MAX_SEED - 2, MAX_SEED - 1, MAX_SEED]
    with pytest.raises(InputError, match=f"seed: expected an integer from 0 to {MAX_SEED - 1}, got {MAX_SEED}"):
        sweep(lambda s: {"x": 1.0}, 2, seed=MAX_SEED, serial=True)


def test_a_draw_must_return_a_dict():
    with pytest.raises(InputError, match="fn: a draw must return a dict of results, got int"):
        sweep(lambda s: s, 1, serial=True)


def _with_non_finite(seed: int) -> dict:
    return {"x": float(seed), "bad": math.nan, "pair": [1.0, math.inf], "flags": [True, False]}


def test_non_finite_results_never_reach_the_table_or_csv(tmp_path):
    """NaN and inf from a draw: null in JSON, an empty cell in the CSV, '-' in the table; bool lists stay flags."""
    res = sweep(_with_non_finite, 2, serial=True)
    path = res.to_csv(tmp_path / "s.csv")
    rows = list(csv.DictReader(open(path)))
    assert rows[1] == {"seed": "1", "x": "1.0", "bad": "", "pair_0": "1.0", "pair_1": "", "flags_0": "True",
                       "flags_1": "False"}
    assert "nan" not in res.table() and "inf" not in res.table() and res.table().split("\n")[2].split()[2] == "-"
    obj = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert obj["rows"][0]["bad"] is None and obj["rows"][0]["pair_1"] is None


# ---- the robustness study on a URDF + spec robot (issue 17): finger_edu with its shipped spec
def test_drawn_spec_draws_what_the_spec_holds_within_the_spread():
    from alpes_dyn.model.spec import example_spec_path, load_spec
    from alpes_dyn.studies.sweep import drawn_spec

    spec = load_spec(example_spec_path("finger_edu"))
    a, b, c = drawn_spec(spec, 0.2, 5), drawn_spec(spec, 0.2, 5), drawn_spec(spec, 0.2, 6)
    assert a == b and a != c  # seeded by the draw's seed alone
    rng = np.random.default_rng(5)  # the documented order: stiffness, coulomb, viscous, each table as written
    for table in ("stiffness", "coulomb", "viscous"):
        nominal = getattr(spec, table)
        factors = rng.uniform(0.8, 1.2, len(nominal))
        assert getattr(a, table) == pytest.approx({j: v * f for (j, v), f in zip(nominal.items(), factors)}, rel=1e-15)
        assert all(0.8 <= getattr(a, table)[j] / v <= 1.2 for j, v in nominal.items())
    assert a.motors == spec.motors and a.rest_angle == spec.rest_angle and a.encoder_counts == spec.encoder_counts
    assert drawn_spec(spec, 0.0, 5) == spec


def test_sweep_command_on_a_urdf_robot_runs_its_draws(tmp_path, capsys, cli_text):
    """``sweep --model finger_edu.urdf --spec ...``: each row's EKF error is the observer's on that draw's experiment
    (the drawn robot simulated, the nominal spec observing), recomputed here through the API; its table says what
    was drawn and held."""
    import json

    import alpes_dyn as ad
    from alpes_dyn import Model, cli
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment
    from alpes_dyn.estimation.observers.replay import estimate_recording
    from alpes_dyn.model.spec import example_spec_path
    from alpes_dyn.studies.sweep import drawn_spec

    urdf, spec = str(ad.example_robot_urdf("finger_edu")), str(example_spec_path("finger_edu"))
    assert cli.main(["sweep", "--model", urdf, "--spec", spec, "--draws", "1", "--seed", "4", "--serial", "--no-fit",
                     "--duration", "0.5", "-o", str(tmp_path / "s.csv"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["model"] == urdf and obj["spec"] == spec and [r["seed"] for r in obj["rows"]] == [4]
    nominal = Model.from_urdf_file(urdf, spec)
    truth = Model(nominal.urdf, drawn_spec(nominal.spec, 0.2, 4))
    rec = model_experiment(nominal, truth, ExperimentDesign(duration=0.5), seed=4)
    rmse = np.degrees(estimate_recording(rec, nominal).rmse)
    got = [obj["rows"][0][f"rmse_deg_before_{i}"] for i in range(3)]
    assert got == pytest.approx(rmse, rel=1e-9)
    # the experiment pulls the finger to mid-range (springs resting at 0: before, it hung still and the nominal
    # spec's EKF read it within a degree whatever its springs); there the drawn springs (17-19 % off) leave the
    # nominal spec's observer tens of degrees off in 0.5 s (40-72 deg), the true spec's within its start's
    # transient (0.7-1.3 deg)
    assert np.degrees(estimate_recording(rec, truth).rmse).max() < 2.0 and rmse[1:].min() > 10.0
    assert (tmp_path / "s.csv").read_text().startswith("seed,rmse_deg_before_0,")
    head = cli_text[0].splitlines()[1]  # the table the same run prints without --json
    assert head.startswith("  drawn: K, F_s, F_v of every joint the spec gives them (motorless joints too); held")


def test_sweep_on_finger_edu_fits_what_it_draws_and_converges(capsys, cli_text):
    """``sweep`` on finger_edu, 2 draws: its passive ab/adduction's spring and friction are drawn with the rest, and
    fitted with the rest (on 4 s experiments: held at the spec's, seed 0 ran into the iteration cap at 7.5 counts;
    freed from the nominal at once, seed 1 did at 3.3). Here 1 s experiments, to keep the test short. Both draws converge at the sensor floor (0.5 count of noise and the quantisation's
    0.29: 0.58 counts), the springs within 1 % of the drawn ones, and the output says what was drawn and held."""
    import json

    import alpes_dyn as ad
    from alpes_dyn import cli
    from alpes_dyn.model.spec import example_spec_path
    from alpes_dyn.studies.sweep import ROBOT_DRAWN, ROBOT_HELD

    urdf, spec = str(ad.example_robot_urdf("finger_edu")), str(example_spec_path("finger_edu"))
    assert cli.main(["sweep", "--model", urdf, "--spec", spec, "--draws", "2", "--serial", "--duration", "1",
                     "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["drawn"] == list(ROBOT_DRAWN) == ["K", "F_s", "F_v"] and obj["held"] == list(ROBOT_HELD)
    for row in obj["rows"]:
        assert row["converged"] is True, row
        assert 0.5 < row["residual_counts"] < 0.65, row  # the floor: sqrt(0.5^2 + 1/12) = 0.577 counts
        assert row["worst_K_pct"] < 1.0, row
        assert max(row[f"rmse_deg_after_{i}"] for i in range(3)) < max(row[f"rmse_deg_before_{i}"] for i in range(3))
    head = cli_text[0].splitlines()[1]  # the table the same run prints without --json (--no-fit's: the test above)
    assert head.startswith("  drawn and fitted: K, F_s, F_v of every joint the spec gives them (motorless joints")


def test_staged_fit_restarts_in_one_stage_where_the_two_stages_fail():
    """staged_fit's rule on stand-in fits: the warm-up capped at WARM_UP_ITERATIONS then everything from it; where that
    does not converge one stage from the spec's values, the converged one kept (neither: the lower residual); one
    stage where every name is driven. (The real case, finger_edu seed 4: two stages 1.63 counts, not converged; one
    stage 0.580 counts, converged: robot_robustness_draw's docstring.)"""
    from types import SimpleNamespace

    from alpes_dyn.studies.sweep import WARM_UP_ITERATIONS, staged_fit

    def fits(outcomes):
        calls = []

        def fit(names, **kw):
            calls.append((tuple(names), kw))
            conv, res = outcomes[len(calls) - 1]
            return SimpleNamespace(converged=conv, residual_rms=res, tag=len(calls))
        return fit, calls

    fit, calls = fits([(False, 5.0), (True, 0.58)])
    res, restarted = staged_fit(fit, ["a", "p"], ["a"])
    assert (res.tag, restarted) == (2, False)
    assert calls[0] == (("a",), {"max_iterations": WARM_UP_ITERATIONS})
    assert calls[1][0] == ("a", "p") and calls[1][1]["start"].tag == 1
    fit, calls = fits([(False, 5.0), (False, 1.63), (True, 0.58)])
    res, restarted = staged_fit(fit, ["a", "p"], ["a"])
    assert (res.tag, restarted) == (3, True) and calls[2] == (("a", "p"), {})
    fit, calls = fits([(False, 5.0), (False, 1.63), (False, 3.3)])
    assert staged_fit(fit, ["a", "p"], ["a"])[0].tag == 2  # neither converged: the lower residual
    fit, calls = fits([(False, 5.0), (False, 1.63), (False, 0.9)])
    assert staged_fit(fit, ["a", "p"], ["a"])[0].tag == 3
    fit, calls = fits([(True, 0.58)])
    res, restarted = staged_fit(fit, ["a", "b"], ["a", "b"])
    assert (res.tag, restarted, calls) == (1, False, [(("a", "b"), {})])
