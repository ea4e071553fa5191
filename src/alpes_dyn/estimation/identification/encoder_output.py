"""The encoder's reading in the fit of :mod:`alpes_dyn.estimation.identification.shooting`: y_k = S q_k + offset +
C (u_k-1 - J_m S qdd) (the encoder offsets, the tendons' stretch under their tension; eq. 3.13 and
:meth:`Transmission.encoder_angles <alpes_dyn.model.transmission.Transmission.encoder_angles>`, the one definition
our own experiment records with). :class:`EncoderOutput` is the part of
:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem` that maps its parameters and states to it.
"""

from __future__ import annotations

import numpy as np

from ...model.transmission import acceleration_before

__all__ = ["EncoderOutput"]


class EncoderOutput:
    """The encoder output's terms, for a problem that has ``ny`` (motors), ``n`` (joints), ``dt`` (s), ``S_enc``
    (m, n), ``off_cols`` and ``comp_cols`` ((index in theta, motor) of the encoder offsets and tendon compliances)
    and ``rotor`` ((m,) J_m, kg m^2, or None: no rotor's share in the stretch)."""

    ny: int
    n: int
    dt: float
    S_enc: np.ndarray
    off_cols: list[tuple[int, int]]
    comp_cols: list[tuple[int, int]]
    rotor: np.ndarray | None

    def per_motor(self, theta: np.ndarray, cols: list[tuple[int, int]]) -> np.ndarray:
        """(m,) the entries ``cols`` (index in theta, motor) of theta on their motors, 0 elsewhere.

        Parameters
        ----------
        theta : numpy.ndarray, shape (p,)
            The fitted parameters, in the fit's units.
        cols : list[tuple[int, int]]
            (index in theta, motor index) pairs.

        Returns
        -------
        numpy.ndarray, shape (m,)
            The entries on their motors (summed where a motor has several).
        """
        out = np.zeros(self.ny)
        for k, mo in cols:
            out[mo] += theta[k]
        return out

    def offset(self, theta: np.ndarray) -> np.ndarray:
        """(m,) the encoder offsets, rad.

        Parameters
        ----------
        theta : numpy.ndarray, shape (p,)
            The fitted parameters, in the fit's units.

        Returns
        -------
        numpy.ndarray, shape (m,)
            The offsets, rad (0 for a motor without one).
        """
        return self.per_motor(theta, self.off_cols)

    def compliance(self, theta: np.ndarray) -> np.ndarray:
        """(m,) the tendon compliances, rad / (N m).

        Parameters
        ----------
        theta : numpy.ndarray, shape (p,)
            The fitted parameters, in the fit's units.

        Returns
        -------
        numpy.ndarray, shape (m,)
            The compliances, rad / (N m) (0 for a motor without one).
        """
        return self.per_motor(theta, self.comp_cols)

    def stretch(self, theta: np.ndarray, u_k: np.ndarray | None) -> np.ndarray | float:
        """(S, L+1, m) the tendons' stretch C u seen by the encoders, rad, for the modelled torque u_k-1
        (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.torque_at`; None without compliance: 0).

        Parameters
        ----------
        theta : numpy.ndarray, shape (p,)
            The fitted parameters, in the fit's units.
        u_k : numpy.ndarray, shape (S, L+1, m), or None
            The modelled torque before each sample, N m (None: no compliance fitted).

        Returns
        -------
        numpy.ndarray, shape (S, L+1, m), or float
            The stretch, rad (0.0 for ``u_k`` None).
        """
        return 0.0 if u_k is None else u_k * self.compliance(theta)

    def motor_acceleration(self, qd: np.ndarray) -> np.ndarray:
        """(s, L+1, m[, d]) the motors' acceleration S qdd over the period before each sample, rad/s^2, from the
        joint velocities qd (s, L+1, n[, d]) of each interval's samples (or their sensitivities, d columns):
        S (qd_k - qd_k-1) / dt; an interval's first sample takes its first period's (its own interval's states
        only: the Jacobian keeps its block structure).

        Parameters
        ----------
        qd : numpy.ndarray, shape (s, L+1, n) or (s, L+1, n, d)
            The joint velocities, rad/s, at each interval's samples (or their sensitivities).

        Returns
        -------
        numpy.ndarray, shape (s, L+1, m) or (s, L+1, m, d)
            The motors' acceleration, rad/s^2.
        """
        return np.einsum("ij,skj...->ski...", self.S_enc, acceleration_before(qd, self.dt, axis=1))

    def tension_torque(self, u_k: np.ndarray | None, xs: np.ndarray) -> np.ndarray | None:
        """(s, L+1, m) the torque that the tendon's tension balances at each sample, N m: the modelled torque u_k-1
        (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.torque_at`) less what accelerates the
        rotor, J_m S qdd (:meth:`motor_acceleration`; xs (s, L+1, nx) the states), where the model has a rotor and a
        compliance (else u_k itself). Why: the cable is stretched by its tension, r_m T = tau_m - J_m qdd_m, not by
        the motor's torque; the stretch taken from the motor's torque leaves an encoder error that biases the fitted
        masses, friction and the EKF on the identified file (MuJoCo's elastic tendon with its rotor,
        ``benchmarks/realism.py``'s cable).

        Parameters
        ----------
        u_k : numpy.ndarray, shape (s, L+1, m), or None
            The modelled torque before each sample, N m (None: passed through).
        xs : numpy.ndarray, shape (s, L+1, nx)
            The states [q; qd] at each interval's samples (rad, rad/s).

        Returns
        -------
        numpy.ndarray, shape (s, L+1, m), or None
            The torque the tension balances, N m (``u_k`` itself without a rotor).
        """
        if self.rotor is None or u_k is None:
            return u_k
        return u_k - self.rotor * self.motor_acceleration(xs[..., self.n: 2 * self.n])
