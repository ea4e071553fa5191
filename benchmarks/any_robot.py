"""Issue 17's goal measured: any tendon-driven robot (a URDF + spec) through every command, as a user types them.

Two robots of example-robot-data with the shipped specs: TriFinger's ``finger_edu``
(``example_spec_path("finger_edu")``: one tendon over the two flexion joints, a passive ab/adduction on its spring)
and the Allegro hand's index finger (``allegro_hand_spec.toml``, the chain of motor ``index``: ``--chain index``).
For each, in a temporary folder, as new processes of ``alpes-dyn ... --model URDF --spec TOML``:

1. ``observability --input motor --output encoder``: the rank of the observability matrix (goal: full, 2n);
2. a drawn robot: every spring the fit fits (finger_edu: all three; the Allegro: the index tendon's three joints, the
   chain's fit holds the others at the spec's values) times 1 + U(-15 %, +15 %) (``--seed``), as ``true.toml``;
   ``experiment --true-spec true.toml -o rec.csv`` (the documented excitation, our simulator), then ``identify
   --data rec.csv --parameters K,friction [--chain index] -o ident.toml``: the fitted springs against the drawn ones
   (goal: every spring of the fitted joints within 1 %);
3. ``mjcf --spec true.toml -o plant.xml``: the drawn robot exported; MuJoCo stepped on that file
   (:func:`alpes_dyn.control.plants.mjcf_recording`: RK4 at 0.1 ms, MuJoCo's stick-slip ``frictionloss``, our
   encoder and torque sensors at 1 kHz) with the experiment's command replayed
   (:func:`~alpes_dyn.estimation.experiments.experiment.model_experiment_torque`: the recording's torque less the
   sensor's noise, checked), written as ``mujoco.csv``;
   ``estimate --spec ident.toml --data mujoco.csv [--chain index]`` (the EKF, reading the identified spec back): the
   RMSE after 1 s, worst joint (goal: < 0.5 degree). Baseline in the same run: the same EKF with the spec the fit
   started from (the ratio says what the identification bought);
4. ``control --spec ident.toml --controller sensor [--frame link_3.0_tip --motor index]``: the tip pressing a block
   in MuJoCo, step reference 0.2 -> 1.0 -> 0.5 N; the steady-state error (goal: < 2 %);
5. the MJCF round trip: ``alpes-dyn mjcf`` of finger3, the hand, finger_edu and the Allegro hand, read back by
   :meth:`Model.from_mjcf <alpes_dyn.Model.from_mjcf>`: the largest difference of A, C, G and the forward dynamics
   from the model exported, over 5 random states (goal: <= 1e-12; the forward dynamics relative to their size).

Every command's wall time is printed (a new process: imports and, where the compile cache is cold, compiles
included). Prints a table, or one JSON object with ``--json``; ``uptime`` before and after.

    python benchmarks/any_robot.py [--json] [--seed 0] [--duration 4] [--robots finger_edu,allegro_index]
                                   [--skip control]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

SPRING_SPREAD = 0.15
GOALS = {"spring_error": 0.01, "ekf_rmse_deg": 0.5, "steady_state_error": 0.02, "round_trip": 1e-12}
STEPS = ("observability", "identify", "estimate", "control")


def robots() -> dict[str, dict[str, Any]]:
    """{name: the URDF, the shipped spec, the chain (motor) fitted and observed, the control's frame and motor}."""
    import alpes_dyn as ad
    from alpes_dyn.model.spec import example_spec_path

    return {"finger_edu": {"urdf": str(ad.example_robot_urdf("finger_edu")), "spec": str(example_spec_path("finger_edu")),
                           "chain": None, "control": []},
            "allegro_index": {"urdf": str(ad.example_robot_urdf("allegro_hand", "allegro_right_hand")),
                              "spec": str(example_spec_path("allegro_hand")), "chain": "index",
                              "control": ["--frame", "link_3.0_tip", "--motor", "index"]}}


def cli(*args: str, as_json: bool = True) -> tuple[float, dict[str, Any]]:
    """Wall time (s) and JSON output of ``alpes-dyn ARGS --json`` as a new process (exit 0 required); ``as_json``
    False: no ``--json`` (``mjcf``, which writes a file), {} for the output."""
    cmd = [sys.executable, "-m", "alpes_dyn.cli", *args] + (["--json"] if as_json else [])
    t0 = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise RuntimeError(f"alpes-dyn {' '.join(args[:1])}: exit {r.returncode}: {r.stderr.strip()[-600:]}")
    return wall, json.loads(r.stdout) if as_json else {}


def drawn_spec(spec_path: str, seed: int, folder: Path, chain: str | None) -> tuple[Path, dict[str, float]]:
    """``true.toml``: the spec with each spring the fit fits (every spring; with ``chain``, those of the joints that
    motor drives) times 1 + U(-SPRING_SPREAD, SPRING_SPREAD) (seeded); the drawn springs returned."""
    import dataclasses

    from alpes_dyn.model.spec import load_spec

    spec = load_spec(spec_path)
    drawn = (list(spec.stiffness) if chain is None else
             [j for m in spec.motors if m.name == chain for j in m.joints if j in spec.stiffness])
    rng = np.random.default_rng(seed)
    true_k = {j: spec.stiffness[j] * (1 + rng.uniform(-SPRING_SPREAD, SPRING_SPREAD)) for j in drawn}
    path = folder / "true.toml"
    path.write_text(dataclasses.replace(spec, stiffness={**spec.stiffness, **true_k}).to_toml())
    return path, true_k


def _rmse_deg(obj: dict[str, Any]) -> list[float]:
    return [float(np.degrees(x)) for x in obj["rmse"]]


def run_robot(name: str, r: dict[str, Any], seed: int, duration: float, skip: set[str], d: Path) -> dict[str, Any]:
    """The steps of the module doc on one robot; each step's figures and wall time."""
    import alpes_dyn as ad
    from alpes_dyn.control.plants import mjcf_recording
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment_torque
    from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
    from alpes_dyn.model.spec import load_spec

    out: dict[str, Any] = {"chain": r["chain"]}
    base = ["--model", r["urdf"]]
    chain = ["--chain", r["chain"]] if r["chain"] else []
    if "observability" not in skip:
        w, obs = cli("observability", *base, "--spec", r["spec"], "--input", "motor", "--output", "encoder")
        out["observability"] = {"rank": obs["rank"], "n_states": obs["n_states"], "wall_s": w,
                                "goal_met": obs["rank"] == obs["n_states"]}
    if "identify" in skip:
        return out
    true_path, true_k = drawn_spec(r["spec"], seed, d, r["chain"])
    rec = d / "rec.csv"
    w_exp, _ = cli("experiment", *base, "--spec", r["spec"], "--true-spec", str(true_path), "-o", str(rec),
                   "--duration", f"{duration:g}", "--seed", str(seed))
    ident = d / "ident.toml"
    w_id, fit = cli("identify", *base, "--spec", r["spec"], "--data", str(rec), "--parameters", "K,friction",
                    *chain, "-o", str(ident))
    fitted = {p[2:]: v["value"] for p, v in fit["parameters"].items() if p.startswith("K_")}
    errors = {j: fitted[j] / true_k[j] - 1 for j in true_k}
    back = load_spec(ident)  # written, and read back as a spec
    out["identify"] = {"experiment_wall_s": w_exp, "identify_wall_s": w_id, "compile_s": fit.get("compile_seconds"),
                       "iterations": fit.get("iterations"), "converged": fit.get("converged"),
                       "residual_rms": fit.get("residual_rms"), "spring_error": errors,
                       "written_source": (back.identified or {}).get("record", {}).get("source", "identified")
                       if back.identified is not None else None,
                       "goal_met": bool(errors) and max(abs(e) for e in errors.values()) < GOALS["spring_error"]}
    if "estimate" not in skip:
        plant = d / "plant.xml"
        w_mj, _ = cli("mjcf", *base, "--spec", str(true_path), "-o", str(plant), as_json=False)
        truth = ad.Model.from_urdf_file(r["urdf"], true_path)
        t0 = time.perf_counter()
        data = read_recording(rec, truth)
        # the experiment's command (the recording's torque less the sensor's noise), not the measured torque
        design = ExperimentDesign(duration=duration)
        _, u, x0 = model_experiment_torque(ad.Model.from_urdf_file(r["urdf"], r["spec"]), truth, design)
        assert np.max(np.abs(data.torque - u)) < 6.0 * design.torque_noise
        mj_rec = mjcf_recording(plant, truth, u, float(data.dt), seed=seed + 1, q0=x0[: truth.n])
        w_rec = time.perf_counter() - t0
        write_recording(mj_rec, d / "mujoco.csv")
        w_ekf, ekf = cli("estimate", *base, "--spec", str(ident), "--data", str(d / "mujoco.csv"), *chain)
        w_base, start = cli("estimate", *base, "--spec", r["spec"], "--data", str(d / "mujoco.csv"), *chain)
        worst, worst0 = max(_rmse_deg(ekf)), max(_rmse_deg(start))
        out["estimate"] = {"mjcf_wall_s": w_mj, "mujoco_recording_s": w_rec, "ekf_wall_s": w_ekf,
                           "rmse_deg": dict(zip(ekf["joints"], _rmse_deg(ekf))), "worst_rmse_deg": worst,
                           "baseline_worst_rmse_deg": worst0, "baseline_wall_s": w_base,
                           "baseline_over_identified": worst0 / worst, "goal_met": worst < GOALS["ekf_rmse_deg"]}
    if "control" not in skip:
        w_c, ctl = cli("control", *base, "--spec", str(ident), "--controller", "sensor", *r["control"],
                       "--seed", str(seed))
        out["control"] = {"wall_s": w_c, "steady_state_error": ctl["steady_state_error"], "force_rmse_N": ctl.get("force_rmse"), "q_hat_rmse_deg": ctl.get("q_rmse_deg"),
                          "frame": ctl.get("frame"), "motor": ctl.get("motor"),
                          "goal_met": ctl["steady_state_error"] < GOALS["steady_state_error"]}
    return out


def round_trip(d: Path) -> dict[str, Any]:
    """``alpes-dyn mjcf`` -> ``Model.from_mjcf``: the largest differences of A, C, G, forward dynamics (5 states)."""
    import alpes_dyn as ad

    rs = robots()
    cases = {"finger3": (["--model", "finger3"], ad.Model.alpes("finger3")),
             "hand": (["--model", "hand"], ad.Model.alpes("hand")),
             "finger_edu": (["--model", rs["finger_edu"]["urdf"], "--spec", rs["finger_edu"]["spec"]],
                            ad.Model.from_urdf_file(rs["finger_edu"]["urdf"], rs["finger_edu"]["spec"])),
             "allegro_hand": (["--model", rs["allegro_index"]["urdf"], "--spec", rs["allegro_index"]["spec"]],
                              ad.Model.from_urdf_file(rs["allegro_index"]["urdf"], rs["allegro_index"]["spec"]))}
    out = {}
    for name, (args, m) in cases.items():
        path = d / f"{name}.xml"
        w, _ = cli("mjcf", *args, "-o", str(path), as_json=False)
        b = ad.Model.from_mjcf(path)
        rng = np.random.default_rng(7)
        diff = {"A": 0.0, "C": 0.0, "G": 0.0, "forward_dynamics_rel": 0.0}
        for _ in range(5):
            q, v = m.random_state(rng)
            tau = rng.normal(scale=0.05, size=m.n)
            diff["A"] = max(diff["A"], float(np.max(np.abs(b.inertia_matrix(q) - m.inertia_matrix(q)))))
            diff["C"] = max(diff["C"], float(np.max(np.abs(b.coriolis_matrix(q, v) - m.coriolis_matrix(q, v)))))
            diff["G"] = max(diff["G"], float(np.max(np.abs(b.gravity_torque(q) - m.gravity_torque(q)))))
            fa, fb = m.forward_dynamics(q, v, tau), b.forward_dynamics(q, v, tau)
            diff["forward_dynamics_rel"] = max(diff["forward_dynamics_rel"],
                                               float(np.max(np.abs(fb - fa)) / np.max(np.abs(fa))))
        out[name] = {**diff, "n": m.n, "wall_s": w, "goal_met": max(diff.values()) <= GOALS["round_trip"]}
    return out


def _uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--seed", type=int, default=0, help="the drawn springs' and the sensors' seed (default 0)")
    ap.add_argument("--duration", type=float, default=4.0, help="the experiment's length, s (default %(default)s)")
    ap.add_argument("--robots", default="finger_edu,allegro_index", help="comma-separated (default: both)")
    ap.add_argument("--skip", default="", help=f"steps to skip, comma-separated: {', '.join(STEPS)}, round_trip")
    a = ap.parse_args()
    skip = {s for s in a.skip.split(",") if s}
    rs = robots()
    names = [n for n in a.robots.split(",") if n]
    bad = [n for n in names if n not in rs] + [s for s in skip if s not in STEPS + ("round_trip",)]
    if bad:
        ap.error(f"unknown robot or step {bad[0]!r}")
    out: dict[str, Any] = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "seed": a.seed,
                           "duration_s": a.duration, "goals": GOALS, "load": {"before": _uptime()}, "robots": {}}
    with tempfile.TemporaryDirectory(prefix="any_robot_") as tmp:
        for n in names:
            (Path(tmp) / n).mkdir()
            out["robots"][n] = run_robot(n, rs[n], a.seed, a.duration, skip, Path(tmp) / n)
            out["load"][f"after_{n}"] = _uptime()
        if "round_trip" not in skip:
            out["round_trip"] = round_trip(Path(tmp))
    out["load"]["after"] = _uptime()
    if a.json:
        print(json.dumps(out))
        return
    print_table(out)


def print_table(out: dict[str, Any]) -> None:
    met = {True: "met", False: "NOT met"}
    print(f"any robot from the CLI (issue 17's goal), {out['date']}, seed {out['seed']}, "
          f"{out['duration_s']:g} s experiment")
    for n, r in out["robots"].items():
        print(f"{n}" + (f" (chain {r['chain']})" if r["chain"] else ""))
        if "observability" in r:
            o = r["observability"]
            print(f"  observability rank {o['rank']} / {o['n_states']}  ({o['wall_s']:.1f} s)  {met[o['goal_met']]}")
        if "identify" in r:
            i = r["identify"]
            errs = ", ".join(f"{j} {100 * e:+.3f} %" for j, e in i["spring_error"].items())
            print(f"  identify: springs vs the drawn robot {errs}; residual {i['residual_rms']:.3f} counts, "
                  f"{i['iterations']} iterations, converged {i['converged']}; experiment {i['experiment_wall_s']:.1f} s,"
                  f" identify {i['identify_wall_s']:.1f} s (compile {i['compile_s']:.1f} s)  "
                  f"goal 1 %: {met[i['goal_met']]}")
        if "estimate" in r:
            e = r["estimate"]
            per = ", ".join(f"{j} {x:.3f}" for j, x in e["rmse_deg"].items())
            print(f"  EKF on MuJoCo (the drawn robot's MJCF) with ident.toml: RMSE after 1 s [deg] {per}; worst "
                  f"{e['worst_rmse_deg']:.3f} ({e['ekf_wall_s']:.1f} s)  goal 0.5: {met[e['goal_met']]}")
            print(f"    baseline, the spec the fit started from: worst {e['baseline_worst_rmse_deg']:.3f} deg "
                  f"({e['baseline_over_identified']:.1f}x); MuJoCo recording {e['mujoco_recording_s']:.1f} s")
        if "control" in r:
            c = r["control"]
            print(f"  control (sensor) at {c['frame']}: steady-state error {100 * c['steady_state_error']:.2f} %, "
                  f"force RMSE {c['force_rmse_N']:.3f} N ({c['wall_s']:.1f} s)  goal 2 %: {met[c['goal_met']]}")
    if "round_trip" in out:
        print("MJCF round trip (alpes-dyn mjcf -> Model.from_mjcf), largest difference over 5 states:")
        print(f"  {'model':14s} {'n':>3s} {'A':>9s} {'C':>9s} {'G':>9s} {'FD (rel)':>9s}")
        for n, g in out["round_trip"].items():
            print(f"  {n:14s} {g['n']:3d} {g['A']:9.1e} {g['C']:9.1e} {g['G']:9.1e} {g['forward_dynamics_rel']:9.1e}"
                  f"  goal 1e-12: {met[g['goal_met']]}")
    for k, v in out["load"].items():
        print(f"load {k}: {v}")


if __name__ == "__main__":
    main()
