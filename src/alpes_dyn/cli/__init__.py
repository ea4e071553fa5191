"""Command line ``alpes-dyn``: URDF generation, dynamics, the report reproduced, observability, estimation.

Every bad input ends with one line on stderr naming the problem and exit code 2, never a traceback.
Exit code 3 (:data:`EXIT_UNTRUSTED`): ``identify`` ran, but its fit did not converge or its model is not
adequate to the recording; nothing was written (``--force`` writes the file, marked not trustworthy).
Vectors are comma-separated numbers; negative values work as ``--q=-0.1,0.2`` and ``--q -0.1,0.2``.

The package holds one module per command family, each a thin layer over the floors below:
``model_cmds`` (urdf, mjcf, import, dynamics, linearize, report), ``analysis_cmds`` (observability,
identifiability), ``estimation_cmds`` (estimate, codegen, experiment, identify), ``control_cmds`` (control) and
``study_cmds`` (sweep); ``parser`` builds the parser (:func:`build_parser`) and ``common`` holds what they
share. This module runs one command (:func:`main`), turns every exception into its exit code and one stderr
line, and re-exports the names of the former module ``cli.py``: ``alpes_dyn.cli.X`` is what it was.
:func:`main` looks :func:`build_parser` up here, so a test that replaces ``alpes_dyn.cli.build_parser``
changes the parser it runs.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from typing import Callable, Sequence

from ..blas_threads import one_blas_thread
from ..errors import AlpesDynError, InputError
from ..fileio import native_stderr_to
from ..limits import MAX_ARGS, max_bytes
from .common import (EXIT_UNTRUSTED, _join_negative_vectors, _one_line, _StdoutError, _Untrusted, _UsageError,
                     _write_stdout, check_cache_before_compiling, check_option_ranges, out_dir_alias, positional_model,
                     refuse_mjcf_model, refuse_repeated_options)
from .parser import build_parser

# the names of the former module cli.py, where they are now (``from alpes_dyn.cli import X`` still works)
from .analysis_cmds import DESIGNS, _observability_summary, cmd_identifiability, cmd_observability  # noqa: F401
from .common import (_ALPES_ONLY, _INPUT_OPTIONS, _NUMLIST, _OUTPUT_OPTIONS, VECTOR_OPTIONS,  # noqa: F401
                     UntrustedFitWarning, _check_model_options, _check_run_files, _drop_stdout, _emit, _fmt_matrix,
                     _fmt_table, _is_urdf_path, _json_safe, _model_from_args, _one_chain, _one_finger, _one_of,
                     _one_or_list, parse_vector)
from .control_cmds import (_check_control_outputs, _control_hand, _na, _output_lines,  # noqa: F401
                           _write_control_outputs, cmd_control)
from .estimation_cmds import (_SCENARIO_ONLY, THUMB_PARAMETERS, _estimate_data, cmd_estimate,  # noqa: F401
                              cmd_identify)
from .experiment_cmds import cmd_experiment  # noqa: F401
from .model_cmds import cmd_dynamics, cmd_linearize, cmd_mjcf, cmd_report, cmd_urdf, dynamics_crosscheck  # noqa: F401
from .parser import (_POINTS, _SEED, DESCRIPTION, OUTPUT_HELP, _int_at_least, _outputs, _Parser,  # noqa: F401
                     _positive_seconds)
from .study_cmds import cmd_sweep  # noqa: F401


def _run(argv: list[str]) -> tuple[int, str | None]:
    """(exit code, error line or None) of one command."""
    try:
        if len(argv) > MAX_ARGS:
            raise InputError(f"{len(argv)} command-line arguments, over the limit of {MAX_ARGS}")
        parser = build_parser()
        refuse_repeated_options(parser, argv)
        args = parser.parse_args(_join_negative_vectors(argv))
        positional_model(args)  # urdf, mjcf: the deprecated positional MODEL as --model (one warning line)
        out_dir_alias(args)  # codegen, import: the deprecated -o DIR as --out-dir (one warning line)
        refuse_mjcf_model(args)
        check_option_ranges(args)
        max_bytes()  # $ALPES_DYN_MAX_BYTES read by every command: a bad one is refused even where no array is sized
        check_cache_before_compiling(args)
        func: Callable[[argparse.Namespace], int] = args.func
        return func(args), None
    except _UsageError as exc:
        return 2, _one_line(str(exc))
    except _Untrusted as exc:
        return EXIT_UNTRUSTED, _one_line(str(exc))
    except AlpesDynError as exc:
        return 2, f"alpes-dyn: error: {_one_line(str(exc))}"
    except KeyboardInterrupt:
        return 130, "alpes-dyn: interrupted"
    except MemoryError:  # a size no check foresaw: still the input's
        return 2, "alpes-dyn: error: out of memory: the input asks for arrays larger than this machine holds"
    except (OverflowError, RecursionError) as exc:
        return 2, f"alpes-dyn: error: an input too large ({type(exc).__name__}: {_one_line(str(exc))[:200]})"
    except Exception as exc:  # never a traceback for a user
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        return 1, f"alpes-dyn: internal error: {type(exc).__name__}: {_one_line(msg)}"


def _tolerant_streams() -> None:
    """Text that the terminal's encoding cannot show (the é of Cramér under ``PYTHONIOENCODING=ascii``) is
    written as a backslash escape rather than raising UnicodeEncodeError."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="backslashreplace")  # type: ignore[union-attr]
        except (AttributeError, ValueError, OSError):
            pass


def _say(line: str) -> None:
    """One line on stderr; nothing if stderr is closed (``2>&-``) or cannot be written."""
    if sys.stderr is None:
        return
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; exit code 0, 2 for bad input (one line on stderr), 3 for an identification not to be
    trusted (:data:`EXIT_UNTRUSTED`), 1 for an internal error.

    Whatever Python warnings (e.g. numpy's RuntimeWarning) and native libraries (urdfdom, CasADi) would
    print on stderr is captured: it is appended to the error line, or, after a successful command,
    summarised in one ``alpes-dyn: warning:`` line. stderr never gets more than one line. A closed or full
    stdout (``| head``, ``> /dev/full``) is exit 2 with one line; a closed stderr (``2>&-``) is written to
    nowhere, the exit code unchanged.
    """
    _tolerant_streams()
    one_blas_thread()  # OpenBLAS's spinning workers off the cores the compiled loops use (blas_threads)
    argv = list(sys.argv[1:] if argv is None else argv)
    printed: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with native_stderr_to(printed):
            try:
                code, error = _run(argv)
            except SystemExit as done:  # --help, --version: argparse printed them
                try:
                    _write_stdout("")
                except _StdoutError as exc:
                    code, error = 2, f"alpes-dyn: error: {exc}"
                else:
                    raise done
    notes = [_one_line(f"{w.category.__name__}: {w.message}") for w in caught] + [_one_line(p) for p in printed]
    more = f" (+{len(notes) - 1} more)" if len(notes) > 1 else ""
    if error is not None:
        _say(error + (f" [{notes[0]}{more}]" if notes else ""))
    elif notes:
        _say(f"alpes-dyn: warning: {notes[0]}{more}")
    return code
