"""Configuration-dependent transmissions: a tendon whose moment arm changes with the joint angles (issue 37, part 2).

A motor's tendon crosses joint i with a moment arm r_i(q_i) (m) that varies with that joint's angle (a tendon routed
over sites and wrapping on a pulley or a cylinder, a measured moment-arm curve). Seen on the motor shaft of radius
r_m, the ratio rho_i(q_i) = r_i(q_i) / r_m (rad of motor per rad of joint) is written as a polynomial

    rho_ki(q_i) = S_ki + c_ki,1 q_i + c_ki,2 q_i^2 + ... + c_ki,P q_i^P

with S the ratio at q = 0 (the spec's ``joints``) and c the spec's ``ratio_curve`` (the coefficients of q^1 ... q^P).
Everything follows from the tendon's length, written once here:

* motor angle (what the encoder reads on a rigid tendon): s_k(q) = L_k(q) / r_m = sum_i int_0^q_i rho_ki
  = sum_i S_ki q_i + sum_p c_ki,p q_i^(p+1) / (p+1), rad;
* its Jacobian ds/dq = rho(q) (m, n), so the motor torques act on the joints as tau = rho(q)^T tau_m (the
  transmission is conservative: tau . qd = tau_m . ds/dt);
* the rotors' inertia on the joints rho(q)^T diag(J_m) rho(q) and, since the rotor turns at qd_m = rho(q) qd, its
  acceleration qdd_m = rho qdd + (drho/dt) qd: the velocity-product torque rho^T diag(J_m) (drho/dt) qd, where
  ((drho/dt) qd)_k = sum_i rho'_ki(q_i) qd_i^2 (each rho_ki depends on q_i alone).

The curve depends on its own joint only (a tendon whose path between two sites spans several joints is not of this
form; :func:`fit_ratio_curve` says how far a measured curve is from it). Each function takes numpy arrays or CasADi
columns (``xp``: numpy or casadi), so that the numeric model and the symbolic one are the same expressions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError, ModelError

__all__ = ["MAX_CURVE_DEGREE", "RatioCurve", "fit_ratio_curve", "encoder_angles", "encoder_rates",
           "encoder_sensitivity", "ratio_zero", "check_ratio_range"]

MAX_CURVE_DEGREE = 16
"""The highest power of q in a ratio curve (a straight tendon segment across a joint of 1.5 rad range needs 13 for
a relative error of 1e-11; much more is ill-conditioned)."""


def _sparse(A: np.ndarray, cs: Any) -> Any:
    """A numeric matrix as a CasADi DM with only its non-zero entries structural (block solves keep the fingers
    apart)."""
    rows, cols = np.nonzero(A)
    return cs.DM.triplet(rows.tolist(), cols.tolist(), cs.DM(A[rows, cols]), A.shape[0], A.shape[1])


class RatioCurve:
    """The q-dependent ratios of a transmission: rho(q) = S + sum_p C_p diag(q)^p (module doc).

    Parameters
    ----------
    S : numpy.ndarray, shape (m, n)
        The ratios at q = 0, rad of motor per rad of joint.
    C : numpy.ndarray, shape (P, m, n)
        The coefficients of q^1 .. q^P (rad/rad^(p+1); a non-zero only where S is), P in 1 ..
        :data:`MAX_CURVE_DEGREE`.

    Raises
    ------
    InputError
        C of another shape, not finite, or non-zero where S is 0.
    """

    def __init__(self, S: np.ndarray, C: np.ndarray) -> None:
        S, C = np.asarray(S, dtype=float), np.asarray(C, dtype=float)
        if C.ndim != 3 or C.shape[1:] != S.shape or not 1 <= C.shape[0] <= MAX_CURVE_DEGREE:
            raise InputError(f"ratio_curve: expected (P, {S.shape[0]}, {S.shape[1]}) coefficients, P in 1.."
                             f"{MAX_CURVE_DEGREE}, got shape {C.shape}")
        if not np.isfinite(C).all() or np.any((C != 0) & (S == 0)[None]):
            raise InputError("ratio_curve: expected finite coefficients, only on a joint its motor drives")
        self.S, self.C = S, C
        self.P = int(C.shape[0])
        p = np.arange(1, self.P + 1, dtype=float)
        self._angle_coef = C / (p + 1)[:, None, None]  # c_p / (p + 1): the integral's coefficients
        self._slope_coef = C * p[:, None, None]  # p c_p: drho/dq's

    def ratio(self, q: Any, xp: Any = np) -> Any:
        """rho(q) = ds/dq, (m, n) for q (n,); (..., m, n) for numpy q (..., n).

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,) or (..., n)
            Joint angles, rad.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        if xp is np:
            q = np.asarray(q, dtype=float)[..., None, :]
            out = self.S + self.C[0] * q
            qp = q
            for c in self.C[1:]:
                qp = qp * q
                out = out + c * qp
            return out
        out, qp = _sparse(self.S, xp), 1
        for c in self.C:
            qp = qp * q
            out = out + xp.mtimes(_sparse(c, xp), xp.diag(qp))
        return out

    def angle(self, q: Any, xp: Any = np) -> Any:
        """s(q) = sum_i int_0^q_i rho_ki, rad of motor shaft: (..., m) for numpy q (..., n), an (m,) column for
        CasADi q.

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,) or (..., n)
            Joint angles, rad.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        if xp is np:
            q = np.asarray(q, dtype=float)
            out = q @ self.S.T
            qp = q
            for c in self._angle_coef:
                qp = qp * q
                out = out + qp @ c.T
            return out
        out, qp = xp.mtimes(_sparse(self.S, xp), q), q
        for c in self._angle_coef:
            qp = qp * q
            out = out + xp.mtimes(_sparse(c, xp), qp)
        return out

    def slope(self, q: np.ndarray) -> np.ndarray:
        """drho_ki/dq_i (m, n), rad/rad^2 (numpy).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            Joint angles, rad.
        """
        q = np.asarray(q, dtype=float)
        out, qp = self._slope_coef[0].copy(), np.ones_like(q)
        for c in self._slope_coef[1:]:
            qp = qp * q
            out = out + c * qp
        return out

    def torque_jacobian(self, q: np.ndarray, tau_m: np.ndarray) -> np.ndarray:
        """d(rho(q)^T tau_m)/dq (n, n), N m/rad: diagonal, each rho_ki depending on q_i alone (numpy).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            Joint angles, rad.
        tau_m : numpy.ndarray, shape (m,)
            Motor torques, N m.
        """
        return np.diag(np.asarray(tau_m, dtype=float) @ self.slope(q))

    @property
    def shape(self) -> tuple[int, int]:
        """(m, n), S's."""
        return self.S.shape

    def rate_product(self, q: Any, v: Any, xp: Any = np) -> Any:
        """(drho/dt) qd, (m,): sum_i rho'_ki(q_i) qd_i^2, rad/s^2 (the rotor's acceleration that qdd does not
        give).

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,)
            Joint angles, rad.
        v : numpy.ndarray or casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        v2 = v * v
        if xp is np:
            out, qp = self._slope_coef[0] @ v2, np.ones_like(v2)
            for c in self._slope_coef[1:]:
                qp = qp * q
                out = out + c @ (qp * v2)
            return out
        out, qp = xp.mtimes(_sparse(self._slope_coef[0], xp), v2), 1
        for c in self._slope_coef[1:]:
            qp = qp * q
            out = out + xp.mtimes(_sparse(c, xp), qp * v2)
        return out


def ratio_zero(curve: RatioCurve, lower: np.ndarray, upper: np.ndarray) -> tuple[int, int, float] | None:
    """The first ratio of ``curve`` that is 0 inside its joint's range.

    Parameters
    ----------
    curve : RatioCurve
        The ratios rho(q) (m, n).
    lower, upper : ndarray
        (n,) the joints' limits, rad.

    Returns
    -------
    tuple of (int, int, float) or None
        Where rho_ki(q_i) = 0 with lower_i <= q_i <= upper_i (a real root of its polynomial).
    """
    for k, i in zip(*np.nonzero(curve.S)):  # a loop over the tendon's crossings (a few)
        roots = np.polynomial.polynomial.polyroots(np.r_[curve.S[k, i], curve.C[:, k, i]])
        real = roots.real[np.abs(roots.imag) <= 1e-9 * np.maximum(1.0, np.abs(roots.real))]
        inside = real[(real >= lower[i]) & (real <= upper[i])]
        if inside.size:
            return int(k), int(i), float(inside.min())
    return None


def check_ratio_range(transmission: Any, lower: np.ndarray, upper: np.ndarray, joint_names: Any) -> None:
    """:class:`~alpes_dyn.errors.ModelError` naming the motor and the joint where a ratio curve crosses 0 inside the
    joint's range (a moment arm of 0 there: the tendon would not move the joint, as a constant ratio of 0 is refused).

    Parameters
    ----------
    transmission : Transmission or None
        The model's transmission (nothing checked without a ratio curve).
    lower, upper : ndarray
        (n,) the joints' limits, rad.
    joint_names : sequence of str
        The joints' names.
    """
    curve = None if transmission is None else transmission.curve
    if curve is None or np.shape(lower) != (curve.S.shape[1],):
        return
    zero = ratio_zero(curve, np.asarray(lower), np.asarray(upper))
    if zero is not None:
        k, i, q = zero
        raise ModelError(f"motor {transmission.motor_names[k]!r}.ratio_curve.{joint_names[i]}: the ratio is 0 at q = "
                         f"{q:.4g} rad, inside the joint's range [{lower[i]:g}, {upper[i]:g}] rad (a moment arm of 0: "
                         "the tendon would not drive the joint there)")


def encoder_angles(enc: "np.ndarray | RatioCurve", q: np.ndarray) -> np.ndarray:
    """The motor angles (..., m), rad, of joint angles q (..., n): S q for a constant S (m, n), s(q) for a
    :class:`RatioCurve` (the fit's encoder map, either form).

    Parameters
    ----------
    enc : numpy.ndarray, shape (m, n), or RatioCurve
        The encoder map: a constant S (rad/rad) or a :class:`RatioCurve`.
    q : numpy.ndarray, shape (..., n)
        Joint angles, rad (for a constant S also (s, k, n)).
    """
    if isinstance(enc, np.ndarray):  # (the fit's own forms, so that constant ratios give the same bits as before)
        return np.einsum("ij,skj->ski", enc, q) if q.ndim == 3 else q @ enc.T
    return enc.angle(q)


def encoder_rates(enc: "np.ndarray | RatioCurve", q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The motor velocities (..., m), rad/s: S v, or rho(q) v.

    Parameters
    ----------
    enc : numpy.ndarray, shape (m, n), or RatioCurve
        The encoder map: a constant S (rad/rad) or a :class:`RatioCurve`.
    q : numpy.ndarray, shape (..., n)
        Joint angles, rad (unused for a constant S).
    v : numpy.ndarray, shape (..., n)
        Joint velocities, rad/s.
    """
    return v @ enc.T if isinstance(enc, np.ndarray) else np.einsum("...ij,...j->...i", enc.ratio(q), v)


def encoder_sensitivity(enc: "np.ndarray | RatioCurve", q: np.ndarray, X: np.ndarray) -> np.ndarray:
    """The motor angles' sensitivities (..., m, d) from the joint angles' X (..., n, d) at q (..., n): S X, or
    rho(q) X.

    Parameters
    ----------
    enc : numpy.ndarray, shape (m, n), or RatioCurve
        The encoder map: a constant S (rad/rad) or a :class:`RatioCurve`.
    q : numpy.ndarray, shape (..., n)
        Joint angles, rad (unused for a constant S).
    X : numpy.ndarray, shape (..., n, d)
        The joint angles' sensitivities to d quantities.
    """
    if isinstance(enc, np.ndarray):
        return np.einsum({4: "ij,skjd->skid", 3: "ij,kjd->kid"}.get(X.ndim, "ij,...jd->...id"), enc, X)
    return np.einsum("...ij,...jd->...id", enc.ratio(q), X)


def fit_ratio_curve(q: Any, ratio: Any, degree: int) -> tuple[np.ndarray, float]:
    """A measured ratio curve as the spec's form: least squares of rho(q) = c_0 + c_1 q + ... + c_P q^P on samples
    (q (N,) rad, ratio (N,) rad/rad: a moment arm over the motor pulley's radius, r_i(q_i) / r_m), P = ``degree``
    (1 .. :data:`MAX_CURVE_DEGREE`). Returns (c (P + 1,) with c_0 the spec's ``joints`` ratio and c_1.. its
    ``ratio_curve``, the largest |error| of the fit on the samples, rad/rad).

    Parameters
    ----------
    q : array_like, shape (N,)
        The joint angles sampled, rad.
    ratio : array_like, shape (N,)
        The ratio measured there, rad/rad.
    degree : int
        P, in 1 .. :data:`MAX_CURVE_DEGREE`.

    Returns
    -------
    tuple of (numpy.ndarray, float)
        c, shape (P + 1,), and the fit's largest |error| on the samples, rad/rad.

    Raises
    ------
    InputError
        A bad degree, or samples not finite, of unequal lengths or too few (at most ``degree``).
    """
    q, r = np.asarray(q, dtype=float).ravel(), np.asarray(ratio, dtype=float).ravel()
    if isinstance(degree, bool) or not isinstance(degree, (int, np.integer)) or not 1 <= degree <= MAX_CURVE_DEGREE:
        raise InputError(f"degree: expected an integer in 1..{MAX_CURVE_DEGREE}, got {degree!r}")
    if q.shape != r.shape or q.size <= degree or not (np.isfinite(q).all() and np.isfinite(r).all()):
        raise InputError(f"q, ratio: expected as many finite samples, more than degree = {degree}, got {q.size} "
                         f"and {r.size}")
    c = np.polynomial.polynomial.polyfit(q, r, degree)
    return c, float(np.max(np.abs(np.polynomial.polynomial.polyval(q, c) - r)))
