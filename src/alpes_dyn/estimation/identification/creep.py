"""A dry friction the smooth law reads as viscous: the cause a fit's verdict names where a joint's F_s collapses.

The fit's friction is F_s tanh(qd / v_s) + F_v qd with the file's v_s (0.1 rad/s; eq. 2.6-2.7). A dry friction
that creeps before it slides -- MuJoCo's default ``frictionloss`` constraint (``solreffriction`` 0.02 s, impedance
0.9) is one -- holds a force that grows with the velocity up to F_s over a band that depends on the joint's inertia:
on a drawn finger3, the heaviest joint's friction reaches F_s by 0.02 rad/s, the lightest's only by 0.3-1 rad/s
(MuJoCo's constraint force on each joint against its velocity, the study's soft case), through most of the motion.
The fit then moves that joint's friction into F_v and drives its F_s towards 0 (log F_s falling without end: the
Gauss-Newton steps of a "lost basin"), and the residual left follows the plant's lag behind the model (a torque
delay's signature, where no delay is). Neither is the cause: the friction law is.

The law (:func:`soft_constraint_friction`, MuJoCo's own constraint force to machine precision): each joint's
friction row is a Huber cost, its force -clip((qdd_j + b qd_j) / R_j, -F_s, F_s) with b = 2 / (d_max t_c) (105 /s
at the default ``solreffriction`` t_c = 0.02 s, ``solimpfriction`` d_max = 0.95) and R_j = (1 - d) / d w_j (d = 0.9,
w_j MuJoCo's ``dof_invweight0``, the joint's inverse inertia at the reference pose). Inside its band the joint
carries an added inertia 1 / R_j (9 / w_j: comparable to the joint's own) and a viscous friction b / R_j (many
times F_v): no memoryless sign (the smooth law at any v_s, one per joint, fits MuJoCo's force only loosely) and no
bristle law (LuGre's and Dahl's presliding is a spring, this has none) holds it, and a fit with either reads the
added inertia into the masses (far off in the study's soft cases). Holding
the friction at the file's values keeps the fit in its basin but does not make the law right (the masses stay
tens of per cent off): such a fit is refused, its verdict naming :data:`CREEP`. The law with the band's added
inertia is the file's ``creep`` law (:class:`~alpes_dyn.model.friction.Creep`, solved with the dynamics by
:mod:`~alpes_dyn.symbolic.creep`): ``--effects creep``, and the ``creep`` round of ``--effects auto`` where a fit
collapsed an F_s (:mod:`~alpes_dyn.estimation.identification.rounds`).

:func:`collapsed` finds the joints whose F_s ended below :data:`CREEP_FRACTION` of its start (the file's value);
:func:`name_creep` puts :data:`CREEP` first among a fit's likely missing effects where it is not to be trusted
and returns the note that says which F_s went where (:func:`~alpes_dyn.estimation.identification.effects.fit_effects`
adds it to its notes).
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from ...errors import InputError

__all__ = ["CREEP_FRACTION", "CREEP", "RAN_DOWN", "collapsed", "ran_down", "name_creep", "soft_constraint_friction"]

CREEP_FRACTION = 0.1
"""A fitted F_s below this fraction of its start has collapsed (the +-20 % draws of a dry friction the law fits
end within 0.5-2 times their start; a soft MuJoCo friction's lightest joint at 0.01)."""

CREEP = ("a dry friction that creeps before it slides (F_s driven towards 0: its force grows with the velocity "
         "over a wider band than the smooth law's v_s, read as viscous; the creep law: --effects creep)")
"""The likely missing effect :func:`name_creep` names."""

RAN_DOWN = "ran it off towards 0"
"""The words of a ``not_identified`` clause of a parameter held at the file's value after the fit's steps drove it
below its start until the basin was lost (:func:`~alpes_dyn.estimation.identification.runaway.friction_held`): the
collapse the hold hides from :func:`collapsed` (:func:`ran_down` reads it)."""


def collapsed(names: tuple[str, ...] | list[str], values: Any, start: Mapping[str, float]) -> dict[str, tuple[float, float]]:
    """The F_s parameters that collapsed: name -> (start, value) where value < :data:`CREEP_FRACTION` start.

    Parameters
    ----------
    names : sequence of str
        The fit's parameter names (``F_s_<joint>`` are looked at).
    values : (p,) array
        Their fitted values, N m.
    start : mapping
        Each parameter's start (the parameter file's value), N m; a name missing or with a start <= 0 is skipped.

    Returns
    -------
    dict
        In the fit's order; empty where none collapsed.
    """
    out = {}
    for n, v in zip(names, values):
        s = float(start.get(n, 0.0))
        if n.startswith("F_s_") and s > 0 and float(v) < CREEP_FRACTION * s:
            out[n] = (s, float(v))
    return out


def ran_down(result: Any) -> dict[str, str]:
    """The F_s parameters a fit holds at the file's value because its steps drove them towards 0 until the basin
    was lost (their ``not_identified`` clause holds :data:`RAN_DOWN`): an F_s collapsing, which the hold hides from
    :func:`collapsed` (on a soft MuJoCo friction the fit lost its basin on F_s_2, then on F_s_3, and was kept with
    both held at the file's).

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        A fit (anything with a ``not_identified`` mapping: parameter name -> clause; none: nothing held).

    Returns
    -------
    dict of str to str
        Name -> its clause, in the mapping's order; empty where no F_s ran down.
    """
    held = getattr(result, "not_identified", None) or {}
    return {n: str(why) for n, why in held.items() if n.startswith("F_s_") and RAN_DOWN in str(why)}


def name_creep(result: Any, start: Mapping[str, float]) -> str | None:
    """Where ``result`` is not to be trusted (not converged, or its verdict not adequate) and a joint's F_s
    collapsed (:func:`collapsed`) or was held after running towards 0 (:func:`ran_down`): :data:`CREEP` first among its verdict's likely missing effects (where it has a
    verdict) and the note returned; None (nothing changed) otherwise.

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit kept.
    start : mapping
        Each parameter's start, the parameter file's value (the first round's ``initial``).

    Returns
    -------
    str or None
        One line: which F_s went from what to what, and the cause.
    """
    if result.trustworthy:
        return None
    gone, down = collapsed(result.names, result.values, start), ran_down(result)
    if not (gone or down):
        return None
    a = getattr(result, "adequacy", None)
    if a is not None:
        if a.adequate:
            a.adequate, a.reasons = False, [f"{', '.join([*gone, *down])} collapsed below {CREEP_FRACTION:g} of the "
                                            "file's or held after running towards 0"]
        a.likely_missing = [CREEP] + [m for m in a.likely_missing if m != CREEP]
    where = [f"{n} {s:.2g} -> {v:.2g} N m" for n, (s, v) in gone.items()]
    where += [f"{n} held at the file's value, the fit's steps having run it towards 0" for n in down]
    return f"dry friction read as viscous ({', '.join(where)}): {CREEP}"


def soft_constraint_friction(qdd: Any, qd: Any, F_s: Any, invweight: Any, timeconst: float = 0.02,
                             impedance: float = 0.9, d_max: float = 0.95) -> np.ndarray:
    """MuJoCo's soft dry friction (a ``frictionloss`` row with ``solreffriction`` (t_c, 1), ``solimpfriction``
    (d, d_max, ...)): -clip((qdd + b qd) / R, -F_s, F_s), b = 2 / (d_max t_c), R = (1 - d) / d ``invweight``
    (module docstring).

    Parameters
    ----------
    qdd : (..., n) array
        The joints' accelerations, rad/s^2 (MuJoCo's ``qacc``: the law is implicit in them).
    qd : (..., n) array
        The joints' velocities, rad/s.
    F_s : (n,) array
        The joints' dry friction (``frictionloss``), N m, >= 0.
    invweight : (n,) array
        MuJoCo's ``dof_invweight0``: each joint's inverse inertia at the reference pose, 1 / (kg m^2), > 0.
    timeconst : float, optional
        s, > 0: the constraint's time constant (MuJoCo's default 0.02).
    impedance : float, optional
        d in (0, 1): the impedance at zero violation (a friction row's; MuJoCo's default 0.9).
    d_max : float, optional
        The impedance's upper value in (0, 1] (MuJoCo's default 0.95), in b.

    Returns
    -------
    (..., n) ndarray
        The friction torque on each joint, N m (MuJoCo's ``efc_force`` of the row).

    Raises
    ------
    InputError
        A constant out of its range, a negative F_s or an invweight <= 0.
    """
    F_s, w = np.asarray(F_s, dtype=float), np.asarray(invweight, dtype=float)
    for name, ok in (("timeconst", timeconst > 0), ("impedance", 0 < impedance < 1), ("d_max", 0 < d_max <= 1),
                     ("F_s", np.all(F_s >= 0)), ("invweight", np.all(w > 0))):
        if not ok:
            raise InputError(f"{name}: out of its range (module alpes_dyn.estimation.identification.creep)")
    R = (1.0 - impedance) / impedance * w
    b = 2.0 / (d_max * timeconst)
    return -np.clip((np.asarray(qdd, dtype=float) + b * np.asarray(qd, dtype=float)) / R, -F_s, F_s)
