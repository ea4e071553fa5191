"""The commands on recordings and observers: ``estimate`` (an observer on the simulated scenario or on a
recording), ``experiment`` (the identification experiment simulated, its recording written) and
``identify`` (a chain's parameters fitted to a recording; exit code 3 when the fit is not to be trusted)."""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from ..errors import InputError
from .common import (UntrustedFitWarning, _check_model_options, _check_run_files, _emit, _is_urdf_path,
                     _model_from_args, _one_chain, _one_of, _Untrusted, parse_vector)


THUMB_PARAMETERS = "K,m_thumb_j1,m_thumb_j2,F_s_thumb_j1,F_s_thumb_j2,F_v_thumb_j1,F_v_thumb_j2"
"""What ``alpes-dyn identify --model thumb`` fits by default: the flexion joints' springs, masses and friction.
Not the ab/adduction joint's own parameters: its base's mass sits on the axis (nothing the encoders see depends on
it: standard error 100 %), and its friction is weak (F_v 21 % standard error: the joint only creeps) and, fitted
from 20 % off, spoils the rest on some thumbs (seed 2: 0.66 counts after 50 iterations, a mass 2.8 % off; without
it 0.58 counts, 0.32 %). Ask for them by name (``F_s_thumb_abd``...)."""


# ---- owned by the observers work (issue 4)
def cmd_estimate(args: argparse.Namespace) -> int:
    """Simulate the default scenario (alpes_dyn.estimation.scenario) and estimate the joints from the motor encoder."""
    from ..estimation.observers import OBSERVERS
    from ..estimation.scenario import ESTIMATION_MODELS, check_plot_path, plot_estimation, run_estimation

    if args.data is not None:
        return _estimate_data(args)
    for flag, dest in (("--disturbance", "disturbance"), ("--torque-noise", "torque_noise"), ("--log", "log"),
                       ("--encoder-offset", "encoder_offset"), ("--tilt", "tilt"), ("--rotor-inertia", "rotor_inertia"),
                       ("--torque-constant", "torque_constant")):
        if getattr(args, dest) not in (None, False):
            raise InputError(f"{flag}: applies to an observer on a recording (--data REC.csv)")
    _check_model_options(args)
    _one_chain(args.model, ESTIMATION_MODELS, "the estimation scenario")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    if args.plot is not None:
        check_plot_path(args.plot)  # before the run: matplotlib, a writable file name, a known format
    _check_run_files(args)
    t0 = time.perf_counter()
    if args.true_params is not None and args.params is not None:
        raise InputError("--true-params: give either --params or --true-params (the simulated finger's file)")
    if args.observer_params is not None and args.mismatch != 0:
        raise InputError("--observer-params: give either --mismatch or --observer-params, not both")
    res = run_estimation(args.observer, model=args.model, spring=args.spring or "torsional",
                         params=args.true_params if args.true_params is not None else args.params,
                         observer_params=args.observer_params, friction=args.friction,
                         mismatch=args.mismatch, duration=args.duration, seed=args.seed, chain=args.chain)
    if args.plot is not None:
        plot_estimation(res, args.plot)
    obj = res.to_dict()
    obj["seconds"] = time.perf_counter() - t0
    if args.plot is not None:
        obj["plot"] = args.plot
    deg = np.degrees
    lines = [
        f"{res.scenario.model}{f' ({args.chain})' if args.chain else ''}: joints estimated from the motor encoder "
        f"by {args.observer} "
        f"(mismatch {args.mismatch:g}, {args.duration:g} s, seed {args.seed})",
        f"  encoder {res.counts_per_rev:g} counts/rev + {res.scenario.encoder_noise_counts:g} count noise; "
        f"motor torque noise {res.scenario.torque_noise:g} N m",
        f"  {f'RMSE after {res.scenario.transient_s:g} s [deg]:':30s}"
        + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.rmse)),
        f"  {'final error [deg]:':30s}"
        + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.final_error)),
    ]
    for name, p in res.parameters.items():
        lines.append(f"  {name}: estimated {p['estimate']:.4f}, true {p['true']:.4f}")
    if args.plot is not None:
        lines.append(f"  figure: {args.plot}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0


_SCENARIO_ONLY = (("--mismatch", "mismatch", 0.0), ("--duration", "duration", 5.0), ("--seed", "seed", 0),
                  ("--true-params", "true_params", None), ("--observer-params", "observer_params", None),
                  ("--plot", "plot", None))


def _estimate_data(args: argparse.Namespace) -> int:
    """``estimate --data REC.csv``: the observer on a recorded encoder and torque (estimation.replay)."""
    from ..estimation.observers import OBSERVERS
    from ..estimation.recording import read_recording
    from ..estimation.replay import estimate_recording
    from ..model.robot import Model

    for flag, dest, default in _SCENARIO_ONLY:
        if getattr(args, dest) != default:
            hint = "; the observer's model is --params" if dest in ("true_params", "observer_params") else ""
            raise InputError(f"{flag}: applies to the simulated scenario, not to a recording (--data){hint}")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    _check_run_files(args)  # the output policy: --log is not --data (nor --params...), not a link, a device...
    t0 = time.perf_counter()
    if _is_urdf_path(args.model):
        model = _model_from_args(args)
    else:
        _check_model_options(args)
        model = Model.alpes(args.model, spring=args.spring or "torsional", friction=args.friction,
                            rotor_inertia=args.rotor_inertia, params=args.params, chain=args.chain)
    rec = read_recording(args.data, model, args.torque_constant)
    offset = parse_vector(args.encoder_offset, "--encoder-offset") if args.encoder_offset is not None else None
    tilt = parse_vector(args.tilt, "--tilt") if args.tilt is not None else None
    res = estimate_recording(rec, model, args.observer, torque_noise=args.torque_noise,
                             disturbance=args.disturbance, encoder_offset=offset, tilt=tilt)
    if args.log is not None:
        res.to_csv(args.log)
    obj = res.to_dict()
    obj.update({"data": args.data, "model": args.model, "chain": args.chain, "params": args.params,
                "seconds": time.perf_counter() - t0})
    if args.log is not None:
        obj["log"] = args.log
    deg = np.degrees
    lines = [f"{args.model}{f' ({args.chain})' if args.chain else ''}: joints estimated by {args.observer} from "
             f"{args.data} ({rec.n_samples} samples, {rec.duration:g} s)",
             f"  torque noise {res.settings['torque_noise_Nm']:.3g} N m"
             + (" (estimated from the recording)" if args.torque_noise is None else "")
             + ("; a disturbance torque per motor" if args.disturbance else "")]
    if res.rmse is not None:
        head = f"RMSE after {res.settings['transient_s']:g} s [deg]:"
        lines.append(f"  {head:30s}"
                     + "  ".join(f"{j} {deg(e):.3f}" for j, e in zip(res.joint_names, res.rmse)))
    else:
        lines.append("  no true_q_* columns: no error to report")
    lines.append(f"  {'final estimate [deg]:':30s}"
                 + "  ".join(f"{j} {deg(q):.2f}" for j, q in zip(res.joint_names, res.q_hat[-1])))
    if res.disturbance is not None:
        lines.append(f"  {'final disturbance [N m]:':30s}"
                     + "  ".join(f"{mn} {d:.3g}" for mn, d in zip(res.motor_names, res.disturbance[-1])))
    if args.log is not None:
        lines.append(f"  log: {args.log}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _emit(obj, "\n".join(lines), args.json)
    return 0


def cmd_experiment(args: argparse.Namespace) -> int:
    """Simulate the documented identification experiment and write its recording."""
    from ..model.description import model_params
    from ..estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign, experiment, perturbed_params
    from ..model.params import load_params, write_params

    _one_chain(args.model, EXPERIMENT_MODELS, "the identification experiment")
    _check_run_files(args)
    if args.perturb is None and args.true_params_out is not None:
        raise InputError("--true-params-out: goes with --perturb (otherwise the true file is --params)")
    truth = load_params(args.params)
    model_params(args.model, truth, args.chain)  # a bad --chain: one line, before any work
    if args.perturb is not None:  # the chain's own values drawn (the thumb's, a finger's, or the shared finger's)
        chains = ("thumb",) if args.model == "thumb" else ((args.chain,) if args.chain else None)
        truth = perturbed_params(truth, args.perturb, args.seed, chains=chains)
    rec = experiment(args.model, truth, ExperimentDesign(duration=args.duration), seed=args.seed,
                     nominal_params=args.params, path=args.output, chain=args.chain)
    if args.true_params_out is not None:
        write_params(truth, args.true_params_out, header=f"true parameters drawn by alpes-dyn experiment "
                                                        f"(spread {args.perturb:g}, seed {args.seed})")
    obj = {"model": args.model, "output": args.output, "samples": rec.n_samples, "duration_s": rec.duration,
           "dt_s": rec.dt, "columns": list(rec.columns()), "true_params": args.true_params_out}
    text = (f"{args.model}: identification experiment, {rec.n_samples} samples over {rec.duration:g} s "
            f"written to {args.output}" + (f"; true parameters in {args.true_params_out}"
                                            if args.true_params_out else ""))
    _emit(obj, text, args.json)
    return 0


def _fit(args: argparse.Namespace, freqs):
    """The fit: --parameters as named (the stick-slip law where --effects asks for it), else the default selection
    with the effects' parameters added, --effects auto trying the stick-slip law where the first fit's adequacy
    check names it (:mod:`alpes_dyn.estimation.effects`). Returns the EffectsFit."""
    from ..estimation.adequacy import AdequacyWarning
    from ..estimation.effects import EffectsFit, fit_effects, parse_effects, stiction_params
    from ..estimation.identification import check_selection, identify
    from ..estimation.recording import read_recording
    from ..model.params import load_params
    from ..model.robot import Model

    effects = parse_effects(args.effects) if args.effects is not None else (
        () if args.parameters is not None else parse_effects(None))
    if args.parameters is not None and set(effects) - {"stiction", "rotor"}:
        raise InputError(f"--effects: {', '.join(e for e in effects if e not in ('stiction', 'rotor'))} with "
                         "--parameters: name their parameters there (tendon_compliance, tilt_y or tilt, encoder_offset)")
    p = load_params(args.params)
    p_stick = stiction_params(p) if "stiction" in effects or "auto" in effects else None

    def model_of(effs: tuple[str, ...]) -> Model:
        return Model.alpes(args.model, friction=True, rotor_inertia=args.rotor_inertia or "rotor" in effs,
                           params=p_stick if "stiction" in effs else p, chain=args.chain)

    data, validate = args.data, args.validate
    if args.torque_constant is not None:  # current_<motor> columns: the recordings read here, as torques
        data = read_recording(args.data, model_of(()), args.torque_constant)
        if validate is not None:
            validate = read_recording(args.validate, model_of(()), args.torque_constant)
    kw = dict(excitation=freqs, torque_noise=args.torque_noise, validation=validate,
              encoder_noise=args.encoder_noise)
    if args.parameters is not None:
        model = model_of(effects)
        check_selection(model, args.parameters)  # a bad selection named before the fit
        with warnings.catch_warnings():  # the command reports the verdict itself, in its one line
            warnings.simplefilter("ignore", AdequacyWarning)
            return EffectsFit(identify(model, data, args.parameters, **kw), effects)
    base = THUMB_PARAMETERS if args.model == "thumb" else None
    rec = data if args.torque_constant is not None else read_recording(args.data, model_of(()))
    return fit_effects(model_of, data, effects, base, rec.gravity is not None, **kw)  # tilt only where not given


def cmd_identify(args: argparse.Namespace) -> int:
    """Fit the parameters of a finger to a recording; write the identified parameter file."""
    from ..estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign

    _one_chain(args.model, EXPERIMENT_MODELS, "identification")
    _check_run_files(args)  # the output policy: -o is none of --data, --validate, --params, nor a link...
    exc = args.excitation
    if exc == "documented":
        freqs = ExperimentDesign().frequencies
    elif exc == "none":
        freqs = None
    else:
        freqs = tuple(parse_vector(exc, "excitation"))
    fit = _fit(args, freqs)
    res, model = fit.result, fit.result.model
    res.recording_path = args.data  # the identified file's header names the recording read
    written = args.output is not None and (res.trustworthy or args.force)
    if written:
        res.write(args.output)
    obj = res.to_dict()
    obj["output"] = args.output if written else None
    obj["chain"] = model.chain
    obj["effects"] = list(fit.effects)
    obj["tried"] = None if fit.tried is None else {
        "effects": list(fit.tried_effects), "residual_rms": fit.tried.residual_rms, "converged": fit.tried.converged,
        "verdict": fit.tried.status()}
    lines = [f"{args.model}{f' ({args.chain})' if args.chain else ''}: parameters identified from {args.data} "
             f"({res.iterations} Gauss-Newton iterations, "
             f"{'converged' if res.converged else 'NOT converged'}, {res.seconds:.1f} s)",
             f"  {'parameter':{max(10, *(len(n) for n in res.names))}s} {'value':>12s} {'std':>10s} {'start':>12s}  unit"]
    w = max(10, *(len(n) for n in res.names))
    for n, v, sd, i, u in zip(res.names, res.values, res.std, res.initial, res.units):
        lines.append(f"  {n:{w}s} {v:12.6g} {sd:10.3g} {i:12.6g}  {u}")
    lines.append(f"  encoder residual {res.residual_rms:.3g} counts RMS")
    a = res.adequacy
    if a is not None:
        lines.append(f"  sensor floor {a.floor.total:.3g} counts (quantisation {a.floor.quantisation:.3g}, noise "
                     f"{a.floor.noise:.3g}, torque {a.floor.torque:.3g}); {a.summary()}")
        if a.validation is not None:
            v = a.validation
            lines.append(f"  validation on {args.validate}: fit {', '.join(f'{x:.1f}' for x in v.fit_percent)} %, "
                         f"NRMSE {', '.join(f'{x:.3g}' for x in v.nrmse)}")
    if written:
        lines.append(f"  written to {args.output}" + ("" if res.trustworthy else " (marked NOT trustworthy)"))
    _emit(obj, "\n".join(lines), args.json)
    if not res.trustworthy:
        why = res.status()
        if not args.force:
            raise _Untrusted(f"alpes-dyn: identify: not trustworthy, {'nothing written' if args.output else 'no file'}"
                             f" (--force writes it anyway): {why}")
        warnings.warn(UntrustedFitWarning(f"identify --force: {args.output or 'the fit'} is NOT trustworthy: {why}"))
    return 0
