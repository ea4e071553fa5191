"""Speed of batched RK4 rollouts: alpes_dyn's compiled rollout against a Python loop and MuJoCo, in one run.

For finger3 and the hand (torsional springs, no friction, joint-torque inputs, dt = 1 ms), the
time per RK4 step per trajectory (microseconds, wall clock) of

* ``alpes_dyn``: :class:`alpes_dyn.simulation.CompiledRollout` -- the CasADi RK4 step generated as
  C, compiled once (cached; the compilation is reported, not timed), B trajectories of N steps
  split over ``--threads`` POSIX threads;
* ``casadi`` / ``casadi-jit``: CasADi's stock path, the documented fallback
  (:class:`alpes_dyn.simulation.codegen.CasadiStepLoop`): ``mapaccum`` over the steps and a threaded ``map`` over
  the batch in CasADi's virtual machine, or with the step JIT-compiled by CasADi; the margin of the generated
  driver over it is ``x casadi``;
* ``pinocchio_python``: RK4 in a Python for-loop over steps, four ``pinocchio.aba`` calls per
  step (springs as -k q in the torque), one trajectory of ``--python-steps`` steps (its cost per
  step does not depend on B);
* ``mujoco``: ``mujoco.rollout.rollout`` on the same URDF (alpes_dyn.urdf_string) with
  ``opt.integrator = RK4``, the same dt and gravity, ``jnt_stiffness`` = the springs, joint limits
  and contacts off, inputs as ``qfrc_applied``; the same B, N and thread count as alpes_dyn.

Before timing, MuJoCo's and the Python loop's trajectories are checked against alpes_dyn's on the
first 200 steps (they integrate the same equations with the same scheme: the difference is
rounding). Each timing is the best of ``--repeat`` runs; OpenBLAS is kept to one thread
(``OPENBLAS_NUM_THREADS=1`` unless set) so that its spinning workers do not take the cores.
Goals: alpes_dyn at least 40x faster than the Python loop and faster than MuJoCo on both models.

    python benchmarks/rollout.py [--json] [--batch 64] [--steps 2000] [--threads 2] [--repeat 5]

Needs ``mujoco`` (the ``bench`` extra); ``--json`` prints one object
``{"finger3": {"alpes_dyn_us_per_step": ..., "pinocchio_python_us_per_step": ..., "mujoco_us_per_step": ...,
...}, "hand": {...}}``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from typing import Any

# OpenBLAS worker threads spin after numpy calls and steal the cores the rollouts run on
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import alpes_dyn as ad  # noqa: E402
from alpes_dyn.simulation import compile_rollout  # noqa: E402

MODELS = ("finger3", "hand")
DT = 1e-3
CHECK_STEPS = 200


def _progress(items, label: str, quiet: bool):
    """tqdm over ``items`` when available and not quiet, else the items."""
    if quiet:
        return items
    try:
        from tqdm import tqdm
    except ImportError:  # pragma: no cover - tqdm is in the bench extra
        return items
    return tqdm(items, desc=label, file=sys.stderr, leave=False)


def mujoco_model(m: ad.Model, dt: float):
    """A MuJoCo model of the same URDF, with the same springs, armature, gravity and RK4; plus the joint map."""
    import mujoco

    urdf = m.urdf
    i = urdf.index("<robot")
    j = urdf.index(">", i) + 1
    xml = (urdf[:j] + '\n  <mujoco><compiler discardvisual="true" fusestatic="false" balanceinertia="false" '
           'autolimits="true"/></mujoco>\n' + urdf[j:])
    mj = mujoco.MjModel.from_xml_string(xml)
    names = [mj.joint(k).name for k in range(mj.njnt)]
    perm = np.array([names.index(nm) for nm in m.joint_names])  # MuJoCo index of each alpes_dyn joint
    mj.jnt_limited[:] = 0
    mj.jnt_stiffness[perm] = m.extras.stiffness
    mj.qpos_spring[:] = 0.0
    mj.dof_armature[perm] = m.extras.armature
    mj.dof_damping[:] = 0.0
    mj.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    mj.opt.timestep = dt
    mj.opt.gravity[:] = m.gravity
    mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    return mj, perm


def mujoco_rollout(mj, perm, X0: np.ndarray, U: np.ndarray, threads: int, datas=None) -> tuple[np.ndarray, Any]:
    """q trajectories (B, N, n) from MuJoCo's threaded rollout (states after each step)."""
    import mujoco
    from mujoco import rollout

    n = len(perm)
    B, N, _ = U.shape
    nstate = mujoco.mj_stateSize(mj, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    init = np.zeros((B, nstate))
    init[:, 1 + perm] = X0[:, :n]  # FULLPHYSICS = [time, qpos, qvel, ...]
    init[:, 1 + mj.nq + perm] = X0[:, n:]
    ctrl = np.zeros((B, N, mj.nv))
    ctrl[:, :, perm] = U
    if datas is None:
        datas = [mujoco.MjData(mj) for _ in range(threads)]
    state, _ = rollout.rollout(mj, datas, init, ctrl, control_spec=mujoco.mjtState.mjSTATE_QFRC_APPLIED)
    return state[:, :, 1 + perm], datas


def python_rk4(m: ad.Model, x0: np.ndarray, U: np.ndarray, dt: float) -> np.ndarray:
    """The baseline: RK4 with pinocchio.aba in a Python loop over steps; returns q after each step."""
    import pinocchio as pin

    pm, pd, k, n = m.pin_model, m.pin_data, m.extras.stiffness, m.n
    q, v = x0[:n].copy(), x0[n:].copy()
    out = np.empty((U.shape[0], n))
    for s in range(U.shape[0]):
        tau = U[s]
        a1 = pin.aba(pm, pd, q, v, tau - k * q)
        q2, v2 = q + 0.5 * dt * v, v + 0.5 * dt * a1
        a2 = pin.aba(pm, pd, q2, v2, tau - k * q2)
        q3, v3 = q + 0.5 * dt * v2, v + 0.5 * dt * a2
        a3 = pin.aba(pm, pd, q3, v3, tau - k * q3)
        q4, v4 = q + dt * v3, v + dt * a3
        a4 = pin.aba(pm, pd, q4, v4, tau - k * q4)
        q = q + dt / 6 * (v + 2 * v2 + 2 * v3 + v4)
        v = v + dt / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
        out[s] = q
    return out


def _best(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def bench_model(name: str, B: int, N: int, threads: int, repeat: int, python_steps: int, quiet: bool) -> dict[str, Any]:
    m = ad.Model.alpes(name, spring="torsional")
    n = m.n
    rng = np.random.default_rng(0)
    X0 = np.array([np.concatenate(m.random_state(rng, speed=0.5)) for _ in range(B)])
    U = rng.normal(scale=0.005, size=(B, 1, n)) + 0.001 * rng.standard_normal((B, N, n))
    t0 = time.perf_counter()
    ro = compile_rollout(m, DT, input="joint", threads=threads)
    build_s = time.perf_counter() - t0
    out: dict[str, Any] = {"B": B, "N": N, "threads": threads, "dt": DT, "n_joints": n,
                           "alpes_dyn_compile_s": ro.compile_seconds, "alpes_dyn_build_s": build_s}

    # agreement on the first steps (same equations, same scheme)
    X = ro.rollout(X0[:4], U[:4, :CHECK_STEPS])
    qp = python_rk4(m, X0[0], U[0, :CHECK_STEPS], DT)
    out["python_max_abs_diff_rad"] = float(np.max(np.abs(qp - X[0, 1:, :n])))
    try:
        mj, perm = mujoco_model(m, DT)
        qm, _ = mujoco_rollout(mj, perm, X0[:4], U[:4, :CHECK_STEPS], threads)
        out["mujoco_max_abs_diff_rad"] = float(np.max(np.abs(qm - X[:, 1:, :n])))
        have_mujoco = True
    except ImportError:
        have_mujoco = False
        out["mujoco_us_per_step"] = None
    for key in ("python_max_abs_diff_rad", "mujoco_max_abs_diff_rad", "casadi_max_abs_diff_rad",
                "casadi-jit_max_abs_diff_rad"):
        if key in out and not out[key] < 1e-8:
            raise SystemExit(f"{name}: {key} = {out[key]:.3g}: the trajectories disagree, timing would be meaningless")

    # CasADi's stock path (the documented fallback): mapaccum over steps, threaded map over the batch
    fallbacks = {be: compile_rollout(m, DT, input="joint", threads=threads, backend=be)
                 for be in ("casadi", "casadi-jit")}
    for be, fb in fallbacks.items():
        out[f"{be}_max_abs_diff_rad"] = float(np.max(np.abs(fb.rollout(X0[:4], U[:4, :CHECK_STEPS]) - X)))
    stages = ["alpes_dyn", "casadi", "casadi-jit", "python"] + (["mujoco"] if have_mujoco else [])
    for stage in _progress(stages, f"{name}", quiet):
        if stage == "alpes_dyn":
            t = _best(lambda: ro.rollout(X0, U, progress=False), repeat)
            out["alpes_dyn_us_per_step"] = t / (B * N) * 1e6
        elif stage in fallbacks:
            fb = fallbacks[stage]
            t = _best(lambda: fb.rollout(X0, U, progress=False), max(1, repeat // 2))
            out[f"{stage}_us_per_step"] = t / (B * N) * 1e6
        elif stage == "python":
            Np = min(python_steps, N)
            t = _best(lambda: python_rk4(m, X0[0], U[0, :Np], DT), max(1, repeat // 2))
            out["pinocchio_python_us_per_step"] = t / Np * 1e6
        else:
            datas: list = []

            def run_mj() -> None:
                nonlocal datas
                _, d = mujoco_rollout(mj, perm, X0, U, threads, datas or None)
                datas = d

            run_mj()  # allocate MjData once, as a user would
            t = _best(run_mj, repeat)
            out["mujoco_us_per_step"] = t / (B * N) * 1e6
    a = out["alpes_dyn_us_per_step"]
    out["speedup_vs_python"] = out["pinocchio_python_us_per_step"] / a
    out["speedup_vs_casadi"] = out["casadi_us_per_step"] / a
    out["speedup_vs_casadi_jit"] = out["casadi-jit_us_per_step"] / a
    out["speedup_vs_mujoco"] = out["mujoco_us_per_step"] / a if out.get("mujoco_us_per_step") else None
    out["goal_40x_python"] = out["speedup_vs_python"] >= 40
    out["goal_faster_than_mujoco"] = bool(out["speedup_vs_mujoco"] and out["speedup_vs_mujoco"] > 1)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--batch", type=int, default=64, help="trajectories B (default %(default)s)")
    ap.add_argument("--steps", type=int, default=2000, help="RK4 steps N per trajectory (default %(default)s)")
    ap.add_argument("--threads", type=int, default=2, help="threads for alpes_dyn and MuJoCo (default %(default)s)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repetitions, best kept (default %(default)s)")
    ap.add_argument("--python-steps", type=int, default=1000, help="steps of the Python loop (default %(default)s)")
    args = ap.parse_args(argv)
    if min(args.batch, args.steps, args.threads, args.repeat, args.python_steps) < 1:
        print("rollout.py: error: --batch, --steps, --threads, --repeat and --python-steps must be >= 1",
              file=sys.stderr)
        return 2
    res = {name: bench_model(name, args.batch, args.steps, args.threads, args.repeat, args.python_steps, args.json)
           for name in MODELS}
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"RK4 rollouts, dt = {DT:g} s, B = {args.batch} trajectories x N = {args.steps} steps, "
          f"{args.threads} threads (us per step per trajectory, best of {args.repeat})")
    print(f"{'model':8s} {'alpes_dyn':>10s} {'casadi':>9s} {'casadi-jit':>10s} {'python+aba':>11s} {'mujoco':>9s} "
          f"{'x casadi':>9s} {'x python':>9s} {'x mujoco':>9s} {'compile s':>9s} {'|dq| mujoco':>11s}")
    for name, r in res.items():
        mj = r.get("mujoco_us_per_step")
        print(f"{name:8s} {r['alpes_dyn_us_per_step']:10.3f} {r['casadi_us_per_step']:9.3f} "
              f"{r['casadi-jit_us_per_step']:10.3f} {r['pinocchio_python_us_per_step']:11.2f} "
              f"{mj if mj is None else f'{mj:9.3f}':>9} {r['speedup_vs_casadi']:9.1f} {r['speedup_vs_python']:9.1f} "
              f"{(r['speedup_vs_mujoco'] or float('nan')):9.1f} {r['alpes_dyn_compile_s']:9.2f} "
              f"{r.get('mujoco_max_abs_diff_rad', float('nan')):11.1e}")
    ok = all(r["goal_40x_python"] and r["goal_faster_than_mujoco"] for r in res.values())
    print(f"goals (>= 40x the Python loop, faster than MuJoCo on both models): {'met' if ok else 'NOT met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
