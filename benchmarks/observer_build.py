"""The observer built in seconds (issue 20): the EKF's construction, its step from Python, and ``estimate --data``.

For finger3, the Allegro hand's index chain (``--chain index``: its sub-model) and the Alpes hand (``--models`` may add
``allegro``, the whole Allegro hand), the observer of ``estimate --data``
(:func:`~alpes_dyn.estimation.observers.replay.
recording_filter`: motor torques in, encoders out, the default substeps) is built

    build 1st     in a fresh process, the model already loaded (its symbolic dynamics, the RK4 step, the Jacobians,
                  the covariance arithmetic: everything that runs before the first sample);
    build again   a second build in the same process (what a sweep's next draw pays);
    instr         the filter step's instructions (CasADi's virtual machine runs each once per sample);
    VM us         the step per sample in CasADi's virtual machine (where ``estimate`` runs it), over 300 samples,
                  the least of five runs; "cse": the same step merged again by ``cse`` (what the baseline built, at
                  the cost of "cse s"), timed in turn in the same process -- the fair comparison of the step's time
                  (the baseline's own "VM us", in another process, moves with the machine's load);

each by the code of this tree and by the baseline commit :data:`BASELINE` (today's main before this work, extracted
with ``git archive`` and run in its own process in the same run: the column "x" is baseline / now). ``=base`` checks
that both filter steps give the same numbers, bit for bit, on the same input.

Then ``alpes-dyn estimate --data REC.csv --model ALLEGRO.urdf --spec SPEC --chain index`` (a 2 s recording of the hand,
``benchmarks/allegro_identify.py``'s experiment) is timed, wall clock, a new process each, ``--rounds`` times by each
tree in turn, the first from an empty compile cache (``ALPES_DYN_CACHE`` a new folder; ``estimate`` compiles nothing:
the number of libraries it left there is printed, 0, so a warm cache gives the same time). Goal: about 10 s or
less. And finger3's compiled step (``online()``, what a 1 kHz loop calls): its first build from an empty cache (gcc)
and from a warm one.

    python benchmarks/observer_build.py [--models finger3,index,hand] [--no-baseline] [--json]

Prints the load average (``os.getloadavg``) before and after: on the shared 2-core machine the figures move with it.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BASELINE = "9d3443d"
"""The commit before this work: the step's whole expression merged by ``cse`` and the covariance in scalar loops."""

ROOT = Path(__file__).resolve().parent.parent


def _model(name: str):
    import alpes_dyn as ad

    if name in ("finger3", "hand"):
        return ad.Model.alpes(name, friction=True)
    from alpes_dyn.model.spec import example_spec_path

    whole = ad.Model.from_urdf_file(ad.example_robot_urdf("allegro_hand", "allegro_right_hand"),
                                    example_spec_path("allegro_hand"))
    if name == "allegro":
        return whole
    from alpes_dyn.cli.estimation_cmds import _chain_model

    return _chain_model(whole, name)


def measure(name: str) -> dict:
    """One model's observer built twice in this process: times, size, VM step, and its step on a fixed input."""
    import casadi as cs
    import numpy as np

    from alpes_dyn.estimation.observers.replay import recording_filter

    m = _model(name)
    t0 = time.perf_counter()
    filt, z0, P0 = recording_filter(m, "ekf", 1e-3)
    first = time.perf_counter() - t0
    t0 = time.perf_counter()
    filt, z0, P0 = recording_filter(m, "ekf", 1e-3)
    again = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    N = 300
    W, Y = 1e-3 * rng.standard_normal((N, filt.nw)), 1e-3 * rng.standard_normal((N + 1, filt.ny))
    filt.run(z0, P0, W[:5], Y[:6])
    est = filt.run(z0, P0, W, Y)
    # the step's time in the VM against the same step merged again by cse (the baseline's expression, give or take
    # the 1-2 % of instructions cse removes), timed in turn in this process: the least of five runs of N samples
    f = filt.filter_step
    t0 = time.perf_counter()
    merged = cs.Function("merged", f.sx_in(), [cs.cse(f.call(f.sx_in())[0])])
    cse_s = time.perf_counter() - t0
    s0 = np.concatenate([z0, np.diag(P0).reshape(-1, order="F")])
    WY = np.hstack([W, Y[1:]]).T
    times: dict[str, list[float]] = {"now": [], "cse": []}
    for _ in range(5):  # a loaded machine's noise is one-sided: the least
        for key, F in (("now", f.mapaccum(N)), ("cse", merged.mapaccum(N))):
            t0 = time.perf_counter()
            F(s0, WY)
            times[key].append((time.perf_counter() - t0) / N * 1e6)
    vm_us, vm_cse_us = min(times["now"]), min(times["cse"])
    B = rng.standard_normal((filt.nz, filt.nz))
    s = np.concatenate([z0, (0.01 * B @ B.T + np.diag(P0)).reshape(-1, order="F")])
    out = np.array(filt.filter_step(s, 1e-3 * rng.standard_normal(filt.nw + filt.ny))).ravel()
    return {"model": name, "nz": filt.nz, "build_first_s": first, "build_again_s": again,
            "instructions": filt.filter_step.n_instructions(), "vm_us": vm_us, "vm_cse_us": vm_cse_us,
            "cse_instructions": merged.n_instructions(), "cse_s": cse_s, "step_out": out.tolist(),
            "run_last": est.z[-1].tolist()}


def _baseline_tree(folder: Path) -> Path | None:
    """The baseline commit's ``src`` extracted into ``folder`` (None outside a git checkout)."""
    try:
        arch = subprocess.run(["git", "-C", str(ROOT), "archive", BASELINE, "src"], capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(folder)], input=arch.stdout, check=True)
    except (OSError, subprocess.CalledProcessError):
        return None
    return folder / "src"


def _in_process(src: Path, args: list[str], env_extra: dict | None = None) -> tuple[float, str]:
    """``python args`` with ``src`` first on the path: (wall s, stdout)."""
    env = dict(os.environ, PYTHONPATH=str(src), **(env_extra or {}))
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{args}: {proc.stderr.strip().splitlines()[-1:]}")
    return wall, proc.stdout


def _measured(src: Path, name: str) -> dict:
    return json.loads(_in_process(src, [__file__, "--measure", name])[1].strip().splitlines()[-1])


def estimate_wall(src: Path, rec: Path, cache: Path) -> float:
    """``alpes-dyn estimate --data rec --chain index`` on the Allegro hand, wall s, cache ``cache``."""
    import alpes_dyn as ad
    from alpes_dyn.model.spec import example_spec_path

    urdf = str(ad.example_robot_urdf("allegro_hand", "allegro_right_hand"))
    args = ["-m", "alpes_dyn.cli", "estimate", "--data", str(rec), "--model", urdf, "--spec",
            str(example_spec_path("allegro_hand")), "--chain", "index", "--json"]
    return _in_process(src, args, {"ALPES_DYN_CACHE": str(cache)})[0]


def online_build(cache: Path) -> tuple[float, float]:
    """finger3's compiled step (``online()``) built from the empty ``cache`` and again from it warm, s."""
    code = ("import time\nfrom alpes_dyn.estimation.observers.replay import recording_filter\nimport alpes_dyn as ad\n"
            "f, z0, P0 = recording_filter(ad.Model.alpes('finger3', friction=True), 'ekf', 1e-3)\n"
            "t = time.perf_counter(); f.online(z0, P0); print(time.perf_counter() - t)\n")
    src = ROOT / "src"
    cold = float(_in_process(src, ["-c", code], {"ALPES_DYN_CACHE": str(cache)})[1].split()[-1])
    warm = float(_in_process(src, ["-c", code], {"ALPES_DYN_CACHE": str(cache)})[1].split()[-1])
    return cold, warm


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="finger3,index,hand")
    ap.add_argument("--no-baseline", action="store_true", help="this tree only")
    ap.add_argument("--duration", type=float, default=2.0, help="the Allegro recording's duration, s")
    ap.add_argument("--rounds", type=int, default=3, help="estimate runs of each tree, in turn")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--measure", help=argparse.SUPPRESS)  # one model, in its own process
    a = ap.parse_args(argv)
    if a.measure:
        print(json.dumps(measure(a.measure)))
        return 0
    import numpy as np

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from allegro_identify import make_recording

    out: dict = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "load_before": os.getloadavg()[0],
                 "baseline": None if a.no_baseline else BASELINE, "rows": []}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        base = None if a.no_baseline else _baseline_tree(d)
        for name in a.models.split(","):
            now = _measured(ROOT / "src", name)
            row = {k: v for k, v in now.items() if k not in ("step_out", "run_last")}
            if base is not None:
                old = _measured(base, name)
                row.update({"base_" + k: v for k, v in old.items()
                            if k in ("build_first_s", "build_again_s", "instructions", "vm_us")})
                row["equal_to_base"] = bool(np.array_equal(now["step_out"], old["step_out"]) and
                                            np.array_equal(now["run_last"], old["run_last"]))
            out["rows"].append(row)
        rec = make_recording(d, a.duration)
        now_s, base_s = [], []
        for _ in range(a.rounds):  # in turn, so that a change of the machine's load falls on both alike
            now_s.append(estimate_wall(ROOT / "src", rec, d / "cache_now"))
            if base is not None:
                base_s.append(estimate_wall(base, rec, d / "cache_base"))
        out["estimate_runs_s"], out["base_estimate_runs_s"] = now_s, base_s
        out["estimate_s"], out["estimate_warm_s"] = now_s[0], min(now_s[1:], default=None)
        out["estimate_cache_files"] = len(list((d / "cache_now").glob("*.so")))  # what estimate compiled: none
        out["base_estimate_s"] = min(base_s) if base_s else None
        out["online_empty_s"], out["online_warm_s"] = online_build(d / "cache_online")
    out["load_after"] = os.getloadavg()[0]
    if a.json:
        print(json.dumps(out))
        return 0
    print(f"observer build, {out['date']}, load average {out['load_before']:.1f} -> {out['load_after']:.1f}; "
          f"baseline {out['baseline'] or 'none'} (x = baseline / now)")
    print(f"{'model':8s} {'nz':>3s} {'build 1st':>9s} {'base':>7s} {'x':>5s} {'again':>7s} {'base':>7s} {'x':>5s} "
          f"{'instr':>8s} {'base':>8s} {'VM us':>7s} {'cse':>7s} {'cse s':>6s} {'base':>7s} {'=base':>5s}")
    for r in out["rows"]:
        b = r.get("base_build_first_s")
        print(f"{r['model']:8s} {r['nz']:3d} {r['build_first_s']:9.2f} "
              + (f"{b:7.2f} {b / r['build_first_s']:5.1f} " if b is not None else f"{'n/a':>7s} {'':5s} ")
              + f"{r['build_again_s']:7.2f} "
              + (f"{r['base_build_again_s']:7.2f} {r['base_build_again_s'] / r['build_again_s']:5.1f} "
                 if b is not None else f"{'n/a':>7s} {'':5s} ")
              + f"{r['instructions']:8d} " + (f"{r['base_instructions']:8d} " if b is not None else f"{'n/a':>8s} ")
              + f"{r['vm_us']:7.0f} {r['vm_cse_us']:7.0f} {r['cse_s']:6.2f} "
              + (f"{r['base_vm_us']:7.0f} {str(r['equal_to_base']):>5s}" if b is not None
                                         else f"{'n/a':>7s}"))
    e, w, be = out["estimate_s"], out["estimate_warm_s"], out["base_estimate_s"]
    best = min(out["estimate_runs_s"])
    print(f"estimate --data --chain index (Allegro, {a.duration:g} s recording), wall s of each run in turn: "
          f"{', '.join(f'{x:.1f}' for x in out['estimate_runs_s'])}"
          + (f"; baseline {', '.join(f'{x:.1f}' for x in out['base_estimate_runs_s'])}" if be else ""))
    print(f"  first from an empty cache {e:.1f} s" + (f", then warm {w:.1f} s" if w is not None else "")
          + f" ({out['estimate_cache_files']} libraries compiled); best {best:.1f} s"
          + (f" against the baseline's best {be:.1f} s (x {be / best:.1f})" if be else "")
          + f"; goal about 10 s: {'met' if best <= 10.0 else 'not met'}")
    print(f"finger3 online() compiled step: {out['online_empty_s']:.1f} s from an empty cache, "
          f"{out['online_warm_s']:.2f} s warm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
