"""Fingertip force control on MuJoCo: the goal of issue 9 measured, in one run.

finger3 presses the block of the MJCF ``"block"`` scene (:mod:`alpes_dyn.control`, palm down, a
frictionless block, joint friction in the plant), with the encoder quantisation and the current noise
of the estimation scenario and a noisy, quantised FlexiForce, the motor limited to
``transmission.tau_max`` = 0.05 N m (assumed: the full scale of the current sensor of the estimation
scenario; the parameter file says so). References: steps 0.2 -> 1.0 -> 0.5 N (1.0 N needs 0.040 N m,
80 % of the limit) and a 1 Hz sine between 0.3 and 0.8 N, for the three controllers:

* ``sensor`` (feedforward from the static balance at the EKF's q_hat + PI on the FlexiForce, 2-DOF),
* ``sensorless`` (F_z estimated from the motor torque, q_hat and the model),
* ``pi`` (the baseline: a PI on the FlexiForce alone, tuned by the same rule as the sensor loop);

then the step with the plant's parameters 10 % off the controller's, link by link: ``--plant-draws``
plants drawn by :func:`alpes_dyn.estimation.experiments.experiment.perturbed_params` (springs, masses with inertias, and
joint friction each times a factor uniform in [0.9, 1.1], draws 0, 1, ...), the controller keeping its own
parameter file. For each controller the loss against the matched plant is printed (mean and worst over
the draws of the change in steady-state error, RMSE and overshoot).

``--params FILE`` gives the controller's parameter file (default: the shipped one), e.g. the file written
by ``alpes-dyn identify``, to measure how much identified parameters win back on a given plant
(``--plant-params FILE``, which then replaces the draws).

Goals (sensor, matched plant): steady-state error < 2 %, overshoot < 10 %, 10-90 % rise < 100 ms, force
RMSE lower than the PI's; sensorless: steady-state error < 10 %; the loop faster than real time (the
ratio of simulated to wall time is printed; the baseline of that ratio is the real time itself).

    python benchmarks/control.py [--json] [--seed 0] [--plant-draws 5] [--params FILE] [--plant-params FILE]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import alpes_dyn as ad
from alpes_dyn.control import CONTROLLERS, run_control
from alpes_dyn.estimation.experiments.experiment import perturbed_params
from _table import cell  # noqa: E402 (this folder is on the path)

METRICS = ("steady_state_error", "force_rmse", "overshoot")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--seed", type=int, default=0, help="noise seed of the loops")
    ap.add_argument("--plant-draws", type=int, default=5, help="plants drawn 10 %% off (0: none)")
    ap.add_argument("--params", default=None, metavar="FILE", help="the controller's parameter file")
    ap.add_argument("--plant-params", default=None, metavar="FILE",
                    help="one off-nominal plant's parameter file (instead of the draws)")
    args = ap.parse_args()
    p = ad.load_params(args.params)
    nominal = ad.load_params()
    cases = {"step": dict(reference="step", duration=3.0), "sine": dict(reference="sine", duration=4.0)}
    plants: dict[str, ad.HandParams] = {}
    if args.plant_params is not None:
        plants["plant file"] = ad.load_params(args.plant_params)
    else:
        for k in range(args.plant_draws):
            plants[f"plant 10 % off #{k}"] = perturbed_params(nominal, spread=0.1, seed=k)
    for name, pp in plants.items():
        cases[f"step, {name}"] = dict(reference="step", duration=3.0, plant_params=pp)
    out: dict = {"tau_max_Nm": p.tau_max, "seed": args.seed, "params": args.params or "shipped",
                 "plant_params": args.plant_params, "runs": {}}
    for case, kw in cases.items():
        for c in CONTROLLERS:
            r = run_control(c, seed=args.seed, params=p, **kw)
            d = r.to_dict()
            d["wall_s"] = r.wall_s
            out["runs"][f"{case} / {c}"] = d
    runs = out["runs"]
    s, pi, sl = runs["step / sensor"], runs["step / pi"], runs["step / sensorless"]
    out["goals"] = {
        "sensor_steady_state_error_lt_2pc": s["steady_state_error"] < 0.02,
        "sensor_overshoot_lt_10pc": s["overshoot"] < 0.10,
        "sensor_rise_lt_100ms": s["rise_time_s"] is not None and s["rise_time_s"] < 0.1,
        "sensor_rmse_lt_pi_step": s["force_rmse"] < pi["force_rmse"],
        "sensor_rmse_lt_pi_sine": runs["sine / sensor"]["force_rmse"] < runs["sine / pi"]["force_rmse"],
        "sensorless_steady_state_error_lt_10pc": sl["steady_state_error"] < 0.10,
        "faster_than_real_time": min(d["realtime_ratio"] for d in runs.values()) > 1.0,
    }
    if plants:  # what the plant's mismatch costs each controller: off-plant minus matched plant
        loss: dict = {}
        for c in CONTROLLERS:
            base = runs[f"step / {c}"]
            deltas = {m: [runs[f"step, {name} / {c}"][m] - base[m] for name in plants] for m in METRICS}
            loss[c] = {m: {"mean": float(np.mean(v)), "worst": float(np.max(v))} for m, v in deltas.items()}
        out["plant_mismatch_loss"] = loss
    if args.json:
        print(json.dumps(out))
        return

    print(f"finger3 pressing a block on MuJoCo; motor limit {p.tau_max:g} N m; seed {args.seed}; "
          f"controller parameters: {out['params']}")
    print(f"{'case / controller':38s} {'RMSE [N]':>9s} {'SSE':>7s} {'overshoot':>9s} {'rise [s]':>8s} "
          f"{'q RMSE [deg]':>18s} {'x real time':>11s}")
    for name, d in runs.items():
        q = "n/a" if d["q_rmse_deg"] is None else " ".join(f"{e:.2f}" for e in d["q_rmse_deg"])
        print(f"{name:38s} {d['force_rmse']:9.4f} {cell(d['steady_state_error'], '7.2%')} {cell(d['overshoot'], '9.1%')} "
              f"{cell(d['rise_time_s'], '8.3f')} {q:>18s} {d['realtime_ratio']:11.1f}")
    if plants:
        print(f"plant mismatch ({len(plants)} plant(s)), change against the matched plant, mean / worst:")
        for c, d in out["plant_mismatch_loss"].items():
            print(f"  {c:11s} SSE {d['steady_state_error']['mean']:+.2%} / {d['steady_state_error']['worst']:+.2%}"
                  f"   RMSE {d['force_rmse']['mean']:+.4f} / {d['force_rmse']['worst']:+.4f} N"
                  f"   overshoot {d['overshoot']['mean']:+.1%} / {d['overshoot']['worst']:+.1%}")
    print("goals: " + ", ".join(f"{k} {'yes' if v else 'NO'}" for k, v in out["goals"].items()))


if __name__ == "__main__":
    main()
