"""A recording's units, checked for plausibility (issue 49): the mistakes a bench's logger makes -- a motor current
(in A or mA) in the torque column, the motor's angle in radians or degrees in the encoder's, which a fit or an
observer reads as a huge torque or a few counts of motion ("the filter diverged", "Newton's method did not
converge") -- refused by :func:`~alpes_dyn.estimation.experiments.recording.read_recording` with one
:class:`~alpes_dyn.errors.RecordingError` naming the column and the likely mistake. (Its time in ms is the
reader's sample-period check.)"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...errors import RecordingError
from ...model.robot import Model

__all__ = ["TORQUE_SCALE_LIMIT", "check_counts", "check_torque_scale", "check_units"]

TORQUE_SCALE_LIMIT = 10.0
"""A recorded torque beyond this many times the parameter file's ``tau_max`` is not N m (a current in A or mA)."""


def check_counts(motor: str, e: np.ndarray, span: float, cpr: float) -> None:
    """An encoder column (counts, (N,)) that is not counts: most of its values not whole numbers and its swing within
    what the joints' range ``span`` (counts) makes in degrees of the motor -- the motor's angle in radians or
    degrees, which a fit or an observer would read as a few counts of motion.

    Parameters
    ----------
    motor : str
        The motor's name (the column ``encoder_<motor>``).
    e : numpy.ndarray, shape (N,)
        The column, counts.
    span : float
        What the joints' range makes at the encoder, counts.
    cpr : float
        The encoder's counts per revolution.

    Raises
    ------
    RecordingError
        The column reads as an angle in radians or degrees.
    """
    e = np.asarray(e, dtype=float)
    if e.size == 0 or np.mean(e != np.round(e)) <= 0.5:
        return
    swing = float(np.ptp(e))
    rad, deg = span * 2 * np.pi / cpr, span * 360.0 / cpr
    if swing > 1.2 * deg:
        return
    unit = "radians" if swing <= 1.2 * rad else "degrees"
    raise RecordingError(f"recording: column 'encoder_{motor}': values not whole numbers swinging {swing:.3g}, where "
                         f"the joints' range spans {span:.6g} counts ({rad:.3g} rad, {deg:.3g} deg of the motor): the "
                         f"motor angle in {unit}? the recording's encoder is in counts ({cpr:g} per turn)")


def check_torque_scale(rec: Any, model: Any, column: str) -> None:
    """Each torque of ``rec`` (a Recording) within :data:`TORQUE_SCALE_LIMIT` times the parameter file's motor limit ``tau_max`` (an
    Alpes model's; none to check on another robot): far beyond it, the column is a current (in A, or in mA), not
    N m. ``column``: ``torque`` or ``current`` (read with a torque constant), the column's name in the message.

    Parameters
    ----------
    rec : Recording
        The recording (its ``torque`` (N, m), N m).
    model : Model
        The model (an Alpes model's ``params.tau_max``, N m).
    column : str
        ``"torque"`` or ``"current"``, named in the message.

    Raises
    ------
    RecordingError
        A torque beyond :data:`TORQUE_SCALE_LIMIT` times ``tau_max``.
    """
    params = getattr(model, "params", None)
    tau_max = getattr(params, "tau_max", None)
    if tau_max is None or rec.torque.size == 0:
        return
    peak = np.max(np.abs(rec.torque), axis=0)
    for mn, v in zip(rec.motor_names, peak):
        if v > TORQUE_SCALE_LIMIT * tau_max:
            guess = "a current in mA" if column == "current" or v > 1000 * tau_max else "a current in A"
            unit = "N m" if column == "torque" else "A (times the torque constant, N m)"
            raise RecordingError(f"recording: column '{column}_{mn}': values up to {float(v):.6g} against tau_max "
                                 f"{tau_max:g} N m: {guess}? the recording's {column} is in {unit}")


def check_units(rec: Any, model: Model, column: str = "torque") -> None:
    """A recording's encoders and torques plausible in their units for ``model``: each encoder within what its
    joints' ranges allow (counts) and the torques within the motors' limits (N m).

    Parameters
    ----------
    rec : Recording
        The recording (its ``encoder`` (N, m) counts and ``torque`` (N, m) N m).
    model : Model
        The model it is read for.
    column : str, optional
        The torque column's name in messages: ``"torque"`` (default) or ``"current"`` (read through a torque
        constant).

    Raises
    ------
    RecordingError
        A column implausible in its unit, naming the column and the likely unit.
    """
    _check_encoder_range(rec, model)
    check_torque_scale(rec, model, column)


def _check_encoder_range(rec: Any, model: Model) -> None:
    """Each encoder column within what its joints' ranges allow (S q over the range box, in counts), with a
    margin of the whole range and one motor turn on each side (an encoder's zero, stops overrun): a reading
    far outside is not this model's encoder in counts, and would send a fit or an observer to overflow."""
    _check_encoder_columns(dict(zip(rec.motor_names, rec.encoder.T)), model)


def _check_encoder_columns(encoders: dict[str, np.ndarray], model: Model) -> None:
    """:func:`_check_encoder_range` of the columns ``encoders`` (motor name of ``model`` -> counts (N,))."""
    tr = model.transmission
    S = np.asarray(tr.S, dtype=float)
    lo_q, hi_q = np.asarray(model.lower, dtype=float), np.asarray(model.upper, dtype=float)
    cpr = float(tr.counts_per_rev)
    for mn, e in encoders.items():
        i = tr.motor_names.index(mn)
        used = S[i] != 0
        if not (np.isfinite(lo_q[used]).all() and np.isfinite(hi_q[used]).all()):
            continue  # an unbounded joint: no range to check against
        a, b = S[i] * lo_q, S[i] * hi_q
        lo = float(np.minimum(a, b).sum()) * cpr / (2 * np.pi)
        hi = float(np.maximum(a, b).sum()) * cpr / (2 * np.pi)
        margin = (hi - lo) + cpr
        check_counts(mn, e, hi - lo, cpr)
        bad = np.flatnonzero((e < lo - margin) | (e > hi + margin))
        if bad.size:
            k = int(bad[0])
            raise RecordingError(f"recording: column 'encoder_{mn}' line {k + 2}: {float(e[k]):g} counts is beyond "
                                 f"what the joint ranges allow ({lo:.6g} to {hi:.6g} counts, give or take the range "
                                 "and a turn); is it this model's encoder, in counts?")
