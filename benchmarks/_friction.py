"""``benchmarks/realism.py --friction``: the friction cases of issue 50 (:mod:`alpes_dyn.studies.realism_friction`),
run seed after seed (every case of a seed before the next seed: a run stopped part-way has the same draws for each
case), and their table (run as ``python benchmarks/realism.py``: this folder is on the path)."""

from __future__ import annotations

import json
import tempfile
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any, Callable

from _table import case_notes, median_worst  # this folder is on the path
from alpes_dyn.studies.realism import EKF_GOAL_DEG, FIT_EFFECTS
from alpes_dyn.studies.realism_friction import (FRICTION_CASES, FRICTION_CASE_NAMES, RAMP_SECONDS, RAMP_TORQUE,
                                                complete_seeds, friction_row, friction_summary)


def friction_output(rows: list[dict], names: list[str], design: Any, rig: str, adapt: str,
                    case_seconds: dict[str, float], **extra: Any) -> dict[str, Any]:
    """The ``--json`` object: the rows of the cases of ``names`` (a case and seed measured twice, by two runs sharing
    a log: the first row kept), each case's seeds (``case_seeds``; ``incomplete_seeds``: the seeds some case of
    ``names`` lacks), the case table, the distribution per case over its own draws
    (:func:`~alpes_dyn.studies.realism_friction.friction_summary`)."""
    rows = list({(r["case"], r["seed"]): r for r in reversed(rows)}.values())[::-1]  # the first of each pair
    complete = complete_seeds(rows, names)
    seeds = sorted({r["seed"] for r in rows if r["case"] in names})
    kept = sorted((r for r in rows if r["case"] in names), key=lambda r: (seeds.index(r["seed"]), names.index(r["case"])))
    return {"model": "finger3", "friction": True, "seeds": seeds,
            "case_seeds": {c: [r["seed"] for r in kept if r["case"] == c] for c in names},
            "incomplete_seeds": [s for s in seeds if s not in complete],
            "cases": [asdict(c) for c in FRICTION_CASES if c.name in names], "duration_s": design.duration,
            "rig": rig, "adapt": adapt, "fit_effects": FIT_EFFECTS,
            "validation": {"scenario_s": 5.0, "ramp_s": RAMP_SECONDS, "ramp_torque_Nm": RAMP_TORQUE},
            "case_seconds": case_seconds, "rows": kept, "summary": friction_summary(kept), **extra}


def run_friction(names: list[str], seeds: list[int], design: Any, adapt: str,
                 log: Callable[[list[dict]], None], check_ramp: bool = False) -> dict[str, float]:
    """Each seed's rows, every case of ``names`` in turn (:func:`~alpes_dyn.studies.realism_friction.friction_row`),
    each handed to ``log`` as measured (a run that raised: a row with ``error``); returns the seconds per case.
    ``check_ramp``: the fit's observer check judged on a held-out slow record (``identify --validate``)."""
    seconds = dict.fromkeys(names, 0.0)
    with tempfile.TemporaryDirectory() as d:
        for s in seeds:
            for c in names:
                t0 = time.perf_counter()
                try:
                    row = friction_row(c, s, design, Path(d), adapt, check_ramp=check_ramp)
                except Exception as exc:  # a run that raised (the plant diverged, ...): counted apart
                    row = {"case": c, "seed": s, "chain": "finger3", "error": f"{type(exc).__name__}: {exc}"}
                log([row])
                seconds[c] += time.perf_counter() - t0
    return seconds


def read_log(path: str) -> list[dict]:
    """The rows of a run's ``--log`` file (one JSON object a line); ValueError with the reason."""
    try:
        rows = [json.loads(x) for x in Path(path).read_text(encoding="utf-8").splitlines() if x.strip()]
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ValueError(f"cannot read {path}: {e}") from None
    if not rows or not all(isinstance(r, dict) and r.get("case") in FRICTION_CASE_NAMES and "seed" in r
                           for r in rows):
        raise ValueError(f"{path} holds no rows of the friction cases (JSON objects with case and seed)")
    return rows


def _short(verdict: str) -> str:
    return "adequate" if verdict == "adequate" else "REFUSED"


def _band(n: dict | None) -> str:
    """A row's joints' NEES with the sigma ``estimate`` reports (the band's, ``nees_band``): 'lo-hi' over the
    joints, ``!`` where one is outside its band; '--' in rows without it."""
    if not n:
        return "--"
    return f"{min(n['per_joint']):.2f}-{max(n['per_joint']):.2f}{'' if all(n['joints_consistent']) else '!'}"


def friction_text(out: dict) -> str:
    """The table: per row the verdict, the springs' and masses' worst errors up to the common scale, the EKF's worst
    joint with the identified and the true file, the worst joint NEES of each with the filter's P alone (``!``
    outside its band) and the range of the joints' NEES with the sigma ``estimate`` reports (the band's) and the
    largest |error / standard error|; then the distribution per case with the silent misses and the refusals (the
    parameters within 3 standard errors, and within 3 of the noise's alone: the classical or HAC sandwich's)."""
    v = out["validation"]
    lines = [f"finger3, friction cases, seeds {out['seeds']} (not measured on every case: {out['incomplete_seeds']}), "
             f"{out['duration_s']:g} s experiment, rig {out['rig']} (adapt {out['adapt']}), identify --effects "
             f"{out['fit_effects']}; validation: the estimate scenario's torque ({v['scenario_s']:g} s) "
             f"then a {v['ramp_s']:g} s ramp of +-{1e3 * v['ramp_torque_Nm']:g} mN m",
             f"{'case':12} {'seed':>4} | {'verdict':>8} {'K%':>6} {'m%':>6} | {'EKF deg ident':>19} | "
             f"{'EKF deg true':>19} | {'NEES ident':>10} {'NEES true':>10} | {'sigma ident':>11} {'sigma true':>10} | "
             f"{'|z| max':>7}"]
    for r in out["rows"]:
        if "error" in r:
            lines.append(f"{r['case']:12} {r['seed']:>4} | RAISED {r['error'][:140]}")
            continue
        e, w = r["extended"], r["extended"]["worst_error_common_scale_pct"]
        n_i, n_t = r["nees"], r["nees_true_file"]
        lines.append(
            f"{r['case']:12} {r['seed']:>4} | {_short(e['verdict']):>8} {w['K']:6.2f} {w['m']:6.1f} | "
            f"{' / '.join(f'{x:.2f}' for x in r['ekf_rmse_deg']):>19} | "
            f"{' / '.join(f'{x:.2f}' for x in r['ekf_true_file_rmse_deg']):>19} | "
            f"{max(n_i['per_joint']):9.3g}{'' if all(n_i['joints_consistent']) else '!'} "
            f"{max(n_t['per_joint']):9.3g}{'' if all(n_t['joints_consistent']) else '!'} | "
            f"{_band(r.get('nees_band')):>11} {_band(r.get('nees_true_file_band')):>10} | "
            f"{max(map(abs, r['z'].values()), default=0.0):7.2f}")
    lines.append(f"distribution per case (median / worst); silent miss: adequate but EKF > {EKF_GOAL_DEG:g} deg "
                 f"on a joint (or m over its goal); NEES: rows with a joint outside its 95 % band")
    lines.append(f"{'case':12} {'n':>3} | {'K %':>13} {'m %':>13} | {'EKF ident deg':>13} {'EKF true deg':>13} | "
                 f"{'adequate':>8} {'silent':>6} {'refused':>7} {'raised':>6} | {'NEES out':>8} {'true':>4} "
                 f"{'sigma out':>9} {'true':>4} | "
                 f"{'|z| max':>7} {'<=3':>4} {'noise':>5}")

    mw = median_worst
    for c, s in out["summary"].items():
        zn = s.get("z_noise_within_3")
        z = "--" if s["z_worst"] is None else (f"{s['z_worst']:7.1f} {100 * s['z_within_3']:3.0f}% "
                                               f"{'--' if zn is None else f'{100 * zn:3.0f}%':>5}")
        lines.append(f"{c:12} {s['n']:>3} | {mw(s['K_pct'], '5.2f'):>13} {mw(s['m_pct'], '5.1f'):>13} | "
                     f"{mw(s['ekf_deg'], '5.2f'):>13} {mw(s['ekf_true_file_deg'], '5.2f'):>13} | "
                     f"{s['adequate']:>8} {len(s['silent_misses']):>6} {len(s['refusals']):>7} {len(s['errors']):>6} | "
                     f"{s['nees_inconsistent']:>8} {s['nees_true_file_inconsistent']:>4} "
                     f"{s['nees_band_inconsistent']:>9} {s['nees_true_file_band_inconsistent']:>4} | {z}")
        lines += case_notes(s)
    return "\n".join(lines)
