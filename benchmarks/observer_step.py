"""The observer's step for a real-time loop (issue 20): microseconds per sample, the compiled step against filterpy.

Timed in the same process:

    OnlineFilter.step   (KalmanFilter.online: one call into the compiled predict-update step)
    C export            (alpes-dyn codegen: alpes_ekf_step in the exported C, its default code -- on the hand the
                         model by chains, the four fingers side by side in vector lanes, and the covariance loops by
                         block; on finger3 CasADi's code of the whole step --, compiled with cc -O2 -std=c99 (-O1 for
                         a source over 500 kB: the hand's) and timed by its main.c -t, no Python in the loop, wall
                         clock and (cpu) the process's processor time, which a loaded machine inflates less; goals:
                         under 5 us on finger3, 30 us on the hand; "build s": its compile)
    C whole             (a baseline C: CasADi's code of the filter's whole step, code="casadi", built and timed the
                         same way; the column C/whole is the ratio)
    C 1model            (the covariance loops on CasADi's code of the whole model, chains=False: the hand's model
                         code of the export before the chains; C/1model is the ratio)
    KalmanFilter.step   (the Python API: CasADi's virtual machine, checks and copies)
    filterpy + Pinocchio  (the baseline: filterpy's ExtendedKalmanFilter with the RK4 step on pinocchio.aba and
                           its exact Jacobian from pinocchio.computeABADerivatives through the four RK4 stages)

on finger3 and the hand (motor inputs, encoder outputs, the scenario's noise settings), each filtering the
same record; the estimates are compared (|C-run|, |Cw-run|, |C1-run|: the C exports give run()'s, 0.0; filterpy's RK4
is the same discretisation: they agree to rounding). Goals: OnlineFilter.step under 20 us on finger3 and 100 us
on the hand. The first run compiles the filter step (seconds on finger3, minutes on the hand: cached on disk); the
timings exclude it.

    python benchmarks/observer_step.py [--models finger3,hand] [--steps 2000] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import alpes_dyn as ad
from alpes_dyn.estimation.cexport.cexport import main_input, read_main_output, write_c_observer
from alpes_dyn.estimation.observers.observers import make_observer
from alpes_dyn.simulation.codegen import _LARGE_SOURCE
from alpes_dyn.symbolic.statespace import StateSpace


def _rk4_and_jacobian(m: ad.Model, dt: float):
    """x_next = RK4(x, u) on pinocchio.aba with the model's springs, dx_next/dx and dx_next/du (exact, chain rule
    through the four stages, u held over the step)."""
    pm, pd, n = m.pin_model, m.pin_data, m.n
    K = np.diag(m.extras.stiffness)
    B = m.transmission.S.T
    I = np.eye(2 * n)

    def f(x, tau):
        q, v = x[:n], x[n:]
        pin.computeABADerivatives(pm, pd, q, v, tau - K @ q)
        J = np.block([[np.zeros((n, n)), np.eye(n)], [pd.ddq_dq - pd.Minv @ K, pd.ddq_dv]])
        Ju = np.vstack([np.zeros((n, B.shape[1])), pd.Minv @ B])
        return np.r_[v, pd.ddq], J, Ju

    def step(x, u):
        tau = B @ u
        k1, J1, U1 = f(x, tau)
        k2, J2, U2 = f(x + 0.5 * dt * k1, tau)
        D2, E2 = J2 @ (I + 0.5 * dt * J1), J2 @ (0.5 * dt * U1) + U2
        k3, J3, U3 = f(x + 0.5 * dt * k2, tau)
        D3, E3 = J3 @ (I + 0.5 * dt * D2), J3 @ (0.5 * dt * E2) + U3
        k4, J4, U4 = f(x + dt * k3, tau)
        D4, E4 = J4 @ (I + dt * D3), J4 @ (dt * E3) + U4
        return (x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4), I + dt / 6 * (J1 + 2 * D2 + 2 * D3 + D4),
                dt / 6 * (U1 + 2 * E2 + 2 * E3 + E4))

    return step


def c_exports(filt, z0, P0, W, Y, rounds: int = 3) -> tuple[dict, dict, dict]:
    """The exported C step (alpes-dyn codegen's files for ``filt``) with its default code (on the hand: the model
    by chains, the fingers side by side, and the covariance loops by block; on a finger CasADi's code of the whole
    step), with the covariance loops on CasADi's code of the whole model (``chains=False``: the model's code of the
    export before; on a finger, where the default is CasADi's code, the loops with it), and with CasADi's code of
    the whole step (code="casadi", the baseline): each built with the system compiler, run on the record (its
    estimates) and timed by main.c's -t (us per step, wall clock and processor time), the three in turn
    ``rounds`` times, the fastest kept (a loaded machine's bursts fall on all); dicts with None where no C
    compiler is found."""
    cc = shutil.which(os.environ.get("CC", "").strip() or "gcc") or shutil.which("cc")
    if cc is None:
        return tuple({"c_us": None, "c_build_s": None, "Z": None} for _ in range(3))  # type: ignore[return-value]
    with tempfile.TemporaryDirectory() as d:
        built = []
        for name, kw in (("default", {}), ("whole_model", {"code": "sparse", "chains": False}),
                         ("casadi", {"code": "casadi"})):
            files = write_c_observer(filt, Path(d) / name, **kw)
            src = files["alpes_ekf.c"]
            opt = "-O1" if src.stat().st_size > _LARGE_SOURCE else "-O2"
            exe = src.parent / "alpes_ekf_main"
            t0 = time.perf_counter()
            subprocess.run([cc, opt, "-std=c99", "-o", str(exe), str(files["main.c"]), str(src), "-lm"], check=True,
                           capture_output=True)
            build_s = time.perf_counter() - t0
            inp = src.parent / "in.txt"
            inp.write_text(main_input(z0, P0, Y[0], W, Y[1:]))
            out = subprocess.run([str(exe), str(inp)], check=True, capture_output=True, text=True).stdout
            Z, _ = read_main_output(out, filt.nz)
            built.append((exe, inp, {"c_us": np.inf, "c_cpu_us": np.inf, "c_build_s": build_s, "c_opt": opt,
                                     "c_source_bytes": src.stat().st_size, "Z": Z}))
        repeat = max(1, 20000 // len(W))
        for _ in range(rounds):
            for exe, inp, r in built:
                timed = subprocess.run([str(exe), "-t", str(repeat), str(inp)], check=True, capture_output=True,
                                       text=True).stdout
                r["c_us"] = min(r["c_us"], float(timed.split(":")[1].split("us")[0]))
                r["c_cpu_us"] = min(r["c_cpu_us"], float(timed.split(",")[1].split("us")[0]))
    return built[0][2], built[1][2], built[2][2]


def bench(name: str, steps: int) -> dict:
    from filterpy.kalman import ExtendedKalmanFilter as FpEKF

    m = ad.Model.alpes(name)
    n, p, dt = m.n, m.transmission.n_motors, 1e-3
    ss = StateSpace(m, input="motor", output="encoder")
    Q = [1e-9**2] * n + [2e-4**2] * n
    R, Sw = [(2 * np.pi / 4096) ** 2 / 12] * p, [5e-4**2] * p
    filt = make_observer("ekf", ss, dt, process_noise=Q, measurement_noise=R, input_noise=Sw)
    rng = np.random.default_rng(0)
    q0 = np.full(n, 0.3)
    W = 0.02 + 1e-3 * rng.standard_normal((steps, p))
    Y = (q0 @ m.transmission.S.T) + 1e-3 * rng.standard_normal((steps + 1, p))
    z0, P0 = np.r_[q0, np.zeros(n)], np.array([0.05**2] * n + [0.1**2] * n)
    t0 = time.perf_counter()
    on = filt.online(z0, P0, Y[0])
    build_s = time.perf_counter() - t0
    Z_on = np.empty((steps + 1, 2 * n))
    Z_on[0] = on.z
    t0 = time.perf_counter()
    for k in range(steps):
        Z_on[k + 1] = on.step(W[k], Y[k + 1])
    online_us = (time.perf_counter() - t0) / steps * 1e6
    # the Python API's step on a shorter stretch (it is slow)
    ns = min(steps, 300)
    z, P = filt.update(z0, P0 * np.eye(2 * n), Y[0])
    t0 = time.perf_counter()
    for k in range(ns):
        z, P = filt.step(z, P, W[k], Y[k + 1])
    step_us = (time.perf_counter() - t0) / ns * 1e6
    # the baseline: filterpy's EKF, our RK4 on Pinocchio, its exact Jacobian; input noise through G = dx/du
    rk4 = _rk4_and_jacobian(m, dt)
    S = m.transmission.S
    fp = FpEKF(dim_x=2 * n, dim_z=p)
    fp.x, fp.P, fp.R = z0.copy(), np.diag(P0), np.diag(R)
    Qm, Swm = np.diag(Q), np.diag(Sw)

    def hx(x):
        return S @ x[:n]

    H = np.hstack([S, np.zeros((p, n))])

    def hj(x):
        return H

    fp.update(Y[0], hj, hx)
    Z_fp = np.empty((steps + 1, 2 * n))
    Z_fp[0] = fp.x
    t0 = time.perf_counter()
    for k in range(steps):
        x_next, F, Gu = rk4(fp.x, W[k])
        fp.x = x_next
        fp.P = F @ fp.P @ F.T + Gu @ Swm @ Gu.T + Qm
        fp.update(Y[k + 1], hj, hx)
        Z_fp[k + 1] = fp.x
    filterpy_us = (time.perf_counter() - t0) / steps * 1e6
    est = filt.run(z0, P0, W, Y)
    c, loops, whole = c_exports(filt, z0, P0, W, Y)  # the baseline C: CasADi's code of the whole step
    Zc, Zl, Zw = c.pop("Z"), loops.pop("Z"), whole.pop("Z")
    return {"model": name, "states": 2 * n, "online_us": online_us, "step_us": step_us, "filterpy_us": filterpy_us,
            "online_vs_filterpy": online_us / filterpy_us, "step_vs_filterpy": step_us / filterpy_us,
            "online_equals_run": bool(np.array_equal(Z_on, est.z)),
            "filterpy_max_diff_rad": float(np.abs(Z_fp[:, :n] - Z_on[:, :n]).max()),
            "online_build_s": build_s, **c,
            "c_vs_filterpy": c["c_us"] / filterpy_us if c["c_us"] is not None else None,
            "c_max_diff_vs_run": float(np.abs(Zc - est.z).max()) if Zc is not None else None,
            "c_casadi_us": whole["c_us"], "c_casadi_cpu_us": whole.get("c_cpu_us"),
            "c_casadi_build_s": whole["c_build_s"], "c_casadi_opt": whole.get("c_opt"),
            "c_vs_c_casadi": c["c_us"] / whole["c_us"] if c["c_us"] is not None else None,
            "c_cpu_vs_c_casadi": c["c_cpu_us"] / whole["c_cpu_us"] if c["c_us"] is not None else None,
            "c_casadi_max_diff_vs_run": float(np.abs(Zw - est.z).max()) if Zw is not None else None,
            "c_build_s": c["c_build_s"], "c_source_bytes": c.get("c_source_bytes"),
            "c_whole_model_us": loops["c_us"], "c_whole_model_cpu_us": loops.get("c_cpu_us"),
            "c_whole_model_build_s": loops["c_build_s"],
            "c_vs_c_whole_model": c["c_us"] / loops["c_us"] if c["c_us"] is not None else None,
            "c_cpu_vs_c_whole_model": c["c_cpu_us"] / loops["c_cpu_us"] if c["c_us"] is not None else None,
            "c_whole_model_max_diff_vs_run": float(np.abs(Zl - est.z).max()) if Zl is not None else None}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="finger3,hand")
    ap.add_argument("--steps", type=int, default=2000)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    rows = [bench(name, a.steps) for name in a.models.split(",")]
    goals = {"finger3": 20.0, "hand": 100.0}
    c_goals = {"finger3": 5.0, "hand": 30.0}
    out = {"rows": rows, "load_avg": os.getloadavg()[0],
           "goals_met": {r["model"]: r["online_us"] < goals.get(r["model"], np.inf) for r in rows},
           "c_goals_met": {r["model"]: r["c_us"] is not None and r["c_us"] < c_goals.get(r["model"], np.inf)
                           for r in rows}}
    if a.json:
        print(json.dumps(out))
        return 0
    print(f"load average {out['load_avg']:.1f}; us per sample (build of the compiled step excluded)")
    print(f"{'model':8s} {'states':>6s} {'online':>9s} {'step()':>9s} {'filterpy':>9s} {'online/fp':>9s} "
          f"{'=run':>5s} {'|fp-online| rad':>15s} {'C export':>9s} {'(cpu)':>7s} {'C/fp':>7s} {'|C-run|':>9s} "
          f"{'C whole':>9s} {'(cpu)':>7s} {'C/whole':>7s} {'(cpu)':>7s} {'|Cw-run|':>9s} "
          f"{'C 1model':>9s} {'(cpu)':>7s} {'C/1model':>8s} {'(cpu)':>7s} {'|C1-run|':>9s} {'build s':>7s}")
    for r in rows:
        c = (f"{r['c_us']:9.2f} {r['c_cpu_us']:7.2f} {r['c_vs_filterpy']:7.4f} {r['c_max_diff_vs_run']:9.1e} "
             f"{r['c_casadi_us']:9.2f} {r['c_casadi_cpu_us']:7.2f} {r['c_vs_c_casadi']:7.3f} "
             f"{r['c_cpu_vs_c_casadi']:7.3f} {r['c_casadi_max_diff_vs_run']:9.1e} "
             f"{r['c_whole_model_us']:9.2f} {r['c_whole_model_cpu_us']:7.2f} {r['c_vs_c_whole_model']:8.3f} "
             f"{r['c_cpu_vs_c_whole_model']:7.3f} {r['c_whole_model_max_diff_vs_run']:9.1e} {r['c_build_s']:7.1f}"
             if r["c_us"] is not None else "no C compiler")
        print(f"{r['model']:8s} {r['states']:6d} {r['online_us']:9.2f} {r['step_us']:9.1f} {r['filterpy_us']:9.1f} "
              f"{r['online_vs_filterpy']:9.3f} {str(r['online_equals_run']):>5s} {r['filterpy_max_diff_rad']:15.2e} "
              f"{c}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
