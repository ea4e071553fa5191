"""Speed of the observability rank test against the report's fully symbolic method, in the same run.

For finger2, finger3 and hand (u = joint torques, y = sum of joint angles, torsional springs, time-
varying input, 8 random points) times

* ``alpes_dyn.check_observability(name)``: the whole check (state space built with ADAM,
  Lie derivatives and O by CasADi AD, O evaluated at the points, row-normalised SVDs), best of
  ``--repeat`` runs in this process (libraries already imported);
* the CLI ``alpes-dyn observability --model hand`` as a new process, start-up included (goal: < 2 s);
* the baseline, the report's method written with sympy: the closed-form Lagrangian of the planar
  finger (E, U -> A, C qd, G, eq. 2.1-2.5, 2.14), qdd = A^-1 (u - C qd - G) by a symbolic LU solve,
  y .. y^(n-1) by ``sympy.diff`` along (f, u', u'', ...), O = d(...)/dx by ``sympy.diff``, then the
  rank of O at one random point (lambdify + numpy). It runs in a child process capped at
  ``--sympy-timeout`` seconds (reported as exceeded); the hand is not attempted (15 DoF).

Prints a table, or one JSON object with ``--json``.

    python benchmarks/observability.py [--json] [--repeat 3] [--sympy-timeout 30]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

MODELS = ("finger2", "finger3", "hand")
CLI_GOAL_S = 2.0


# ----------------------------------------------------------------------------- the sympy baseline
def sympy_check(n: int) -> dict[str, Any]:
    """The report's symbolic observability check of the n-phalanx finger (n = 2 or 3); returns rank, seconds."""
    import sympy as sp

    from alpes_dyn.model.params import load_params

    t0 = time.perf_counter()
    p = load_params()
    L, s, m, Izz, K = (np.asarray(getattr(p.finger, k))[:n].tolist() for k in ("L", "s", "m", "I", "K"))
    g0 = float(-p.gravity[2])
    q = sp.symbols(f"q1:{n + 1}")
    qd = sp.symbols(f"qd1:{n + 1}")
    E = sp.Integer(0)
    U = sp.Integer(0)
    th = sp.Integer(0)
    base = sp.Matrix([0, 0])
    for i in range(n):
        th = th + q[i]
        d = L[i] - s[i]
        c = base + d * sp.Matrix([sp.cos(th), sp.sin(th)])
        cd = c.jacobian(q) * sp.Matrix(qd)
        thd = sum(qd[: i + 1])
        E += sp.Rational(1, 2) * m[i] * (cd.T * cd)[0] + sp.Rational(1, 2) * (Izz[i] - m[i] * d**2) * thd**2
        U += m[i] * g0 * c[1] + sp.Rational(1, 2) * K[i] * q[i] ** 2
        base = base + L[i] * sp.Matrix([sp.cos(th), sp.sin(th)])
    A = sp.hessian(E, qd)
    Adot = sp.Matrix(n, n, lambda i, j: sum(sp.diff(A[i, j], qk) * qdk for qk, qdk in zip(q, qd)))
    Cqd = Adot * sp.Matrix(qd) - sp.Matrix([sp.diff(E, qi) for qi in q])
    G = sp.Matrix([sp.diff(U, qi) for qi in q])
    us = [sp.Matrix(sp.symbols(f"u{j}_1:{n + 1}")) for j in range(2 * n)]  # u, u', u'', ...
    qdd = A.LUsolve(us[0] - Cqd - G)
    x = list(q) + list(qd)
    f = list(qd) + list(qdd)
    phis = [sum(q)]
    for k in range(1, 2 * n):
        phi = phis[-1]
        dphi = sum(sp.diff(phi, xi) * fi for xi, fi in zip(x, f))
        for j in range(k - 1):
            dphi += sum(sp.diff(phi, a) * b for a, b in zip(us[j], us[j + 1]))
        phis.append(dphi)
    O = sp.Matrix([[sp.diff(ph, xi) for xi in x] for ph in phis])
    t_sym = time.perf_counter() - t0
    syms = x + [a for u in us for a in u]
    fn = sp.lambdify([syms], O, "numpy", cse=True)
    rng = np.random.default_rng(0)
    pt = np.concatenate([rng.uniform(0, np.pi / 2, n), rng.uniform(-2, 2, n), rng.uniform(-0.05, 0.05, len(syms) - 2 * n)])
    On = np.asarray(fn(pt), dtype=float)
    On = On / np.linalg.norm(On, axis=1, keepdims=True)
    rank = int(np.linalg.matrix_rank(On))
    return {"rank": rank, "seconds": time.perf_counter() - t0, "symbolic_seconds": t_sym}


def run_sympy(name: str, timeout: float) -> dict[str, Any]:
    n = {"finger2": 2, "finger3": 3}.get(name)
    if n is None:
        return {"status": "not attempted", "seconds": None, "rank": None}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--sympy-worker", str(n)]
    t0 = time.perf_counter()
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=True)
    except subprocess.TimeoutExpired:  # subprocess.run kills the child it started
        return {"status": "exceeded", "seconds": time.perf_counter() - t0, "rank": None, "cap": timeout}
    except subprocess.CalledProcessError as exc:
        return {"status": f"failed: {exc.stderr.strip().splitlines()[-1] if exc.stderr.strip() else exc}",
                "seconds": None, "rank": None}
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["status"] = "done"
    res["wall_seconds"] = time.perf_counter() - t0
    return res


# ----------------------------------------------------------------------------- ours
def run_ours(name: str, repeat: int) -> dict[str, Any]:
    from alpes_dyn.analysis.observability import check_observability as observability

    times = []
    rep = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        rep = observability(name)
        times.append(time.perf_counter() - t0)
    assert rep is not None
    return {"seconds": min(times), "rank": rep.rank, "n_states": rep.n_states, "index": rep.index,
            "min_singular_value": rep.min_singular_value}


def run_cli(repeat: int) -> dict[str, Any]:
    exe = shutil.which("alpes-dyn", path=str(Path(sys.executable).parent)) or "alpes-dyn"
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run([exe, "observability", "--model", "hand"], capture_output=True, check=True,
                       env={**os.environ, "PYTHONWARNINGS": "ignore"})
        times.append(time.perf_counter() - t0)
    return {"seconds": min(times), "all_seconds": times, "goal_seconds": CLI_GOAL_S, "met": min(times) < CLI_GOAL_S}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--repeat", type=int, default=3, help="runs of our check, best kept (default %(default)s)")
    ap.add_argument("--sympy-timeout", type=float, default=30.0,
                    help="cap of each sympy run, s (default %(default)s; finger3 needs minutes)")
    ap.add_argument("--sympy-worker", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.sympy_worker:
        print(json.dumps(sympy_check(a.sympy_worker)))
        return
    import alpes_dyn.analysis.observability  # noqa: F401  (imports out of the timings)
    import adam.casadi  # noqa: F401

    res: dict[str, Any] = {}
    for name in MODELS:
        ours = run_ours(name, a.repeat)
        base = run_sympy(name, a.sympy_timeout)
        bs = base.get("seconds")
        ratio = (bs / ours["seconds"]) if bs is not None else None
        res[name] = {"ours": ours, "sympy": base,
                     "speedup": ratio, "speedup_is_lower_bound": base["status"] == "exceeded"}
    res["cli_hand"] = run_cli(a.repeat)
    if a.json:
        print(json.dumps(res))
        return
    print(f"{'model':8s} {'alpes_dyn s':>11s} {'rank':>6s} {'sympy s':>14s} {'sympy rank':>10s} {'speedup':>9s}")
    for name in MODELS:
        r = res[name]
        o, b = r["ours"], r["sympy"]
        if b["status"] == "done":
            bs, br, sp_ = f"{b['seconds']:10.2f}", str(b["rank"]), f"{r['speedup']:9.0f}"
        elif b["status"] == "exceeded":
            bs, br, sp_ = f"> {b['cap']:.0f} (cap)", "-", f"> {r['speedup']:.0f}"
        else:
            bs, br, sp_ = b["status"], "-", "-"
        print(f"{name:8s} {o['seconds']:11.3f} {str(o['rank']) + '/' + str(o['n_states']):>6s} {bs:>14s} {br:>10s} {sp_:>9s}")
    c = res["cli_hand"]
    print(f"alpes-dyn observability --model hand (new process): {c['seconds']:.2f} s "
          f"(goal < {CLI_GOAL_S:.0f} s: {'met' if c['met'] else 'NOT met'})")


if __name__ == "__main__":
    main()
