"""The multiple-shooting output-error problem of :func:`~alpes_dyn.estimation.identification.identification.identify`.

A recording of N samples is cut into S intervals of L samples; the unknowns are each interval's start state s_j
(and, with a constant torque correction per interval, that correction: ``nb`` local variables per interval) and
``ng`` global ones: the parameters rho (log theta / theta_0; the additive ones, encoder offsets and tilt angles, as
(theta - theta_0) / scale) and, with the excitation's lines, the whitened line-coefficient corrections c of the
torque. The problem is

    min  1/2 |r(s, rho, c)|^2 + 1/2 |c|^2    subject to  s_j+1 = x(end of interval j; s_j, rho, c),

with r the encoder residuals (S q_k + offset + C u_k-1 - y_k) / sigma_y (Section 3, eq. 3.13; C the tendon's
compliance, u_k-1 the torque held before the sample: :func:`~alpes_dyn.model.transmission.torque_before`, less
J_m S qdd where the model has a rotor:
:meth:`~alpes_dyn.estimation.identification.encoder_output.EncoderOutput.tension_torque`),
the camera's (q - q_meas) / sigma_q where the recording has joint angles, and the per-interval corrections' prior.
:class:`ShootingProblem` holds the data cut at the intervals and evaluates r, the continuity defects and their
Jacobians from the compiled sensitivities
(:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`), and the Gauss-Newton normal and KKT matrices of
:mod:`alpes_dyn.estimation.identification.kkt` (its part :mod:`~alpes_dyn.estimation.identification.shooting_algebra`;
a long record's Jacobian held compact: :mod:`~alpes_dyn.estimation.identification.normal_blocks`). It knows nothing of how the problem is solved: that is
:mod:`alpes_dyn.estimation.identification.gauss_newton`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Mapping

import numpy as np

from ...errors import InputError, ModelError
from ...model.robot import Model
from ...model.ratio_curve import encoder_angles, encoder_sensitivity
from ...simulation.sensitivity import SensitivityModel
from .encoder_output import EncoderOutput
from .shooting_algebra import Evaluation, ShootingAlgebra
from .torque_lines import CHOLESKY_QR_ROWS, TorqueModel, _thin_qr, line_basis, torque_model  # noqa: F401
from .held import ShootingSolution, start_values  # noqa: F401  (re-exported: their home before)
from .kkt import Shape
from ..experiments.recording import Recording
from .runs import run_cuts
from . import normal_blocks
from .normal_blocks import NormalBlocks
from .drift import GAIN_NEEDS_LINES, check_drift, drift_basis, gain_sensitivity, line_coefficients, recorded_time

__all__ = ["TorqueModel", "torque_model", "ShootingProblem", "Evaluation", "ShootingSolution",
           "JACOBIAN_CHUNK", "FitDiverged", "FitSingular"]


class FitDiverged(InputError):
    """A fit's parameters or states overflowed to NaN or inf (:meth:`ShootingProblem.evaluate`): a trial step that
    makes them is refused by the solver (:mod:`~alpes_dyn.estimation.identification.gauss_newton`), a round whose fit
    runs away is a failed round (:class:`~alpes_dyn.estimation.identification.effects.RoundWalker`); raised out of
    :func:`~alpes_dyn.estimation.identification.identification.identify` where no step was left to refuse."""


class FitSingular(FitDiverged):
    """A fit whose linear system is singular where no least-squares fallback solves it (a sparse system of more
    than :data:`~alpes_dyn.estimation.identification.kkt.DENSE_LIMIT` rows: a state or parameter the recording does
    not see, e.g. a LuGre bristle deflection relaxed within an interval of a long or joined record): a failed round
    like a fit that ran away (:class:`~alpes_dyn.estimation.identification.effects.RoundWalker`), an InputError out of
    :func:`~alpes_dyn.estimation.identification.identification.identify`, never an internal error."""


JACOBIAN_CHUNK = 2**20
"""Doubles of sensitivities (8 MiB) computed at a time by :meth:`ShootingProblem.evaluate`: the intervals in
chunks of at most this many, each reduced to its rows of the Jacobian before the next (a 4 s record at 50 ms is
two chunks); the states alone likewise, by the compiled step's per-sample inputs."""


class ShootingProblem(EncoderOutput, ShootingAlgebra):
    """The fit of ``sens``' parameters to a recording by multiple shooting at ``L`` samples per interval.

    Parameters
    ----------
    model : Model
        The finger (:class:`~alpes_dyn.model.robot.Model`; its transmission reads the encoder).
    rec : Recording
        The recording (:class:`~alpes_dyn.estimation.experiments.recording.Recording`): encoder counts, torques
        N m, joint angles rad where recorded. A recording of several runs (module runs: each run starting on a
        node, see ``runs.aligned``) has no continuity into a run's first interval (``cut``) and each run's own line
        coefficients (``blk``).
    sens : SensitivityModel
        The compiled sensitivities of the selection
        (:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`; with the torque model's correction:
        ``input_offset`` without the lines, ``input_basis`` with).
    L : int
        Samples per interval.
    torque : TorqueModel
        The torque's model, :func:`torque_model`.
    camera_noise : float
        sigma_q, rad: the camera's joint-angle noise.
    start : Mapping[str, float] or None, optional
        Starting values by parameter name (default None: the rest, all, the model's).
    dense : bool, optional
        True: the KKT matrices as arrays (the reference) instead of sparse (default False).
    structured : bool, optional
        True (default): the sparse matrices factorised by their band and border (kkt.bordered_factorize); False:
        by SuperLU (the general sparse LU, the reference the structured one is tested against).
    drift : str or None, optional
        ``"offset"``, ``"gain"`` or both (:func:`~alpes_dyn.estimation.identification.drift.check_drift`; default
        None: neither): the encoders' offset drift (``nd_off`` knots' values, counts) and the torque constants'
        relative drift (``nd_gain``) fitted too (module drift), after the line corrections in ``glob``.

    Raises
    ------
    InputError
        The gain's drift without the excitation's lines.
    ModelError
        A fitted multiplicative parameter whose starting value is not positive.

    Notes
    -----
    The unknowns are ``nodes`` (S, nx), ``offs`` (S, no) and ``glob`` (ng,): theta's (p), the line corrections (ncg),
    the drift's (nd); :meth:`values` maps ``glob`` to theta.
    """

    def __init__(self, model: Model, rec: Recording, sens: SensitivityModel, L: int, torque: TorqueModel,
                 camera_noise: float, start: Mapping[str, float] | None = None, dense: bool = False,
                 structured: bool = True, drift: str | None = None) -> None:
        self.model, self.rec, self.sens, self.L, self.torque = model, rec, sens, L, torque
        self.camera_noise = camera_noise
        self.nx, self.p, self.nu, self.n = sens.nx, sens.p, sens.nu, sens.n
        eiv, lines = torque.eiv, torque.lines
        self.no = sens.no if (eiv and not lines) else 0  # local torque corrections per interval
        self.ncg = sens.no * torque.blocks if lines else 0  # global line-coefficient corrections (every run's)
        self.drift = drift = check_drift(drift)
        if "gain" in drift and not lines:
            raise InputError(GAIN_NEEDS_LINES)
        H = drift_basis(rec) if drift else np.zeros((rec.n_samples, 0))  # (N+1, K): module drift
        self.nK = H.shape[1]
        self.nd_off = np.shape(model.transmission.S)[0] * self.nK if "offset" in drift else 0  # counts
        self.nd_gain = self.nu * self.nK if "gain" in drift else 0  # the torque constants' relative scale
        self.nd = self.nd_off + self.nd_gain
        self.ng = self.p + self.ncg + self.nd  # parameters, line corrections, the drifts' knots
        self.nb = self.nx + self.no  # local variables of an interval: its start state and its torque correction
        tr = model.transmission
        self.S_enc = np.asarray(tr.S, dtype=float)
        self.enc = tr.curve if tr.curved else self.S_enc  # the encoder map: S q, or s(q) on q-dependent ratios
        self.ny = self.S_enc.shape[0]
        self.step = 2 * np.pi / tr.counts_per_rev
        self.y = rec.encoder * self.step  # motor angle, rad
        self.sig_y = self.step / math.sqrt(12.0)
        self.sig_off = torque.noise / math.sqrt(L) if eiv else 1.0  # the mean of L white samples
        N = self.N = rec.n_samples - 1
        self.G = rec.gravity[:-1] if rec.gravity is not None else np.broadcast_to(model.gravity, (N, 3))
        n_int = self.n_int = -(-N // L)
        self.cut, self.before = run_cuts(rec, L, n_int)
        self.blk = np.cumsum(np.r_[0, self.cut]) if torque.blocks > 1 else None  # (S,) each interval's run
        pad = n_int * L - N
        U, nu = torque.U, self.nu
        self.Ub = np.concatenate([U, np.repeat(U[-1:], pad, axis=0)]).reshape(n_int, L, nu)
        self.Gb = (np.concatenate([self.G, np.repeat(self.G[-1:], pad, axis=0)]).reshape(n_int, L, 3)
                   if rec.gravity is not None else np.broadcast_to(model.gravity, (n_int, L, 3)))  # (a view: constant)
        # residual layout per interval: samples j = 0..L-1 (the last interval also its final sample)
        k_idx = np.arange(n_int)[:, None] * L + np.arange(L + 1)[None, :]
        valid = k_idx <= N
        valid[:-1, L] = False  # an interval's end is the next one's start
        self.valid = valid
        self.kk = np.minimum(k_idx, N)
        self.Yb = self.y[self.kk]  # (S, L+1, m)
        self.Qm = rec.q[self.kk] if rec.q is not None else None  # (S, L+1, n) with NaN
        self.q_mask = np.isfinite(self.Qm) & valid[:, :, None] if self.Qm is not None else None
        self._parameters(start)
        self.dt = rec.dt
        J_m = np.asarray(tr.rotor_inertia, dtype=float)
        # the rotor in the stretch (y_k = S q_k + C (u_k-1 - J_m S qdd)): with a compliance and a rotor only
        self.rotor = J_m if (self.comp_cols and np.any(J_m > 0)) else None
        if self.rotor is not None and tr.curved:
            raise ModelError("identify: the rotor's share of the tendon's stretch (a compliance fitted with a rotor) "
                             "is built for constant ratios; this transmission's change with q (ratio_curve)")
        self.Ufull = np.concatenate([U, torque.U_last])  # the modelled torque at every sample, the last one's too
        # the torque each residual's stretch C u is under: the one held over the period before its sample (the
        # cable's tension at t_k has seen u_k-1: model.transmission.torque_before), and the lines' basis with it
        self.Uk = self.Ufull[self.before][self.kk]  # (S, L+1, nu) (torque_before within each run)
        # (torque_before(X)[k] is X[max(k - 1, 0)]: rows of Q alone, one gather, no copy of the whole basis first)
        self.Psib = self.Psi0 = None
        if lines:  # sigma_u Q at the held samples, the last interval padded with the last one's
            QS = np.empty((n_int * L, torque.nphi))
            QS[:N], QS[N:] = torque.Q, torque.Q[-1]
            QS *= torque.noise
            self.Psib = QS.reshape(n_int, L, torque.nphi)  # (S, L, nphi): the basis over each interval's periods
            self.Psi0 = QS[self.before[np.arange(n_int) * L]]  # (S, nphi): over the period before each
            self.Acoef = (line_coefficients(QS[:N], U, np.minimum(rec.run_starts()[:-1], N), self.blk, n_int)
                          if self.nd_gain else None)  # (S, nu, nphi): the gain's direction (module drift)
            torque = dataclasses.replace(torque, Q=None)
        self.torque = torque
        self.shape = Shape(n_int, self.nb, self.nx, self.ng, self.cut)
        self.nv, self.nz, self.nc = self.shape.nv, self.shape.nz, self.shape.nc
        self.prior = np.r_[np.zeros(self.p), np.ones(self.ncg), np.zeros(self.nd)]  # d rg / d glob, squared
        self._drift_bases(H)
        del H
        self.dense, self.structured = dense, structured and not dense
        n_res = (int(valid.sum()) * self.ny + (int(self.q_mask.sum()) if self.q_mask is not None else 0)
                 + n_int * self.no + self.ncg)
        nc_held = self.nc - int(self.cut.sum()) * self.nx  # the constraints that hold (none across a run's start)
        self.dof = max(n_res - (self.nz - nc_held), 1)  # residuals less free variables (constraints count back)
        self.compact = self.jacobian_bytes() > normal_blocks.COMPACT_BYTES  # (module normal_blocks)
        self.unit_p = np.zeros((self.nz + self.nc, self.p))  # right-hand sides that give the parameters' covariance
        self.unit_p[self.nv + np.arange(self.p), np.arange(self.p)] = 1.0

    def jacobian_bytes(self) -> int:
        """Bytes of the residuals' Jacobian J (S, R, nb + ng) in double precision (R: the encoders', the camera's
        where recorded and the torque corrections' residuals per interval)."""
        rows = (self.L + 1) * (self.ny + (self.n if self.Qm is not None else 0)) + self.no
        return self.n_int * rows * (self.nb + self.ng) * 8

    def _drift_bases(self, H: np.ndarray) -> None:
        """The drifts' hat functions (``H`` (N+1, K), module drift) where the fit takes them: at each residual's
        sample in rad per count (the offset's, ``Hb`` (S, L+1, K)), at each interval's middle sample (the gain's,
        ``Hs`` (S, K)), and the samples' recorded time ``tau_k`` (S, L+1) s (the gain's, sample by sample)."""
        self.Hb = H[self.kk] * self.step if self.nd_off else None
        self.Hs = H[self.kk[:, self.L // 2]] if self.nd_gain else None
        self.tau_k = recorded_time(self.rec)[self.kk] if self.nd_gain else None

    def _parameters(self, start: Mapping[str, float] | None) -> None:
        """theta_0, which parameters are additive, their scales and the encoder offsets' and compliances' columns."""
        sens, model, p = self.sens, self.model, self.p
        theta0 = sens.nominal.copy()
        # additive parameters (encoder offsets, tilt angles: nominal 0, either sign) are fitted as they are, the
        # others as log theta / theta_0; the encoder offsets enter the output only (their state sensitivities are 0)
        additive = np.array([pp.additive for pp in sens.dynamics.parameters], dtype=bool)
        if start is not None:
            theta0 = start_values(theta0, sens.names, additive, start)
        self.off_cols = [(k, model.motor_index(pp.motor)) for k, pp in enumerate(sens.dynamics.parameters)
                         if pp.kind == "encoder_offset"]
        # tendon compliances (y_k = S q_k + offset + C u_k-1, u the modelled torque): fitted in units of
        # the recording's own encoder-to-torque scale std(y) / std(u), so that a unit step is of the data's order
        self.comp_cols = [(k, model.motor_index(pp.motor)) for k, pp in enumerate(sens.dynamics.parameters)
                          if pp.kind == "tendon_compliance"]
        scale = np.ones(p)
        for k, mo in self.comp_cols:
            su, sy = float(np.std(self.rec.torque[:, mo])), float(np.std(self.y[:, mo]))
            scale[k] = sy / su if su > 0 and sy > 0 else 1.0
        if np.any((theta0 <= 0) & ~additive):
            bad = sens.names[int(np.argmax((theta0 <= 0) & ~additive))]
            raise ModelError(f"parameters: {bad} has the starting value {theta0[sens.names.index(bad)]:g}; a fitted "
                             "parameter needs a positive starting value (use a model with that term switched on)")
        self.theta0, self.additive, self.scale = theta0, additive, scale

    # --- the parameters and the output ------------------------------------------------------------------------

    def values(self, glob: np.ndarray) -> np.ndarray:
        """theta from the fitted variables: theta_0 exp(rho), or theta_0 + scale rho for the additive ones.

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).

        Returns
        -------
        numpy.ndarray, shape (p,)
            theta, in the parameters' own units (``sens.names``' order).
        """
        p, additive = self.p, self.additive
        return np.where(additive, self.theta0 + self.scale * glob[:p],
                        self.theta0 * np.exp(np.where(additive, 0.0, glob[:p])))

    def _scatter(self, A: np.ndarray, sl: slice) -> np.ndarray:
        """(s, ..., ncg) the last axis of ``A`` (s, ..., w), the intervals ``sl``' own run's block of a quantity
        per line coefficient (w of them per run: its lines' or its coefficients'), laid in that run's place among
        every run's (zero elsewhere); ``A`` itself with one run."""
        if self.blk is None:
            return A
        w = A.shape[-1]
        out = np.zeros(A.shape[:-1] + (w * self.torque.blocks,))
        blk = self.blk[sl]
        for r in np.unique(blk):  # a loop over the runs in these intervals (one or two)
            out[blk == r, ..., r * w:(r + 1) * w] = A[blk == r]
        return out

    def psik(self, sl: slice) -> np.ndarray:
        """(s, L+1, nphi) the lines' basis (times sigma_u) over the period before each residual's sample of the
        intervals ``sl`` (:func:`~alpes_dyn.model.transmission.torque_before`: the first residual's the period
        before the interval, the others' the interval's own).

        Parameters
        ----------
        sl : slice
            The intervals.

        Returns
        -------
        numpy.ndarray, shape (s, L+1, nphi)
            The basis, laid in each interval's run's block where the recording has several runs.
        """
        return self._scatter(np.concatenate([self.Psi0[sl, None], self.Psib[sl]], axis=1), sl)

    def torque_at(self, glob: np.ndarray, offs: np.ndarray, gained: bool = True) -> np.ndarray:
        """(S, L+1, nu) the modelled torque (N m: the measured or projected one plus the fitted correction) that the
        tendons' tension balances at each residual's sample: the one held over the period before it
        (:func:`~alpes_dyn.model.transmission.torque_before`; the per-interval correction of the interval's own);
        times the gain's drift where fitted (:meth:`gain`).

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        gained : bool, optional
            True (default): times the gain's drift where fitted; False: without it.

        Returns
        -------
        numpy.ndarray, shape (S, L+1, nu)
            The torque, N m.
        """
        if self.nd_gain and gained:
            return self.torque_at(glob, offs, False) * self.gain(glob, per_sample=True)
        if self.torque.lines:
            C = self.correction(glob, offs)  # (nu, nphi), or per interval (S, nu, nphi): its run's
            u = self.Uk.copy()
            if C.ndim == 2:  # one run
                u[:, 0] += self.Psi0 @ C.T
                u[:, 1:] += np.einsum("skl,il->ski", self.Psib, C)
            else:
                u[:, 0] += np.einsum("sl,sil->si", self.Psi0, C)
                u[:, 1:] += np.einsum("skl,sil->ski", self.Psib, C)
            return u
        if self.torque.eiv:
            return self.Uk + offs[:, None, :]
        return self.Uk

    def correction(self, glob: np.ndarray, offs: np.ndarray) -> np.ndarray | None:
        """The torque correction the sensitivities take: the line coefficients (nu, nphi), the per-interval
        constants (S, nu), or None.

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).

        Returns
        -------
        numpy.ndarray or None
            The line coefficients (nu, nphi) (with several runs each interval's run's, (S, nu, nphi)), the
            per-interval constants ``offs`` (S, nu), N m, or None without a torque correction.
        """
        if self.torque.lines:
            C = glob[self.p:self.p + self.ncg].reshape(self.torque.nlines, self.nu).T  # (nu, nlines), column-major
            if self.blk is None:
                return C
            return C.reshape(self.nu, self.torque.blocks, -1)[:, self.blk].transpose(1, 0, 2)  # its run's, (S, nu, nphi)
        return offs if self.torque.eiv else None

    def drift_offset(self, glob: np.ndarray, sl: slice = slice(None)) -> np.ndarray | float:
        """(s, L+1, m) rad the encoders' drift at each residual's sample of the intervals ``sl`` (module drift:
        the hat functions times the knots' values, counts, in ``glob`` after the line corrections), or 0.0.

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        sl : slice, optional
            The intervals (default all).

        Returns
        -------
        numpy.ndarray, shape (s, L+1, m), or float
            The drift, or 0.0 without the offset's drift.
        """
        if not self.nd_off:
            return 0.0
        d0 = self.p + self.ncg
        D = glob[d0:d0 + self.nd_off].reshape(self.ny, -1)  # (m, K) counts
        return np.einsum("skK,mK->skm", self.Hb[sl], D)

    def gain(self, glob: np.ndarray, per_sample: bool = False) -> np.ndarray | None:
        """(S, nu) each motor's torque-constant scale at each interval's middle sample, relative to the first
        sample's (module drift: 1 plus the hat functions times the knots' values, the last of ``glob``), or
        ``per_sample`` (S, L+1, nu) at each residual's sample; None without the gain's drift.

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        per_sample : bool, optional
            False (default): at each interval's middle sample, (S, nu); True: at each residual's sample,
            (S, L+1, nu), piecewise linear in the recorded time.

        Returns
        -------
        numpy.ndarray or None
            The scale (dimensionless, 1 at the first sample), or None without the gain's drift.
        """
        if not self.nd_gain:
            return None
        D = glob[self.ng - self.nd_gain:].reshape(self.nu, -1)  # (nu, K)
        if not per_sample:
            return 1.0 + self.Hs @ D.T
        T = float(recorded_time(self.rec)[-1])
        knots = np.linspace(0.0, T, self.nK + 1)
        return 1.0 + np.stack([np.interp(self.tau_k, knots, np.r_[0.0, d]) for d in D], axis=-1)  # (a few motors)

    def inputs(self, glob: np.ndarray, offs: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(the torque per interval (S, L, nu), the correction the sensitivities take: :meth:`correction`) as the
        dynamics see them: with the gain's drift the torque times :meth:`gain` at each sample (piecewise linear in
        time, as drifted) and the correction (per interval, (S, nu, nphi); the noise's size) times its value at the
        interval's middle; else as they are.

        Parameters
        ----------
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).

        Returns
        -------
        torque : numpy.ndarray, shape (S, L, nu)
            The torque per interval, N m.
        correction : numpy.ndarray or None
            :meth:`correction`'s (times the gain at the interval's middle where the gain's drift is fitted).
        """
        corr = self.correction(glob, offs)
        g = self.gain(glob)
        if g is None:
            return self.Ub, corr
        C = np.broadcast_to(corr, (self.n_int,) + corr.shape[-2:]) if corr.ndim == 2 else corr
        return self.Ub * self.gain(glob, per_sample=True)[:, :self.L], C * g[:, :, None]

    def encoder_rms(self, r: np.ndarray) -> float:
        """RMS of the encoder residuals in r, counts.

        Parameters
        ----------
        r : numpy.ndarray, shape (S, R)
            The residuals per interval (the :class:`Evaluation`'s ``r``), whitened: the first (L+1) ny of each
            row the encoders' (divided by sigma_y); those of samples past the record's end zero.

        Returns
        -------
        float
            The RMS over the valid samples and encoders, counts.
        """
        enc = r[:, : (self.L + 1) * self.ny] * self.sig_y / self.step
        return float(np.sqrt(np.sum(enc**2) / max(int(self.valid.sum()) * self.ny, 1)))

    # --- the residuals, the defects and their Jacobians ---------------------------------------------------------

    def evaluate(self, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray, jac: bool | str = True,
                 sink=None) -> Evaluation:
        """The :class:`Evaluation` at (nodes, offs, glob). ``jac=False``: r, c, rg and the states alone (J, Cv, Cr
        None), from the step without its sensitivities (a tenth of the time). ``jac="state"``: J (S, R, nx) and Cv
        (S-1, nx, nx) with respect to the start states alone (Cr None; stage 1's sweeps, theta fixed: the sensitivities of the
        state alone, a third to a fifth of the time of all of them). With them, the intervals go through
        the compiled sensitivities :data:`JACOBIAN_CHUNK` doubles of sensitivities at a time, each chunk reduced to
        its rows of J before the next (the sensitivities of a 60 s record at 100 ms are 180 MB, J a sixth of it).
        Where :attr:`compact` (module normal_blocks), J is not kept: its normal blocks are (``normal``; J None); or
        ``sink(sl, J_c, x_c)`` takes each chunk's rows of J (the intervals ``sl``, their states), J not kept (a pass
        over the Jacobian for its products: :func:`~alpes_dyn.estimation.identification.normal_blocks.remainders`).

        Parameters
        ----------
        nodes : numpy.ndarray, shape (S, nx)
            Each interval's start state s_j ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        jac : bool or str, optional
            True (default): all the Jacobians; False: none; ``"state"``: with respect to the start states alone.
        sink : callable or None, optional
            ``sink(sl, J_c, x_c)`` taking each chunk's rows of J (default None: J kept, or its normal blocks where
            :attr:`compact`).

        Returns
        -------
        Evaluation
            r, J, c, Cv, Cr, rg and the states.

        Raises
        ------
        FitDiverged
            theta or the nodes not finite.
        """
        theta = self.values(glob)
        if not (np.isfinite(theta).all() and np.isfinite(nodes).all()):  # not sens.run's "theta: expected finite"
            raise FitDiverged("identify: the fit diverged (its parameters or states overflowed to NaN or inf)")
        L = self.L
        u_raw = self.torque_at(glob, offs, gained=False) if self.comp_cols else None
        g = self.gain(glob)
        u_k = u_raw * g[:, None, :] if (u_raw is not None and g is not None) else u_raw
        Ub, corr = self.inputs(glob, offs)
        gain = None if g is None else (g, self.Acoef + (np.broadcast_to(self.correction(glob, offs), self.Acoef.shape)),
                                       u_raw)
        def residuals(x: np.ndarray, sl: slice = slice(None)) -> np.ndarray:
            return self._residuals(x, sl, theta, glob, offs, u_k)
        normal = None
        if jac is True and self.compact and sink is None:
            normal = NormalBlocks.empty(self.n_int, self.nb, self.ng)

            def sink(sl: slice, J_c: np.ndarray, x_c: np.ndarray) -> None:
                normal.add(sl, J_c, residuals(x_c, sl))
        xs, J, Cv, Cr = self._sensitivities(nodes, theta, corr, u_k, jac, Ub, gain, sink)
        c = xs[:-1, L] - nodes[1:]
        c[self.cut] = 0.0  # no continuity into a run's first interval
        rg = np.concatenate([np.zeros(self.p), glob[self.p:self.p + self.ncg], np.zeros(self.nd)])
        r = residuals(xs)
        if not jac:
            return Evaluation(r, None, c, None, None, rg, xs)
        if jac == "state":
            return Evaluation(r, J, c, Cv, None, rg, xs)
        return Evaluation(r, J, c, Cv, Cr, rg, xs, normal, (nodes, offs, glob))

    def state_rows(self, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                   only: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`evaluate`'s residuals and, as with ``jac="state"``, their Jacobian with respect to the start
        states, of the intervals ``only`` alone, by the same operations per interval (stage 1's sweeps recompute
        only the intervals whose start moved; the others' rows are unchanged).

        Parameters
        ----------
        nodes : numpy.ndarray, shape (K, nx)
            The intervals' start states (rad, rad/s).
        offs : numpy.ndarray
            The per-interval offsets, as :meth:`evaluate` takes them.
        glob : numpy.ndarray, shape (p,)
            The global parameters (log values), as :meth:`evaluate` takes them.
        only : numpy.ndarray of int, shape (k,)
            The indices of the intervals to evaluate.

        Returns
        -------
        r : numpy.ndarray, shape (k, R)
            The intervals' weighted residuals.
        J : numpy.ndarray, shape (k, R, nx)
            Their Jacobian with respect to each interval's start state.
        """
        theta = self.values(glob)
        u_raw = self.torque_at(glob, offs, gained=False) if self.comp_cols else None
        g = self.gain(glob)
        u_k = u_raw * g[:, None, :] if (u_raw is not None and g is not None) else u_raw
        Ub, corr = self.inputs(glob, offs)
        per = corr is not None and (self.no or corr.ndim == 3)
        chunk = max(1, JACOBIAN_CHUNK // ((self.L + 1) * self.nx * self.nx))
        r, J = [], []
        for a in range(0, only.size, chunk):  # (a loop over chunks of intervals)
            ix = only[a:a + chunk]
            x_c, X_c = self.sens.run(nodes[ix], Ub[ix], self.Gb[ix], theta, corr[ix] if per else corr,
                                     basis=self.Psib[ix] if self.Psib is not None else None, sensitivities="state")
            J.append(self._state_jacobian(X_c, ix, theta, x_c[:, :, : self.n]))
            r.append(self._residuals(x_c, ix, theta, glob, offs, u_k))
        return np.concatenate(r), np.concatenate(J)

    def _residuals(self, xs: np.ndarray, sl: slice, theta: np.ndarray, glob: np.ndarray, offs: np.ndarray,
                   u_k: np.ndarray | None) -> np.ndarray:
        """(s, R) the residuals of the intervals ``sl`` from their states ``xs`` (s, L+1, nx): the encoder's, the
        camera's where recorded, the per-interval torque corrections' prior (zero mean, sigma_u / sqrt(L))."""
        q = xs[:, :, :self.n]
        u = None if u_k is None else u_k[sl]
        res = [((encoder_angles(self.enc, q) + self.offset(theta) + self.drift_offset(glob, sl)
                 + self.stretch(theta, self.tension_torque(u, xs)) - self.Yb[sl])
                / self.sig_y * self.valid[sl, :, None]).reshape(xs.shape[0], -1)]
        if self.Qm is not None:
            res.append((np.where(self.q_mask[sl], q - np.nan_to_num(self.Qm[sl]), 0.0)
                        / self.camera_noise).reshape(xs.shape[0], -1))
        if self.no:
            res.append(offs[sl] / self.sig_off)
        return np.concatenate(res, axis=1)

    def _sensitivities(self, nodes: np.ndarray, theta: np.ndarray, corr: np.ndarray | None,
                       u_k: np.ndarray | None, jac: bool = True, Ub: np.ndarray | None = None, gain=None,
                       sink=None):
        """The states xs (S, L+1, nx) and, with ``jac``, J (S, R, nb + ng) and the end-of-interval sensitivities Cv
        (S-1, nx, nb), Cr (S-1, nx, ng) (else None), the intervals in chunks of :data:`JACOBIAN_CHUNK` doubles of
        sensitivities (or of the compiled step's per-sample inputs, without them); with ``sink``, each chunk's rows
        of J given to ``sink(sl, J_c, x_c)`` (its intervals, their states) and J not kept (None). ``Ub``: the torque per interval
        (default :attr:`Ub`; :meth:`inputs`); ``gain``: (the gain (S, nu), the torque's coefficients ungained (S,
        nu, nphi), the tension's torque ungained (S, L+1, nu) or None) where its drift is fitted."""
        Ub = self.Ub if Ub is None else Ub
        n_int, L, nx = self.n_int, self.L, self.nx
        state = jac == "state"
        per_interval = ((L + 1) * nx * (nx if state else nx + self.p + self.sens.no) if jac
                        else L * self.sens.nw)
        chunk = max(1, JACOBIAN_CHUNK // per_interval)
        xs = np.empty((n_int, L + 1, nx))
        J = Cv = Cr = None
        for a in range(0, n_int, chunk):
            sl = slice(a, min(a + chunk, n_int))
            per = corr is not None and (self.no or corr.ndim == 3)  # per interval, or the lines' (global)
            corr_sl = corr[sl] if per else corr
            x_c, X_c = self.sens.run(nodes[sl], Ub[sl], self.Gb[sl], theta, corr_sl,
                                     basis=self.Psib[sl] if self.Psib is not None else None, sensitivities=jac)
            xs[sl] = x_c
            if not jac:
                continue
            if state:
                A_c = self._state_jacobian(X_c, sl, theta, x_c[:, :, : self.n])
                if J is None:
                    J, Cv = np.empty((n_int,) + A_c.shape[1:]), np.empty((n_int - 1, nx, nx))
                J[sl] = A_c
                last = min(sl.stop, n_int - 1)
                Cv[a:last] = X_c[: last - a, L]  # the end states' sensitivities to the start states
                continue
            J_c, Xv_end, Xr_end = self._jacobian(X_c, theta,
                                                 None if u_k is None else self.tension_torque(u_k[sl], x_c), sl,
                                                 x_c[:, :, : self.n], None if gain is None else
                                                 (gain[0][sl], gain[1][sl], None if gain[2] is None else gain[2][sl]))
            del X_c
            if sink is not None:
                sink(sl, J_c, x_c)
            elif J is None:
                J = np.empty((n_int,) + J_c.shape[1:])
            if Cv is None:
                Cv = np.empty((n_int - 1,) + Xv_end.shape[1:])
                Cr = np.empty((n_int - 1,) + Xr_end.shape[1:])
            if sink is None:
                J[sl] = J_c
            last = min(sl.stop, n_int - 1)  # the last interval has no continuity constraint
            Cv[a:last], Cr[a:last] = Xv_end[: last - a], Xr_end[: last - a]
        if Cv is not None:
            Cv[self.cut] = 0.0
        if Cr is not None:
            Cr[self.cut] = 0.0
        return xs, J, Cv, Cr

    def _state_jacobian(self, X: np.ndarray, sl: slice, theta: np.ndarray, q: np.ndarray) -> np.ndarray:
        """(s, R, nx) the residuals' Jacobian of the intervals ``sl`` with respect to their start states alone, from
        the state sensitivities X (s, L+1, nx, nx): the first nx columns of :meth:`_jacobian`'s J, by the same
        operations (``theta``: the parameters, for the rotor's share of the stretch; ``q`` (s, L+1, n) the joint
        angles, where the encoder's ratios change with them)."""
        n, s_int = self.n, X.shape[0]
        w = self.valid[sl, :, None, None] / self.sig_y
        J_enc = encoder_sensitivity(self.enc, q, X[:, :, :n])
        if self.rotor is not None:  # C (u - J_m S qdd): through qdd, as in _jacobian
            J_enc -= (self.compliance(theta) * self.rotor)[:, None] * self.motor_acceleration(X[:, :, n: 2 * n])
        jac = [(J_enc * w).reshape(s_int, -1, self.nx)]
        if self.Qm is not None:
            jac.append((X[:, :, :n] / self.camera_noise * self.q_mask[sl, :, :, None]).reshape(s_int, -1, self.nx))
        if self.no:
            jac.append(np.zeros((s_int, self.no, self.nx)))
        return np.concatenate(jac, axis=1)

    def _jacobian(self, X: np.ndarray, theta: np.ndarray, u_k: np.ndarray | None, sl: slice, q: np.ndarray,
                  gain=None):
        """J (s, R, nb + ng) of the residuals of the intervals ``sl`` from their sensitivities X (s, L+1, nx,
        nx + p + no), and the sensitivities at their ends with respect to the local (nx, nb) and global (nx, ng)
        variables. ``gain``: (g (s, nu), the torque's coefficients W (s, nu, nphi), the tension's torque (s, L+1,
        nu) or None), all ungained, where the gain's drift is fitted (module drift; its columns last)."""
        nx, p, n, nb, ng, nu = self.nx, self.p, self.n, self.nb, self.ng, self.nu
        s_int = X.shape[0]
        iv, ip, io = slice(0, nx), slice(nx, nx + p), slice(nx + p, nx + p + self.sens.no)
        Xv = np.concatenate([X[..., iv], X[..., io]], axis=-1) if self.no else X[..., iv]  # (s, L+1, nx, nb)
        Xr = X[..., ip] * np.where(self.additive, self.scale, theta)  # d/d log theta (d/d (theta / scale) if additive)
        if self.torque.lines:  # each interval's run's coefficients in their place (several runs: _scatter)
            X_io = X[..., io] if gain is None else X[..., io] * np.tile(gain[0], self.torque.nphi)[:, None, None, :]
            Xr = np.concatenate([Xr, self._scatter(X_io, sl)], axis=-1)  # (the dynamics see g C: d/dC = g X_io)
        if self.nd_off:  # the offset's knots: no state depends on them (output only)
            Xr = np.concatenate([Xr, np.zeros(Xr.shape[:-1] + (self.nd_off,))], axis=-1)
        if self.nd_gain:  # the gain's knots: the torque's own direction on the lines (module drift)
            Xr = np.concatenate([Xr, gain_sensitivity(X[..., io], gain[1], self.Hs[sl], nu)], axis=-1)
        w = self.valid[sl, :, None, None] / self.sig_y
        J_enc = np.concatenate([encoder_sensitivity(self.enc, q, Xv[:, :, :n]),
                                encoder_sensitivity(self.enc, q, Xr[:, :, :n])], axis=-1)
        for k, mo in self.off_cols:  # y = S q + offset: d r / d offset_m = e_m
            J_enc[:, :, mo, nb + k] += 1.0
        if self.nd_off:  # y += H d (module drift): motor mo's knots at columns nb + p + ncg + mo K ...
            K, d0 = self.nK, nb + p + self.ncg
            for mo in range(self.ny):  # a loop over the motors (one or two)
                J_enc[:, :, mo, d0 + mo * K: d0 + (mo + 1) * K] += self.Hb[sl]
        if self.comp_cols:  # y += C u: d/d C (in its scale) = u scale; d/d the torque's correction = C
            for k, mo in self.comp_cols:
                J_enc[:, :, mo, nb + k] += u_k[:, :, mo] * self.scale[k]
                gk = 1.0 if gain is None else gain[0][:, None, mo, None]  # the stretch is under g u
                if self.torque.lines:  # vec(C_lines) is column-major: coefficient (motor mo, line l) at l * nu + mo
                    J_enc[:, :, mo, nb + p + mo:nb + p + self.ncg:nu] += theta[k] * gk * self.psik(sl)
                elif self.torque.eiv:
                    J_enc[:, :, mo, nx + mo] += theta[k]
                if self.nd_gain:  # d (C g u) / d the gain's knots of motor mo: C u (ungained) times each hat
                    g0, K = nb + p + self.ncg + self.nd_off + mo * self.nK, self.nK
                    J_enc[:, :, mo, g0:g0 + K] += theta[k] * gain[2][:, :, mo, None] * self.Hs[sl][:, None, :]
        if self.rotor is not None:  # C (u - J_m S qdd): d/d the states and parameters through qdd
            dA = self.motor_acceleration(np.concatenate([Xv[:, :, n: 2 * n], Xr[:, :, n: 2 * n]], axis=-1))
            J_enc -= (self.compliance(theta) * self.rotor)[:, None] * dA
        J_enc = J_enc * w
        jac = [J_enc.reshape(s_int, -1, nb + ng)]
        if self.Qm is not None:
            Jq = (np.concatenate([Xv[:, :, :n], Xr[:, :, :n]], axis=-1) / self.camera_noise
                  * self.q_mask[sl, :, :, None])
            jac.append(Jq.reshape(s_int, -1, nb + ng))
        if self.no:
            Jo = np.zeros((s_int, self.no, nb + ng))
            Jo[:, :, nx:nb] = np.eye(self.no) / self.sig_off
            jac.append(Jo)
        return np.concatenate(jac, axis=1), Xv[:, self.L], Xr[:, self.L]

    # --- the start --------------------------------------------------------------------------------------------

    def solution(self, nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray,
                 response: np.ndarray | None = None) -> ShootingSolution:
        """The variables (``nodes``, ``offs``, ``glob``) as a :class:`ShootingSolution` (theta left out: it goes by
        name, :func:`start_values`), with the optimum's ``response`` (nz, p) where given.

        Parameters
        ----------
        nodes : numpy.ndarray, shape (S, nx)
            Each interval's start state s_j ([q; qd], rad and rad/s; LuGre's bristles after them).
        offs : numpy.ndarray, shape (S, no)
            Each interval's constant torque correction, N m (no = 0 without it).
        glob : numpy.ndarray, shape (ng,)
            The global variables: rho (p), the whitened line corrections (ncg), the drifts' knots (nd).
        response : numpy.ndarray or None, optional
            (nz, p) the optimum's response (default None).

        Returns
        -------
        ShootingSolution
            Copies of the variables, the interval ``L``, the drift's knots and the parameters' additive flags and
            scales.
        """
        return ShootingSolution(nodes.copy(), offs.copy(), glob[self.p:self.p + self.ncg].copy(), self.L,
                                glob[self.p + self.ncg:].copy(), response, self.additive.copy(), self.scale.copy())

    def warm_variables(self, sol: ShootingSolution | None) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(nodes, offs, glob) of this problem from another fit's ``sol`` on the same recording: its trajectory and
        line corrections, theta at theta_0 (the start's values, given by name). None where the two problems are
        not cut alike (another interval, state size or torque model: another model's states, a retry at half the
        interval), or where ``sol`` is None.

        Parameters
        ----------
        sol : ShootingSolution or None
            Another fit's solution (:meth:`solution`).

        Returns
        -------
        tuple of numpy.ndarray, or None
            (nodes (S, nx), offs (S, no), glob (ng,)), or None.
        """
        nodes = None if sol is None else self.with_bristles(sol.nodes)
        if sol is None or sol.samples != self.L or nodes.shape != (self.n_int, self.nx) \
                or sol.offs.shape != (self.n_int, self.no) or sol.lines.shape != (self.ncg,):
            return None
        drift = sol.drift if sol.drift.shape == (self.nd,) else np.zeros(self.nd)  # the same drift, else from 0
        return nodes, sol.offs.copy(), np.concatenate([np.zeros(self.p), sol.lines, drift])

    def with_bristles(self, nodes: np.ndarray) -> np.ndarray:
        """A copy of ``nodes`` (S, 2n) of a memoryless friction's fit with, where this problem's law is LuGre (nx =
        3n), each node's bristles z = F_s tanh(qd / v_s) / sigma0 appended (rad, theta_0's F_s and sigma0): the
        deflection whose spring gives the smooth law's torque at that velocity (eq. L2, z' = 0). Other nodes as they
        are (copied).

        Parameters
        ----------
        nodes : numpy.ndarray, shape (S, 2n) or (S, nx)
            Start states [q; qd], rad and rad/s.

        Returns
        -------
        numpy.ndarray, shape (S, nx)
            The nodes, with the bristles (rad) appended where this problem's law is LuGre and ``nodes`` has none.
        """
        n, lugre = self.n, self.sens.lugre
        if lugre is None or nodes.shape[1:] != (2 * n,):
            return nodes.copy()
        Fs, s0 = np.array(self.model.extras.coulomb, dtype=float), lugre.sigma0
        for k, pp in enumerate(self.sens.dynamics.parameters):  # theta_0's, where fitted
            if pp.kind == "F_s":
                Fs[self.model.joint_names.index(pp.joint)] = self.theta0[k]
            elif pp.kind == "sigma0":
                s0 = self.theta0[k]
        v_s = self.model.extras.smooth_velocity
        return np.hstack([nodes, Fs * np.tanh(nodes[:, n:] / v_s) / s0])

    def initial_nodes(self, q0: np.ndarray, theta: np.ndarray | None = None) -> np.ndarray:
        """(S, nx) the model's own response from the rest ``q0`` under the torque, cut at the nodes, then shifted
        onto the measured encoder (the stretch of the start's compliance off): a start close to the data. (Not
        shifted, the response alone is no start on a long record even with the parameters right: over a record of
        seconds it drifts hundreds of counts from the encoder.)

        Parameters
        ----------
        q0 : numpy.ndarray, shape (n,)
            The rest the response starts from (each run's), rad.
        theta : numpy.ndarray or None, optional
            (p,) the parameters to simulate with (default None: theta_0).

        Returns
        -------
        numpy.ndarray, shape (S, nx)
            The start states.
        """
        n, L, n_int, nu, N = self.n, self.L, self.n_int, self.nu, self.N
        theta = self.theta0 if theta is None else theta
        C = np.zeros((1, nu, self.sens.nb)) if self.sens.nb else None
        # the record in pieces of whole intervals, each from the last one's end (the same steps: its per-sample
        # inputs 8 MiB at a time, not the whole record's at once: hundreds of MB on a long record)
        K = L * max(1, JACOBIAN_CHUNK // (L * self.sens.nw))
        nodes = np.empty((n_int, self.nx))
        runs = self.rec.run_starts()
        first = np.zeros(N + 1, dtype=bool)
        first[runs[:-1]] = True  # each run from the rest, its pieces within it (runs start on a node: run_cuts)
        for a, b in ((a, min(a + K, N, int(runs[np.searchsorted(runs, a, side="right")])))
                     for a0, a1 in zip(runs[:-1], runs[1:]) for a in range(int(a0), min(int(a1), N), K)):
            x = np.concatenate([q0, np.zeros(self.nx - n)]) if first[a] else x
            basis = self.Psib.reshape(-1, self.torque.nphi)[None, a:b] if self.torque.lines else None
            x_c, _ = self.sens.run(x[None], self.torque.U[None, a:b], self.G[None, a:b], theta, C, basis=basis,
                                   sensitivities=False)
            nodes[a // L: -(-b // L)] = x_c[0, 0:b - a:L]
            x = x_c[0, -1]
        if not np.isfinite(nodes).all():
            nodes[:] = np.concatenate([q0, np.zeros(self.nx - n)])
        k_nodes = np.arange(n_int) * L
        S_enc, y = self.S_enc, self.y
        Sp = np.linalg.pinv(S_enc)
        C0 = np.asarray(self.model.transmission.tendon_compliance)
        y_rigid = y - self.Ufull[self.before] * C0 if self.comp_cols else y
        nodes[:, :n] += (y_rigid[k_nodes] - encoder_angles(self.enc, nodes[:, :n])) @ Sp.T  # (S: rho(0), a start)
        yd = np.concatenate([np.gradient(y[a:b], self.rec.dt, axis=0) for a, b in zip(runs[:-1], runs[1:])])
        nodes[:, n:2 * n] += (yd[k_nodes] - nodes[:, n:2 * n] @ S_enc.T) @ Sp.T  # (a LuGre law's bristles kept)
        return nodes
