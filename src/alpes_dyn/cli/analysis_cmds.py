"""The commands that test a model before any data: ``observability`` (of the joints from the outputs) and
``identifiability`` (of the physical parameters from the encoder, structurally and by Cramér-Rao bounds);
the observability summary of the ``report`` command."""

from __future__ import annotations

import argparse
import warnings
from typing import Any

import numpy as np

from ..errors import InputError
from ..limits import MAX_ORDER
from .common import (_emit, _is_urdf_path, _model_from_args, _one_finger, _one_of, _one_or_list, _strict_int, _urdf_robot,
                     parse_vector)


# ---- owned by the observability work (issue 3): replace the body, keep the signature
def _observability_summary(args: argparse.Namespace) -> dict[str, Any]:
    """Observability of finger2, finger3 and the hand in the report's setting (u = joint torques,
    y = sum of joint angles), with the report's spring law (eq. 2.14) and the torsional one."""
    from ..analysis.observability import observability

    lines = ["  model    spring     states outputs  rank  observable  index  min sv    condition  at rest  parts"]
    results: dict[str, Any] = {}
    for spring in ("report", "torsional"):
        for name in ("finger2", "finger3", "hand"):
            r = observability(name, input="joint", output="sum", spring=spring, points=args.points, seed=args.seed)
            d = r.to_dict()
            d.pop("rank_drops", None)
            results[f"{name}/{spring}"] = d
            cond = f"{r.condition:9.2e}" if np.isfinite(r.condition) else "      inf"
            parts = ", ".join(f"{p.model} {p.rank}/{p.n_states}" for p in r.parts)
            lines.append(f"  {name:8s} {spring:10s} {r.n_states:6d} {r.n_outputs:7d} {f'{r.rank}/{r.n_states}':>5s}  "
                         f"{'yes' if r.observable else 'NO':10s} {r.index:6d}  {r.min_singular_value:9.2e} {cond} "
                         f"{f'{r.rank_at_rest}/{r.n_states}':>7s}  {parts}")
    lines.append("  (report: finger2 rank 4 of 4, finger3 rank 6 of 6, both observable. Fingers: O up to y^(n-1) as in "
                 "the report; hand: up to y^(5), where its rank is already full. min sv = median over "
                 f"{args.points} random points of s_n/s_1 of the row-normalised O)")
    return {"lines": lines, "input": "joint", "output": "sum", "points": args.points, "seed": args.seed,
            "results": results}


# ---- owned by the observability work (issue 3)
def cmd_observability(args: argparse.Namespace) -> int:
    from ..analysis.observability import observability

    order: str | int = getattr(args, "order", "auto")
    if order not in ("auto", "report"):
        try:
            order = _strict_int(order)
        except ValueError:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order!r}") from None
        if order < 0:
            raise InputError(f"--order: expected auto, report or a non-negative integer, got {order}")
        if order > MAX_ORDER:
            raise InputError(f"--order: {order if order < 10**30 else 'an integer of %d digits' % len(str(order))} "
                             f"is over the limit of {MAX_ORDER}")
    model = _model_from_args(args)
    rep = observability(model, input=args.input, output=_one_or_list(args.output), points=args.points, seed=args.seed,
                        constant_input=getattr(args, "constant_input", False), order=order,
                        max_operations=args.max_operations)
    _emit(rep.to_dict(), rep.to_text(), args.json)
    return 0


DESIGNS = ("documented", "scenario", "none")


def _identifiability_report(args: argparse.Namespace, model, spec: str, torque) -> int:
    """The structural test of ``spec`` on ``model`` and, unless ``--design none``, the Cramér-Rao bounds of the
    experiment whose motor torque ``torque(design, t)`` gives (N, m) on the design's grid; one JSON object or
    the text."""
    from ..analysis.identifiability import fisher_information, identifiability
    from ..estimation.experiments.experiment import ExperimentDesign, _schedule

    cams = tuple(float(c) for c in parse_vector(args.camera_times, "camera-times")) if args.camera_times else ()
    design = ExperimentDesign(duration=args.duration, camera_times=cams).check() if args.design != "none" else None
    rep = identifiability(model, spec, output=args.output, points=args.points, seed=args.seed,
                          max_operations=args.max_operations)
    obj: dict[str, Any] = {"structural": rep.to_dict(), "design": args.design, "practical": None}
    lines = [rep.to_text()]
    if design is not None:
        t, _, G = _schedule(design)
        fim = fisher_information(model, spec, U=torque(design, t), G=G[:-1], design=design)
        obj["practical"] = fim.to_dict()
        lines += [f"Practical identifiability, design {args.design!r} ({args.duration:g} s)"
                  + (" with the camera" if cams else "") + ":", fim.to_text()]
    _emit(obj, "\n".join(lines), args.json)
    return 0


def cmd_identifiability(args: argparse.Namespace) -> int:
    """Structural identifiability of physical parameters, and the Cramér-Rao bounds of an experiment."""
    from ..estimation.experiments.experiment import _profile, dither_amplitude, excitation
    from ..model.robot import Model
    from ..estimation.observers.scenario import SCENARIO_MODELS, EstimationScenario, _torque
    from ..model.stops import JointRangeWarning

    if _is_urdf_path(args.model):
        return _identifiability_robot(args)
    if args.spec is not None:
        raise InputError(f"--spec: applies to a URDF --model; the Alpes model {args.model!r} takes its transmission "
                         "from --params")
    _one_finger(args.model, SCENARIO_MODELS, "identifiability")
    _one_of(args.design, DESIGNS, "--design", "design")
    spec = args.parameters if args.parameters is not None else "K,m,friction"
    friction = any(k in spec for k in ("F_s", "F_v", "friction"))
    model = Model.alpes(args.model, friction=friction, params=args.params)

    def torque(design, t):
        if args.design != "documented":
            return _torque(EstimationScenario(model=args.model), t[:-1], model.transmission.n_motors)
        nominal = model if friction else Model.alpes(args.model, friction=True, params=args.params)
        with warnings.catch_warnings():  # the amplitude search tries runs that leave the joint range
            warnings.simplefilter("ignore", JointRangeWarning)
            bias, amp = excitation(nominal, design)
        return _profile(design, t, bias, amp, dither=float(dither_amplitude(nominal, design)[0]))[:-1, None]

    return _identifiability_report(args, model, spec, torque)


def _identifiability_robot(args: argparse.Namespace) -> int:
    """``identifiability --model PATH.urdf --spec FILE.toml``: the structural test on the spec's robot and the
    Cramér-Rao bounds of its documented experiment (the multisine designed for its own joint ranges and masses,
    :func:`~alpes_dyn.estimation.experiments.experiment.model_experiment`'s), or structural only (``--design none``)."""
    from ..estimation.experiments.experiment import _excitation, _profiles, dither_amplitude
    from ..model.stops import JointRangeWarning

    _one_of(args.design, DESIGNS, "--design", "design")
    if args.design == "scenario":
        raise InputError("--design: scenario is the Alpes fingers' estimation scenario; a URDF --model takes "
                         "documented (its identification multisine) or none (structural only)")
    spec = args.parameters if args.parameters is not None else "K,m,friction"
    model = _urdf_robot(args, "identifiability")

    def torque(design, t):
        with warnings.catch_warnings():  # the amplitude search tries runs that leave the joint range
            warnings.simplefilter("ignore", JointRangeWarning)
            bias, amp = _excitation(model, design)
        return _profiles(design, t, bias, amp, dither_amplitude(model, design))[:-1]

    return _identifiability_report(args, model, spec, torque)
