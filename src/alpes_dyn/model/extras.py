"""Joint-space terms the URDF cannot hold: springs, friction and rotor inertia.

They are written once here and applied identically by the numeric (Pinocchio) and symbolic
(CasADi) backends: every method takes the math namespace ``xp`` (``numpy`` or ``casadi``).

* springs (eq. 2.14): tau_s = k (q - q_rest) with a per-joint stiffness k (N m/rad) and rest angle q_rest
  (rad, default 0: the report's springs rest at q = 0; a spec's ``[rest_angle]`` table), written once in
  :func:`spring_law` and used by the numeric, symbolic and parametric models, the spring energy and the MJCF
  export (MuJoCo's ``springref``). k depends on the spring model:

  - ``"torsional"`` (default): U = 1/2 K_i q_i^2, so k_i = K_i. Table 1.2 gives K_i in N m/rad,
    a torsional stiffness.
  - ``"report"``: eq. 2.14 read literally, U = 1/2 K_i (q_i (b/2 + r))^2, so k_i = K_i (b/2 + r)^2.
    With K_i in N m/rad this makes the springs about 10^4 times weaker than gravity
    ((b/2 + r)^2 = 3.0e-5 m^2): the report's units are inconsistent, kept for comparison.
  - ``"none"``: no spring.

* friction (eq. 2.6-2.7): tau_f = F_s sign(v) + F_v v, with ``sign`` optionally replaced by
  ``tanh(v / v_s)`` (``smooth=True``) for integration and automatic differentiation.
* joint-side inertia (``armature``, kg m^2): added to the diagonal of A (Pinocchio's ``armature``; eq. 2.8's
  N^2 J_m for a motor that drives that joint alone). A motor's rotor on a tendon shared by several joints
  is not diagonal: it is the transmission's S^T diag(J_m) S (:attr:`Model.rotor_matrix
  <alpes_dyn.Model.rotor_matrix>`, :class:`~alpes_dyn.model.spec.Motor`'s ``rotor_inertia``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ModelError

__all__ = ["SPRING_MODELS", "JointExtras", "spring_stiffness", "spring_law", "STICTION_VELOCITY"]

SPRING_MODELS: tuple[str, ...] = ("torsional", "report", "none")
STICTION_VELOCITY = 0.02
"""v_s (rad/s) of the smooth sign tanh(qd / v_s) as a stick-slip law: under a torque below F_s a joint creeps at
v_s atanh(tau / F_s) instead of sticking. Against MuJoCo's stick-slip finger (``frictionloss``), finger3 with
its true values replayed open loop on the identification experiment follows the plant several times closer at a
small v_s than at the file's 0.1 rad/s, and a fit on that plant lands its masses close at 0.02, far off at 0.1; a
smaller v_s costs more RK4 steps. It needs RK4 steps of about 1/15 ms on finger3
(:func:`~alpes_dyn.simulation.integrate.stable_substeps`)."""


def spring_stiffness(K: np.ndarray, spring: str, b: float, r: float) -> np.ndarray:
    """Joint stiffness k (N m/rad) of springs with constants K under a spring model (eq. 2.14).

    Parameters
    ----------
    K : numpy.ndarray, shape (n,)
        The springs' constants K_i (Table 1.2, N m/rad).
    spring : str
        The spring model, one of :data:`SPRING_MODELS` (module doc): ``"torsional"`` k = K, ``"report"``
        k = K (b/2 + r)^2, ``"none"`` k = 0.
    b : float
        The spring's thickness b, m (eq. 2.14; used by ``"report"`` only).
    r : float
        The phalanges' pulley radius r, m (used by ``"report"`` only).

    Returns
    -------
    numpy.ndarray, shape (n,)
        k, N m/rad (a new array).

    Raises
    ------
    ModelError
        An unknown spring model.
    """
    if spring == "torsional":
        return np.asarray(K, dtype=float).copy()
    if spring == "report":
        return np.asarray(K, dtype=float) * (b / 2 + r) ** 2
    if spring == "none":
        return np.zeros_like(np.asarray(K, dtype=float))
    raise ModelError(f"unknown spring model {spring!r} (expected one of {', '.join(SPRING_MODELS)})")


def _as(xp: Any, a: np.ndarray) -> Any:
    return a if xp is np else xp.DM(a)


def spring_law(k: Any, rest: np.ndarray | None, q: Any, xp: Any = np) -> Any:
    """The spring torque k (q - q_rest) (N m): the one place it is written.

    Parameters
    ----------
    k : numpy.ndarray or casadi.SX or casadi.MX, shape (n,)
        Stiffness, N m/rad: a numpy array, or a CasADi column such as the parametric model's fitted K.
    rest : numpy.ndarray, shape (n,), or None
        Rest angles q_rest, rad; None (or all zero): then k q, bit for bit what the springs gave before rest angles
        existed.
    q : numpy.ndarray or casadi.SX or casadi.MX, shape (n,)
        Joint angles, rad: an array or a CasADi column.
    xp : module, optional
        The math namespace, ``numpy`` (default) or ``casadi`` (module doc).

    Returns
    -------
    numpy.ndarray or casadi expression, shape (n,)
        The spring torque, N m.
    """
    k = _as(xp, k) if isinstance(k, np.ndarray) else k
    if rest is None or not np.any(np.asarray(rest) != 0):
        return k * q
    return k * (q - _as(xp, np.asarray(rest, dtype=float)))


@dataclass(frozen=True)
class JointExtras:
    """Per-joint extras, in the model's joint (velocity) order; all arrays have shape (n,).

    stiffness: k (N m/rad); armature: joint-side inertia on A's diagonal (kg m^2); coulomb: F_s (N m); viscous: F_v (N m s/rad);
    smooth_velocity: v_s (rad/s) of the smooth sign tanh(v/v_s); rest: q_rest (rad), the angle at which each
    spring exerts no torque (default None: zeros).

    Validated on construction (:class:`~alpes_dyn.ModelError` naming the field): the four arrays
    are 1-D of one length, finite and >= 0, and are stored as read-only float arrays; v_s > 0; ``rest``
    of the same length, finite, of either sign.
    """

    stiffness: np.ndarray
    armature: np.ndarray
    coulomb: np.ndarray
    viscous: np.ndarray
    smooth_velocity: float = 0.01
    rest: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Every array 1-D, of one length, finite and >= 0 (a negative stiffness, friction or rotor
        inertia would inject energy); ``smooth_velocity`` finite and > 0. Arrays are stored as float."""
        n = None
        for fname in ("stiffness", "armature", "coulomb", "viscous"):
            x = getattr(self, fname)
            try:
                a = np.array(x, dtype=float) if np.asarray(x).dtype.kind != "c" else None
            except (TypeError, ValueError):
                a = None
            if a is None or a.ndim != 1:
                got = f"shape {a.shape}" if a is not None else f"{type(x).__name__} {np.asarray(x).dtype}"
                raise ModelError(f"extras.{fname}: expected a 1-D array of numbers, got {got}")
            if n is not None and a.shape != (n,):
                raise ModelError(f"extras.{fname}: expected shape ({n},) like extras.stiffness, got {a.shape}")
            n = a.shape[0]
            if not np.isfinite(a).all():
                raise ModelError(f"extras.{fname}: contains NaN or inf")
            if np.any(a < 0):
                i = int(np.argmax(a < 0))
                raise ModelError(f"extras.{fname}: must be >= 0 (got {a[i]:g} at index {i})")
            a.flags.writeable = False
            object.__setattr__(self, fname, a)
        try:
            vs = float(self.smooth_velocity)
        except (TypeError, ValueError):
            vs = float("nan")
        if not (np.isfinite(vs) and vs > 0):
            raise ModelError(f"extras.smooth_velocity: expected a finite number > 0 rad/s, got {self.smooth_velocity!r}")
        object.__setattr__(self, "smooth_velocity", vs)
        object.__setattr__(self, "rest", self._rest_array(n))
        object.__setattr__(self, "_rest_used", self.rest if np.any(self.rest != 0) else None)  # None: k q, fast

    def _rest_array(self, n: int | None) -> np.ndarray:
        """``rest`` as a read-only (n,) float array (zeros for None), finite, any sign."""
        x = np.zeros(n or 0) if self.rest is None else self.rest
        try:
            a = np.array(x, dtype=float) if np.asarray(x).dtype.kind != "c" else None
        except (TypeError, ValueError):
            a = None
        if a is None or a.shape != (n,):
            got = f"shape {a.shape}" if a is not None else f"{type(x).__name__}"
            raise ModelError(f"extras.rest: expected shape ({n},) like extras.stiffness (rest angles, rad), got {got}")
        if not np.isfinite(a).all():
            raise ModelError("extras.rest: contains NaN or inf")
        a.flags.writeable = False
        return a

    @classmethod
    def zeros(cls, n: int) -> "JointExtras":
        """No spring, armature nor friction on ``n`` joints.

        Parameters
        ----------
        n : int
            The joints.

        Returns
        -------
        JointExtras
            Zeros, (n,) each.
        """
        z = np.zeros(n)
        return cls(z, z.copy(), z.copy(), z.copy())

    @property
    def has_spring(self) -> bool:
        return bool(np.any(self.stiffness != 0))

    @property
    def has_friction(self) -> bool:
        return bool(np.any(self.coulomb != 0) or np.any(self.viscous != 0))

    @property
    def has_rest(self) -> bool:
        """Whether any spring rests elsewhere than at q = 0."""
        return self._rest_used is not None

    def spring_torque(self, q: Any, xp: Any = np) -> Any:
        """Spring torque k (q - q_rest) (:func:`spring_law`), the spring part of G(q) in eq. 2.11.

        Parameters
        ----------
        q : array_like or casadi.SX
            (n,) joint angles, rad.
        xp : module, optional
            ``numpy`` or ``casadi``.

        Returns
        -------
        ndarray or casadi.SX
            (n,) N m.
        """
        return spring_law(self.stiffness, self._rest_used, q, xp)  # no rest angle: k q, the hot path

    def spring_energy(self, q: Any, xp: Any = np) -> Any:
        """Spring potential energy sum 1/2 k_i (q_i - q_rest,i)^2 = 1/2 tau_s . (q - q_rest).

        Parameters
        ----------
        q : array_like or casadi.SX
            (n,) joint angles, rad.
        xp : module, optional
            ``numpy`` or ``casadi``.

        Returns
        -------
        float or casadi.SX
            J.
        """
        dq = q - _as(xp, self.rest) if self.has_rest else q
        return 0.5 * xp.dot(self.spring_torque(q, xp), dq)

    def friction_torque(self, v: Any, smooth: bool = False, xp: Any = np) -> Any:
        """Friction torque F_s sign(v) + F_v v (eq. 2.6-2.7).

        Parameters
        ----------
        v : array_like or casadi.SX
            (n,) joint velocities, rad/s.
        smooth : bool, optional
            sign(v) as tanh(v / v_s) (v_s: ``smooth_velocity``).
        xp : module, optional
            ``numpy`` or ``casadi``.

        Returns
        -------
        ndarray or casadi.SX
            (n,) N m.
        """
        sgn = xp.tanh(v / self.smooth_velocity) if smooth else xp.sign(v)
        return _as(xp, self.coulomb) * sgn + _as(xp, self.viscous) * v

    def passive_torque(self, q: Any, v: Any, smooth: bool = False, xp: Any = np) -> Any:
        """Springs plus friction, the extras' share of the left side of eq. 2.10.

        Parameters
        ----------
        q, v : array_like or casadi.SX
            (n,) joint angles, rad, and velocities, rad/s.
        smooth : bool, optional
            The friction's sign smoothed (:meth:`friction_torque`).
        xp : module, optional
            ``numpy`` or ``casadi``.

        Returns
        -------
        ndarray or casadi.SX
            (n,) N m.
        """
        out = self.spring_torque(q, xp)
        if self.has_friction:
            out = out + self.friction_torque(v, smooth, xp)
        return out
