"""What every command shares: the exit codes and their exceptions, vectors and choices read from the
command line, the model of ``--model``, the output policy of the files a command reads and writes, and the
printing of its result (text, or one strict JSON object) on a stdout that may be closed or full."""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import warnings
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from ..errors import AlpesDynError, AlpesDynWarning, InputError, plain
from ..fileio import check_outputs
from ..limits import PHYSICAL_RANGES, check_not_subnormal, check_physical


VECTOR_OPTIONS = ("--q", "--v", "--u", "--tau", "--tau-m", "--force", "--contact-q")


_NUMLIST = re.compile(r"^-[0-9.]")


class _UsageError(Exception):
    pass


FORCE_USE_HELP = ("use a parameter file (or a URDF --spec) marked not trustworthy (written by 'identify --force'); "
                  "without it such a file is refused with its reason; the output says it is not")
"""The help of ``--force`` on the commands that use a parameter file's values (estimate, codegen, control)."""

EXIT_UNTRUSTED = 3
"""Exit code of ``identify`` when the fit did not converge or the model is not adequate (and no --force)."""


class _Untrusted(Exception):
    """The fit ran but is not to be trusted: exit :data:`EXIT_UNTRUSTED` with one line."""


class UntrustedFitWarning(AlpesDynWarning):
    """``identify --force`` wrote a file from a fit that did not converge or whose model is not adequate."""


def _one_of(value: str, choices: Sequence[str], option: str, kind: str) -> None:
    """InputError ``<option>: unknown <kind> 'x' (expected one of ...)`` unless ``value`` is a choice."""
    if value not in choices:
        raise InputError(f"{option}: unknown {kind} {value!r} (expected one of {', '.join(choices)})")


def _one_chain(model: str, models: Sequence[str], what: str, hand: bool = False) -> None:
    """InputError unless ``model`` is one of the one-chain ``models`` ``what`` is defined for (``hand``: the whole
    hand is too, handled before this check)."""
    if model not in models:
        raise InputError(f"--model: {what} is defined for one chain ({', '.join(models)}; a finger of the hand "
                         f"with --chain){' or the whole hand (hand)' if hand else ''}, got {model!r}")


def _one_finger(model: str, models: Sequence[str], what: str) -> None:
    """InputError unless ``model`` is one of the one-finger ``models`` ``what`` is defined for."""
    if model not in models:
        raise InputError(f"--model: {what} is defined for one finger ({', '.join(models)}), got {model!r}")


VECTOR_UNITS: dict[str, tuple[str, str]] = {
    "q": ("rad", "any"), "v": ("rad/s", "any"), "tau": ("N m", "any"), "tau-m": ("N m", "any"), "u": ("N m", "any"),
    "force": ("N", "any"), "contact-q": ("rad", "any"), "encoder-offset": ("rad", "any"), "tilt": ("rad", "any"),
    "camera-times": ("s", "nonneg"), "excitation": ("Hz", "pos"),
}
"""The unit and sign of each comma-separated option's numbers (their ranges: :data:`alpes_dyn.limits.PHYSICAL_RANGES`;
a joint coordinate of a prismatic joint is read in m, within the same magnitude)."""

OPTION_UNITS: dict[str, tuple[str, str]] = {
    "stiction": ("s", "pos"), "tendon_stiffness": ("N/m", "pos"), "tendon_damping": ("N s/m", "nonneg"),
    "tendon_dead_band": ("m", "nonneg"), "dt": ("s", "pos"), "mismatch": ("-", "any"), "duration": ("s", "pos"),
    "torque_noise": ("N m", "nonneg"), "torque_constant": ("N m/A", "pos"),
    "encoder_noise": ("counts", "nonneg"), "tau_max": ("N m", "pos"), "tilt": ("deg", "any"),
}
"""The unit and sign of each number option (by its ``dest``), checked by :func:`check_option_ranges` right after
parsing, before any work: not subnormal, within the magnitude :data:`alpes_dyn.limits.PHYSICAL_RANGES` gives its
unit."""


def check_option_ranges(args: argparse.Namespace) -> None:
    """InputError ``--<option>: ...`` for the first number option of ``args`` (:data:`OPTION_UNITS`) that is
    subnormal or larger in magnitude than its unit's accepted range allows (an angle of 1e300 deg, a duration of
    1e300 s), right after parsing; its sign, zero, NaN and inf are left to the command's own check, which names the
    quantity (``torque_noise: expected a non-negative number of N m, at most 1``)."""
    for dest, (unit, kind) in OPTION_UNITS.items():
        value = getattr(args, dest, None)
        if isinstance(value, float) and np.isfinite(value) and (abs(value) > PHYSICAL_RANGES[unit][1]
                                                                 or 0 < abs(value) < sys.float_info.min):
            check_physical(value, "--" + dest.replace("_", "-"), unit, kind)
    for dest in FRACTION_OPTIONS:
        value = getattr(args, dest, None)
        if isinstance(value, float):
            check_fraction(value, "--" + dest)


FRACTION_OPTIONS = ("perturb", "spread")
"""The options that are a relative spread, each a fraction in [0, 1) (``experiment --perturb``, ``sweep --spread``):
named by the option the user typed (``--perturb nan`` said ``spread: ...``, ``--perturb 1e300`` gave the range
[0, 1e+06] of a ratio, 2 being refused later)."""


def check_fraction(value: float, flag: str) -> float:
    """``value`` if it is a fraction in [0, 1), not subnormal, else InputError naming ``flag``."""
    check_not_subnormal(value, flag)
    if not (np.isfinite(value) and 0 <= value < 1):
        raise InputError(f"{flag}: expected a fraction in [0, 1), got {value!r}")
    return value


def _strict_int(text: str) -> int:
    """An integer as ``int()`` reads it, less Python's digit separators (``1_0`` is not 10: ``--draws 1_0`` ran ten
    draws)."""
    if "_" in text:
        raise ValueError(text)
    return int(text)


def parse_vector(text: str, name: str) -> np.ndarray:
    """``"-0.1,0.2"`` -> array([-0.1, 0.2]); a clear :class:`InputError` otherwise (and for numbers outside the
    accepted range of the option's unit, :data:`VECTOR_UNITS`)."""
    name = name.lstrip("-")
    parts = [p.strip() for p in text.split(",")]
    try:
        if any("_" in p for p in parts):  # float() reads 1_0 as 10: not a number written on a command line
            raise ValueError(text)
        vals = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"--{name}: expected comma-separated numbers, got {text[:80]!r}") from None
    a = np.array(vals)
    if not np.isfinite(a).all():
        raise InputError(f"--{name}: contains NaN or inf ({text[:80]!r})")
    unit, kind = VECTOR_UNITS.get(name, ("", "any"))
    check_physical(a, f"--{name}", unit, kind)
    return a


COMPILING_COMMANDS = ("estimate", "codegen", "experiment", "identify", "identifiability", "control", "sweep")
"""The commands that may compile C code into the cache: its folder is checked before they start."""


def check_cache_before_compiling(args: argparse.Namespace) -> None:
    """For a command of :data:`COMPILING_COMMANDS`: the compiled-code cache's folder checked before any work
    (:func:`alpes_dyn.simulation.codegen.cache_dir`): a symbolic link, a file or a folder that cannot be written is
    one line and exit 2, not a silent fall-back to uncompiled code minutes later."""
    if getattr(args, "command", None) in COMPILING_COMMANDS:
        from ..simulation.codegen import cache_dir

        cache_dir()


def refuse_repeated_options(parser: argparse.ArgumentParser, argv: Sequence[str]) -> None:
    """InputError ``--x: given 2 times; give it once`` for an option given more than once on the command line (the
    last would silently win over the others). Flags of the command's subparser, by their dest."""
    sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    words = [a for a in argv if not a.startswith("-")]
    command = sub.choices.get(words[0]) if sub is not None and words else None
    if command is None:
        return
    seen: dict[str, int] = {}
    flags: dict[str, str] = {}
    for a in argv:
        if a == "--":
            break
        action = command._option_string_actions.get(a.split("=", 1)[0]) if a.startswith("-") else None
        if action is None or isinstance(action, argparse._HelpAction):
            continue
        seen[action.dest] = seen.get(action.dest, 0) + 1
        flags.setdefault(action.dest, a.split("=", 1)[0])
    for dest, n in seen.items():
        if n > 1:
            raise InputError(f"{flags[dest]}: given {n} times; give it once")


def _join_negative_vectors(argv: Sequence[str]) -> list[str]:
    """Turn ``--q -0.1,0.2`` into ``--q=-0.1,0.2`` (argparse would read -0.1,0.2 as an option)."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in VECTOR_OPTIONS and i + 1 < len(argv) and _NUMLIST.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


_INPUT_OPTIONS = (("params", "--params"), ("spec", "--spec"), ("true_spec", "--true-spec"),
                  ("true_model", "--true-model"), ("data", "--data"),
                  ("validate", "--validate"),
                  ("true_params", "--true-params"), ("observer_params", "--observer-params"),
                  ("plant_params", "--plant-params"), ("mjcf", "--mjcf"))


_OUTPUT_OPTIONS = (("output", "-o"), ("true_params_out", "--true-params-out"), ("log", "--log"), ("plot", "--plot"))


def _check_run_files(args: argparse.Namespace, extensions: dict[str, Sequence[str]] | None = None,
                     more: Sequence[tuple[str, str]] = ()) -> None:
    """The output policy (:func:`alpes_dyn.fileio.check_outputs`) of the command in ``args``, before any work:
    every output it writes (-o, --true-params-out, --log, --plot) checked against every file it reads
    (--params, --spec, --data, --true-params, --observer-params, --plant-params, --mjcf, a URDF or MJCF --model) and
    the others; ``more``: (what, path) of the other files it writes (identify's URDF beside -o)."""
    inputs = [(flag, f) for dest, flag in _INPUT_OPTIONS for f in _files(getattr(args, dest, None))]
    model = getattr(args, "model", None)
    if isinstance(model, str) and (_is_urdf_path(model) or _is_mjcf_path(model)):
        inputs.append(("--model", model))
    outputs = [(flag, getattr(args, dest, None)) for dest, flag in _OUTPUT_OPTIONS]
    outputs = [(f, v) for f, v in outputs if isinstance(v, str)] + list(more)  # (linearize's --output: names)
    # --log FILE.csv is a CSV, --true-params-out a parameter file (TOML), by their names
    check_outputs(outputs, inputs, {"--log": ("csv",), "--true-params-out": ("toml",), **(extensions or {})})


def _files(value: Any) -> list[str]:
    """An input option's files: its one path, or each of a list of paths (``identify --data A.csv B.csv``)."""
    if isinstance(value, str):
        return [value]
    return [v for v in value if isinstance(v, str)] if isinstance(value, (list, tuple)) else []


def data_label(args: argparse.Namespace) -> str:
    """``--data`` as the text and the identified file name it: its path, or its paths joined by ", "."""
    return ", ".join(_files(args.data))


def read_data(args: argparse.Namespace, model: Any, **kw: Any) -> Any:
    """The recording of ``--data`` read for ``model`` (with ``--torque-constant``; ``kw`` to
    :func:`~alpes_dyn.estimation.experiments.recording.read_recording`): of several files, one recording of several
    runs, each file its own (:func:`~alpes_dyn.estimation.experiments.recording.join_runs`)."""
    from ..estimation.experiments.recording import join_runs, read_recording

    files = _files(args.data)
    seen: dict[Any, str] = {}
    for f in files:  # a loop over the few files: the same file, or a copy of it, given twice
        key = (os.path.realpath(f), None) if not os.path.isfile(f) else _content_key(f)
        if key in seen:
            raise InputError(f"--data: {f!r} is the same recording as {seen[key]!r}: a run fitted twice makes its "
                             "standard errors sqrt(2) too small")
        seen[key] = f
    recs = [read_recording(f, model, args.torque_constant, **kw) for f in files]
    return recs[0] if len(recs) == 1 else join_runs(recs)


def _content_key(path: str) -> tuple[int, str]:
    """(size, SHA-256 of the bytes) of a readable file: two names of one recording have the same key."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return os.path.getsize(path), h.hexdigest()


def _is_urdf_path(model: str) -> bool:
    return model.endswith(".urdf") or "/" in model


def _is_mjcf_path(model: str) -> bool:
    """Whether a --model names an MJCF file (by its extension, .xml or .mjcf)."""
    return model.lower().endswith((".xml", ".mjcf"))


MJCF_MODEL_COMMANDS = ("urdf", "import")
"""The commands that read an MJCF --model (``urdf``: the URDF of its tree; ``import``: its URDF and spec)."""


def positional_model(args: argparse.Namespace) -> None:
    """``urdf`` and ``mjcf``'s positional MODEL of version 0.1 (``alpes-dyn urdf finger3``), a deprecated alias of
    ``--model``: moved into ``args.model`` with one DeprecationWarning naming --model (the one warning line of
    :func:`alpes_dyn.cli.main`); given with --model it is refused; neither given: finger3, as every command's."""
    if not hasattr(args, "legacy_model"):
        return
    legacy = args.legacy_model
    if legacy is not None:
        if args.model is not None:
            raise InputError(f"--model: given with the positional model {legacy!r}; give --model only")
        warnings.warn(f"'alpes-dyn {args.command} {legacy}': the positional model is deprecated, give --model "
                      f"{legacy}", DeprecationWarning, stacklevel=2)
        args.model = legacy
    elif args.model is None:
        args.model = "finger3"


def refuse_mjcf_model(args: argparse.Namespace) -> None:
    """InputError naming ``alpes-dyn import`` for an MJCF --model given to a command that reads a name or a URDF
    (all but :data:`MJCF_MODEL_COMMANDS`): its URDF and spec are written first, then given as --model, --spec."""
    model = getattr(args, "model", None)
    if isinstance(model, str) and _is_mjcf_path(model) and args.command not in MJCF_MODEL_COMMANDS:
        stem = Path(model).stem
        raise InputError(f"--model: {model!r} is an MJCF file; 'alpes-dyn import --model {model} --out-dir DIR' "
                         f"writes its URDF and spec, then give --model DIR/{stem}.urdf --spec DIR/{stem}.toml")


OUT_DIR_COMMANDS = ("codegen", "import")
"""The commands that write a directory (``--out-dir DIR``; ``-o DIR`` its deprecated alias)."""


def out_dir_alias(args: argparse.Namespace) -> None:
    """``codegen`` and ``import``'s ``-o DIR`` of version 0.1, a deprecated alias of ``--out-dir DIR`` (``-o`` names
    a file in every other command): moved into ``args.out_dir`` with one DeprecationWarning naming --out-dir (the
    one warning line of :func:`alpes_dyn.cli.main`); ``args.out_flag`` is the option given, for the error lines.

    Raises
    ------
    InputError
        ``-o`` given with ``--out-dir``; neither given (``--out-dir: required ...``).
    """
    if getattr(args, "command", None) not in OUT_DIR_COMMANDS:
        return
    if args.output is not None:
        if args.out_dir is not None:
            raise InputError("-o: given with --out-dir; give --out-dir only (-o DIR is its deprecated alias)")
        warnings.warn(f"'alpes-dyn {args.command} -o {args.output}': -o for a directory is deprecated (-o names a "
                      f"file in every other command), give --out-dir {args.output}", DeprecationWarning, stacklevel=2)
        args.out_dir, args.out_flag, args.output = args.output, "-o", None
    elif args.out_dir is None:
        raise InputError(f"--out-dir: required: the directory {args.command} writes (new, or empty)")
    else:
        args.out_flag = "--out-dir"


_ALPES_ONLY = (("spring", "--spring"), ("params", "--params"), ("friction", "--friction"),
               ("no_friction", "--no-friction"), ("rotor_inertia", "--rotor-inertia"))


def friction_from_file(args: argparse.Namespace, path: str | None, flag: str) -> str:
    """``args.friction`` for ``estimate`` and ``codegen`` on an Alpes model: ``--friction`` or ``--no-friction``
    where given (an override: where the file says otherwise, one warning line names both), else what the parameter
    file's fit record says (:func:`~alpes_dyn.model.trust.fitted_friction`: ``identify`` fitted with
    friction), else no friction (the shipped file, a file without a record).

    Parameters
    ----------
    args : argparse.Namespace
        The command's options (``model``, ``chain``, ``friction``, ``no_friction``); ``args.friction`` is set.
    path : str or None
        The parameter file of the observer's model (None: the shipped one, which says nothing).
    flag : str
        The option that gave ``path`` (``--params``, ``--observer-params``), for the lines.

    Returns
    -------
    str
        Where the choice came from: ``"--friction"``, ``"--no-friction"``, ``"<flag>"`` or ``"default"``.

    Raises
    ------
    InputError
        ``--no-friction`` given with ``--friction``.
    """
    from ..model.params import load_params
    from ..model.trust import fitted_friction

    if args.friction and args.no_friction:
        raise InputError("--no-friction: given with --friction; give one of them")
    said = None
    if path is not None:
        said = fitted_friction(load_params(path), "thumb" if args.model == "thumb" else (args.chain or "finger"))
    if args.friction or args.no_friction:
        given = bool(args.friction)
        option = "--friction" if given else "--no-friction"
        if said is not None and said != given:
            warnings.warn(f"{option} overrides {flag} {path}, whose fit had {'' if said else 'no '}friction: the "
                          f"observer's model has {'' if given else 'no '}friction", AlpesDynWarning, stacklevel=2)
        args.friction = given
        return option
    args.friction = bool(said)
    return flag if said is not None else "default"


def _given(value: object) -> bool:
    """Whether an option's parsed value was given: not its default None or a flag's False (by identity: a number
    option given 0, which equals False, is given; ``--torque-noise 0`` was taken as absent and silently ignored)."""
    return value is not None and value is not False


def _check_model_options(args: argparse.Namespace) -> None:
    """Refuse, with one line, the options that do not apply to the kind of --model given (never ignore them)."""
    if _is_urdf_path(args.model):
        for dest, flag in _ALPES_ONLY:
            if _given(getattr(args, dest, None)):
                raise InputError(f"{flag}: applies to the Alpes models (finger2, finger3, hand); for a URDF --model "
                                 "put springs, friction and rotor inertia in a --spec file")
    elif getattr(args, "spec", None) is not None:
        raise InputError(f"--spec: applies to a URDF --model; the Alpes model {args.model!r} takes its transmission "
                         "from --params")


def _model_from_args(args: argparse.Namespace):
    from ..model.robot import Model

    _check_model_options(args)
    if _is_urdf_path(args.model):
        return Model.from_urdf_file(args.model, getattr(args, "spec", None))
    return Model.alpes(args.model, spring=getattr(args, "spring", None) or "torsional",
                       friction=getattr(args, "friction", False), rotor_inertia=getattr(args, "rotor_inertia", False),
                       params=getattr(args, "params", None))


def _refuse_for_urdf(args: argparse.Namespace, options: Sequence[tuple[str, str, Any, str]]) -> None:
    """InputError ``<flag>: <why>`` for the first of ``options`` (flag, dest, default, why) given on a URDF --model."""
    for flag, dest, default, why in options:
        if getattr(args, dest, default) != default:
            raise InputError(f"{flag}: {why}")


def _urdf_robot(args: argparse.Namespace, what: str, spec: str | None = None):
    """The Model of a URDF --model with its --spec (required: ``what`` needs the robot's motors and encoders)."""
    from ..model.robot import Model

    _check_model_options(args)
    spec = args.spec if spec is None else spec
    if spec is None:
        raise InputError(f"--spec: {what} on a URDF --model needs its transmission spec (motors, encoder, springs, "
                         "friction: see the user guide, 'Your own robot')")
    return Model.from_urdf_file(args.model, spec)


def _one_or_list(outputs: list[str]) -> str | list[str]:
    return outputs[0] if len(outputs) == 1 else outputs


def _json_safe(x: Any) -> Any:
    """``x`` with every non-finite float (NaN, inf: not JSON) written as null."""
    if isinstance(x, float):
        return x if np.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_json_safe(v) for v in x]
    return x


def _emit(obj: dict[str, Any], text: str, as_json: bool) -> None:
    """Print the result: one JSON object (strict JSON: a non-finite number is null) or the text."""
    _write_stdout((json.dumps(_json_safe(obj), allow_nan=False) if as_json else text) + "\n")


class _StdoutError(AlpesDynError):
    """Standard output cannot take the result (a closed pipe, a full device)."""


def _write_stdout(text: str) -> None:
    """Write ``text`` to stdout and flush it; a closed pipe or a full device is :class:`_StdoutError` (one line,
    exit 2), and stdout is then pointed at /dev/null so that the interpreter's last flush cannot fail again."""
    if sys.stdout is None:  # started with stdout closed (``>&-``)
        raise _StdoutError("stdout: closed (nowhere to write the output)")
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except BrokenPipeError:
        _drop_stdout()
        raise _StdoutError("stdout: broken pipe (the reader closed it before the end of the output)") from None
    except OSError as exc:
        _drop_stdout()
        raise _StdoutError(f"stdout: cannot write the output ({exc.strerror or exc})") from None


def _drop_stdout() -> None:
    try:
        fd = os.open(os.devnull, os.O_WRONLY)
        os.dup2(fd, sys.stdout.fileno())
        os.close(fd)
    except (OSError, ValueError, AttributeError):
        pass


def _fmt_matrix(M: np.ndarray) -> str:
    return "\n".join("  " + " ".join(f"{x: .6e}" for x in row) for row in np.atleast_2d(M))


def _fmt_table(M: np.ndarray, rows: Sequence[str], cols: Sequence[str]) -> str:
    """A matrix with a header of column names and each row led by its name."""
    M = np.atleast_2d(M)
    w = max([len(r) for r in rows] + [1])
    cw = max([len(c) for c in cols] + [13])
    head = "  " + " " * w + " " + " ".join(f"{c:>{cw}s}" for c in cols)
    return "\n".join([head] + ["  " + f"{r:<{w}s} " + " ".join(f"{x:>{cw}.6e}" for x in row)
                               for r, row in zip(rows, M)])


def _one_line(text: str) -> str:
    """``text`` on one line, numpy scalar reprs as plain numbers (a warning's or a library's text too)."""
    return " ".join(plain(str(text)).split())


def _excursion_lines(rec: Any, obj: dict[str, Any]) -> str:
    """:func:`~alpes_dyn.estimation.experiments.excursion.excursion_report` of the recording ``rec`` into ``obj``; its
    lines, one per motor whose encoder barely moved, each on a line of its own after a command's text (experiment,
    identify)."""
    from ..estimation.experiments.excursion import excursion_report

    obj.update(excursion_report(rec))
    return "".join(f"\n  WARNING: {line}" for line in obj["small_excursions"])


def _drift_choice(text: str) -> str:
    """``--drift``: a comma-separated choice of the drifts (:data:`~alpes_dyn.estimation.identification.drift.DRIFTS`),
    checked here (argparse's one line), passed on as given."""
    from ..errors import InputError
    from ..estimation.identification.drift import check_drift

    try:
        check_drift(text)
    except InputError as err:
        raise argparse.ArgumentTypeError(str(err).removeprefix("drift: ")) from None
    return text


def _trust_notes(args: argparse.Namespace, files: Sequence[tuple[str, str | None]]) -> list[str]:
    """The parameter files or URDF specs a command uses, ``(option, path or None)``, each refused when it is marked
    not trustworthy (a file written by ``identify --force``: :func:`~alpes_dyn.model.trust.check_trusted`; a spec's
    ``[identified]`` record with ``trustworthy = false``) -- one line with the reason the file records, exit 2 --
    unless ``--force`` (``args.force``); then its lines ``<option>: <path> is NOT trustworthy (<why>)`` for the output."""
    from ..errors import ModelError
    from ..model.params import load_params
    from ..model.trust import check_trusted, untrusted_reason
    from ..model.spec import load_spec

    notes = []
    for option, path in files:
        if path is None:
            continue
        if _is_urdf_path(getattr(args, "model", "")) and option == "--spec":
            rec = (load_spec(path).identified or {}).get("record", {})
            if rec.get("trustworthy") is not False:
                continue
            why = untrusted_reason(rec)
            if not args.force:
                raise ModelError(f"{option}: {path!r} is marked not trustworthy ({why}); --force uses it anyway")
            notes.append(f"{option}: {path!r} is NOT trustworthy ({why})")
            continue
        note = check_trusted(load_params(path), bool(args.force), option, "--force uses it anyway")
        if note:
            notes.append(f"{option}: {note}")
    return notes


def _note_untrusted(obj: dict, lines: list[str], notes: list[str]) -> None:
    """The files used with --force though marked not trustworthy (:func:`_trust_notes`): ``obj``'s
    ``not_trustworthy`` (a list, empty when none) and a WARNING line each."""
    obj["not_trustworthy"] = list(notes)
    lines += [f"  WARNING: {n}" for n in notes]
