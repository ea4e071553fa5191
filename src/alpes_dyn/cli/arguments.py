"""The command line's argument types and shared options: numbers checked at parse time (one line, exit 2), the
outputs of ``--output``, the options every model command shares (``--model``, ``--spec``, ``--json``...)."""

from __future__ import annotations

import argparse
from typing import Callable

import numpy as np

from ..limits import MAX_POINTS, MAX_SEED
from .common import _strict_int


def _int_at_least(low: int, high: int | None = None) -> Callable[[str], int]:
    want = f"an integer >= {low}" if high is None else f"an integer from {low} to {high}"

    def parse(text: str) -> int:
        try:
            value = _strict_int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {want}, got {text!r}") from None
        if value < low or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {want}, got {value}")
        return value

    parse.__name__ = want
    return parse


_SEED = _int_at_least(0, MAX_SEED)
_POINTS = _int_at_least(1, MAX_POINTS)


def _strict_float(text: str) -> float:
    """A number as argparse's ``type=float`` reads it, less Python's digit separators (``1_0`` is not 10)."""
    if "_" in text:
        raise ValueError(text)
    return float(text)


_strict_float.__name__ = "float"  # argparse's message: "invalid float value: 'x'"


def _positive_seconds(text: str) -> float:
    try:
        value = _strict_float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}") from None
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text!r}")
    return value


_positive_seconds.__name__ = "seconds"


def _positive_number(unit: str) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = _strict_float(text)
        except ValueError:
            value = float("nan")
        if not (np.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"expected a positive number of {unit}, got {text!r}")
        return value

    parse.__name__ = unit
    return parse


OUTPUT_HELP = ("y: sum (of each motor's joint angles, default), encoder (q_m = S q), joints, joints:<a>,<b>, "
               "tip_position:<frame>; several joined by '+', e.g. encoder+tip_position:tip")


def _outputs(text: str) -> list[str]:
    parts = [p.strip() for p in text.split("+")]
    if not all(parts):
        raise argparse.ArgumentTypeError(f"expected output names joined by '+', got {text!r}")
    return parts


def _common(sp: argparse.ArgumentParser, model_default: str | None = "finger3") -> None:
    """The options of the commands on one model: --model, --spec, --spring, --params, --json."""
    sp.add_argument("--model", default=model_default, required=model_default is None,
                    help="finger2, finger3, hand, or a path to a fixed-base URDF file (default %(default)s)")
    sp.add_argument("--spec", default=None, metavar="FILE.toml",
                    help="transmission spec of a URDF --model: motors, ratios, encoder, springs, friction, "
                         "rotor inertia (see the user guide, 'Your own robot')")
    sp.add_argument("--spring", default=None, choices=("report", "torsional", "none"),
                    help="Alpes models: spring model torsional 1/2 K q^2 (default), report (eq. 2.14 literally), "
                         "none")
    sp.add_argument("--params", default=None, metavar="FILE",
                    help="Alpes models: parameter file (default: the shipped one)")
    sp.add_argument("--json", action="store_true", help="print one JSON object")


def _json_option(sp: argparse.ArgumentParser) -> None:
    """``--json``: the command's result as one JSON object on stdout (every command has it)."""
    sp.add_argument("--json", action="store_true", help="print one JSON object")


def _out_dir_option(sp: argparse.ArgumentParser, help: str) -> None:
    """``--out-dir DIR`` (the directory a command writes: ``codegen``, ``import``) and its deprecated alias ``-o DIR``
    of version 0.1 (``-o`` names a file in every other command; :func:`~alpes_dyn.cli.common.out_dir_alias`: one
    warning line naming --out-dir). One of the two is required (checked after parsing)."""
    sp.add_argument("--out-dir", default=None, metavar="DIR", help=help + " (required)")
    sp.add_argument("-o", "--output", default=None, metavar="DIR",
                    help="deprecated alias of --out-dir (-o names a file in every other command)")


def _model_option(sp: argparse.ArgumentParser, help: str) -> None:
    """``--model`` (default finger3, as every command's) and the deprecated positional MODEL of version 0.1
    (:func:`~alpes_dyn.cli.common.positional_model`: one warning line naming --model)."""
    sp.add_argument("legacy_model", nargs="?", default=None, metavar="MODEL",
                    help="deprecated: the model as a positional argument; give --model MODEL")
    sp.add_argument("--model", default=None, help=help + " (default finger3)")
