"""The compile cache keyed on a model's structure (issue 20): a second EKF of other values compiles nothing.

In a private, empty compile cache, the compiled EKF step (``ExtendedKalmanFilter(compiled=True)``, the
scenario's noise settings) is built for a finger and then for the same finger of other masses, springs and friction
(drawn +-20 % per link, as the sweep's draws and an identified file differ from the nominal), two ways in the same
process:

    lifted   the model's numbers an input of the step (``filter_step_p``: the code today), one library per structure
    baked    the baseline: the same step with the numbers as literals in the C (``filter_step``: the code before),
             one library per model

and prints, per way, each build's seconds (the compile included where there was one), whether it compiled, the
libraries in the cache afterwards, and the step's microseconds per sample called as ``OnlineFilter.step`` calls it
(one ctypes call of the compiled step and the copies, rounds of both ways in turn, the median) with the ratio
lifted / baked (goal: within a few per cent: the parameters are one more input the step reads). The two ways'
estimates on one record are compared (their last-bit differences, amplified by the filter's transient).

    python benchmarks/param_cache.py [--model finger3] [--seed 5] [--steps 20000] [--rounds 7] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _step_us(loop, nz: int, nw: int, ny: int, steps: int) -> float:
    """Microseconds per call of the compiled step on one sample, as OnlineFilter.step makes it."""
    X = np.zeros((1, 2, nz + nz * nz))
    X[0, 0, :nz] = 0.1
    X[0, 0, nz:] = (1e-3 * np.eye(nz)).ravel()
    Wb = np.zeros((1, 1, nw + ny))
    wp, xp = Wb.ctypes.data_as(loop._dp), X.ctypes.data_as(loop._dp)
    s, nxt, w, y = X[0, 0], X[0, 1], Wb[0, 0, :nw], Wb[0, 0, nw:]
    fn, pp = loop._fn, loop._pp
    t0 = time.perf_counter()
    for k in range(steps):
        w[:] = 0.01
        y[:] = 0.1
        fn(wp, xp, pp, 1, 1, 0, 1, 1)
        s[:] = nxt
    return 1e6 * (time.perf_counter() - t0) / steps


def main(argv: list[str] | None = None) -> int:
    cache = Path(tempfile.mkdtemp(prefix="alpes_param_cache_"))
    try:
        return _main(argv, cache)
    finally:
        shutil.rmtree(cache, ignore_errors=True)  # the private cache and its libraries


def _main(argv: list[str] | None, cache: Path) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="finger3")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    os.environ["ALPES_DYN_CACHE"] = str(cache)  # read at each build (simulation.codegen.cache_dir)
    import alpes_dyn as ad
    from alpes_dyn.estimation.experiments.experiment import perturbed_params
    from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter
    from alpes_dyn.estimation.observers.scenario import run_estimation
    from alpes_dyn.simulation.codegen import CompiledStepLoop
    from alpes_dyn.symbolic.statespace import StateSpace

    load0 = os.getloadavg()[0]
    res = run_estimation("ekf", model=a.model, duration=1.0, seed=0)
    n, nm = ad.Model.alpes(a.model).n, ad.Model.alpes(a.model).transmission.n_motors
    kw = dict(process_noise=[1e-18] * n + [4e-8] * n, measurement_noise=[1.96e-7] * nm, input_noise=[2.5e-7] * nm)
    models = {"nominal": ad.Model.alpes(a.model),
              "drawn": ad.Model.alpes(a.model, params=perturbed_params(spread=0.2, seed=a.seed))}
    out: dict = {"model": a.model, "seed": a.seed, "cache": str(cache), "ways": {}}
    loops, filters = {}, {}
    for way in ("lifted", "baked"):
        rows = []
        for name, m in models.items():
            t0 = time.perf_counter()
            f = ExtendedKalmanFilter(StateSpace(m, input="motor", output="encoder"), 1e-3, **kw)
            loop = (f._compiled_loop() if way == "lifted" else
                    CompiledStepLoop(f.filter_step, f"baked_ekf_{a.model}", threads=1, vectorize=False))
            rows.append({"model": name, "build_s": time.perf_counter() - t0, "compiled": bool(loop.compiled),
                         "compile_s": loop.compile_seconds, "library": Path(loop.library).name})
            loops[way, name], filters[way, name] = loop, f
        libs = sorted(p.name for p in cache.glob("*.so") if p.name.startswith(("ekf_", "baked_ekf_")))
        out["ways"][way] = {"builds": rows, "libraries": [x for x in libs if x.startswith("ekf_" if way == "lifted"
                                                                                           else "baked_")]}
    f = filters["lifted", "nominal"]
    times: dict[str, list[float]] = {"lifted": [], "baked": []}
    for _ in range(a.rounds):
        for way in times:
            times[way].append(_step_us(loops[way, "nominal"], f.nz, f.nw, f.ny, a.steps))
    us = {way: float(np.median(v)) for way, v in times.items()}
    z0, P0 = res.x_true[0], [1e-4] * n + [1e-2] * n
    W, Y = res.u_meas, res.y
    lifted = loops["lifted", "nominal"]
    zu, Pu = f._update(f._z(z0), f._P(P0), Y[0])
    s0 = np.concatenate([np.array(zu).ravel(), np.array(Pu).ravel(order="F")])[None]
    WY = np.hstack([W, Y[1:]])[None]
    diff = float(np.abs(lifted.run(s0, WY)[0] - loops["baked", "nominal"].run(s0, WY)[0]).max())
    out.update(step_us=us, step_us_rounds=times, lifted_vs_baked=us["lifted"] / us["baked"], max_diff_run=diff,
               n_parameters=int(f.model.values.size), load_avg=[load0, os.getloadavg()[0]])
    if a.json:
        print(json.dumps(out))
        return 0
    print(f"{a.model}, nominal and drawn +-20 % (seed {a.seed}); a private empty cache (removed after); load average "
          f"{load0:.1f} -> {os.getloadavg()[0]:.1f}; {f.model.values.size} numbers in p")
    print(f"{'way':7s} {'model':8s} {'build s':>8s} {'compiled':>8s} {'gcc s':>6s}  library")
    for way, w in out["ways"].items():
        for r in w["builds"]:
            print(f"{way:7s} {r['model']:8s} {r['build_s']:8.2f} {str(r['compiled']):>8s} {r['compile_s']:6.1f}  "
                  f"{r['library']}")
        print(f"{'':7s} libraries in the cache: {len(w['libraries'])}")
    print(f"step (as OnlineFilter.step calls it, median of {a.rounds} rounds of {a.steps}): lifted "
          f"{us['lifted']:.2f} us, baked {us['baked']:.2f} us, ratio {out['lifted_vs_baked']:.3f}; "
          f"|lifted - baked| on a 1 s run {diff:.1e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
