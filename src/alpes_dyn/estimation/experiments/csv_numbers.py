"""A recording's data rows read by NumPy's C parser where they are plain numbers (issue 39).

:func:`~alpes_dyn.estimation.experiments.recording.read_recording` checks every cell on its own, in Python (the one
line naming the column and the line of a bad cell): on a long recording of the hand a large share of the fit's
time. Most recordings are a logger's plain numbers, and :func:`plain_rows` reads those with
:func:`numpy.loadtxt` (its C parser, ``comments=None``: no line is skipped as a comment). It gives up -- returns None,
and the cell-by-cell reader runs and names what is wrong -- on anything else: a cell that is not a plain number (an
empty one, a quoted one, digit separators, text), a row of another length, a NaN or an infinity anywhere (only the
optional columns may hold one, and the cell-by-cell reader says which), a subnormal value, or a cell longer than
:data:`~alpes_dyn.limits.MAX_CSV_CELL` (the cell-by-cell reader's limit).
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from ...errors import RecordingError
from ...limits import MAX_CSV_CELL

__all__ = ["plain_rows", "lines", "empty_row", "refuse_empty_row"]

_BLANK_ROW = re.compile(r"\n[ \t\r,]*\n")  # a line of nothing but blanks and commas, after another line
_LEADING_BLANKS = re.compile(r"(?:[ \t\r,]*\n)*")
_CONTENT = re.compile(r"[^\s,]")


def empty_row(text: str) -> int | None:
    """The line number (1-based) of the first empty row of a recording's CSV ``text`` (blank, or every cell empty)
    that lies between its header and a later data row, or None. Empty lines before the header and after the last
    data row are not counted (a file's trailing newlines); one in between is a lost sample, never skipped.

    Parameters
    ----------
    text : str
        The recording's text.

    Returns
    -------
    int or None
        The empty row's line number.
    """
    header = text.find("\n", _LEADING_BLANKS.match(text).end())
    if header < 0:
        return None
    blank = _BLANK_ROW.search(text, header)  # (about 6 ms a megabyte)
    if blank is None or _CONTENT.search(text, blank.end() - 1) is None:
        return None
    return text.count("\n", 0, blank.start() + 1) + 1


def refuse_empty_row(text: str, path: object) -> None:
    """:class:`~alpes_dyn.errors.RecordingError` naming the line of an empty row between data rows
    (:func:`empty_row`) of the recording ``path``'s ``text``.

    Parameters
    ----------
    text : str
        The recording's CSV text.
    path : object
        The recording's path, named in the error.

    Raises
    ------
    RecordingError
        An empty row between data rows.
    """
    line = empty_row(text)
    if line is not None:
        raise RecordingError(f"recording {str(path)!r}: line {line} is empty between data rows (a lost sample: fill "
                             "it or remove the line)")


class _LongLine(ValueError):
    """A cell longer than :data:`MAX_CSV_CELL` characters (the exact reader's limit)."""


def lines(text: str, start: int = 0):
    """The lines of ``text`` from offset ``start``, each with its "\\n", as ``io.StringIO(text)`` gives them (newline
    "\\n": no other line ending cuts a line), cut one at a time (no copy of the text: ``io.StringIO`` keeps one of 4
    bytes a character, 1 GiB for 600 s of the hand).

    Parameters
    ----------
    text : str
        The text.
    start : int, optional
        The offset of the first line, characters (default 0).

    Yields
    ------
    str
        Each line, with its newline.
    """
    n = len(text)
    while start < n:  # a loop over the lines (csv.reader and loadtxt take one at a time)
        end = text.find("\n", start)
        end = n if end < 0 else end + 1
        yield text[start:end]
        start = end


def _data_lines(text: str):
    """The lines of ``text`` after its first (the header), :func:`lines`'; :class:`_LongLine` at a cell longer than
    :data:`MAX_CSV_CELL` characters (only a longer line is split to see)."""
    for line in lines(text, text.find("\n") + 1):
        if len(line) > MAX_CSV_CELL and max(map(len, line.split(","))) > MAX_CSV_CELL:
            raise _LongLine(f"line {line[:40]!r}...: a cell over {MAX_CSV_CELL} characters")
        yield line


def plain_rows(text: str, columns: int) -> np.ndarray | None:
    """(rows, ``columns``) the data rows of a recording's CSV ``text`` whose first line is its header, where every
    cell of every other non-blank line is a plain finite number, normal or zero (the module doc); else None.

    Parameters
    ----------
    text : str
        The recording's CSV text, its header first.
    columns : int
        The number of columns expected.

    Returns
    -------
    numpy.ndarray, shape (rows, columns), or None
        The numbers, or None where the exact reader must read the text.
    """
    first = text.find("\n")
    if first < 0 or not text[:first].strip() or '"' in text:
        return None  # one line, a blank first line, or quoted cells: the exact reader
    try:
        with warnings.catch_warnings():  # (loadtxt warns of no data: None below)
            warnings.simplefilter("ignore")
            data = np.loadtxt(_data_lines(text), delimiter=",", comments=None, dtype=float, ndmin=2)
    except (ValueError, TypeError):  # (_LongLine too)
        return None
    if data.shape[0] == 0 or data.shape[1] != columns or not np.isfinite(data).all():
        return None
    if np.any((data != 0) & (np.abs(data) < np.finfo(float).tiny)):
        return None
    return data
