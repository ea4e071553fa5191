"""The figures of each benchmark's ``--json`` object, as the documentation states them (issue 36).

``SUMMARIES[name](result)`` gives the bullet lines of ``docs/benchmarks.rst``'s section for ``benchmarks/name.py``
(``docs/make_benchmarks.py``), from the object the script printed (kept by ``benchmarks/record.py``);
``HEADLINES[name] = (what, figure)``: the README's row, ``figure(result)`` its text. A key the script no longer
writes is a KeyError when the page is made: the page cannot silently drop a figure. Numbers only, no judgement the
JSON does not hold: a goal is "met" where the script says so.
"""

from __future__ import annotations

from statistics import median
from typing import Any, Callable

Result = dict[str, Any]


def _met(flag: bool) -> str:
    return "**met**" if flag else "**missed**"


def _r(x: float | None, fmt: str = ".2f") -> str:
    return "n/a" if x is None else format(x, fmt)


def dynamics(r: Result) -> list[str]:
    out = []
    for m in ("finger3", "hand"):
        d = r[m]
        out.append(f"{m}: ``forward_dynamics`` {d['forward_dynamics_us']:.2f} µs, {d['forward_dynamics_ratio']:.2f}x "
                   f"``pinocchio.aba`` ({d['forward_dynamics_raw_us']:.2f} µs); with the rotors on the tendons "
                   f"{d['forward_dynamics_rotor_ratio']:.2f}x; ``inertia_matrix`` {d['inertia_matrix_ratio']:.2f}x, "
                   f"``gravity_torque`` {d['gravity_torque_ratio']:.2f}x the raw Pinocchio calls")
    g = r["goal"]
    out.append(f"goal: the hand's forward dynamics within {g['hand_forward_dynamics_ratio_max']}x ABA: {_met(g['met'])}")
    return out


def observability(r: Result) -> list[str]:
    out = []
    for m in ("finger2", "finger3", "hand"):
        d = r[m]
        o, s = d["ours"], d["sympy"]
        ref = {"done": f"sympy {s['seconds']:.1f} s ({d['speedup']:.0f}x)",
               "exceeded": f"sympy over its {s.get('cap', 0):.0f} s cap (> {d['speedup']:.0f}x)"}.get(s["status"], "sympy not run")
        out.append(f"{m}: rank {o['rank']}/{o['n_states']} (index {o['index']}) in {o['seconds']:.3f} s; {ref}")
    c = r["cli_hand"]
    out.append(f"``alpes-dyn observability --model hand`` with process start {c['seconds']:.2f} s (goal "
               f"< {c['goal_seconds']:.0f} s: {_met(c['met'])})")
    return out


def allegro(r: Result) -> list[str]:
    return [f"{r['robot']}: rank {r['rank']}/{r['n_states']} from {r['n_outputs']} outputs (index {r['index']})",
            f"the command {r['cli_seconds']:.2f} s as a process vs {r['import_only_seconds']:.2f} s importing "
            f"alpes_dyn only ({r['cli_over_import']:.1f}x); in process {r['in_process_seconds']:.2f} s; goal "
            f"< {r['goal_seconds']:.0f} s: {_met(r['met'])}"]


def rollout(r: Result) -> list[str]:
    out = []
    for m in ("finger3", "hand"):
        d = r[m]
        out.append(f"{m} (B = {d['B']}, N = {d['N']}, {d['threads']} threads): {d['alpes_dyn_us_per_step']:.2f} µs per "
                   f"step per trajectory vs CasADi's ``mapaccum`` {d['casadi_us_per_step']:.2f} ({d['speedup_vs_casadi']:.0f}x), "
                   f"its JIT {d['casadi-jit_us_per_step']:.2f} ({d['speedup_vs_casadi_jit']:.1f}x), a Python RK4 loop over "
                   f"``pinocchio.aba`` {d['pinocchio_python_us_per_step']:.1f} ({d['speedup_vs_python']:.0f}x), MuJoCo's "
                   f"``rollout`` {d['mujoco_us_per_step']:.2f} ({d['speedup_vs_mujoco']:.1f}x); the same trajectories to "
                   f"{max(d['python_max_abs_diff_rad'], d['mujoco_max_abs_diff_rad']):.1e} rad; built in {d['alpes_dyn_build_s']:.1f} s")
        out.append(f"{m} goals: 40x the Python loop {_met(d['goal_40x_python'])}, faster than MuJoCo "
                   f"{_met(d['goal_faster_than_mujoco'])}")
    return out


def mimic(r: Result) -> list[str]:
    f, p = r["finger_mimic"], r["panda"]
    return [f"a 3-link finger whose DIP mimics its PIP, the forward dynamics against Pinocchio's mimic model "
            f"{f['pinocchio_mimic']:.1e}, the welded tree {f['welded']:.1e}, MuJoCo projected {f['mujoco_projected']:.1e}, "
            f"ADAM {f['adam']:.1e} rad/s² (MuJoCo's soft joint equality {f['mujoco_equality']:.1e})",
            f"Panda (its finger a mimic): nq {p['nq_full_tree']} -> {p['n_model']}, the forward dynamics equal the "
            f"whole tree's projected to {p['fd_vs_full_tree']:.1e}; {p['us_forward_dynamics']:.1f} µs, "
            f"{p['ratio_vs_model_without_mimic']:.1f}x the model with the finger free ({p['us_model_without_mimic']:.1f} µs), "
            f"the projection route {p['us_projection_route']:.1f} µs"]


SUMMARIES: dict[str, Callable[[Result], list[str]]] = {
    "dynamics": dynamics, "observability": observability, "allegro": allegro,
    "rollout": rollout, "mimic": mimic,
}

ORDER = ["default_path", "force_realism", "realism", "long_records", "identification", "fit_scaling", "observability",
         "allegro", "dynamics", "rollout", "observer_step", "observer_build", "param_cache", "control", "hand_control",
         "urdf_control", "any_robot", "allegro_identify", "mimic", "sweep"]
"""The page's order: the lead issues' benchmarks first."""

HEADLINES: dict[str, tuple[str, Callable[[Result], str]]] = {
    "observability": ("observability of the whole hand (30 states)",
                      lambda r: f"{r['hand']['ours']['seconds']:.2f} s in process; the command "
                                f"{r['cli_hand']['seconds']:.2f} s with process start"),
}
