"""The fit behind ``alpes-dyn identify`` on an Alpes model: the effects' rounds on a recording (the whole hand's
chains too, :mod:`alpes_dyn.cli.hand_cmds`), and the excitation's lines the fit takes; a URDF robot's fit written
(its spec, the URDF with its masses, and with ``--mjcf`` the MJCF it was imported from with the fit's values)."""

from __future__ import annotations

import argparse
import os
import warnings

from ..errors import AlpesDynWarning, InputError
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
    if args.law_spread and "auto" not in effects:
        raise InputError("--law-spread: the friction law's spread is made by the rounds of --effects auto")
    if args.parameters is not None and set(effects) - {"stiction", "rotor", "lugre", "creep"}:
        bad = ", ".join(e for e in effects if e not in ("stiction", "rotor", "lugre", "creep"))
        raise InputError(f"--effects: {bad} with "
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
    # gravity columns are the rig's orientation as it was set up (palm up, hung: what alpes-dyn experiment and the
    # experiment on the hand write), not a measurement: the mount's tilt on top of them is fitted where "tilt" is
    # among the effects, as without columns (fit_effects' has_gravity False)
    return fit_effects(model_of, data, effects, base, spread=args.law_spread, **kw), data


def _mass_urdf_path(output: str) -> str:
    """The URDF written beside ``identify -o FILE.toml`` when the fit has masses: ``FILE.urdf``."""
    from pathlib import Path

    return str(Path(output).with_suffix(".urdf"))


def _mjcf_out_path(output: str) -> str:
    """The MJCF written beside ``identify -o FILE.toml --mjcf ROBOT.xml``: ``FILE.xml``."""
    from pathlib import Path

    return str(Path(output).with_suffix(".xml"))


def _mjcf_applies(args: argparse.Namespace, urdf: bool) -> None:
    """``identify --mjcf`` refused on an Alpes model (its MJCF is ``alpes-dyn mjcf``'s, nothing to write back)."""
    if args.mjcf is not None and not urdf:
        raise InputError(f"--mjcf: applies to a URDF --model imported from that MJCF (alpes-dyn import); the Alpes "
                         f"model {args.model!r}'s MJCF: alpes-dyn mjcf --model {args.model}")


def _written_lines(obj: dict, args: argparse.Namespace, res, robot: bool, written: bool,
                   omitted: list[str]) -> list[str]:
    """identify's files in its JSON (``urdf_output``, ``mjcf_output``, ``mjcf_omitted``: None or empty where not
    written) and its text's lines saying them; ``robot``: a URDF robot's fit written (:func:`_write_robot`)."""
    from ..estimation.identification.identified_spec import spec_misfits

    obj["urdf_output"] = _mass_urdf_path(args.output) if robot and spec_misfits(res.model, res.names) else None
    obj["mjcf_output"] = _mjcf_out_path(args.output) if robot and args.mjcf is not None else None
    obj["mjcf_omitted"] = list(omitted) if obj["mjcf_output"] else []
    if not written:
        return []
    u = obj["urdf_output"]
    lines = [f"  written to {args.output}"
             + (f" and {u} (the masses; use --model {u} --spec {args.output})" if u else "")
             + ("" if res.trustworthy else " (marked NOT trustworthy)")]
    if obj["mjcf_output"]:
        lines.append(f"  the MJCF {args.mjcf} with the identified values: {obj['mjcf_output']}"
                     + (f" (not in it: {', '.join(obj['mjcf_omitted'])}, a sensor law MuJoCo's rigid tendon cannot "
                        "hold; in the spec)" if obj["mjcf_omitted"] else ""))
    return lines


def _check_mjcf_option(args: argparse.Namespace, model) -> None:
    """``identify --mjcf ROBOT.xml``, before the fit: with -o, on a URDF --model imported from that MJCF
    (:func:`~alpes_dyn.model.mjcf_update.check_origin`); its file beside -o none of the inputs."""
    from ..errors import ModelError
    from ..model.mjcf_update import check_origin
    from .common import _check_run_files, _is_mjcf_path

    if args.mjcf is None:
        return
    if args.output is None:
        raise InputError("--mjcf: the identified MJCF is written beside -o FILE.toml (as FILE.xml); give -o")
    if not _is_mjcf_path(args.mjcf):
        raise InputError(f"--mjcf: expected the MJCF file the --model was imported from (FILE.xml), got {args.mjcf!r}")
    _check_run_files(args, {"-o": ("toml",)}, [("-o's MJCF", _mjcf_out_path(args.output))])
    try:
        check_origin(model, args.mjcf)
    except ModelError as exc:
        head, sep, tail = str(exc).partition(": ")
        raise InputError(f"--mjcf: {tail}" if sep and head == "mjcf" else str(exc)) from None


def _write_robot(res, args: argparse.Namespace) -> list[str]:
    """A URDF robot's fit written: the identified spec at -o, and where it fitted masses the URDF ``--model`` with
    them beside it (:func:`_mass_urdf_path`;
    :func:`~alpes_dyn.estimation.identification.identified_spec.identified_urdf`), with ``--mjcf`` the MJCF with
    the fit's values beside it (:func:`_mjcf_out_path`;
    :func:`~alpes_dyn.estimation.identification.identified_spec.identified_mjcf`): all built before any is
    written, the spec last (a failed URDF or MJCF write leaves no spec naming it). Returns the fitted parameters
    the MJCF cannot hold (none without --mjcf)."""
    from ..errors import ModelError
    from ..estimation.identification.identified_spec import (identified_mjcf, identified_spec, identified_urdf,
                                                             spec_misfits, write_identified_spec)
    from ..fileio import atomic_write, read_text
    from ..model.spec import load_spec

    base = load_spec(args.spec)
    masses = "urdf" if spec_misfits(res.model, res.names) else "refuse"
    text = identified_urdf(res, read_text(args.model, "--model")) if masses == "urdf" else None
    identified_spec(res, base, masses=masses)  # the spec's errors before anything is written
    mjcf, omitted = None, []
    if args.mjcf is not None:
        try:
            mjcf, omitted = identified_mjcf(res, base, args.mjcf, _mjcf_out_path(args.output))
        except ModelError as exc:
            head, sep, tail = str(exc).partition(": ")
            raise InputError(f"--mjcf: {tail}; nothing written" if sep and head == "mjcf" else str(exc)) from None
    if text is not None:
        if os.path.lexists(_mass_urdf_path(args.output)):  # not named by the user: said, never replaced silently
            warnings.warn(AlpesDynWarning(f"-o: {_mass_urdf_path(args.output)} (the URDF with the fit's masses beside "
                                          f"{args.output}) existed and is replaced"))
        atomic_write(_mass_urdf_path(args.output), text, "-o")
    if mjcf is not None:
        atomic_write(_mjcf_out_path(args.output), mjcf, "-o")
    write_identified_spec(res, base, args.output, masses=masses)
    return omitted
