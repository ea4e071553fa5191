"""Play a torque profile through any hand on the bench and keep what its sensors read."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from .interface import HardwareInterface, check_command

__all__ = ["play"]


def play(hw: HardwareInterface, commands: Any) -> dict[str, np.ndarray]:
    """Write ``commands`` through ``hw`` tick by tick and return its readings.

    Parameters
    ----------
    hw : HardwareInterface
        The hand (e.g. :class:`~alpes_dyn.bench.mujoco_hand.MujocoHand`), at its current tick.
    commands : array_like
        (N, m) motor torques, N m, in [0, ``hw.tau_max``], row k held over the k-th period (one motor: (N,) too);
        all checked before the first is written.

    Returns
    -------
    dict
        ``t`` (N+1,) s, ``counts`` (N+1, m), ``torque`` (N+1, m) N m, ``force`` (N+1,) N: the readings before the
        first command and after each.

    Raises
    ------
    InputError
        ``commands`` of the wrong shape, not finite or out of [0, tau_max] (one line naming it).
    """
    m = len(hw.motor_names)
    u = np.asarray(commands, dtype=float)
    u = u[:, None] if u.ndim == 1 and m == 1 else u
    if u.ndim != 2 or u.shape[1] != m or u.shape[0] < 1:
        raise InputError(f"commands: expected (N, {m}) motor torques in N m, N >= 1, got shape {u.shape}")
    try:
        check_command(u.ravel(), u.size, hw.tau_max)
    except InputError as exc:
        raise InputError("commands" + str(exc).removeprefix("command")) from None
    readings = [hw.read()]
    for row in u:  # the hand's own clock: one write and one read per period
        hw.write(row)
        readings.append(hw.read())
    return {"t": np.array([r.t for r in readings]), "counts": np.array([r.counts for r in readings]),
            "torque": np.array([r.torque for r in readings]), "force": np.array([r.force for r in readings])}
