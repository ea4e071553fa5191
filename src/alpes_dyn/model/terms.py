"""The terms of eq. 2.10 on a built :class:`~alpes_dyn.model.robot.Model`, its forward and inverse dynamics and its
static balance (eq. 2.11).

    (A(q) + I_a) qdd + C(q, qd) qd + F_v qd + f_s + G(q) = Gamma + J^T F            (eq. 2.10)

A mixin of :class:`~alpes_dyn.model.robot.Model` (one concept: what the equation's terms are at a state and how it
is solved for qdd, for Gamma or for a rest q); it reads the model's ``pin_model``, ``pin_data``, ``n``, ``extras``,
``transmission``, ``mimic``, ``rotor_matrix``, the caches :meth:`Model.__init__
<alpes_dyn.model.robot.Model>` sets (``_spring``, ``_friction``, ``_rotor*``, ``_dense``, ``_k``, ``_lower``,
``_shape``, ``_tiny``), its argument check :meth:`~alpes_dyn.model.robot.Model.vector`, and the contact torque of
:class:`~alpes_dyn.model.frames.FrameKinematics`.

Every vector is a 1-D float array of length ``n`` (joints in ``Model.joint_names`` order), in SI units (rad, rad/s,
rad/s^2, N m, N); a vector of another shape, NaN, inf or an entry over
:data:`~alpes_dyn.limits.MAX_HOT_MAGNITUDE` raises :class:`~alpes_dyn.errors.InputError` naming the argument.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pinocchio as pin
from scipy.linalg import lapack as _lapack

from ..limits import _NRM2, MAX_HOT_MAGNITUDE
from ..errors import InputError
from .robot_checks import newton_equilibrium

__all__ = ["DynamicsTerms"]

_F64 = np.dtype(np.float64)
_ND = np.ndarray
_aba = pin.aba
_crba = pin.crba
_nle = pin.nonLinearEffects
_potrf, _potrs = _lapack.dpotrf, _lapack.dpotrs
_chol_decompose, _chol_solve = pin.cholesky.decompose, pin.cholesky.solve
_isfinite = math.isfinite
_HOT = MAX_HOT_MAGNITUDE
_INF = math.inf


class DynamicsTerms:
    """A(q) + I_a, C, G, the friction and the energies of eq. 2.10; forward and inverse dynamics; the static balance
    of eq. 2.11 (mixed into :class:`~alpes_dyn.model.robot.Model`)."""

    def inertia_matrix(self, q: np.ndarray) -> np.ndarray:
        """The inertia matrix A(q) + I_a (eq. 2.3, 2.8), by CRBA.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.

        Returns
        -------
        numpy.ndarray
            (n, n) symmetric positive definite, kg m^2: A(q), the joint-side ``armature`` on the diagonal and the
            rotors' S^T diag(J_m) S (:attr:`~alpes_dyn.model.robot.Model.rotor_matrix`; rho(q)^T diag(J_m) rho(q)
            where the ratios change with q).

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        """
        q = self.vector(q, "q")
        R = self.transmission.rotor_matrix_at(q) if self._rotor_curved else self.rotor_matrix
        if self.mimic is not None:  # (Pinocchio's CRBA on a mimic model is right on its first call only)
            M = self.mimic.mass_matrix(q)
            M[np.diag_indices(self.n)] += self.pin_model.armature
            return M + R if self._rotor else M
        M = pin.crba(self.pin_model, self.pin_data, q).copy()
        M[self._lower] = M.T[self._lower]  # CRBA fills the upper triangle
        if self._rotor:
            M += R
        return M

    def coriolis_matrix(self, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The Coriolis matrix C(q, qd) of eq. 2.4-2.5, Christoffel-consistent (A_dot - 2C skew-symmetric).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        v : array_like
            Joint velocities qd (n,), rad/s.

        Returns
        -------
        numpy.ndarray
            (n, n), N m s: C qd are the Coriolis and centrifugal torques.

        Raises
        ------
        InputError
            ``q`` or ``v`` not (n,) finite numbers below 2^40.
        """
        q, v = self.vector(q, "q"), self.vector(v, "v")
        if self.mimic is not None:
            return self.mimic.coriolis_matrix(q, v)
        return pin.computeCoriolisMatrix(self.pin_model, self.pin_data, q, v).copy()

    def spring_torque(self, q: np.ndarray) -> np.ndarray:
        """The springs' torques k (q - q_rest) (eq. 2.14 under the model's spring law).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.

        Returns
        -------
        numpy.ndarray
            (n,), N m; q_rest the rest angles, 0 unless the spec's ``[rest_angle]`` gives them.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        """
        return self.extras.spring_torque(self.vector(q, "q"))

    def gravity_torque(self, q: np.ndarray) -> np.ndarray:
        """G(q) of eq. 2.11: the gravity torques plus the springs'.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.

        Returns
        -------
        numpy.ndarray
            (n,), N m.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        """
        q = self.vector(q, "q")
        g = pin.computeGeneralizedGravity(self.pin_model, self.pin_data, q)
        return g + self.extras.spring_torque(q) if self._spring else g.copy()

    def gravity_jacobian(self, q: np.ndarray) -> np.ndarray:
        """dG/dq of eq. 2.11: Pinocchio's analytic gravity derivatives plus the spring stiffness diag(k).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.

        Returns
        -------
        numpy.ndarray
            (n, n), N m/rad.

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        """
        q = self.vector(q, "q")
        if self.mimic is not None:
            dG = self.mimic.gravity_jacobian(q)
        else:
            dG = pin.computeGeneralizedGravityDerivatives(self.pin_model, self.pin_data, q).copy()
        dG[np.diag_indices(self.n)] += self._k
        return dG

    def friction_torque(self, v: np.ndarray, smooth: bool = False) -> np.ndarray:
        """The joint friction F_v qd + f_s of eq. 2.6-2.7.

        Parameters
        ----------
        v : array_like
            Joint velocities qd (n,), rad/s.
        smooth : bool
            Replace sign(qd) by tanh(qd / v_s) (v_s the extras' ``smooth_velocity``, rad/s); default False.

        Returns
        -------
        numpy.ndarray
            (n,), N m.

        Raises
        ------
        InputError
            ``v`` not (n,) finite numbers below 2^40.
        """
        return self.extras.friction_torque(self.vector(v, "v"), smooth)

    def kinetic_energy(self, q: np.ndarray, v: np.ndarray) -> float:
        """E = 1/2 qd^T (A(q) + I_a) qd (eq. 2.3).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        v : array_like
            Joint velocities qd (n,), rad/s.

        Returns
        -------
        float
            The kinetic energy, J.

        Raises
        ------
        InputError
            ``q`` or ``v`` not (n,) finite numbers below 2^40.
        """
        v = self.vector(v, "v")
        return 0.5 * float(v @ self.inertia_matrix(q) @ v)

    def potential_energy(self, q: np.ndarray) -> float:
        """U of eq. 2.2: the gravity's and the springs' potential energy.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.

        Returns
        -------
        float
            U, J: zero at the base height and with every spring at its rest angle (its gradient is G(q), eq. 2.11).

        Raises
        ------
        InputError
            ``q`` not (n,) finite numbers below 2^40.
        """
        q = self.vector(q, "q")
        u = self.mimic.potential_energy(q) if self.mimic else pin.computePotentialEnergy(self.pin_model, self.pin_data, q)
        return float(u) + float(self.extras.spring_energy(q))

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray, F: object = None,
                         tip: str | None = None, smooth: bool = False, contacts: Any = None) -> np.ndarray:
        """The joint accelerations qdd that solve eq. 2.10 (ABA + extras).

        With rotor inertia on the tendons (:attr:`~alpes_dyn.model.robot.Model.rotor_matrix` non-zero; ABA takes
        only a diagonal armature), or mimic joints (Pinocchio's ABA refuses them): CRBA + S^T diag(J_m) S, the bias
        by RNEA at zero acceleration, a Cholesky solve. With ratios that change with q (the transmission's
        ``ratio_curve``) the rotors' rho(q)^T diag(J_m) rho(q) and their velocity product
        (:meth:`~alpes_dyn.model.transmission.Transmission.rotor_bias`). This is the hot path: float64 arrays of
        the right shape skip conversion, every entry checked finite and below
        :data:`~alpes_dyn.limits.MAX_HOT_MAGNITUDE` (2^40: beyond it an angle's sine is noise) with one BLAS norm
        per vector.

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        v : array_like
            Joint velocities qd (n,), rad/s.
        tau : array_like
            Joint torques Gamma (n,), N m.
        F : float, array_like or dict, optional
            Contact force at ``tip``, N, base axes (eq. 2.9): a scalar is F_z (eq. 2.13), else (3,); or the stacked
            forces/wrenches of ``contacts``; or a dict {frame: force (3,) or wrench (6,)}
            (:meth:`~alpes_dyn.model.frames.FrameKinematics.contact_torque`). Default: none.
        tip : str, optional
            The frame F acts at (default: the model's default tip).
        smooth : bool
            Friction's sign as tanh(qd / v_s) (eq. 2.6-2.7 smoothed); default False.
        contacts : sequence of Contact or str, optional
            Several contact frames, F their stacked forces/wrenches.

        Returns
        -------
        numpy.ndarray
            qdd (n,), rad/s^2.

        Raises
        ------
        InputError
            An input not of its shape, NaN, inf or over 2^40 (named), or accelerations that overflowed.
        ModelError
            An unknown ``tip`` or contact frame.
        """
        if not (q.__class__ is _ND and v.__class__ is _ND and tau.__class__ is _ND and q.dtype is _F64
                and v.dtype is _F64 and tau.dtype is _F64 and q.shape == v.shape == tau.shape == self._shape
                and _NRM2(q) < _HOT and _NRM2(v) < _HOT and _NRM2(tau) < _HOT):
            q, v, tau = self.vector(q, "q"), self.vector(v, "v"), self.vector(tau, "tau")
        if self._spring:
            tau = tau - self.extras.spring_torque(q)
        if self._friction:
            tau = tau - self.extras.friction_torque(v, smooth)
        if F is not None:
            tau = tau + self.contact_torque(q, F, tip, contacts)
        if self._dense:
            qdd = self._rotor_solve(q, v, tau)
        else:
            qdd = _aba(self.pin_model, self.pin_data, q, v, tau)
        if not _NRM2(qdd) < _INF and not np.isfinite(qdd).all():  # (inputs checked: an overflow inside)
            raise InputError("forward dynamics gave non-finite accelerations (inputs too large?)")
        return qdd

    def _rotor_solve(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """(A(q) + armature + S^T J_m S)^-1 (tau - C qd - gravity), CRBA and a Cholesky solve.

        Where every tendon runs along one branch of the tree (each pair of joints it couples is an
        ancestor and a descendant: the Alpes chains), the rotors' matrix has the tree's sparsity and
        Pinocchio's sparse Cholesky of ``data.M`` solves it (1.6x ABA on the hand); otherwise LAPACK's
        dense ``dpotrf``/``dpotrs`` on the upper triangle. NaN where the factorisation fails (a
        non-finite input: the caller's finiteness check names it).
        """
        pm, pd = self.pin_model, self.pin_data
        if self._rotor_curved:  # the rotors' velocity product (drho/dt) qd on the joints
            tau = tau - self.transmission.rotor_bias(q, v)
        if self.mimic is not None:  # the whole tree's CRBA, projected (mimic.MimicCoupling.mass_matrix)
            b = tau - _nle(pm, pd, q, v)
            if not _isfinite(b.dot(self._tiny)):
                return np.full(self.n, np.nan)
            c, info = _potrf(self.inertia_matrix(q), lower=0, clean=0, overwrite_a=1)
            return _potrs(c, b)[0] if info == 0 else np.full(self.n, np.nan)
        _crba(pm, pd, q)
        b = tau - _nle(pm, pd, q, v)
        if not _isfinite(b.dot(self._tiny)):  # a non-finite input: NaN out, no solve of inf (no numpy warning)
            return np.full(self.n, np.nan)
        if self._rotor_tree:
            M = pd.M
            M += self._rotor_upper  # in place: Pinocchio's factorisation reads data.M's upper triangle
            _chol_decompose(pm, pd)
            return _chol_solve(pm, pd, b)
        R = self.transmission.rotor_matrix_at(q) if self._rotor_curved else self.rotor_matrix
        c, info = _potrf(pd.M + R, lower=0, clean=0, overwrite_a=1)
        if info != 0:
            return np.full(self.n, np.nan)
        return _potrs(c, b)[0]

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray, F: object = None,
                         tip: str | None = None, smooth: bool = False, contacts: Any = None) -> np.ndarray:
        """The joint torques Gamma that produce the accelerations ``a`` (eq. 2.10 solved for Gamma; RNEA + extras).

        Parameters
        ----------
        q : array_like
            Joint angles (n,), rad.
        v : array_like
            Joint velocities qd (n,), rad/s.
        a : array_like
            Joint accelerations qdd (n,), rad/s^2.
        F : float, array_like or dict, optional
            Contact force(s), N, as in :meth:`forward_dynamics` (J^T F subtracted, eq. 2.9); default none.
        tip : str, optional
            The frame F acts at (default: the model's default tip).
        smooth : bool
            Friction's sign as tanh(qd / v_s); default False.
        contacts : sequence of Contact or str, optional
            Several contact frames, F their stacked forces/wrenches.

        Returns
        -------
        numpy.ndarray
            Gamma (n,), N m.

        Raises
        ------
        InputError
            An input not of its shape, NaN, inf or over 2^40 (named).
        ModelError
            An unknown ``tip`` or contact frame.
        """
        q, v, a = self.vector(q, "q"), self.vector(v, "v"), self.vector(a, "a")
        tau = pin.rnea(self.pin_model, self.pin_data, q, v, a).copy()
        if self._rotor_curved:
            tau += self.transmission.rotor_matrix_at(q) @ a + self.transmission.rotor_bias(q, v)
        elif self._rotor:
            tau += self.rotor_matrix @ a
        if self._spring:
            tau += self.extras.spring_torque(q)
        if self._friction:
            tau += self.extras.friction_torque(v, smooth)
        if F is not None:
            tau -= self.contact_torque(q, F, tip, contacts)
        return tau

    def static_equilibrium(self, tau: np.ndarray | None, q0: np.ndarray | None = None, tol: float = 1e-12,
                           fixed: Sequence[str] = (), tau_m: np.ndarray | None = None) -> np.ndarray:
        """The joint angles where gravity and springs balance the joint torques: G(q) = tau (eq. 2.11 at rest).

        Newton's method from ``q0`` with the analytic Jacobian of G (:meth:`gravity_jacobian`), at most 0.5 rad per
        step (:func:`~alpes_dyn.model.robot_checks.newton_equilibrium`).

        Parameters
        ----------
        tau : array_like or None
            Joint torques (n,), N m; None: zero.
        q0 : array_like, optional
            Start (n,), rad (default 0); the held joints' angles.
        tol : float
            Stop when max |G(q) - tau| < ``tol``, N m (default 1e-12).
        fixed : sequence of str or str
            Joint names held at their ``q0`` values (e.g. a joint without spring that its own motor holds, the
            thumb's ab/adduction): the balance is solved on the other joints only.
        tau_m : array_like, optional
            Motor torques (m,), N m, added as S^T tau_m, or rho(q)^T tau_m where the ratios change with q (its
            Jacobian diag(tau_m . drho/dq) then in Newton's).

        Returns
        -------
        numpy.ndarray
            q (n,), rad.

        Raises
        ------
        InputError
            ``tau`` or ``q0`` not (n,) finite numbers, a singular stiffness, or no convergence in 50 iterations.
        ModelError
            An unknown joint in ``fixed``.
        """
        tau = np.zeros(self.n) if tau is None else self.vector(tau, "tau")
        tr, curve = self.transmission, None
        if tau_m is not None:
            tau_m = np.atleast_1d(np.asarray(tau_m, dtype=float))
            if tr.curved:
                curve = tr.curve
            else:
                tau = tau + tr.joint_torque(tau_m)

        def res(q: np.ndarray) -> np.ndarray:
            return self.gravity_torque(q) - tau if curve is None else self.gravity_torque(q) - tau - curve.ratio(q).T @ tau_m

        def jac(q: np.ndarray) -> np.ndarray:
            return self.gravity_jacobian(q) if curve is None else self.gravity_jacobian(q) - curve.torque_jacobian(q, tau_m)
        q0 = np.zeros(self.n) if q0 is None else self.vector(q0, "q0")
        if isinstance(fixed, str):
            fixed = (fixed,)
        held = [self.joint_index(j) for j in fixed]
        if not held:
            return newton_equilibrium(res, jac, q0, tol)
        free = np.setdiff1d(np.arange(self.n), held)
        if free.size == 0:
            return q0.copy()

        def full(qf: np.ndarray) -> np.ndarray:
            q = q0.copy()
            q[free] = qf
            return q

        qf = newton_equilibrium(lambda qf: res(full(qf))[free], lambda qf: jac(full(qf))[np.ix_(free, free)],
                                q0[free], tol)
        return full(qf)
