"""The figures of each benchmark's ``--json`` object, as the documentation states them (issue 36).

``SUMMARIES[name](result)`` gives the bullet lines of ``docs/benchmarks.rst``'s section for ``benchmarks/name.py``
(``docs/make_benchmarks.py``), from the object the script printed (kept by ``benchmarks/record.py``);
``HEADLINES[name] = (what, figure)``: the README's row, ``figure(result)`` its text. A key the script no longer
writes is a KeyError when the page is made: the page cannot silently drop a figure. Numbers only, no judgement the
JSON does not hold: a goal is "met" where the script says so.
"""

from __future__ import annotations

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
        if s["status"] == "done":
            ref = f"sympy {s['seconds']:.1f} s ({d['speedup']:.0f}x)"
        elif s["status"] == "exceeded":
            ref = f"sympy over its {s['cap']:.0f} s cap (> {d['speedup']:.0f}x)"
        else:
            ref = "sympy not run"
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


def _pct(x: float) -> str:
    return f"{100 * x:.2f} %"


def identification(r: Result) -> list[str]:
    rows = r["finger3"]
    out = []
    for d in rows:
        p = d["parameters"]
        worst = {k: max(abs(v["error_pct"]) for n, v in p.items() if n.startswith(k + "_")) for k in ("K", "m", "F_s", "F_v")}
        out.append(f"finger3 seed {d['seed']}: K within {worst['K']:.2f} %, m within {worst['m']:.2f} %, friction "
                   f"F_s {worst['F_s']:.2f} %, F_v {worst['F_v']:.2f} %; EKF on the identified file "
                   f"{max(d['rmse_deg_after']):.3f} deg on the worst joint (on the nominal file "
                   f"{max(d['rmse_deg_before']):.1f} deg); fit {d['fit_seconds']:.1f} s (compile {d['compile_seconds']:.1f} s), "
                   f"{d['iterations']} iterations, {'converged' if d['converged'] else 'not converged'}, residual "
                   f"{d['residual_counts']:.2f} counts")
    return out


def fit_scaling(r: Result) -> list[str]:
    out = []
    for d in r["rows"]:
        w = d.get("worst_error_pct") or {}
        errs = f", K within {w['K']:.2f} %, m within {w['m']:.2f} %" if w else ""
        out.append(f"{r['model']} {d['duration_s']:.0f} s record (seed {d['seed']}, fit {d['fit']}): {d['seconds']:.1f} s "
                   f"({d['time_ratio']:.1f}x the first row; {d['cpu_seconds']:.1f} s of CPU), peak {d['peak_rss_mib']:.0f} MiB "
                   f"({d['memory_ratio']:.2f}x), {d['iterations']} iterations, "
                   f"{'converged' if d['converged'] else 'not converged'}, "
                   f"{'adequate' if d['trustworthy'] else 'flagged'}{errs}")
    return out


def observer_step(r: Result) -> list[str]:
    out = []
    for d in r["rows"]:
        m = d["model"]
        out.append(f"{m} ({d['states']} states): ``OnlineFilter.step`` {d['online_us']:.1f} µs vs ``step()`` "
                   f"{d['step_us']:.0f} µs vs filterpy {d['filterpy_us']:.0f} µs ({d['online_vs_filterpy']:.3f}x); equal "
                   f"to ``run()`` bit for bit: {d['online_equals_run']}; built in {d['online_build_s']:.1f} s; goal "
                   f"{_met(r['goals_met'][m])}")
        if d.get("c_us") is not None:
            out.append(f"{m} standalone C (``alpes-dyn codegen``, {d['c_opt']}): {d['c_us']:.2f} µs "
                       f"({d['c_cpu_us']:.2f} processor), CasADi's code of the same step {d['c_casadi_us']:.2f} µs "
                       f"({d['c_vs_c_casadi']:.2f}x), of the whole model {d['c_whole_model_us']:.2f} µs "
                       f"({d['c_vs_c_whole_model']:.2f}x); difference to ``run()`` {d['c_max_diff_vs_run']:.1e}; goal "
                       f"{_met(r['c_goals_met'][m])}")
    return out


def observer_build(r: Result) -> list[str]:
    out = [f"{d['model']}: built {d['build_first_s']:.2f} s in a fresh process, {d['build_again_s']:.2f} s again; "
           f"{d['instructions']} instructions, VM step {d['vm_us']:.0f} µs ({d['vm_cse_us']:.0f} µs merged again by "
           f"``cse``)" for d in r["rows"]]
    base = "" if r["base_estimate_s"] is None else f" (the baseline {r['base_estimate_s']:.1f} s)"
    out.append(f"``alpes-dyn estimate --data --chain index`` on the Allegro hand: {r['estimate_s']:.1f} s{base}, "
               f"{r['estimate_warm_s']:.1f} s again; finger3's ``online()`` step compiled from an empty cache "
               f"{r['online_empty_s']:.1f} s, {r['online_warm_s']:.2f} s warm")
    return out


def param_cache(r: Result) -> list[str]:
    lifted, baked = r["ways"]["lifted"], r["ways"]["baked"]
    drawn = {w: next(b for b in r["ways"][w]["builds"] if b["model"] == "drawn") for w in ("lifted", "baked")}
    return [f"{r['model']} drawn ±20 % (seed {r['seed']}) after the nominal: the filter {drawn['lifted']['build_s']:.2f} s, "
            f"{'compiled' if drawn['lifted']['compiled'] else 'nothing compiled'}, {len(lifted['libraries'])} library; "
            f"with the numbers as C literals {drawn['baked']['build_s']:.2f} s, "
            f"{'compiled again' if drawn['baked']['compiled'] else 'nothing compiled'}, {len(baked['libraries'])} libraries",
            f"the step {r['step_us']['lifted']:.2f} vs {r['step_us']['baked']:.2f} µs ({r['lifted_vs_baked']:.3f}x); runs "
            f"equal to {r['max_diff_run']:.1e}"]


def sweep(r: Result) -> list[str]:
    return [f"{r['draws']} draws (seeds from {r['seed']}), {r['rounds']} round(s), {r['workers']} workers: Dask "
            f"{r['median_dask_s']:.1f} s vs the serial loop {r['median_serial_s']:.1f} s (**{r['median_speedup']:.2f}x**) "
            f"and the serial loop on one thread {r['median_serial_1thread_s']:.1f} s ({r['median_speedup_vs_1thread']:.2f}x); "
            f"the bound 2 x serial / serial on one thread {r['median_speedup_bound']:.2f}x; the same rows: {r['same_rows']}"]


def _runs(runs: dict, keys: list[str]) -> list[str]:
    out = []
    for k in keys:
        d = runs[k]
        step = ("" if d["steady_state_error"] is None else
                f"steady-state error {_pct(d['steady_state_error'])}, overshoot {_pct(d['overshoot'])}, rise "
                f"{1e3 * d['rise_time_s']:.0f} ms, ")
        out.append(f"{k}: {step}RMSE {d['force_rmse']:.3f} N, {d['realtime_ratio']:.1f}x real time")
    return out


def control(r: Result) -> list[str]:
    out = _runs(r["runs"], [k for k in r["runs"] if "off" not in k])
    for c, v in r["plant_mismatch_loss"].items():
        sse = [d["steady_state_error"] for k, d in r["runs"].items() if "off" in k and k.endswith("/ " + c)]
        out.append(f"{c} on {len(sse)} plants drawn 10 % off per link: steady-state error {_pct(min(sse))}-"
                   f"{_pct(max(sse))}")
    out.append("goals: " + ", ".join(f"{k} {_met(v)}" for k, v in r["goals"].items()))
    return out


def hand_control(r: Result) -> list[str]:
    out = []
    for c, d in r["runs"].items():
        ch = d["chains"]
        q = [x["q_rmse_deg"] for x in ch if x["q_rmse_deg"] is not None]
        out.append(f"{c}: the five forces within {_pct(max(x['steady_state_error'] for x in ch))}, overshoot "
                   f"{_pct(min(x['overshoot'] for x in ch))}-{_pct(max(x['overshoot'] for x in ch))}, rise "
                   f"{1e3 * min(x['rise_time_s'] for x in ch):.0f}-{1e3 * max(x['rise_time_s'] for x in ch):.0f} ms, RMSE "
                   f"{min(x['force_rmse'] for x in ch):.3f}-{max(x['force_rmse'] for x in ch):.3f} N"
                   + (f", q̂ RMSE {min(q):.2f}-{max(q):.2f} deg" if q else "")
                   + f"; {d['realtime_ratio']:.2f}x real time"
                   + ("" if c == "pi" else f", {d['wall_vs_pi']:.1f}x the PIs' wall time"))
    return out


def urdf_control(r: Result) -> list[str]:
    out = _runs(r["runs"], list(r["runs"]))
    out.append("goals: " + ", ".join(f"{k} {_met(v)}" for k, v in r["goals"].items()))
    return out


def any_robot(r: Result) -> list[str]:
    out = []
    for name, d in r["robots"].items():
        o, i, e, c = d["observability"], d["identify"], d["estimate"], d["control"]
        out.append(f"{name}{'' if d['chain'] is None else ' (--chain ' + d['chain'] + ')'}: rank {o['rank']}/{o['n_states']}; "
                   f"springs within {100 * max(abs(v) for v in i['spring_error'].values()):.3f} % ({i['iterations']} iterations, "
                   f"identify {i['identify_wall_s']:.1f} s); EKF worst joint {e['worst_rmse_deg']:.3f} deg (the starting "
                   f"spec's {e['baseline_worst_rmse_deg']:.2f} deg); force steady-state error "
                   f"{_pct(c['steady_state_error'])}; goals "
                   + ", ".join(f"{k} {_met(d[k]['goal_met'])}" for k in ("observability", "identify", "estimate", "control")))
    rt = r["round_trip"]
    out.append("the MJCF round trip: " + ", ".join(f"{k} {max(v['A'], v['C'], v['G'], v['forward_dynamics_rel']):.1e}"
                                                    for k, v in rt.items()))
    return out


def foreign_hands(r: Result) -> list[str]:
    out = []
    h, f = r.get("hand"), r.get("finger")
    if h:
        e = h["dynamics_vs_mujoco"]
        out.append(f"Shadow Hand E3M5 ({h['n']} joints, {h['motors']} motors) against MuJoCo on its MJCF, {h['states']} "
                   f"states: M {e['M']:.1e}, bias {e['bias']:.1e}, S^T f {e['actuator']:.1e}, forward dynamics "
                   f"{e['qdd']:.1e} (relative; goal <= 1e-9: {_met(h['dynamics_goal_met'])})")
        out.append(f"first runs, new processes: import {h['import_wall_s']:.1f} s, dynamics {h['dynamics_wall_s']:.1f} s, "
                   f"observability {h['observability_wall_s']:.1f} s (rank {h['observability_rank']}), mjcf "
                   f"{h['mjcf_wall_s']:.1f} s")
    c = r.get("commands")
    if c:
        g = c["goal"]
        out.append(f"every command on the whole hand, wrist free (goal {g['wall_s']:.0f} s and {g['peak_mib']:.0f} MiB "
                   "each; wall s / CPU s / peak MiB / load before): " + ", ".join(
                       f"{k} {v['wall_s']:.0f} s / {v['cpu_s']:.0f} s / {v['peak_mib']:.0f} MiB / {v['load']:.1f}"
                       + (" (stopped)" if v["stopped"] else f" (exit {v['exit']})" if v["exit"] else "")
                       for k, v in c.items() if k != "goal"))
    hh = r.get("held")
    if hh:
        out.append(f"the whole hand with its wrist held ({hh['n']} joints, ``import --hold``): experiment "
                   f"{hh['experiment_wall_s']:.1f} s, identify --chain rh_A_FFJ0 {hh['identify']['wall_s']:.1f} s "
                   f"(converged {hh['identify']['converged']}), estimate --chain {hh['estimate']['wall_s']:.1f} s "
                   f"(worst joint {hh['estimate']['worst_rmse_deg']:.3f} deg on our simulator's recording)")
        if hh.get("codegen"):
            c = hh["codegen"]
            out.append(f"codegen of the held hand's EKF ({c['states']} states) {c['wall_s']:.1f} s: "
                       f"{c['c_bytes'] / 1e6:.1f} MB of C, {c['c_lines']} lines"
                       + (f"; compiled (cc {c['compile_flags']}) in {c['compile_s']:.0f} s, the compiler's peak "
                          f"{c['compiler_peak_mib']:.0f} MiB; against ``estimate --data``'s filter over {c['samples']} "
                          f"samples: z within {c['max_z_diff']:.1e}, P within {c['max_P_diff']:.1e}; "
                          f"{c['step_us']:.0f} us per step" if "compile_s" in c else " (not compiled by the benchmark)"))
    if f:
        i, idf = f["identify"], f["identifiability"]
        out.append(f"first finger, wrist held ({f['n']} joints): identifiability {f['identifiability_wall_s']:.1f} s "
                   f"(Cramér-Rao on the 4 s experiment " + ", ".join(f"{k} {100 * v:.1f} %" if v is not None else
                                                                    f"{k} none"
                                                                    for k, v in idf["mass_relative_std"].items())
                   + f"), experiment {f['experiment_wall_s']:.1f} s, identify {i['wall_s']:.1f} s, codegen "
                   f"{f['codegen_wall_s']:.1f} s")
        if "duration_s" in f:
            runs = f.get("runs", 1)
            out.append(f"the finger's experiment {f['duration_s']:g} s"
                       + (f", {runs} runs of it fitted together (the command replayed on MuJoCo each time, its own "
                          "sensor noise; the EKF on one more run, not fitted)" if runs > 1 else "")
                       + ", trimmed on the drawn finger (``--true-model``, "
                       f"``--amplitude 1``), MuJoCo's dry friction a real stick-slip (``mjcf --stiction``), the fit's "
                       f"v_s {f['smooth_velocity']:g} rad/s; MuJoCo's joints within {f['mujoco_vs_ours_deg']:.2f} deg "
                       "of our simulator's under the same torque")
        std = i.get("mass_std", {})
        out.append("masses on the MuJoCo recording: " + ", ".join(
            f"{k} {100 * v:+.1f} %" + (f" (sd {100 * std[k]:.1f} %)" if k in std else "")
            for k, v in i["mass_error"].items())
                   + f" (converged {i['converged']}, trustworthy {i['trustworthy']}; goal within 5 %: "
                   f"{_met(i['goal_met'])})")
        if i.get("reasons") and not i["trustworthy"]:
            out.append("not trusted: " + "; ".join(i["reasons"]) + ("; likely missing: " + "; ".join(
                i["likely_missing"]) if i.get("likely_missing") else ""))
        if i.get("mjcf_output"):
            out.append("the fit written back into the Shadow hand's MJCF (``identify --mjcf``): MuJoCo's compiled masses "
                       f"and frictions vs the fit's, largest relative difference {i['mjcf_mismatch']:.1g}")
        if "estimate" in f:
            e = f["estimate"]
            out.append(f"EKF on the identified pair: worst joint {e['worst_rmse_deg']:.3f} deg (nominal "
                       f"{e['baseline_worst_rmse_deg']:.3f} deg, the true finger "
                       f"{e.get('truth_worst_rmse_deg', float('nan')):.3f} deg; goal < 0.5 deg: {_met(e['goal_met'])}); RMSE "
                       + ", ".join(f"{k} {v:.2f}" for k, v in e.get("rmse_deg", {}).items())
                       + (" deg; final estimate " + ", ".join(f"{k} {v:.1f}" for k, v in e["final_q_deg"].items())
                          + " deg" if e.get("final_q_deg") else ""))
        c = f.get("control")
        if c:
            out.append(f"control {c['wall_s']:.1f} s: " + (f"steady-state error {_pct(c['steady_state_error'])}"
                                                          if c["error"] is None else f"``{c['error']}``"))
    sp = r.get("spatial")
    if sp:
        e, i = sp["dynamics_vs_mujoco"], sp["identify"]
        out.append(f"spatial-tendon finger (3 joints, a flexor over sites and two wrapping cylinders; ``import`` "
                   f"{sp['import_wall_s']:.1f} s, its moment arms fitted) against MuJoCo: ratio {e['ratio']:.1e}, "
                   f"motor angle {e['angle_rad']:.1e} rad, forward dynamics {e['qdd']:.1e} (relative; goal <= 1e-9: "
                   f"{_met(sp['dynamics_goal_met'])})")
        out.append(f"spatial finger on a MuJoCo recording (masses drawn +-15 %, springs +-10 %): identify "
                   f"{i['wall_s']:.1f} s, " + ", ".join(f"{k} {100 * v:+.2f} %" for k, v in i["error"].items())
                   + f" (converged {i['converged']}, trustworthy {i['trustworthy']}; goal springs 3 %, masses 5 %: "
                   f"{_met(i['goal_met'])})" + (f"; EKF on the identified pair: worst joint "
                                                f"{sp['estimate']['worst_rmse_deg']:.3f} deg (goal < 0.5 deg: "
                                                f"{_met(sp['estimate']['goal_met'])})" if "estimate" in sp else ""))
    return out


def allegro_identify(r: Result) -> list[str]:
    out = [f"{r['sub_model']} ({r['duration_s']:.0f} s record), first ``identify`` from its own empty cache: "
           f"**{r['sub_cold_wall_s']:.1f} s** (processor {r['sub_cold_cpu_s']:.1f} s, compile {r['sub_cold_compile_s']:.1f} s, "
           f"fit {r['sub_cold_fit_s']:.1f} s, {r['sub_iterations']} iterations), warm {r['sub_warm_wall_s']:.1f} s; goal "
           f"< {r['goal_s']:.0f} s: {_met(r['sub_cold_wall_s'] < r['goal_s'])}",
           "springs against the truth: " + ", ".join(f"{k} {100 * v:+.3f} %" for k, v in r["K_error_rel"].items())]
    if r["whole_cold_wall_s"] is not None:
        out.append(f"the whole hand (baseline): {r['whole_cold_wall_s']:.1f} s ({r['speedup_cold']:.1f}x)")
    return out


def _mw(st: dict, fmt: str = ".2f") -> str:
    return "n/a" if st["median"] is None else f"{format(st['median'], fmt)} / {format(st['worst'], fmt)}"


def _seeds(r: Result) -> str:
    s = r["seeds"]
    return f"{s[0]}-{s[-1]}" if s == list(range(s[0], s[-1] + 1)) else ", ".join(str(x) for x in s)


def realism(r: Result) -> list[str]:
    rows = [x for x in r["rows"] if "adaptation" in x]
    hung = sum(x["adaptation"]["rig"] == "hanging" for x in rows)
    turned = sum(x["adaptation"]["rig"] == "both" for x in rows)
    scaled = sum(x["adaptation"]["amplitude_scale"] != 1.0 for x in rows)
    out = [f"{r['model']} drawn +-20 %, seeds {_seeds(r)}, {r['duration_s']:g} s experiments on the "
           f"{r['rig']} rig, adapted on the plant (``--adapt {r.get('adapt', 'none')}``): "
           + (f"{turned} of {len(rows)} turned halfway (palm up, then hung), " if turned else "")
           + f"{hung} of {len(rows)} hung fingers down, {scaled} scaled"]
    for case, c in r["summary"].items():
        g = c["goal"]
        misses = ", ".join(f"seed {m['seed']}: EKF {m['ekf_deg']:.2f} deg, m {m['m_pct']:.1f} %"
                           for m in c["silent_misses"]) or "none"
        refused = "; ".join(f"seed {x['seed']}: {x['verdict']}" for x in c["refusals"]) or "none"
        w = _adequate_worst(r, case)
        good = "" if w is None else (f" (the adequate files: K within {w['K']:.2f} %, m within {w['m']:.2f} %, EKF "
                                     f"within {w['ekf']:.2f} deg)")
        out.append(f"**{case}** ({c['n']} draws; median / worst over all, refused included, errors up to the common "
                   f"scale): **{c['adequate']} adequate**{good}, K {_mw(c['K_pct'])} %, m {_mw(c['m_pct'])} %, F_s "
                   f"{_mw(c['F_s_pct'], '.1f')} %, EKF {_mw(c['ekf_deg'])} deg (worst joint), fit "
                   f"{_mw(c['fit_seconds'], '.1f')} s (every round and the observer's check); silent misses: {misses}; "
                   f"refused: {refused}; runs that raised: {len(c['errors'])}")
        out.append(f"{case}'s goals (EKF < {g['ekf_deg']:g} deg, K {g['K_pct']:g} %, m {g['m_pct']:g} % on every "
                   f"adequate file, no silent miss): {_met(g['accuracy_met'])}; median fit < {g['fit_seconds']:g} s: "
                   f"{_met(g['time_met'])}")
    return out


def realism_friction(r: Result) -> list[str]:
    """``realism.py --friction`` (issue 50): per friction case the verdicts, the worst errors and EKF, the NEES and
    the standard scores."""
    v = r["validation"]
    per_case = ", ".join(f"{c} {len(s)}" for c, s in r.get("case_seeds", {}).items()) or f"{len(r['seeds'])} each"
    out = [f"{r['model']} drawn +-20 %, seeds {_seeds(r)} (draws per case: {per_case}), {r['duration_s']:g} s "
           f"experiments (``--adapt {r['adapt']}``), ``identify --effects {r['fit_effects']}``; the EKF on a validation "
           f"run the fit never saw: the ``estimate`` scenario's torque ({v['scenario_s']:g} s) then a "
           f"{v['ramp_s']:g} s ramp of +-{1e3 * v['ramp_torque_Nm']:g} mN m through the stick band; cases: MuJoCo's "
           f"``frictionloss`` with its default constraint (soft, 0.02 s: creeps) or 0.5 ms (stiff: sticks), 1x or 3x "
           f"the draw's F_s, alone or with every other effect (``all_``)"]
    for case, c in r["summary"].items():
        misses = ", ".join(f"seed {m['seed']}: EKF {m['ekf_deg']:.2f} deg" for m in c["silent_misses"]) or "none"
        refused = "; ".join(f"seed {x['seed']}: {x['verdict']}" for x in c["refusals"]) or "none"
        zn = c.get("z_noise_within_3")
        z = "n/a" if c["z_worst"] is None else (f"{c['z_worst']:.1f} ({100 * c['z_within_3']:.0f} % within 3"
                                                + ("" if zn is None else f"; {100 * zn:.0f} % with the noise's "
                                                   "standard errors alone") + ")")
        out.append(f"**{case}** ({c['n']} draws, worst over all): **{c['adequate']} adequate**, **silent misses: "
                   f"{len(c['silent_misses'])}** ({misses}); K {_r(c['K_pct']['worst'])} %, m "
                   f"{_r(c['m_pct']['worst'], '.1f')} % (up to the common scale); EKF worst joint "
                   f"{_r(c['ekf_deg']['worst'])} deg with the identified file, {_r(c['ekf_true_file_deg']['worst'])} deg "
                   f"with the true one; draws with a joint's NEES outside its 95 % band: {c['nees_inconsistent']} "
                   f"(identified), {c['nees_true_file_inconsistent']} (true file), worst joint NEES "
                   f"{_r(c['nees_worst'], '.3g')}; largest error in standard errors {z}; refused: {refused}; runs that "
                   f"raised: {len(c['errors'])}; issue 50's goal on every draw: {_met(c['issue_goal_met'])}")
    return out


def observer_law(r: Result) -> list[str]:
    """``observer_law.py`` (issue 50): per friction case and observer law, the EKF with the plant's true file; the
    law closest to the truth per friction kind; what the true file cannot hold."""
    seeds = sorted({x["seed"] for x in r["rows"] if "error" not in x})
    out = [f"finger3 drawn +-20 %, seeds {', '.join(map(str, seeds))} on every case; the EKF with the plant's true "
           f"file (``bench.truth.write_truth``: the rig's effects in the file), no fit, on the friction study's "
           f"validation run; worst joint's RMSE after 1 s (median / worst over the draws, goal "
           f"{r['ekf_goal_deg']:g} deg) and its NEES"]
    for case, laws in r["summary"]["cases"].items():
        out.append(f"**{case}**: " + "; ".join(
            f"{law} {_mw(s['rmse_worst_joint_deg'])} deg (NEES {_mw(s['nees_worst_joint'], '.3g')}, "
            f"{s['within_goal']}/{s['rows']} within the goal)" for law, s in laws.items()))
    for kind, c in r["summary"]["choice"].items():
        out.append(f"closest for a {kind} friction (over {', '.join(c['cases'])}): **{c['law']}** (worst joint "
                   + ", ".join(f"{law} {v:.2f}" for law, v in c["worst_joint_deg"].items())
                   + " deg; the observer's default stays smooth, ``--friction-law`` asks for another)")
    held = sorted({n.split(" ")[0] for x in r["rows"] for n in x.get("not_held", [])})
    out.append("effects the true file cannot hold (named by the writer): " + (", ".join(held) or "none"))
    out += [f"raised: {x['case']} seed {x['seed']}: {x['error']}" for x in r["summary"]["raised"]]
    return out


def _adequate_worst(r: Result, case: str) -> dict[str, float] | None:
    """The worst K and m errors (%, up to the common scale) and EKF (deg) over a case's adequate rows."""
    good = [x for x in r["rows"] if x.get("case") == case and "extended" in x and not x["extended"]["flagged"]]
    if not good:
        return None
    return {"K": max(x["extended"]["worst_error_common_scale_pct"]["K"] for x in good),
            "m": max(x["extended"]["worst_error_common_scale_pct"]["m"] for x in good),
            "ekf": max(max(x["ekf_rmse_deg"]) for x in good)}


def force_realism(r: Result) -> list[str]:
    """Per model / variant / controller (the script's ``summary``): the runs, how many met the goals, the figures."""
    who = ", ".join(r["models"]) + (f" on seeds {', '.join(str(x) for x in r['seeds'])}" if r["models"] else "")
    if r["hand_seeds"]:
        who += ("; " if who else "") + f"the hand on seeds {', '.join(str(x) for x in r['hand_seeds'])}"
    ids = [i for i in r["identifications"] if "converged" in i]  # the fits (the hand's grasp probes apart)
    probe = " (the hand's per chain, scaled from its grasp probe)" if r["hand_seeds"] else ""
    out = [f"{who}; levels {' -> '.join(f'{x:g}' for x in r['levels_N'])} N{probe}; identifications: "
           f"{sum(i['converged'] for i in ids)} of {len(ids)} converged, {sum(not i['flagged'] for i in ids)} adequate"]
    for key, c in r["summary"].items():
        parts = [f"{c['runs']} runs"]
        if "goal_met" in c:
            parts.append(f"**{c['goal_met']} met the goals**")
        if "rmse_pct" in c:
            parts.append(f"RMSE after the rise {_mw(_mm(c['rmse_pct']))} %, overshoot {_mw(_mm(c['overshoot_pct']), '.1f')} %, "
                         f"rise {_mw(_mm(c['rise_ms']), '.0f')} ms, steady-state error {_mw(_mm(c['sse_pct']))} % "
                         "(median / worst)")
        if "worst_sse_pct" in c:
            parts.append(f"worst force error {c['worst_sse_pct']:.2f} %")
        if c.get("failed"):
            parts.append(f"{c['failed']} failed")
        out.append(f"``{key}``: " + ", ".join(parts))
    return out


def _mm(st: dict) -> dict:
    """A ``{median, max}`` statistic as ``{median, worst}``."""
    return {"median": st["median"], "worst": st["max"]}


def default_path(r: Result) -> list[str]:
    out = []
    for model, c in r["summary"].items():
        out.append(f"{model}, seeds {_seeds(r)}: **{c['exit_0']} of {c['n']} exit 0** ({c['hung']} hung fingers down by "
                   f"the experiment, {c['scaled']} scaled); springs within {_r(c['K_pct']['worst'])} % (median "
                   f"{_r(c['K_pct']['median'])}), masses within {_r(c['m_pct']['worst'])} % (median "
                   f"{_r(c['m_pct']['median'])}); over K 3 %: {c['over_K'] or 'none'}, over m 5 %: {c['over_m'] or 'none'}; "
                   f"refused: {c['refused'] or 'none'}; files with a non-physical value: {c['unphysical'] or 'none'}; "
                   f"identify {c['fit_seconds_median']:.1f} s median; goals (exit 0, K 3 %, m 5 %, physical): "
                   f"{_met(c['goal_met'])}")
    return out


def _default_path_headline(r: Result) -> str:
    parts = [f"{m} {c['exit_0']} of {c['n']} exit 0, springs within {_r(c['K_pct']['worst'])} %, masses within "
             f"{_r(c['m_pct']['worst'])} %" for m, c in r["summary"].items()]
    bad = sum(len(c["unphysical"]) for c in r["summary"].values())
    return f"seeds {_seeds(r)}: " + "; ".join(parts) + f"; {bad or 'no'} file with a non-physical value"


def _realism_headline(r: Result) -> str:
    case = "all" if "all" in r["summary"] else next(iter(r["summary"]))
    c, w = r["summary"][case], _adequate_worst(r, case)
    n_miss = len(c["silent_misses"])
    within = "" if w is None else f" (K {w['K']:.2f} %, m {w['m']:.2f} %, EKF {w['ekf']:.2f} deg at worst)"
    return (f"seeds {_seeds(r)}: {c['adequate']} of {c['n']} adequate{within}, {n_miss} silent "
            f"miss{'es' if n_miss != 1 else ''}, {len(c['refusals'])} refused naming a cause")


def _identification_headline(r: Result) -> str:
    rows = r["finger3"]
    worst = {k: max(abs(v["error_pct"]) for d in rows for n, v in d["parameters"].items() if n.startswith(k + "_"))
             for k in ("K", "m")}
    ekf = [max(d["rmse_deg_after"]) for d in rows]
    return (f"K within {worst['K']:.2f} %, m within {worst['m']:.2f} %, EKF on the identified file {min(ekf):.2f}-"
            f"{max(ekf):.2f} deg (seeds {', '.join(str(d['seed']) for d in rows)}; fits "
            f"{min(d['fit_seconds'] for d in rows):.1f}-{max(d['fit_seconds'] for d in rows):.1f} s)")


def _observer_step_headline(r: Result) -> str:
    d = {x["model"]: x for x in r["rows"]}
    return (f"`OnlineFilter.step` finger3 {d['finger3']['online_us']:.1f} µs, hand {d['hand']['online_us']:.1f} µs; "
            f"C export finger3 {d['finger3']['c_us']:.2f} µs, hand {d['hand']['c_us']:.1f} µs (builds excluded)")


def _bench_counts(r: Result) -> dict[str, str]:
    """Each goal of ``bench_loop``: how many draws met it, of those that reached it."""
    rows = r["rows"]
    return {g: f"{sum(1 for x in rows if x['goals'][g])} of {sum(1 for x in rows if x['goals'][g] is not None)}"
            for g in rows[0]["goals"]} if rows else {}


def _bench_worst(r: Result) -> dict[str, float | None]:
    """Each goal's worst figure over the draws identified adequate (None where none reached it)."""
    rows = [x for x in r["rows"] if x.get("verdict") == "adequate"]
    loops = [{y["controller"]: y for y in x.get("loops", [])} for x in rows]

    def worst(values: list) -> float | None:
        v = [a for a in values if a is not None]
        return max(v) if v else None
    return {"K_pct": worst([x.get("K_pct") for x in rows]), "m_pct": worst([x.get("m_pct") for x in rows]),
            "rmse_pct": worst([lp.get("sensor", {}).get("rmse_pct") for lp in loops]),
            "overshoot_pct": worst([lp.get("sensor", {}).get("overshoot_pct") for lp in loops]),
            "rise_ms": worst([lp.get("sensor", {}).get("rise_ms") for lp in loops]),
            "sse_pct": worst([lp.get("sensorless", {}).get("sse_pct") for lp in loops]),
            "q_deg": worst([max(lp["sensor"]["q_rmse_deg_joints"]) for lp in loops
                            if lp.get("sensor", {}).get("q_rmse_deg_joints")])}


def _bench_draws(r: Result) -> str:
    """The draws by model: "12 fresh draws of finger3, finger2 and 6 of the hand (24 finger chains)"."""
    fingers = sorted({x["model"] for x in r["rows"] if x["model"] != "hand"})
    n_f = sum(1 for x in r["rows"] if x["model"] != "hand")
    hand = [x for x in r["rows"] if x["model"] == "hand"]
    text = f"{n_f} fresh draws of {' and '.join(fingers)}" if n_f else ""
    if hand:
        n_h = len({x["seed"] for x in hand})
        n_t = sum(1 for x in hand if x.get("chain") == "thumb")
        parts = [f"{len(hand) - n_t} finger chains"] * (len(hand) > n_t) + [f"{n_t} thumbs"] * (n_t > 0)
        text += f"{' and ' if text else ''}{n_h} fresh draws of the hand ({', '.join(parts)})"
    return text


def bench_loop(r: Result) -> list[str]:
    """Per draw: where the workflow stopped, or its figures; then how many draws met each goal, and each goal's
    worst figure over the draws identified adequate."""
    out = []
    for x in r["rows"]:
        head = f"{x['model']}{'/' + x['chain'] if 'chain' in x else ''} seed {x['seed']}"
        if "experiment_error" in x:
            out.append(f"{head}: the experiment refused on every rig ({x['experiment_error'][:160]})")
            continue
        rig = f"{x['rig']} rig, a stop reached in the record: {x['stop_reached']}"
        if "identify_error" in x:
            out.append(f"{head}: {rig}; identify refused ({x['identify_error'][:160]})")
            continue
        loops = {y["controller"]: y for y in x.get("loops", [])}
        s, sl = loops.get("sensor", {}), loops.get("sensorless", {})
        q = s.get("q_rmse_deg_joints")
        c = [y for y in loops.values() if "c_step_diff" in y or "c_diff" in y]
        c_text = "" if not c else (f"; C step within {_c_diff_text(c)}, "
                                   + (f"{max(y['c_us_min'] for y in c):.1f} µs per step (each step's minimum over "
                                      f"{c[0]['c_passes']} passes; median {max(y['c_us_median'] for y in c):.1f})"
                                      if all("c_us_min" in y for y in c) else
                                      f"{max(y['c_cpu_us'] for y in c):.1f} µs of processor time per step"
                                      + (f" (the best of {c[0]['c_passes']} passes)" if "c_passes" in c[0] else "")))
        if s.get("scene") == "cylinder":  # the thumb: the whole hand's step on the cylinder
            c_text += (f"; loops on the hand's cylinder, the ab/adduction ending at "
                       f"{_r(s.get('abduction_end_deg'), '.1f')} deg (target 35)")
            if loops.get("calibration", {}).get("force_scale_found") is not None:  # bench_loop.thumb_loops' press
                c_text += f", after a calibration press (force_scale {loops['calibration']['force_scale_found']:.3f})"
        out.append(f"{head}: {rig}; springs {_r(x['K_pct'])} %, masses {_r(x['m_pct'])} % ({x['verdict']}); sensor "
                   f"RMSE {_r(s.get('rmse_pct'))} %, overshoot {_r(s.get('overshoot_pct'), '.1f')} %, rise "
                   f"{_r(s.get('rise_ms'), '.0f')} ms; sensorless {_r(sl.get('sse_pct'))} %; joints in contact "
                   f"{'n/a' if not q else ' / '.join(f'{v:.2f}' for v in q)} deg{c_text}")
    counts = _bench_counts(r)
    out.append("goals met (of the draws that reached them): " + ", ".join(f"{g} {c}" for g, c in counts.items()))
    w = _bench_worst(r)
    out.append(f"worst over the draws identified adequate: springs {_r(w['K_pct'])} %, masses {_r(w['m_pct'])} %, "
               f"sensor RMSE {_r(w['rmse_pct'])} %, overshoot {_r(w['overshoot_pct'], '.1f')} %, rise "
               f"{_r(w['rise_ms'], '.0f')} ms, sensorless {_r(w['sse_pct'])} %, joints in contact {_r(w['q_deg'])} deg")
    return out


def _bench_loop_headline(r: Result) -> str:
    c = _bench_counts(r)
    fitted = sum(1 for x in r["rows"] if x.get("verdict") == "adequate")
    refused = sum(1 for x in r["rows"] if "identify_error" in x or "experiment_error" in x)
    return (f"{_bench_draws(r)}: {fitted} adequate, {refused} refused naming why; of the adequate: springs 3 % "
            f"{c['springs_3pct']}, masses 5 % {c['masses_5pct']}, sensor loop {c['sensor_loop']}, sensorless 10 % "
            f"{c['sensorless_10pct']}, joints 1 deg {c['joints_1deg']}"
            + (f", C step {c['c_step']}" if "c_step" in c else "") + f"; no stop {c['no_stop']}")


def _c_diff_text(loops: list[dict]) -> str:
    """The C step's largest difference from Python over ``loops``: one step from the same state and free-running
    (c_step.py's docstring); a record before the per-step column: its free run's (``c_diff``)."""
    if all("c_step_diff" in y for y in loops):
        return (f"{max(y['c_step_diff'] for y in loops):.1e} of Python one step from the same state "
                f"({max(y['c_run_diff'] for y in loops):.1e} free-running)")
    return f"{max(y.get('c_run_diff', y.get('c_diff', 0.0)) for y in loops):.1e} of Python free-running"


def c_step(r: Result) -> list[str]:
    out = []
    for d in r["rows"]:
        dq = "" if d["diff_q"] is None else f", joints {d['diff_q']:.1e} rad"
        free = " free-running" if "c_step_diff" in d else ""
        per_step = "" if not free else f"; one step from the same state {d['c_step_diff']:.1e}"
        what = (f"EKF with friction: {d['observer_friction']}, {d['substeps']} RK4 substeps" if d["model"] != "hand"
                else "five chains' EKFs with friction and the ab/adduction PD, on the cylinder")
        passes = (f", the best of {d['c_passes']} passes; median {d['c_cpu_us_median']:.1f}" if "c_passes" in d
                  else "")
        if "c_us_min" in d:  # the goal's figure: each step's minimum over the passes (c_step.py's time rule)
            passes += f"; each step's minimum over the passes {d['c_us_min']:.1f}, median {d['c_us_median']:.1f}"
        out.append(f"{d['model']} {d['controller']} ({what}): C step {d['c_us']:.1f} µs "
                   f"({d['c_cpu_us']:.1f} processor{passes}) "
                   f"vs Python step "
                   f"{d['py_us']:.0f} µs ({d['c_vs_py']:.3f}x); built at -O2 in {d['c_build_s']:.1f} s "
                   f"({d['c_build_cpu_s']:.1f} s of the compiler's processor time) "
                   f"({d['c_source_kb']:.0f} kB of C); C - Python{free}: commands {d['diff_command']:.1e} N m{dq}, "
                   f"forces {d['diff_force']:.1e} N{per_step}; goals {_met(d['goals_met'])}")
    hand = f" ({r['goal_hand_us']:.0f} µs for the hand)" if "goal_hand_us" in r else ""
    timed = ("per step (each step's minimum over the passes)" if all("c_us_min" in d for d in r["rows"])
             else "of processor time per step")
    out.append(f"load average {r['load_avg'][0]:.1f} -> {r['load_avg'][1]:.1f}; goals: under {r['goal_us']:.0f} µs "
               f"{timed}{hand}, built in under {r['goal_build_s']:.0f} s of processor time, within "
               f"{r['goal_diff']:.0e}")
    return out


SUMMARIES: dict[str, Callable[[Result], list[str]]] = {
    "dynamics": dynamics, "observability": observability, "allegro": allegro,
    "rollout": rollout, "mimic": mimic, "identification": identification, "fit_scaling": fit_scaling,
    "observer_step": observer_step, "observer_build": observer_build, "param_cache": param_cache, "sweep": sweep,
    "control": control, "hand_control": hand_control, "urdf_control": urdf_control, "any_robot": any_robot,
    "allegro_identify": allegro_identify, "foreign_hands": foreign_hands, "realism": realism, "default_path": default_path,
    "force_realism": force_realism, "force_realism.hand": force_realism, "realism.friction": realism_friction,
    "realism.stick_ramp": realism_friction, "realism.creep": realism_friction,
    "observer_law": observer_law,
    "fit_scaling.hand": fit_scaling, "bench_loop": bench_loop, "bench_loop.hand": bench_loop,
    "bench_loop.thumb": bench_loop, "c_step": c_step,
}

ORDER = ["bench_loop", "default_path", "force_realism", "realism", "observer_law", "long_records", "identification", "fit_scaling", "observability",
         "allegro", "dynamics", "rollout", "observer_step", "c_step", "observer_build", "param_cache", "control", "hand_control",
         "urdf_control", "any_robot", "foreign_hands", "allegro_identify", "mimic", "sweep"]
"""The page's order: the lead issues' benchmarks first."""

HEADLINES: dict[str, tuple[str, Callable[[Result], str]]] = {
    "observability": ("observability of the whole hand (30 states, rank test over the state space)",
                      lambda r: f"{r['hand']['ours']['seconds']:.2f} s in process; `alpes-dyn observability --model hand` "
                                f"{r['cli_hand']['seconds']:.2f} s with process start"),
    "identification": ("identification of a finger (K, m, friction; 4 s record)", _identification_headline),
    "fit_scaling": ("identify on long records (`alpes-dyn identify` on `alpes-dyn experiment --duration` records)",
                    lambda r: "; ".join(f"{d['duration_s']:.0f} s {d['seconds']:.0f} s, {d['peak_rss_mib']:.0f} MiB"
                                        for d in r["rows"])
                    + f" ({r['model']}, ratios to the {r['rows'][0]['duration_s']:.0f} s fit "
                      f"{', '.join(format(d['time_ratio'], '.1f') + 'x' for d in r['rows'][1:])} in time)"),
    "default_path": ("the default path on every draw: `experiment` then `identify`, no options, fingers drawn +-20 %",
                     _default_path_headline),
    "realism": ("identify and the EKF on MuJoCo plants drawn +-20 % with every effect of a real hand",
                _realism_headline),
    "observer_step": ("EKF step for a real-time loop / standalone C", _observer_step_headline),
    "bench_loop": ("the whole workflow through the hardware interface on the MuJoCo stand-in, truth hidden",
                   _bench_loop_headline),
    "sweep": ("sweeps on a local Dask cluster (2 workers)",
              lambda r: f"{r['median_speedup']:.2f}x the serial loop over {r['draws']} draws, {r['rounds']} round(s) "
                        f"({r['median_speedup_vs_1thread']:.2f}x the loop on one thread)"),
}
"""The README's generated rows: ``(what, figure)``, ``figure(result)`` the text."""

HEADLINE_ORDER = ["observability", "bench_loop", "default_path", "force_realism", "realism", "identification", "fit_scaling",
                  "observer_step", "sweep"]
"""The README's rows in order; a name without a record or a figure keeps its row of ``_handwritten.README_ROWS``."""
