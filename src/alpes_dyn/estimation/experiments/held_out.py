"""The samples of a recording held out of the fit (issue 50): a recording's optional ``held_out`` column (0 or 1 per
sample) marks the slow stiction ramp that ``alpes-dyn experiment`` records after its excitation
(:mod:`~alpes_dyn.estimation.experiments.stick_ramp`). The fit never sees them; ``identify``'s observer check and its
choice of the observer's friction law are judged on them (``identify --validate``'s record takes precedence where
given), not its open-loop validation (a memoryless friction law's simulation does not follow a joint that sticks:
on a stiff stick-slip finger3 at 1x F_s whose fit was within 0.6 % and its EKF 0.14 degree, the simulation fitted
the ramp 3.9 %, against the 70 % the verdict asks). In each run the held-out samples are the run's last ones (the fitted samples of a run one
block, with no jump in time), at least :data:`~alpes_dyn.estimation.experiments.recording.MIN_SAMPLES` of them where
there are any, and a run keeps at least as many fitted. A recording without the column is fitted whole, as before."""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import RecordingError

__all__ = ["held_out_column", "check_held_out", "split_held_out"]


def held_out_column(col: dict[str, np.ndarray]) -> np.ndarray | None:
    """The ``held_out`` column of a CSV's columns as (N,) bool (None without it): each cell 0 or 1.

    Parameters
    ----------
    col : dict of str to numpy.ndarray
        The recording's columns by name, each (N,).

    Returns
    -------
    numpy.ndarray of bool, shape (N,), or None

    Raises
    ------
    RecordingError
        A cell other than 0 or 1, naming its line.
    """
    if "held_out" not in col:
        return None
    h = np.asarray(col["held_out"], dtype=float)
    bad = np.flatnonzero((h != 0) & (h != 1))
    if bad.size:
        k = int(bad[0])
        raise RecordingError(f"recording: column 'held_out' line {k + 2}: {h[k]:g} is not 0 or 1 (1: a sample held out "
                             "of the fit, the observer check judged on it)")
    return h == 1


def check_held_out(held_out: Any, run_starts: np.ndarray, min_samples: int) -> None:
    """Check a recording's held-out samples (module docstring): RecordingError naming the column where they are not
    each run's last samples, or leave too few on either side.

    Parameters
    ----------
    held_out : numpy.ndarray or None
        (N,) bool (or 0/1): the samples held out of the fit; None: none.
    run_starts : numpy.ndarray of int
        (R+1,) the first sample of each run, then N (:meth:`~alpes_dyn.estimation.experiments.recording.Recording.
        run_starts`).
    min_samples : int
        The fewest samples a held-out tail (where there is one) and a run's fitted part may have.

    Raises
    ------
    RecordingError
        A mask of the wrong shape, held-out samples not at a run's end, or too few.
    """
    if held_out is None:
        return
    h = np.asarray(held_out)
    N = int(run_starts[-1])
    if h.shape != (N,) or not (h.dtype == bool or np.all((h == 0) | (h == 1))):
        raise RecordingError(f"recording: held_out has shape {h.shape}, expected ({N},) values 0 or 1")
    h = h.astype(bool)
    for r, (a, b) in enumerate(zip(run_starts[:-1], run_starts[1:])):  # a loop over the runs (a few)
        part = h[a:b]
        n_out = int(part.sum())
        if n_out and not part[b - a - n_out:].all():
            k = a + int(np.argmax(part))
            raise RecordingError(f"recording: column 'held_out' line {k + 2}: the held-out samples must be the last of "
                                 f"their run (run {r}: a fitted sample follows them)")
        if n_out and (n_out < min_samples or b - a - n_out < min_samples):
            raise RecordingError(f"recording: column 'held_out' in run {r}: {n_out} held-out and {b - a - n_out} "
                                 f"fitted samples; each needs at least {min_samples}")


def split_held_out(rec: Any, validation: Any = None) -> tuple[Any, Any]:
    """``rec``'s fitted part and the record the observer check judges on: ``validation`` where given, else ``rec``'s
    held-out samples (None where it has none); ``rec`` as it is where it has no held-out samples.

    Parameters
    ----------
    rec : Recording or other
        The recording given to the fit (anything but a :class:`~alpes_dyn.estimation.experiments.recording.
        Recording` with held-out samples is returned as it is).
    validation : Recording or str or Path or None, optional
        ``identify --validate``'s record (it takes precedence over the held-out samples).

    Returns
    -------
    tuple
        (the recording fitted, without the ``held_out`` column; the validation: ``validation``, the held-out
        samples as their own recording, or None).
    """
    h = getattr(rec, "held_out", None)
    if h is None:
        return rec, validation
    h = np.asarray(h, dtype=bool)
    if not h.any():
        fit = rec.take(slice(None))
        fit.held_out = None
        return fit, validation
    fit, out = rec.take(~h), rec.take(h)
    fit.held_out = out.held_out = None
    return fit, (out if validation is None else validation)
