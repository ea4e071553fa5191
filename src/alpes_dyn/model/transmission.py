"""Tendon transmission and actuation of the Alpes hand (report Section 3, eq. 3.13).

Each finger has one motor whose encoder reads q_m = (r/r_m)(q_1 + q_2 + q_3). The map is linear,
q_m = S q with S of shape (n_motors, n_joints); by power consistency (tau_m . qdot_m = tau . qdot)
the motor torques act on the joints as tau = S^T tau_m, so S^T is the actuation matrix.
For the hand: 6 motors -- index, middle, ring, little, thumb flexion (on the thumb's two flexion
joints) and thumb ab/adduction (on its own joint, ratio ``transmission.abduction_ratio``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from .ratio_curve import RatioCurve

__all__ = ["Transmission", "acceleration_before", "torque_before", "capstan_loss", "capstan_torque",
           "capstan_velocity"]


def capstan_loss(mu_theta: Any, xp: Any = np) -> Any:
    """1 - exp(-mu theta): the fraction of a tendon's tension lost over a sheath or pulley of wrap angle theta (rad)
    and friction coefficient mu while the motor pulls the cable (the capstan equation T_out = T_in exp(-mu theta)).

    Parameters
    ----------
    mu_theta : numpy.ndarray or casadi.SX, shape (m,)
        mu theta, dimensionless, >= 0.
    xp : module, optional
        ``numpy`` (default) or ``casadi``.

    Returns
    -------
    numpy.ndarray or casadi.SX, shape (m,)
        The fraction lost, in [0, 1).
    """
    return 1.0 - xp.exp(-mu_theta)


def capstan_velocity(S: np.ndarray, smooth_velocity: float) -> np.ndarray:
    """(m,) rad/s of motor shaft: the smooth sign's scale of each tendon, v_s max_i |S_ki| (the motor's velocity when
    its fastest joint moves alone at the joints' v_s, so that the tendon's sign is as sharp as the joints').

    Parameters
    ----------
    S : numpy.ndarray, shape (m, n)
        The ratios, rad of motor per rad of joint (a motor with none: scale 1).
    smooth_velocity : float
        The joints' v_s, rad/s.
    """
    scale = np.max(np.abs(np.asarray(S, dtype=float)), axis=1)
    return float(smooth_velocity) * np.where(scale > 0, scale, 1.0)


def capstan_torque(tau_m: Any, v_m: Any, mu_theta: Any, v_c: Any, xp: Any = np) -> Any:
    """The motor torque that reaches the joints through a tendon with sheath friction (capstan), N m:

        tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c)

    a friction on the motor side proportional to the tension (|tau_m| / r_m), opposing the tendon's sliding, its
    sign smoothed as the joints' friction is. Written once here for the numeric and the symbolic and parametric
    paths. Why this form and not the capstan's own exp(-mu theta sign v): it is the same where the motor pulls the
    cable (v_m > 0: the joints get tau_m exp(-mu theta)), to first order in mu theta where the joints pull it back
    (tau_m (2 - exp(-mu theta)) against tau_m exp(mu theta)), and it is a friction: its power
    -(1 - exp(-mu theta)) |tau_m| |v_m| tanh-smoothed never feeds energy in, and at v_m = 0 it vanishes smoothly
    (the exponential's jump in sign v would be a step in the joint torque at every reversal). The tension is the
    motor torque (the rotor's inertia and the cable's stretch ignored: the tension the sheath sees).

    Parameters
    ----------
    tau_m : numpy.ndarray or casadi.SX, shape (..., m)
        Motor torques, N m.
    v_m : numpy.ndarray or casadi.SX, shape (..., m)
        Motor velocities, rad/s of motor shaft.
    mu_theta : numpy.ndarray or casadi.SX, shape (m,)
        mu theta, dimensionless.
    v_c : numpy.ndarray or casadi.SX, shape (m,)
        The smooth sign's scale, rad/s (:func:`capstan_velocity`).
    xp : module, optional
        ``numpy`` (default) or ``casadi``.

    Returns
    -------
    numpy.ndarray or casadi.SX, shape (..., m)
        The torque that reaches the joints, N m.
    """
    if xp is np:
        return tau_m - capstan_loss(np.asarray(mu_theta, dtype=float)) * np.abs(tau_m) * np.tanh(v_m / v_c)
    if isinstance(mu_theta, np.ndarray):
        mu_theta = xp.DM(mu_theta)
    if isinstance(v_c, np.ndarray):
        v_c = xp.DM(v_c)
    return tau_m - capstan_loss(mu_theta, xp) * xp.fabs(tau_m) * xp.tanh(v_m / v_c)


def torque_before(tau_m: np.ndarray) -> np.ndarray:
    """(N, m) the motor torque that each sample's tendon tension balances: the one held over the period before
    it, tau_m,k-1 (N m), the first sample its own. A recording's torque tau_m,k acts over [t_k, t_k+1) (zero-order
    hold), and the cable's tension at t_k has seen only the torques before t_k, so the elastic tendon's stretch the
    encoder reads at t_k is C tau_m,k-1 (:meth:`Transmission.encoder_angles`). The shift matters
    with a dither: its half-period turns into a stretch in quadrature, and the stretch taken from the same sample's
    torque biases the fitted masses (MuJoCo's elastic tendon, ``benchmarks/realism.py``'s cable).

    Parameters
    ----------
    tau_m : numpy.ndarray, shape (N, m) or (N,)
        The recorded motor torques, N m.

    Returns
    -------
    numpy.ndarray, shape of ``tau_m``
        tau_m,k-1 at each sample k (the first sample its own).

    Raises
    ------
    InputError
        No sample, or not numbers.
    """
    tau_m = as_float_array(tau_m, "tau_m", "motor torques")
    if tau_m.ndim == 0 or tau_m.shape[0] == 0:
        raise InputError(f"tau_m: expected one row per sample, got shape {tau_m.shape}")
    return np.concatenate([tau_m[:1], tau_m[:-1]])


def acceleration_before(qd_m: np.ndarray, dt: float, axis: int = 0) -> np.ndarray:
    """The acceleration over the period before each sample, rad/s^2, (qd_k - qd_k-1) / dt, from velocities qd
    (rad/s, the samples along ``axis``, every ``dt`` s; e.g. the motors' (N, m)); the first sample takes the first
    period's. With :func:`torque_before`, what the cable's tension balances at a reading: r_m T = tau_m,k-1 - J_m
    qdd_m (:meth:`Transmission.encoder_angles`; the fit's
    :meth:`~alpes_dyn.estimation.identification.encoder_output.EncoderOutput.motor_acceleration`, per interval).

    Parameters
    ----------
    qd_m : numpy.ndarray
        Velocities, rad/s, the samples along ``axis`` (e.g. the motors' (N, m)).
    dt : float
        The sample period, s.
    axis : int, optional
        The samples' axis (default 0).

    Returns
    -------
    numpy.ndarray, shape of ``qd_m``
        The accelerations, rad/s^2.

    Raises
    ------
    InputError
        Fewer than two samples along ``axis``.
    """
    qd_m = as_float_array(qd_m, "qd_m", "motor velocities")
    if qd_m.ndim <= axis or qd_m.shape[axis] < 2:
        raise InputError(f"qd_m: expected two samples or more along axis {axis}, got shape {qd_m.shape}")
    d = np.diff(qd_m, axis=axis) / dt
    return np.concatenate([d.take([0], axis=axis), d], axis=axis)


@dataclass(frozen=True)
class Transmission:
    """Linear joint-to-motor map of a model.

    Attributes
    ----------
    motor_names: names of the motors, length m.
    S: (m, n) map q_m = S q (rad of motor shaft per rad of joint).
    sum_matrix: (m, n) map y = (sum of each motor's joints), the report's output y = q_1 + ... + q_k.
    counts_per_rev: encoder resolution (counts per motor revolution), for quantisation.
    rotor_inertia: (m,) J_m of each motor's rotor about its shaft, kg m^2 (default zeros).
    tendon_compliance: (m,) C of each motor's tendon, rad/(N m) (default zeros: rigid): the encoder reads
        y_k = S q_k + C tau_m,k-1 (:meth:`encoder_angles` with :func:`torque_before`; the series-elastic tendon's
        quasi-static limit, :mod:`alpes_dyn.model.spec`).
    ratio_curve: (P, m, n) or None (default: constant ratios): the coefficients of q^1 .. q^P of each ratio,
        rho_ki(q_i) = S_ki + sum_p c_ki,p q_i^p (:mod:`alpes_dyn.model.ratio_curve`); S is then the ratio at q = 0,
        the motor angle is s(q) = L(q) / r_m (:meth:`motor_positions`), the joint torque rho(q)^T tau_m
        (:meth:`joint_torque` with q) and the rotors' inertia rho(q)^T diag(J_m) rho(q) (:meth:`rotor_matrix_at`).
    capstan: (m,) mu theta of each motor's tendon, dimensionless, >= 0 (default zeros: no sheath friction): the
        friction coefficient times the wrap angle of the sheaths and pulleys it slides over; the motor torque that
        reaches the joints is :func:`capstan_torque`'s (:meth:`transmitted`).
    paths: (m,) a :class:`~alpes_dyn.model.spatial_path.SpatialPath` or None for each motor (default None: none):
        a motor's spatial tendon as its geometry, its ratios from its length (:mod:`alpes_dyn.model.path_ratios`; S
        its ratios at q = 0); :attr:`curve` is then a :class:`~alpes_dyn.model.path_ratios.PathRatios`.
    joint_names: (n,) the joints' names, which the paths name (with ``paths``).
    """

    motor_names: tuple[str, ...]
    S: np.ndarray
    sum_matrix: np.ndarray
    counts_per_rev: float
    rotor_inertia: np.ndarray | None = None
    tendon_compliance: np.ndarray | None = None
    ratio_curve: np.ndarray | None = None
    capstan: np.ndarray | None = None
    paths: tuple | None = None
    joint_names: tuple | None = None

    def __post_init__(self) -> None:
        J = np.zeros(self.S.shape[0]) if self.rotor_inertia is None else np.asarray(self.rotor_inertia, dtype=float)
        if J.shape != (self.S.shape[0],) or not np.all(np.isfinite(J)) or np.any(J < 0):
            raise InputError(f"rotor_inertia: expected {self.S.shape[0]} finite numbers >= 0 (kg m^2), got {J.tolist()!r}")
        J = J.copy()
        J.flags.writeable = False
        object.__setattr__(self, "rotor_inertia", J)
        m = self.S.shape[0]
        C = np.zeros(m) if self.tendon_compliance is None else np.array(self.tendon_compliance, dtype=float)
        if C.shape != (m,) or not np.all(np.isfinite(C)):
            raise InputError(f"tendon_compliance: expected {m} finite numbers (rad/(N m)), got {C.tolist()!r}")
        C.flags.writeable = False
        object.__setattr__(self, "tendon_compliance", C)
        mu = np.zeros(m) if self.capstan is None else np.array(self.capstan, dtype=float)
        if mu.shape != (m,) or not np.all(np.isfinite(mu)) or np.any(mu < 0):
            raise InputError(f"capstan: expected {m} finite numbers >= 0 (mu theta, dimensionless), got {mu.tolist()!r}")
        mu.flags.writeable = False
        object.__setattr__(self, "capstan", mu)
        curve = None if self.ratio_curve is None else RatioCurve(self.S, self.ratio_curve)
        if self.paths is not None and any(p is not None for p in self.paths):
            from .path_ratios import PathRatios

            base = curve if curve is not None else RatioCurve(self.S, np.zeros((1,) + self.S.shape))
            curve = PathRatios(base, {k: p for k, p in enumerate(self.paths) if p is not None}, self.motor_names,
                               self.joint_names)
        object.__setattr__(self, "_curve", curve)

    @property
    def curved(self) -> bool:
        """True when a ratio changes with the joint angle (:attr:`ratio_curve`), False for a constant S."""
        return self._curve is not None

    @property
    def curve(self) -> Any:
        """The q-dependent ratios (:class:`~alpes_dyn.model.ratio_curve.RatioCurve`, or
        :class:`~alpes_dyn.model.path_ratios.PathRatios` with :attr:`paths`), None for a constant S."""
        return self._curve

    def ratio(self, q: np.ndarray) -> np.ndarray:
        """rho(q) = ds/dq, rad of motor per rad of joint (S itself for constant ratios).

        Parameters
        ----------
        q : array_like
            (n,) or (..., n) joint angles, rad.

        Returns
        -------
        ndarray
            (m, n), or (..., m, n).
        """
        q = self._joints(q)
        if self._curve is None:
            return np.broadcast_to(self.S, q.shape[:-1] + self.S.shape).copy()
        return self._curve.ratio(q)

    def rotor_matrix_at(self, q: np.ndarray) -> np.ndarray:
        """rho(q)^T diag(J_m) rho(q), kg m^2: the rotors' inertia on the joints at q (:attr:`rotor_matrix` for
        constant ratios).

        Parameters
        ----------
        q : array_like
            (n,) joint angles, rad.

        Returns
        -------
        ndarray
            (n, n).
        """
        if self._curve is None:
            return self.rotor_matrix
        R = self._curve.ratio(self._joints(q))
        return R.T @ (self.rotor_inertia[:, None] * R)

    def rotor_bias(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """rho(q)^T diag(J_m) (drho/dt) qd, N m: the rotors' velocity-product torque on the joints (zeros for
        constant ratios).

        Parameters
        ----------
        q, v : array_like
            (n,) joint angles, rad, and velocities, rad/s.

        Returns
        -------
        ndarray
            (n,).
        """
        if self._curve is None:
            return np.zeros(self.S.shape[1])
        q, v = self._joints(q), self._joints(v, "v")
        return self._curve.ratio(q).T @ (self.rotor_inertia * self._curve.rate_product(q, v))

    @property
    def has_capstan(self) -> bool:
        """True when a tendon has sheath friction (a non-zero :attr:`capstan`)."""
        return bool(np.any(self.capstan != 0))

    def transmitted(self, tau_m: Any, v_m: Any, smooth_velocity: float, xp: Any = np) -> Any:
        """The motor torques that reach the joints through the tendons' sheaths: tau_m less the capstan friction
        (:func:`capstan_torque`) at the motor velocities; tau_m itself without sheath friction.

        Parameters
        ----------
        tau_m : array_like or casadi.SX
            (..., m) motor torques, N m.
        v_m : array_like or casadi.SX
            (..., m) motor velocities, rad/s.
        smooth_velocity : float
            The joints' friction sign's v_s, rad/s (the sheath's: :func:`capstan_velocity` of it).
        xp : module, optional
            ``numpy`` or ``casadi``.

        Returns
        -------
        ndarray or casadi.SX
            (..., m) N m.
        """
        if not self.has_capstan:
            return tau_m
        return capstan_torque(tau_m, v_m, self.capstan, capstan_velocity(self.S, smooth_velocity), xp)

    @property
    def elastic(self) -> bool:
        """True when a tendon has a non-zero compliance (the encoder then reads S q + C tau_m)."""
        return bool(np.any(self.tendon_compliance != 0))

    def encoder_angles(self, q: np.ndarray, tau_m: np.ndarray | None = None,
                       qdd_m: np.ndarray | None = None) -> np.ndarray:
        """What the encoders read, rad: S q + C (tau_m - J_m qdd_m), the tendons' stretch under their tension (S q
        without tau_m, or with rigid tendons).

        Parameters
        ----------
        q : array_like
            (..., n) joint angles, rad.
        tau_m : array_like or None, optional
            (..., m) the motor torque the tension balances at the reading's instant, N m (in a sampled record the
            torque held over the period before it, :func:`torque_before`).
        qdd_m : array_like or None, optional
            (..., m) the motor accelerations, rad/s^2 (:func:`acceleration_before`): J_m qdd_m, what accelerates the
            rotor, taken off tau_m; None: not taken off.

        Returns
        -------
        ndarray
            (..., m) rad.
        """
        y = self.motor_positions(q)
        if tau_m is None or not self.elastic:
            return y
        tau_m = as_float_array(tau_m, "tau_m", "motor torques")
        if tau_m.shape[-1:] != (self.n_motors,):
            raise InputError(f"tau_m: expected last dimension {self.n_motors}, got shape {tau_m.shape}")
        if qdd_m is not None:
            qdd_m = as_float_array(qdd_m, "qdd_m", "motor accelerations")
            if qdd_m.shape != tau_m.shape:
                raise InputError(f"qdd_m: expected the shape of tau_m {tau_m.shape}, got {qdd_m.shape}")
            tau_m = tau_m - self.rotor_inertia * qdd_m
        return y + tau_m * self.tendon_compliance

    @property
    def driven(self) -> np.ndarray:
        """(n,) bool: the joints some motor's tendon moves (a non-zero column of S); the others are passive."""
        return np.any(self.S != 0, axis=0)

    @property
    def rotor_matrix(self) -> np.ndarray:
        """S^T diag(J_m) S, (n, n), kg m^2: the rotors' inertia on the joints (eq. 2.8's I_a on the
        tendon coordinate; kinetic energy 1/2 sum_k J_m,k qd_m,k^2 with qd_m = S qd)."""
        return self.S.T @ (self.rotor_inertia[:, None] * self.S)

    @property
    def n_motors(self) -> int:
        return int(self.S.shape[0])

    @property
    def actuation_matrix(self) -> np.ndarray:
        """B = S^T, shape (n, m): joint torques tau = B tau_m."""
        return self.S.T

    def _joints(self, q: np.ndarray, name: str = "q") -> np.ndarray:
        q = as_float_array(q, name, "joint angles" if name == "q" else "joint velocities")
        if q.shape[-1:] != (self.S.shape[1],):
            raise InputError(f"{name}: expected last dimension {self.S.shape[1]}, got shape {q.shape}")
        return q

    def motor_positions(self, q: np.ndarray) -> np.ndarray:
        """Encoder angles q_m = S q, or s(q) = L(q) / r_m with a :attr:`ratio_curve`.

        Parameters
        ----------
        q : array_like
            (n,) or (..., n) joint angles, rad.

        Returns
        -------
        ndarray
            (m,) or (..., m) rad.
        """
        q = self._joints(q)
        return q @ self.S.T if self._curve is None else self._curve.angle(q)

    def motor_velocities(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Motor velocities qd_m = S qd, or rho(q) qd with a :attr:`ratio_curve`.

        Parameters
        ----------
        q, v : array_like
            (..., n) joint angles, rad, and velocities, rad/s.

        Returns
        -------
        ndarray
            (..., m) rad/s.
        """
        v = self._joints(v, "v")
        return v @ self.S.T if self._curve is None else np.einsum("...ij,...j->...i", self._curve.ratio(
            self._joints(q)), v)

    def unstretched(self, y: np.ndarray, tau_m: np.ndarray) -> np.ndarray:
        """S q from an encoder reading: y - C tau_m, the tendons' stretch taken off (y itself for rigid tendons).

        Parameters
        ----------
        y : array_like
            (..., m) encoder angles, rad.
        tau_m : array_like
            (..., m) the motor torque held before the reading, N m (:func:`torque_before`).

        Returns
        -------
        ndarray
            (..., m) rad.
        """
        y = as_float_array(y, "y", "encoder angles")
        if not self.elastic:
            return y
        return y - as_float_array(tau_m, "tau_m", "motor torques") * self.tendon_compliance

    def joint_torque(self, tau_m: np.ndarray, q: np.ndarray | None = None) -> np.ndarray:
        """Joint torques S^T tau_m; with a :attr:`ratio_curve`, rho(q)^T tau_m.

        Parameters
        ----------
        tau_m : array_like
            (m,) or (..., m) motor torques, N m.
        q : array_like or None, optional
            (n,) or (..., n) joint angles, rad (required with a :attr:`ratio_curve`).

        Returns
        -------
        ndarray
            (n,) or (..., n) N m.
        """
        tau_m = as_float_array(tau_m, "tau_m", "motor torques")
        if tau_m.shape[-1:] != (self.n_motors,):
            raise InputError(f"tau_m: expected last dimension {self.n_motors}, got shape {tau_m.shape}")
        if self._curve is None:
            return tau_m @ self.S
        if q is None:
            raise InputError("q: a transmission whose ratios change with the joints (ratio_curve) needs the joint "
                             "angles to map motor torques onto the joints")
        return np.einsum("...k,...ki->...i", tau_m, self._curve.ratio(self._joints(q)))

    def quantize(self, q_m: np.ndarray) -> np.ndarray:
        """Encoder reading: q_m rounded to the encoder's resolution 2 pi / counts_per_rev.

        Parameters
        ----------
        q_m : array_like
            Motor angles, rad.

        Returns
        -------
        ndarray
            The reading, rad, the shape of ``q_m``.
        """
        step = 2.0 * np.pi / self.counts_per_rev
        return np.round(as_float_array(q_m, "q_m", "motor angles") / step) * step
