"""Joint stops: the mechanical end stops of the joints, and the check that a trajectory stays within them.

The report's model (eq. 2.10) has no joint stop, and neither has the library's default simulation:
nothing in eq. 2.10 keeps a joint within its range, so a finger driven hard enough turns past it
(0.02 N m on each hand motor for 1 s turns ``thumb_abd``, which has no spring, by more than 100 rad).
Two tools:

* :class:`JointStops` -- a stop modelled as a stiff unilateral spring-damper (a rubber end stop):
  outside [lower, upper] by a penetration p > 0 the joint feels ``max(0, k p - d v_in)`` back
  toward the range (v_in the velocity further into the stop), nothing inside. Smooth enough for
  RK4 and automatic differentiation. On the Alpes models k = 2 N m/rad (50 times the stiffest finger
  spring: 1.4 degrees of penetration under 0.05 N m) and d = 4e-3 N m s/rad keep the stop's own
  mode (sqrt(k / I) ~ 1300 rad/s on a distal phalanx) stable for RK4 steps up to about 1 ms. On any
  other robot :meth:`JointStops.of` sizes them to the robot (:func:`sized_stops`: the same 1.4 degrees under
  the robot's own static torque into its stops; one k for the robot, or one per joint with ``per_joint=True``),
  or refuses where nothing sizes them; a spec's ``[stops]`` table (:mod:`alpes_dyn.model.spec`) gives them per joint
  or robot-wide instead (:func:`spec_stops`), the joints it leaves out sized.
  Pass it to :func:`~alpes_dyn.simulation.integrate.simulate` as ``stops=``. Rigid stops with an impact law
  (MuJoCo's constraint solver) are what the MJCF export (:mod:`alpes_dyn.model.mjcf`) gives.
* :func:`check_range` -- whether a trajectory leaves the joint range; :func:`simulate` calls it
  when no stop is modelled and warns (:class:`JointRangeWarning`) or raises, per ``joint_range=``.

Why off by default: the report's model has no stop; the observers and the estimation scenario use
eq. 2.10 as it is, and a stiff stop makes the dynamics stiff (smaller RK4 steps).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from ..errors import AlpesDynWarning, InputError

__all__ = ["JointStops", "JointRangeWarning", "check_range", "JOINT_RANGE_MODES", "sized_stops", "STOP_PENETRATION",
           "STOP_DAMPING_RATIO", "ALPES_STOP", "stop_table", "spec_stops"]

JOINT_RANGE_MODES: tuple[str, ...] = ("warn", "error", "ignore")
ALPES_STOP: tuple[float, float] = (2.0, 4e-3)
"""(k N m/rad, d N m s/rad) of the Alpes models' stops (the module doc): :meth:`JointStops.of`'s on a model with an
Alpes parameter file."""
STOP_PENETRATION = math.radians(1.4)
"""p* (rad, 1.4 degrees): how far a sized stop gives under the robot's largest static torque into a stop (the
Alpes stop's 1.4 degrees under 0.05 N m)."""
STOP_DAMPING_RATIO = 1.0
"""zeta of a sized stop's mode on the robot's lightest limited joint: d = 2 zeta sqrt(k I_min) (critical
damping; the Alpes stop's d = 4e-3 N m s/rad is zeta = 1.25 on finger3's distal joint, I = 1.27e-6 kg m^2)."""


class JointRangeWarning(AlpesDynWarning):
    """A simulated joint left its range [lower, upper] while no joint stop was modelled."""


@dataclass(frozen=True)
class JointStops:
    """Unilateral spring-damper end stops (``lower``, ``upper``: arrays (n,), rad): one stiffness k (N m/rad) and
    damping d (N m s/rad) for every joint (numbers), or one per joint (arrays (n,), :meth:`of` with
    ``per_joint=True``)."""

    lower: np.ndarray
    upper: np.ndarray
    stiffness: float | np.ndarray = 2.0
    damping: float | np.ndarray = 4e-3

    @classmethod
    def of(cls, model: Any, stiffness: Any = None, damping: Any = None, per_joint: bool = False) -> "JointStops":
        """Stops at a :class:`~alpes_dyn.Model`'s URDF limits (joints without finite limits get none).

        Parameters
        ----------
        model : alpes_dyn.Model
            The model.
        stiffness : float or array_like of shape (n,) or None, optional
            k, N m/rad: a number (every joint), n numbers (one per joint, in
            :attr:`~alpes_dyn.Model.joint_names` order), or None (default): the spec's ``[stops]`` table where it
            gives them (:func:`spec_stops`; a joint it leaves out sized as below); on an Alpes model (one with an
            Alpes parameter file) the Alpes stop's :data:`ALPES_STOP` (2 N m/rad) unless ``per_joint``; on any
            other robot sized to it by :func:`sized_stops`.
        damping : float or array_like of shape (n,) or None, optional
            d, N m s/rad, given as ``stiffness`` is; None (default): the spec's, else :data:`ALPES_STOP`'s
            (4e-3 N m s/rad) on an Alpes model unless ``per_joint``, else sized to the k (:func:`sized_stops`; a
            damping the spec leaves out sized to its k).
        per_joint : bool, optional
            What is sized, sized per joint (arrays (n,): the same rule on each joint, so a light distal joint gets
            a softer stop than the heavy proximal one); default False, one k and one d for the robot.

        Returns
        -------
        JointStops
            The stops.

        Raises
        ------
        InputError
            A bad value, or stops that cannot be sized (no torque toward any stop).
        """
        if not isinstance(per_joint, (bool, np.bool_)):
            raise InputError(f"per_joint: expected True or False, got {per_joint!r}")
        stiffness = _stop_value(stiffness, "stiffness", "N m/rad", True, model.n)
        damping = _stop_value(damping, "damping", "N m s/rad", False, model.n)
        lo, hi = _limits(model)
        stiffness, damping = _with_spec_stops(model, stiffness, damping, bool(per_joint))
        if stiffness is None or damping is None:
            if getattr(model, "params", None) is not None and not per_joint:
                k, d = ALPES_STOP
            else:
                k, d = sized_stops(model, stiffness, per_joint=bool(per_joint))
            stiffness = k if stiffness is None else stiffness
            damping = d if damping is None else damping
        return cls(lo, hi, _frozen(stiffness), _frozen(damping))

    def torque(self, q: Any, v: Any, xp: Any = np) -> Any:
        """Stop torques (n,), N m: a spring k and a damper d past each stop, pushing back only.

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,)
            Joint angles, rad.
        v : numpy.ndarray or casadi.SX, shape (n,)
            Joint velocities, rad/s.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        lo = np.where(np.isfinite(self.lower), self.lower, -1e30)
        hi = np.where(np.isfinite(self.upper), self.upper, 1e30)
        if xp is not np:
            lo, hi = xp.DM(lo), xp.DM(hi)
        k, d = self.stiffness, self.damping
        if np.ndim(k) and xp is not np:
            k = xp.DM(np.asarray(k, dtype=float))
        if np.ndim(d) and xp is not np:
            d = xp.DM(np.asarray(d, dtype=float))
        p_lo = xp.fmax(lo - q, 0)
        p_hi = xp.fmax(q - hi, 0)
        push_up = xp.fmax(k * p_lo - d * v * (p_lo > 0), 0)    # below the lower stop: pushes toward +q
        push_down = xp.fmax(k * p_hi + d * v * (p_hi > 0), 0)  # above the upper stop: pushes toward -q
        return push_up - push_down


def spec_stops(model: Any) -> tuple[np.ndarray, np.ndarray]:
    """The stop stiffness (n,) N m/rad and damping (n,) N m s/rad the model's spec gives (its ``[stops]`` table,
    :meth:`~alpes_dyn.model.spec.TransmissionSpec.stop_values`), NaN where it gives none (all NaN without a spec or
    table). :class:`~alpes_dyn.InputError` naming the field where it gives a value to a joint without a finite limit
    (no stop to hold it).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model (its spec and joint limits).

    Returns
    -------
    tuple of (numpy.ndarray, numpy.ndarray)
        Stiffness (n,), N m/rad, and damping (n,), N m s/rad.

    Raises
    ------
    InputError
        A value given to a joint without a finite limit, naming the field.
    """
    spec = getattr(model, "spec", None)
    if spec is None or getattr(spec, "stops", None) is None:
        return np.full(model.n, np.nan), np.full(model.n, np.nan)
    k, d = spec.stop_values(model.joint_names)
    lo, hi = _limits(model)
    free = ~(np.isfinite(lo) | np.isfinite(hi))
    for j in spec.stops["joints"]:
        if free[model.joint_names.index(j)]:
            raise InputError(f"stops.joints.{j}: joint {j!r} has no finite limit (URDF limits beyond 1e3 or none): "
                             "no stop to hold it")
    k[free], d[free] = np.nan, np.nan  # a robot-wide value: only on the joints with a stop
    return k, d


def _with_spec_stops(model: Any, stiffness: Any, damping: Any, per_joint: bool) -> tuple[Any, Any]:
    """``stiffness`` and ``damping`` as :meth:`JointStops.of` got them, completed by the spec's ``[stops]`` table
    (unchanged without one): an argument given wins; else on each limited joint the table's value, or where the table
    gives none the value the robot gets without it (:func:`sized_stops`, ``per_joint``), except a damping the table
    leaves out on a joint whose stiffness it gives (or the argument does): d = 2 zeta sqrt(k I), I the robot's
    least effective inertia (per joint: the joint's own), as :func:`sized_stops` sizes d from a given k. A number
    where every limited joint gets the same value, else arrays (n,)."""
    ks, ds = spec_stops(model)
    if not (np.isfinite(ks).any() or np.isfinite(ds).any()) or (stiffness is not None and damping is not None):
        return stiffness, damping
    lo, hi = _limits(model)
    limited = np.isfinite(lo) | np.isfinite(hi)
    k_given = np.isfinite(ks) if stiffness is None else np.ones(model.n, dtype=bool)
    if stiffness is not None:
        ks = np.broadcast_to(np.asarray(stiffness, dtype=float), (model.n,)).copy()
    if damping is not None:
        ds = np.broadcast_to(np.asarray(damping, dtype=float), (model.n,)).copy()
    k, d = ks.copy(), ds.copy()
    unsized = limited & (~np.isfinite(ks) | (~np.isfinite(ds) & ~k_given))
    if unsized.any():  # the joints the table leaves out: what they get without it
        k0, d0 = (np.broadcast_to(x, (model.n,)) for x in sized_stops(model, per_joint=per_joint))
        k = np.where(np.isfinite(k), k, k0)
        d = np.where(np.isfinite(d) | k_given, d, d0)
    if (limited & ~np.isfinite(d)).any():  # d sized to the k given
        inertia = _effective_inertia(model)
        inertia = inertia if per_joint else np.full(model.n, np.min(inertia[limited]))
        d = np.where(np.isfinite(d), d, _stop_damping(k, inertia))
    return _collapsed(k, limited), _collapsed(d, limited)


def _stop_damping(k: Any, inertia: Any) -> Any:
    """d = 2 zeta sqrt(k I) (N m s/rad), zeta = :data:`STOP_DAMPING_RATIO`: the stop's mode of stiffness k (N m/rad)
    on the inertia I (kg m^2) so damped; numbers or arrays alike."""
    return 2.0 * STOP_DAMPING_RATIO * np.sqrt(np.multiply(k, inertia))


def _effective_inertia(model: Any) -> np.ndarray:
    """(n,) kg m^2: each joint's effective inertia 1 / (A^-1)_ii at mid-range (rotors included; the others free)."""
    lo, hi = _limits(model)
    flo, fhi = np.where(np.isfinite(lo), lo, 0.0), np.where(np.isfinite(hi), hi, 0.0)
    return 1.0 / np.diag(np.linalg.inv(model.inertia_matrix(0.5 * (flo + fhi))))


def _collapsed(x: np.ndarray, limited: np.ndarray) -> float | np.ndarray:
    """One number where every limited joint has the same value, else (n,) with the joints without a stop (unused)
    given the least of the others (finite: a stop's torque is k times a zero penetration there)."""
    vals = x[limited]
    if np.all(vals == vals[0]):
        return float(vals[0])
    return np.where(limited, x, np.min(vals))


def _stop_value(x: Any, name: str, unit: str, positive: bool, n: int) -> float | np.ndarray | None:
    """A stop's k or d as given: None, a number, or n numbers (one per joint); :class:`InputError` naming it."""
    if x is None:
        return None
    want = f"a {'positive number' if positive else 'number >= 0'} of {unit} or {n} of them (one per joint)"
    if isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_)):
        a = np.asarray(float(x))
    elif isinstance(x, (list, tuple, np.ndarray)) and not isinstance(x, str):
        try:
            a = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"{name}: expected {want} (or None: sized to the robot), got {x!r}") from None
        if a.shape != (n,) or (isinstance(x, np.ndarray) and x.dtype.kind not in "iuf"):
            raise InputError(f"{name}: expected {want}, got shape {np.shape(x)}")
    else:
        raise InputError(f"{name}: expected {want} (or None: sized to the robot), got {x!r}")
    if not (np.all(np.isfinite(a)) and np.all(a > 0 if positive else a >= 0)):
        got = repr(x) if a.ndim == 0 else repr(a.tolist())
        raise InputError(f"{name}: expected {want} (or None: sized to the robot), got {got}")
    return float(a) if a.ndim == 0 else a


def _frozen(x: float | np.ndarray) -> float | np.ndarray:
    if np.ndim(x) == 0:
        return float(x)
    a = np.array(x, dtype=float)
    a.flags.writeable = False
    return a


def _limits(model: Any) -> tuple[np.ndarray, np.ndarray]:
    """The URDF limits with missing or huge (|x| >= 1e3) ones as -inf / inf: no stop there."""
    lo, hi = model.lower, model.upper
    return (np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.inf),
            np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.inf))


def _torque_into_stops(model: Any, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """(n,) N m: the largest static torque that pushes joint i into one of its stops, gravity and springs G_i(q)
    (eq. 2.11) or gravity alone (the joint's weight on the stop where its spring would help it off: a motor may
    hold the spring's side), the joint at that stop and the others at their lower ends, middles, upper ends or a
    generic angle inside their ranges (0 where nothing pushes; a spring pushes into a stop only where it rests
    beyond it)."""
    flo, fhi = np.where(np.isfinite(lo), lo, 0.0), np.where(np.isfinite(hi), hi, 0.0)
    frac = np.mod(0.5 + 0.6180339887498949 * np.arange(1, model.n + 1), 1.0)
    others = (flo, 0.5 * (flo + fhi), fhi, flo + frac * (fhi - flo))
    out = np.zeros(model.n)
    for i in range(model.n):
        for limit, sign, finite in ((lo[i], 1.0, np.isfinite(lo[i])), (hi[i], -1.0, np.isfinite(hi[i]))):
            if not finite:
                continue
            for base in others:
                q = base.copy()
                q[i] = limit
                G = model.gravity_torque(q)
                g_only = G[i] - model.spring_torque(q)[i]
                out[i] = max(out[i], sign * float(G[i]), sign * float(g_only))  # G > 0 drives q down: the lower stop
    return out


def sized_stops(model: Any, stiffness: Any = None, per_joint: bool = False) -> tuple[Any, Any]:
    """(k N m/rad, d N m s/rad) of stops sized to ``model``'s own gravity torque and inertia: two numbers, or with
    ``per_joint`` two arrays (n,), the same rule on each joint.

    Rule: k = tau* / p*, with tau* the largest static torque (gravity and springs, eq. 2.11, or gravity alone)
    that pushes a joint into one of its stops (the joint at the stop, the others at their lower ends, middles,
    upper ends or a generic angle) and p* = :data:`STOP_PENETRATION` (1.4 degrees): a joint resting on its stop
    under its own weight gives at most 1.4 degrees, whatever the robot weighs. d = 2 zeta sqrt(k I) with zeta =
    :data:`STOP_DAMPING_RATIO` (1) and I an effective inertia 1 / (A^-1)_ii (kg m^2, rotors included, the joint's
    inertia with the others free) at mid-range: the stop's mode critically damped. The mode's rate sqrt(k / I)
    bounds the RK4 step (about 2.8 / rate).

    * One k and d (default): tau* the largest over the robot's limited joints, I = I_min the least over them
      (critical damping on the lightest joint); the proximal joint's weight sizes every stop, so a light distal
      joint resting on its stop gives much less than p* (and its mode is the fastest).
    * ``per_joint``: k_i = tau*_i / p* and d_i = 2 zeta sqrt(k_i I_i) for each joint i: every joint resting on its
      stop under its own weight gives p* (less its spring's share, k_i / (k_i + k_spring,i)). A limited joint that
      nothing pushes into a stop (tau*_i = 0: its weight is across its axis) gets the least k_i of the others; a
      joint without limits gets that k too (it has no stop: unused).

    The Alpes stop that the Alpes models keep (:data:`ALPES_STOP`) is somewhat stiffer and more damped than the
    one sized on finger3. k and d scale with the robot: a finger with masses and inertias c times as large gets k
    and d c times as large.

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.
    stiffness : float or array_like of shape (n,) or None, optional
        k, N m/rad, given (a number, or n with ``per_joint``): only d is sized; default None: k sized too.
    per_joint : bool, optional
        Size each joint by its own torque and inertia (default False: one k and one d for the robot).

    Returns
    -------
    tuple
        (k, d): two floats, or with ``per_joint`` two arrays (n,); N m/rad and N m s/rad.

    Raises
    ------
    InputError
        Nothing sizes k: no torque pushes any joint into a stop (no gravity across the joints and no spring
        resting beyond a limit) or no joint has a finite limit.
    """
    lo, hi = _limits(model)
    limited = np.isfinite(lo) | np.isfinite(hi)
    if not limited.any():
        raise InputError(f"stops: model {model.name!r} has no joint with a finite limit; no stop to size")
    if stiffness is None:
        tau = _torque_into_stops(model, lo, hi)
        if not np.max(tau[limited]) > 0:
            raise InputError(f"stops: nothing pushes model {model.name!r} into its joint stops (no gravity torque, no "
                             "spring resting beyond a limit) to size them by; pass stiffness= (N m/rad) and damping= "
                             "(N m s/rad), or give them in the --spec file's [stops] table")
        pushed = limited & (tau > 1e-9 * np.max(tau[limited]))  # not a rounding error's torque across a vertical axis
        stiffness = (np.where(pushed, tau, np.min(tau[pushed])) if per_joint else float(np.max(tau[limited])))
        stiffness = stiffness / STOP_PENETRATION
    inertia = _effective_inertia(model)
    if per_joint or np.ndim(stiffness):
        k = np.broadcast_to(np.asarray(stiffness, dtype=float), (model.n,)).copy()
        return k, _stop_damping(k, inertia)
    I_min = float(np.min(inertia[limited]))
    return float(stiffness), float(_stop_damping(stiffness, I_min))


def stop_table(model: Any, per_joint: bool = False) -> dict[str, Any]:
    """What :meth:`JointStops.of` (``model``, ``per_joint``) gives each joint, and where it comes from: what
    ``alpes-dyn dynamics`` prints.

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.
    per_joint : bool, optional
        As :meth:`JointStops.of`'s (default False).

    Returns
    -------
    dict
        Lists in :attr:`~alpes_dyn.Model.joint_names` order: ``stiffness`` (N m/rad) and ``damping``
        (N m s/rad), None on a joint without a finite limit (no stop); ``source`` per joint: ``"spec"`` (the spec's
        ``[stops]`` table gives both; ``"spec k, sized d"`` or ``"sized k, spec d"`` where it gives one),
        ``"alpes"`` (the Alpes models' :data:`ALPES_STOP`), ``"sized"`` (:func:`sized_stops`: the robot's largest
        static torque into a stop over :data:`STOP_PENETRATION`, critical damping on its lightest limited joint; per
        joint: that joint's own), ``"least of the others"`` (per joint, a limited joint that nothing pushes into a
        stop), ``"none"`` (no finite limit); and ``torque_into_stop`` (N m, the sizing's tau*_i),
        ``penetration_rad`` (p*). Where nothing sizes the stops (:func:`sized_stops` refuses) every stiffness and
        damping is None, the sources ``"not sized"`` and ``error`` the reason; otherwise ``error`` is None.

    Raises
    ------
    InputError
        ``model`` not a model, or ``per_joint`` not a bool.
    """
    if not all(hasattr(model, a) for a in ("joint_names", "lower", "upper", "gravity_torque", "inertia_matrix")):
        raise InputError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
    if not isinstance(per_joint, (bool, np.bool_)):
        raise InputError(f"per_joint: expected True or False, got {per_joint!r}")
    lo, hi = _limits(model)
    limited = np.isfinite(lo) | np.isfinite(hi)
    tau = _torque_into_stops(model, lo, hi)
    out: dict[str, Any] = {"joints": list(model.joint_names), "per_joint": bool(per_joint),
                           "torque_into_stop": [float(t) if lim else None for t, lim in zip(tau, limited)],
                           "penetration_rad": STOP_PENETRATION, "error": None}
    try:
        stops = JointStops.of(model, per_joint=bool(per_joint))
    except InputError as exc:
        out.update(stiffness=[None] * model.n, damping=[None] * model.n, error=str(exc),
                   source=["not sized" if lim else "none" for lim in limited])
        return out
    k = np.broadcast_to(np.asarray(stops.stiffness, dtype=float), (model.n,))
    d = np.broadcast_to(np.asarray(stops.damping, dtype=float), (model.n,))
    alpes = getattr(model, "params", None) is not None and not per_joint
    pushed = tau > 1e-9 * np.max(np.where(limited, tau, 0.0), initial=0.0)
    source = ["none" if not lim else "alpes" if alpes else "sized" if not per_joint or push else "least of the others"
              for lim, push in zip(limited, pushed)]
    ks, ds = spec_stops(model)
    for i in np.flatnonzero(limited & (np.isfinite(ks) | np.isfinite(ds))):
        source[i] = ("spec" if np.isfinite(ks[i]) and np.isfinite(ds[i]) else
                     "spec k, sized d" if np.isfinite(ks[i]) else "sized k, spec d")
    out.update(stiffness=[float(x) if lim else None for x, lim in zip(k, limited)],
               damping=[float(x) if lim else None for x, lim in zip(d, limited)], source=source)
    return out


def check_range(t: np.ndarray, q: np.ndarray, lower: np.ndarray, upper: np.ndarray, names: Sequence[str],
                mode: str = "warn", tol: float = 1e-9, rest: np.ndarray | None = None) -> str:
    """Whether the trajectory q (N+1, n) at times t leaves [lower - tol, upper + tol].

    Parameters
    ----------
    t : numpy.ndarray, shape (N+1,)
        The times, s.
    q : numpy.ndarray, shape (N+1, n)
        The joint angles, rad.
    lower : numpy.ndarray, shape (n,)
        The joints' lower limits, rad.
    upper : numpy.ndarray, shape (n,)
        The joints' upper limits, rad.
    names : sequence of str
        The joints' names.
    mode : str, optional
        One of :data:`JOINT_RANGE_MODES`: ``"warn"`` (default) also issues a :class:`JointRangeWarning`,
        ``"error"`` raises :class:`~alpes_dyn.InputError`, ``"ignore"`` only returns the message.
    tol : float, optional
        The tolerance beyond the limits, rad (default 1e-9).
    rest : numpy.ndarray, shape (n,), or None, optional
        The springs' rest angles, rad, NaN on a joint without spring: every spring that rests outside its joint's
        range is named too, with the spec field that moves it (``[rest_angle]``); default None.

    Returns
    -------
    str
        "" if q stays within, else a one-line message naming the first joint to leave, when and how far.

    Raises
    ------
    InputError
        An unknown mode, or ``mode="error"`` and q leaves the range.
    """
    if mode not in JOINT_RANGE_MODES:
        raise InputError(f"joint_range: expected one of {', '.join(JOINT_RANGE_MODES)}, got {mode!r}")
    out = (q < lower - tol) | (q > upper + tol)
    if not out.any():
        return ""
    k, j = np.argwhere(out)[0]
    worst = np.max(np.maximum(lower - q, q - upper), axis=0)
    jw = int(np.argmax(worst))
    msg = (f"joint {names[j]!r} left its range [{lower[j]:g}, {upper[j]:g}] rad at t = {t[k]:g} s (q = {q[k, j]:.4g} "
           f"rad) and no joint stop is modelled (worst: {names[jw]!r} {worst[jw]:.3g} rad outside; pass "
           "stops=JointStops.of(model) to simulate them)")
    if rest is not None:
        r = np.asarray(rest, dtype=float)
        bad = [i for i in range(len(names)) if np.isfinite(r[i]) and not lower[i] <= r[i] <= upper[i]]
        if bad:
            msg += ("; " + ", ".join(f"the spring of {names[i]!r} rests at {r[i]:g} rad, outside [{lower[i]:g}, "
                                     f"{upper[i]:g}]" for i in bad)
                    + ": set its rest angle inside the range in the spec's [rest_angle] table")
    if mode == "error":
        raise InputError(msg)
    if mode == "warn":
        warnings.warn(msg, JointRangeWarning, stacklevel=3)
    return msg


def divergence_message(t: np.ndarray, q: np.ndarray, k: int, lower: np.ndarray, upper: np.ndarray,
                       names: Sequence[str], curved: bool) -> str:
    """The one line of a simulation whose state is first not finite at sample ``k``: where a ratio curve's model
    (``curved``) saw a joint leave its range before, that joint (the curve's polynomial holds only within the
    range, and outside it can grow without bound), else the step and the inputs.

    Parameters
    ----------
    t : ndarray
        (N+1,) the times, s.
    q : ndarray
        (N+1, n) the joint angles, rad (finite before ``k``).
    k : int
        The first sample with a non-finite state.
    lower, upper : ndarray
        (n,) the joints' limits, rad.
    names : sequence of str
        The joints' names.
    curved : bool
        The model's transmission has a ratio curve.

    Returns
    -------
    str
        The message.
    """
    head = f"simulation diverged (non-finite state at t = {t[k]:g} s)"
    left = check_range(t[:k], q[:k], lower, upper, names, "ignore") if curved and k > 0 else ""
    if left:
        return (f"{head} after {left.split(' and no joint stop')[0]}, where its ratio_curve no longer holds (keep the "
                "joints in range: stops=JointStops.of(model), or smaller inputs)")
    return f"{head}; reduce dt or the inputs"
