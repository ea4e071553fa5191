"""The linear algebra of :class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`: its Gauss-Newton
normal, continuity and KKT systems from an :class:`Evaluation`'s blocks (:mod:`alpes_dyn.estimation.identification.kkt`),
their solvers and the cost's gradient -- the part of the problem that the solver
(:mod:`alpes_dyn.estimation.identification.gauss_newton`) calls, apart from how the residuals and Jacobians are made.
An evaluation held compact (:mod:`alpes_dyn.estimation.identification.normal_blocks`) gives its normal blocks instead
of its Jacobian (:meth:`ShootingAlgebra.normal_of`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .kkt import (Shape, bordered_factorize, continuity_jacobian, factorize, kkt_from_blocks, kkt_matrix, kkt_order,
                  normal_matrix, penalized_from_blocks)
from .normal_blocks import NormalBlocks, assembled

__all__ = ["Evaluation", "ShootingAlgebra"]


@dataclass
class Evaluation:
    """The problem at one point: residuals ``r`` (S, R), their Jacobians ``J`` (S, R, nb + ng) with respect to the
    interval's local variables and the global ones, continuity defects ``c`` (S-1, nx) and their Jacobians ``Cv``
    (S-1, nx, nb), ``Cr`` (S-1, nx, ng), the global residuals ``rg`` (ng,) (the line corrections' prior; zeros for
    theta) and the states ``xs`` (S, L+1, nx). Without the sensitivities J, Cv and Cr are None. Held compact
    (:mod:`~alpes_dyn.estimation.identification.normal_blocks`), J is None and ``normal`` holds its blocks and J'r."""

    r: np.ndarray
    J: np.ndarray | None
    c: np.ndarray
    Cv: np.ndarray | None
    Cr: np.ndarray | None
    rg: np.ndarray
    xs: np.ndarray
    normal: NormalBlocks | None = None  # a compact Jacobian's (module normal_blocks): J then None
    point: tuple | None = None  # (nodes, offs, glob) where the Jacobians were taken (with them)

    @property
    def cost(self) -> float:
        """1/2 (|r|^2 + |rg|^2)."""
        return 0.5 * float(np.sum(self.r**2) + np.sum(self.rg**2))


class ShootingAlgebra:
    """The linear algebra of a problem with ``shape`` (:class:`~alpes_dyn.estimation.identification.kkt.Shape`; its
    ``n_int``, ``nb``, ``nx``, ``ng``, ``p``, ``nv``, ``nz``, ``nc``), ``prior`` (ng,), ``dense`` and ``structured``."""

    shape: Shape
    prior: np.ndarray
    dense: bool
    structured: bool
    n_int: int
    nb: int
    nx: int
    ng: int
    nv: int
    nz: int
    nc: int

    # --- the linear algebra (module kkt) ------------------------------------------------------------------------

    def normal(self, J: np.ndarray, mu: float):
        """Gauss-Newton normal matrix of the interval-structured residuals, LM-damped by mu (:mod:`.kkt`).

        Parameters
        ----------
        J : numpy.ndarray or NormalBlocks
            The residuals' Jacobian per interval, (S, rows, nb + ng), or its compact blocks (:meth:`normal_of`).
        mu : float
            The Levenberg-Marquardt damping.

        Returns
        -------
        scipy.sparse.csc_matrix or numpy.ndarray, shape (nz, nz)
            The damped normal matrix, with the prior (an array where :attr:`dense`).
        """
        return normal_matrix(J, self.shape, mu, self.prior, self.dense)

    def continuity(self, Cv: np.ndarray, Cr: np.ndarray):
        """(nc, nz) Jacobian of the continuity defects.

        Parameters
        ----------
        Cv : numpy.ndarray, shape (S-1, nx, nb)
            The continuity defects' Jacobian on each interval's local variables.
        Cr : numpy.ndarray, shape (S-1, nx, ng)
            Their Jacobian on the global variables.

        Returns
        -------
        scipy.sparse.csc_matrix or numpy.ndarray, shape (nc, nz)
            The continuity Jacobian (an array where :attr:`dense`).
        """
        return continuity_jacobian(Cv, Cr, self.shape, self.dense)

    def kkt_system(self, J: np.ndarray, Cv: np.ndarray, Cr: np.ndarray, mu: float):
        """Normal equations of the interval-structured least squares, with the continuity constraints.

        Parameters
        ----------
        J : numpy.ndarray or NormalBlocks
            The residuals' Jacobian per interval, (S, rows, nb + ng), or its compact blocks (:meth:`normal_of`).
        Cv : numpy.ndarray, shape (S-1, nx, nb)
            The continuity defects' Jacobian on each interval's local variables.
        Cr : numpy.ndarray, shape (S-1, nx, ng)
            Their Jacobian on the global variables.
        mu : float
            The Levenberg-Marquardt damping.

        Returns
        -------
        scipy.sparse.csc_matrix or numpy.ndarray, shape (nz + nc, nz + nc)
            The KKT matrix (:func:`~alpes_dyn.estimation.identification.kkt.kkt_matrix`).
        """
        return kkt_matrix(self.normal(J, mu), self.continuity(Cv, Cr), self.shape.dropped)

    def continuity_t(self, Cv: np.ndarray, Cr: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(nz,) C' v for the continuity Jacobian C (:meth:`continuity`) and v (S-1, nx), from its blocks.

        Parameters
        ----------
        Cv : numpy.ndarray, shape (S-1, nx, nb)
            The continuity defects' Jacobian on each interval's local variables.
        Cr : numpy.ndarray, shape (S-1, nx, ng)
            Their Jacobian on the global variables.
        v : numpy.ndarray, shape (S-1, nx)
            One value per continuity defect (e.g. the multipliers).

        Returns
        -------
        numpy.ndarray, shape (nz,)
            C' v.
        """
        out = np.zeros((self.n_int, self.nb))
        out[:-1] += np.einsum("sia,si->sa", Cv, v)
        out[1:, :self.nx] -= v * self.shape.keep[:, None]
        return np.concatenate([out.reshape(-1), np.einsum("sig,si->g", Cr, v)])

    def penalized_solver(self, e: Evaluation, mu: float, wv: np.ndarray, hold: np.ndarray):
        """The homotopy's system at ``e``: H (:meth:`normal`, damped by ``mu``) + C' W C (the defects' rows weighted
        by ``wv`` (nx,)), 1e12 max(d, 1) added to the diagonal d of the global variables ``hold`` (indices 0..ng-1).
        Returns (its solver, the solver of its local variables' block H[:nv, :nv], that block's border H[:nv, nv:]):
        where :attr:`structured`, from the blocks (:func:`~alpes_dyn.estimation.identification.kkt.penalized_from_blocks`),
        else from the matrices (dense or SuperLU).

        Parameters
        ----------
        e : Evaluation
            The problem evaluated at a point, with its Jacobians
            (:class:`~alpes_dyn.estimation.identification.shooting.Evaluation`).
        mu : float
            The Levenberg-Marquardt damping.
        wv : numpy.ndarray, shape (nx,)
            The weights of the defects' rows (the same for every defect).
        hold : numpy.ndarray
            Indices in 0..ng-1 of the global variables held.

        Returns
        -------
        tuple
            (the whole system's solver, its local block's solver, the border H[:nv, nv:] (nv, ng)).
        """
        nv = self.nv
        if self.structured:
            def fallback():
                return factorize(self._penalized_matrix(e, mu, wv, hold))
            return penalized_from_blocks(self.normal_of(e), e.Cv, e.Cr, wv, self.shape, mu, self.prior, hold,
                                         fallback)
        H = self._penalized_matrix(e, mu, wv, hold)
        return factorize(H), factorize(H[:nv, :nv]), H[:nv, nv:]

    def _penalized_matrix(self, e: Evaluation, mu: float, wv: np.ndarray, hold: np.ndarray):
        """:meth:`penalized_solver`'s matrix, (nz, nz), sparse (an array if :attr:`dense`)."""
        wdef = np.tile(wv, self.n_int - 1) * np.repeat(self.shape.keep, self.nx)
        C = self.continuity(e.Cv, e.Cr)
        C = C * wdef[:, None] if self.dense else sp.diags(wdef) @ C
        H = self.normal(self.normal_of(e), mu) + C.T @ C
        h = np.zeros(self.nz)
        idx = self.nv + np.asarray(hold, dtype=int)
        h[idx] = 1e12 * np.maximum(H.diagonal()[idx], 1.0)
        return H + (np.diag(h) if self.dense else sp.diags(h, format="csc"))

    def kkt_solver(self, J: np.ndarray, Cv: np.ndarray, Cr: np.ndarray, mu: float):
        """A solver of :meth:`kkt_system` (J, Cv, Cr, mu): where :attr:`structured`, laid out in band and border from
        the intervals' blocks (:func:`~alpes_dyn.estimation.identification.kkt.kkt_from_blocks`: no sparse matrix
        formed), else :meth:`factorize` of the matrix.

        Parameters
        ----------
        J : numpy.ndarray or NormalBlocks
            The residuals' Jacobian per interval, (S, rows, nb + ng), or its compact blocks (:meth:`normal_of`).
        Cv : numpy.ndarray, shape (S-1, nx, nb)
            The continuity defects' Jacobian on each interval's local variables.
        Cr : numpy.ndarray, shape (S-1, nx, ng)
            Their Jacobian on the global variables.
        mu : float
            The Levenberg-Marquardt damping.

        Returns
        -------
        Callable[[numpy.ndarray], numpy.ndarray]
            ``solve(b)`` of the KKT system, b (nz + nc,) or (nz + nc, k).
        """
        if not self.structured:
            return self.factorize(self.kkt_system(J, Cv, Cr, mu), "kkt")
        return kkt_from_blocks(J, Cv, Cr, self.shape, mu, self.prior,
                               lambda: factorize(self.kkt_system(J, Cv, Cr, mu)))

    def factorize(self, M, system: str):
        """A solver x = M^-1 b for one of the problem's matrices: ``system`` "kkt" (:meth:`kkt_system`), "normal"
        (the (nz, nz) normal matrix, with or without the continuity penalty C'WC) or "local" (its local variables'
        (nv, nv) block); by :func:`~alpes_dyn.estimation.identification.kkt.bordered_factorize` in the order that makes it banded
        but for the global variables where :attr:`structured`, else :func:`~alpes_dyn.estimation.identification.kkt.factorize`.

        Parameters
        ----------
        M : scipy.sparse matrix or numpy.ndarray
            The matrix, (nz + nc) square for "kkt", (nz, nz) for "normal", (nv, nv) for "local".
        system : str
            ``"kkt"``, ``"normal"`` or ``"local"``.

        Returns
        -------
        Callable[[numpy.ndarray], numpy.ndarray]
            ``solve(b)``: x = M^-1 b, b (n,) or (n, k).

        Raises
        ------
        ValueError
            An unknown ``system`` (where :attr:`structured`).
        """
        if not self.structured:
            return factorize(M)
        if system == "kkt":
            return bordered_factorize(M, kkt_order(self.shape), self.ng)
        if system not in ("normal", "local"):
            raise ValueError(f"system: expected 'kkt', 'normal' or 'local', got {system!r}")
        return bordered_factorize(M, np.arange(M.shape[0]), self.ng if system == "normal" else 0)

    def grad(self, r: np.ndarray, J: np.ndarray, rg: np.ndarray) -> np.ndarray:
        """(nz,) the cost's gradient J^T r (+ rg for the global variables).

        Parameters
        ----------
        r : numpy.ndarray, shape (S, rows)
            The residuals per interval.
        J : numpy.ndarray, shape (S, rows, nb + ng)
            Their Jacobian per interval.
        rg : numpy.ndarray, shape (ng,)
            Added to the global variables' part (a prior's gradient).

        Returns
        -------
        numpy.ndarray, shape (nz,)
            The gradient.
        """
        return assembled(np.einsum("sk,skd->sd", r, J), rg, self.nb)

    def gradient(self, e: Evaluation) -> np.ndarray:
        """(nz,) the cost's gradient at ``e``: :meth:`grad`, or its compact Jacobian's (the same numbers).

        Parameters
        ----------
        e : Evaluation
            The problem evaluated at a point, with its Jacobians
            (:class:`~alpes_dyn.estimation.identification.shooting.Evaluation`).

        Returns
        -------
        numpy.ndarray, shape (nz,)
            The gradient.
        """
        return e.normal.gradient(e.rg) if e.normal is not None else self.grad(e.r, e.J, e.rg)

    @staticmethod
    def normal_of(e: Evaluation):
        """What :meth:`kkt_solver` and :meth:`normal` take of ``e``: J, or its compact Jacobian's blocks.

        Parameters
        ----------
        e : Evaluation
            The problem evaluated at a point, with its Jacobians
            (:class:`~alpes_dyn.estimation.identification.shooting.Evaluation`).

        Returns
        -------
        numpy.ndarray or NormalBlocks
            ``e.J`` (S, rows, nb + ng), or ``e.normal``.
        """
        return e.normal if e.normal is not None else e.J
