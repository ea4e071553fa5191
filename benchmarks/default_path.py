"""The default path on every draw (issue 35): ``alpes-dyn experiment`` then ``alpes-dyn identify``, no options.

For each seed of the +-20 % tolerance family (``--perturb 0.2``; the true file written with ``--true-params-out``):

    alpes-dyn experiment --model MODEL --perturb 0.2 --seed S -o rec.csv --true-params-out true.toml
    alpes-dyn identify --model MODEL --data rec.csv -o ident.toml --json

run in this process (the commands' own ``main``), as a user types them. Per draw: the design the experiment chose
(``--rig auto``: palm up unless the finger leaves its range there), identify's exit code (0 written, 3 refused),
the worst error of the springs K and of the masses m against the true file, the parameters the fit reported not
identified, and the fit's time (every round; cache warm after the first draw). The goals: exit 0 on every draw,
K within 3 %, m within 5 %, and no written file holding a value outside its physical range (a negative compliance,
friction, mass or spring: checked on the file read back). ``--json``: one object, the rows and per model their
summary with ``goal_met`` (:func:`summary`).

    python benchmarks/default_path.py [--models finger3,finger2,hand] [--seeds 1-60] [--json] [--log FILE]

``--models hand``: the whole hand in one experiment (``experiment --model hand``: the six motors at once, one
recording) fitted chain by chain from it (``identify --model hand``, one file); the errors per chain.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

from _table import cell


def _run(argv: list[str]) -> tuple[int, str, str]:
    from alpes_dyn.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def _physical(path: Path) -> list[str]:
    """The fields of an identified file outside their physical range (none expected: the loader refuses them)."""
    data = tomllib.loads(path.read_text())
    bad = []
    for sec in ("finger", "transmission", "thumb"):
        for key, entry in data.get(sec, {}).items():
            if isinstance(entry, dict) and entry.get("source") == "identified":
                v = np.atleast_1d(np.asarray(entry["value"], dtype=float))
                if key in ("K", "m", "I", "F_s", "F_v", "tendon_compliance", "J_m") and np.any(v < 0):
                    bad.append(f"{sec}.{key}")
    return bad


def chain_errors(ident: Path, true: Path, model: str) -> dict[str, tuple[float, float]]:
    """Each chain's worst K and m error (%) of the identified file against the true one (the fingers' own values
    ``[finger.<name>]`` and ``[thumb]`` on the hand; the shared ``[finger]`` on a finger model)."""
    from alpes_dyn.model.params import load_params

    got, want = load_params(ident), load_params(true)
    chains = (tuple(want.finger_names) + ("thumb",)) if model == "hand" else ("thumb",) if model == "thumb" \
        else ("finger",)
    n = 2 if model == "finger2" else None  # finger2 is the first two links of the finger's values
    out = {}
    for c in chains:
        g, w = got.chain(c), want.chain(c)
        out[c] = (float(np.max(np.abs(g.K[:n] / w.K[:n] - 1))) * 100,
                  float(np.max(np.abs(g.m[:n] / w.m[:n] - 1))) * 100)
    return out


def draw(model: str, seed: int, tmp: Path) -> dict:
    rec, true, ident = tmp / f"{model}-{seed}.csv", tmp / f"{model}-{seed}-true.toml", tmp / f"{model}-{seed}-id.toml"
    code, out, _ = _run(["experiment", "--model", model, "--perturb", "0.2", "--seed", str(seed), "-o", str(rec),
                         "--true-params-out", str(true), "--json"])
    if code != 0:
        return {"model": model, "seed": seed, "experiment_exit": code}
    design = json.loads(out)["design"]
    designs = design if model == "hand" else {"finger": design}
    t0 = time.perf_counter()
    code, out, err = _run(["identify", "--model", model, "--data", str(rec), "-o", str(ident), "--json"])
    wall = time.perf_counter() - t0
    row = {"model": model, "seed": seed, "experiment_exit": 0, "rig": next(iter(designs.values()))["rig"],
           "amplitude_scale": min(d["amplitude_scale"] for d in designs.values()),
           "design_note": "; ".join(d["note"] for d in designs.values() if d["note"]), "identify_exit": code,
           "identify_wall_s": wall}
    if code not in (0, 3):
        row["error"] = err.strip()[:300]
        return row
    res = json.loads(out)
    fits = res["chains"] if model == "hand" else {"finger": res}
    row.update(trustworthy=res["trustworthy"],
               not_identified=sorted(f"{c}:{n}" if model == "hand" else n for c, r in fits.items()
                                     for n in r.get("not_identified", {})),
               refused={c: "; ".join((r.get("adequacy") or {}).get("reasons", [])) or r["reason"]
                        for c, r in fits.items() if not r["trustworthy"]})
    if code == 0:
        per = chain_errors(ident, true, model)
        row["chains"] = {c: {"K_err_pct": k, "m_err_pct": m} for c, (k, m) in per.items()}
        row["K_err_pct"] = max(k for k, _ in per.values())
        row["m_err_pct"] = max(m for _, m in per.values())
        row["unphysical_fields"] = _physical(ident)
    return row


def table(rows: list[dict]) -> str:
    lines = [f"{'model':8} {'seed':>4} {'rig':8} {'amp':>4} {'exit':>4} {'K %':>6} {'m %':>6} {'fit s':>6}  not identified"]
    for r in rows:
        lines.append(f"{r['model']:8} {r['seed']:4d} {r.get('rig', '-'):8} {cell(r.get('amplitude_scale'), '4.2f')} "
                     f"{r.get('identify_exit', r['experiment_exit']):4d} {cell(r.get('K_err_pct'), '6.2f')} "
                     f"{cell(r.get('m_err_pct'), '6.2f')} {cell(r.get('identify_wall_s'), '6.1f')}  "
                     f"{', '.join(r.get('not_identified', []))}")
    for model in sorted({r["model"] for r in rows}):
        rs = [r for r in rows if r["model"] == model]
        ok = [r for r in rs if r.get("identify_exit") == 0]
        K = [r["K_err_pct"] for r in ok]
        m = [r["m_err_pct"] for r in ok]
        lines.append(f"{model}: {len(ok)}/{len(rs)} exit 0; hung {sum(r.get('rig') == 'hanging' for r in rs)}; "
                     f"K worst {max(K, default=float('nan')):.2f} % (median {np.median(K) if K else float('nan'):.2f}), "
                     f"m worst {max(m, default=float('nan')):.2f} % (median {np.median(m) if m else float('nan'):.2f}); "
                     f"over K 3 %: {sum(k > 3 for k in K)}, over m 5 %: {sum(x > 5 for x in m)}; "
                     f"unphysical files: {sum(bool(r.get('unphysical_fields')) for r in rs)}")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--models", default="finger3,finger2")
    ap.add_argument("--seeds", default="1-60")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--log", default=None, help="append each row as a JSON line to this file as it comes")
    args = ap.parse_args()
    from alpes_dyn.studies.realism import parse_seeds  # the benchmarks' one reader of --seeds

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for model in args.models.split(","):
            for seed in parse_seeds(args.seeds):
                row = draw(model, seed, Path(tmp))
                rows.append(row)
                if args.log:
                    with open(args.log, "a") as f:
                        f.write(json.dumps(row) + "\n")
    out = {"models": args.models.split(","), "seeds": parse_seeds(args.seeds), "rows": rows, "summary": summary(rows)}
    print(json.dumps(out) if args.json else table(rows))
    return 0


def summary(rows: list[dict]) -> dict:
    """Per model: the draws, how many exited 0, hung, scaled; the worst and median K and m errors (%) of the files
    written; the draws over K 3 % or m 5 %; the files holding a non-physical value; ``goal_met``: every draw exited 0
    within K 3 % and m 5 % and no file is non-physical."""
    out = {}
    for model in dict.fromkeys(r["model"] for r in rows):
        rs = [r for r in rows if r["model"] == model]
        ok = [r for r in rs if r.get("identify_exit") == 0]
        K, m = [r["K_err_pct"] for r in ok], [r["m_err_pct"] for r in ok]
        s = {"n": len(rs), "exit_0": len(ok), "hung": sum(r.get("rig") == "hanging" for r in rs),
             "scaled": sum((r.get("amplitude_scale") or 1.0) != 1.0 for r in rs),
             "K_pct": {"worst": max(K, default=None), "median": float(np.median(K)) if K else None},
             "m_pct": {"worst": max(m, default=None), "median": float(np.median(m)) if m else None},
             "over_K": [r["seed"] for r in ok if r["K_err_pct"] > 3], "over_m": [r["seed"] for r in ok if r["m_err_pct"] > 5],
             "refused": [r["seed"] for r in rs if r.get("identify_exit") != 0],
             "unphysical": [r["seed"] for r in rs if r.get("unphysical_fields")],
             "fit_seconds_median": float(np.median([r["identify_wall_s"] for r in rs if "identify_wall_s" in r]))}
        s["goal_met"] = (s["exit_0"] == s["n"] and not s["over_K"] and not s["over_m"] and not s["unphysical"])
        out[model] = s
    return out


if __name__ == "__main__":
    sys.exit(main())
