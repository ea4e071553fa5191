"""The whole force step in C (issue 49, item 4): its build, its agreement with the Python step, its time per step.

For each finger and controller, in one process:

    Python step   ForceStep.step (its EKF compiled, the compile excluded and reported: "py build s"), timed over the
                  readings of a run on the MuJoCo stand-in (the block scene, every effect of a real hand, a fresh
                  noise seed), replayed: us per step
    C step        alpes-dyn codegen --step's sources (alpes_dyn.control.cstep), built with cc -O2 -std=c99 ("build
                  s", wall clock, and "(cpu)" the compiler's processor time, which a loaded machine inflates less:
                  the goal is under 30 s), run over the same readings by its main.c: the largest
                  difference from the Python step's commands (N m), joint estimates (rad) and forces fed back (N)
                  (the agreement rule below), and timed (the time rule below): "min us" each step's minimum over
                  PASSES passes (the goal's figure), "C us" the best of PASSES single-pass processes' wall clock,
                  "(cpu)" their best processor time per step

The agreement rule: the C step is compared with the Python step one step from the same state (``main -s``: at
every tick the C step starts from the Python step's state before that tick, cstep.step_state_row /
chand.hand_state_row, and its command, estimate and force fed back are held against the Python step's at that tick):
``step_diff_command``, ``step_diff_q``, ``step_diff_force`` and their largest ``c_step_diff``, the goal (1e-9). The
free run (the C step fed only the readings, from its own state: ``diff_command``, ``diff_q``, ``diff_force``,
``c_run_diff``) is kept beside it and is not a goal: the two run the same operations but for the order of a few
sums (CasADi's feedforward and contact force against the Python step's), and the loop's filter amplifies a
1e-17 difference by up to 1e10 where a joint's friction changes branch near rest (the smooth law's slope F_s / v_s,
alpes_dyn.control.step.force_ekf) or where a joint in contact is barely observed (the step's command is its
observer's motor torque and its observer's estimate feeds its command: a loop inside the step, also in a replay).
Measured on an identified finger3 (sensor loop, 1.5 s): one step from the same state 7e-18 N m and the estimates
equal, free-running 3e-8 rad; on the hand with a file of the thumb's identification (sensor loop, 2.5 s): 1.4e-17
against 0.98 rad/s free-running (the little finger's velocities; its angles 9e-3 rad, the commands 4e-5 N m apart),
and the Python step against itself, its force readings scaled by 1 + 1e-15, 0.81 rad/s apart as much: the free run's
difference is the loop's sensitivity, not the C's.

The time rule: the goal (50 us per finger, 200 us for the hand) is real time on the user's machine, the step's
own cost on a core of its own. It is measured as Python's ``timeit`` recommends: the timed passes repeated and
their minimum taken, the minimum being the code's own cost and the rest the other processes' (the time slices
taken, the caches evicted). ``main -t PASSES`` runs the record PASSES times in one process and times each step on
its own: ``c_us_min``, the figure held against the goal, is the mean over the record's steps of each step's
minimum over the passes (every step of the record counts, the contact's and the free motion's alike, each at its
own cost), and ``c_us_median`` the same of each step's median, kept beside it (their gap is the load's share). The
earlier figures are kept: PASSES passes of ``main -t 1``, each its own process, their best processor time per step
(``c_cpu_us``: on a shared machine a whole pass is rarely quiet; the hand's record had identified finger chains
with the stick-slip law at 26-45 us on most rows and 50-57 us on a few), their median (``c_cpu_us_median``) and
the best pass's wall clock ("C us", ``c_us``). At a load of 6-7 on two cores the per-step minimum was 2-4 % below
the best pass's processor time (finger2 4.8 against 5.0 us, finger3 9.1 against 9.3, the hand 43.5 against 45.4;
the hand with an identified thumb's file with the stick-slip law and the torque delay 130 against 133).

The columns C/py give the C step's time as a fraction of the Python step's. The model "hand" is the whole hand's
step (HandForceStep, alpes_dyn.control.chand's C: five chains and the ab/adduction PD; the stand-in's cylinder scene,
every chain 0.3 N then 0.4 N after 2 s of a 2.5 s run; the normals the Python step used fed to the C step; goal:
under 200 us per step). "py build s" is the step's construction (its EKFs compiled or loaded from the shared cache);
"build s" the C build alone.

``--laws tanh,creep,lugre`` runs each model and controller once per friction law (the shipped file with its
``friction.law`` set, the law's constants at their defaults; the EKF then runs that law, alpes_dyn.control.step.
force_ekf), on the same stand-in seed for every law: the C step's time per step by law (column "law"; default: the
file's own law only).

    python benchmarks/c_step.py [--models finger2,finger3,hand] [--controllers sensor[,sensorless,pi]] [--seed 9693]
                                [--laws tanh,creep,lugre] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from alpes_dyn.bench.mujoco_hand import MujocoHand
from alpes_dyn.control.bench_loop import run_on_bench
from alpes_dyn.control.cstep import read_step_output, step_main_input, step_state_row, write_c_step
from alpes_dyn.control.step import ForceStep

GOAL_US = 50.0
GOAL_HAND_US = 200.0
GOAL_BUILD_S = 30.0
GOAL_DIFF = 1e-9
PASSES = 10
"""The C step is timed over this many passes over the record (the module docstring's time rule)."""


def _python_us(step: ForceStep, run, repeat: int = 3) -> float:
    """us per ForceStep.step over the recorded readings (the best of ``repeat`` replays)."""
    best = np.inf
    rows = [(run.counts[k], run.torque[k], float(run.force[k]), float(run.F_ref[k])) for k in range(len(run.t))]
    for _ in range(repeat):
        step.reset()
        t0 = time.perf_counter()
        for c, tq, f, r in rows:
            step.step(c, tq, f, r)
        best = min(best, (time.perf_counter() - t0) / len(rows))
    return 1e6 * best


def _build_c(cc: str, d: Path, files: dict, row: dict) -> None:
    """cc -O2 of every C file in ``d``: the wall and processor seconds into ``row``."""
    row["c_source_kb"] = sum(len((d / n).read_bytes()) for n in files) / 1e3
    sources = [str(d / n) for n in sorted(files) if n.endswith(".c")]
    t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run([cc, "-O2", "-std=c99", "-o", str(d / "main"), *sources, "-lm"], check=True, capture_output=True,
                   timeout=1800)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    row["c_build_s"] = time.perf_counter() - t0
    row["c_build_cpu_s"] = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def _time_c(d: Path, row: dict) -> None:
    """The C step's time per step, us, into ``row`` (the module docstring's time rule): ``main -t PASSES`` (the
    record :data:`PASSES` times in one process, each step timed on its own): ``c_us_min`` the mean over the record's
    steps of each step's minimum over the passes (the goal's figure), ``c_us_median`` of its median; and ``main -t
    1`` run :data:`PASSES` times, each its own process: ``c_cpu_us`` the best pass's processor time per step,
    ``c_us`` the best pass's wall clock, ``c_cpu_us_median`` the passes' median processor time."""
    t = subprocess.run([str(d / "main"), "-t", str(PASSES), str(d / "in.txt")], check=True, capture_output=True,
                       text=True).stdout
    lo, med = re.search(r"minimum over the passes (\S+) us, its median (\S+) us", t).groups()
    row["c_us_min"], row["c_us_median"] = float(lo), float(med)
    wall, cpu = [], []
    for _ in range(PASSES):
        t = subprocess.run([str(d / "main"), "-t", "1", str(d / "in.txt")], check=True, capture_output=True,
                           text=True).stdout.split()
        wall.append(float(t[4]))
        cpu.append(float(t[8]))
    row["c_us"], row["c_cpu_us"], row["c_cpu_us_median"] = min(wall), min(cpu), float(np.median(cpu))
    row["c_passes"] = PASSES


def law_params(law: str | None):
    """The shipped parameter file with ``friction.law`` = ``law`` (None: the shipped file as it is)."""
    from alpes_dyn.model.params import Param, load_params, with_values

    return None if law is None else with_values(load_params(), {"friction.law": Param(law, "-", "assumed",
                                                                                     "benchmarks/c_step.py --laws")})


def bench_hand(controller: str, seed: int, duration: float, cc: str | None, law: str | None = None) -> dict:
    """The whole hand's step (module docstring)."""
    from alpes_dyn.control.hand_step import HandForceStep

    t0 = time.perf_counter()
    step = HandForceStep(law_params(law), controller=controller)
    py_build = time.perf_counter() - t0
    hw = MujocoHand("hand", scene="cylinder", seed=seed)
    keys = ("counts", "torque", "force", "ref", "normals", "command", "z", "F_fb")
    rec = {k: [] for k in keys}
    py_s = 0.0
    for k in range(int(round(duration / hw.period))):
        r = hw.read()
        ref = np.full(5, 0.3 if k * hw.period < 2.0 else 0.4)
        t1 = time.perf_counter()
        u = step.step(r.counts, r.torque, None if controller == "sensorless" else r.force, ref)
        py_s += time.perf_counter() - t1
        hw.write(u)
        for key, v in zip(keys, (r.counts, r.torque, r.force, ref, step.normals, u, step.state, step.force_estimate)):
            rec[key].append(v)
    rec = {k: np.array(v) for k, v in rec.items()}
    n = len(rec["command"])
    row = {"model": "hand", "controller": controller, "law": law, "seed": seed, "steps": n, "py_build_s": py_build,
           "py_us": 1e6 * py_s / n, "observer_friction": True, "substeps": None,
           "F_held_N": [float(x) for x in np.nanmean(rec["force"][-300:], axis=0)]}
    if cc is None:
        return {**row, "c_us": None}
    row.update(hand_c_columns(step, rec, cc))
    row["c_vs_py"] = row["c_us"] / row["py_us"]
    row["goals_met"] = c_goals_met(row, GOAL_HAND_US)
    return row


def hand_c_columns(step, rec: dict, cc: str) -> dict:
    """The hand's C step of ``step`` (a :class:`~alpes_dyn.control.hand_step.HandForceStep`; ``alpes-dyn codegen
    --step --model hand``'s sources) built with ``cc -O2`` and run over the readings ``rec`` of a run of ``step``
    (arrays per tick: counts, torque, force, ref, normals and the step's command, z (state), F_fb): the columns of
    :func:`c_columns` (one step from the Python step's state, replayed with the run's normals, and free-running)."""
    from alpes_dyn.control.chand import hand_main_input, hand_state_row, read_hand_output, write_c_hand

    row: dict = {}
    step.reset()
    states = []
    force = rec["force"] if step.kind != "sensorless" else [None] * len(rec["counts"])
    for k in range(len(rec["counts"])):  # the Python step replayed: its state before each tick
        states.append(hand_state_row(step))
        step.step(rec["counts"][k], rec["torque"][k], force[k], rec["ref"][k], rec["normals"][k])
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "c"
        files = write_c_hand(step, d)
        _build_c(cc, d, files, row)
        args = (rec["counts"], rec["torque"], rec["force"], rec["ref"], rec["normals"])
        (d / "in.txt").write_text(hand_main_input(*args))
        (d / "in_s.txt").write_text(hand_main_input(*args, states=np.array(states)))
        for key, flag, name in (("", [], "in.txt"), ("step_", ["-s"], "in_s.txt")):
            out = subprocess.run([str(d / "main"), *flag, str(d / name)], check=True, capture_output=True,
                                 text=True).stdout
            U, Z, F = read_hand_output(out)
            row[key + "diff_command"] = float(np.abs(U - rec["command"]).max())
            row[key + "diff_q"] = float(np.nanmax(np.abs(Z - rec["z"]))) if step.kind != "pi" else None
            row[key + "diff_force"] = float(np.abs(F - rec["F_fb"]).max())
        _diffs(row)
        _time_c(d, row)
    return row


def bench(model: str, controller: str, seed: int, duration: float, cc: str | None, law: str | None = None) -> dict:
    if model == "hand":
        return bench_hand(controller, seed, max(duration, 2.5), cc, law)
    t0 = time.perf_counter()
    step = ForceStep(model, law_params(law), controller=controller)  # its EKF compiled (or loaded from the cache)
    py_build = time.perf_counter() - t0
    run = run_on_bench(MujocoHand(model, scene="block", seed=seed), step, 0.4, duration)
    row = {"model": model, "controller": controller, "law": law, "seed": seed, "steps": len(run.t),
           "py_build_s": py_build,
           "py_us": _python_us(step, run), "observer_friction": step.design.observer_model is not None,
           "substeps": step._ekf.model.substeps if step.filter_step is not None else None}
    if cc is None:
        return {**row, "c_us": None}
    row.update(c_columns(step, run, cc))
    row["c_vs_py"] = row["c_us"] / row["py_us"]
    row["goals_met"] = c_goals_met(row)
    return row


def c_columns(step: ForceStep, run, cc: str) -> dict:
    """The C step of ``step`` (alpes-dyn codegen --step's sources) built with ``cc -O2 -std=c99`` and run over the
    readings of ``run`` (a :class:`~alpes_dyn.control.bench_loop.BenchRun` of ``step``): its source size (kB), its
    build (wall and the compiler's processor time, s), its largest differences from the Python step's commands
    (N m), joint estimates (rad) and forces fed back (N) one step from the Python step's state (``step_diff_*``,
    ``c_step_diff`` their largest: the goal) and free-running (``diff_*``, ``c_run_diff``: the module docstring),
    its time per step (wall and processor, us)."""
    row = {}
    rows = [(run.counts[k], run.torque[k], float(run.force[k]), float(run.F_ref[k])) for k in range(len(run.t))]
    step.reset()
    states = []
    for c, tq, f, r in rows:  # the Python step replayed: its state before each tick
        states.append(step_state_row(step))
        step.step(c, tq, f, r)
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp) / "c"
        files = write_c_step(step, d)
        _build_c(cc, d, files, row)
        args = (run.counts, run.torque, run.force, run.F_ref, step.design.normal)
        (d / "in.txt").write_text(step_main_input(*args))
        (d / "in_s.txt").write_text(step_main_input(*args, states=np.array(states)))
        for key, flag, name in (("", [], "in.txt"), ("step_", ["-s"], "in_s.txt")):
            out = subprocess.run([str(d / "main"), *flag, str(d / name)], check=True, capture_output=True,
                                 text=True).stdout
            U, Z, F = read_step_output(out, step.m, step.nz)
            row[key + "diff_command"] = float(np.abs(U - run.command).max())
            row[key + "diff_q"] = (float(np.nanmax(np.abs(Z[:, :step.n] - run.q_hat)))
                                   if step.filter_step is not None else None)
            row[key + "diff_force"] = float(np.abs(F - run.F_fb).max())
        _diffs(row)
        _time_c(d, row)
    return row


def _diffs(row: dict) -> None:
    """``c_step_diff`` and ``c_run_diff`` into ``row``: the largest of its ``step_diff_*`` and its ``diff_*``."""
    for key, pre in (("c_step_diff", "step_"), ("c_run_diff", "")):
        row[key] = max(row[pre + "diff_command"], row[pre + "diff_q"] or 0.0, row[pre + "diff_force"])


def c_goals_met(row: dict, goal_us: float = GOAL_US) -> bool:
    """The C step's goals on a row of :func:`c_columns`: under ``goal_us`` us per step, each step's minimum over the
    passes (``c_us_min``, the module docstring's time rule; :data:`GOAL_US` for a finger, :data:`GOAL_HAND_US` for
    the hand), built in under :data:`GOAL_BUILD_S` s of the compiler's processor time, within :data:`GOAL_DIFF` of
    the Python step one step from its state."""
    return bool(row["c_us_min"] < goal_us and row["c_build_cpu_s"] < GOAL_BUILD_S and row["c_step_diff"] <= GOAL_DIFF)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="finger2,finger3")
    ap.add_argument("--controllers", default="sensor")
    ap.add_argument("--seed", type=int, default=9693, help="the stand-in's noise seed of the first row (then +1)")
    ap.add_argument("--duration", type=float, default=1.5, help="s of the run on the stand-in")
    ap.add_argument("--laws", default=None, help="friction laws, e.g. tanh,creep,lugre (default: the file's own)")
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    cc = shutil.which("cc") or shutil.which("gcc")
    load0 = os.getloadavg()[0]
    rows, pairs = [], 0
    laws = [None] if a.laws is None else a.laws.split(",")
    for model in a.models.split(","):
        for controller in a.controllers.split(","):
            for law in laws:  # every law on the same stand-in seed
                rows.append(bench(model, controller, a.seed + pairs, a.duration, cc, law))
            pairs += 1
    out = {"rows": rows, "load_avg": [load0, os.getloadavg()[0]], "goal_us": GOAL_US, "goal_hand_us": GOAL_HAND_US,
           "goal_build_s": GOAL_BUILD_S,
           "goal_diff": GOAL_DIFF, "goals_met": all(r.get("goals_met", False) for r in rows)}
    if a.json:
        print(json.dumps(out))
        return 0
    print(f"load average {load0:.1f} -> {out['load_avg'][1]:.1f}; us per step; differences C - Python")
    print("|du| |dq| |dF|: the free run; step: c_step_diff, one step from the same state (the goal)")
    print(f"{'model':8s} {'ctl':10s} {'law':6s} {'steps':>5s} {'py build s':>10s} {'py us':>7s} {'C kB':>6s} {'build s':>7s} "
          f"{'(cpu)':>6s} {'min us':>6s} {'C us':>6s} {'(cpu)':>6s} {'C/py':>6s} {'|du| N m':>9s} {'|dq| rad':>9s} {'|dF| N':>9s} "
          f"{'step':>9s} goals")
    for r in rows:
        c = (f"{r['c_source_kb']:6.0f} {r['c_build_s']:7.1f} {r['c_build_cpu_s']:6.1f} {r['c_us_min']:6.1f} {r['c_us']:6.1f} {r['c_cpu_us']:6.1f} {r['c_vs_py']:6.3f} "
             f"{r['diff_command']:9.1e} {r['diff_q'] if r['diff_q'] is not None else float('nan'):9.1e} "
             f"{r['diff_force']:9.1e} {r['c_step_diff']:9.1e} {'met' if r['goals_met'] else 'NOT met'}"
             if r["c_us"] is not None
             else "no C compiler")
        print(f"{r['model']:8s} {r['controller']:10s} {r['law'] or 'file':6s} {r['steps']:5d} {r['py_build_s']:10.1f} {r['py_us']:7.1f} {c}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
