"""The observer's friction law with the plant's whole truth (issue 50, items 2 and 5): the EKF on the friction
study's validation run (:mod:`alpes_dyn.studies.realism_friction`, its cases: MuJoCo's dry friction soft or stiff,
at 1x and 3x the draw's F_s, alone or with every other effect of a real hand) with the plant's true file
(:func:`alpes_dyn.bench.truth.write_truth`: the drawn finger with the tilt, the encoder's zero, the delay, the
cable's compliance and rotor and the torque constant in the file; what it cannot hold named), no fit, each observer
friction law (``smooth`` F_s tanh(v / v_s), ``stick`` the switched law, ``lugre`` the bristle state:
:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`). Per case, law and seed
(:func:`~alpes_dyn.studies.realism_friction.true_file_row`): the worst joint's RMSE after 1 s (deg) and each
joint's NEES against its 95 % band; per case and law the median and worst over the seeds; per friction kind (the
cases' ``constraint``, soft or stiff) the law whose worst joint is smallest over the kind's rows that ran every law
(``choice``). The observer's default law is not this choice
(:func:`~alpes_dyn.simulation.stick.observer_friction_law`: ``lugre`` for a LuGre file, else ``smooth``): as the
default for the files ``identify --effects stiction`` writes, the stick law's predictions failed identify's own
observer check (the CHANGELOG); ``--friction-law stick`` asks for it.

    python benchmarks/observer_law.py [--cases soft,stiff_3x,...] [--seeds 10101-10102] [--laws smooth,stick,lugre]
                                      [--log FILE | --from-log FILE] [--json]

Every case runs on every seed given. ``--log`` appends each row as a JSON line (a stopped run resumes: the rows
already in it are not measured again); ``--from-log`` reads the rows of one or more logs (comma-separated) and
measures nothing. The recorded run (``benchmarks/results/observer_law.json``): each case's own two draws, its
rows logged, then

    python benchmarks/record.py observer_law --from-log a.jsonl,b.jsonl --json
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from _table import cell
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.simulation.stick import FRICTION_LAWS
from alpes_dyn.studies.realism import EKF_GOAL_DEG, parse_seeds
from alpes_dyn.studies.realism_friction import FRICTION_CASE_NAMES, FRICTION_CASES, true_file_row


def read_logs(paths: str) -> list[dict]:
    """The rows of the comma-separated JSON-lines logs ``paths`` (the last row of a case and seed kept)."""
    rows = {}
    for p in paths.split(","):
        for line in Path(p).read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                rows[(r["case"], r["seed"])] = r
    return list(rows.values())


def _stats(values: list[float]) -> dict:
    return {"median": float(np.median(values)), "worst": float(np.max(values))} if values else \
        {"median": None, "worst": None}


def summary(rows: list[dict]) -> dict:
    """Per case and law: ``rmse_worst_joint_deg`` (median / worst over the seeds of the worst joint),
    ``nees_worst_joint`` (likewise, the largest joint NEES), ``joints_consistent`` (the fraction of joints in their
    band), ``within_goal`` (rows whose every joint is within :data:`EKF_GOAL_DEG`), ``rows``; per friction kind
    ``choice``: the law with the smallest worst joint over the kind's rows that ran every law of
    :data:`FRICTION_LAWS` (ties: the first), with those rows' ``cases``; ``raised``: the rows whose plant did not
    run (case, seed, the error)."""
    kind = {c.name: c.constraint for c in FRICTION_CASES}
    raised = [{"case": r["case"], "seed": r["seed"], "error": r["error"]} for r in rows if "error" in r]
    rows = [r for r in rows if "error" not in r]
    cases: dict = {}
    for r in rows:
        for law, v in r["laws"].items():
            cases.setdefault(r["case"], {}).setdefault(law, []).append(v)
    out = {"cases": {}, "choice": {}, "raised": raised}
    for case, laws in cases.items():
        out["cases"][case] = {law: {
            "rmse_worst_joint_deg": _stats([max(v["rmse_deg"]) for v in vs]),
            "nees_worst_joint": _stats([max(v["nees"]["per_joint"]) for v in vs]),
            "joints_consistent": float(np.mean([c for v in vs for c in v["nees"]["joints_consistent"]])),
            "within_goal": sum(max(v["rmse_deg"]) <= EKF_GOAL_DEG for v in vs), "rows": len(vs)}
            for law, vs in laws.items()}
    for k in sorted(set(kind.values())):
        every = [r for r in rows if kind[r["case"]] == k and set(FRICTION_LAWS) <= set(r["laws"])]
        if every:
            worst = {law: max(max(r["laws"][law]["rmse_deg"]) for r in every) for law in FRICTION_LAWS}
            out["choice"][k] = {"law": min(worst, key=worst.get), "worst_joint_deg": worst,
                                "cases": sorted({r["case"] for r in every}), "rows": len(every)}
    return out


def text(out: dict) -> str:
    """The table: per case and law, the worst joint's RMSE and NEES (median / worst), the joints consistent."""
    lines = [f"{'case':<13}{'law':<8}{'RMSE deg med':>13}{'worst':>8}{'NEES med':>10}{'worst':>9}"
             f"{'consistent':>11}{'<=goal':>8}"]
    for case, laws in out["summary"]["cases"].items():
        for law, s in laws.items():
            r, n = s["rmse_worst_joint_deg"], s["nees_worst_joint"]
            lines.append(f"{case:<13}{law:<8}{cell(r['median'], '13.2f')}{cell(r['worst'], '8.2f')}"
                         f"{cell(n['median'], '10.1f')}{cell(n['worst'], '9.1f')}{s['joints_consistent']:>11.2f}"
                         f"{s['within_goal']:>5d}/{s['rows']}")
    for k, c in out["summary"]["choice"].items():
        lines.append(f"{k}: {c['law']} (worst joint " + ", ".join(f"{law} {v:.2f}" for law, v in
                                                                 c["worst_joint_deg"].items()) + " deg)")
    lines += [f"raised {x['case']} seed {x['seed']}: {x['error'][:150]}" for x in out["summary"]["raised"]]
    held = sorted({n.split(" ")[0] for r in out["rows"] for n in r.get("not_held", [])})
    lines.append("not held by the true file: " + (", ".join(held) or "none"))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", default=",".join(FRICTION_CASE_NAMES))
    ap.add_argument("--seeds", default="10101-10102")
    ap.add_argument("--laws", default=",".join(FRICTION_LAWS))
    ap.add_argument("--log", help="append each row to this JSON-lines file (resumes)")
    ap.add_argument("--from-log", help="read the rows of these logs (comma-separated), measure nothing")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    names, laws = args.cases.split(","), tuple(args.laws.split(","))
    bad = [c for c in names if c not in FRICTION_CASE_NAMES] + [w for w in laws if w not in FRICTION_LAWS]
    if bad:
        ap.error(f"unknown case or law: {', '.join(bad)}")
    if args.from_log:
        rows = read_logs(args.from_log)
    else:
        done = {(r["case"], r["seed"]) for r in read_logs(args.log)} if args.log and Path(args.log).exists() else set()
        rows = read_logs(args.log) if done else []
        for case in names:
            for seed in parse_seeds(args.seeds):
                if (case, seed) in done:
                    continue
                try:
                    row = true_file_row(case, seed, laws)
                except (InputError, ModelError) as exc:  # the plant that does not run: its row says why
                    row = {"case": case, "seed": seed, "error": str(exc)}
                rows.append(row)
                if args.log:
                    with open(args.log, "a") as f:
                        f.write(json.dumps(row) + "\n")
                print(f"{case} {seed}: " + (row.get("error") or ", ".join(
                    f"{w} {max(v['rmse_deg']):.2f} deg" for w, v in row["laws"].items())), file=sys.stderr, flush=True)
    out = {"rows": rows, "summary": summary(rows), "ekf_goal_deg": EKF_GOAL_DEG,
           "from_log": bool(args.from_log)}
    print(json.dumps(out) if args.json else text(out))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
