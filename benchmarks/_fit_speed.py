"""``fit_scaling.py --speed CASE``: ``identify --effects auto`` on one friction case's MuJoCo record (issue 50's
study, :func:`alpes_dyn.studies.realism_friction.friction_row`'s fit), the old path and the new one in the same
process, each round's time, the observer check's, and the two fits compared.

The old path: the observer check's predictions (:mod:`alpes_dyn.estimation.observers.ahead`) in CasADi's virtual
machine, as before they were compiled (``ahead._loop`` returning None: the fallback without a C compiler, the same
expressions mapped over the starts). The new path: the compiled loop. Each fit is the whole ``fit_effects`` as
the study calls it (``--effects auto``, the law spread); wall and CPU time (the machine is shared: CPU is the fit's
own work), the observer check's time summed over every check made (the walk judges the kept fit again after each
``auto`` stage and the rounds as good a fit).
"""

from __future__ import annotations

import contextlib
import os
import time
from typing import Any
from unittest import mock

import numpy as np


def _cpu() -> float:
    """CPU seconds of this process (user and system, every thread)."""
    return time.process_time()


def _record(case: str, seed: int, duration: float):
    """The case's MuJoCo record of ``duration`` s on finger3 drawn with ``seed``, as the study makes it."""
    from alpes_dyn.studies.realism import FINGER3, plant_experiment, rig_design
    from alpes_dyn.studies.realism_friction import FRICTION_CASE_NAMES, FRICTION_CASES

    c = FRICTION_CASES[FRICTION_CASE_NAMES.index(case)]
    rec, design, _, _ = plant_experiment(c.effects(), seed, rig_design("level", duration), c.true_params(seed),
                                         FINGER3, "auto")
    return rec, design


def _fit(rec: Any, design: Any, old: bool) -> dict[str, Any]:
    """One ``fit_effects`` as the study calls it, timed; ``old``: the observer's predictions in the VM."""
    from alpes_dyn.estimation.identification import observer_check as oc
    from alpes_dyn.estimation.identification.effects import alpes_models, fit_effects, parse_effects
    from alpes_dyn.estimation.observers import ahead
    from alpes_dyn.model.params import load_params
    from alpes_dyn.studies.realism import FINGER3, FIT_EFFECTS, on_rig, rig_of

    rig = rig_of(design)
    model_of = alpes_models(FINGER3.model, load_params(), chain=FINGER3.chain)
    checks: list[tuple[float, float]] = []
    inner = oc.observer_check

    def timed(*a: Any, **k: Any) -> Any:
        t, c = time.perf_counter(), _cpu()
        out = inner(*a, **k)
        checks.append((time.perf_counter() - t, _cpu() - c))
        return out

    t0, c0 = time.perf_counter(), _cpu()
    with contextlib.ExitStack() as stack:
        stack.enter_context(mock.patch.object(oc, "observer_check", timed))
        if old:
            stack.enter_context(mock.patch.object(ahead, "_loop", lambda filt, covariance: None))
        fit = fit_effects(lambda e: on_rig(model_of(e), rig), rec, parse_effects(FIT_EFFECTS), FINGER3.base,
                          rec.gravity is not None, excitation=design.lines, progress=False, spread=True)
    wall, cpu = time.perf_counter() - t0, _cpu() - c0
    res, a = fit.result, fit.result.adequacy
    obs = fit.observer
    return {"wall_s": wall, "cpu_s": cpu, "observer_wall_s": sum(w for w, _ in checks),
            "observer_cpu_s": sum(c for _, c in checks), "observer_checks": len(checks),
            "rounds": [{"effects": list(e), "seconds": r.seconds, "iterations": r.iterations,
                        "converged": bool(r.converged), "residual_counts": r.residual_rms} for e, r in fit.rounds],
            "effects": list(fit.effects), "names": list(res.names), "values": res.values.tolist(),
            "std": res.std.tolist(), "adequate": None if a is None else bool(a.adequate),
            "trustworthy": bool(res.trustworthy), "reasons": [] if a is None else list(a.reasons),
            "observer": None if obs is None else {
                "passed": bool(obs.passed), "innovation_rms": obs.innovation_rms,
                "prediction_rms": obs.prediction_rms,
                "nis": [None if v is None else v.value for v in (obs.nis, obs.prediction_nis, obs.split_nis)]}}


def _rel(a: Any, b: Any) -> float:
    """The largest relative difference of two lists of numbers (None entries skipped), 0 where both are empty."""
    pa = [x for x in np.ravel(a) if x is not None]
    pb = [x for x in np.ravel(b) if x is not None]
    if len(pa) != len(pb):
        return float("inf")
    if not pa:
        return 0.0
    x, y = np.asarray(pa, float), np.asarray(pb, float)
    return float(np.max(np.abs(x - y) / np.maximum(np.abs(y), 1e-300)))


def speed(case: str, seed: int, duration: float) -> dict[str, Any]:
    """The record, then the old path's fit and the new one's in this process (old first: the imports and the
    sensitivities' libraries warm for both; the new path's compiled prediction loaded from the disk cache, or built
    in its time where the cache is cold); the comparison."""
    import warnings

    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    rec, design = _record(case, seed, duration)
    record_s = time.perf_counter() - t0
    old = _fit(rec, design, old=True)
    new = _fit(rec, design, old=False)
    same = {"values_max_rel": _rel(new["values"], old["values"]), "std_max_rel": _rel(new["std"], old["std"]),
            "effects": new["effects"] == old["effects"], "adequate": new["adequate"] == old["adequate"],
            "trustworthy": new["trustworthy"] == old["trustworthy"],
            "observer_passed": (new["observer"] or {}).get("passed") == (old["observer"] or {}).get("passed"),
            "observer_max_rel": _rel([(o or {}).get(k) for o in (new["observer"],) for k in ("innovation_rms",
                                      "prediction_rms")] + list((new["observer"] or {}).get("nis", [])),
                                     [(o or {}).get(k) for o in (old["observer"],) for k in ("innovation_rms",
                                      "prediction_rms")] + list((old["observer"] or {}).get("nis", [])))}
    return {"case": case, "seed": seed, "duration_s": duration, "record_s": record_s, "load_start": os.getloadavg(),
            "old": old, "new": new, "same": same,
            "ratio": {"wall": old["wall_s"] / new["wall_s"], "cpu": old["cpu_s"] / new["cpu_s"],
                      "observer_wall": old["observer_wall_s"] / max(new["observer_wall_s"], 1e-9),
                      "observer_cpu": old["observer_cpu_s"] / max(new["observer_cpu_s"], 1e-9)}}


def table(r: dict[str, Any]) -> None:
    """The speed run as a table: each round's fit time, the observer checks', the totals, old and new."""
    print(f"{r['case']} seed {r['seed']}, {r['duration_s']:g} s record: identify --effects auto, old path vs new "
          f"(same process; load {r['load_start'][0]:.1f})")
    print(f"{'round':<44} {'old s':>7} {'new s':>7} {'its':>4} {'conv':>5} {'resid':>6}")
    for a, b in zip(r["old"]["rounds"], r["new"]["rounds"]):
        print(f"{'+'.join(b['effects']):<44} {a['seconds']:7.1f} {b['seconds']:7.1f} {b['iterations']:4d} "
              f"{str(b['converged']):>5} {b['residual_counts']:6.3f}")
    o, n = r["old"], r["new"]
    print(f"{'observer checks (' + str(n['observer_checks']) + ')':<44} {o['observer_wall_s']:7.1f} "
          f"{n['observer_wall_s']:7.1f}   cpu {o['observer_cpu_s']:.1f} -> {n['observer_cpu_s']:.1f} s")
    print(f"{'total':<44} {o['wall_s']:7.1f} {n['wall_s']:7.1f}   cpu {o['cpu_s']:.1f} -> {n['cpu_s']:.1f} s; "
          f"ratio wall {r['ratio']['wall']:.2f}x, cpu {r['ratio']['cpu']:.2f}x; observer cpu "
          f"{r['ratio']['observer_cpu']:.2f}x")
    s = r["same"]
    print(f"same fit: values within {s['values_max_rel']:.1e}, std {s['std_max_rel']:.1e}, effects {s['effects']}, "
          f"verdict {s['adequate'] and s['trustworthy']}, observer {s['observer_passed']} "
          f"(its statistics within {s['observer_max_rel']:.1e})")
