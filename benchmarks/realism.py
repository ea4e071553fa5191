"""Realism benchmark (issue 16): today's identification and EKF on MuJoCo plants with the effects of a real hand.

The identification benchmark fits data from the library's own simulator, whose structure is the fitted
model's. Here the plant is the finger exported to MuJoCo (:mod:`alpes_dyn.control.plants`: joint stops on,
RK4 at 0.1 ms, our encoder and torque sensors at 1 kHz), finger3 drawn +-20 % per link
(:func:`~alpes_dyn.estimation.experiments.experiment.perturbed_params`, seeds 11, 12, 13 by default: the identification
benchmark uses 1-4; issue 38's fresh draws: ``--seeds 401-420``), with one effect of a real hand at a time, or all
of them:

========== ================================================================================================
case       the plant
========== ================================================================================================
none       the model's own structure (its smooth friction law applied in MuJoCo by a passive callback)
stiction   stick-slip dry friction: MuJoCo's frictionloss F_s, a stiff constraint (0.5 ms, impedance 0.999)
tendon     a series-elastic, pull-only cable with the motor's rotor J_m on its own joint: k_t such that the
           cable stretches, under the experiment's mean tension, by 3 % of the tendon's travel from the
           springs' rest (printed: 3.97e4 N/m, the EA/L of a 0.3 mm Dyneema cable 0.15-0.2 m long),
           damping ratio 0.2 on the rotor-on-cable mode
rotor      the rotor inertia J_m on the rigid tendon: J_m S^T S added to the mass matrix (all entries)
tilt       the palm tilted by 3 degrees in the finger's plane (gravity rotated; the recording does not say)
kt         the torque constant 5 % off: the recorded torque is 1.05 times the true one
offset     the encoder's zero 4 counts off
slack      the series-elastic cable of ``tendon`` with 0.5 degree of slack (backlash) at the motor shaft: a dead band
           r_m radians(0.5) on the cable's stretch
delay      the torque measured one sample (1 ms) late
all        all of the above at once
========== ================================================================================================

Per case and seed: the identification experiment's torque (designed on the nominal file, the bias trimmed on
the true finger as it stands) replayed on the plant, and two fits of it:

* **rigid**: the rigid, smooth-friction model (K, m, F_s, F_v; ``alpes-dyn identify --effects none``), whose
  adequacy verdict must flag every plant with an effect and none with the model's own structure;
* **extended**: what ``alpes-dyn identify`` fits by default (``--effects auto``, :mod:`alpes_dyn.estimation.identification.effects`):
  the tendon's compliance and the palm's tilt, then rounds with the stick-slip law and the rotor where a fit asks
  for them (:func:`~alpes_dyn.estimation.identification.effects.fit_effects`), the lower residual kept; from the nominal file.
  Its time is every round's (``fit_seconds_total``; each round in ``rounds``).

For each, the worst error (%) of each kind, also up to the one common scale (exp of the mean log ratio over
K and m: the torque constant scales every parameter together, and the encoder cannot see it), the residual
(counts; the sensor floor is 0.58), ``converged``, the fit time, the verdict. Then the EKF
(:func:`~alpes_dyn.estimation.observers.replay.estimate_recording`, as ``alpes-dyn estimate --data``) on the extended
fit's file, with its fitted tilt and offset, and for comparison on the true file (rigid, level: it knows
neither), on a fresh run of the plant -- the experiment's design on other lines (0.4-12.7 Hz: a torque the fit
never saw), from the plant's rest -- from that run's recorded encoder and torque: RMSE after 1 s, deg per joint.
(The estimation scenario's torque is not used: it takes the nominal finger outside its joint range, into
MuJoCo's stops.) The verdict is the fit's adequacy check (:mod:`alpes_dyn.estimation.identification.adequacy`, in-sample:
whiteness, cross-correlation with the torque, residual against the sensor floor): "adequate", or "FLAGGED"
with the reason.

    python benchmarks/realism.py [--seeds 11,12,13 | 301-320] [--cases none,stiction,...] [--rig level|hanging] [--quick]
                                 [--json] [--log FILE]
    python benchmarks/realism.py --chains index,middle,ring,little,thumb [--hand-seed 5] [--cases ...]
    python benchmarks/realism.py ... --workers 2      # each case's seeds on a local Dask cluster (the same rows)
    python benchmarks/realism.py --from-log FILE [--json]   # the table of a run's --log rows, nothing measured
    python benchmarks/realism.py --friction [--seeds ...] [--cases soft,stiff_3x,...] [--log FILE | --from-log FILE]

``--rig hanging``: the hand hung fingers down during the experiments (:func:`~alpes_dyn.model.mjcf.hanging_gravity`),
the experiment designed and trimmed in that orientation, the fits and the EKF on the models turned to it (the
tilt cases' 3 degrees on top). Palm up, a finger with soft springs folds (its static equilibria snap through
before it reaches mid-range): held below the fold it rests on its stop, and no fit holds (5 of the 20 draws of
seeds 30-49). Hanging, none folds. ``--adapt auto`` (the default) does what ``alpes-dyn experiment --rig auto``
does, on the plant's own joint angles (:func:`~alpes_dyn.studies.realism.plant_experiment`): the whole record is
checked against the joints' range and the hand hung where palm up the finger leaves it, then the excitation scaled
to 0.7 and 0.5; the table's last column says which rig each row ran on (``l`` level, ``h`` hung, the scale where not
1, ``!`` where it adapted) and the JSON rows hold the ``adaptation``. ``--adapt none`` runs ``--rig`` as given.
``--adapt both`` does what ``alpes-dyn experiment --rig both`` does (issue 38): the first half of the record palm up,
the second hung fingers down, each its own run of the excitation, MuJoCo turned between them (its state carrying
on), the recording's gravity columns the two nominal orientations (the plant's 3 degree tilt on top of each, fitted);
palm up alone, then hung alone where the finger leaves its range (``b`` in the last column); the EKF's run palm up.

``--seeds`` takes ranges (``301-320,5``). After the rows, the distribution per case
(:func:`~alpes_dyn.studies.realism.summarise`): the median and worst of each kind's error up to the common scale,
of the EKF's worst joint (deg) and of the fit's time (every round and the observer's check); the **silent misses**
(the fit adequate, but the EKF above 0.5 degree on a joint or the masses more than 5 % off), the **refusals** (the
fit flagged) each with its verdict, and the runs that raised. ``--no-rigid`` skips the rigid fit (its columns "--").

``--quick``: one seed (the first) and a 2 s experiment.

``--friction`` (issue 50): the friction cases instead (:mod:`alpes_dyn.studies.realism_friction`, the table
:data:`~alpes_dyn.studies.realism_friction.FRICTION_CASES`): MuJoCo's own dry friction, ``soft`` (its default
constraint, ``solreffriction`` 0.02 s: the joints creep) or ``stiff`` (0.5 ms: they stick), at 1x and 3x the draw's
F_s (``_3x``), alone or with every other effect of a real hand (``all_``): 8 cases, run seed after seed (every case
of a seed before the next, so that a run stopped part-way keeps the same draws for each case; the summary holds the
seeds with every case). Per row: ``identify``'s verdict, the springs' and masses' worst errors up to the common
scale, the EKF's worst joint on a validation run the fit never saw (the ``estimate`` scenario's torque, then a slow
ramp through the stick band) with the identified file and with the true one, each joint's NEES against its 95 %
band, each parameter's error in units of its reported standard error; per case the worst of each and the silent
misses (adequate yet the EKF above 0.5 degree). Each parameter's error is given in its reported standard errors
(the noise's covariance and the friction law's spread, :mod:`alpes_dyn.estimation.identification.law_spread`) and
in the noise's alone (``z_noise``). A row costs 35 s on a quiet core (the fit 13 s, the two EKF runs 9 s, their
NEES 6 s, the two MuJoCo runs 5 s; compiles cached on disk across draws), a soft case's refused fit up to 13 min
(its rounds). The recorded run (``benchmarks/results/realism.friction.json``), the two groups of cases in two
processes, one log each::

    python benchmarks/realism.py --friction --cases stiff,stiff_3x,all_stiff,all_stiff_3x --seeds 10001-10020 --log stiff.jsonl
    python benchmarks/realism.py --friction --cases soft,soft_3x,all_soft,all_soft_3x --seeds 10001-10020 --log soft.jsonl
    cat stiff.jsonl soft.jsonl > friction.jsonl
    python benchmarks/realism.py --friction --from-log friction.jsonl --json            # its JSON, nothing measured
    python benchmarks/record.py realism --output benchmarks/results/realism.friction.json --friction --from-log FILE

``--chains``: the hand's chains instead of finger3, one at a time, each as ``alpes-dyn identify`` fits it (a finger
as ``--model finger3 --chain <name>``; the thumb as ``--model thumb``, its flexion springs, masses and friction,
:data:`~alpes_dyn.estimation.identification.identification.THUMB_PARAMETERS`, its ab/adduction on its own geared motor), from the nominal file; the
true hand is the nominal one with every chain drawn +-20 % (``perturbed_params(..., chains=<all the hand's
chains>)``, seed ``--hand-seed``, which also seeds the sensors' noise). The errors are over the parameters of the
chain's catalogue (:func:`~alpes_dyn.symbolic.parametric.parameter_catalogue`) that the fit holds and whose truth
is not 0 (not the tendon's compliance, the tilt or the encoder's offset, of the rig), up to the common scale over
its K and m. The cable of the tendon case is finger3's (the flexion tendon's; the thumb's geared ab/adduction
motor stays rigid).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
import time
import warnings
from pathlib import Path

from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.stick_ramp import STICK_SECONDS
from alpes_dyn.model.params import load_params
from alpes_dyn.model.stops import JointRangeWarning
from alpes_dyn.studies.realism import (ADAPT, CASE_NAMES, FINGER3, FIT_EFFECTS, MODEL, RIGS, STRETCH, cases, hand_plant,
                                       EKF_GOAL_DEG, MASS_GOAL_PCT, parse_seeds, realism_case, realism_row, rig_design,
                                       summarise, tendon_stiffness)
from alpes_dyn.studies.realism_friction import FRICTION_CASE_NAMES
from alpes_dyn.studies.sweep import local_client, sweep


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="11,12,13")
    ap.add_argument("--cases", default=None, help="comma-separated (default: every case of the table, or with "
                                                     "--friction every friction case)")
    ap.add_argument("--friction", action="store_true",
                    help="the friction cases of issue 50 (soft, soft_3x, stiff, stiff_3x and all_ of each), seed "
                         "after seed, with the validation run, the NEES and the standard scores")
    ap.add_argument("--quick", action="store_true", help="the first seed only and a 2 s experiment")
    ap.add_argument("--rig", choices=tuple(RIGS), default="level",
                    help="the hand's orientation during the experiments: level (palm up, the file's gravity; "
                         "default) or hanging (fingers down: no fold of a soft finger's equilibria)")
    ap.add_argument("--adapt", choices=ADAPT, default="auto",
                    help="auto (default): the experiment adapted on the plant as alpes-dyn experiment --rig auto adapts "
                         "it (hung fingers down where palm up the finger leaves its range, then smaller amplitudes); "
                         "level / hanging: that orientation only, the amplitudes adapting; both: palm up then hung in "
                         "one record (alpes-dyn experiment --rig both); none: the design as given")
    ap.add_argument("--check-ramp", action="store_true",
                    help="with --friction: give identify a held-out slow record (the validation ramp, its own noise) "
                         "as --validate does: its observer check and its choice of the friction law judged on it")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--no-rigid", action="store_true", help="skip the rigid fit (the extended fit and the EKF only)")
    ap.add_argument("--log", metavar="FILE", help="append each row to FILE as a JSON line as it is measured")
    ap.add_argument("--from-log", metavar="FILE",
                    help="measure nothing: the table (or --json object) of the rows a run's --log FILE holds, with "
                         "this script's distribution and goals (a run interrupted, or summarised again)")
    ap.add_argument("--chains", help="the hand's chains instead of finger3, comma-separated (index, middle, ring, "
                                     "little, thumb)")
    ap.add_argument("--workers", type=int, default=0,
                    help="run each case's seeds on a local Dask cluster of this many processes "
                         "(alpes_dyn.studies.sweep; 0: in this process, one after another, the default)")
    ap.add_argument("--hand-seed", type=int, default=None,
                    help="with --chains: the seed of the hand's draw and of the sensors' noise (default 5)")
    args = ap.parse_args(argv)
    if args.friction:
        return _friction_main(ap, args)
    if args.check_ramp:
        ap.error("--check-ramp: only with --friction (the friction cases' held-out ramp)")
    if args.from_log is not None:
        return _from_log(ap, args)
    try:
        seeds = parse_seeds(args.seeds)
    except InputError as e:
        ap.error(f"--{e}")
    plants = [FINGER3]
    if args.chains is not None:
        known = load_params().chain_names
        chains = [c.strip() for c in args.chains.split(",") if c.strip()]
        bad = [c for c in chains if c not in known]
        if bad or not chains or len(set(chains)) != len(chains):
            why = f"unknown chain {bad[0]!r}" if bad else ("no chain" if not chains else "a chain named twice")
            ap.error(f"--chains: {why} (expected some of {', '.join(known)})")
        plants = [hand_plant(c) for c in chains]
        seeds = [5 if args.hand_seed is None else args.hand_seed]
        if seeds[0] < 0:
            ap.error(f"--hand-seed: expected a non-negative integer, got {seeds[0]}")
    elif args.hand_seed is not None:
        ap.error("--hand-seed: only with --chains (finger3's seeds are --seeds)")
    if not 0 <= args.workers <= 64:
        ap.error(f"--workers: expected 0 (in this process) to 64, got {args.workers}")
    names = [c.strip() for c in (args.cases or ",".join(CASE_NAMES)).split(",") if c.strip()]
    bad = [c for c in names if c not in CASE_NAMES]
    if bad or not names:
        ap.error(f"--cases: unknown case {bad[0] if bad else ''!r} (expected some of {', '.join(CASE_NAMES)})")
    duration = 2.0 if args.quick else None
    if args.quick:
        seeds = seeds[:1]
    warnings.simplefilter("ignore", JointRangeWarning)  # the library's simulator in the design; MuJoCo has stops
    # the cable: sized on the level rig, the same cable on every rig
    k_t, c_t, info = tendon_stiffness(rig_design("level", duration))
    table = cases(k_t, c_t, RIGS[args.rig])
    design = rig_design(args.rig, duration)  # designed, trimmed and fitted in the rig's orientation
    rows, case_seconds = [], {}

    def log(new_rows: list) -> None:
        rows.extend(new_rows)
        if args.log:
            with open(args.log, "a", encoding="utf-8") as f:
                f.writelines(json.dumps(r) + "\n" for r in new_rows)

    client = local_client(args.workers) if args.workers else None
    try:
        with tempfile.TemporaryDirectory() as d:
            for c in names:
                t0 = time.perf_counter()
                for plant in plants:
                    if client is None:
                        for s in seeds:
                            try:
                                row = realism_case(c, table[c], s, design, Path(d), plant, rigid=not args.no_rigid,
                                                   adapt=args.adapt)
                            except Exception as exc:  # a run that raised (the plant diverged, ...): counted apart
                                row = {"case": c, "seed": s, "chain": plant.label,
                                       "error": f"{type(exc).__name__}: {exc}"}
                            log([row])
                    else:  # the seeds of a case and plant as one sweep on the cluster (alpes_dyn.studies.sweep)
                        opts = {"case": c, "rig": args.rig, "chain": None if plant is FINGER3 else plant.label,
                                "duration": design.duration, "cable": (k_t, c_t), "adapt": args.adapt}
                        log(sweep(realism_row, seeds=seeds, options=opts, client=client, flat=False).rows)
                case_seconds[c] = time.perf_counter() - t0
    finally:
        if client is not None:
            cluster = client.cluster
            client.close()
            cluster.close()
    out = {"model": MODEL if args.chains is None else "hand", "seeds": seeds, "duration_s": design.duration,
           "rig": args.rig, "adapt": args.adapt,
           "tendon": info, "case_seconds": case_seconds, "rows": rows, "summary": summarise(rows)}
    if args.chains is not None:
        out["chains"] = [p.label for p in plants]
    print(json.dumps(out) if args.json else table_text(out))
    return 0


def _friction_main(ap: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """--friction: the friction cases (:mod:`alpes_dyn.studies.realism_friction`, ``_friction.py``) measured seed
    after seed, or with --from-log the table of a run's rows (the seeds that hold every case)."""
    from _friction import friction_output, friction_text, read_log, run_friction  # this folder is on the path

    for flag, bad in (("--chains", args.chains is not None), ("--hand-seed", args.hand_seed is not None),
                      ("--workers", args.workers != 0), ("--no-rigid", args.no_rigid),
                      ("--rig", args.rig != "level")):
        if bad:
            ap.error(f"{flag}: not with --friction (finger3 on the level rig, --adapt hanging it where it must; "
                     f"the extended fit only, in this process)")
    names = [c.strip() for c in (args.cases or ",".join(FRICTION_CASE_NAMES)).split(",") if c.strip()]
    bad = [c for c in names if c not in FRICTION_CASE_NAMES]
    if bad or not names or len(set(names)) != len(names):
        ap.error(f"--cases: {'unknown case ' + repr(bad[0]) if bad else 'none or one named twice'} (expected some "
                 f"of {', '.join(FRICTION_CASE_NAMES)} with --friction)")
    warnings.simplefilter("ignore", JointRangeWarning)  # the library's simulator in the design; MuJoCo has stops
    # the experiment as alpes-dyn experiment records it: its stiction ramp after the excitation (held out, judged on)
    design = dataclasses.replace(rig_design("level", 2.0 if args.quick else None), stick_seconds=STICK_SECONDS)
    if args.from_log is not None:
        try:
            rows = read_log(args.from_log)
        except ValueError as e:
            ap.error(f"--from-log: {e}")
        out = friction_output(rows, names, design, "level", args.adapt, {}, from_log=args.from_log)
    else:
        try:
            seeds = parse_seeds(args.seeds)
        except InputError as e:
            ap.error(f"--{e}")
        rows: list[dict] = []

        def log(new_rows: list) -> None:
            rows.extend(new_rows)
            if args.log:
                with open(args.log, "a", encoding="utf-8") as f:
                    f.writelines(json.dumps(r) + "\n" for r in new_rows)

        seconds = run_friction(names, seeds[:1] if args.quick else seeds, design, args.adapt, log, args.check_ramp)
        out = friction_output(rows, names, design, "level", args.adapt, seconds)
    print(json.dumps(out) if args.json else friction_text(out))
    return 0


def _from_log(ap: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """--from-log FILE: the output of the run whose rows FILE holds (one JSON object a line), nothing measured but
    the tendon's sizing (one MuJoCo run, as the run did it); the rig and adapt as given on this command line."""
    try:
        lines = Path(args.from_log).read_text(encoding="utf-8").splitlines()
        rows = [json.loads(x) for x in lines if x.strip()]
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        ap.error(f"--from-log: cannot read {args.from_log}: {e}")
    if not rows or not all(isinstance(r, dict) and "case" in r and "seed" in r for r in rows):
        ap.error(f"--from-log: {args.from_log} holds no rows of this benchmark (JSON objects with case and seed)")
    design = rig_design(args.rig, 2.0 if args.quick else None)
    warnings.simplefilter("ignore", JointRangeWarning)
    info = tendon_stiffness(rig_design("level", design.duration))[2]
    out = {"model": MODEL, "seeds": list(dict.fromkeys(r["seed"] for r in rows)), "duration_s": design.duration,
           "rig": args.rig, "adapt": args.adapt, "tendon": info, "case_seconds": {}, "rows": rows,
           "summary": summarise(rows), "from_log": args.from_log}
    print(json.dumps(out) if args.json else table_text(out))
    return 0


def table_text(out: dict) -> str:
    """The table of a run (the --json object): per case and seed the rigid fit (its worst K and m errors, residual,
    verdict) and the extended one (worst errors up to the common scale, residual, converged, fit time, verdict),
    then the EKF on the extended fit's file and on the true file."""
    info = out["tendon"]
    what = f"hand chains {', '.join(out['chains'])}, hand seed" if "chains" in out else f"{out['model']}, seeds"
    lines = [f"{what} {out['seeds']}, {out['duration_s']:g} s experiment on the "
             f"{out.get('rig', 'level')} rig; tendon k_t = "
             f"{info['k_t_N_per_m']:.3g} N/m ({100 * STRETCH:g} % stretch: mean tension "
             f"{info['mean_tension_N']:.1f} N over a travel of {1e3 * info['tendon_travel_m']:.2f} mm from q = 0; "
             f"swing {info['tension_swing_N']:.2f} N over {1e3 * info['swing_travel_m']:.2f} mm), "
             f"c_t = {info['c_t_N_s_per_m']:.3g} N s/m, rotor mode {info['rotor_mode_Hz']:.0f} Hz; extended fit: "
             f"--effects {FIT_EFFECTS} (effects kept: c compliance, t tilt, s stiction, r rotor)",
             f"{'case':9} {'chain':>6} {'seed':>4} | {'rigid K%':>8} {'m%':>6} {'resid':>5} {'flag':>5} | {'ext K%':>6} {'m%':>5} "
             f"{'F_s%':>5} {'F_v%':>5} {'resid':>5} {'conv':>5} {'fit s':>5} {'flag':>5} {'eff':>5} | "
             f"{'EKF deg (extended file)':>23} | {'EKF deg (true file)':>19} | rig"]
    for r in out["rows"]:
        if "error" in r:
            lines.append(f"{r['case']:9} {r.get('chain', out['model']):>6} {r['seed']:>4} | RAISED {r['error'][:140]}")
            continue
        a, b = r.get("rigid"), r["extended"]
        wb = b["worst_error_common_scale_pct"]
        rigid = (f"{'--':>8} {'--':>6} {'--':>5} {'--':>5}" if a is None else
                 f"{a['worst_error_pct']['K']:8.2f} {a['worst_error_pct']['m']:6.1f} {a['residual_counts']:5.2f} "
                 f"{'yes' if a['flagged'] else 'no':>5}")
        lines.append(f"{r['case']:9} {r.get('chain', out['model']):>6} {r['seed']:>4} | {rigid} | {wb['K']:6.2f} {wb['m']:5.1f} {wb['F_s']:5.1f} "
                     f"{wb['F_v']:5.1f} {b['residual_counts']:5.2f} {str(b['converged']):>5} "
                     f"{b['fit_seconds_total']:5.1f} "
                     f"{'yes' if b['flagged'] else 'no':>5} {''.join(e[0] for e in b['effects']):>5} | "
                     f"{' / '.join(f'{x:.2f}' for x in r['ekf_rmse_deg']):>23} | "
                     f"{' / '.join(f'{x:.2f}' for x in r['ekf_true_file_rmse_deg']):>19} | {_rig(r)}")
    lines.append("time per case (all seeds and chains; plant + two fits + EKF runs): "
                 + ", ".join(f"{c} {s:.0f} s" for c, s in out["case_seconds"].items()))
    lines += summary_text(out["summary"])
    return "\n".join(lines)


def _rig(row: dict) -> str:
    """The rig the experiment ran on and its amplitude scale (``h 0.7``: hung, scaled), ``!`` where it adapted."""
    a = row.get("adaptation")
    if a is None:
        return "--"
    return f"{a['rig'][0]}{'' if a['amplitude_scale'] == 1.0 else ' %g' % a['amplitude_scale']}{'!' if a['note'] else ''}"


def summary_text(summary: dict) -> list[str]:
    """The distribution per case (:func:`~alpes_dyn.studies.realism.summarise`): median / worst of the extended fit's
    errors up to the common scale, of the EKF's worst joint and of the fit's time; the silent misses (adequate, but
    the EKF above EKF_GOAL_DEG or the masses above MASS_GOAL_PCT) and the refusals with their verdicts."""
    from _table import case_notes, median_worst  # this folder is on the path

    mw = median_worst
    lines = [f"distribution per case (median / worst; extended fit, errors up to the common scale; silent miss: "
             f"adequate but EKF > {EKF_GOAL_DEG:g} deg on a joint or m > {MASS_GOAL_PCT:g} %)",
             f"{'case':9} {'n':>3} | {'K %':>13} {'m %':>13} {'F_s %':>13} {'F_v %':>13} | {'EKF deg':>13} | "
             f"{'fit s':>11} | {'adequate':>8} {'silent':>6} {'refused':>7} {'raised':>6}"]
    for c, s in summary.items():
        lines.append(f"{c:9} {s['n']:>3} | {mw(s['K_pct'], '5.2f'):>13} {mw(s['m_pct'], '5.2f'):>13} "
                     f"{mw(s['F_s_pct'], '5.1f'):>13} {mw(s['F_v_pct'], '5.1f'):>13} | {mw(s['ekf_deg']):>13} | "
                     f"{mw(s['fit_seconds'], '4.1f'):>11} | {s['adequate']:>8} {len(s['silent_misses']):>6} "
                     f"{len(s['refusals']):>7} {len(s['errors']):>6}")
        lines += case_notes(s)
        g = s["goal"]
        lines.append(f"    goal: adequate files within EKF {g['ekf_deg']:g} deg, K {g['K_pct']:g} %, m {g['m_pct']:g} % and no "
                     f"silent miss: {'met' if g['accuracy_met'] else 'MISSED'}; median fit within {g['fit_seconds']:g} s: "
                     f"{'met' if g['time_met'] else 'MISSED'}")
    return lines


if __name__ == "__main__":
    sys.exit(main())
