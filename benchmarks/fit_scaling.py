"""Fit cost against the record's length (issues 20 and 39): time and peak memory of ``identify`` on 4 s to 10 min.

finger3 drawn +-20 % per link (seed 21 by default: not one the other benchmarks tune on), the documented
identification experiment simulated for each duration as ``alpes-dyn experiment`` makes it (the design adapted over
the whole record: :func:`~alpes_dyn.estimation.experiments.adapt.adapted_experiment`; our simulator, sensor noise on) and
written to a CSV by one process (kept in ``--records DIR`` where given; simulated at the sample rate in compiled C,
:func:`~alpes_dyn.simulation.sampled.sampled_rk4`: a 600 s record of finger3 in 16 s and 381 MiB, of the hand in 3.6
min, 105 s of CPU, 655 MiB, load 2-3.7, 2026-12-05; it took 10-20 minutes per chain through the whole-run
``simulate``), then fitted in a fresh process, so that its peak resident memory is the fit's own. Two fits: ``api``, ``identify`` with the default selection (K, m,
friction; ``excitation`` the documented lines), and ``cli``, ``alpes-dyn identify --data FILE`` as a user runs it
(``--effects auto``: the tendon compliance fitted, then the fit again without it where the data do not support it).
Each row's time and peak memory also as ratios to the 4 s fit of the same run (the first duration), and the worst
error of K and m against the truth. Optionally the dense KKT (``kkt="dense"``, the baseline, up to
``--dense-up-to`` seconds) and SuperLU (``kkt="superlu"``, the general sparse LU the banded one replaced).

    python benchmarks/fit_scaling.py [--durations 4,16,60] [--fit api|cli] [--records DIR] [--seed 21]
                                     [--dense-up-to 0] [--superlu-up-to 0] [--model finger3|hand] [--json]
    python benchmarks/fit_scaling.py --speed stiff [--duration 2] [--seed S] [--json]

``--speed CASE``: ``identify --effects auto`` on a friction case's MuJoCo record (``studies/realism_friction.py``),
the old path and the new one in the same process, each round's time, the observer checks', wall and CPU, and the
two fits compared (``benchmarks/_fit_speed.py``).

``--model hand``: the whole hand, every chain drawn +-20 % (``alpes-dyn experiment --model hand --perturb 0.2``: the
six motors excited at once) and fitted chain by chain as ``alpes-dyn identify --model hand`` fits it (``--fit cli``
only); a row's iterations are every chain's, its errors the worst chain's (the thumb's springs and masses of its two
flexion joints with the fingers'), converged and adequate only where every chain is.

Goal (issue 39): time and memory linear in the record; with the cache warm, ``alpes-dyn identify`` on 60 s under
20 s and 400 MiB, on 600 s under 3 min and 1 GiB, the parameters as accurate as the 4 s fit's (K 3 %, m 5 %). The
figures are one finger's (finger3, the default); the whole hand's five chains are fitted one after the other (its 4 s
fit alone takes half a minute): for it, the ratios to its 4 s fit, and memory within 1 GiB.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _hand_truth(seed: int):
    """The hand drawn as ``alpes-dyn experiment --model hand --perturb 0.2 --seed SEED`` draws it."""
    from alpes_dyn.estimation.experiments.experiment import perturbed_params
    from alpes_dyn.estimation.experiments.hand_experiment import hand_chains
    from alpes_dyn.model.params import load_params

    nominal = load_params(None)
    return perturbed_params(nominal, 0.2, seed, chains=hand_chains(nominal))


def make(duration: float, seed: int, path: str, model: str = "finger3") -> None:
    """The record of one duration, written to ``path`` (the recording CSV), as ``alpes-dyn experiment --model
    finger3 --perturb 0.2 --seed SEED --duration D`` writes it (the design adapted, ``--rig auto``; ``model`` hand:
    ``--model hand``)."""
    import warnings

    from alpes_dyn.estimation.experiments.adapt import adapted_experiment
    from alpes_dyn.estimation.experiments.excursion import SmallExcursionWarning
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, perturbed_params

    warnings.simplefilter("ignore", SmallExcursionWarning)
    if model == "hand":
        from alpes_dyn.estimation.experiments.hand_experiment import hand_experiment

        _, how = hand_experiment(_hand_truth(seed), ExperimentDesign(duration=duration), seed=seed, path=path)
        print(json.dumps({"design": "; ".join(f"{c}: {a.note}" for c, a in how.items() if a.note)}))
        return
    _, adaptation = adapted_experiment("finger3", perturbed_params(spread=0.2, seed=seed),
                                       ExperimentDesign(duration=duration), seed=seed, path=path)
    print(json.dumps({"design": adaptation.note}))


def _errors(names, values, truth: dict) -> dict:
    import numpy as np

    err = {k: 0.0 for k in ("K", "m", "F_s", "F_v")}
    for nm, v in zip(names, values):
        kind = nm.rsplit("_", 1)[0]
        if nm in truth and kind in err:
            err[kind] = max(err[kind], float(np.abs(100.0 * (v / truth[nm] - 1.0))))
    return err


def _hand_row(obj: dict, seed: int) -> dict:
    """A ``identify --model hand --json`` object as a row's fields: every chain's iterations summed, converged and
    adequate where all are, the worst residual, the worst K and m errors against the drawn truth (module docstring)."""
    truth = _hand_truth(seed)
    err = {"K": 0.0, "m": 0.0}
    for chain, c in obj["chains"].items():  # a loop over the five chains
        ch = truth.chain(chain)
        for name, v in c["parameters"].items():
            kind, _, j = name.rpartition("_j") if chain == "thumb" else name.rpartition("_")
            kind = kind.removesuffix("_thumb")
            if kind in err and j.isdigit():
                err[kind] = max(err[kind], abs(100.0 * (v["value"] / float(getattr(ch, kind)[int(j) - 1]) - 1.0)))
    cs = obj["chains"].values()
    return {"iterations": sum(c["iterations"] for c in cs), "converged": all(c["converged"] for c in cs),
            "residual_counts": max(c["residual_rms"] for c in cs), "trustworthy": bool(obj["trustworthy"]),
            "chains": len(obj["chains"]), "worst_error_pct": err}


def _cpu() -> float:
    """CPU seconds of this process so far (user and system): the fit's own work, less sensitive than the wall
    clock to the other processes of a shared machine."""
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def child(duration: float, seed: int, fit: str, kkt: tuple[str, ...], path: str, robot: str = "finger3") -> dict:
    """One duration, in this process: the record read from ``path``, the fit (``api`` or ``cli``), then the
    references ``kkt`` (``dense``, ``superlu``) on the same record; peak RSS after the fit. ``robot`` hand:
    ``alpes-dyn identify --model hand`` (:func:`_hand_row`)."""
    import warnings

    import numpy as np

    import alpes_dyn as ad
    from alpes_dyn.estimation.identification.adequacy import AdequacyWarning
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, perturbed_params
    from alpes_dyn.estimation.identification.identification import identify
    from alpes_dyn.estimation.experiments.recording import read_recording

    warnings.simplefilter("ignore", AdequacyWarning)
    f = perturbed_params(spread=0.2, seed=seed).finger
    truth = {f"{k}_{i + 1}": float(getattr(f, k)[i]) for k in ("K", "m", "F_s", "F_v") for i in range(3)}
    out: dict = {"duration_s": duration, "seed": seed, "fit": fit,
                 "rss_before_fit_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}
    design = ExperimentDesign(duration=duration)
    model = ad.Model.alpes("finger3", friction=True)
    t0, cpu0 = time.perf_counter(), _cpu()
    if robot == "hand":
        import contextlib
        import io

        from alpes_dyn.cli import main as cli_main

        with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()) as so:
            rc = cli_main(["identify", "--model", "hand", "--data", path, "-o", str(Path(tmp) / "fit.toml"), "--json"])
        out["seconds"], out["cpu_seconds"] = time.perf_counter() - t0, _cpu() - cpu0
        out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        out.update({"exit": rc, "model": "hand", **_hand_row(json.loads(so.getvalue().strip().splitlines()[-1]), seed)})
        return out
    if fit == "cli":
        import contextlib
        import io

        from alpes_dyn.cli import main as cli_main

        with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(io.StringIO()) as so:
            rc = cli_main(["identify", "--data", path, "-o", str(Path(tmp) / "fit.toml"), "--json"])
        obj = json.loads(so.getvalue().strip().splitlines()[-1])
        names = list(obj["parameters"])
        values = [obj["parameters"][n]["value"] for n in names]
        res_d = {"exit": rc, "iterations": obj["iterations"], "converged": bool(obj["converged"]),
                 "residual_counts": obj["residual_rms"], "trustworthy": obj["trustworthy"]}
    else:
        rec = read_recording(path, model)
        res = identify(model, rec, excitation=design.lines, progress=False)
        names, values = list(res.names), list(map(float, res.values))
        res_d = {"iterations": res.iterations, "converged": bool(res.converged), "residual_counts": res.residual_rms,
                 "compile_seconds": res.compile_seconds}
    out["seconds"], out["cpu_seconds"] = time.perf_counter() - t0, _cpu() - cpu0
    out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    out.update(res_d)
    out["worst_error_pct"] = _errors(names, values, truth)
    if kkt:
        rec = read_recording(path, model)
        base = identify(model, rec, excitation=design.lines, progress=False) if fit == "cli" else res
    for k in kkt:
        t0 = time.perf_counter()
        ref = identify(model, rec, excitation=design.lines, progress=False, kkt=k)
        out[k] = {"seconds": time.perf_counter() - t0, "iterations": ref.iterations,
                  "max_relative_difference": float(np.max(np.abs(ref.values / base.values - 1)))}
    return out


def _table(rows: list[dict], seed: int, fit: str, model: str = "finger3") -> None:
    print(f"{model} seed {seed}: identify ({'alpes-dyn identify, --effects auto' if fit == 'cli' else 'K, m, friction'})"
          " on records of each length; ratios to the first row (same run)")
    print(f"{'T s':>5} {'design':>24} | {'fit s':>6} {'x':>5} {'cpu s':>6} {'peak MiB':>8} {'x':>5} {'its':>4} {'resid':>5} "
          f"{'K%':>5} {'m%':>5} | refs (kkt: s, max rel diff)")
    t0, m0 = rows[0]["seconds"], rows[0]["peak_rss_mib"]
    for r in rows:
        refs = "  ".join(f"{k} {r[k]['seconds']:.1f} s {r[k]['max_relative_difference']:.0e}" for k in ("dense", "superlu")
                         if k in r)
        print(f"{r['duration_s']:5g} {r.get('design', '')[:24]:>24} | {r['seconds']:6.1f} {r['seconds'] / t0:5.1f} {r['cpu_seconds']:6.1f} "
              f"{r['peak_rss_mib']:8.0f} {r['peak_rss_mib'] / m0:5.2f} {r['iterations']:4d} {r['residual_counts']:5.2f} "
              f"{r['worst_error_pct']['K']:5.2f} {r['worst_error_pct']['m']:5.2f} | {refs}")


def _speed(args: argparse.Namespace) -> int:
    """``--speed CASE``: benchmarks/_fit_speed.py's run, its table or its JSON."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import _fit_speed
    from alpes_dyn.studies.realism_friction import FRICTION_CASE_NAMES

    if args.speed not in FRICTION_CASE_NAMES:
        print(f"--speed: expected one of {', '.join(FRICTION_CASE_NAMES)}, got {args.speed!r}", file=sys.stderr)
        return 2
    r = _fit_speed.speed(args.speed, args.seed, args.duration)
    if args.json:
        print(json.dumps({"speed": r}))
    else:
        _fit_speed.table(r)
    return 0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", default="4,16,60")
    ap.add_argument("--fit", choices=("api", "cli"), default="api")
    ap.add_argument("--records", help="a directory to keep the simulated records in (reused where present)")
    ap.add_argument("--dense-up-to", type=float, default=0.0, help="run the dense KKT too up to this length, s")
    ap.add_argument("--superlu-up-to", type=float, default=0.0, help="run SuperLU too up to this length, s")
    ap.add_argument("--seed", type=int, default=21)
    ap.add_argument("--model", choices=("finger3", "hand"), default="finger3")
    ap.add_argument("--speed", metavar="CASE", help="the old and the new path of identify --effects auto on a friction "
                    "case's MuJoCo record (benchmarks/_fit_speed.py), instead of the durations")
    ap.add_argument("--duration", type=float, default=2.0, help="--speed: the record's length, s")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--child", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--kkt", default="", help=argparse.SUPPRESS)
    ap.add_argument("--make", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--data", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.model == "hand" and (args.fit != "cli" or args.dense_up_to or args.superlu_up_to):
        ap.error("--model hand: the command line's fit alone (--fit cli), no KKT references")
    if args.speed is not None:
        return _speed(args)
    if args.make is not None:
        make(args.make, args.seed, args.data, args.model)
        return 0
    if args.child is not None:
        print(json.dumps(child(args.child, args.seed, args.fit, tuple(k for k in args.kkt.split(",") if k),
                               args.data, args.model)))
        return 0
    try:
        durations = [float(d) for d in args.durations.split(",")]
    except ValueError:
        ap.error(f"--durations: expected comma-separated seconds, got {args.durations!r}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.records) if args.records else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        for d in durations:
            path = folder / f"{args.model}_seed{args.seed}_{d:g}s.csv"
            base = [sys.executable, __file__, "--seed", str(args.seed), "--data", str(path), "--model", args.model,
                    "--fit", args.fit]  # (--model hand takes --fit cli alone, its --make too)
            design = "(record reused)"
            if not path.exists():
                done = subprocess.run(base + ["--make", str(d)], capture_output=True, text=True, check=False)
                if done.returncode != 0:
                    print(f"{d:g} s: the experiment failed: {done.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
                    return 1
                design = json.loads(done.stdout.strip().splitlines()[-1])["design"] or "as designed (level)"
            kkt = [k for k, up in (("dense", args.dense_up_to), ("superlu", args.superlu_up_to)) if d <= up]
            done = subprocess.run(base + ["--child", str(d), "--kkt", ",".join(kkt)],
                                  capture_output=True, text=True, check=False)
            if done.returncode != 0:
                print(f"{d:g} s: the fit failed: {done.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
                return 1
            row = json.loads(done.stdout.strip().splitlines()[-1])
            row["design"] = design
            rows.append(row)
    t0, m0 = rows[0]["seconds"], rows[0]["peak_rss_mib"]
    for r in rows:
        r["time_ratio"], r["memory_ratio"] = r["seconds"] / t0, r["peak_rss_mib"] / m0
        r["cpu_ratio"] = r["cpu_seconds"] / rows[0]["cpu_seconds"]
    if args.json:
        print(json.dumps({"model": args.model, "fit": args.fit, "rows": rows}))
        return 0
    _table(rows, args.seed, args.fit, args.model)
    return 0


if __name__ == "__main__":
    sys.exit(main())
