"""``alpes-dyn codegen``: the observer's step (the estimation scenario's filter on ``--params``, or on a URDF
``--model`` the observer of ``estimate --data``) written as standalone C into ``--out-dir DIR``, with
``--controller`` the force controller's too."""

from __future__ import annotations

import argparse
import time

from ..errors import InputError
from .common import (_emit, _is_urdf_path, _note_untrusted, _one_chain, _one_of, _refuse_for_urdf, _trust_notes,
                     _urdf_robot, friction_from_file)


def cmd_codegen(args: argparse.Namespace) -> int:
    """``codegen``: write the observer's step (the estimation scenario's filter) as C source, header and test
    program into a new directory (alpes_dyn.estimation.cexport.cexport), with --controller the force controller's too
    (alpes_dyn.control.cexport)."""
    from ..estimation.cexport.cexport import c_sources, check_output_directory, scenario_filter, write_sources
    from ..estimation.observers.observers import OBSERVERS
    from ..estimation.observers.scenario import ESTIMATION_MODELS

    if args.step:
        from .control_cmds import codegen_step

        return codegen_step(args)
    if _is_urdf_path(args.model):
        return _codegen_robot(args)
    for flag, dest in (("--spec", "spec"), ("--frame", "frame"), ("--motor", "motor")):
        if getattr(args, dest) is not None:
            raise InputError(f"{flag}: applies to a URDF --model; the Alpes model {args.model!r} takes its "
                             "transmission from --params and presses with its fingertip")
    _one_chain(args.model, ESTIMATION_MODELS, "the C export")
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    from_where = friction_from_file(args, args.params, "--params")
    if args.controller is not None:
        from ..control.controller import CONTROLLERS

        _one_of(args.controller, CONTROLLERS, "--controller", "controller")
        if args.model not in ("finger2", "finger3") or args.chain is not None or args.friction:
            said = f" (--params {args.params}'s fit had friction: --no-friction)" if from_where == "--params" else ""
            raise InputError("--controller: the force controller is exported for finger2 and finger3 on the block "
                             f"(alpes-dyn control's scene), without --chain and friction{said}")
    check_output_directory(args.out_dir, args.out_flag)  # before the build: a new or empty directory, never a file
    notes = _trust_notes(args, [("--params", args.params)])
    t0 = time.perf_counter()
    filt, z0, P0 = scenario_filter(args.observer, args.model, params=args.params, chain=args.chain,
                                   friction=args.friction, force=args.force)
    rig = _rig_words(args)
    about = (f"Model {args.model}{f' (chain {args.chain})' if args.chain else ''}, parameter file "
             f"{args.params or 'shipped with alpes_dyn'}{', with friction' if args.friction else ''}; observer "
             f"{args.observer} with the noise settings of 'alpes-dyn estimate'." + (f" {rig[0]}" if rig[0] else ""))
    files = c_sources(filt, about=about, z0=z0, P0=P0)
    if args.controller is not None:
        from ..control.cexport import block_controller, controller_c_sources

        files.update(controller_c_sources(block_controller(args.controller, args.model, args.params, args.force)))
    written = write_sources(files, args.out_dir, args.out_flag)
    prefix = f"alpes_{filt.kind}"
    obj = {"model": args.model, "chain": args.chain, "params": args.params, "observer": args.observer,
           "controller": args.controller, "friction": args.friction, "directory": args.out_dir,
           "files": sorted(written), "prefix": prefix,
           "nz": filt.nz, "nw": filt.nw, "ny": filt.ny, "dt": filt.dt, "states": list(filt.names),
           "seconds": time.perf_counter() - t0, **rig[1]}
    lines = [f"{args.model}: {args.observer} step{f' and {args.controller} controller' if args.controller else ''} "
             f"written to {args.out_dir}/ ({', '.join(sorted(written))})",
             f"  {prefix}_step(z[{filt.nz}], P[{filt.nz}*{filt.nz}], w[{filt.nw}], y[{filt.ny}], z_out, P_out, "
             f"work), dt = {filt.dt:g} s; the API in {prefix}.h",
             f"  build: cc -O2 -o {prefix}_main main.c {prefix}.c -lm"]
    if rig[0]:
        lines.append(f"  {rig[0]}")
    if args.controller is not None:
        lines.append("  alpes_force_update(&state, F_ref, F_fb, q_hat, &tau, work): the API in alpes_force.h; "
                     "build: cc -O2 -o alpes_force_main force_main.c alpes_force.c -lm")
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0


def _rig_words(args: argparse.Namespace) -> tuple[str, dict]:
    """What the exported step leaves to its caller of the rig's side identified in --params: (a sentence, empty
    without any; the JSON's ``encoder_offset_rad`` (per motor) and ``torque_delay_samples``). The tilt is in the
    file's gravity, which the step's model holds."""
    from ..estimation.observers.replay import file_encoder_offsets
    from ..model.params import load_params
    from ..model.robot import Model

    p = load_params(args.params)
    off = file_encoder_offsets(Model.alpes(args.model, params=p, chain=args.chain)).tolist()
    words = ([f"Subtract the identified encoder zero ({', '.join(f'{x:.6g}' for x in off)} rad of the motor) from the "
              "reading before y."] if any(off) else []) + (
        [f"The recorded torque lags the motor's by {p.torque_delay} samples (identified): give w the command held, "
         "not the late reading."] if p.torque_delay else [])
    return " ".join(words), {"encoder_offset_rad": off, "torque_delay_samples": int(p.torque_delay)}


_URDF_CODEGEN = (
    ("--chain", "chain", None, "names a finger of the Alpes hand; a URDF --model's observer estimates every joint of "
     "its spec's motors"),
    ("--params", "params", None, "applies to the Alpes models; a URDF --model's observer is its --spec"),
    ("--friction", "friction", False, "applies to the Alpes models; a URDF --model's observer has its --spec's "
     "friction"),
    ("--no-friction", "no_friction", False, "applies to the Alpes models; a URDF --model's observer has its --spec's "
     "friction"),
)


def _codegen_robot(args: argparse.Namespace) -> int:
    """``codegen --model PATH.urdf --spec FILE.toml``: the observer that ``estimate --data`` runs on a recording of
    the robot (:func:`~alpes_dyn.estimation.observers.replay.recording_filter`) at the estimation scenario's sampling
    and sensor noises, and with ``--controller`` the force controller of ``control`` on the robot
    (:func:`~alpes_dyn.control.cexport.robot_controller`: ``--frame``, ``--motor``), as standalone C."""
    from ..estimation.cexport.cexport import c_sources, check_output_directory, write_sources
    from ..estimation.observers.observers import OBSERVERS
    from ..estimation.observers.replay import recording_filter
    from ..estimation.observers.scenario import EstimationScenario

    _refuse_for_urdf(args, _URDF_CODEGEN)
    _one_of(args.observer, OBSERVERS, "--observer", "observer")
    if args.controller is not None:
        from ..control.controller import CONTROLLERS

        _one_of(args.controller, CONTROLLERS, "--controller", "controller")
    elif args.frame is not None or args.motor is not None:
        raise InputError(f"{'--frame' if args.frame is not None else '--motor'}: names the force controller's tip "
                         "frame or motor; give it with --controller")
    check_output_directory(args.out_dir, args.out_flag)  # before the build: a new or empty directory, never a file
    notes = _trust_notes(args, [("--spec", args.spec)])
    t0 = time.perf_counter()
    model = _urdf_robot(args, "the C export")
    ctl = None
    if args.controller is not None:  # the controller first: a frame or motor that cannot press is one line, no C
        from ..control.cexport import robot_controller

        try:
            ctl = robot_controller(args.controller, model, frame=args.frame, motor=args.motor)
        except InputError as exc:  # the scenario's field names as the command's options
            head, sep, tail = str(exc).partition(": ")
            raise InputError(f"--{head}: {tail}" if sep and head in ("frame", "motor", "spec") else str(exc)) from None
    sc = EstimationScenario()
    filt, z0, P0 = recording_filter(model, args.observer, sc.dt, torque_noise=sc.torque_noise,
                                    encoder_noise_counts=sc.encoder_noise_counts)
    about = (f"Model {model.name} ({args.model}, spec {args.spec}), with its spec's friction; observer "
             f"{args.observer} of 'alpes-dyn estimate --data' at dt = {sc.dt:g} s, torque noise "
             f"{sc.torque_noise:g} N m, encoder noise {sc.encoder_noise_counts:g} counts; prior: the rest, motors off.")
    files = c_sources(filt, about=about, z0=z0, P0=P0)
    if ctl is not None:
        from ..control.cexport import controller_c_sources

        files.update(controller_c_sources(ctl))
    written = write_sources(files, args.out_dir, args.out_flag)
    prefix = f"alpes_{filt.kind}"
    obj = {"model": args.model, "spec": args.spec, "observer": args.observer, "controller": args.controller,
           "frame": None if ctl is None else ctl.tip, "motor": None if ctl is None else model.motor_names[ctl.motor],
           "directory": args.out_dir, "files": sorted(written), "prefix": prefix, "nz": filt.nz, "nw": filt.nw,
           "ny": filt.ny, "dt": filt.dt, "states": list(filt.names), "seconds": time.perf_counter() - t0}
    lines = [f"{model.name}: {args.observer} step"
             + (f" and {args.controller} controller (motor {obj['motor']}, frame {obj['frame']})" if ctl else "")
             + f" written to {args.out_dir}/ ({', '.join(sorted(written))})",
             f"  {prefix}_step(z[{filt.nz}], P[{filt.nz}*{filt.nz}], w[{filt.nw}], y[{filt.ny}], z_out, P_out, "
             f"work), dt = {filt.dt:g} s; the API in {prefix}.h",
             f"  build: cc -O2 -o {prefix}_main main.c {prefix}.c -lm"]
    if ctl is not None:
        lines.append("  alpes_force_update(&state, F_ref, F_fb, q_hat, &tau, work): the API in alpes_force.h; "
                     "build: cc -O2 -o alpes_force_main force_main.c alpes_force.c -lm")
    _note_untrusted(obj, lines, notes)
    _emit(obj, "\n".join(lines), args.json)
    return 0
