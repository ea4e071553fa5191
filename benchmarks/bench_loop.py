"""The whole workflow on a hand through the hardware interface only (issue 49): calibration -> guarded experiment
-> identify -> force loop, on the MuJoCo stand-in with a real hand's effects, its truth hidden.

Per model and seed, the "true" finger drawn +-20 % per link (:func:`~alpes_dyn.estimation.experiments.draws.perturbed_params`,
seed ``s``) is given to :class:`~alpes_dyn.bench.mujoco_hand.MujocoHand` and to nothing else:

1. **experiment** (:func:`~alpes_dyn.estimation.experiments.on_hand.run_experiment` on the stand-in's free scene,
   :func:`~alpes_dyn.bench.effects.real_hand_effects`): the calibration, the bias trimmed on the hand, the amplitude
   brought up in steps, the guarded record; written as the documented CSV. finger3 (and the hand's finger chains)
   is recorded palm up and hung fingers down, the two runs joined (:data:`TURNED`); finger2 and the thumb in one
   rig (:func:`run_rigs`). Scored: whether the true joints came
   within ``STOP_MARGIN_DEG`` of a joint stop (the stand-in's truth read after each tick,
   :func:`~alpes_dyn.bench.mujoco_hand.scoring_truth`: the workflow never reads it);
2. **identify**: ``alpes-dyn identify --data rec.csv -o ident.toml --json`` as a user runs it (its defaults:
   ``--effects auto`` from the shipped file); scored: the springs' and the masses' worst errors up to the torque
   constant's common scale (:func:`~alpes_dyn.studies.realism.errors`), the verdict;
3. **force loop** (:func:`~alpes_dyn.control.bench_loop.run_on_bench` with a
   :class:`~alpes_dyn.control.step.ForceStep` built from ``ident.toml``, on the stand-in's block scene, another
   noise seed): the ``sensor`` and ``sensorless`` controllers on the CLI's default step reference
   (:class:`~alpes_dyn.control.finger_loop.ControlScenario`'s levels and step times); scored on MuJoCo's noise-free
   contact force with the metrics of ``force_realism.py`` (RMSE after the rise in % of the step, overshoot, 10-90 %
   rise, steady-state error) and the joint estimates' RMSE during contact against the true joints.

Goals (issue 49): springs within 3 %, masses within 5 %; sensor loop RMSE after the rise < 3 % of the step,
overshoot < 10 %, rise < 100 ms; sensorless within 10 %; joint estimates < 1 degree; no stop reached.
With a C compiler (``cc``, unless ``--no-c``), each loop's step is also built as C
(:mod:`~alpes_dyn.control.cstep`, ``alpes-dyn codegen --step``'s sources, ``benchmarks/c_step.py``'s
:func:`c_step.c_columns`) and run over the loop's readings: its largest difference from the Python step (commands,
joint estimates, forces fed back) one step from the Python step's state (``c_step_diff``; goal 1e-9) and
free-running (``c_run_diff``, not a goal: ``c_step.py``'s docstring), its time per step measured as ``timeit``
does (``c_step.py``'s time rule: the record run ``c_step.PASSES`` times, each step timed on its own; ``c_us_min``
the mean over the steps of each step's minimum over the passes, the step's own cost, the figure held against the
goal, < 50 us per finger, 200 us for the hand; ``c_us_median`` the same of each step's median beside it, the other
processes' share in the gap; ``c_cpu_us`` the best single-pass process's processor time, kept) and its build
(goal < 30 s): the ``c_step`` goal.

The hand (``--models hand``) is run chain by chain: one draw of the hand (each finger and the thumb its own +-20 %
values, ``perturbed_params(chains=HAND_CHAINS)``) and each finger chain's workflow as above on the stand-in of a
finger3 with that chain's true values (:func:`~alpes_dyn.model.params.chain_params`; the hand's chains do not move
one another, :mod:`~alpes_dyn.estimation.experiments.hand_experiment`), its own noise seeds; one row per chain.
The thumb's row (:func:`thumb_row`):

1. its experiment on the stand-in of the thumb's chain (``MujocoHand("thumb")``: its flexion and ab/adduction
   motors, the hand's true thumb), the nominal ``Model.alpes("thumb")``: the flexion excited and trimmed as a
   finger's, the ab/adduction held relaxed at 0 N m (a motor that only pulls, on a joint without a spring:
   :mod:`~alpes_dyn.estimation.experiments.on_hand`); stops scored on the flexion's joints (the ab/adduction
   rests, relaxed, on its 0 degree stop: ``abduction_deg`` its range over the record);
2. ``alpes-dyn identify --model thumb`` (its default parameters,
   :data:`~alpes_dyn.estimation.identification.identification.THUMB_PARAMETERS`), scored as a finger's;
3. its force loop on the stand-in's ``"cylinder"`` scene, the whole hand
   (:class:`~alpes_dyn.control.hand_step.HandForceStep` from the thumb's identified file: its ab/adduction PD
   brings the thumb's pad opposite the cylinder; the fingers' chains at the file's shipped values, loaded but
   not scored), at the CLI's default references of the hand (``alpes-dyn control --model hand``:
   :data:`~alpes_dyn.control.hand_loop.HAND_LEVELS`, the step at 2.5 s of 3.5 s); scored on the thumb's chain
   (MuJoCo's force at its fingertip, its joint estimates), the metrics' percentages of the thumb's own step; the
   hand's C step (:mod:`~alpes_dyn.control.chand`) replayed on the same readings, goal 200 us. First the
   calibration press (:func:`thumb_loops`, ``alpes-dyn control --calibrate``'s): the sensorless loop uncalibrated,
   the ratio of its estimate to the fingertip sensor before the step
   (:func:`~alpes_dyn.control.grasp_calibration.force_scale_of`: the torque constant's error, which the
   identification cannot see) the thumb's ``force_scale`` of both loops -- the sensorless estimate divided by it,
   the EKF's force input multiplied by it (the sensor's newtons in the file's torque units).

    python benchmarks/bench_loop.py [--seeds 9501,...] [--models finger2,finger3,hand] [--chains thumb] [--json]
                                    [--out-json PATH]
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from alpes_dyn.bench.mujoco_hand import MujocoHand, scoring_truth
from alpes_dyn.control.bench_loop import run_on_bench
from alpes_dyn.control.controller import reference_profile
from alpes_dyn.control.finger_loop import ControlResult, ControlScenario, _metrics
from alpes_dyn.control.grasp_calibration import force_scale_of
from alpes_dyn.control.hand_loop import HAND_LEVELS, HandControlScenario
from alpes_dyn.control.hand_step import HandForceStep
from alpes_dyn.control.realism_loop import Compensation
from alpes_dyn.control.step import ForceStep
from alpes_dyn.errors import AlpesDynError
from alpes_dyn.estimation.experiments.draws import perturbed_params
from alpes_dyn.estimation.experiments.hand_experiment import _chain_seeds
from alpes_dyn.estimation.experiments.on_hand import ROOM_SHARE, roomier, run_experiment
from alpes_dyn.estimation.experiments.recording import write_recording
from alpes_dyn.estimation.experiments.turned import TURNED_RIGS, RigTripped, joined_runs, rig_design
from alpes_dyn.estimation.experiments.turned import run_turned as turned_experiment
from alpes_dyn.model.params import chain_params
from alpes_dyn.model.robot import Model
from alpes_dyn.studies.realism import errors
from alpes_dyn.symbolic.parametric import parameter_catalogue

from c_step import GOAL_HAND_US, c_columns, c_goals_met, hand_c_columns
from force_realism import metrics

RIGS = TURNED_RIGS
"""The rigs tried in turn: palm up, then hung fingers down."""
TURNED = ("finger3",)
"""The models recorded in both rigs, the runs joined (:func:`run_turned`): in one orientation finger3's three
masses trade with its cable's compliance (the stretch C tau_m that the encoder reads beside S q), and a model error
of the quasi-static stretch moves them along that direction, m_1 and m_3 one way and m_2 the other, by up to 5 %
at a standard error of 1 %; the second orientation's gravity separates them. finger2 and the thumb, masses within
1 % in one orientation, keep the rig rule (:func:`run_rigs`)."""
STOP_MARGIN_DEG = 0.5
"""A true joint within this of its stop counts as a stop reached."""
CONTROLLERS = ("sensor", "sensorless")
HAND_CHAINS = ("index", "middle", "ring", "little", "thumb")
"""The hand's chains run (the module docstring)."""
LOOP_SEED = 1000
"""The force loop's noise seed: this plus the draw's (another draw of the sensors' noise than the experiment's)."""


class Scored:
    """A :class:`~alpes_dyn.bench.interface.HardwareInterface` that passes everything to the stand-in ``hw`` and
    keeps its truth after each tick for the score (the workflow sees only the interface)."""

    def __init__(self, hw: MujocoHand) -> None:
        self.hw = hw
        self.period, self.motor_names = hw.period, hw.motor_names
        self.counts_per_rev, self.tau_max = hw.counts_per_rev, hw.tau_max
        self.q, self.F = [], []
        self._keep()

    def _keep(self) -> None:
        q, F = scoring_truth(self.hw)
        self.q.append(q)
        self.F.append(F)

    def read(self):
        return self.hw.read()

    def write(self, command) -> None:
        self.hw.write(command)
        self._keep()

    def close(self) -> None:
        self.hw.close()


def run_rigs(model: str, truth: Any, seed: int, nominal: Model) -> tuple[tuple | None, list[str]]:
    """Calibration and the guarded experiment on the free stand-in, palm up, then hung fingers down where the guard
    found no room palm up or palm up left less than :data:`~alpes_dyn.estimation.experiments.on_hand.ROOM_SHARE`
    of the designed amplitude (as a user turns the hand); of two runs, the one with the larger amplitude kept
    (:func:`~alpes_dyn.estimation.experiments.on_hand.roomier`). Returns ((rig, the scored stand-in, the
    :class:`~alpes_dyn.estimation.experiments.on_hand.OnHandResult`) or None where every rig failed, the rigs
    tried and why each was not kept)."""
    kept, tried = None, []
    for rig in RIGS:
        hw = Scored(MujocoHand(model, truth, scene="free", seed=seed, rig=rig))
        try:
            res = run_experiment(hw, nominal, rig_design(rig))
        except AlpesDynError as e:
            tried.append(f"{rig}: {e}")
            continue
        if kept is not None:
            tried.append(f"{kept[0]}: amplitude scale {kept[2].amplitude_scale:.3g} (below {ROOM_SHARE:g})")
            if roomier(kept[2], res) is kept[2]:
                tried.append(f"{rig}: amplitude scale {res.amplitude_scale:.3g} (not roomier: not kept)")
                continue
        kept = (rig, hw, res)
        if res.amplitude_scale >= ROOM_SHARE:
            break
    return kept, tried


def run_turned(model: str, truth: Any, seed: int, nominal: Model) -> tuple[list, list[str]]:
    """Calibration and the guarded experiment on the free stand-in in each of :data:`RIGS` (palm up, then hung
    fingers down), as ``alpes-dyn experiment --bench mujoco --rig both`` runs them: the library's
    :func:`~alpes_dyn.estimation.experiments.turned.run_turned` with ``keep_going=True`` (the hand turned between
    the runs, each rig's stand-in seeded ``seed`` plus the rig's index; a rig whose guard trips left out, the other
    kept). Returns (the runs that recorded, each (rig, the scored stand-in, the
    :class:`~alpes_dyn.estimation.experiments.on_hand.OnHandResult`); the rigs left out, and why: every rig where
    none recorded, or the rig whose run raised another error, as the command would exit with it)."""
    hands: dict[str, Scored] = {}

    def hand_in(rig: str) -> Scored:
        hands[rig] = Scored(MujocoHand(model, truth, scene="free", seed=seed + RIGS.index(rig), rig=rig))
        return hands[rig]

    try:
        res = turned_experiment(hand_in, nominal, None, RIGS, keep_going=True)
    except RigTripped as e:  # no rig recorded
        return [], [f"{rig}: {why}" for rig, why in (*e.tripped, (e.rig, str(e.trip)))]
    except AlpesDynError as e:  # a rig's settings (e.g. no encoder counts left for the excitation): the command's exit
        return [], [f"{list(hands)[-1]}: {e}"]
    return [(rig, hands[rig], r) for rig, r in zip(res.rigs, res.runs)], [f"{rig}: {why}" for rig, why in res.tripped]


def _stops(hw: Scored, res: Any, nominal: Model) -> dict[str, Any]:
    """One run's stops, scored on the stand-in's truth (the module docstring, step 1)."""
    lo, hi = nominal.lower, nominal.upper  # the URDF's joint stops (the MJCF's ranges)
    # hw.q[i]: the truth after the i-th write (hw.q[0] before any); the experiment's log starts after the
    # calibration's writes (its own session): its row k is the truth hw.q[off + k]
    off = len(hw.q) - len(res.log.t)
    q = np.array(hw.q)
    margin = math.radians(STOP_MARGIN_DEG)
    held = [nominal.joint_index(j) for j in nominal.springless_joints]  # the thumb's ab/adduction: relaxed, held
    at_stop = (q <= lo + margin) | (q >= hi - margin)
    at_stop[:, held] = False
    rows = slice(off + res.record_rows.start, off + res.record_rows.stop)
    rec = q[rows]
    out = {"stop_reached": bool(at_stop[rows].any()),  # during the record
           "stop_in_calibration": bool(at_stop[1: off + 1].any()),  # the calibration's ramps (to a stop, by design)
           "stop_before_record": bool(at_stop[off + 1: rows.start].any()),  # trim, stages
           "record_q_range_deg": [[float(np.degrees(a)), float(np.degrees(b))] for a, b in zip(rec.min(0),
                                                                                               rec.max(0))]}
    if held:
        out["abduction_deg"] = out["record_q_range_deg"][held[0]]
    return out


def experiment_row(model: str, truth: Any, seed: int, tmp: Path, name: str = "") -> tuple[dict, Path | None]:
    """The experiment's row and the recording's path (None if every rig failed): a model of :data:`TURNED` recorded
    in both rigs and the runs joined (:func:`run_turned`,
    :func:`~alpes_dyn.estimation.experiments.turned.joined_runs`; each run's figures under ``runs``, the
    stops of either counted), any other in one (:func:`run_rigs`: the rig rule)."""
    nominal = Model.alpes(model, friction=True)
    t0, c0 = time.perf_counter(), time.process_time()
    if model in TURNED:
        runs, tried = run_turned(model, truth, seed, nominal)
    else:
        kept, tried = run_rigs(model, truth, seed, nominal)
        runs = [] if kept is None else [kept]
    row: dict[str, Any] = {"model": model, "seed": seed, "tried": tried,
                           "experiment_s": time.perf_counter() - t0, "experiment_cpu_s": time.process_time() - c0}
    if not runs:
        row["experiment_error"] = tried[-1]
        return row, None
    row["rig"] = "+".join(rig for rig, _, _ in runs)
    scored = [{**_stops(hw, res, nominal), **res.to_dict(), "rig": rig} for rig, hw, res in runs]
    row.update({k: v for k, v in scored[0].items() if k != "rig"})
    for flag in ("stop_reached", "stop_in_calibration", "stop_before_record"):
        row[flag] = any(x[flag] for x in scored)
    if len(runs) > 1:
        row["runs"] = scored
        row["amplitude_scale"] = min(x["amplitude_scale"] for x in scored)
    path = tmp / f"rec_{model}{name}_{seed}.csv"
    write_recording(joined_runs([r for _, _, r in runs], nominal) if len(runs) > 1 else runs[0][2].recording, path)
    return row, path


def identify_row(model: str, rec: Path, truth: Any, tmp: Path) -> tuple[dict, Path | None]:
    """``alpes-dyn identify`` on the recording, as a user runs it; its errors against the truth."""
    out = tmp / f"ident_{rec.stem}.toml"
    t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([sys.executable, "-m", "alpes_dyn.cli", "identify", "--model", model, "--data", str(rec),
                        "-o", str(out), "--json"], capture_output=True, text=True)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    row: dict[str, Any] = {"identify_s": time.perf_counter() - t0, "identify_exit": p.returncode,
                           "identify_cpu_s": r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime}
    if p.returncode != 0 or not out.exists():
        row["identify_error"] = (p.stderr.strip().splitlines() or ["(no message)"])[-1]
        return row, None
    fit = json.loads(p.stdout)
    values = {k: float(v["value"]) for k, v in fit["parameters"].items() if v.get("value") is not None}
    tv = _truth_values(model, truth, values)
    worst, worst_c, c = errors(values, tv)
    verdict = "adequate" if fit["trustworthy"] else ("not converged" if not fit["converged"] else "inadequate")
    tilt = fit["parameters"].get("tilt_y", {}).get("value")
    row["tilt_deg"] = None if tilt is None else math.degrees(tilt)  # the mount's tilt found (the stand-in's: 3)
    row["identify_rounds"] = [{"effects": r["effects"], "residual_rms": r["residual_rms"], "seconds": r["seconds"]}
                              for r in fit["rounds"]]
    row.update(verdict=verdict, trustworthy=fit["trustworthy"], common_scale=c,
               K_pct=worst_c["K"], m_pct=worst_c["m"], F_s_pct=worst_c["F_s"])
    return row, out


def _truth_values(model: str, truth: Any, values: dict[str, float]) -> dict[str, float]:
    """The true value of each fitted K_i, m_i, F_s_i, F_v_i of the shared finger (the thumb's: its parameter
    catalogue's, as ``identify --model thumb`` names them)."""
    if model == "thumb":
        cat = {p.name: p.nominal for p in parameter_catalogue(Model.alpes("thumb", friction=True, params=truth))}
        return {k: float(cat[k]) for k in values if k in cat}
    f = truth.finger
    out = {}
    for name in values:
        kind, _, i = name.rpartition("_")
        if kind in ("K", "m") and i.isdigit():
            out[name] = float(getattr(f, kind)[int(i) - 1])
        elif kind in ("F_s", "F_v") and i.isdigit() and getattr(f, kind, None) is not None:
            out[name] = float(np.broadcast_to(getattr(f, kind), (3,))[int(i) - 1])
    return out


def loop_row(model: str, ident: Path, truth: Any, seed: int, controller: str, cc: str | None = None) -> dict:
    """The force loop through the interface: ForceStep from the identified file on the block stand-in; with a C
    compiler ``cc``, its C step run over the same readings (:func:`c_step.c_columns`: the largest difference from
    the Python step, us per step, its build)."""
    sc = ControlScenario(model=model, controller=controller)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    F_ref = reference_profile(sc.reference, t, sc.levels, sc.sine, sc.step_times)
    t0, c0 = time.perf_counter(), time.process_time()
    step = ForceStep(model, ident, controller)
    build_s = time.perf_counter() - t0
    hw = Scored(MujocoHand(model, truth, scene="block", seed=LOOP_SEED + seed))
    run = run_on_bench(hw, step, F_ref, sc.duration)
    q_true, F_true = np.array(hw.q[:N]), np.array(hw.F[:N])
    res = ControlResult(scenario=sc, t=t, F_ref=F_ref, F_true=F_true, F_meas=run.force, F_hat=run.F_fb,
                        q_true=q_true, q_hat=run.q_hat, tau_cmd=run.command[:, 0], tau_meas=run.torque[:, 0],
                        joint_names=step.model.joint_names, tau_max=step.tau_max, wall_s=run.wall_s)
    _metrics(res)
    m = metrics(res)
    row = {"controller": controller, "build_s": build_s, "loop_s": run.wall_s, "loop_cpu_s": time.process_time() - c0,
           **m, "q_rmse_deg_joints": res.q_rmse_deg}
    if cc is not None:
        c = c_columns(step, run, cc)
        row.update(c, c_goals_met=c_goals_met(c))
    return row


def thumb_loop_row(ident: Path, truth: Any, seed: int, controller: str, cc: str | None = None,
                   force_scale: float = 1.0) -> dict:
    """The thumb's force loop through the interface (the module docstring, step 3): the whole hand's step from the
    thumb's identified file on the stand-in's cylinder scene, at the hand's default references, the thumb's
    ``force_scale`` (:class:`~alpes_dyn.control.realism_loop.Compensation`); scored on the thumb's chain; with
    ``cc``, the hand's C step over the same readings. A sensorless loop's row also gives the scale its estimate
    reads against the sensor (``force_scale_found``, :func:`~alpes_dyn.control.grasp_calibration.force_scale_of`:
    the calibration press)."""
    hs = HandControlScenario(controller=controller)
    a, b = HAND_LEVELS["thumb"]
    sc = ControlScenario(model="finger2", controller=controller, reference="step", duration=hs.duration,
                         levels=(a, b, b), step_times=(hs.step_time, hs.duration), settle=hs.settle)
    N = int(round(hs.duration / hs.dt))
    t = hs.dt * np.arange(N)
    t0, c0 = time.perf_counter(), time.process_time()
    step = HandForceStep(ident, controller, compensation=Compensation(force_scale={"thumb": force_scale}))
    build_s = time.perf_counter() - t0
    hw = Scored(MujocoHand("hand", truth, scene="cylinder", seed=LOOP_SEED + seed))
    chains = list(step.chains)
    ref = np.array([[lv[0] if tk < hs.step_time else lv[1] for lv in (HAND_LEVELS[c] for c in chains)] for tk in t])
    keys = ("counts", "torque", "force", "ref", "normals", "command", "z", "F_fb")
    rec: dict[str, list] = {k: [] for k in keys}
    i = chains.index("thumb")
    thumb = step.chain_steps["thumb"]
    q_hat = np.empty((N, thumb.n))
    t1 = time.perf_counter()
    for k in range(N):  # the user's loop: read, step, write
        r = hw.read()
        u = step.step(r.counts, r.torque, None if controller == "sensorless" else r.force, ref[k])
        hw.write(u)
        q_hat[k] = thumb.estimate[0]
        for key, v in zip(keys, (r.counts, r.torque, r.force, ref[k], step.normals, u, step.state,
                                 step.force_estimate)):
            rec[key].append(v)
    wall = time.perf_counter() - t1
    hw.close()
    rec = {k: np.array(v) for k, v in rec.items()}
    hand = Model.alpes("hand")
    joints = [hand.joint_names.index(f"thumb_{j}") for j in thumb.model.joint_names]
    res = ControlResult(scenario=sc, t=t, F_ref=ref[:, i], F_true=np.array(hw.F[:N])[:, i],
                        F_meas=rec["force"][:, i], F_hat=rec["F_fb"][:, i], q_true=np.array(hw.q[:N])[:, joints],
                        q_hat=q_hat, tau_cmd=rec["command"][:, i], tau_meas=rec["torque"][:, i],
                        joint_names=thumb.model.joint_names, tau_max=step.tau_max, wall_s=wall)
    _metrics(res)
    row = {"controller": controller, "scene": "cylinder", "build_s": build_s, "loop_s": wall,
           "loop_cpu_s": time.process_time() - c0, **metrics(res, step=b - a), "q_rmse_deg_joints": res.q_rmse_deg,
           "abduction_end_deg": float(np.degrees(np.array(hw.q[N - 1])[hand.joint_names.index("thumb_abd")])),
           "force_scale": force_scale}
    if controller == "sensorless":
        try:
            row["force_scale_found"] = float(force_scale_of(res, force_scale))
        except AlpesDynError as e:  # no contact before the step, or a ratio beyond a scale
            row["force_scale_found"], row["force_scale_error"] = None, str(e)
    if cc is not None:
        c = hand_c_columns(step, rec, cc)
        row.update(c, c_goals_met=c_goals_met(c, GOAL_HAND_US))
    return row


def thumb_loops(ident: Path, truth: Any, seed: int, cc: str | None = None) -> list[dict]:
    """The thumb's loops (the module docstring, step 3): the calibration press first -- the sensorless loop
    uncalibrated (``controller`` ``"calibration"``, no C), the scale its estimate reads against the fingertip
    sensor before the step -- then each of :data:`CONTROLLERS` with that ``force_scale``."""
    try:
        cal = thumb_loop_row(ident, truth, seed, "sensorless")
    except AlpesDynError as e:
        return [{"controller": "calibration", "error": str(e)}]
    loops = [{**cal, "controller": "calibration"}]
    if cal["force_scale_found"] is None:
        return loops + [{"controller": ctl, "error": f"calibration: {cal['force_scale_error']}"} for ctl in CONTROLLERS]
    for ctl in CONTROLLERS:
        try:
            loops.append(thumb_loop_row(ident, truth, seed, ctl, cc, cal["force_scale_found"]))
        except AlpesDynError as e:
            loops.append({"controller": ctl, "error": str(e)})
    return loops


def draw_rows(model: str, seed: int, tmp: Path, truth: Any = None, noise_seed: int | None = None,
              name: str = "", cc: str | None = None) -> dict:
    """One draw's workflow (``truth`` default the finger drawn with ``seed``; the sensors' noise seeded by
    ``noise_seed``, default ``seed``; the loops' C step built with ``cc`` where given); ``model`` ``"thumb"``: the
    thumb's row (the module docstring), ``truth`` the hand's."""
    truth = perturbed_params(spread=0.2, seed=seed) if truth is None else truth
    noise = seed if noise_seed is None else noise_seed
    row, rec = experiment_row(model, truth, noise, tmp, name)
    row["seed"] = seed
    if rec is None:
        return row
    fit, ident = identify_row(model, rec, truth, tmp)
    row.update(fit)
    if ident is None:
        return row
    if model == "thumb":
        row["loops"] = thumb_loops(ident, truth, noise, cc)
        return row
    row["loops"] = []
    for ctl in CONTROLLERS:
        try:
            row["loops"].append(thumb_loop_row(ident, truth, noise, ctl, cc) if model == "thumb"
                                else loop_row(model, ident, truth, noise, ctl, cc))
        except AlpesDynError as e:
            row["loops"].append({"controller": ctl, "error": str(e)})
    return row


def model_rows(model: str, seed: int, tmp: Path, cc: str | None = None,
               chains: tuple[str, ...] = HAND_CHAINS) -> list[dict]:
    """A finger's draw (one row), or the hand's (one row per chain of ``chains``, of :data:`HAND_CHAINS`, the module
    docstring: the hand drawn whole and each chain's noise seeded as in the whole run, whichever are run)."""
    if model != "hand":
        return [draw_rows(model, seed, tmp, cc=cc)]
    truth = perturbed_params(spread=0.2, seed=seed, chains=HAND_CHAINS)
    rows = []
    for chain, noise in zip(HAND_CHAINS, _chain_seeds(seed, len(HAND_CHAINS))):
        if chain not in chains:
            continue
        noise = noise % (2 ** 31 - LOOP_SEED)  # the stand-in's seed and the loop's LOOP_SEED above it
        if chain == "thumb":
            row = draw_rows("thumb", seed, tmp, truth, noise, "", cc)
        else:
            row = draw_rows("finger3", seed, tmp, chain_params(truth, chain), noise, f"_{chain}", cc)
        rows.append({**row, "model": "hand", "chain": chain})
    return rows


def goals(row: dict) -> dict[str, bool | None]:
    """Each goal of the issue for one draw (None where the step before failed)."""
    loops = {r["controller"]: r for r in row.get("loops", [])}
    s, sl = loops.get("sensor", {}), loops.get("sensorless", {})
    ok = lambda c: None if c is None else bool(c)  # noqa: E731
    c = [x for x in loops.values() if "c_goals_met" in x]
    return {
        "no_stop": ok(None if "stop_reached" not in row else not row["stop_reached"]),
        "springs_3pct": ok(None if "K_pct" not in row else row["K_pct"] < 3),
        "masses_5pct": ok(None if "m_pct" not in row else row["m_pct"] < 5),
        "sensor_loop": ok(None if "rmse_pct" not in s else s["rmse_pct"] < 3 and (s["overshoot_pct"] or 0) < 10
                          and s["rise_ms"] is not None and s["rise_ms"] < 100),
        "sensorless_10pct": ok(None if "sse_pct" not in sl else sl["sse_pct"] is not None and sl["sse_pct"] < 10),
        "joints_1deg": ok(None if not s.get("q_rmse_deg_joints") else max(s["q_rmse_deg_joints"]) < 1),
        "c_step": ok(None if not c or len(c) < len(CONTROLLERS) else all(x["c_goals_met"] for x in c)),
    }


def _f(x: Any, fmt: str) -> str:
    return "n/a" if x is None else format(x, fmt)


def table_text(rows: list[dict]) -> str:
    head = ("model        seed  stop  K %   m %   verdict        sensor rmse % / os % / rise ms  sensorless sse %  "
            "q deg (sensor)   C |dC-py| step / run / us")
    lines = [head, "-" * len(head)]
    for r in rows:
        loops = {x["controller"]: x for x in r.get("loops", [])}
        s, sl = loops.get("sensor", {}), loops.get("sensorless", {})
        err = r.get("experiment_error") or r.get("identify_error") or s.get("error")
        qd = s.get("q_rmse_deg_joints")
        c = [x for x in loops.values() if "c_step_diff" in x]
        cs = "n/a" if not c else (f"{max(x['c_step_diff'] for x in c):.1e} / {max(x['c_run_diff'] for x in c):.1e} / "
                                  f"{max(x.get('c_us_min', x['c_cpu_us']) for x in c):.1f}")
        label = r["model"] + (f"/{r['chain']}" if "chain" in r else "")
        lines.append(f"{label:12s} {r['seed']:5d} {str(r.get('stop_reached', 'n/a')):5s} "
                     f"{_f(r.get('K_pct'), '5.2f')} {_f(r.get('m_pct'), '5.2f')} {str(r.get('verdict', ''))[:14]:14s} "
                     f"{_f(s.get('rmse_pct'), '5.2f')} / {_f(s.get('overshoot_pct'), '5.1f')} / "
                     f"{_f(s.get('rise_ms'), '5.0f')}          {_f(sl.get('sse_pct'), '5.2f')}            "
                     f"{'n/a' if not qd else ' '.join(f'{x:.2f}' for x in qd):16s} {cs}"
                     + (f"  ERROR: {err}" if err else ""))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="9501,9502,9503,9504,9505,9506")
    ap.add_argument("--models", default="finger2,finger3")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--out-json", default=None)
    ap.add_argument("--no-c", action="store_true", help="skip the C step's column")
    ap.add_argument("--chains", default=",".join(HAND_CHAINS), help="--models hand: the chains run (default all)")
    a = ap.parse_args(argv)
    chains = tuple(c.strip() for c in a.chains.split(",") if c.strip())
    if not chains or set(chains) - set(HAND_CHAINS):
        ap.error(f"--chains: expected some of {','.join(HAND_CHAINS)}, got {a.chains!r}")
    cc = None if a.no_c else shutil.which("cc") or shutil.which("gcc")
    seeds = [int(s) for s in a.seeds.split(",") if s.strip()]
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for model in a.models.split(","):
            for s in seeds:
                for row in model_rows(model, s, Path(d), cc, chains):
                    row["goals"] = goals(row)
                    rows.append(row)
                    if not a.json:
                        print(table_text([row]).splitlines()[-1], flush=True)
    out = {"rows": rows, "goals_met": {g: sum(1 for r in rows if r["goals"][g]) for g in rows[0]["goals"]} if rows
           else {}, "draws": len(rows)}
    if a.out_json:
        Path(a.out_json).write_text(json.dumps(out, indent=1, default=float))
    print(json.dumps(out, default=float) if a.json else table_text(rows) + "\n" + json.dumps(out["goals_met"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
