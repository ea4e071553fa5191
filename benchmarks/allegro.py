"""Observability of a robot that is not the Alpes hand: the Allegro hand of example-robot-data with a tendon spec.

The check the issue asks for, ``alpes-dyn observability`` on the Allegro URDF with the shipped tendon spec
(``alpes_dyn/data/allegro_hand_spec.toml``: one tendon per finger over its three flexion joints, one motor per
ab/adduction joint), motor torques in, the 8 encoders out (4 tendons + 4 ab/adduction joints), 32 states,
timed as a new process, start-up included (goal: < 2 s). Baseline in the same run: a process that only
imports alpes_dyn (the floor any command pays). Also timed in this process: ``check_observability`` on the
same state space (libraries imported, state space built inside the call).

Prints a table, or one JSON object with ``--json``.

    python benchmarks/allegro.py [--json] [--repeat 5]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from typing import Any

GOAL_S = 2.0


def best_process(cmd: list[str], repeat: int) -> tuple[float, list[float], str]:
    times, out = [], ""
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = subprocess.run(cmd, capture_output=True, text=True, check=True)
        times.append(time.perf_counter() - t0)
        out = r.stdout
    return min(times), times, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--repeat", type=int, default=5, help="runs of each, best kept (default %(default)s)")
    a = ap.parse_args()

    import alpes_dyn as ad
    from alpes_dyn.model.spec import example_spec_path

    urdf, spec = ad.example_robot_urdf("allegro_hand", "allegro_right_hand"), example_spec_path("allegro_hand")
    cli = [sys.executable, "-m", "alpes_dyn.cli", "observability", "--model", str(urdf), "--spec", str(spec),
           "--input", "motor", "--output", "encoder", "--json"]
    base = [sys.executable, "-c", "import alpes_dyn"]
    # interleave the two kinds of run so that load on the machine affects both alike
    t_cli, t_base, out = [], [], ""
    for _ in range(a.repeat):
        s, _, out = best_process(cli, 1)
        t_cli.append(s)
        t_base.append(best_process(base, 1)[0])
    rep = json.loads(out)
    model = ad.Model.from_urdf_file(urdf, spec)
    inproc = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        r = ad.check_observability(model, input="motor", output="encoder")
        inproc.append(time.perf_counter() - t0)
    res: dict[str, Any] = {
        "robot": "allegro_hand (example-robot-data) + allegro_hand_spec.toml",
        "n_states": rep["n_states"], "n_outputs": rep["n_outputs"], "rank": rep["rank"], "observable": rep["observable"],
        "index": rep["index"], "parts": [(p["model"], p["rank"], p["n_states"]) for p in rep["parts"]],
        "cli_seconds": min(t_cli), "cli_all_seconds": t_cli, "goal_seconds": GOAL_S, "met": min(t_cli) < GOAL_S,
        "import_only_seconds": min(t_base), "cli_over_import": min(t_cli) / min(t_base),
        "in_process_seconds": min(inproc), "in_process_rank": r.rank,
    }
    if a.json:
        print(json.dumps(res))
        return
    print(f"Allegro hand + tendon spec: {res['n_states']} states, {res['n_outputs']} outputs (4 tendon encoders + "
          f"4 ab/adduction joints), rank {res['rank']}/{res['n_states']}, index {res['index']}")
    print(f"{'run':52s} {'best s':>8s}")
    print(f"{'alpes-dyn observability (new process)':52s} {res['cli_seconds']:8.2f}")
    label = 'baseline: python -c "import alpes_dyn" (new process)'
    print(f"{label:52s} {res['import_only_seconds']:8.2f}")
    print(f"{'check_observability in this process':52s} {res['in_process_seconds']:8.2f}")
    print(f"CLI / import-only: {res['cli_over_import']:.2f}x; goal < {GOAL_S:.0f} s: {'met' if res['met'] else 'NOT met'}")


if __name__ == "__main__":
    main()
