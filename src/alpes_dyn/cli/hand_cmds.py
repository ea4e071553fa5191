"""``alpes-dyn experiment --model hand`` and ``alpes-dyn identify --model hand``: the whole hand in one experiment
(:mod:`alpes_dyn.estimation.experiments.hand_experiment`), one recording of its six motors, every chain fitted from it
into one parameter file."""

from __future__ import annotations

import argparse
import dataclasses
import warnings

from ..errors import InputError
from ..estimation.experiments.excursion import SmallExcursionWarning
from .common import _Untrusted, _check_run_files, _emit, _excursion_lines, data_label, read_data


def experiment_hand(args: argparse.Namespace) -> int:
    """The six motors excited at once (each chain's experiment, one orientation of the hand), one recording."""
    from ..estimation.experiments.design import ExperimentDesign
    from ..estimation.experiments.draws import perturbed_params
    from ..estimation.experiments.hand_experiment import hand_chains, hand_experiment
    from ..model.params import load_params, write_params

    if args.chain is not None:
        raise InputError("--chain: the hand's experiment drives every chain at once; for one finger give --model "
                         "finger3 --chain NAME (or --model thumb)")
    _check_run_files(args, {"-o": ("csv",)})
    if args.perturb is None and args.true_params_out is not None:
        raise InputError("--true-params-out: goes with --perturb (otherwise the true file is --params)")
    if args.rig == "both":
        raise InputError("--rig both: one finger at a time (--model finger2/finger3/thumb --chain NAME); the hand's "
                         "six motors are excited at once in one orientation: auto, level or hanging")
    truth = load_params(args.params)
    if args.perturb is not None:  # every chain its own values, drawn
        truth = perturbed_params(truth, args.perturb, args.seed, chains=hand_chains(truth))
    with warnings.catch_warnings():  # its lines printed on stdout, one per motor: _excursion_lines
        warnings.simplefilter("ignore", SmallExcursionWarning)
        rec, how = hand_experiment(truth, ExperimentDesign(duration=args.duration, amplitude_fraction=args.amplitude), seed=args.seed,
                                   path=args.output, nominal_params=args.params, rig=args.rig)
    if args.true_params_out is not None:
        write_params(truth, args.true_params_out, header=f"true parameters drawn by alpes-dyn experiment --model "
                                                        f"hand (spread {args.perturb:g}, seed {args.seed})")
    obj = {"model": "hand", "output": args.output, "samples": rec.n_samples, "duration_s": rec.duration,
           "dt_s": rec.dt, "columns": list(rec.columns()), "true_params": args.true_params_out,
           "design": {c: a.to_dict() for c, a in how.items()}}
    rig = next(iter(how.values())).rig
    where = "palm up" if rig == "level" else "hung fingers down"
    text = (f"hand: identification experiment of the six motors at once ({where}), {rec.n_samples} samples over "
            f"{rec.duration:g} s written to {args.output}"
            + (f"; true parameters in {args.true_params_out}" if args.true_params_out else ""))
    text += "".join(f"\n  design, {c}: {a.note}" for c, a in how.items() if a.note)
    _emit(obj, text + _excursion_lines(rec, obj), args.json)
    return 0


def _chain_lines(chain: str, fit) -> list[str]:
    """A chain's lines of the text output: its verdict, then its parameters (value, std) and those not identified."""
    res = fit.result
    lines = [f"  {chain}: {'converged' if res.converged else 'NOT converged'}, {res.seconds:.1f} s, effects "
             f"{'+'.join(fit.effects) or 'none'}, residual {res.residual_rms:.3g} counts; "
             + (res.adequacy.summary() if res.adequacy is not None else "")]
    w = max(10, *(len(n) for n in res.names))
    lines += [f"    {n:{w}s} {v:12.6g} {sd:10.3g}  {u}" for n, v, sd, u in zip(res.names, res.values, res.std,
                                                                             res.units)]
    if res.standard_errors is not None:  # which covariance each std is (estimation.identification.robust_covariance)
        lines.append(f"    {res.standard_errors.summary(res.names)}")
    lines += [f"    {n:{w}s} not identified: {why}" for n, why in res.not_identified.items()]
    return lines


def identify_hand(args: argparse.Namespace) -> int:
    """Every chain of the hand (or ``--chain``'s) fitted from one recording of its six motors (--data), each as
    ``identify --model finger3 --chain NAME`` / ``--model thumb`` fits it; one parameter file (-o) with every chain's
    section, written only where every chain's fit is to be trusted (or with --force)."""
    from ..estimation.experiments.hand_experiment import chain_model_name, chain_recording, hand_chains
    from ..estimation.experiments.recording import read_recording
    from ..model.params import load_params, write_params
    from ..model.robot import Model
    from .fitting import _fit, _identify_lines

    if args.parameters is not None:
        raise InputError("--parameters: with --model hand each chain fits its default selection; to name a chain's "
                         "parameters fit its columns with --model finger3 --chain NAME (or --model thumb)")
    if args.spec is not None:
        raise InputError("--spec: applies to a URDF --model; the Alpes hand takes its transmission from --params")
    _check_run_files(args, {"-o": ("toml",)})
    p = load_params(args.params)
    chains = hand_chains(p)
    if args.chain is not None and args.chain not in chains:
        raise InputError(f"--chain: unknown chain {args.chain!r} of the hand (expected one of {', '.join(chains)})")
    freqs = _identify_lines(args)
    hand = Model.alpes("hand", params=p)
    data = read_data(args, hand)
    if data.true_q is not None:  # a simulation's truth, which no fit reads: not held through five fits (72 MB at 600 s)
        data = dataclasses.replace(data, true_q=None)
    val = None if args.validate is None else read_recording(args.validate, hand, args.torque_constant)
    out, done, lines, untrusted, seconds = p, {}, [], {}, 0.0
    for chain in (args.chain,) if args.chain else chains:
        a = argparse.Namespace(**{**vars(args), "model": chain_model_name(chain),
                                  "chain": None if chain == "thumb" else chain})
        fit, _ = _fit(a, freqs, (chain_recording(data, chain), None if val is None else chain_recording(val, chain)))
        fit.result.recording_path = data_label(args)
        # what the outputs take of the chain's fit, and the fit let go before the next chain's (its rounds'
        # residuals, states and solutions: tens of MB each on a 600 s record)
        done[chain] = {**fit.result.to_dict(), "effects": list(fit.effects)}
        seconds += fit.seconds
        out = fit.result.params(out, chain)
        lines += _chain_lines(chain, fit)
        if not fit.result.trustworthy:
            untrusted[chain] = fit.result.status()
        fit = None
    written = args.output is not None and (not untrusted or args.force)
    if written:
        header = f"Identified by alpes_dyn from {data_label(args)}, chain by chain ({', '.join(done)})"
        if untrusted:
            header += f"\nNOT TRUSTWORTHY (written with --force): {', '.join(untrusted)}"
        write_params(out, args.output, header=header)
    obj = {"model": "hand", "output": args.output if written else None, "trustworthy": not untrusted,
           "seconds": seconds, "chains": done}
    text = (f"hand: {len(done)} chains identified from {data_label(args)} in {obj['seconds']:.1f} s"
            + (f", written to {args.output}" if written else "") + "\n" + "\n".join(lines))
    _emit(obj, text, args.json)
    if untrusted and not args.force:
        raise _Untrusted(f"alpes-dyn: identify: {', '.join(untrusted)} not trustworthy, "
                         f"{'nothing written' if args.output else 'no file'} (--force writes it anyway): "
                         + "; ".join(f"{c}: {why}" for c, why in untrusted.items()))
    return 0
