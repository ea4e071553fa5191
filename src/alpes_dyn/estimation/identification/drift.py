"""A slow drift of the encoder offsets fitted with the parameters (issue 39: ``identify(drift="offset")``,
``alpes-dyn identify --drift offset``).

Over minutes an encoder's zero can creep (a warming motor, a slipping coupling); a constant offset
(``encoder_offset``) does not follow it, and the fit trades the springs and masses for it. With the drift on, each
encoder's reading is y_k = S q_k + offset + d(tau_k): d piecewise linear in the recorded time tau, zero at the first
sample (the constant part is ``encoder_offset``'s, fitted or not), its values at knots every :data:`DRIFT_KNOT`
seconds (a record shorter than that: a ramp, the value at its end) the fit's unknowns, in counts. It enters the
output only, linearly (like the offset): it adds columns to the residuals' Jacobian and none to the continuity's.
The recorded time tau runs on through the runs of a recording of several (each run's own duration, the time
between runs not counted: a run's own clock may restart). Without the drift, the verdict's regressors hold a ramp
of the encoder (``"drift"``, :data:`~alpes_dyn.estimation.identification.adequacy.SIGNATURES`): a residual that
trends with time names it.
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from ..experiments.recording import Recording

__all__ = ["DRIFT_KNOT", "DRIFTS", "recorded_time", "drift_basis", "check_drift"]

DRIFT_KNOT = 15.0
"""s: the spacing of the drift's knots (four a minute): a record of T seconds has ceil(T / 15) segments."""
DRIFTS = ("offset",)
"""What ``drift`` may name: the encoder offsets (the torque constant's drift is not modelled)."""


def check_drift(drift: str | None) -> str | None:
    """``drift`` (None or one of :data:`DRIFTS`), or :class:`~alpes_dyn.InputError` naming it."""
    if drift is not None and (not isinstance(drift, str) or drift not in DRIFTS):
        raise InputError(f"drift: expected None or one of {', '.join(DRIFTS)}, got {drift!r:.60}")
    return drift


def recorded_time(rec: Recording) -> np.ndarray:
    """(N+1,) s the time recorded up to each sample: t - t_0 within a run, each run after the earlier runs'
    durations (their sample period apart)."""
    b = rec.run_starts()
    tau = np.empty(rec.n_samples)
    base = 0.0
    for a, z in zip(b[:-1], b[1:]):  # a loop over the runs (a few)
        tau[a:z] = base + rec.t[a:z] - rec.t[a]
        base = tau[z - 1] + rec.dt
    return tau


def drift_basis(rec: Recording, knot: float = DRIFT_KNOT) -> np.ndarray:
    """(N+1, K) the hat functions of the knots 1..K (every ``knot`` seconds of :func:`recorded_time`, the last at
    its end; knot 0 at the first sample left out: d(0) = 0) at each sample: d(tau) = H @ d_knots."""
    tau = recorded_time(rec)
    K = max(1, math.ceil(tau[-1] / knot - 1e-9))
    x = tau / tau[-1] * K  # knot coordinates 0..K
    H = np.maximum(0.0, 1.0 - np.abs(x[:, None] - np.arange(1, K + 1)[None, :]))
    return H
