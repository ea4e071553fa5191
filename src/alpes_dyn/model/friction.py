"""Dry friction with a state: the LuGre law per joint, next to the smooth tanh law of eq. 2.6-2.7.

The smooth law F_s tanh(v / v_s) + F_v v (:meth:`~alpes_dyn.model.extras.JointExtras.friction_torque`) has no
memory: under a net torque below F_s it needs a velocity v_s atanh(tau / F_s), so a modelled joint creeps where the
real one stays, and a Gaussian filter built on it drifts through stick-slip. The LuGre law (Canudas de Wit, Olsson,
Astrom and Lischinsky, IEEE TAC 40(3), 1995) gives each joint a bristle deflection z (rad), a state:

    z' = v - sigma0 |v| z / g(v),                                   (L1)
    tau_f = sigma0 z + sigma1 z' + F_v v,                           (L2)

here with g(v) = F_s (the Coulomb and static levels equal, F_c = F_s: the parameter file's F_s, no Stribeck
curve, so the law adds two numbers to the file, not four). A stuck joint is a bristle deflected by |z| < F_s /
sigma0 whose spring sigma0 z holds any net torque up to F_s; sliding at a steady v, z = F_s sign(v) / sigma0 and
tau_f = F_s sign(v) + F_v v, the sign law (eq. 2.6). The law is smooth in (z, v) (its |v| aside, Lipschitz), so an
extended Kalman filter can carry z in its state and represent a stuck joint.

Why LuGre and not the others (Dahl, generalised Maxwell-slip, a switched stick/slip law): Dahl is L1 without the
damping sigma1 and without the static peak (here g is flat, so LuGre is Dahl plus sigma1 z', the damping of the
presliding oscillation a stiff sigma0 otherwise leaves); Maxwell-slip needs several elements per joint (several
states and parameters each) for a hysteresis an encoder behind a tendon cannot resolve; the switched law is not
differentiable, which the library's observers have as :mod:`~alpes_dyn.simulation.stick` already (time stepping).
MuJoCo 4's ``dcmotor`` actuator models LuGre friction on a motor, an independent plant for this law.

The parameter file chooses the law (``friction.law = "tanh"`` (default) or ``"lugre"``) with ``friction.sigma0``
(N m/rad) and ``friction.sigma1`` (N m s/rad), one value for every joint (:func:`lugre_of`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..checks import one_of
from ..errors import ModelError

__all__ = ["FRICTION_MODELS", "OBSERVER_LAWS", "check_observer_law",
           "LuGre", "PRESLIDING", "SIGMA0", "SIGMA1", "lugre_rate", "lugre_torque",
           "lugre_steady", "lugre_of", "check_law", "Creep", "CREEP_KAPPA", "CREEP_RATE", "creep_of",
           "creep_of_constraint"]

FRICTION_MODELS: tuple[str, ...] = ("tanh", "lugre", "creep")
"""The parameter file's ``friction.law``: ``tanh`` the memoryless smooth law, ``lugre`` the law of this module,
``creep`` the soft dry friction of :class:`Creep`."""

OBSERVER_LAWS: tuple[str, ...] = ("smooth", "stick", "lugre")
"""The observers' dry-friction laws (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`), which the parameter file's
optional ``friction.observer_law`` names: the law its observer runs (``identify`` writes the one its observer
check chose, :mod:`~alpes_dyn.estimation.identification.law_choice`)."""

PRESLIDING = 1e-3
"""rad: the default presliding displacement F_s / sigma0 of a joint, the angle a stuck joint yields elastically
before it slides (a ball bearing or a plain pulley bush: micrometres at its radius of a few millimetres)."""

SIGMA0 = 0.5
"""N m/rad: the default bristle stiffness sigma0, F_s / :data:`PRESLIDING` at the Alpes file's F_s = 0.5 mN m: ten
times the joints' return springs, a presliding mode of about 50 Hz on finger3's lightest phalanx (4.8e-6 kg m^2),
slow enough for the observers' RK4 at 4 steps per millisecond, fast enough that a stuck joint moves 0.06 degree."""

SIGMA1 = 3e-3
"""N m s/rad: the default bristle damping sigma1, about critical on that presliding mode, 2 sqrt(sigma0 I) with
I = 4.8e-6 kg m^2 (finger3's third phalanx with its share of the rotor)."""


def check_law(law: Any, field: str = "friction.law") -> str:
    """``law`` if it is one of :data:`FRICTION_MODELS`, else :class:`~alpes_dyn.ModelError` naming ``field``.

    Parameters
    ----------
    law : Any
        The friction law read (``"tanh"``, ``"lugre"`` or ``"creep"``).
    field : str, optional
        The field the error names (default ``"friction.law"``).

    Returns
    -------
    str
        ``law``.

    Raises
    ------
    ModelError
        ``law`` not a string of :data:`FRICTION_MODELS`.
    """
    return one_of(law, FRICTION_MODELS, field, ModelError)


def check_observer_law(law: Any, field: str = "friction.observer_law") -> str:
    """``law`` if it is one of :data:`OBSERVER_LAWS`, else :class:`~alpes_dyn.ModelError` naming ``field``.

    Parameters
    ----------
    law : Any
        The observer's law read (``"smooth"``, ``"stick"`` or ``"lugre"``).
    field : str, optional
        The field the error names (default ``"friction.observer_law"``).

    Returns
    -------
    str
        ``law``.

    Raises
    ------
    ModelError
        ``law`` not a string of :data:`OBSERVER_LAWS`.
    """
    return one_of(law, OBSERVER_LAWS, field, ModelError)


def _positive(x: Any, field: str, unit: str) -> float:
    try:
        v = float(x) if not isinstance(x, (bool, np.bool_, str)) else float("nan")
    except (TypeError, ValueError):
        v = float("nan")
    if not (math.isfinite(v) and v > 0):
        raise ModelError(f"{field}: expected a finite number > 0 {unit}, got {x!r:.40}")
    return v


@dataclass(frozen=True)
class LuGre:
    """The LuGre law's two numbers, the same on every joint (module docstring, eq. L1-L2).

    Parameters
    ----------
    sigma0 : float
        Bristle stiffness, N m/rad (> 0): the presliding stiffness d tau_f / dq of a stuck joint.
    sigma1 : float
        Bristle damping, N m s/rad (> 0).

    Raises
    ------
    ModelError
        A value not finite or not > 0 (``friction.sigma0`` / ``friction.sigma1`` named).
    """

    sigma0: float = SIGMA0
    sigma1: float = SIGMA1

    def __post_init__(self) -> None:
        object.__setattr__(self, "sigma0", _positive(self.sigma0, "friction.sigma0", "N m/rad"))
        object.__setattr__(self, "sigma1", _positive(self.sigma1, "friction.sigma1", "N m s/rad"))


def lugre_rate(z: Any, v: Any, coulomb: np.ndarray, sigma0: Any, xp: Any = np) -> Any:
    """z' of eq. L1 with g = F_s, (n,) rad/s; a joint with F_s = 0 has no bristle (z' = 0).

    Parameters
    ----------
    z, v : array_like or casadi column
        (n,) bristle deflection (rad) and joint velocity (rad/s).
    coulomb : numpy.ndarray
        (n,) F_s, N m (>= 0).
    sigma0 : float or casadi scalar
        N m/rad.
    xp : module
        ``numpy`` or ``casadi``.
    """
    Fs = np.asarray(coulomb, dtype=float)
    dry = Fs > 0
    inv = np.where(dry, 1.0 / np.where(dry, Fs, 1.0), 0.0)
    if xp is np:
        return np.where(dry, v - sigma0 * np.abs(v) * z * inv, 0.0)
    mask, inv = xp.DM(dry.astype(float)), xp.DM(inv)
    return mask * (v - sigma0 * xp.fabs(v) * z * inv)


def lugre_torque(z: Any, zdot: Any, v: Any, viscous: np.ndarray, law: LuGre, xp: Any = np) -> Any:
    """tau_f of eq. L2, (n,) N m: sigma0 z + sigma1 z' + F_v v.

    Parameters
    ----------
    z : array_like or casadi column
        (n,) bristle deflection, rad.
    zdot : array_like or casadi column
        (n,) its rate z' (eq. L1, :func:`lugre_rate`), rad/s.
    v : array_like or casadi column
        (n,) joint velocity, rad/s.
    viscous : numpy.ndarray
        (n,) F_v, N m s/rad.
    law : LuGre
        sigma0 (N m/rad) and sigma1 (N m s/rad).
    xp : module, optional
        ``numpy`` (default) or ``casadi``.

    Returns
    -------
    numpy.ndarray or casadi column
        (n,) friction torque, N m.
    """
    Fv = np.asarray(viscous, dtype=float)
    return law.sigma0 * z + law.sigma1 * zdot + (Fv * v if xp is np else xp.DM(Fv) * v)


def lugre_steady(v: Any, coulomb: np.ndarray, viscous: np.ndarray, sigma0: float) -> tuple[np.ndarray, np.ndarray]:
    """The law in steady sliding (z' = 0) at velocity ``v``: the sign law of eq. 2.6.

    Parameters
    ----------
    v : array_like
        (n,) joint velocity, rad/s, != 0.
    coulomb : numpy.ndarray
        (n,) F_s, N m.
    viscous : numpy.ndarray
        (n,) F_v, N m s/rad.
    sigma0 : float
        Bristle stiffness, N m/rad.

    Returns
    -------
    z : numpy.ndarray
        (n,) F_s sign(v) / sigma0, rad.
    tau_f : numpy.ndarray
        (n,) F_s sign(v) + F_v v, N m.
    """
    v = np.asarray(v, dtype=float)
    Fs, Fv = np.asarray(coulomb, dtype=float), np.asarray(viscous, dtype=float)
    return Fs * np.sign(v) / sigma0, Fs * np.sign(v) + Fv * v


def lugre_of(model: Any) -> LuGre | None:
    """The LuGre law of ``model``'s parameter file (``friction.law = "lugre"``: its ``sigma0``/``sigma1``, else the
    defaults :data:`SIGMA0`, :data:`SIGMA1`), or None (the file's law is ``tanh``, or the model has no file).

    Parameters
    ----------
    model : Model
        The model (its ``params``; anything without them: None).

    Returns
    -------
    LuGre or None
    """
    p = getattr(model, "params", None)
    if p is None or getattr(p, "friction_law", "tanh") != "lugre":
        return None
    return LuGre(p.sigma0, p.sigma1)


CREEP_KAPPA = 9.0
"""-: the default band inertia of the ``creep`` law, d / (1 - d) at MuJoCo's default friction impedance d = 0.9
(``solimpfriction``): the band's added inertia in units of the joint's own, 1 / (M(0)^-1)_jj."""

CREEP_RATE = 2.0 / (0.95 * 0.02)
"""1/s: the default band rate b of the ``creep`` law, 2 / (d_max t_c) at MuJoCo's default ``solreffriction``
t_c = 0.02 s (damping ratio 1) and d_max = 0.95."""


@dataclass(frozen=True)
class Creep:
    """A dry friction that creeps before it slides (``friction.law = "creep"``): MuJoCo's soft ``frictionloss``.

    Measured on drawn finger3s (``benchmarks/soft_friction_law.py``): under a constant torque tau below F_s a
    joint creeps at the steady velocity tau / (a_j b) (to 4 digits), and slides above; the friction is the clipped
    row of :func:`~alpes_dyn.estimation.identification.creep.soft_constraint_friction`,

        tau_f,j = clip(a_j (qdd_j + b qd_j), -F_s,j, F_s,j) + F_v,j qd_j,                 (C1)

    with the band's added inertia a_j = kappa / (M(0)^-1)_jj (kg m^2, the joint's own inertia at the reference pose
    times kappa) and its rate b (1/s): a viscous friction a_j b up to the band's edge v_c = F_s / (a_j b) plus an
    inertia a_j, saturating at F_s. The friction depends on the acceleration, so neither a memoryless sign (any v_s)
    nor a bristle (a spring) holds it; the dynamics solve it (:meth:`~alpes_dyn.symbolic.parametric.
    ParametricDynamics.dynamics_terms`).

    Parameters
    ----------
    kappa : float
        The band's added inertia in units of the joint's own, > 0 (:data:`CREEP_KAPPA`).
    rate : float
        The band's rate b, 1/s, > 0 (:data:`CREEP_RATE`).

    Raises
    ------
    ModelError
        A value not finite or not > 0 (``friction.creep_kappa`` / ``friction.creep_rate`` named).
    """

    kappa: float = CREEP_KAPPA
    rate: float = CREEP_RATE

    def __post_init__(self) -> None:
        object.__setattr__(self, "kappa", _positive(self.kappa, "friction.creep_kappa", "(-)"))
        object.__setattr__(self, "rate", _positive(self.rate, "friction.creep_rate", "1/s"))

    def band(self, Minv0: Any, F_s: Any) -> tuple[np.ndarray, np.ndarray]:
        """The band's added inertia a_j = kappa / (M(0)^-1)_jj and its edge v_c,j = F_s,j / (a_j b) (eq. C1).

        Parameters
        ----------
        Minv0 : array_like
            (n, n) the inverse inertia matrix at the reference pose q = 0, 1/(kg m^2).
        F_s : array_like
            (n,) the joints' dry friction, N m.

        Returns
        -------
        tuple of numpy.ndarray
            (a (n,) kg m^2, v_c (n,) rad/s).
        """
        a = self.kappa / np.diag(np.asarray(Minv0, dtype=float))
        return a, np.asarray(F_s, dtype=float) / (a * self.rate)


def creep_of(model: Any) -> Creep | None:
    """The :class:`Creep` law of ``model``'s parameter file (``friction.law = "creep"``: its ``creep_kappa`` /
    ``creep_rate``, else the defaults), or None (another law, or no file).

    Parameters
    ----------
    model : Model
        The model (its ``params``; anything without them: None).

    Returns
    -------
    Creep or None
    """
    p = getattr(model, "params", None)
    if p is None or getattr(p, "friction_law", "tanh") != "creep":
        return None
    return Creep(p.creep_kappa, p.creep_rate)


def creep_of_constraint(timeconst: float = 0.02, impedance: float = 0.9, d_max: float = 0.95) -> Creep:
    """The :class:`Creep` law of a MuJoCo dry-friction constraint: kappa = d / (1 - d) and b = 2 / (d_max t_c),
    the inverse of the MJCF writers' map (:func:`~alpes_dyn.model.mjcf_export.creep_attributes`, which writes
    d_max = d); the defaults are MuJoCo's own (``solreffriction`` "0.02 1", ``solimpfriction`` "0.9 0.95 ...":
    :data:`CREEP_KAPPA`, :data:`CREEP_RATE`).

    Parameters
    ----------
    timeconst : float, optional
        The constraint's time constant t_c, s, > 0 (``solreffriction``'s first number, damping ratio 1).
    impedance : float, optional
        Its impedance d at zero velocity, in (0, 1) (``solimpfriction``'s first number, d0).
    d_max : float, optional
        Its largest impedance, in (0, 1) (``solimpfriction``'s second number; MuJoCo scales the rate by it).

    Returns
    -------
    Creep
        The law (kappa -, rate 1/s).

    Raises
    ------
    ModelError
        ``timeconst`` not finite and > 0 (``solreffriction`` named), or ``impedance`` / ``d_max`` not in (0, 1)
        (``solimpfriction`` named).
    """
    t = _positive(timeconst, "solreffriction", "s")
    d, dm = (_positive(x, "solimpfriction", "(-)") for x in (impedance, d_max))
    if d >= 1.0 or dm >= 1.0:
        raise ModelError(f"solimpfriction: expected impedances in (0, 1), got {impedance!r:.40} and {d_max!r:.40}")
    return Creep(d / (1.0 - d), 2.0 / (dm * t))
