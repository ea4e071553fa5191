"""The commands on recordings and observers: ``estimate`` (an observer on the simulated scenario or on a
recording) and ``identify`` (a chain's parameters fitted to a recording; exit code 3 when the fit is not to be
trusted); ``codegen`` is :mod:`~alpes_dyn.cli.codegen_cmds`."""

from __future__ import annotations

import argparse
import dataclasses
import time
import warnings
from typing import Any

import numpy as np

from ..errors import InputError
from ..estimation.experiments.excursion import excursion_report
from ..estimation.identification.identification import THUMB_PARAMETERS  # noqa: F401  (its old place)
from .fitting import (_check_mjcf_option, _fit, _identify_lines, _mass_urdf_path, _mjcf_applies, _write_robot,
                      _written_lines)
from .uncertainty import _sigma_limit, _uncertainty
from .common import (UntrustedFitWarning, _check_model_options, _check_run_files, _emit, _note_untrusted,
                     _trust_notes, friction_from_file,
                     _is_urdf_path, _one_chain, _one_of, _refuse_for_urdf, _Untrusted, _urdf_robot,
                     data_label, parse_vector, read_data)


FRICTION_LAW_HELP = ("with --data: the observer's dry friction, smooth (F_s tanh(v/v_s)), stick (the "
                     "time-stepping Coulomb law, which holds a joint at rest under a torque below F_s; the torque "
                     "read through a 10-sample moving average) or lugre (a bristle state per joint, the parameter "
                     "file's friction.sigma0/sigma1, the torque averaged likewise). Default the file's: lugre where "
                     "its friction.law is lugre, else smooth")
"""``estimate --friction-law``'s help (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`)."""


# ---- owned by the observers work (issue 4)
def cmd_estimate(args: argparse.Namespace) -> int:
    """Simulate the default scenario (alpes_dyn.estimation.observers.scenario) and estimate the joints from the motor
    encoder."""
    from ..estimation.observers.observers import OBSERVERS
    from ..estimation.observers.scenario import ESTIMATION_MODELS, check_plot_path, plot_estimation, run_estimation
    from .common import _given

    if args.data is not None:
        return _estimate_data(args)
    for flag, dest in (("--disturbance", "disturbance"), ("--torque-noise", "torque_noise"), ("--log", "log"),
                       ("--encoder-offset", "encoder_offset"), ("--tilt", "tilt"), ("--rotor-inertia", "rotor_inertia"),
                       ("--torque-constant", "torque_constant"), ("--torque-delay", "torque_delay"),
                       ("--friction-law", "friction_law"), ("--stops", "stops"), ("--law-spread", "law_spread"),
                       ("--band-sigma", "band_sigma"), ("--no-band-sigma", "no_band_sigma")):
        if _given(getattr(args, dest)):
            raise InputError(f"{flag}: applies to an observer on a recording (--data REC.csv)")
    if _is_urdf_path(args.model):
        raise InputError("--model: the simulated estimation scenario is the Alpes fingers'; on a URDF --model run "
                         "the observer on a recording (--data REC.csv, e.g. written by alpes-dyn experiment)")
    if args.friction_free:
        raise InputError("--friction-free: applies to a URDF --model on a recording (--data); the Alpes models "
                         "take --friction")
    _check_model_options(args)
    _one_chain(args.model, ESTIMATION_MODELS, "the estimation scenario")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    if args.plot is not None:
        check_plot_path(args.plot)  # before the run: matplotlib, a writable file name, a known format
    _check_run_files(args)
    limit = _sigma_limit(args.sigma_limit)
    t0 = time.perf_counter()
    if args.true_params is not None and args.params is not None:
        raise InputError("--true-params: give either --params or --true-params (the simulated finger's file)")
    if args.observer_params is not None and args.mismatch != 0:
        raise InputError("--observer-params: give either --mismatch or --observer-params, not both")
    notes = _trust_notes(args, [("--params", args.params), ("--observer-params", args.observer_params)])
    friction_from_file(args, *next(((f, flag) for f, flag in ((args.observer_params, "--observer-params"),
                                    (args.true_params, "--true-params"), (args.params, "--params")) if f is not None),
                                   (None, "--params")))
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
    more, extra = _uncertainty(res.estimate, res.filter, res.u_meas, res.q_true, res.scenario.transient_s,
                               res.joint_names, limit)
    obj.update(more)
    lines += extra
    obj["seconds"] = time.perf_counter() - t0
    if args.plot is not None:
        lines.append(f"  figure: {args.plot}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0


_SCENARIO_ONLY = (("--mismatch", "mismatch", 0.0), ("--duration", "duration", 5.0), ("--seed", "seed", 0),
                  ("--true-params", "true_params", None), ("--observer-params", "observer_params", None),
                  ("--plot", "plot", None))


def _estimate_data(args: argparse.Namespace) -> int:
    """``estimate --data REC.csv``: the observer on a recorded encoder and torque (estimation.observers.replay)."""
    from ..estimation.observers.observers import OBSERVERS
    from ..estimation.experiments.recording import read_recording
    from ..estimation.observers import replay, torque_reading
    from ..simulation.stick import library_law, observer_friction_law

    for flag, dest, default in _SCENARIO_ONLY:
        if getattr(args, dest) != default:
            hint = "; the observer's model is --params" if dest in ("true_params", "observer_params") else ""
            raise InputError(f"{flag}: applies to the simulated scenario, not to a recording (--data){hint}")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    _check_law_options(args)
    law = args.friction_law
    _check_run_files(args)  # the output policy: --log is not --data (nor --params...), not a link, a device...
    limit = _sigma_limit(args.sigma_limit)
    t0 = time.perf_counter()
    notes = _trust_notes(args, [("--spec", args.spec) if _is_urdf_path(args.model) else ("--params", args.params)])
    model, whole = _data_model(args)
    law = law if law is not None else observer_friction_law(model)  # the file's law
    delay = args.torque_delay  # None: the file's (transmission.torque_delay, as identify wrote it)
    if delay is not None and not 0 <= delay <= torque_reading.MAX_DELAY:
        raise InputError(f"--torque-delay: expected a whole number of samples from 0 to {torque_reading.MAX_DELAY} "
                         f"(identify's torque_delay), got {delay}")
    rec = read_recording(args.data, model, args.torque_constant, ignore_others_of=whole)
    offset = parse_vector(args.encoder_offset, "--encoder-offset") if args.encoder_offset is not None else None
    tilt = parse_vector(args.tilt, "--tilt") if args.tilt is not None else None
    def run(friction_law: str, model: Any = model):
        return replay.estimate_recording(rec, model, args.observer, torque_noise=args.torque_noise,
                                  disturbance=args.disturbance, encoder_offset=offset, tilt=tilt,
                                  torque_delay=delay, friction_law=friction_law, force=args.force, stops=args.stops)

    res = run(law)
    spread = _law_spread(run, res, model, law) if args.law_spread else None
    band = _band_sigma(args, res, library_law(model, law))
    if args.log is not None:  # its q_std the sigma reported: the band's widening in it where there is one
        (res if band is None else dataclasses.replace(res, estimate=band.widened(res.estimate))).to_csv(args.log)
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
             + ("; a disturbance torque per motor" if args.disturbance else "")
             + (f"; stick-slip friction law, the torque averaged over {res.settings['torque_window_samples']} samples"
                if res.settings["friction_law"] == "stick" else "")
             + (f"; LuGre friction law (a bristle state per joint), the torque averaged over "
                f"{res.settings['torque_window_samples']} samples" if res.settings["friction_law"] == "lugre" else "")]
    from_file = [w for w, given, v in (
        (f"torque delay {res.settings['torque_delay_samples']} samples", args.torque_delay,
         res.settings["torque_delay_samples"]),
        ("encoder offset " + ", ".join(f"{x:.4g}" for x in res.settings["encoder_offset_rad"]) + " rad",
         args.encoder_offset, any(res.settings["encoder_offset_rad"]))) if given is None and v]
    if from_file:
        lines.append(f"  from --params: {'; '.join(from_file)} (as identified)")
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
    more, extra = _uncertainty(res.estimate, res.filter, res.inputs, rec.true_q if res.rmse is not None else None,
                               res.settings["transient_s"], res.joint_names, limit, whole=res.segments == 1,
                               measurement=res.measurement, spread=spread, band=band)
    obj.update(more)
    lines += extra
    obj["seconds"] = time.perf_counter() - t0
    if args.log is not None:
        lines.append(f"  log: {args.log}")
    lines.append(f"  {obj['seconds']:.1f} s")
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0


def _check_law_options(args: argparse.Namespace) -> None:
    """``estimate --data``'s friction options, before the run: ``--friction-law`` one of
    :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`, not both ``--band-sigma`` and ``--no-band-sigma``
    (:class:`~alpes_dyn.errors.InputError` naming the option)."""
    from ..simulation.stick import FRICTION_LAWS

    if args.friction_law is not None:
        _one_of(args.friction_law, FRICTION_LAWS, "--friction-law", "friction law")
    if args.band_sigma and args.no_band_sigma:
        raise InputError("--no-band-sigma: give either --band-sigma (the default) or --no-band-sigma")


def _law_spread(run: Any, res: Any, model: Any, law: str) -> Any:
    """``estimate --law-spread``: the observer run again with each other law of the library, the joints' spread
    (:func:`~alpes_dyn.estimation.observers.law_sigma.law_sigma`; ``run(observer_law, model)`` the observer, ``res``
    its run on ``model`` with the observer's law ``law``, named as the file's:
    :func:`~alpes_dyn.simulation.stick.library_law`; each other law on the file with its ``friction.law``,
    :func:`~alpes_dyn.simulation.stick.law_model`)."""
    from ..estimation.observers.law_sigma import law_sigma
    from ..simulation.stick import LIBRARY_LAWS, law_model, library_law

    def run_law(other: str) -> Any:
        m, observer_law = law_model(model, other)
        return run(observer_law, m)

    # the creep law's band is read from a parameter file: without one (a URDF with its spec), not run
    laws = tuple(name for name in LIBRARY_LAWS if model.params is not None or LIBRARY_LAWS[name][1] != "creep")
    return law_sigma(run_law, res, laws=laws, kept_law=library_law(model, law))


def _band_sigma(args: argparse.Namespace, res: Any, law: str) -> Any:
    """``estimate --data``'s widening by the dry-friction band (by default; ``--no-band-sigma``: None): the joints'
    variance from the band along ``res`` (the observer's run;
    :func:`~alpes_dyn.estimation.observers.band_sigma.band_sigma` on its model, estimate and torque, c that of the
    observer's ``law`` as :func:`~alpes_dyn.simulation.stick.library_law` names it; before the log is written). None
    where the observer's model has no dry friction (nothing to widen by) or the recording holds several orientations
    (one filter each: their gravity differs); there, an :class:`~alpes_dyn.errors.InputError` naming
    ``--band-sigma`` if it was asked for by name. By default, the joints of a direction the band does not bound
    (:attr:`~alpes_dyn.estimation.observers.band_sigma.BandSigma.unbounded`) get nothing from it: the observability
    analysis flags them and reports the data's bound (:func:`~alpes_dyn.cli.uncertainty.reported_sigma`), tighter
    than the band's prior."""
    from ..estimation.observers.band_sigma import band_fraction, band_sigma

    if args.no_band_sigma:
        return None
    model = res.filter.model.system.model
    if not np.any(np.asarray(model.extras.coulomb) > 0):
        if not args.band_sigma:
            return None
        raise InputError("--band-sigma: the observer's model has no dry friction (F_s 0 on every joint: give "
                         "--friction, or a file with F_s)")
    if res.segments != 1:
        if not args.band_sigma:
            return None
        raise InputError(f"--band-sigma: the recording holds {res.segments} orientations (one filter each); run "
                         "it on one orientation's part")
    band = band_sigma(model, res.estimate.z, res.inputs, fraction=band_fraction(law), law=law)
    if args.band_sigma or not band.unbounded:
        return band
    # by default a joint the band does not bound is left to the observability analysis, whose data's bound it
    # reports (reported_sigma) rather than the band's prior
    keep = np.array([j not in band.unbounded for j in model.joint_names])
    return dataclasses.replace(band, variance=band.variance * keep)


def _data_model(args: argparse.Namespace) -> tuple[Any, Any]:
    """``estimate --data``'s observer model and, with ``--chain`` on a URDF, the whole robot whose other columns the
    recording may hold (None otherwise)."""
    from ..model.robot import Model

    if _is_urdf_path(args.model):
        whole = _urdf_robot(args, "the observer")
        model = _chain_model(whole, args.chain)  # --chain MOTOR: the observer on that motor's branches alone
        if args.friction_free:
            model = _without_friction(model)
        return model, (whole if args.chain is not None else None)
    if args.friction_free:
        raise InputError("--friction-free: applies to a URDF --model (its spec's friction taken off); the Alpes "
                         "models take --friction")
    _check_model_options(args)
    friction_from_file(args, args.params, "--params")
    return Model.alpes(args.model, spring=args.spring or "torsional", friction=args.friction,
                       rotor_inertia=args.rotor_inertia or _rotor_identified(args.params), params=args.params,
                       chain=args.chain), None


def _rotor_identified(params: str | None) -> bool:
    """Whether the parameter file's rotor inertia ``transmission.J_m`` was identified (``identify`` fitted it with
    the rotor on the tendons: the observer's model takes it the same way, as ``--rotor-inertia``)."""
    from ..model.params import load_params

    prm = load_params(params).raw.get("transmission.J_m")
    return prm is not None and prm.source == "identified"


def _without_friction(model):
    """``model`` rebuilt from its URDF and spec with the spec's Coulomb and viscous tables taken off."""
    import dataclasses

    from ..model.robot import Model

    return Model(model.urdf, dataclasses.replace(model.spec, coulomb={}, viscous={}, identified=None), name=model.name)


def _drift_lines(drift: dict | None) -> list[str]:
    """``identify --drift``'s text: each encoder's fitted offset drift and each motor's torque-constant scale at the
    knots (none without them)."""
    at = " at " + ", ".join(f"{t:.3g}" for t in (drift or {}).get("knots_s", [])) + " s"
    return ([f"  encoder_{motor} drift: " + ", ".join(f"{v:+.3g}" for v in d) + " counts" + at
             for motor, d in (drift or {}).get("counts", {}).items()]
            + [f"  torque constant {motor} scale: " + ", ".join(f"{v:.4f}" for v in d) + " (relative to the first "
               "sample)" + at for motor, d in (drift or {}).get("torque_scale", {}).items()])


def _data_lines(obj: dict, data: Any) -> list[str]:
    """The fit's data into ``obj``: :func:`~alpes_dyn.estimation.experiments.excursion.excursion_report` (its motors
    whose encoder barely moved: a WARNING line each) and ``runs`` (the recording's runs, each its ``samples`` and
    its ``gravity``, m/s^2, as recorded, or None: the file's; a text line where there are several, e.g.
    ``experiment --rig both``'s two orientations)."""
    obj.update(excursion_report(data))
    warn = [f"  WARNING: {line}" for line in obj["small_excursions"]]
    b = data.run_starts()
    obj["runs"] = [{"samples": int(e - a), "gravity": None if data.gravity is None else
                    [float(x) for x in data.gravity[a]]} for a, e in zip(b[:-1], b[1:])]
    if len(obj["runs"]) < 2:
        return warn
    return [f"  {len(obj['runs'])} runs, gravity " + "; ".join(
        "the file's" if r["gravity"] is None else "(" + ", ".join(f"{x:.3g}" for x in r["gravity"]) + ") m/s^2"
        for r in obj["runs"])] + warn


def cmd_identify(args: argparse.Namespace) -> int:
    """Fit the parameters of a finger (or of a URDF robot) to a recording; write the identified parameter file
    (or, for a URDF robot, its identified spec: :mod:`alpes_dyn.estimation.identification.identified_spec`)."""
    from ..estimation.experiments.experiment import EXPERIMENT_MODELS

    urdf = _is_urdf_path(args.model)
    _mjcf_applies(args, urdf)
    if args.model == "hand":  # every chain from one recording of the six motors
        from .hand_cmds import identify_hand

        return identify_hand(args)
    if not urdf:
        _one_chain(args.model, EXPERIMENT_MODELS, "identification", hand=True)
        if args.spec is not None:
            raise InputError(f"--spec: applies to a URDF --model; the Alpes model {args.model!r} takes its "
                             "transmission from --params")
    _check_run_files(args, {"-o": ("toml",)})  # the output policy: -o (a TOML file) is none of --data, --params...
    freqs = _identify_lines(args)
    fit, data = _fit_robot(args, freqs) if urdf else _fit(args, freqs)
    res, model = fit.result, fit.result.model
    res.recording_path = data_label(args)  # the identified file's header names the recording(s) read
    written = args.output is not None and (res.trustworthy or args.force)
    omitted: list[str] = []  # what the MJCF beside -o cannot hold (--mjcf)
    if written:  # a URDF robot's into a copy of its whole spec (the stick-slip law's smooth_velocity kept, as in a
        # file; with --chain the chain's values replaced, the other motors' and joints' as they were)
        if urdf:
            omitted = _write_robot(res, args)
        else:
            res.write(args.output)
    obj = res.to_dict()
    obj["output"] = args.output if written else None
    obj["chain"] = args.chain if urdf else model.chain
    obj["effects"] = list(fit.effects)
    obj["torque_delay"] = fit.delay  # samples, of the rig's sensors: the file's transmission.torque_delay
    obj["tried"] = None if fit.tried is None else {
        "effects": list(fit.tried_effects), "residual_rms": fit.tried.residual_rms, "converged": fit.tried.converged,
        "verdict": fit.tried.status()}
    obj["rounds"] = [{"effects": list(e), "residual_rms": r.residual_rms, "converged": bool(r.converged),
                      "seconds": r.seconds} for e, r in fit.rounds]
    obj["fit_seconds_total"], obj["notes"] = fit.seconds, list(fit.notes)  # notes: a failed round's (EffectsFit)
    more = (f"; {len(fit.rounds)} fits in {fit.seconds:.1f} s: "
            + ", ".join(f"{'+'.join(e) or 'rigid'} {r.residual_rms:.3g} counts" for e, r in fit.rounds)
            if len(fit.rounds) > 1 else "")
    lines = [f"{args.model}{f' ({args.chain})' if args.chain else ''}: parameters identified from {data_label(args)} "
             f"({res.iterations} Gauss-Newton iterations, "
             f"{'converged' if res.converged else 'NOT converged'}, {res.seconds:.1f} s{more})",
             f"  {'parameter':{max(10, *(len(n) for n in res.names))}s} {'value':>12s} {'std':>10s} {'start':>12s}  unit"]
    w = max(10, *(len(n) for n in res.names))
    for n, v, sd, i, u in zip(res.names, res.values, res.std, res.initial, res.units):
        lines.append(f"  {n:{w}s} {v:12.6g} {sd:10.3g} {i:12.6g}  {u}")
    lines += [f"  {res.standard_errors.summary(res.names)}"] if res.standard_errors is not None else []  # which std
    for n, why in res.not_identified.items():  # held in the fit kept, never written (estimation.identification.bounds)
        lines.append(f"  {n:{w}s} not identified: {why}")
    lines += [f"  note: {n}" for n in fit.notes]
    lines += _drift_lines(res.drift)
    held = _held_masses(model, args) if urdf else ()
    obj["held"] = list(held)
    if held:
        lines.append(f"  held at the URDF's values: {', '.join(held)} (a link that only motorless joints move: the "
                     "encoders see its mass only with those joints' springs; name it in --parameters to fit it)")
    lines.append(f"  encoder residual {res.residual_rms:.3g} counts RMS")
    if fit.delay:
        lines.append(f"  torque delay: the recorded torque {fit.delay} sample{'s' if fit.delay > 1 else ''} late (the "
                     f"rig's sensors: transmission.torque_delay in the file, which estimate --data reads)")
    lines += [] if res.model_error is None else [f"  observer's model error: {res.model_error:.3g} F_s (calibrated)"]
    lines += _data_lines(obj, data)
    a = res.adequacy
    if a is not None:
        lines.append(f"  sensor floor {a.floor.total:.3g} counts (quantisation {a.floor.quantisation:.3g}, noise "
                     f"{a.floor.noise:.3g}, torque {a.floor.torque:.3g}); {a.summary()}")
        if a.validation is not None:
            v = a.validation
            lines.append(f"  validation on {args.validate}: fit {', '.join(f'{x:.1f}' for x in v.fit_percent)} %, "
                         f"NRMSE {', '.join(f'{x:.3g}' for x in v.nrmse)}")
    lines += _written_lines(obj, args, res, urdf and written, written, omitted)
    _emit(obj, "\n".join(lines), args.json)
    if not res.trustworthy:
        why = res.status()
        if not args.force:
            raise _Untrusted(f"alpes-dyn: identify: not trustworthy, {'nothing written' if args.output else 'no file'}"
                             f" (--force writes it anyway): {why}")
        warnings.warn(UntrustedFitWarning(f"identify --force: {args.output or 'the fit'} is NOT trustworthy: {why}"))
    return 0


def _held_masses(model, args: argparse.Namespace) -> tuple[str, ...]:
    """The masses the default selection held on a URDF --model (:func:`~alpes_dyn.symbolic.parametric.unseen_masses`);
    none where --parameters names the selection."""
    from ..symbolic.parametric import unseen_masses

    return unseen_masses(model) if args.parameters is None else ()


_URDF_IDENTIFY = (("--rotor-inertia", "rotor_inertia", False, "applies to the Alpes models; a URDF --model's rotor "
                   "inertia is its spec's motors' rotor_inertia (fit it with --parameters J_m)"),)


def _fit_robot(args: argparse.Namespace, freqs):
    """``identify --model PATH.urdf --spec FILE.toml``: :func:`_fit` on the spec's robot (the stick-slip law: the
    spec's smooth_velocity at :data:`~alpes_dyn.estimation.identification.effects.STICTION_VELOCITY`); ``--chain MOTOR``
    fits on the sub-model of that motor's branches (:meth:`~alpes_dyn.model.robot.Model.subtree`: on a fixed base the
    other branches do not change its joints' dynamics; the recording's columns of their motors and joints are
    ignored) and keeps the parameters of the joints that motor drives and its own (compliance, offset); with -o and
    masses in the selection, the URDF written beside -o is checked against the inputs before the fit. Returns the
    EffectsFit and the recording it read."""
    import dataclasses

    from ..estimation.identification.adequacy import AdequacyWarning
    from ..estimation.identification.effects import STICTION_VELOCITY, EffectsFit, fit_effects, parse_effects
    from ..estimation.identification.identification import check_selection, identify
    from ..estimation.identification.identified_spec import spec_misfits
    from ..model.robot import Model

    _refuse_for_urdf(args, _URDF_IDENTIFY)
    whole = _urdf_robot(args, "identification")
    _check_mjcf_option(args, whole)  # the MJCF written beside -o: the model's origin, checked before the fit
    model = _chain_model(whole, args.chain)
    effects = parse_effects(args.effects) if args.effects is not None else (
        () if args.parameters is not None else parse_effects(None))
    if args.law_spread and "auto" not in effects:
        raise InputError("--law-spread: the friction law's spread is made by the rounds of --effects auto")
    for law in ("lugre", "creep"):
        if law in effects:
            raise InputError(f"--effects: {law} applies to the Alpes models (their parameter file's friction.law); a "
                             "URDF --model has no parameter file to hold the law")
    if "rotor" in effects:
        raise InputError("--effects: rotor applies to the Alpes models (their file's J_m put on the tendons); a URDF "
                         "--model's rotors are always on, its spec's motors' rotor_inertia (fit them with "
                         "--parameters J_m)")
    if args.parameters is not None and set(effects) - {"stiction"}:
        raise InputError(f"--effects: {', '.join(e for e in effects if e != 'stiction')} with --parameters: name their "
                         "parameters there (tendon_compliance, tilt_y or tilt, encoder_offset, capstan)")
    sticky = Model(model.urdf, dataclasses.replace(model.spec, smooth_velocity=STICTION_VELOCITY), name=model.name)

    def model_of(effs: tuple[str, ...]) -> Model:  # "rotor", named by auto's verdict, is the spec's rotors: on
        return sticky if "stiction" in effs else model

    masses = spec_misfits(model, _chain_names(model, args.parameters, args.chain))  # the effects add none
    if masses and args.output is not None:  # written into a copy of the URDF beside -o (cmd_identify)
        _check_run_files(args, {"-o": ("toml",)}, [("-o's URDF", _mass_urdf_path(args.output))])
    data, validate = _robot_recordings(args, model, whole if args.chain is not None else None)
    kw = dict(excitation=freqs, torque_noise=args.torque_noise, validation=validate,
              encoder_noise=args.encoder_noise, drift=args.drift)
    if args.parameters is not None:
        fitted = model_of(effects)
        names = _chain_names(fitted, args.parameters, args.chain)
        check_selection(fitted, names)  # a bad selection named before the fit
        with warnings.catch_warnings():  # the command reports the verdict itself, in its one line
            warnings.simplefilter("ignore", AdequacyWarning)
            return EffectsFit.single(identify(fitted, data, names, **kw), effects), data
    has_gravity = data.gravity is not None  # tilt only where not given
    if args.chain is None:
        return fit_effects(model_of, data, effects, None, has_gravity, spread=args.law_spread, **kw), data
    own = tuple(e for e in effects if e in ("compliance", "offset"))  # the motor's own, named here
    base = ",".join(_chain_names(model, None, args.chain, own))
    fit = fit_effects(model_of, data, tuple(e for e in effects if e not in own), base, has_gravity,
                      spread=args.law_spread, **kw)
    fit.effects = own + fit.effects
    return fit, data


def _chain_model(model, motor: str | None):
    """``model`` (a URDF + spec robot), or with ``motor`` (``--chain``) its sub-model on that motor's branches
    (:meth:`~alpes_dyn.model.robot.Model.subtree`), with those of any tendon or mimic joint that couples them to
    another branch (:func:`~alpes_dyn.model.subtree.closed_motors`: never refused, the whole robot at worst); an
    unknown motor named as --chain's."""
    from ..model.subtree import closed_motors

    if motor is None:
        return model
    if motor not in model.motor_names:
        raise InputError(f"--chain: unknown motor {motor!r} of the URDF --model (motors: "
                         f"{', '.join(model.motor_names)})")
    motors = closed_motors(model, motor)
    return model if len(motors) == len(model.motor_names) else model.subtree(motors)


def _robot_recordings(args: argparse.Namespace, model, whole=None):
    """--data and --validate read for ``model`` (with --chain a sub-model of the robot ``whole``, whose other
    columns are then ignored), with --torque-constant where they hold currents."""
    from ..estimation.experiments.recording import read_recording

    data = read_data(args, model, ignore_others_of=whole)
    validate = None if args.validate is None else read_recording(args.validate, model, args.torque_constant,
                                                                 ignore_others_of=whole)
    return data, validate


def _chain_names(model, parameters: str | None, motor: str | None, own: tuple[str, ...] = ()) -> list[str]:
    """The names of the selection ``parameters`` (:func:`~alpes_dyn.symbolic.parametric.select_parameters`), with
    ``motor`` those of the joints it drives, its own and the robot's (tilt, input gain), and with ``own`` effects
    (compliance, offset) that motor's tendon compliance and encoder offset."""
    from ..symbolic.parametric import select_parameters

    chosen = select_parameters(model, parameters)
    if motor is None:
        return [p.name for p in chosen]
    names = [p.name for p in _motor_chain(model, chosen, motor)]
    extra = {"compliance": f"tendon_compliance_{motor}", "offset": f"encoder_offset_{motor}",
             "capstan": f"capstan_{motor}"}
    return names + [extra[e] for e in own if extra[e] not in names]


def _motor_chain(model, chosen, motor: str):
    """The parameters of ``chosen`` that belong to ``motor``'s chain: of the joints it drives, or its own (J_m,
    tendon compliance, encoder offset), and the robot's (tilt, input gain)."""
    if motor not in model.motor_names:
        raise InputError(f"--chain: unknown motor {motor!r} of the URDF --model (motors: "
                         f"{', '.join(model.motor_names)})")
    joints = {model.joint_names[i] for i in np.flatnonzero(model.transmission.S[model.motor_index(motor)])}
    out = tuple(p for p in chosen if p.joint in joints or p.motor == motor or (p.joint is None and p.motor is None))
    if not out:
        raise InputError(f"--chain: the selection has no parameter of motor {motor!r}'s joints "
                         f"({', '.join(sorted(joints))})")
    return out
