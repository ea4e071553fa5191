"""The hand's grasp of the cylinder: the default references and gains of its force loops and the cylinder's normal at
a chain's fingertip (:data:`HAND_LEVELS`, :data:`HAND_GAINS`, :func:`hand_gains`, :func:`cylinder_normal`,
:func:`cylinder_in_chain`),
shared by the whole hand's step (:class:`~alpes_dyn.control.hand_step.HandForceStep`) and the simulated grasp
(:func:`~alpes_dyn.control.hand_loop.run_hand_control`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..errors import InputError
from ..model.hand_chains import chain_frame
from ..model.mjcf import CYLINDER
from ..model.params import HandParams
from ..model.robot import Model
from .controller import DEFAULT_GAINS, _normal

__all__ = ["HAND_LEVELS", "HAND_GAINS", "HAND_CONTROLLER_GAINS", "HAND_CHAIN_GAINS", "hand_gains", "cylinder_normal",
           "cylinder_in_chain"]

#: Default references of :func:`~alpes_dyn.control.hand_loop.run_hand_control` per chain, N: (before, after) the
#: step at ``step_time``. Within what each fingertip holds on the :data:`~alpes_dyn.model.mjcf.CYLINDER` before
#: its pad slides around it (:func:`~alpes_dyn.control.grasp_calibration.grasp_limits`: the thumb holds more than
#: the fingers).
HAND_LEVELS: dict[str, tuple[float, float]] = {
    "index": (0.25, 0.4), "middle": (0.2, 0.35), "ring": (0.3, 0.4), "little": (0.25, 0.35), "thumb": (0.4, 0.7),
}
#: :class:`.ForceController` settings of the hand's loops over :data:`.DEFAULT_GAINS` (then the scenario's
#: ``gains``): a slower approach (15 mN m/s; faster, the fingertips reach the cylinder sooner and bounce on it)
#: and, for the model-based loops, a 40 ms prefilter, the shortest of {25, 30, 40, 50} ms with the fingers'
#: overshoots near 10 % on :data:`HAND_LEVELS` (with the block's shorter prefilter a pad slips on the curved
#: surface at the up-step and its force falls to 0). The release (the prefilter while a reference falls) as the
#: rise. The hand's loops with these settings: ``benchmarks/results/hand_control.json``.
HAND_GAINS: dict[str, float] = {"approach_rate": 0.015, "prefilter_s": 0.04, "release_s": 0.04}
#: One controller's settings of the hand's loops over :data:`HAND_GAINS`: the sensor loop's integral as tuned on the
#: cylinder (ki 1.6 N m/(N s)); the block's faster integral (:data:`.DEFAULT_GAINS`, set for the rise on the block)
#: let a finger's pad slide off the cylinder at the end of its approach, its force falling to 0.
HAND_CONTROLLER_GAINS: dict[str, dict[str, float]] = {"sensor": {"ki": 1.6}}
#: One chain's settings over :data:`HAND_CONTROLLER_GAINS`, per controller: the thumb's sensor loop with the block's
#: 25 ms prefilter. Its pad, opposite the fingers, holds more (:data:`HAND_LEVELS`) and did not slide with it; with
#: the fingers' 40 ms (88 ms of rise alone) its 10-90 % rise was 91-100 ms on the +-20 % draws of the hand, with 25 ms
#: 53-62 ms, its overshoot and RMSE within 0.6 and 0.2 points of the step of what they were (the block's ki 2.4 on
#: top raised its RMSE to 3 % of the step on a draw). The hand's loops with these settings:
#: ``benchmarks/results/hand_control.json``.
HAND_CHAIN_GAINS: dict[str, dict[str, dict[str, float]]] = {"thumb": {"sensor": {"prefilter_s": 0.025}}}


def hand_gains(controller: str, gains: dict | None = None, chain: str | None = None) -> dict[str, float]:
    """The :class:`.ForceController` settings of a hand's chain: :data:`.DEFAULT_GAINS` of ``controller``, overridden
    by :data:`HAND_GAINS`, by :data:`HAND_CONTROLLER_GAINS` of ``controller``, by :data:`HAND_CHAIN_GAINS` of
    ``chain`` and ``controller``, then by ``gains``.

    Parameters
    ----------
    controller : str
        The controller's kind, a key of :data:`.DEFAULT_GAINS`.
    gains : dict or None, optional
        The caller's overrides (any :class:`.ForceController` field).
    chain : str or None, optional
        The chain (:func:`~alpes_dyn.model.hand_chains.hand_chains`); None: a finger's settings.

    Returns
    -------
    dict of str to float
        The settings.
    """
    return {**DEFAULT_GAINS[controller], **HAND_GAINS, **HAND_CONTROLLER_GAINS.get(controller, {}),
            **HAND_CHAIN_GAINS.get(chain or "", {}).get(controller, {}), **(gains or {})}


def cylinder_normal(model: Model, q: np.ndarray, center: Sequence[float], axis: Sequence[float] = (0.0, 1.0, 0.0),
                    tip: str | None = None) -> np.ndarray:
    """Unit normal n (3,) of a cylinder's surface at the fingertip, the model's base frame: from the tip frame
    (the centre of the fingertip's rounded end) toward the cylinder's axis, the direction the fingertip
    presses in.

    Parameters
    ----------
    model : Model
        The chain's model.
    q : ndarray
        (n,) joint angles, rad.
    center, axis : sequence of float
        A point of the cylinder's axis, m, and its direction (base frame).
    tip : str or None, optional
        The fingertip's frame (default: the model's first tip)."""
    a = _normal(axis)
    d = np.asarray(center, dtype=float) - model.fingertip_position(q, tip)
    d = d - a * (d @ a)
    nd = float(np.linalg.norm(d))
    if not nd > 0:
        raise InputError("q: the fingertip is on the cylinder's axis; the normal is undefined")
    return d / nd


def cylinder_in_chain(params: HandParams, chain: str, abduction: float) -> tuple[np.ndarray, np.ndarray]:
    """(a point of the cylinder's axis (3,) m, its direction (3,)) of :data:`~alpes_dyn.model.mjcf.CYLINDER` in a
    chain's base frame (:func:`~alpes_dyn.model.hand_chains.chain_frame`; the thumb at ``abduction`` rad).

    Parameters
    ----------
    params : HandParams
        The hand's parameters (palm down).
    chain : str
        A chain of :func:`~alpes_dyn.model.hand_chains.hand_chains`.
    abduction : float
        The thumb's ab/adduction angle, rad.

    Returns
    -------
    tuple of numpy.ndarray
        The point and the direction.
    """
    R, pos = chain_frame(params, chain, abduction)
    return R.T @ (np.asarray(CYLINDER["center"], dtype=float) - pos), R.T @ np.array([0.0, 1.0, 0.0])
