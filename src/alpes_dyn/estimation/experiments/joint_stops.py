"""The joints' own stops as a bound on the encoder, for the guard of the experiment on the hand
(:func:`joint_band`).

The guard of :class:`~alpes_dyn.estimation.experiments.hand_session.HandSession` watches the encoder: the one
thing measured. The joints are not, and a finger whose spring is soft at one joint can bring that joint onto its stop
while the motor's reading is still well inside the range that the calibration found (the encoder goes on rising as
the other joints bend). :func:`joint_band` turns the joints' stops into encoder counts through the model: along a
slow sweep of the motor torque from 0 to the driver's limit, the static equilibrium of the finger (springs and
gravity against the tendon, eq. 2.11 at rest; a joint that reaches a stop held there while the others go on), the
encoder reading and the joint angles of each equilibrium; the sweep ends where no equilibrium is found near the
last one (past a fold: the finger snaps, which the calibration finds and the encoder's band already ends before). The counts below which some joint lies within ``margin``
of its lower stop, and above which some joint lies within ``margin`` of its upper stop, bound the excitation.

The uncertainty: the joints' angles at a reading depend on the springs and masses, which the experiment is run to
find. The bound is taken over the nominal finger and :data:`FAMILY_DRAWS` draws of the tolerance family about it
(:func:`~alpes_dyn.estimation.experiments.draws.perturbed_params`, springs and masses each within
+-:data:`FAMILY_SPREAD`): the lowest upper bound and the highest lower bound of them all, so that the joints of any
finger of the family stay ``margin`` inside their stops while the encoder stays inside the band (quasi-statically:
the multisine's lowest lines are well below the finger's first mode; the guard's own margin covers the rest).
"""

from __future__ import annotations

import math

import numpy as np

from ...errors import InputError
from ...model.robot import Model
from .draws import perturbed_params
from .trim import _oriented, _reading

__all__ = ["FAMILY_DRAWS", "FAMILY_SPREAD", "SWEEP_POINTS", "joint_band"]

FAMILY_DRAWS = 8
"""The draws of the tolerance family, besides the nominal finger, that :func:`joint_band` bounds over."""
FAMILY_SPREAD = 0.2
"""The family's relative half-width on the springs and masses (the parameter file's tolerance)."""
SWEEP_POINTS = 121
"""The motor torques of the sweep, from 0 to the driver's limit."""


def _sweep(model: Model, gravity: np.ndarray, tau_max: float, lo: np.ndarray, hi: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray]:
    """(counts (K,), q (K, n) rad): the static equilibria of ``model`` under the torques of the sweep, a joint past
    its stop (``lo``, ``hi``, rad) held at it (the stops' active set grown until no joint is past one)."""
    m = _oriented(model, gravity)
    names = list(m.joint_names)
    held = set(m.springless_joints)
    q = np.zeros(m.n)
    for j in held:
        q[names.index(j)] = 0.5 * (lo[names.index(j)] + hi[names.index(j)])
    counts, angles = [], []
    scale = m.transmission.counts_per_rev / (2 * np.pi)
    for tau in np.linspace(0.0, tau_max, SWEEP_POINTS):
        try:
            q = _stopped_equilibrium(m, q, tau, lo, hi, held)
        except InputError:  # no equilibrium near the last one: past a fold, where the calibration's band ends
            break
        counts.append(float(np.atleast_1d(_reading(m, q))[0]) * scale)
        angles.append(q.copy())
    return np.array(counts), np.array(angles).reshape(-1, m.n)


def _stopped_equilibrium(m: Model, q: np.ndarray, tau: float, lo: np.ndarray, hi: np.ndarray, held: set[str]
                         ) -> np.ndarray:
    """The static equilibrium under the motor torque ``tau`` from ``q``, the joints past a stop held at it."""
    names = list(m.joint_names)
    at_stop: set[int] = set()
    for _ in range(m.n + 1):  # each pass holds at least one more joint at its stop, or ends
        fixed = held | {names[i] for i in at_stop}
        if len(fixed) == m.n:
            return q  # every joint held: nothing left to move
        q = m.static_equilibrium(None, q, fixed=sorted(fixed), tau_m=np.array([tau]))
        past = {i for i in range(m.n) if names[i] not in held and not lo[i] <= q[i] <= hi[i]} - at_stop
        if not past:
            return q
        at_stop |= past
        q = np.clip(q, lo, hi)
    return q


def _family(nominal: Model) -> list[Model]:
    """The nominal finger and :data:`FAMILY_DRAWS` draws of its tolerance family (none without a parameter set)."""
    if nominal.params is None:
        return [nominal]
    chain = getattr(nominal, "chain", None)
    out = [nominal]
    for k in range(FAMILY_DRAWS):
        draw = perturbed_params(nominal.params, FAMILY_SPREAD, k, kinds=("K", "m"))
        out.append(Model.alpes(nominal.name, params=draw, **({"chain": chain} if chain else {})))
    return out


def joint_band(nominal: Model, gravity: np.ndarray, margin: float, tau_max: float
               ) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The encoder counts between which every joint of every finger of the family stays ``margin`` inside its stops
    (the module docstring).

    Parameters
    ----------
    nominal : Model
        The finger (one motor; its joint stops ``lower``, ``upper``, rad: every member's), with its parameter set
        for the family.
    gravity : numpy.ndarray
        (3,) the gravity the hand is in, m/s^2.
    margin : float
        rad, inside each stop.
    tau_max : float
        The driver's limit, N m: the sweep's end.

    Returns
    -------
    low, high : numpy.ndarray
        (1,) counts (-inf / +inf where no joint's stop bounds that side).
    joints : list of str
        The joints whose stops set ``low`` and ``high`` (the first of the two empty where that side is unbounded).

    Raises
    ------
    InputError
        A model with more than one motor, or a margin or limit that is not a positive number.
    """
    if not isinstance(nominal, Model) or nominal.transmission is None or nominal.transmission.n_motors != 1:
        raise InputError("nominal: the joints' stops are bounded for a finger of one motor")
    for name, v in (("margin", margin), ("tau_max", tau_max)):
        if isinstance(v, bool) or not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive number, got {v!r}")
    low, high, who = -np.inf, np.inf, ["", ""]
    g = np.asarray(gravity, dtype=float)
    lo, hi = np.asarray(nominal.lower, dtype=float), np.asarray(nominal.upper, dtype=float)  # the hand's, not drawn
    for model in _family(nominal):
        c, q = _sweep(model, g, float(tau_max), lo, hi)
        free = [i for i, n in enumerate(model.joint_names) if n not in set(model.springless_joints)]
        near_lo = (q[:, free] <= lo[free] + margin)
        near_hi = (q[:, free] >= hi[free] - margin)
        if near_lo.any():
            k = int(np.argmax(np.where(near_lo.any(axis=1), c, -np.inf)))
            if c[k] > low:
                low, who[0] = c[k], model.joint_names[free[int(np.argmax(near_lo[k]))]]
        if near_hi.any():
            k = int(np.argmin(np.where(near_hi.any(axis=1), c, np.inf)))
            if c[k] < high:
                high, who[1] = c[k], model.joint_names[free[int(np.argmax(near_hi[k]))]]
    return np.array([low]), np.array([high]), who
