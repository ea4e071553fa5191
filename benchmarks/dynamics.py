"""Wrapper overhead of alpes_dyn's dynamics against the raw Pinocchio calls, in the same process.

For finger3 and hand (torsional springs, the default), times per call of

    Model.forward_dynamics   vs  pinocchio.aba
    the same with the rotors on the tendons (rotor_inertia=True: CRBA + S^T diag(J_m) S + Cholesky)
                             vs  pinocchio.aba (which takes only a diagonal armature)
    Model.inertia_matrix     vs  pinocchio.crba
    Model.gravity_torque     vs  pinocchio.computeGeneralizedGravity

and prints a table (or one JSON object with ``--json``) of microseconds and ratios.
Goal: forward_dynamics at most 1.5x the raw pinocchio.aba call on the hand.

    python benchmarks/dynamics.py [--json] [--repeat 7] [--number 20000]
"""

from __future__ import annotations

import argparse
import json
import timeit

import numpy as np
import pinocchio as pin

import alpes_dyn as ad


def bench(name: str, number: int, repeat: int) -> dict[str, float]:
    m = ad.Model.alpes(name)
    mr = ad.Model.alpes(name, rotor_inertia=True)
    rng = np.random.default_rng(0)
    q, v = m.random_state(rng)
    tau = rng.normal(scale=0.05, size=m.n)
    pm, pd = m.pin_model, m.pin_data
    pairs = {
        "forward_dynamics": (lambda: m.forward_dynamics(q, v, tau), lambda: pin.aba(pm, pd, q, v, tau)),
        "forward_dynamics_rotor": (lambda: mr.forward_dynamics(q, v, tau), lambda: pin.aba(pm, pd, q, v, tau)),
        "inertia_matrix": (lambda: m.inertia_matrix(q), lambda: pin.crba(pm, pd, q)),
        "gravity_torque": (lambda: m.gravity_torque(q), lambda: pin.computeGeneralizedGravity(pm, pd, q)),
    }
    out: dict[str, float] = {}
    for key, (ours, raw) in pairs.items():
        # interleaved rounds, best of each kept, so that both see the same state of the machine
        t_raw = t_ours = float("inf")
        for _ in range(repeat):
            t_raw = min(t_raw, timeit.timeit(raw, number=number) / number * 1e6)
            t_ours = min(t_ours, timeit.timeit(ours, number=number) / number * 1e6)
        out[f"{key}_us"] = t_ours
        out[f"{key}_raw_us"] = t_raw
        out[f"{key}_ratio"] = t_ours / t_raw
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--number", type=int, default=20000, help="calls per timing (default %(default)s)")
    ap.add_argument("--repeat", type=int, default=7, help="timings, best kept (default %(default)s)")
    a = ap.parse_args()
    res = {name: bench(name, a.number, a.repeat) for name in ("finger3", "hand")}
    res["goal"] = {"hand_forward_dynamics_ratio_max": 1.5,
                   "met": res["hand"]["forward_dynamics_ratio"] <= 1.5}
    if a.json:
        print(json.dumps(res))
        return
    print(f"{'model':8s} {'call':22s} {'alpes_dyn us':>13s} {'pinocchio us':>13s} {'ratio':>7s}")
    for name in ("finger3", "hand"):
        r = res[name]
        for key in ("forward_dynamics", "forward_dynamics_rotor", "inertia_matrix", "gravity_torque"):
            print(f"{name:8s} {key:22s} {r[key + '_us']:13.2f} {r[key + '_raw_us']:13.2f} {r[key + '_ratio']:7.2f}")
    print(f"goal: hand forward_dynamics <= 1.5x pinocchio.aba: {'met' if res['goal']['met'] else 'NOT met'}")


if __name__ == "__main__":
    main()
