"""The whole hand grasping the cylinder on MuJoCo: a force loop and an EKF per motor, measured in one run.

:func:`alpes_dyn.control.run_hand_control` with each of the three controllers (``sensor``, ``sensorless``,
``pi``) on the same noise draws: the hand palm down over the fixed, frictionless cylinder of the MJCF's
``"cylinder"`` scene, the four fingers and the thumb each tracking its reference of
:data:`alpes_dyn.control.HAND_LEVELS` (a step up at 2.5 s), the thumb's ab/adduction held at 35 degrees by a
PD on its encoder. Per chain: asked and held force, steady-state error, overshoot, 10-90 % rise, force RMSE,
the EKF's worst joint RMSE during contact. Speed: simulated time over wall time of each loop, and the wall
time of the model-based loops over the PI's (the baseline, run in the same process).

    python benchmarks/hand_control.py [--json] [--seed 0]
"""

from __future__ import annotations

import argparse
import json

from alpes_dyn.control import CONTROLLERS, run_hand_control
from _table import cell  # noqa: E402 (this folder is on the path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--seed", type=int, default=0, help="noise seed of the loops")
    args = ap.parse_args()
    run_hand_control("pi", seed=args.seed)  # warm-up: builds and caches the compiled filters once
    out: dict = {"seed": args.seed, "runs": {}}
    for c in CONTROLLERS:
        r = run_hand_control(c, seed=args.seed)
        d = r.to_dict()
        d["wall_s"] = r.wall_s
        out["runs"][c] = d
    pi_wall = out["runs"]["pi"]["wall_s"]
    for d in out["runs"].values():
        d["wall_vs_pi"] = d["wall_s"] / pi_wall
    if args.json:
        print(json.dumps(out))
        return

    print(f"the hand grasping the cylinder on MuJoCo; seed {args.seed}")
    print(f"{'controller / chain':22s} {'asked':>6s} {'held':>7s} {'SSE':>7s} {'overshoot':>9s} {'rise [s]':>8s} "
          f"{'RMSE [N]':>9s} {'q RMSE [deg]':>12s}")
    for c, d in out["runs"].items():
        for row in d["chains"]:
            print(f"{c + ' / ' + row['chain']:22s} {row['F_ref']:6.2f} {row['F_held']:7.3f} "
                  f"{cell(row['steady_state_error'], '7.2%')} {cell(row['overshoot'], '9.1%')} {cell(row['rise_time_s'], '8.3f')} "
                  f"{row['force_rmse']:9.4f} {cell(row['q_rmse_deg'], '12.2f')}")
    for c, d in out["runs"].items():
        print(f"{c:11s} {d['realtime_ratio']:.2f} x real time, wall {d['wall_s']:.2f} s = {d['wall_vs_pi']:.1f} x the PI's")


if __name__ == "__main__":
    main()
