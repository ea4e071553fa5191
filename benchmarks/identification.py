"""Identification benchmark (issue 8): experiment -> identify -> EKF on the identified parameters.

For each seed: a finger3 whose K_i, m_i (I_i with them), F_s_i, F_v_i are each drawn within +-20 % of the
shipped values (friction on), the documented identification experiment simulated on it, the fit, and the
estimation scenario (friction on) with the EKF on the nominal file (before) and on the identified file
(after). Prints, per seed, the parameter errors (%), the fit's standard errors (%, the Gauss-Newton
covariance: the local Cramér-Rao bound of the fit), the EKF RMSE per joint (deg) before and after, the
fit time and the one-off compile time. Goal: < 0.5 deg on every joint, K within 3 %, m within 5 %, fit
< 10 s.

    python benchmarks/identification.py [--seeds 1,2,3] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.identification.identification import identify
from alpes_dyn.model.params import load_params, write_params
from alpes_dyn.estimation.observers.scenario import run_estimation


def one(seed: int, tmp: Path) -> dict:
    true = perturbed_params(spread=0.2, seed=seed)
    true_path = write_params(true, tmp / f"true{seed}.toml")
    rec = experiment("finger3", true, seed=seed)
    model = ad.Model.alpes("finger3", friction=True)
    t0 = time.perf_counter()
    res = identify(model, rec, excitation=ExperimentDesign().lines, progress=False)  # torque noise: estimated
    fit_s = time.perf_counter() - t0
    ident_path = res.write(tmp / f"ident{seed}.toml")
    truth = np.r_[true.finger.K, true.finger.m, true.finger.F_s, true.finger.F_v]
    before = run_estimation("ekf", friction=True, params=str(true_path), observer_params=str(load_params().path))
    after = run_estimation("ekf", friction=True, params=str(true_path), observer_params=str(ident_path))
    return {
        "seed": seed,
        "parameters": {n: {"error_pct": 100 * (v / t - 1), "std_pct": 100 * s / t}
                       for n, v, s, t in zip(res.names, res.values, res.std, truth)},
        "rmse_deg_before": np.degrees(before.rmse).tolist(), "rmse_deg_after": np.degrees(after.rmse).tolist(),
        "fit_seconds": fit_s, "compile_seconds": res.compile_seconds, "iterations": res.iterations,
        "converged": res.converged, "residual_counts": res.residual_rms,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    with tempfile.TemporaryDirectory() as d:
        rows = [one(s, Path(d)) for s in seeds]
    if args.json:
        print(json.dumps({"finger3": rows}))
        return 0
    for r in rows:
        p = r["parameters"]
        print(f"seed {r['seed']}: fit {r['fit_seconds']:.1f} s (+{r['compile_seconds']:.1f} s compiling), "
              f"{r['iterations']} iterations, {'converged' if r['converged'] else 'NOT converged'}, "
              f"residual {r['residual_counts']:.2f} counts")
        print("  " + " ".join(f"{n} {v['error_pct']:+.2f}% (+-{v['std_pct']:.2f})" for n, v in p.items()))
        print(f"  EKF RMSE [deg] before {np.round(r['rmse_deg_before'], 3).tolist()}  "
              f"after {np.round(r['rmse_deg_after'], 3).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
