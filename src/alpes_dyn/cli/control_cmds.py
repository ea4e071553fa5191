"""The ``control`` command: closed-loop fingertip force control on a MuJoCo plant, a finger pressing a block
(an Alpes finger, or a URDF + spec robot's tip frame on a block placed from its kinematics) or the hand grasping a
cylinder, with its ``--log`` CSV and ``--plot`` figure."""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import math
import time
from typing import Any

import numpy as np

from ..errors import InputError
from .common import (_check_run_files, _emit, _is_urdf_path, _note_untrusted, _one_of, _trust_notes, _urdf_robot,
                     parse_vector)


def _check_control_outputs(args: argparse.Namespace) -> None:
    """Before a closed-loop run: matplotlib for ``--plot`` and writable ``--log``/``--plot`` paths."""
    if args.plot:
        try:
            importlib.import_module("matplotlib")
        except ImportError:
            raise InputError("--plot: matplotlib is not installed (pip install 'alpes_dyn[plot]')") from None
    _check_run_files(args, {"--plot": ("png",)})


def _write_control_outputs(res: Any, args: argparse.Namespace, plot: Any) -> dict[str, Any]:
    """The run's ``--log`` CSV and ``--plot`` figure; its JSON object with their paths."""
    if args.log:
        res.to_csv(args.log)
    if args.plot:
        plot(res, args.plot)
    obj = res.to_dict()
    for k, v in (("log", args.log), ("plot", args.plot)):
        if v:
            obj[k] = v
    sc = res.scenario
    if getattr(sc, "effects", None) is not None:
        from ..control.realism_loop import Compensation

        obj["plant_effects"] = dataclasses.asdict(sc.effects)
        obj["compensation"] = dataclasses.asdict(Compensation() if sc.compensation is None else sc.compensation)
    return obj


def _output_lines(args: argparse.Namespace) -> list[str]:
    return ([f"  log: {args.log}"] if args.log else []) + ([f"  figure: {args.plot}"] if args.plot else [])


_EFFECT_FLAGS = (("--stiction", "stiction"), ("--tendon-stiffness", "tendon_stiffness"),
                 ("--tendon-damping", "tendon_damping"), ("--tendon-dead-band", "tendon_dead_band"),
                 ("--tilt", "tilt"), ("--torque-constant-error", "torque_constant_error"),
                 ("--encoder-offset", "encoder_offset"), ("--torque-delay", "torque_delay"))


def realism_effects() -> Any:
    """The ``--plant-effects all`` plant (``benchmarks/force_realism.py``'s): a real hand's effects,
    :func:`~alpes_dyn.bench.effects.real_hand_effects` (the realism study's ``all`` case,
    :func:`~alpes_dyn.studies.realism.cases`, on the cable :func:`~alpes_dyn.studies.realism.tendon_stiffness` sizes
    on the documented experiment: 0.5 degree of its slack at the motor shaft, the torque read 1 sample late)."""
    from ..bench.effects import real_hand_effects

    return real_hand_effects()


def _plant_effects(args: argparse.Namespace) -> Any:
    """The plant's effects of the command line (``--plant-effects`` then each effect's flag), or None; checked."""
    import math

    from ..control.plants import PlantEffects
    from ..control.realism_loop import effects_mjcf_kwargs
    from ..model.mjcf import mjcf_string

    given = {dest: getattr(args, dest) for _, dest in _EFFECT_FLAGS if getattr(args, dest) is not None}
    if args.tendon_rotor:
        given["tendon_rotor"] = True
    if args.plant_effects in (None, "none") and not given:
        if args.no_compensation:
            raise InputError("--no-compensation: applies to a plant with effects (--plant-effects or an effect's flag)")
        return None
    if args.plant_effects == "none":
        raise InputError("--plant-effects: 'none' with an effect's flag (" + ", ".join(
            f for f, d in _EFFECT_FLAGS if d in given) + "): give one or the other")
    if "tilt" in given:
        given["tilt"] = math.radians(given["tilt"])
    base = realism_effects() if args.plant_effects == "all" else PlantEffects()
    try:
        e = dataclasses.replace(base, **given).check()
        mjcf_string("finger3", **effects_mjcf_kwargs(e))  # the MJCF side's own checks, one line each
    except InputError as exc:
        head, sep, tail = str(exc).partition(": ")
        flag = dict((d, f) for f, d in _EFFECT_FLAGS).get(head, "--tendon-rotor" if head == "tendon_rotor" else None)
        raise InputError(f"{flag}: {tail}" if sep and flag else str(exc)) from None
    return e


def _na(x: Any, fmt: str) -> str:
    return "n/a" if x is None else format(x, fmt)


def cmd_control(args: argparse.Namespace) -> int:
    """Closed loop on MuJoCo: a finger presses a block with the force asked for, or the hand grasps a cylinder."""
    from ..control.force import CONTROL_MODELS, CONTROLLERS, REFERENCES, plot_control, run_control

    urdf = _is_urdf_path(args.model)
    if args.model != "hand" and args.model not in CONTROL_MODELS and not urdf:
        raise InputError(f"--model: the control scenario is defined for one finger ({', '.join(CONTROL_MODELS)}), "
                         f"the hand on the cylinder (hand) or a URDF path with --spec, got {args.model!r}")
    _one_of(args.controller, CONTROLLERS, "--controller", "controller")
    _one_of(args.reference, REFERENCES, "--reference", "reference")
    if not urdf:
        for flag, dest in _URDF_ONLY:
            if getattr(args, dest) is not None:
                raise InputError(f"{flag}: applies to a URDF --model; the Alpes {args.model!r} presses with its "
                                 "fingertip, its transmission and motor limit from its parameter file (--params)")
    if urdf:
        given = [f for f, d in (("--plant-effects", "plant_effects"), *_EFFECT_FLAGS) if getattr(args, d) is not None]
        given += [f for f, d in (("--tendon-rotor", "tendon_rotor"), ("--no-compensation", "no_compensation"))
                  if getattr(args, d)]
        if given:
            raise InputError(f"{given[0]}: a real hand's effects apply to the Alpes models (finger2, finger3, hand); "
                             "a URDF --model's plant is its spec's MJCF")
    effects = _plant_effects(args)
    fx = {} if effects is None else {"effects": effects, **({"compensation": _rigid()} if args.no_compensation else {})}
    _check_calibration(args, fx, urdf)
    notes = _trust_notes(args, [("--spec", args.spec) if urdf else ("--params", args.params)])
    if args.model == "hand":
        return _control_hand(args, fx, notes)
    if args.duration is None:
        args.duration = 3.0
    kw: dict[str, Any] = {}
    if urdf:
        for flag, dest in (("--params", "params"), ("--plant-params", "plant_params")):
            if getattr(args, dest) is not None:
                raise InputError(f"{flag}: applies to the Alpes models (finger2, finger3, hand); a URDF --model's "
                                 "controller and plant are its --spec")
        robot = _urdf_robot(args, "control")
        kw = {"frame": args.frame, "motor": args.motor, "tau_max": args.tau_max,
              "contact_q": None if args.contact_q is None else tuple(parse_vector(args.contact_q, "contact-q"))}
        _check_control_outputs(args)
        try:
            res = run_control(args.controller, model=robot, reference=args.reference, duration=args.duration,
                              seed=args.seed, **kw)
        except InputError as exc:  # the scenario's field names as the command's options
            raise InputError(_as_option(str(exc))) from None
        where = (f"{robot.name}: {res.block.frame} pressing a block (motor {res.block.motor}, normal "
                 f"{', '.join(f'{x:.3f}' for x in res.block.normal)})")
    else:
        _check_control_outputs(args)
        scale = _force_scale(args, fx, run_control)
        res = run_control(args.controller, model=args.model, reference=args.reference, duration=args.duration,
                          seed=args.seed, params=args.params, plant_params=args.plant_params, force=args.force, **fx)
        where = f"{args.model} pressing a block" + _effects_words(fx)
    obj = _write_control_outputs(res, args, plot_control)
    if not urdf:
        obj["force_scale"] = scale
    f = _na

    lines = [
        f"{where}, {args.controller} controller, {args.reference} reference, MuJoCo plant "
        f"({args.duration:g} s, seed {args.seed})",
        f"  force RMSE {res.force_rmse:.4f} N; steady-state error {f(res.steady_state_error, '.2%')}; "
        f"overshoot {f(res.overshoot, '.1%')}; 10-90 % rise "
        f"{'n/a' if res.rise_time_s is None else f'{res.rise_time_s:.3f} s'}",
        "  joints observed during contact, RMSE [deg]: "
        + ("n/a (no observer)" if res.q_rmse_deg is None else
           "  ".join(f"{j} {e:.2f}" for j, e in zip(res.joint_names, res.q_rmse_deg))),
        f"  motor torque limit {res.tau_max:g} N m, saturated {res.saturated:.1%} of the time; "
        f"loop {res.realtime_ratio:.1f}x faster than real time",
    ]
    if not urdf and scale is not None:
        lines.append(f"  sensorless force estimate divided by {scale:.4f} ("
                     f"{'read by a calibration run, seed ' + str(args.seed + CALIBRATION_SEED) if args.calibrate else '--force-scale'})")
    _untrusted_lines(obj, lines, notes)
    _emit(obj, "\n".join(lines + _output_lines(args)), args.json)
    return 0


CALIBRATION_SEED = 1000
"""--calibrate's run: the loop's seed plus this (another draw of the sensors' noise than the run's)."""


def _check_calibration(args: argparse.Namespace, fx: dict, urdf: bool) -> None:
    """--force-scale and --calibrate: the sensorless controller of a finger on a plant with effects, one of them."""
    flag = "--force-scale" if args.force_scale is not None else "--calibrate" if args.calibrate else None
    if flag is None:
        return
    if args.force_scale is not None and args.calibrate:
        raise InputError("--force-scale: give it or --calibrate (which reads it from a calibration run), not both")
    if urdf or args.model == "hand":
        raise InputError(f"{flag}: applies to a finger model (finger2, finger3); the hand's chains are calibrated "
                         "from Python (control.force_scale_of on a sensorless run_hand_control)")
    if args.controller != "sensorless":
        raise InputError(f"{flag}: applies to the sensorless controller (--controller sensorless), got "
                         f"{args.controller!r}: the sensor and pi loops read the fingertip sensor itself")
    if not fx:
        raise InputError(f"{flag}: applies to a plant with a real hand's effects (--plant-effects all, or an effect's "
                         "flag): the torque constant's error it undoes is one of them")
    if args.force_scale is not None and not (math.isfinite(args.force_scale) and 0.5 <= args.force_scale <= 2.0):
        raise InputError(f"--force-scale: expected a scale from 0.5 to 2 (the estimate over the fingertip sensor), "
                         f"got {args.force_scale!r}")


def _force_scale(args: argparse.Namespace, fx: dict, run_control: Any) -> float | None:
    """The scale the loop's sensorless estimate is divided by (--force-scale, or read by --calibrate's run), put
    into ``fx``'s compensation; None without either."""
    from ..control.grasp_calibration import force_scale_of
    from ..control.realism_loop import Compensation

    if args.force_scale is None and not args.calibrate:
        return None
    comp = fx.get("compensation") or Compensation()
    if args.calibrate:
        first = run_control("sensorless", model=args.model, reference="step", duration=args.duration,
                            seed=args.seed + CALIBRATION_SEED, params=args.params, plant_params=args.plant_params,
                            force=args.force, **{**fx, "compensation": comp})
        try:
            scale = float(force_scale_of(first, comp.force_scale))
        except InputError as exc:
            raise InputError(f"--calibrate: {str(exc).partition(': ')[2]}") from None
    else:
        scale = float(args.force_scale)
    fx["compensation"] = dataclasses.replace(comp, force_scale=scale)
    return scale


_URDF_ONLY = (("--spec", "spec"), ("--frame", "frame"), ("--motor", "motor"), ("--contact-q", "contact_q"),
              ("--tau-max", "tau_max"))
_FIELD_OPTIONS = {"frame": "--frame", "motor": "--motor", "contact_q": "--contact-q", "tau_max": "--tau-max",
                  "spec": "--spec"}


def _as_option(message: str) -> str:
    """A scenario's error ``field: ...`` as ``--option: ...`` (the same words, the option the user typed)."""
    head, sep, tail = message.partition(": ")
    return f"{_FIELD_OPTIONS[head]}: {tail}" if sep and head in _FIELD_OPTIONS else message


def _rigid() -> Any:
    from ..control.realism_loop import NO_COMPENSATION

    return NO_COMPENSATION


def _effects_words(fx: dict) -> str:
    """`` (plant effects: ...; compensated|rigid design)`` for the report line, or nothing."""
    if not fx:
        return ""
    e = fx["effects"]
    on = [f.name for f in dataclasses.fields(e) if getattr(e, f.name) not in (None, 0, 0.0, False)]
    return f" (plant effects: {', '.join(on) or 'none'}; {'rigid' if 'compensation' in fx else 'compensated'} design)"


def _untrusted_lines(obj: dict, lines: list[str], notes: list[str]) -> None:
    """The files used with --force though marked not trustworthy: ``obj``'s ``not_trustworthy`` and a line each."""
    obj["not_trustworthy"] = list(notes)
    lines += [f"  WARNING: {n}" for n in notes]


def _control_hand(args: argparse.Namespace, fx: dict | None = None, notes: list[str] = ()) -> int:
    """``alpes-dyn control --model hand``: run_hand_control, one loop per motor, per-chain metrics."""
    from ..control.force import HandControlScenario, plot_hand_control, run_hand_control

    if args.reference != "step":
        raise InputError(f"--reference: the hand's loops follow step references (control.HAND_LEVELS), "
                         f"got {args.reference!r}")
    sc = HandControlScenario()
    duration = sc.duration if args.duration is None else args.duration
    if duration < sc.step_time + 0.25:
        raise InputError(f"--duration: the hand's run needs at least {sc.step_time + 0.25:g} s (its references "
                         f"step up at {sc.step_time:g} s), got {duration:g}")
    _check_control_outputs(args)
    res = run_hand_control(args.controller, duration=duration, seed=args.seed, params=args.params,
                           plant_params=args.plant_params, force=args.force, **(fx or {}))
    obj = _write_control_outputs(res, args, plot_hand_control)
    f = _na

    lines = [f"the hand grasping the cylinder{_effects_words(fx or {})}, {args.controller} loops, MuJoCo plant ({duration:g} s, seed {args.seed}, "
             f"references step up at {sc.step_time:g} s)",
             f"  {'chain':7s} {'asked':>6s} {'held':>7s} {'SSE':>7s} {'overshoot':>9s} {'rise':>7s} {'RMSE':>8s} "
             f"{'q RMSE':>7s}"]
    for row in res.table():
        rise = "n/a" if row["rise_time_s"] is None else f"{1e3 * row['rise_time_s']:.0f} ms"
        lines.append(f"  {row['chain']:7s} {row['F_ref']:4.2f} N {row['F_held']:5.3f} N "
                     f"{f(row['steady_state_error'], '7.2%')} {f(row['overshoot'], '9.1%')} {rise:>7s} "
                     f"{row['force_rmse']:6.4f} N {f(row['q_rmse_deg'], '5.2f')}{'' if row['q_rmse_deg'] is None else ' deg'}")
    lines.append(f"  thumb ab/adduction held at {np.degrees(res.q_abduction[-1]):.1f} deg; "
                 f"loop {res.realtime_ratio:.1f}x faster than real time")
    _untrusted_lines(obj, lines, list(notes))
    _emit(obj, "\n".join(lines + _output_lines(args)), args.json)
    return 0


def codegen_step(args: argparse.Namespace) -> int:
    """``codegen --step``: the whole force step, :class:`~alpes_dyn.control.step.ForceStep` of --model, --params and
    --controller, as C (:func:`alpes_dyn.control.cstep.write_c_step`)."""
    from ..control.controller import CONTROLLERS
    from ..control.cstep import write_c_step
    from ..control.step import ForceStep
    from ..estimation.cexport.cexport import check_output_directory

    urdf = _is_urdf_path(args.model)
    if args.model not in ("finger2", "finger3", "hand") and not urdf:
        raise InputError(f"--step: the force step is exported for finger2, finger3, hand and a URDF --model with its "
                         f"--spec, got --model {args.model!r}")
    if args.controller is None:
        raise InputError("--step: needs --controller (sensor, sensorless or pi)")
    _one_of(args.controller, CONTROLLERS, "--controller", "controller")
    if urdf:
        return _codegen_robot_step(args)
    for flag, bad, why in (("--friction", args.friction, "the step's EKF has the --params file's friction"),
                           ("--chain", args.chain is not None, "the step is one finger's"),
                           ("--observer", args.observer != "ekf", "the step's observer is the EKF"),
                           ("--spec", args.spec is not None, "applies to a URDF --model"),
                           ("--frame", args.frame is not None, "applies to a URDF --model"),
                           ("--motor", args.motor is not None, "applies to a URDF --model")):
        if bad:
            raise InputError(f"{flag}: not with --step ({why})")
    check_output_directory(args.out_dir, args.out_flag)  # before the build: a new or empty directory, never a file
    notes = _trust_notes(args, [("--params", args.params)])
    if args.model == "hand":
        return _codegen_hand_step(args, notes)
    t0 = time.perf_counter()
    step = ForceStep(args.model, args.params, args.controller, compiled=False, force=args.force)
    about = (f"Model {args.model}, parameter file {args.params or 'shipped with alpes_dyn'}, palm down; controller "
             f"{args.controller} with the tuned gains and every compensation of its effects.")
    written = write_c_step(step, args.out_dir, about=about)
    return _emit_step(args, step, args.model, written, {"model": args.model, "params": args.params}, t0, notes)


def _emit_step(args: argparse.Namespace, step: Any, name: str, written: Any, head: dict, t0: float,
               notes: Any) -> int:
    """The summary of a force step written as C (``written``: its files) for ``name``: the JSON object (``head``
    first) and the lines saying its API and its build, with the trust notes; exit 0."""
    from ..control.cstep import C_STEP_BUILD

    obj = {**head, "controller": args.controller, "directory": args.out_dir, "files": sorted(written),
           "nm": step.m, "nz": step.nz, "dt": step.dt, "tau_max": step.tau_max,
           "normal": [float(x) for x in step.design.normal], "seconds": time.perf_counter() - t0}
    build = C_STEP_BUILD if step.filter_step is not None else C_STEP_BUILD.replace(" alpes_step_ekf.c", "")
    lines = [f"{name}: the {args.controller} force step written to {args.out_dir}/ ({', '.join(sorted(written))})",
             f"  alpes_step(&state, counts[{step.m}], torque[{step.m}], force, F_ref, normal[3], command[{step.m}], "
             "work) once per tick: the API in alpes_step.h",
             f"  build: cd {args.out_dir} && {build}"]
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0


def _codegen_hand_step(args: argparse.Namespace, notes: Any) -> int:
    """``codegen --step --model hand``: :class:`~alpes_dyn.control.hand_step.HandForceStep` of --params and
    --controller as C (:func:`alpes_dyn.control.chand.write_c_hand`)."""
    from ..control.chand import C_HAND_BUILD, write_c_hand
    from ..control.hand_step import HandForceStep

    t0 = time.perf_counter()
    step = HandForceStep(args.params, args.controller, compiled=False, force=args.force)
    about = (f"The hand, parameter file {args.params or 'shipped with alpes_dyn'}, palm down; controller "
             f"{args.controller} with the hand's gains on every flexion chain, every compensation of its effects.")
    written = write_c_hand(step, args.out_dir, about=about)
    obj = {"model": "hand", "params": args.params, "controller": args.controller, "directory": args.out_dir,
           "files": sorted(written), "motors": list(step.motor_names), "chains": list(step.chains), "dt": step.dt,
           "tau_max": step.tau_max, "seconds": time.perf_counter() - t0}
    lines = [f"hand: the {args.controller} force step written to {args.out_dir}/ ({len(written)} files)",
             "  alpes_hand_step(&state, counts[6], torque[6], force[5], reference[5], normals[15], command[6], work) "
             "once per tick: the API in alpes_hand.h",
             f"  build: cd {args.out_dir} && {C_HAND_BUILD}"]
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0


def _codegen_robot_step(args: argparse.Namespace) -> int:
    """``codegen --step --model PATH.urdf --spec FILE.toml``: the force step of ``control`` on the robot
    (:class:`~alpes_dyn.control.step.ForceStep` of the Model: its tip ``--frame`` pulled by ``--motor`` onto the
    block placed from its kinematics, the EKF on the spec's model without its friction) as C."""
    from ..control.cstep import write_c_step
    from ..control.step import ForceStep
    from ..estimation.cexport.cexport import check_output_directory

    for flag, bad, why in (("--params", args.params is not None, "applies to the Alpes models; a URDF --model's "
                            "parameters are its --spec"),
                           ("--friction", args.friction, "a URDF --model's step has its --spec"),
                           ("--chain", args.chain is not None, "names a finger of the Alpes hand"),
                           ("--observer", args.observer != "ekf", "the step's observer is the EKF")):
        if bad:
            raise InputError(f"{flag}: not with --step on a URDF --model ({why})")
    check_output_directory(args.out_dir, args.out_flag)  # before the build: a new or empty directory, never a file
    notes = _trust_notes(args, [("--spec", args.spec)])
    t0 = time.perf_counter()
    model = _urdf_robot(args, "the force step")
    try:
        step = ForceStep(model, controller=args.controller, compiled=False, frame=args.frame, motor=args.motor)
    except InputError as exc:  # the step's argument names as the command's options
        head, sep, tail = str(exc).partition(": ")
        raise InputError(f"--{head}: {tail}" if sep and head in ("frame", "motor") else str(exc)) from None
    about = (f"Model {model.name} ({args.model}, spec {args.spec}): tip {step.design.frame} pulled by motor "
             f"{model.motor_names[step.motor]} onto its block; controller {args.controller} with the gains scaled to "
             "the robot.")
    written = write_c_step(step, args.out_dir, about=about)
    return _emit_step(args, step, model.name, written, {"model": args.model, "spec": args.spec, "frame":
                      step.design.frame, "motor": model.motor_names[step.motor]}, t0, notes)
