"""The ``sweep`` command: a study over seeded draws of a finger within its tolerances, on Dask workers or
serially (:mod:`alpes_dyn.studies.sweep`)."""

from __future__ import annotations

import argparse

import numpy as np

from ..errors import InputError
from .common import _check_run_files, _emit, _one_of


def cmd_sweep(args: argparse.Namespace) -> int:
    """A study over seeded draws, on Dask workers or serially (studies.sweep)."""
    from ..estimation.experiment import EXPERIMENT_MODELS, ExperimentDesign
    from ..studies.sweep import STUDIES, sweep

    _one_of(args.study, tuple(STUDIES), "--study", "study")
    if args.model not in EXPERIMENT_MODELS or args.model == "thumb":
        raise InputError(f"--model: the robustness study is defined for one finger (finger2, finger3), got "
                         f"{args.model!r}")
    if not (np.isfinite(args.spread) and 0 <= args.spread < 1):
        raise InputError(f"--spread: expected a fraction in [0, 1), got {args.spread!r}")
    if args.serial and (args.scheduler is not None or args.workers != 2):
        raise InputError("--serial: runs in this process; give no --workers or --scheduler with it")
    if args.scheduler is not None and args.workers != 2:
        raise InputError("--workers: sizes a local cluster; a --scheduler has its own workers")
    _check_run_files(args, {"-o": ("csv",)})  # the table: a CSV by its name
    opts = {"model": args.model, "spread": args.spread, "duration": args.duration, "fit": not args.no_fit}
    ExperimentDesign(duration=args.duration).check()  # before any worker starts
    res = sweep(STUDIES[args.study], args.draws, seed=args.seed, options=opts,
                workers=None if args.serial or args.scheduler is not None else args.workers,
                scheduler=args.scheduler, serial=args.serial)
    res.meta.update({"study": args.study, **opts})
    if args.output is not None:
        res.to_csv(args.output)
    obj = res.to_dict()
    if args.output is not None:
        obj["output"] = args.output
    head = (f"{args.study} study on {args.model}: {args.draws} draws (seeds {args.seed}..{args.seed + args.draws - 1}), "
            f"+-{100 * args.spread:g} % per link, {args.duration:g} s experiments; {res.backend} on {res.workers} "
            f"worker{'s' if res.workers != 1 else ''}, {res.seconds:.1f} s")
    lines = [head, res.table()] + ([f"  table: {args.output}"] if args.output else [])
    _emit(obj, "\n".join(lines), args.json)
    return 0
