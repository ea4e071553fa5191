"""The fit behind ``alpes-dyn identify`` on an Alpes model: the effects' rounds on a recording (the whole hand's
chains too, :mod:`alpes_dyn.cli.hand_cmds`), and the excitation's lines the fit takes; a URDF robot's fit written
(its spec, and the URDF with its masses)."""

from __future__ import annotations

import argparse
import warnings

from ..errors import InputError
from ..estimation.identification.identification import THUMB_PARAMETERS
from .common import parse_vector, read_data


def _identify_lines(args: argparse.Namespace):
    """--excitation's lines, Hz (``documented``: the multisine's and the dither's; ``none``: None)."""
    from ..estimation.experiments.experiment import ExperimentDesign

    if args.excitation == "documented":
        return ExperimentDesign().lines
    return None if args.excitation == "none" else tuple(parse_vector(args.excitation, "excitation"))



def _fit(args: argparse.Namespace, freqs, recordings=None):
    """The fit: --parameters as named (the stick-slip law where --effects asks for it), else the default selection
    with the effects' parameters added, --effects auto trying the stick-slip law where the first fit's adequacy
    check names it (:mod:`alpes_dyn.estimation.identification.effects`). ``recordings``: (data, validation or None)
    already read (a chain's of the whole hand's), else --data and --validate are read. Returns the EffectsFit and the
    recording it fitted."""
    from ..estimation.identification.adequacy import AdequacyWarning
    from ..estimation.identification.effects import EffectsFit, alpes_models, fit_effects, parse_effects
    from ..estimation.identification.identification import check_selection, identify
    from ..estimation.experiments.recording import read_recording
    from ..model.params import load_params

    effects = parse_effects(args.effects) if args.effects is not None else (
        () if args.parameters is not None else parse_effects(None))
    if args.parameters is not None and set(effects) - {"stiction", "rotor"}:
        raise InputError(f"--effects: {', '.join(e for e in effects if e not in ('stiction', 'rotor'))} with "
                         "--parameters: name their parameters there (tendon_compliance, tilt_y or tilt, encoder_offset, "
                         "capstan)")
    model_of = alpes_models(args.model, load_params(args.params), rotor_inertia=args.rotor_inertia, chain=args.chain)

    if args.parameters is not None:
        check_selection(model_of(effects), args.parameters)  # a bad selection named before the recording is read
    # the recordings read once (with --torque-constant their current_<motor> columns as torques), for every round
    if recordings is not None:
        data, validate = recordings
    else:
        data = read_data(args, model_of(()))
        validate = None if args.validate is None else read_recording(args.validate, model_of(()), args.torque_constant)
    kw = dict(excitation=freqs, torque_noise=args.torque_noise, validation=validate,
              encoder_noise=args.encoder_noise, drift=args.drift)
    if args.parameters is not None:
        model = model_of(effects)
        with warnings.catch_warnings():  # the command reports the verdict itself, in its one line
            warnings.simplefilter("ignore", AdequacyWarning)
            return EffectsFit.single(identify(model, data, args.parameters, **kw), effects), data
    base = THUMB_PARAMETERS if args.model == "thumb" else None
    return fit_effects(model_of, data, effects, base, data.gravity is not None, **kw), data  # tilt where not given


def _mass_urdf_path(output: str) -> str:
    """The URDF written beside ``identify -o FILE.toml`` when the fit has masses: ``FILE.urdf``."""
    from pathlib import Path

    return str(Path(output).with_suffix(".urdf"))


def _write_robot(res, args: argparse.Namespace) -> None:
    """A URDF robot's fit written: the identified spec at -o, and where it fitted masses the URDF ``--model`` with
    them beside it (:func:`_mass_urdf_path`;
    :func:`~alpes_dyn.estimation.identification.identified_spec.identified_urdf`): both built before either is
    written, the spec last (a failed URDF write leaves no spec naming it)."""
    from ..estimation.identification.identified_spec import (identified_spec, identified_urdf, spec_misfits,
                                                             write_identified_spec)
    from ..fileio import atomic_write, read_text
    from ..model.spec import load_spec

    base = load_spec(args.spec)
    if spec_misfits(res.model, res.names):
        text = identified_urdf(res, read_text(args.model, "--model"))
        identified_spec(res, base, masses="urdf")  # the spec's errors before the URDF is written
        atomic_write(_mass_urdf_path(args.output), text, "-o")
        write_identified_spec(res, base, args.output, masses="urdf")
    else:
        write_identified_spec(res, base, args.output)
