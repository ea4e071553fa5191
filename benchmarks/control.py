"""Fingertip force control on MuJoCo: the goal of issue 9 measured, in one run.

finger3 presses the block of the MJCF ``"block"`` scene (:mod:`alpes_dyn.control`, palm down, a
frictionless block, joint friction in the plant), with the encoder quantisation and the current noise
of the estimation scenario and a noisy, quantised FlexiForce, the motor limited to
``transmission.tau_max`` = 0.05 N m (assumed: the full scale of the current sensor of the estimation
scenario; the parameter file says so). References: steps 0.2 -> 1.0 -> 0.5 N (1.0 N needs 0.040 N m,
80 % of the limit) and a 1 Hz sine between 0.3 and 0.8 N, for the three controllers:

* ``sensor`` (feedforward from the static balance at the EKF's q_hat + PI on the FlexiForce),
* ``sensorless`` (F_z estimated from the motor torque, q_hat and the model),
* ``pi`` (the baseline: a PI on the FlexiForce alone);

then the same with the plant's masses, inertias and springs 10 % off the controller's, link by link
(+10 %, -10 %, +10 % from the proximal phalanx), the controller keeping the parameter file's values.

Goals (sensor): steady-state error < 2 %, overshoot < 10 %, 10-90 % rise < 100 ms, force RMSE lower
than the PI's; sensorless: steady-state error < 10 %; the loop faster than real time (the ratio of
simulated to wall time is printed; the baseline of that ratio is the real time itself).

    python benchmarks/control.py [--json] [--seed 0]
"""

from __future__ import annotations

import argparse
import dataclasses
import json

import numpy as np

import alpes_dyn as ad
from alpes_dyn.control import CONTROLLERS, run_control


def mismatched(p: ad.HandParams, scales=(1.1, 0.9, 1.1)) -> ad.HandParams:
    """The finger's m, I and K times ``scales`` link by link (the plant 10 % off the controller's model)."""
    s = np.asarray(scales)
    f = dataclasses.replace(p.finger, m=p.finger.m * s, I=p.finger.I * s, K=p.finger.K * s)
    return dataclasses.replace(p, finger=f)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    p = ad.load_params()
    cases = {"step": dict(reference="step", duration=3.0), "sine": dict(reference="sine", duration=4.0),
             "step, plant 10 % off": dict(reference="step", duration=3.0, plant_params=mismatched(p))}
    out: dict = {"tau_max_Nm": p.tau_max, "seed": args.seed, "runs": {}}
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
    if args.json:
        print(json.dumps(out))
        return

    def f(x, fmt):
        width = int(fmt.split(".")[0])
        return "n/a".rjust(width) if x is None else format(x, fmt)

    print(f"finger3 pressing a block on MuJoCo; motor limit {p.tau_max:g} N m; seed {args.seed}")
    print(f"{'case / controller':34s} {'RMSE [N]':>9s} {'SSE':>7s} {'overshoot':>9s} {'rise [s]':>8s} "
          f"{'q RMSE [deg]':>18s} {'x real time':>11s}")
    for name, d in runs.items():
        q = "n/a" if d["q_rmse_deg"] is None else " ".join(f"{e:.2f}" for e in d["q_rmse_deg"])
        print(f"{name:34s} {d['force_rmse']:9.4f} {f(d['steady_state_error'], '7.2%')} {f(d['overshoot'], '9.1%')} "
              f"{f(d['rise_time_s'], '8.3f')} {q:>18s} {d['realtime_ratio']:11.1f}")
    print("goals: " + ", ".join(f"{k} {'yes' if v else 'NO'}" for k, v in out["goals"].items()))


if __name__ == "__main__":
    main()
