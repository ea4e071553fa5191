"""Numeric rigid-body dynamics of a fixed-base URDF tree, with the Alpes extras (Pinocchio).

The model solves eq. 2.10 of the report,

    (A(q) + I_a) qdd + C(q, qd) qd + F_v qd + f_s + G(q) = Gamma + J^T F,

with A from CRBA, C the Christoffel-consistent Coriolis matrix (A_dot - 2C skew-symmetric),
G = gravity + springs (eq. 2.11, 2.14), I_a = N^2 J_m (eq. 2.8, Pinocchio's ``armature``),
friction eq. 2.6-2.7 and the contact torque J^T F of eq. 2.9 with F a linear force at a tip frame,
expressed in the base frame (default F = [0, 0, F_z], eq. 2.13).

Following Pinocchio, a :class:`Model` owns one ``pinocchio.Model`` and one ``pinocchio.Data``;
it is not thread-safe (use :meth:`Model.copy` per thread).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np
import pinocchio as pin

from .description import Layout, check_model_name, layout, urdf_string
from .checks import as_float_array
from .errors import InputError, ModelError
from .extras import JointExtras, spring_stiffness
from .fileio import native_stderr_to, read_text
from .inertial import check_inertials
from .params import HandParams, load_params
from .transmission import Transmission

__all__ = ["Model", "DEFAULT_GRAVITY"]

DEFAULT_GRAVITY = np.array([0.0, 0.0, -9.81])
_F64 = np.dtype(np.float64)
_ND = np.ndarray
_aba = pin.aba
_isfinite = math.isfinite
_WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_TINY = 2.0**-1000  # |x| * _TINY < 2e7 for every finite float64 x


def _build_pinocchio(urdf: str) -> pin.Model:
    printed: list[str] = []  # urdfdom prints its parse errors on the process's stderr: into the message
    try:
        with native_stderr_to(printed):
            model = pin.buildModelFromXML(urdf)
    except Exception as exc:  # pinocchio raises ValueError/RuntimeError with multi-line text
        errors = [line.removeprefix("Error:").strip() for line in printed if line.startswith("Error:")]
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ModelError(f"URDF could not be parsed by Pinocchio: {errors[0] if errors else first}") from None
    if model.nv == 0:
        raise ModelError("URDF has no movable joint")
    if model.nq != model.nv:
        raise ModelError(
            f"URDF has joints with nq != nv (nq={model.nq}, nv={model.nv}); only fixed-base trees of "
            "revolute/prismatic joints are supported"
        )
    return model


def _generic_configuration(model: pin.Model) -> np.ndarray:
    """A fixed, generic q inside the joint limits (golden-ratio fractions of each range)."""
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    lo = np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.pi)
    hi = np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.pi)
    frac = np.mod(0.5 + 0.6180339887498949 * np.arange(1, model.nv + 1), 1.0)
    return lo + frac * (hi - lo)


def _check_mass_matrix(model: pin.Model, data: pin.Data, names: Sequence[str]) -> None:
    """ModelError if A(q) + I_a is singular at a generic q: a joint that moves only massless links."""
    A = pin.crba(model, data, _generic_configuration(model))
    A = np.triu(A) + np.triu(A, 1).T
    d = np.diag(A)
    scale = float(np.max(np.abs(d))) if d.size else 0.0
    for i, name in enumerate(names):
        if not d[i] > 1e-14 * scale:
            raise ModelError(f"joint {name!r} moves no mass: the links it carries are massless, so A(q) is singular "
                             "(give them a mass and inertia, or make the joint fixed)")
    try:
        np.linalg.cholesky(A)
    except np.linalg.LinAlgError:
        raise ModelError("A(q) is singular at a generic configuration (massless links?)") from None


class Model:
    """Dynamics of a fixed-base tree of 1-DoF joints (an Alpes model or any URDF).

    Parameters
    ----------
    urdf:
        URDF text (not a path; see :meth:`from_urdf_file`).
    extras:
        Springs, friction, rotor inertia in joint order (default: none).
    gravity:
        Gravity vector in the base frame, m/s^2, shape (3,) (default (0, 0, -9.81)).
    name:
        A label (default: the robot name of the URDF).
    check_inertia:
        ``"strict"`` (default) or ``"relaxed"``: how the URDF's inertials are validated
        (:func:`alpes_dyn.inertial.check_inertials`; relaxed skips the triangle inequality).
    layout, params:
        Set by :meth:`alpes`: the chains/tips/transmission of an Alpes model and its parameters.

    All vectors are 1-D float arrays of length ``n`` (joints in :attr:`joint_names` order), in SI
    units (rad, rad/s, rad/s^2, N m, N).
    """

    def __init__(self, urdf: str, extras: JointExtras | None = None, gravity: Sequence[float] | None = None,
                 name: str | None = None, layout: Layout | None = None, params: HandParams | None = None,
                 spring: str = "none", *, check_inertia: str = "strict") -> None:
        if not isinstance(urdf, str) or "<robot" not in urdf:
            raise ModelError("urdf: expected URDF text containing a <robot> element")
        self.urdf: str = urdf
        self.pin_model: pin.Model = _build_pinocchio(urdf)
        check_inertials(urdf, check_inertia)
        self.check_inertia = check_inertia
        n = self.pin_model.nv
        self.n: int = n
        self.joint_names: tuple[str, ...] = tuple(self.pin_model.names[1:])
        self.name: str = name or self.pin_model.name
        self.layout = layout
        self.params = params
        self.spring = spring
        try:
            g = DEFAULT_GRAVITY if gravity is None else as_float_array(gravity, "gravity", "3 finite numbers")
        except InputError as exc:
            raise ModelError(str(exc)) from None
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise ModelError(f"gravity: expected 3 finite numbers, got {np.asarray(gravity).tolist()!r}")
        self.gravity: np.ndarray = g.copy()
        self.pin_model.gravity.linear = g
        self.extras: JointExtras = extras if extras is not None else JointExtras.zeros(n)
        for fname in ("stiffness", "armature", "coulomb", "viscous"):
            a = getattr(self.extras, fname)
            if np.shape(a) != (n,):
                raise ModelError(f"extras.{fname}: expected shape ({n},), got {np.shape(a)}")
        if np.any(self.extras.armature < 0):
            raise ModelError("extras.armature: must be >= 0")
        self.pin_model.armature = np.asarray(self.extras.armature, dtype=float).copy()
        self.pin_data: pin.Data = self.pin_model.createData()
        _check_mass_matrix(self.pin_model, self.pin_data, self.joint_names)
        self._k = np.asarray(self.extras.stiffness, dtype=float)
        self._spring = self.extras.has_spring
        self._friction = self.extras.has_friction
        self._lower = np.tril_indices(n, -1)
        self._shape = (n,)
        self._tiny = np.full(n, _TINY)  # x . tiny is finite iff x is, and never overflows (no numpy warning)
        self._frames = {f.name: i for i, f in enumerate(self.pin_model.frames)}
        if layout is not None:
            self.tips: tuple[str, ...] = layout.tips
        else:
            parents = {self.pin_model.frames[i].parentFrame for i in range(len(self.pin_model.frames))}
            self.tips = tuple(f.name for i, f in enumerate(self.pin_model.frames)
                              if i not in parents and f.type == pin.FrameType.BODY)
        self.transmission: Transmission | None = None
        if layout is not None and params is not None:
            self.transmission = Transmission.from_layout(
                layout, self.joint_names, params.transmission_ratio, params.abduction_ratio, params.encoder_counts)

    # ------------------------------------------------------------------ construction
    @classmethod
    def alpes(cls, model: str = "finger3", spring: str = "torsional", friction: bool = False,
              rotor_inertia: bool = False, params: HandParams | str | Path | None = None) -> "Model":
        """An Alpes model (``finger2``, ``finger3`` or ``hand``) built from the parameter file.

        ``spring`` is ``"torsional"`` (default), ``"report"`` (eq. 2.14 literally) or ``"none"``;
        ``friction`` and ``rotor_inertia`` switch on eq. 2.6-2.7 and eq. 2.8 with the file's values.
        """
        check_model_name(model)
        p = params if isinstance(params, HandParams) else load_params(params)
        lay = layout(model, p)
        m = cls(urdf_string(model, p), gravity=p.gravity, name=model, layout=lay, params=p, spring=spring)
        names = m.joint_names
        K = np.zeros(m.n)
        arm = np.zeros(m.n)
        idx = {j: i for i, j in enumerate(names)}
        for ch in lay.chains:
            K[[idx[j] for j in ch.joints]] = ch.stiffness
            arm[[idx[j] for j in ch.joints]] = p.N**2 * p.J_m
            if ch.abduction:
                K[idx[ch.abduction]] = lay.abduction_stiffness
                arm[idx[ch.abduction]] = p.abduction_ratio**2 * p.J_m
        k = spring_stiffness(K, spring, p.b, p.r)
        ones = np.ones(m.n)
        extras = JointExtras(
            stiffness=k,
            armature=arm if rotor_inertia else np.zeros(m.n),
            coulomb=p.F_s * ones if friction else np.zeros(m.n),
            viscous=p.F_v * ones if friction else np.zeros(m.n),
            smooth_velocity=p.smooth_velocity,
        )
        return cls(m.urdf, extras=extras, gravity=p.gravity, name=model, layout=lay, params=p, spring=spring)

    @classmethod
    def from_urdf_file(cls, path: str | Path, **kwargs) -> "Model":
        """Load any fixed-base URDF file (e.g. one of example-robot-data); extras default to none."""
        return cls(read_text(path, "URDF file", ModelError), **kwargs)

    def copy(self) -> "Model":
        """An independent model (own Pinocchio data), e.g. for another thread."""
        return Model(self.urdf, self.extras, self.gravity, self.name, self.layout, self.params, self.spring,
                     check_inertia=self.check_inertia)

    def __repr__(self) -> str:
        return f"Model({self.name!r}, n={self.n}, spring={self.spring!r}, tips={list(self.tips)})"

    # ------------------------------------------------------------------ input checks
    def vector(self, x: object, name: str, n: int | None = None) -> np.ndarray:
        """``x`` as a finite float vector of length n (default the model's), else :class:`InputError`."""
        n = self.n if n is None else n
        if x.__class__ is _ND and x.dtype is _F64 and x.shape == (n,):  # fast path, no copy
            a = x
            if math.isfinite(a.dot(self._tiny if n == self.n else np.full(n, _TINY))):  # one BLAS call
                return a
        else:
            a = as_float_array(x, name, f"{n} numbers")
            if a.shape != (n,):
                raise InputError(f"{name}: expected shape ({n},), got {a.shape}")
        if not np.isfinite(a).all():
            raise InputError(f"{name}: contains NaN or inf ({a.tolist()})")
        return a

    def frame_id(self, tip: str | None) -> int:
        """Pinocchio frame index of ``tip`` (default: the first tip)."""
        if tip is None:
            if not self.tips:
                raise ModelError("model has no tip frame; pass a frame name")
            tip = self.tips[0]
        try:
            return self._frames[tip]
        except (KeyError, TypeError):
            raise ModelError(f"unknown tip/frame {tip!r} (tips: {', '.join(self.tips)})") from None

    def _force(self, F: object) -> np.ndarray:
        if F is None:
            return np.zeros(3)
        a = as_float_array(F, "F", "F_z or 3 numbers Fx, Fy, Fz")
        if a.shape == ():
            return np.array([0.0, 0.0, float(self.vector(np.atleast_1d(a), "F", 1)[0])])  # F_z only (eq. 2.13)
        return self.vector(a, "F", 3)

    # ------------------------------------------------------------------ terms of eq. 2.10
    def inertia_matrix(self, q: np.ndarray) -> np.ndarray:
        """A(q) + I_a: full symmetric (n, n) inertia matrix, kg m^2 (CRBA; eq. 2.3, 2.8)."""
        q = self.vector(q, "q")
        M = pin.crba(self.pin_model, self.pin_data, q).copy()
        M[self._lower] = M.T[self._lower]  # CRBA fills the upper triangle
        return M

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """C(q, qd), (n, n), N m s: C qd are the Coriolis/centrifugal torques (eq. 2.4-2.5), A_dot - 2C skew."""
        q, v = self.vector(q, "q"), self.vector(v, "v")
        return pin.computeCoriolisMatrix(self.pin_model, self.pin_data, q, v).copy()

    def spring_torque(self, q: np.ndarray) -> np.ndarray:
        """Spring torques k q, (n,), N m (eq. 2.14 under the model's spring law)."""
        return self.extras.spring_torque(self.vector(q, "q"))

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """G(q) of eq. 2.11: gravity plus springs, (n,), N m."""
        q = self.vector(q, "q")
        g = pin.computeGeneralizedGravity(self.pin_model, self.pin_data, q)
        return g + self._k * q if self._spring else g.copy()

    def gravity_jacobian(self, q: np.ndarray) -> np.ndarray:
        """dG/dq (n, n), N m/rad: Pinocchio's analytic gravity derivatives plus the spring stiffness diag(k)."""
        q = self.vector(q, "q")
        dG = pin.computeGeneralizedGravityDerivatives(self.pin_model, self.pin_data, q).copy()
        dG[np.diag_indices(self.n)] += self._k
        return dG

    def friction_torque(self, v: np.ndarray, smooth: bool = False) -> np.ndarray:
        """Friction F_v qd + f_s (eq. 2.6-2.7), (n,), N m; ``smooth`` uses tanh(qd / v_s) for sign."""
        return self.extras.friction_torque(self.vector(v, "v"), smooth)

    def fingertip_position(self, q: np.ndarray, tip: str | None = None) -> np.ndarray:
        """Position of a tip frame in the base frame, (3,), m."""
        q = self.vector(q, "q")
        fid = self.frame_id(tip)
        pin.framesForwardKinematics(self.pin_model, self.pin_data, q)
        return self.pin_data.oMf[fid].translation.copy()

    def fingertip_jacobian(self, q: np.ndarray, tip: str | None = None) -> np.ndarray:
        """Linear velocity Jacobian J of a tip frame in the base frame, (3, n), m (Section 2.2, eq. 2.12)."""
        q = self.vector(q, "q")
        fid = self.frame_id(tip)
        return pin.computeFrameJacobian(self.pin_model, self.pin_data, q, fid, _WORLD)[:3].copy()

    def contact_torque(self, q: np.ndarray, F: object = None, tip: str | None = None) -> np.ndarray:
        """J^T F (eq. 2.9), (n,), N m, for a force F (N, base frame; a scalar means [0, 0, F_z], eq. 2.13)."""
        return self.fingertip_jacobian(q, tip).T @ self._force(F)

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """E = 1/2 qd^T (A + I_a) qd (eq. 2.3), J."""
        v = self.vector(v, "v")
        return 0.5 * float(v @ self.inertia_matrix(q) @ v)

    def potential_energy(self, q: np.ndarray) -> float:
        """U = gravity + spring potential energy (J), zero at the base height and q = 0 springs."""
        q = self.vector(q, "q")
        return float(pin.computePotentialEnergy(self.pin_model, self.pin_data, q)) + float(self.extras.spring_energy(q))

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, F: object = None,
                         tip: str | None = None, smooth: bool = False) -> np.ndarray:
        """Joint accelerations qdd (n,), rad/s^2, solving eq. 2.10 (ABA + extras).

        ``tau`` is Gamma (N m); F an optional contact force at ``tip`` (N, base frame; a scalar is F_z).
        This is the hot path: float64 arrays of the right shape skip conversion, and finiteness is
        checked once on the result (NaN/inf in any input propagates to it); a non-finite result
        raises :class:`InputError` naming the offending input.
        """
        if not (q.__class__ is _ND and v.__class__ is _ND and tau.__class__ is _ND and q.dtype is _F64
                and v.dtype is _F64 and tau.dtype is _F64 and q.shape == v.shape == tau.shape == self._shape):
            q, v, tau = self.vector(q, "q"), self.vector(v, "v"), self.vector(tau, "tau")
        if self._spring:
            tau = tau - self._k * q
        if self._friction:
            tau = tau - self.extras.friction_torque(v, smooth)
        if F is not None:
            tau = tau + self.contact_torque(q, F, tip)
        qdd = _aba(self.pin_model, self.pin_data, q, v, tau)
        if not _isfinite(qdd.dot(self._tiny)):
            for x, name in ((q, "q"), (v, "v"), (tau, "tau")):
                self.vector(x, name)
            if not np.isfinite(qdd).all():
                raise InputError("forward dynamics gave non-finite accelerations (inputs too large?)")
        return qdd

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, F: object = None,
                         tip: str | None = None, smooth: bool = False) -> np.ndarray:
        """Joint torques Gamma (n,), N m, that produce accelerations ``a`` (eq. 2.10; RNEA + extras)."""
        q, v, a = self.vector(q, "q"), self.vector(v, "v"), self.vector(a, "a")
        tau = pin.rnea(self.pin_model, self.pin_data, q, v, a).copy()
        if self._spring:
            tau += self._k * q
        if self._friction:
            tau += self.extras.friction_torque(v, smooth)
        if F is not None:
            tau -= self.contact_torque(q, F, tip)
        return tau

    # ------------------------------------------------------------------ helpers
    @property
    def lower(self) -> np.ndarray:
        """Joint lower limits from the URDF (rad)."""
        return self.pin_model.lowerPositionLimit.copy()

    @property
    def upper(self) -> np.ndarray:
        """Joint upper limits from the URDF (rad)."""
        return self.pin_model.upperPositionLimit.copy()

    def random_state(self, rng: np.random.Generator | int | None, speed: float = 2.0,
                     size: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """A random (q, v): q uniform within the joint limits (+-pi where a limit is missing or huge),
        v uniform in [-speed, speed] rad/s; shapes (n,), or (size, n) for ``size`` states at once.

        ``rng`` is a ``numpy.random.Generator``, or a seed (an integer >= 0, or None for fresh
        entropy) given to ``numpy.random.default_rng``.
        """
        rng, speed, size = _check_random_args(rng, speed, size)
        lo, hi = self.lower, self.upper
        lo = np.where(np.isfinite(lo) & (np.abs(lo) < 1e3), lo, -np.pi)
        hi = np.where(np.isfinite(hi) & (np.abs(hi) < 1e3), hi, np.pi)
        shape = self.n if size is None else (size, self.n)
        return rng.uniform(lo, hi, size=None if size is None else shape), rng.uniform(-speed, speed, shape)


def _check_random_args(rng: object, speed: object, size: object) -> tuple[np.random.Generator, float, int | None]:
    if not isinstance(rng, np.random.Generator):
        if rng is not None and (isinstance(rng, (bool, np.bool_)) or not isinstance(rng, (int, np.integer))
                                or rng < 0):
            raise InputError(f"rng: expected a numpy Generator, an integer seed >= 0 or None, got {rng!r}")
        rng = np.random.default_rng(rng)
    try:
        s = float(speed)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        s = float("nan")
    if not (math.isfinite(s) and s >= 0):
        raise InputError(f"speed: expected a finite number >= 0 rad/s, got {speed!r}")
    if size is not None and (isinstance(size, (bool, np.bool_)) or not isinstance(size, (int, np.integer))
                             or size < 0):
        raise InputError(f"size: expected an integer >= 0 or None, got {size!r}")
    return rng, s, None if size is None else int(size)
