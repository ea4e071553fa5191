"""The hand's chains as one-motor models: :func:`hand_chains`, :func:`chain_frame`, :func:`chain_model`.

The hand's force loops (:mod:`alpes_dyn.control.hand_loop`, :mod:`alpes_dyn.control.hand_step`) and its MuJoCo
stand-in's cylinder scene (:mod:`alpes_dyn.bench.mujoco_hand`) treat each flexion chain -- the four fingers and the
thumb's flexion, one motor each -- as a finger of its own, in its own base frame.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from ..errors import InputError
from .params import HandParams
from .robot import Model

__all__ = ["hand_chains", "chain_frame", "chain_model"]


def _rotation(axis: Sequence[float], angle: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def hand_chains(params: HandParams) -> tuple[str, ...]:
    """The hand's flexion chains, one motor each: the fingers of the parameter file, then ``"thumb"``.

    Parameters
    ----------
    params : HandParams
        The hand's parameters.
    """
    return (*params.finger_names, "thumb")


def chain_frame(params: HandParams, chain: str, abduction: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), p (3,)): orientation and position (m) of a chain's base frame -- its first flexion joint's
    frame at q = 0, the frame of a standalone finger model -- in the palm frame, the thumb at the
    ab/adduction angle ``abduction`` (rad). A finger's frame is the palm's, translated; the thumb's is
    turned by ``palm.thumb_yaw`` about z, then by ``abduction`` about ``thumb.abduction_axis``.

    Parameters
    ----------
    params : HandParams
        The hand's parameters.
    chain : str
        A chain of :func:`hand_chains`.
    abduction : float, optional
        The thumb's ab/adduction angle, rad."""
    if chain in params.finger_names:
        x, y = params.finger_xy[list(params.finger_names).index(chain)]
        return np.eye(3), np.array([x, y, 0.0])
    if chain == "thumb":
        R = _rotation((0.0, 0.0, 1.0), params.thumb_yaw) @ _rotation(params.abduction_axis, float(abduction))
        return R, np.asarray(params.thumb_xyz, dtype=float).copy()
    raise InputError(f"chain: unknown chain {chain!r} (expected one of {', '.join(hand_chains(params))})")


def chain_model(params: HandParams, chain: str, abduction: float = 0.0, friction: bool = False) -> Model:
    """The controller's model of one chain of the hand: ``finger3`` for a finger; for the thumb's flexion
    chain (the ab/adduction held at ``abduction``, rad) a two-phalanx finger with the ``[thumb]`` table's
    values. Gravity is the parameter file's, expressed in the chain's base frame (R^T g,
    :func:`chain_frame`), so that the chain's G(q), J(q) and encoder are the hand's on its joints.

    Parameters
    ----------
    params : HandParams
        The hand's parameters.
    chain : str
        A chain of :func:`hand_chains`.
    abduction : float, optional
        The thumb's ab/adduction angle, rad.
    friction : bool, optional
        With the file's joint friction (eq. 2.6-2.7): the force step's EKF model."""
    R, _ = chain_frame(params, chain, abduction)
    g = R.T @ np.asarray(params.gravity, dtype=float)
    if chain == "thumb":
        return Model.alpes("finger2", friction=friction,
                           params=dataclasses.replace(params, finger=params.thumb, gravity=g))
    # a finger's own values
    return Model.alpes("finger3", friction=friction, params=dataclasses.replace(params, gravity=g), chain=chain)
