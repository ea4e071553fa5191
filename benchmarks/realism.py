"""Realism benchmark (issue 16): today's identification and EKF on MuJoCo plants with the effects of a real hand.

The identification benchmark fits data from the library's own simulator, whose structure is the fitted
model's. Here the plant is the finger exported to MuJoCo (:mod:`alpes_dyn.control.plants`: joint stops on,
RK4 at 0.1 ms, our encoder and torque sensors at 1 kHz), finger3 drawn +-20 % per link
(:func:`~alpes_dyn.estimation.experiment.perturbed_params`, seeds 11, 12, 13 by default: the identification
benchmark uses 1-4), with one effect of a real hand at a time, or all of them:

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
all        all of the above at once
========== ================================================================================================

Per case and seed: the identification experiment's torque (designed on the nominal file, the bias trimmed on
the true finger as it stands) replayed on the plant, and two fits of it:

* **rigid**: the rigid, smooth-friction model (K, m, F_s, F_v; ``alpes-dyn identify --effects none``), whose
  adequacy verdict must flag every plant with an effect and none with the model's own structure;
* **extended**: what ``alpes-dyn identify`` fits by default (``--effects auto``, :mod:`alpes_dyn.estimation.effects`):
  the tendon's compliance and the palm's tilt, then rounds with the stick-slip law and the rotor where a fit asks
  for them (:func:`~alpes_dyn.estimation.effects.fit_effects`), the lower residual kept; from the nominal file.
  Its time is every round's (``fit_seconds_total``; each round in ``rounds``).

For each, the worst error (%) of each kind, also up to the one common scale (exp of the mean log ratio over
K and m: the torque constant scales every parameter together, and the encoder cannot see it), the residual
(counts; the sensor floor is 0.58), ``converged``, the fit time, the verdict. Then the EKF
(:func:`~alpes_dyn.estimation.replay.estimate_recording`, as ``alpes-dyn estimate --data``) on the extended
fit's file, with its fitted tilt and offset, and for comparison on the true file (rigid, level: it knows
neither), on a fresh run of the plant -- the experiment's design on other lines (0.4-12.7 Hz: a torque the fit
never saw), from the plant's rest -- from that run's recorded encoder and torque: RMSE after 1 s, deg per joint.
(The estimation scenario's torque is not used: it takes the nominal finger outside its joint range, into
MuJoCo's stops.) The verdict is the fit's adequacy check (:mod:`alpes_dyn.estimation.adequacy`, in-sample:
whiteness, cross-correlation with the torque, residual against the sensor floor): "adequate", or "FLAGGED"
with the reason.

    python benchmarks/realism.py [--seeds 11,12,13] [--cases none,stiction,...] [--rig level|hanging] [--quick]
                                 [--json] [--log FILE]
    python benchmarks/realism.py --chains index,middle,ring,little,thumb [--hand-seed 5] [--cases ...]

``--rig hanging``: the hand hung fingers down during the experiments (:func:`~alpes_dyn.model.mjcf.hanging_gravity`),
the experiment designed and trimmed in that orientation, the fits and the EKF on the models turned to it (the
tilt cases' 3 degrees on top). Palm up, a finger with soft springs folds (its static equilibria snap through
before it reaches mid-range): held below the fold it rests on its stop, and no fit holds (5 of the 20 draws of
seeds 30-49). Hanging, none folds.

``--quick``: one seed (the first) and a 2 s experiment.

``--chains``: the hand's chains instead of finger3, one at a time, each as ``alpes-dyn identify`` fits it (a finger
as ``--model finger3 --chain <name>``; the thumb as ``--model thumb``, its flexion springs, masses and friction,
:data:`~alpes_dyn.cli.THUMB_PARAMETERS`, its ab/adduction on its own geared motor), from the nominal file; the
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
import math
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import alpes_dyn as ad
from alpes_dyn.control.plants import PlantEffects, mujoco_recording, plant_model
from alpes_dyn.estimation.experiment import ExperimentDesign, experiment_torque, perturbed_params
from alpes_dyn.estimation.effects import alpes_models, fit_effects, parse_effects
from alpes_dyn.estimation.identification import identify
from alpes_dyn.estimation.replay import estimate_recording
from alpes_dyn.model.mjcf import HANGING_TILT, STICTION_TIMECONST, tilted_gravity
from alpes_dyn.model.params import load_params, write_params
from alpes_dyn.model.stops import JointRangeWarning
from alpes_dyn.symbolic.parametric import parameter_catalogue

KINDS = ("K", "m", "F_s", "F_v")  # the kinds of parameter whose errors the table gives

MODEL = "finger3"
STRETCH = 0.03  # cable stretch / tendon travel under the experiment's torque swing
ZETA = 0.2  # damping ratio of the rotor-on-cable mode
TILT_DEG = 3.0
KT_ERROR = 0.05
OFFSET_COUNTS = 4.0
FRESH_FREQUENCIES = (0.4, 0.9, 1.7, 2.9, 4.3, 6.1, 8.9, 12.7)  # Hz: the EKF's validation run
FIT_EFFECTS = "auto"  # the extended fit: alpes-dyn identify's default --effects


RIGS = {"level": 0.0, "hanging": HANGING_TILT}
"""The rig's orientation (rad about the joints' axes from the file's palm-up gravity, :func:`tilted_gravity`)."""

CASE_NAMES = ("none", "stiction", "tendon", "rotor", "tilt", "kt", "offset", "all")


def tendon_stiffness(design: ExperimentDesign) -> tuple[float, float, dict]:
    """k_t (N/m) and c_t (N s/m) for the tendon case, from the nominal finger's experiment on a rigid MuJoCo plant:
    under the experiment's mean tension mean(tau_m) / r_m the cable stretches by STRETCH times the tendon's travel
    from the springs' rest (q = 0) to the mean configuration, r mean(sum q). c_t gives the rotor-on-cable mode
    (J_m on r_m^2 k_t) the damping ratio ZETA."""
    p = load_params()
    t, u, x0 = experiment_torque(MODEL, p, design)
    rec = mujoco_recording(MODEL, p, u, design.dt, encoder_noise_counts=0.0, torque_noise=0.0)
    travel = p.r * float(np.mean(rec.true_q.sum(axis=1)))
    tension = float(np.mean(u)) / p.r_m
    k_t = tension / (STRETCH * travel)
    c_t = 2 * ZETA * math.sqrt(k_t * p.J_m) / p.r_m
    info = {"mean_tension_N": tension, "tension_swing_N": float(np.ptp(u)) / p.r_m, "tendon_travel_m": travel,
            "swing_travel_m": p.r * float(np.ptp(rec.true_q.sum(axis=1))), "k_t_N_per_m": k_t,
            "c_t_N_s_per_m": c_t, "rotor_mode_Hz": math.sqrt(k_t * p.r_m**2 / p.J_m) / (2 * math.pi)}
    return k_t, c_t, info


def cases(k_t: float, c_t: float, rig_tilt: float = 0.0) -> dict[str, PlantEffects]:
    """Each case's plant effects; ``rig_tilt`` (rad): the rig's orientation (:func:`tilted_gravity`), under every
    plant (the tilt cases' error on top of it)."""
    one = {
        "none": PlantEffects(),
        "stiction": PlantEffects(stiction=STICTION_TIMECONST),
        "tendon": PlantEffects(tendon_stiffness=k_t, tendon_damping=c_t),
        "rotor": PlantEffects(tendon_rotor=True),
        "tilt": PlantEffects(tilt=math.radians(TILT_DEG)),
        "kt": PlantEffects(torque_constant_error=KT_ERROR),
        "offset": PlantEffects(encoder_offset=OFFSET_COUNTS),
    }
    # all: every effect; the elastic tendon carries the rotor (tendon_rotor is its rigid limit)
    one["all"] = PlantEffects(stiction=STICTION_TIMECONST, tendon_stiffness=k_t, tendon_damping=c_t,
                              tilt=math.radians(TILT_DEG), torque_constant_error=KT_ERROR,
                              encoder_offset=OFFSET_COUNTS)
    if rig_tilt:
        one = {c: dataclasses.replace(e, tilt=rig_tilt + e.tilt) for c, e in one.items()}
    return one


def verdict(res) -> str:
    """The fit's own word on itself (:mod:`alpes_dyn.estimation.adequacy`): adequate, or why not (the stop reason,
    the failed checks, the likely missing effect)."""
    if res.trustworthy:
        return "adequate"
    why = [] if res.converged else [f"not converged ({res.reason})"]
    if res.adequacy is not None and not res.adequacy.adequate:
        why.append("inadequate")
        if res.adequacy.likely_missing:
            why.append("likely " + ", ".join(res.adequacy.likely_missing[:2]))
    return "FLAGGED: " + "; ".join(why)


@dataclasses.dataclass(frozen=True)
class Plant:
    """What is identified: ``label`` (the table's), the Alpes ``model`` (finger3 or thumb) and the hand's ``chain``
    (None: the shared ``[finger]`` values of the default finger3 run), and the parameters the fits start from and
    select (``base``: None for a finger's default K, m and friction; :data:`~alpes_dyn.cli.THUMB_PARAMETERS` for the
    thumb)."""

    label: str
    model: str = MODEL
    chain: str | None = None
    base: str | None = None

    def true_params(self, seed: int):
        """The plant's parameters: finger3 drawn +-20 % (default), or the whole hand, every chain drawn."""
        if self.chain is None and self.model == MODEL:
            return perturbed_params(spread=0.2, seed=seed)
        nominal = load_params()
        return perturbed_params(nominal, spread=0.2, seed=seed, chains=nominal.chain_names)

    def alpes(self, **kwargs) -> ad.Model:
        return ad.Model.alpes(self.model, friction=True, chain=self.chain, **kwargs)


FINGER3 = Plant("finger3")


def hand_plant(chain: str) -> Plant:
    """The :class:`Plant` of one of the hand's chains (``thumb`` or a finger's name), as ``identify`` fits it."""
    if chain == "thumb":
        from alpes_dyn.cli import THUMB_PARAMETERS
        return Plant("thumb", "thumb", None, THUMB_PARAMETERS)
    return Plant(chain, MODEL, chain)


def ekf_rmse(rec, params_path: str, fitted: dict, transient: float = 1.0, rotor: bool = False,
             plant: Plant = FINGER3, rig: np.ndarray | None = None) -> np.ndarray:
    """RMSE (rad, per joint) after ``transient`` s of the EKF on ``params_path`` run on a recording's encoder and
    torque (:func:`~alpes_dyn.estimation.replay.estimate_recording`, as ``alpes-dyn estimate --data``: friction on,
    the tendon's stretch of the file taken off, and the rig's encoder offset and palm tilt as ``fitted``; ``rig``:
    the gravity of the rig's orientation, if not the file's, the tilt on top of it)."""
    obs = _on_rig(plant.alpes(rotor_inertia=rotor, params=params_path), rig)
    off = [fitted.get(f"encoder_offset_{mo}", 0.0) for mo in obs.transmission.motor_names]
    tilt = (fitted.get("tilt_x", 0.0), fitted.get("tilt_y", 0.0))
    est = estimate_recording(rec, obs, "ekf", encoder_offset=off, tilt=tilt, transient=transient)
    return est.rmse


_TORQUES: dict = {}


def torque_of(seed: int, p, design: ExperimentDesign, gravity: np.ndarray, plant: Plant = FINGER3):
    """experiment_torque for a seed's finger (memoised: the cases of one seed share it, but for the tilt's trim)."""
    key = (plant, seed, design, tuple(np.round(gravity, 12)))
    if key not in _TORQUES:
        _TORQUES[key] = experiment_torque(plant.model, p, design, chain=plant.chain, true_gravity=gravity)
    return _TORQUES[key]


def fresh_run(p, effects: PlantEffects, seed: int, design: ExperimentDesign, plant: Plant = FINGER3):
    """A validation run of the plant: the experiment's design on other lines (:data:`FRESH_FREQUENCIES`: a torque
    the fit never saw, in the joint range by the same design rule), from the plant's rest."""
    fresh = dataclasses.replace(design, frequencies=FRESH_FREQUENCIES, dither=0.0)  # in use: no dither, stick phases
    _, u, x0 = torque_of(seed, p, fresh, plant_model(plant.model, p, effects, plant.chain).gravity, plant)
    return mujoco_recording(plant.model, p, u, fresh.dt, effects=effects, q0=x0[: x0.size // 2], seed=seed + 1000,
                            chain=plant.chain)


def _on_rig(model, rig: np.ndarray | None):
    """``model`` in the rig's orientation (gravity ``rig``, m/s^2), or as it is (None: the file's)."""
    return model if rig is None else model.copy(gravity=rig)


def rig_of(design: ExperimentDesign) -> np.ndarray | None:
    """The rig's gravity (the design's orientation) where it is not the parameter file's, else None."""
    g = np.asarray(design.orientations[0], dtype=float)
    return None if np.array_equal(g, load_params().gravity) else g


def errors(values: dict[str, float], truth: dict[str, float]) -> tuple[dict, dict, float]:
    """The worst error (%) of each of :data:`KINDS` over the fitted ``values`` whose ``truth`` is known and not 0,
    plain and up to the common scale c = exp(mean log(value / truth)) over K and m (the torque constant scales
    every parameter together: the encoder cannot see it); and c."""
    kinds = {nm: kind for kind in KINDS for nm in values if nm.startswith(kind + "_") and truth.get(nm, 0.0) != 0.0}
    km = [values[nm] / truth[nm] for nm, kind in kinds.items() if kind in ("K", "m")]
    c = float(np.exp(np.mean(np.log(km))))
    worst = {kind: 0.0 for kind in KINDS}
    worst_c = dict(worst)
    for nm, kind in kinds.items():
        worst[kind] = max(worst[kind], abs(100 * (values[nm] / truth[nm] - 1)))
        worst_c[kind] = max(worst_c[kind], abs(100 * (values[nm] / (c * truth[nm]) - 1)))
    return worst, worst_c, c


def one(case: str, effects: PlantEffects, seed: int, design: ExperimentDesign, tmp: Path,
        plant: Plant = FINGER3) -> dict:
    """One row: the plant's recording with ``effects`` (seed ``seed``: the draw and the noise), the two fits, the
    EKF runs (see the module docstring)."""
    true = plant.true_params(seed)
    rig = rig_of(design)
    nominal = load_params()
    t0 = time.perf_counter()
    g_true = plant_model(plant.model, true, effects, plant.chain).gravity
    _, u, x0 = torque_of(seed, true, design, g_true, plant)
    rec = mujoco_recording(plant.model, true, u, design.dt, effects=effects, q0=x0[: x0.size // 2], seed=seed,
                           chain=plant.chain)
    plant_s = time.perf_counter() - t0
    rigid = identify(_on_rig(plant.alpes(params=nominal), rig), rec, plant.base, excitation=design.lines,
                     progress=False)
    model_of = alpes_models(plant.model, nominal, chain=plant.chain)
    fit = fit_effects(lambda e: _on_rig(model_of(e), rig), rec, parse_effects(FIT_EFFECTS), plant.base,
                      rec.gravity is not None, excitation=design.lines, progress=False)
    res = fit.result
    ident = res.write(tmp / f"ident_{plant.label}_{case}_{seed}.toml")  # marked NOT TRUSTWORTHY where the fit says so
    truth = {pp.name: pp.nominal for pp in parameter_catalogue(plant.alpes(params=true))}
    t1 = time.perf_counter()
    fresh = fresh_run(true, effects, seed, design, plant)
    fitted = dict(zip(res.names, res.values))
    rmse = ekf_rmse(fresh, str(ident), fitted, rotor="rotor" in fit.effects, plant=plant, rig=rig)
    true_path = write_params(true, tmp / f"true_{plant.label}_{seed}.toml")
    rmse_true = ekf_rmse(fresh, str(true_path), {}, plant=plant, rig=rig)
    ekf_s = time.perf_counter() - t1
    row = {"case": case, "seed": seed, "chain": plant.label}
    for label, one_fit, effects in (("rigid", rigid, []), ("extended", res, list(fit.effects))):
        worst, worst_c, c = errors(dict(zip(one_fit.names, one_fit.values.tolist())), truth)
        row[label] = {
            "worst_error_pct": worst, "worst_error_common_scale_pct": worst_c,
            "common_scale": c, "values": dict(zip(one_fit.names, one_fit.values.tolist())),
            "residual_counts": one_fit.residual_rms, "converged": bool(one_fit.converged),
            "iterations": one_fit.iterations,
            "fit_seconds": one_fit.seconds, "compile_seconds": one_fit.compile_seconds, "verdict": verdict(one_fit),
            "flagged": not one_fit.trustworthy, "stop_reason": one_fit.reason, "effects": effects,
            "adequacy": one_fit.adequacy.to_dict() if one_fit.adequacy is not None else None}
    row["joint_range_deg"] = [np.degrees(rec.true_q.min(axis=0)).tolist(), np.degrees(rec.true_q.max(axis=0)).tolist()]
    row["extended"]["rounds"] = [{"effects": list(e), "residual_counts": r.residual_rms, "converged": bool(r.converged),
                                  "fit_seconds": r.seconds} for e, r in fit.rounds]
    row["extended"]["fit_seconds_total"] = fit.seconds  # every round of auto
    row["extended"]["tried"] = None if fit.tried is None else {
        "effects": list(fit.tried_effects), "residual_counts": fit.tried.residual_rms, "flagged": not fit.tried.trustworthy,
        "fit_seconds": fit.tried.seconds}
    row.update({"plant_seconds": plant_s, "ekf_seconds": ekf_s, "ekf_rmse_deg": np.degrees(rmse).tolist(),
                "ekf_true_file_rmse_deg": np.degrees(rmse_true).tolist()})
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="11,12,13")
    ap.add_argument("--cases", default=",".join(CASE_NAMES))
    ap.add_argument("--quick", action="store_true", help="the first seed only and a 2 s experiment")
    ap.add_argument("--rig", choices=tuple(RIGS), default="level",
                    help="the hand's orientation during the experiments: level (palm up, the file's gravity; "
                         "default) or hanging (fingers down: no fold of a soft finger's equilibria)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--log", metavar="FILE", help="append each row to FILE as a JSON line as it is measured")
    ap.add_argument("--chains", help="the hand's chains instead of finger3, comma-separated (index, middle, ring, "
                                     "little, thumb)")
    ap.add_argument("--hand-seed", type=int, default=None,
                    help="with --chains: the seed of the hand's draw and of the sensors' noise (default 5)")
    args = ap.parse_args(argv)
    try:
        seeds = [int(s) for s in args.seeds.split(",")]
    except ValueError:
        ap.error(f"--seeds: expected comma-separated integers, got {args.seeds!r}")
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
    names = [c.strip() for c in args.cases.split(",") if c.strip()]
    bad = [c for c in names if c not in CASE_NAMES]
    if bad or not names:
        ap.error(f"--cases: unknown case {bad[0] if bad else ''!r} (expected some of {', '.join(CASE_NAMES)})")
    design = ExperimentDesign()
    if args.quick:
        seeds, design = seeds[:1], dataclasses.replace(design, duration=2.0)
    warnings.simplefilter("ignore", JointRangeWarning)  # the library's simulator in the design; MuJoCo has stops
    k_t, c_t, info = tendon_stiffness(design)  # the cable: sized on the level rig, the same cable on every rig
    rig_tilt = RIGS[args.rig]
    table = cases(k_t, c_t, rig_tilt)
    if rig_tilt:  # the experiment designed, trimmed and fitted in the rig's orientation
        design = dataclasses.replace(design, orientations=(tuple(tilted_gravity(load_params().gravity, rig_tilt)),))
    rows, case_seconds = [], {}
    with tempfile.TemporaryDirectory() as d:
        for c in names:
            t0 = time.perf_counter()
            for plant in plants:
                for s in seeds:
                    rows.append(one(c, table[c], s, design, Path(d), plant))
                    if args.log:
                        with open(args.log, "a", encoding="utf-8") as f:
                            f.write(json.dumps(rows[-1]) + "\n")
            case_seconds[c] = time.perf_counter() - t0
    out = {"model": MODEL if args.chains is None else "hand", "seeds": seeds, "duration_s": design.duration,
           "rig": args.rig,
           "tendon": info, "case_seconds": case_seconds, "rows": rows}
    if args.chains is not None:
        out["chains"] = [p.label for p in plants]
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
             f"{'EKF deg (extended file)':>23} | {'EKF deg (true file)':>19}"]
    for r in out["rows"]:
        a, b = r["rigid"], r["extended"]
        wa, wb = a["worst_error_pct"], b["worst_error_common_scale_pct"]
        lines.append(f"{r['case']:9} {r.get('chain', out['model']):>6} {r['seed']:>4} | {wa['K']:8.2f} {wa['m']:6.1f} {a['residual_counts']:5.2f} "
                     f"{'yes' if a['flagged'] else 'no':>5} | {wb['K']:6.2f} {wb['m']:5.1f} {wb['F_s']:5.1f} "
                     f"{wb['F_v']:5.1f} {b['residual_counts']:5.2f} {str(b['converged']):>5} "
                     f"{b['fit_seconds_total']:5.1f} "
                     f"{'yes' if b['flagged'] else 'no':>5} {''.join(e[0] for e in b['effects']):>5} | "
                     f"{' / '.join(f'{x:.2f}' for x in r['ekf_rmse_deg']):>23} | "
                     f"{' / '.join(f'{x:.2f}' for x in r['ekf_true_file_rmse_deg']):>19}")
    lines.append("time per case (all seeds and chains; plant + two fits + EKF runs): "
                 + ", ".join(f"{c} {s:.0f} s" for c, s in out["case_seconds"].items()))
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
