"""``experiment --design-only`` and ``experiment --bench mujoco``: the identification experiment without a simulated
truth.

``alpes-dyn experiment --model finger3 --design-only -o torque.csv`` writes the experiment's motor torque as designed
on the nominal model (``--params``: the file the experimenter starts from), for a user who plays it on their hand
with their own tools. The CSV: a header line, then one row per sample at the design's rate (1 kHz; ``--duration``
s, 4 by default):

=================== ===== =============================================================================
column              unit  meaning
=================== ===== =============================================================================
``t``               s     the sample's time, from 0, uniform (the period 1 / rate: 1e-3 s)
``torque_<motor>``  N m   the motor torque to apply from this row's time to the next (bias, multisine,
                          dither); ``<motor>`` the model's motor name (``finger`` on finger2, finger3)
=================== ===== =============================================================================

The bias is the nominal finger's (no finger to trim it on): on the MuJoCo stand-in's drawn fingers it left the motion
up to 16 degrees per joint off the designed trajectory, and pulled a soft finger onto its stop. The command prints the encoder reading (counts) the
bias should hold the finger at, so that the user can trim it; ``--bench`` does that on the hand itself.

``alpes-dyn experiment --model finger3 --bench mujoco -o rec.csv`` runs the whole experiment through the hardware
interface on the MuJoCo stand-in (:class:`~alpes_dyn.bench.mujoco_hand.MujocoHand`, a real hand's effects, its
parameters drawn from ``--params`` by ``--perturb`` and ``--seed`` and hidden from the experiment): the calibration
(:func:`~alpes_dyn.estimation.experiments.calibration.calibrate`), then the guarded experiment
(:func:`~alpes_dyn.estimation.experiments.on_hand.run_experiment`), designed on ``--params``; the recording is the
documented CSV that ``alpes-dyn identify`` reads. A guard trip (the encoder near a stop, a missed period) relaxes the
finger and names the rig; with ``--rig both`` that rig is left out and the other recorded (``tripped`` in
``--json``, a note in the text), and where no rig recorded the command writes nothing and exits 3 with the reason.

``--rig`` (:data:`RIG_RUNS`) turns the hand: ``level`` palm up, ``hanging`` hung fingers down (the design's gravity
turned by :func:`~alpes_dyn.estimation.experiments.turned.rig_design`), ``both`` palm up then hung, each its own
calibration and guarded run on the stand-in in that orientation (its noise seeded ``--seed`` plus the rig's index:
level 0, hanging 1), the runs joined into one recording of two runs with their gravity columns
(:func:`~alpes_dyn.estimation.experiments.turned.run_turned`): ``identify --data`` fits each run in its own
orientation and the tilt, which pins finger3's masses that one orientation trades with its cable's compliance.
``auto`` is palm up (``level``), as the stand-in always ran. ``--json`` names each run's ``rig``, ``calibration``,
trim (``bias_nm``) and ``amplitude_scale`` under ``runs``. With ``--design-only``, ``--rig hanging`` writes the hung
profile to ``-o``; ``--rig both`` writes one profile per rig beside it, ``-o``'s name with ``_level`` and
``_hanging`` before ``.csv`` (``torque.csv``: ``torque_level.csv``, ``torque_hanging.csv``; ``-o`` itself is not
written), each with its own target reading.
"""

from __future__ import annotations

import argparse

from ..errors import InputError
from .common import EXIT_UNTRUSTED, _check_run_files, _emit, _Untrusted

__all__ = ["add_options", "experiment_on_hand", "GUARD_EXIT", "RIG_RUNS"]

RIG_RUNS: dict[str, tuple[str, ...]] = {"auto": ("level",), "level": ("level",), "hanging": ("hanging",),
                                       "both": ("level", "hanging")}
"""``--rig`` with --design-only or --bench: the rigs run, in order (:data:`~alpes_dyn.estimation.experiments.turned.RIGS`;
``auto`` palm up, as ``level``: the module docstring)."""

GUARD_EXIT = EXIT_UNTRUSTED
"""The exit code of ``experiment --bench`` where the guard stopped the experiment (the finger relaxed, no file): 3,
as ``identify``'s for a fit not to be trusted (the run went, but its result is not there to use)."""

def add_options(s: argparse.ArgumentParser) -> None:
    """``experiment``'s --design-only and --bench, and its -o and --json (their help says what each writes)."""
    s.add_argument("--design-only", action="store_true",
                   help="write the experiment's torque profile designed on --params (columns t in s, torque_<motor> in "
                        "N m, one row per 1 ms sample) for a hand you drive with your own tools, instead of a recording")
    s.add_argument("--bench", choices=("mujoco",), default=None,
                   help="run the experiment on a hand through the hardware interface: mujoco, the MuJoCo stand-in "
                        "(finger2, finger3, thumb; a real hand's effects; its finger drawn by --perturb, --seed and "
                        "hidden; the thumb's ab/adduction held relaxed): "
                        "calibration, the bias trimmed on the hand, the guarded run; exit 3 where the guard stops it")
    s.add_argument("-o", "--output", required=True, metavar="FILE.csv",
                   help="the recording to write (with --design-only: the torque profile)")
    s.add_argument("--json", action="store_true", help="print one JSON object")


_NOT_WITH = (("--true-spec", "true_spec"), ("--true-model", "true_model"), ("--spec", "spec"))


def _checked(args: argparse.Namespace) -> None:
    """One line for every option that does not go with --design-only / --bench, before any work."""
    mode = "--design-only" if args.design_only else f"--bench {args.bench}"
    if args.design_only and args.bench is not None:
        raise InputError("--bench: runs the experiment on a hand; --design-only writes its torque alone (one of them)")
    for flag, dest in _NOT_WITH:
        if getattr(args, dest) is not None:
            raise InputError(f"{flag}: goes with a URDF --model's simulated experiment, not {mode} (an Alpes "
                             "finger's)")
    models = ("finger2", "finger3", "thumb")  # the thumb: its ab/adduction held relaxed (estimation.experiments.on_hand)
    if args.model not in models:
        raise InputError(f"--model: {mode} is defined for {', '.join(models)}, got {args.model!r}")
    if args.design_only:
        for flag, dest in (("--perturb", "perturb"), ("--true-params-out", "true_params_out")):
            if getattr(args, dest) is not None:
                raise InputError(f"{flag}: --design-only draws no true finger (the torque is designed on --params)")
        if args.seed != 0:
            raise InputError("--seed: --design-only has no noise to seed (the torque is designed on --params)")
    else:
        if args.chain is not None:
            raise InputError(f"--chain: the MuJoCo stand-in is one finger ({args.model}) of the shipped file")
        if args.perturb is None and args.true_params_out is not None:
            raise InputError("--true-params-out: goes with --perturb (otherwise the true file is --params)")
    _check_run_files(args, {"-o": ("csv",)}, more=[("-o", p) for p in _profile_paths(args)[1:]])


def _rigs(args: argparse.Namespace) -> tuple[str, ...]:
    """The rigs ``--rig`` runs in, in order (the module docstring): auto and level palm up, hanging hung, both."""
    return RIG_RUNS[args.rig]


def _profile_paths(args: argparse.Namespace) -> list[str]:
    """``--design-only``'s torque profiles, one per rig: -o itself for one rig; for ``--rig both`` -o's name with
    ``_level`` and ``_hanging`` before ``.csv`` (first entry -o itself, never written then: the rigs' files follow)."""
    if not args.design_only or len(_rigs(args)) == 1:
        return [args.output]
    stem = args.output[:-4] if args.output.lower().endswith(".csv") else args.output
    return [args.output] + [f"{stem}_{rig}.csv" for rig in _rigs(args)]


def experiment_on_hand(args: argparse.Namespace) -> int:
    """``experiment --design-only`` or ``experiment --bench mujoco`` (the module docstring)."""
    from ..estimation.experiments.design import ExperimentDesign
    from ..model.params import load_params
    from ..model.robot import Model

    _checked(args)
    nominal_params = load_params(args.params)
    nominal = Model.alpes(args.model, friction=True, params=nominal_params, chain=args.chain)
    design = ExperimentDesign(duration=args.duration, amplitude_fraction=args.amplitude)
    if args.design_only:
        return _design_only(args, nominal, design)
    return _bench(args, nominal, nominal_params, design)


def _design_only(args: argparse.Namespace, nominal, design) -> int:
    from ..estimation.experiments.on_hand import designed_torque, write_torque_profile
    from ..estimation.experiments.turned import rig_design

    rigs, paths = _rigs(args), _profile_paths(args)[-len(_rigs(args)):]
    names = nominal.transmission.motor_names
    made = [(rig, path, designed_torque(nominal, rig_design(rig, design=design, gravity=nominal.gravity)))
            for rig, path in zip(rigs, paths)]  # every profile designed before any is written
    for _, path, (t, u, _) in made:
        write_torque_profile(path, t, u, names)
    cols = ["t"] + [f"torque_{n}" for n in names]
    t = made[0][2][0]
    profiles = [{"rig": rig, "output": path, "target_counts": {n: float(c) for n, c in zip(names, target)},
                 "torque_range_nm": {n: [float(u[:, k].min()), float(u[:, k].max())] for k, n in enumerate(names)}}
                for rig, path, (_, u, target) in made]
    obj = {"model": args.model, "rig": args.rig, "rigs": list(rigs), "output": paths[0] if len(paths) == 1 else paths,
           "samples": int(t.size), "rate_hz": 1.0 / design.dt, "duration_s": float(t[-1]), "columns": cols,
           "units": {"t": "s", **{c: "N m" for c in cols[1:]}}, "profiles": profiles}
    if len(rigs) == 1:
        obj.update({k: profiles[0][k] for k in ("target_counts", "torque_range_nm")})
    text = (f"{args.model}: the identification experiment's torque, {t.size} samples at {1 / design.dt:g} Hz "
            f"({', '.join(cols)}; s, N m) designed on the nominal model")
    for p in profiles:
        text += (f"\n  {p['rig']}: written to {p['output']}; trim the bias on your hand until the encoder rests at "
                 + ", ".join(f"{c:.0f} counts ({n})" for n, c in p["target_counts"].items()))
    _emit(obj, text, args.json)
    return 0


def _bench(args: argparse.Namespace, nominal, nominal_params, design) -> int:
    from ..bench.mujoco_hand import MujocoHand
    from ..estimation.experiments.draws import perturbed_params
    from ..estimation.experiments.excursion import excursion_report
    from ..estimation.experiments.turned import RIGS, RigTripped, run_turned
    from ..model.params import write_params

    chains = ("thumb",) if args.model == "thumb" else None  # the thumb's own values drawn (a finger's: [finger])
    truth = nominal_params if args.perturb is None else perturbed_params(nominal_params, args.perturb, args.seed,
                                                                          chains=chains)

    def hand_in(rig: str) -> MujocoHand:  # the stand-in turned: its noise seeded --seed plus the rig's index
        return MujocoHand(args.model, truth, seed=args.seed + list(RIGS).index(rig), rig=rig)

    try:  # --rig both: a rig whose guard trips is left out, named in the output (run_turned's keep_going)
        res = run_turned(hand_in, nominal, design, _rigs(args), path=args.output, keep_going=True)
    except RigTripped as trip:  # no rig recorded: one line on stderr, exit 3 (GUARD_EXIT)
        raise _Untrusted(f"alpes-dyn: experiment stopped: {trip} (no recording written)") from None
    if args.true_params_out is not None:
        write_params(truth, args.true_params_out, header=f"true parameters of the MuJoCo stand-in drawn by alpes-dyn "
                                                         f"experiment --bench (spread {args.perturb:g}, seed {args.seed})")
    _emit(*_bench_report(args, res, excursion_report(res.recording)), args.json)
    return 0


def _bench_report(args: argparse.Namespace, res, excursion: dict) -> tuple[dict, str]:
    """(the JSON object, the text) of ``--bench``: the recording, each rig's calibration, trim and amplitude."""
    from ..estimation.experiments.on_hand import ROOM_SHARE

    rec, runs = res.recording, res.to_dict()
    obj = {"model": args.model, "bench": args.bench, "rig": args.rig, "rigs": list(res.rigs), "output": args.output,
           "samples": rec.n_samples, "duration_s": rec.duration, "dt_s": rec.dt, "columns": list(rec.columns()),
           "true_params": args.true_params_out, "runs": runs, **excursion}
    if len(runs) == 1:  # one rig: its calibration and run as before
        obj["calibration"] = runs[0]["calibration"]
        obj["run"] = {k: v for k, v in runs[0].items() if k not in ("rig", "calibration")}
    text = (f"{args.model}: identification experiment on the MuJoCo stand-in ({' then '.join(res.rigs)}, "
            f"{len(runs)} run{'s' if len(runs) > 1 else ''}), {rec.n_samples} samples written to {args.output}")
    notes = [f"{rig}: the guard stopped its run ({why}); the finger relaxed; the recording holds the other "
             f"rig{'s' if len(runs) > 1 else ''} only" for rig, why in res.tripped]
    obj["tripped"] = [{"rig": rig, "reason": why} for rig, why in res.tripped]
    for r, run in zip(runs, res.runs):
        cal = run.calibration
        text += (f"\n  {r['rig']}: calibration: rest {', '.join(f'{v:.0f}' for v in cal.rest)} counts, usable range "
                 f"{', '.join(f'{a:.0f}-{b:.0f}' for a, b in zip(cal.low, cal.high))} counts; trim: bias "
                 f"{', '.join(f'{b:.5g}' for b in run.bias)} N m (nominal {', '.join(f'{b:.5g}' for b in run.nominal_bias)}),"
                 f" multisine at {run.amplitude_scale:.2g} of the design's")
        if run.amplitude_scale < ROOM_SHARE:  # too small a record for the masses: say so (on_hand.ROOM_SHARE)
            notes.append(f"{r['rig']}: the multisine ran at {run.amplitude_scale:.2g} of the designed amplitude, "
                         f"below {ROOM_SHARE:g}: too small a record to trust the masses of; record the hand in another "
                         "rig too (--rig hanging, both) and keep the run with more room (on_hand.roomier)")
    if notes:
        obj["note"] = "; ".join(notes)
        text += f"\n  note: {obj['note']}"
    return obj, text
