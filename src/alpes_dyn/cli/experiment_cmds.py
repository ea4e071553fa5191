"""The ``experiment`` command: the identification experiment simulated on an Alpes finger, the hand or a URDF +
spec robot, its recording written (the design checked over the whole record first, what it chose said)."""

from __future__ import annotations

import argparse
import math
import warnings

from ..errors import InputError, ModelError
from ..estimation.experiments.excursion import SmallExcursionWarning
from .common import (_check_model_options, _check_run_files, _emit, _excursion_lines, _is_urdf_path, _one_chain,
                     _refuse_for_urdf, _urdf_robot)

__all__ = ["cmd_experiment"]


def cmd_experiment(args: argparse.Namespace) -> int:
    """Simulate the documented identification experiment and write its recording; with ``--design-only`` write its
    torque profile, with ``--bench mujoco`` run it on the MuJoCo stand-in (:mod:`alpes_dyn.cli.on_hand_cmds`)."""
    from ..model.description import model_params
    from ..estimation.experiments.adapt import adapted_experiment
    from ..estimation.experiments.experiment import EXPERIMENT_MODELS, ExperimentDesign, perturbed_params
    from ..model.params import load_params, write_params

    if not (math.isfinite(args.amplitude) and 0 < args.amplitude <= 1):
        raise InputError(f"--amplitude: expected a fraction in (0, 1], got {args.amplitude!r}")
    if not (math.isfinite(args.stick_seconds) and 0 <= args.stick_seconds <= 600):
        raise InputError(f"--stick-seconds: expected 0 (no stiction ramp) or a duration in s up to 600, got "
                         f"{args.stick_seconds!r}")
    if args.design_only or args.bench is not None:  # no simulated truth: the torque alone, or a hand through its interface
        from .on_hand_cmds import experiment_on_hand

        return experiment_on_hand(args)
    if _is_urdf_path(args.model):
        return _experiment_robot(args)
    for flag, value in (("--true-spec", args.true_spec), ("--true-model", args.true_model)):
        if value is not None:
            raise InputError(f"{flag}: applies to a URDF --model; the Alpes model {args.model!r} takes the true "
                             "finger from --params (or --perturb)")
    _check_model_options(args)
    if args.model == "hand":  # the six motors at once, one recording
        from .hand_cmds import experiment_hand

        return experiment_hand(args)
    _one_chain(args.model, EXPERIMENT_MODELS, "the identification experiment", hand=True)
    _check_run_files(args, {"-o": ("csv",)})  # a recording: a CSV by its name
    if args.perturb is None and args.true_params_out is not None:
        raise InputError("--true-params-out: goes with --perturb (otherwise the true file is --params)")
    truth = load_params(args.params)
    model_params(args.model, truth, args.chain)  # a bad --chain: one line, before any work
    if args.perturb is not None:  # the chain's own values drawn (the thumb's, a finger's, or the shared finger's)
        chains = ("thumb",) if args.model == "thumb" else ((args.chain,) if args.chain else None)
        truth = perturbed_params(truth, args.perturb, args.seed, chains=chains)
    design = ExperimentDesign(duration=args.duration, amplitude_fraction=args.amplitude,
                              stick_seconds=args.stick_seconds)
    with warnings.catch_warnings():  # its lines printed on stdout, one per motor: _excursion_lines
        warnings.simplefilter("ignore", SmallExcursionWarning)
        # the design checked over the whole record on the finger before it is written; --rig auto: palm up
        # unless the finger leaves its range there, then hung fingers down (gravity columns written)
        rec, adaptation = adapted_experiment(args.model, truth, design, seed=args.seed, nominal_params=args.params,
                                             path=args.output, chain=args.chain, rig=args.rig)
    if args.true_params_out is not None:
        write_params(truth, args.true_params_out, header=f"true parameters drawn by alpes-dyn experiment "
                                                        f"(spread {args.perturb:g}, seed {args.seed})")
    obj = {"model": args.model, "output": args.output, "samples": rec.n_samples, "duration_s": rec.duration,
           "dt_s": rec.dt, "columns": list(rec.columns()), "true_params": args.true_params_out,
           "design": adaptation.to_dict()}
    text = (f"{args.model}: identification experiment, {rec.n_samples} samples over {rec.duration:g} s "
            f"written to {args.output}" + (f"; true parameters in {args.true_params_out}"
                                            if args.true_params_out else ""))
    if adaptation.note:
        text += f"\n  design: {adaptation.note}"
    _emit(obj, text + _excursion_lines(rec, obj), args.json)
    return 0


_URDF_EXPERIMENT = (
    ("--chain", "chain", None, "names a finger of the Alpes hand; a URDF --model's experiment excites every motor of "
     "its spec"),
    ("--perturb", "perturb", None, "draws an Alpes parameter file; for a URDF --model give the perturbed robot's "
     "spec as --true-spec"),
    ("--true-params-out", "true_params_out", None, "goes with --perturb on an Alpes model; a URDF --model's true "
     "robot is --true-spec"),
    ("--rig", "rig", "auto", "hangs an Alpes hand fingers down; a URDF --model's experiment runs in its spec's "
     "gravity"),
)


def _experiment_robot(args: argparse.Namespace) -> int:
    """``experiment --model PATH.urdf --spec FILE.toml [--true-spec TRUE.toml]``: the documented multisine designed
    on the spec's robot, simulated on the true one
    (:func:`~alpes_dyn.estimation.experiments.experiment.model_experiment`)."""
    from ..estimation.experiments.experiment import ExperimentDesign, model_experiment
    from ..model.robot import Model

    _refuse_for_urdf(args, _URDF_EXPERIMENT)
    _check_run_files(args, {"-o": ("csv",)})  # a recording: a CSV by its name
    nominal = _urdf_robot(args, "the identification experiment")
    truth = None
    if args.true_spec or args.true_model:
        try:
            truth = Model.from_urdf_file(args.true_model or args.model, args.true_spec or args.spec)
        except (InputError, ModelError) as e:
            raise InputError(f"{'--true-model' if args.true_model else '--true-spec'}: {e}") from None
        if truth.joint_names != nominal.joint_names or truth.motor_names != nominal.motor_names:
            flag = "--true-model" if args.true_model else "--true-spec"
            raise InputError(f"{flag}: the true robot has joints {', '.join(truth.joint_names)} and motors "
                             f"{', '.join(truth.motor_names)}; expected the --model's {', '.join(nominal.joint_names)} "
                             f"and {', '.join(nominal.motor_names)}")
    design = ExperimentDesign(duration=args.duration, amplitude_fraction=args.amplitude,
                              stick_seconds=args.stick_seconds)
    with warnings.catch_warnings():  # its lines printed on stdout, one per motor: _excursion_lines
        warnings.simplefilter("ignore", SmallExcursionWarning)
        rec = model_experiment(nominal, truth, design, seed=args.seed, path=args.output)
    obj = {"model": args.model, "spec": args.spec, "true_spec": args.true_spec, "true_model": args.true_model,
           "amplitude": args.amplitude, "output": args.output, "samples": rec.n_samples, "duration_s": rec.duration,
           "dt_s": rec.dt, "columns": list(rec.columns())}
    true_robot = " + ".join(x for x in (args.true_model, args.true_spec) if x) or args.spec
    text = (f"{nominal.name}: identification experiment on {', '.join(nominal.motor_names)}, {rec.n_samples} samples "
            f"over {rec.duration:g} s (true robot: {true_robot}) written to {args.output}")
    _emit(obj, text + _excursion_lines(rec, obj), args.json)
    return 0
