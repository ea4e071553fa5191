"""benchmarks/bench_loop.py's C column (benchmarks/c_step.c_columns): the C step built from a ForceStep and run over
a BenchRun's readings, its difference from the Python step, and the goal it feeds (bench_loop.goals' ``c_step``).

References: the Python step's own commands and estimates logged by run_on_bench (the C step must reproduce them to
1e-9 free-running, to 1e-12 one step from the Python step's state: commands about 0.03 N m, joints about 1 rad,
forces about 0.5 N); a run whose logged commands are shifted by a
known 1e-6 N m, which the column must report as that shift (within 1e-9).
"""

from __future__ import annotations

import dataclasses
import importlib
import shutil
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
CC = shutil.which("cc") or shutil.which("gcc")
pytestmark = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH")


@pytest.fixture(scope="module")
def bench():
    """The benchmark modules (benchmarks/ on the path while imported)."""
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("c_step"), importlib.import_module("bench_loop")
    finally:
        sys.path.remove(str(BENCH))


@pytest.fixture(scope="module")
def pressed():
    """finger2's sensor step and 0.6 s of it pressing the stand-in's block."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.control.bench_loop import run_on_bench
    from alpes_dyn.control.step import ForceStep

    step = ForceStep("finger2", controller="sensor", compiled=False)
    run = run_on_bench(MujocoHand("finger2", scene="block", seed=9690), step, 0.4, 0.6)
    return step, run


def test_c_column_matches_the_python_step(bench, pressed):
    c_step, _ = bench
    step, run = pressed
    assert run.force.max() > 0.2  # the finger pressed the block: the contact's branch of the step ran
    row = c_step.c_columns(step, run, CC)
    assert row["diff_command"] < 1e-9 and row["diff_q"] < 1e-9 and row["diff_force"] < 1e-9  # the free run
    # one step from the Python step's state (the goal's column): rounding only
    assert row["step_diff_command"] < 1e-12 and row["step_diff_q"] < 1e-12 and row["step_diff_force"] < 1e-12
    assert row["c_step_diff"] == max(row["step_diff_command"], row["step_diff_q"], row["step_diff_force"])
    assert row["c_run_diff"] == max(row["diff_command"], row["diff_q"], row["diff_force"])
    assert 0 < row["c_cpu_us"] < 1e4 and row["c_build_s"] > 0 and row["c_source_kb"] > 1
    # the time rule (c_step's docstring): the best of PASSES passes, each a process of its own, kept; the goal's
    # figure each step's minimum over PASSES passes in one process: below its median, and its mean over the steps
    # below the best single pass's wall clock per step (each step's minimum is at most its time in any pass; 1.5x:
    # the two runs are different processes of a loaded machine)
    assert row["c_passes"] == c_step.PASSES and row["c_cpu_us"] <= row["c_cpu_us_median"] * (1 + 1e-12)
    assert 0 < row["c_us_min"] <= row["c_us_median"] * (1 + 1e-12) and row["c_us_min"] < 1.5 * row["c_us"]
    assert c_step.c_goals_met(row) == (row["c_us_min"] < c_step.GOAL_US and row["c_build_cpu_s"] < c_step.GOAL_BUILD_S)
    assert not c_step.c_goals_met({**row, "c_us_min": c_step.GOAL_US, "c_cpu_us": 1.0})  # judged on the minimum
    assert c_step.c_goals_met({**row, "c_cpu_us": 1e3}) == c_step.c_goals_met(row)
    assert not c_step.c_goals_met({**row, "c_step_diff": 2e-9, "c_run_diff": 0.0})  # the goal is on the per-step one
    assert c_step.c_goals_met({**row, "c_run_diff": 1.0}) == c_step.c_goals_met(row)
    # a command logged 1e-6 N m off is reported as 1e-6 off, free-running and one step from the Python state
    shifted = dataclasses.replace(run, command=run.command + 1e-6)
    row = c_step.c_columns(step, shifted, CC)
    assert row["diff_command"] == pytest.approx(1e-6, abs=1e-9)
    assert row["step_diff_command"] == pytest.approx(1e-6, abs=1e-9)


def test_c_step_goal_needs_both_controllers(bench):
    _, bench_loop = bench
    good = {"c_goals_met": True, "c_step_diff": 1e-15, "c_run_diff": 2e-12, "c_cpu_us": 10.0}
    row = {"stop_reached": False, "loops": [{"controller": "sensor", **good}, {"controller": "sensorless", **good}]}
    assert bench_loop.goals(row)["c_step"] is True
    row["loops"][1] = {"controller": "sensorless", **good, "c_goals_met": False}
    assert bench_loop.goals(row)["c_step"] is False
    row["loops"] = row["loops"][:1]  # one controller measured: the goal not reached
    assert bench_loop.goals(row)["c_step"] is None
    assert bench_loop.goals({"stop_reached": False})["c_step"] is None
    text = bench_loop.table_text([{"model": "finger2", "seed": 1, "loops": [{"controller": "sensor", **good}]}])
    assert "1.0e-15 / 2.0e-12 / 10.0" in text
