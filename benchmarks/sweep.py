"""Sweep benchmark (issue 20): the robustness study over draws, serial vs a local Dask cluster.

The same draws (finger3 drawn +-20 % per link, its identification experiment, the fit, the EKF before and
after) run one after another in this process (the baseline) and on a 2-process local Dask cluster; the
per-draw rows must be equal (with the fit to 1e-8 relative, a parameter error to 1e-6 %-points: its last digits depend on
the process's BLAS threads; bit for bit without it; the wall times apart), and the speed-up is the ratio of the wall times (the cluster's start-up
included; printed apart: the cluster's start-up and close). Goal: >= 1.8x on 2 cores.

The serial loop's fit already runs its compiled sensitivities on both cores (two threads), which the cluster's
workers do not (one thread each, as Dask sets OMP_NUM_THREADS): the speed-up is also printed against the serial
loop on one thread (``OMP_NUM_THREADS=1`` for the compiled loops; numpy's BLAS keeps the threads it started with),
the baseline the goal's 2x refers to where every draw is single-threaded.

    python benchmarks/sweep.py [--draws 4] [--seed 1] [--duration 4] [--no-fit] [--workers 2] [--json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

from alpes_dyn.studies.sweep import local_client, robustness_draw, sweep


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=4)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration", type=float, default=4.0)
    ap.add_argument("--no-fit", action="store_true")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    opts = {"duration": args.duration, "fit": not args.no_fit}
    robustness_draw(args.seed, **{**opts, "duration": 0.5})  # warm the compile cache outside the timings
    serial = sweep(robustness_draw, args.draws, seed=args.seed, options=opts, serial=True)
    omp = os.environ.get("OMP_NUM_THREADS")
    os.environ["OMP_NUM_THREADS"] = "1"  # read at each compiled call (simulation.codegen._default_threads)
    try:
        serial1 = sweep(robustness_draw, args.draws, seed=args.seed, options=opts, serial=True)
    finally:
        if omp is None:
            del os.environ["OMP_NUM_THREADS"]
        else:
            os.environ["OMP_NUM_THREADS"] = omp
    t0 = time.perf_counter()  # the sweep's own local cluster, its start-up and close timed apart
    client = local_client(args.workers)
    t1 = time.perf_counter()
    dask = sweep(robustness_draw, args.draws, seed=args.seed, options=opts, client=client)
    t2 = time.perf_counter()
    client.close()
    client.cluster.close()
    t3 = time.perf_counter()
    dask.seconds = t3 - t0  # the cluster's start-up and close included, as sweep(workers=) counts them
    cluster_s = {"start": t1 - t0, "draws": t2 - t1, "close": t3 - t2}
    def close(a, b) -> bool:  # a fit's numbers differ in their last digits between processes (BLAS threads): a
        # parameter error in % to 1e-6 %-points (1e-8 of the parameter), every other number to 1e-8 relative
        return math.isclose(a, b, rel_tol=1e-8, abs_tol=1e-6) if isinstance(a, float) else a == b

    differ = [f"seed {ra['seed']} {k}: {ra.get(k)!r} vs {rb.get(k)!r}"
              for other in (dask.rows, serial1.rows) for ra, rb in zip(serial.rows, other)
              for k in sorted(set(ra) | set(rb)) if not k.endswith("_seconds") and not close(ra.get(k), rb.get(k))]
    same = not differ
    out = {"draws": args.draws, "seed": args.seed, "duration_s": args.duration, "fit": opts["fit"],
           "serial_s": serial.seconds, "dask_s": dask.seconds, "workers": dask.workers,
           "speedup": serial.seconds / dask.seconds, "serial_1thread_s": serial1.seconds,
           "speedup_vs_1thread": serial1.seconds / dask.seconds, "cluster_seconds": cluster_s,
           "speedup_bound": args.workers * serial.seconds / serial1.seconds, "same_rows": same, "differ": differ, "load_avg": os.getloadavg()[0],
           "rows": serial.to_dict()["rows"]}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{args.draws} draws (seeds {args.seed}..), {args.duration:g} s experiments, fit {opts['fit']}; "
          f"load average {out['load_avg']:.1f}")
    print(f"  serial {serial.seconds:.1f} s   dask ({dask.workers} workers) {dask.seconds:.1f} s   "
          f"speed-up {out['speedup']:.2f}x   same rows: {same}")
    print(f"  serial on one thread {serial1.seconds:.1f} s   speed-up against it {out['speedup_vs_1thread']:.2f}x")
    print(f"  the cluster: start-up {cluster_s['start']:.1f} s, draws {cluster_s['draws']:.1f} s, close "
          f"{cluster_s['close']:.1f} s; the bound on {args.workers} cores with no start-up nor imbalance "
          f"{out['speedup_bound']:.2f}x ({args.workers} x serial / serial on one thread)")
    for d in differ:
        print(f"  differs: {d}")
    print(serial.table())
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
