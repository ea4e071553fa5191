"""Fit cost against the record's length (issue 20, item 2): time and peak memory of ``identify`` on 2-60 s records.

finger3 drawn +-20 % per link (seed 21 by default: not one the other benchmarks tune on), the documented
identification experiment simulated for each duration (our simulator; sensor noise on) and written to a CSV by
one process, the default fit (K, m, friction; ``excitation`` the documented lines) of that file in a fresh one, as
``alpes-dyn identify --data`` does, so that its peak resident memory is the fit's own (the 60 s experiment's
simulation alone peaks at about 500 MiB). The sparse KKT (the default, :mod:`alpes_dyn.estimation.identification.kkt`)
against the dense one (``kkt="dense"``, the baseline, run in the same process where it fits in memory: up to 16 s), with
the ratio of their times and their parameters' largest relative difference.

    python benchmarks/fit_scaling.py [--durations 2,4,8,16,60] [--dense-up-to 16] [--seed 21] [--json]

Goal: time and memory linear in the record; a 60 s record under 60 s and 500 MB.
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


def make(duration: float, seed: int, path: str) -> None:
    """The record of one duration, written to ``path`` (the recording CSV)."""
    import warnings

    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from alpes_dyn.estimation.experiments.recording import write_recording
    from alpes_dyn.model.stops import JointRangeWarning

    warnings.simplefilter("ignore", JointRangeWarning)
    write_recording(experiment("finger3", perturbed_params(spread=0.2, seed=seed), ExperimentDesign(duration=duration),
                               seed=seed), path)


def child(duration: float, seed: int, dense: bool, path: str) -> dict:
    """One duration, in this process: the record read from ``path``, the sparse fit, optionally the dense one; peak
    RSS at the end."""
    import warnings

    import numpy as np

    import alpes_dyn as ad
    from alpes_dyn.estimation.identification.adequacy import AdequacyWarning
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, perturbed_params
    from alpes_dyn.estimation.identification.identification import identify
    from alpes_dyn.estimation.experiments.recording import read_recording

    warnings.simplefilter("ignore", AdequacyWarning)
    true = perturbed_params(spread=0.2, seed=seed)
    design = ExperimentDesign(duration=duration)
    model = ad.Model.alpes("finger3", friction=True)
    rec = read_recording(path, model)
    truth = np.r_[true.finger.K, true.finger.m, true.finger.F_s, true.finger.F_v]
    out: dict = {"duration_s": duration, "seed": seed}
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    t0 = time.perf_counter()
    res = identify(model, rec, excitation=design.lines, progress=False)
    out["sparse"] = {"seconds": time.perf_counter() - t0, "compile_seconds": res.compile_seconds,
                     "iterations": res.iterations, "converged": bool(res.converged),
                     "residual_counts": res.residual_rms,
                     "worst_error_pct": {k: float(np.max(np.abs(100 * (res.values[i:i + 3] / truth[i:i + 3] - 1))))
                                         for k, i in (("K", 0), ("m", 3), ("F_s", 6), ("F_v", 9))}}
    out["peak_rss_mib_sparse"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    out["rss_before_fit_mib"] = rss0
    if dense:
        t0 = time.perf_counter()
        ref = identify(model, rec, excitation=design.lines, progress=False, kkt="dense")
        out["dense"] = {"seconds": time.perf_counter() - t0, "iterations": ref.iterations,
                        "residual_counts": ref.residual_rms}
        out["dense_over_sparse_time"] = out["dense"]["seconds"] / out["sparse"]["seconds"]
        out["max_relative_difference"] = float(np.max(np.abs(ref.values / res.values - 1)))
        out["peak_rss_mib_with_dense"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--durations", default="2,4,8,16,60")
    ap.add_argument("--dense-up-to", type=float, default=16.0, help="run the dense baseline up to this length, s")
    ap.add_argument("--seed", type=int, default=21)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--child", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--dense", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--make", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--data", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.make is not None:
        make(args.make, args.seed, args.data)
        return 0
    if args.child is not None:
        print(json.dumps(child(args.child, args.seed, args.dense, args.data)))
        return 0
    try:
        durations = [float(d) for d in args.durations.split(",")]
    except ValueError:
        ap.error(f"--durations: expected comma-separated seconds, got {args.durations!r}")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for d in durations:
            path = str(Path(tmp) / f"rec_{d:g}.csv")
            base = [sys.executable, __file__, "--seed", str(args.seed), "--data", path]
            cmd = base + ["--child", str(d)] + (["--dense"] if d <= args.dense_up_to else [])
            for step in (base + ["--make", str(d)], cmd):
                done = subprocess.run(step, capture_output=True, text=True, check=False)
                if done.returncode != 0:
                    print(f"{d:g} s: the child failed: {done.stderr.strip().splitlines()[-1:]}", file=sys.stderr)
                    return 1
            rows.append(json.loads(done.stdout.strip().splitlines()[-1]))
    if args.json:
        print(json.dumps({"model": "finger3", "rows": rows}))
        return 0
    print(f"finger3 seed {args.seed}: identify (K, m, friction) on records of each length; sparse KKT (default) "
          "against dense (baseline, same process)")
    print(f"{'T s':>5} | {'sparse s':>8} {'its':>4} {'resid':>5} {'K%':>5} {'m%':>5} {'peak MiB':>8} | "
          f"{'dense s':>7} {'dense/sparse':>12} {'max rel diff':>12}")
    for r in rows:
        s = r["sparse"]
        dn = r.get("dense")
        tail = (f"{dn['seconds']:7.1f} {r['dense_over_sparse_time']:12.2f} {r['max_relative_difference']:12.1e}"
                if dn else f"{'-':>7} {'-':>12} {'-':>12}")
        print(f"{r['duration_s']:5g} | {s['seconds']:8.1f} {s['iterations']:4d} {s['residual_counts']:5.2f} "
              f"{s['worst_error_pct']['K']:5.2f} {s['worst_error_pct']['m']:5.2f} {r['peak_rss_mib_sparse']:8.0f} | {tail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
