"""The ``sweep`` command: a study over seeded draws of a finger within its tolerances, on Dask workers or
serially (:mod:`alpes_dyn.studies.sweep`)."""

from __future__ import annotations

import argparse

from ..errors import InputError
from .common import _check_run_files, _emit, _is_urdf_path, _one_of, _urdf_robot, check_fraction


def cmd_sweep(args: argparse.Namespace) -> int:
    """A study over seeded draws, on Dask workers or serially (studies.sweep)."""
    from ..estimation.experiments.experiment import EXPERIMENT_MODELS, ExperimentDesign
    from ..studies.sweep import ROBOT_DRAWN, ROBOT_HELD, STUDIES, robot_robustness_draw, sweep

    _one_of(args.study, tuple(STUDIES), "--study", "study")
    urdf = _is_urdf_path(args.model)
    if not urdf and args.spec is not None:
        raise InputError(f"--spec: applies to a URDF --model; the Alpes model {args.model!r} is drawn from its "
                         "shipped parameter file")
    if urdf:
        _urdf_robot(args, "the robustness study")  # the files read and checked before any worker starts
    elif args.model not in EXPERIMENT_MODELS or args.model == "thumb":
        raise InputError(f"--model: the robustness study is defined for one finger (finger2, finger3) or a URDF "
                         f"path with --spec, got {args.model!r}")
    check_fraction(args.spread, "--spread")  # (also right after parsing: before any file is read)
    if args.serial and (args.scheduler is not None or args.workers != 2):
        raise InputError("--serial: runs in this process; give no --workers or --scheduler with it")
    if args.scheduler is not None and args.workers != 2:
        raise InputError("--workers: sizes a local cluster; a --scheduler has its own workers")
    _check_run_files(args, {"-o": ("csv",)})  # the table: a CSV by its name
    opts = {"model": args.model, "spread": args.spread, "duration": args.duration, "fit": not args.no_fit}
    ExperimentDesign(duration=args.duration).check()  # before any worker starts
    study = STUDIES[args.study]
    if urdf:  # the files' paths travel to the workers (the same machine, or a shared file system)
        opts = {"urdf": args.model, "spec": args.spec, **{k: v for k, v in opts.items() if k != "model"}}
        study = robot_robustness_draw
    res = sweep(study, args.draws, seed=args.seed, options=opts,
                workers=None if args.serial or args.scheduler is not None else args.workers,
                scheduler=args.scheduler, serial=args.serial)
    res.meta.update({"study": args.study, "model": args.model, **opts})
    drawn = ""
    if urdf:  # what the draw perturbs is what the fit frees; the rest is held at the files' values in both
        res.meta.update({"drawn": list(ROBOT_DRAWN), "held": list(ROBOT_HELD)})
        drawn = (f"\n  drawn{'' if args.no_fit else ' and fitted'}: {', '.join(ROBOT_DRAWN)} of every joint the spec "
                 f"gives them (motorless joints too); held at the files' values: {', '.join(ROBOT_HELD)}")
    if args.output is not None:
        res.to_csv(args.output)
    obj = res.to_dict()
    if args.output is not None:
        obj["output"] = args.output
    head = (f"{args.study} study on {args.model}: {args.draws} draws (seeds {args.seed}..{args.seed + args.draws - 1}), "
            f"+-{100 * args.spread:g} % per {'value of the spec' if urdf else 'link'}, {args.duration:g} s experiments; "
            f"{res.backend} on {res.workers} worker{'s' if res.workers != 1 else ''}, {res.seconds:.1f} s{drawn}")
    lines = [head, res.table()] + ([f"  table: {args.output}"] if args.output else [])
    _emit(obj, "\n".join(lines), args.json)
    return 0
