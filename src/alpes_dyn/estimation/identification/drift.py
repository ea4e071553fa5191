"""Slow drifts fitted with the parameters (issue 39: ``identify(drift="offset")``, ``"gain"`` or ``"offset,gain"``;
``alpes-dyn identify --drift offset,gain``).

Over minutes an encoder's zero can creep (a warming motor, a slipping coupling) and a motor's torque constant can
change (its magnets warming: a few per cent per 10 K); a constant offset (``encoder_offset``) or gain (``input_gain``)
does not follow it, and the fit trades the springs and masses for it. Each drift is piecewise linear in the recorded
time tau, with knots every :data:`DRIFT_KNOT` seconds (a record shorter than that: a ramp), its values at the knots
the fit's unknowns:

* ``offset``: each encoder's reading y_k = S q_k + offset + d(tau_k), d zero at the first sample (the constant part
  is ``encoder_offset``'s, fitted or not), in counts. It enters the output only, linearly: it adds columns to the
  residuals' Jacobian and none to the continuity's.
* ``gain``: each motor's torque is g(tau) times the recorded one (the torque constant's scale relative to the one
  the recording was converted with), g = 1 at the first sample: a **relative** drift. The absolute scale is not
  observable from the encoder (theta -> c theta with the torque times c leaves the motion unchanged:
  :func:`~alpes_dyn.symbolic.parametric.common_scale`), so the drift is anchored at 1 at the start and the
  parameters carry the torque constant of the first sample. g multiplies the torque, sample by sample, in the
  dynamics and in the tendon's stretch (the small fitted correction on the lines by its value at the interval's
  middle). It needs the excitation's lines (``excitation``): its sensitivity is that of the torque along itself,
  which the compiled sensitivities give through the lines' coefficients (the projected torque lies on them), with
  the knots' hat functions taken at each shooting interval's middle sample (over 50 ms a 15 s knot's hat changes
  by 1/300: the Jacobian's only approximation; the residuals are exact).

The recorded time tau runs on through the runs of a recording of several (each run's own duration, the time
between runs not counted: a run's own clock may restart). Without the offset's drift, the verdict's regressors hold
a ramp of the encoder (``"drift"``, :data:`~alpes_dyn.estimation.identification.adequacy.SIGNATURES`): a residual
that trends with time names it.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from ..experiments.recording import Recording

__all__ = ["DRIFT_KNOT", "DRIFTS", "recorded_time", "drift_basis", "check_drift", "line_coefficients", "gain_sensitivity"]

DRIFT_KNOT = 15.0
"""s: the spacing of the drift's knots (four a minute): a record of T seconds has ceil(T / 15) segments."""
DRIFTS = ("offset", "gain")
"""What ``drift`` may name: the encoder offsets, the torque constants (module docstring)."""


GAIN_NEEDS_LINES = ("drift: 'gain' needs the excitation's lines (excitation=..., the command line's default --excitation "
                    "documented) and a torque noise above 0: the torque constant's drift is fitted through the lines' "
                    "coefficients")
"""The error where ``drift`` names the gain and the fit takes the torque as it is."""


def check_drift(drift: str | tuple[str, ...] | list[str] | None) -> tuple[str, ...]:
    """The drifts ``drift`` names, in :data:`DRIFTS`' order.

    Parameters
    ----------
    drift : str, tuple[str, ...], list[str] or None
        None or an empty list: none; a comma-separated string or a list of :data:`DRIFTS`.

    Returns
    -------
    tuple[str, ...]
        The drifts named.

    Raises
    ------
    InputError
        Naming ``drift``: an unknown, repeated or empty choice.
    """
    if drift is None or (isinstance(drift, (list, tuple)) and not drift):
        return ()
    if isinstance(drift, str):
        items = [s.strip() for s in drift.split(",")]
    elif isinstance(drift, (list, tuple)) and all(isinstance(s, str) for s in drift):
        items = list(drift)
    else:
        raise InputError(f"drift: expected None or a comma-separated choice of {', '.join(DRIFTS)}, got {drift!r:.60}")
    bad = [s for s in items if s not in DRIFTS]
    if bad or not items:
        raise InputError(f"drift: expected None or a comma-separated choice of {', '.join(DRIFTS)}, got {drift!r:.60}")
    if len(set(items)) != len(items):
        raise InputError(f"drift: {drift!r:.60} names a drift twice")
    return tuple(d for d in DRIFTS if d in items)


def recorded_time(rec: Recording) -> np.ndarray:
    """(N+1,) s the time recorded up to each sample: t - t_0 within a run, each run after the earlier runs'
    durations (their sample period apart).

    Parameters
    ----------
    rec : Recording
        The recording (one run or several).

    Returns
    -------
    numpy.ndarray, shape (N+1,)
        The recorded time at each sample, s.
    """
    b = rec.run_starts()
    tau = np.empty(rec.n_samples)
    base = 0.0
    for a, z in zip(b[:-1], b[1:]):  # a loop over the runs (a few)
        tau[a:z] = base + rec.t[a:z] - rec.t[a]
        base = tau[z - 1] + rec.dt
    return tau


def drift_basis(rec: Recording, knot: float = DRIFT_KNOT) -> np.ndarray:
    """(N+1, K) the hat functions of the knots 1..K (every ``knot`` seconds of :func:`recorded_time`, the last at
    its end; knot 0 at the first sample left out: d(0) = 0) at each sample: d(tau) = H @ d_knots.

    Parameters
    ----------
    rec : Recording
        The recording.
    knot : float, optional
        The knots' spacing, s of recorded time (default :data:`DRIFT_KNOT`).

    Returns
    -------
    numpy.ndarray, shape (N+1, K)
        H, the hat functions at each sample.
    """
    tau = recorded_time(rec)
    K = max(1, math.ceil(tau[-1] / knot - 1e-9))
    x = tau / tau[-1] * K  # knot coordinates 0..K
    H = np.maximum(0.0, 1.0 - np.abs(x[:, None] - np.arange(1, K + 1)[None, :]))
    return H


def line_coefficients(QS: np.ndarray, U: np.ndarray, starts: np.ndarray, blk: np.ndarray | None,
                      n_int: int) -> np.ndarray:
    """(S, nu, nphi) each interval's run's torque ``U`` (N, nu) on its lines' basis ``QS`` (N, nphi; a run's rows its
    own block, :mod:`~alpes_dyn.estimation.identification.torque_lines`): U = QS A_r' on run r's rows, by least squares
    (exact where U is the projection on the lines, as
    :func:`~alpes_dyn.estimation.identification.torque_lines.torque_model` makes it). ``starts``: the runs' first rows
    (R,), in order; ``blk`` (S,) each of the ``n_int`` intervals' run (None: one run).

    Parameters
    ----------
    QS : numpy.ndarray, shape (N, nphi)
        The lines' basis at each row.
    U : numpy.ndarray, shape (N, nu)
        The torque, N m.
    starts : numpy.ndarray, shape (R,)
        The runs' first rows, in order.
    blk : numpy.ndarray, shape (S,), or None
        Each interval's run (None: one run).
    n_int : int
        S, the number of intervals.

    Returns
    -------
    numpy.ndarray, shape (S, nu, nphi)
        Each interval's run's coefficients A_r.
    """
    edges = np.append(np.asarray(starts, dtype=int), U.shape[0])
    out = []
    for a, b in zip(edges[:-1], edges[1:]):  # a loop over the runs (a few): normal equations, nphi x nphi each
        Q = QS[a:b]
        out.append(np.linalg.lstsq(Q.T @ Q, Q.T @ U[a:b], rcond=None)[0].T)
    A = np.stack(out)
    return A[blk] if blk is not None else np.broadcast_to(A[0], (n_int,) + A.shape[1:])


def gain_sensitivity(X_io: np.ndarray, W: np.ndarray, Hs: np.ndarray, nu: int) -> np.ndarray:
    """(s, L+1, nx, nu K) the states' sensitivities to the gain drift's knots (module docstring) of ``s`` intervals,
    from their sensitivities to the torque's line coefficients ``X_io`` (s, L+1, nx, nphi nu; coefficient (motor i,
    line l) at l nu + i), the coefficients of the torque each interval is under, ungained, ``W`` (s, nu, nphi)
    (its run's :func:`line_coefficients` plus the fitted correction), and the hat functions at the intervals'
    middles ``Hs`` (s, K): the torque's direction is W's on the lines, so d x / d g_i = sum_l X_io[l, i] W[i, l], times
    each knot's hat; motor i's knots at columns i K .. (i + 1) K - 1.

    Parameters
    ----------
    X_io : numpy.ndarray, shape (s, L+1, nx, nphi nu)
        The states' sensitivities to the torque's line coefficients (coefficient (motor i, line l) at l nu + i).
    W : numpy.ndarray, shape (s, nu, nphi)
        The coefficients of the torque each interval is under, ungained.
    Hs : numpy.ndarray, shape (s, K)
        The hat functions at the intervals' middles (:func:`drift_basis`).
    nu : int
        The number of motors.

    Returns
    -------
    numpy.ndarray, shape (s, L+1, nx, nu K)
        The states' sensitivities to the knots of the gain drift.
    """
    s, L1, nx, no = X_io.shape
    dg = np.einsum("sknli,sil->skni", X_io.reshape(s, L1, nx, no // nu, nu), W)  # (s, L+1, nx, nu)
    return (dg[..., :, None] * Hs[:, None, None, None, :]).reshape(s, L1, nx, nu * Hs.shape[1])
