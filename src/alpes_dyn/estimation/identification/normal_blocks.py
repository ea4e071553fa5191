"""A long record's Jacobian held compact: its normal blocks, not itself (issue 39).

The shooting fit's residual Jacobian J (S, R, nb + ng) (:class:`~alpes_dyn.estimation.identification.shooting.Evaluation`)
is the largest array of a fit: on a long record (thousands of 50 ms intervals) larger than the record and its
problem together, and it set the fit's peak memory. Gauss-Newton needs only J's normal blocks -- each interval's
A'A (nb, nb) and A'P (nb, ng), the sum of the P'P (ng, ng), with A the interval's local columns and P the
global ones -- and each interval's J'r (nb + ng): accumulated chunk by chunk while the sensitivities are computed
(:meth:`NormalBlocks.add`), by the einsums of
:func:`~alpes_dyn.estimation.identification.kkt.normal_matrix`, they are the same numbers as from the whole J (the sum
of the P'P in another order: within 1e-12), and the steps, the covariance and the stopping rule read them alone.
The one use of J itself is the verdict's projection of each missing effect's response R on the fit's tangent space
(J'R, the KKT solve, then R - J z): :func:`remainders` takes it in two more passes over the sensitivities at the fit's
end, chunk by chunk, instead of holding J (at the cost of two more evaluations of the whole record with its
sensitivities).

A problem holds its Jacobians compact where J would take more than :data:`COMPACT_BYTES`
(:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.evaluate`): a 600 s record; shorter ones keep
the whole J. The fits' peak memory by record length: ``benchmarks/results/fit_scaling.json`` and
``fit_scaling.hand.json`` (their rows' ``peak_rss_mib``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

__all__ = ["COMPACT_BYTES", "NormalBlocks", "blocks_of", "assembled", "j_dot", "remainders"]

COMPACT_BYTES = 2**27
"""Bytes (128 MiB): a problem whose Jacobian J (S, R, nb + ng) in double precision would take more holds it compact
(module doc). finger3 at 60 s: 17 MB (whole); at 600 s: 175 MB (compact); the hand's thumb at 600 s: 548 MB."""


def blocks_of(J: np.ndarray, nb: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A'A (s, nb, nb), A'P (s, nb, ng), the sum of the P'P (ng, ng)) of J (s, rows, nb + ng): A its first ``nb``
    columns (the intervals' local variables), P the others (the global ones). The one place these products are
    taken (:func:`~alpes_dyn.estimation.identification.kkt.normal_matrix`, :meth:`NormalBlocks.add`).

    Parameters
    ----------
    J : numpy.ndarray, shape (s, rows, nb + ng)
        The intervals' rows of the Jacobian.
    nb : int
        The local variables per interval.

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray, numpy.ndarray]
        A'A (s, nb, nb), A'P (s, nb, ng), the sum of the P'P (ng, ng).
    """
    A, P = J[:, :, :nb], J[:, :, nb:]
    At = A.transpose(0, 2, 1)
    Pf = P.reshape(P.shape[0] * P.shape[1], P.shape[2])  # the intervals' rows stacked (ng may be 0: no -1)
    return At @ A, At @ P, Pf.T @ Pf


def assembled(gs: np.ndarray, rg: np.ndarray | float, nb: int) -> np.ndarray:
    """(S nb + ng,) the vector J'r in the fit's layout from each interval's J_s'r_s ``gs`` (S, nb + ng): the local
    variables' parts interval by interval, then the global ones summed (plus ``rg``).

    Parameters
    ----------
    gs : numpy.ndarray, shape (S, nb + ng)
        Each interval's J_s'r_s.
    rg : numpy.ndarray, shape (ng,), or float
        Added to the global variables' part (a prior's gradient; 0.0: none).
    nb : int
        The local variables per interval.

    Returns
    -------
    numpy.ndarray, shape (S nb + ng,)
        J'r.
    """
    return np.concatenate([gs[:, :nb].reshape(-1), gs[:, nb:].sum(axis=0) + rg])


def j_dot(J: np.ndarray, z_local: np.ndarray, z_glob: np.ndarray) -> np.ndarray:
    """(s, rows) J z of J (s, rows, nb + ng) for z's local part ``z_local`` (s, nb) and global part ``z_glob`` (ng,).

    Parameters
    ----------
    J : numpy.ndarray, shape (s, rows, nb + ng)
        The intervals' rows of the Jacobian.
    z_local : numpy.ndarray, shape (s, nb)
        z's part on the intervals' local variables.
    z_glob : numpy.ndarray, shape (ng,)
        z's part on the global variables.

    Returns
    -------
    numpy.ndarray, shape (s, rows)
        J z.
    """
    nb = z_local.shape[1]
    return (J[:, :, :nb] @ z_local[:, :, None])[:, :, 0] + J[:, :, nb:] @ z_glob


@dataclass
class NormalBlocks:
    """J's normal blocks, undamped and without the prior: ``AA`` (S, nb, nb) each interval's A'A, ``AP`` (S, nb, ng)
    its A'P, ``PP`` (ng, ng) the sum of the P'P; and ``gs`` (S, nb + ng) each interval's J'r (r the residuals the
    blocks were accumulated with)."""

    AA: np.ndarray
    AP: np.ndarray
    PP: np.ndarray
    gs: np.ndarray

    @classmethod
    def empty(cls, n_int: int, nb: int, ng: int) -> "NormalBlocks":
        """Blocks of zeros, to be filled by :meth:`add`.

        Parameters
        ----------
        n_int : int
            S, the number of intervals.
        nb : int
            The local variables per interval.
        ng : int
            The global variables.

        Returns
        -------
        NormalBlocks
            Its arrays zero.
        """
        return cls(np.zeros((n_int, nb, nb)), np.zeros((n_int, nb, ng)), np.zeros((ng, ng)), np.zeros((n_int, nb + ng)))

    def add(self, sl: slice, J: np.ndarray, r: np.ndarray) -> None:
        """The intervals ``sl``' blocks from their rows of J (s, R, nb + ng), double precision, and residuals r (s, R),
        by :func:`blocks_of`, as :func:`~alpes_dyn.estimation.identification.kkt.normal_matrix` takes them.

        Parameters
        ----------
        sl : slice
            The intervals.
        J : numpy.ndarray, shape (s, R, nb + ng)
            Their rows of the Jacobian, double precision.
        r : numpy.ndarray, shape (s, R)
            Their residuals.
        """
        AA, AP, PP = blocks_of(J, self.AA.shape[1])
        self.AA[sl], self.AP[sl] = AA, AP
        self.PP += PP
        self.gs[sl] = (r[:, None, :] @ J)[:, 0]

    def gradient(self, rg: np.ndarray) -> np.ndarray:
        """(nz,) the cost's gradient J'r (+ ``rg`` for the global variables), as
        :meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.grad` gives it from J.

        Parameters
        ----------
        rg : numpy.ndarray, shape (ng,)
            Added to the global variables' part (a prior's gradient).

        Returns
        -------
        numpy.ndarray, shape (nz,)
            J'r + [0; rg].
        """
        return assembled(self.gs, rg, self.AA.shape[1])


def remainders(pb: Any, point: tuple[np.ndarray, np.ndarray, np.ndarray], solve: Callable[[np.ndarray], np.ndarray],
               R: np.ndarray) -> np.ndarray:
    """(k, S, rows) each R_i - J z_i, in ``R`` itself (overwritten), z_i = ``solve``([J'R_i; 0]) (the KKT system's solver: the projection of R_i on
    the fit's tangent space, continuity kept), for ``R`` (k, S, rows) residual-shaped responses, J the Jacobian of
    ``pb`` (a :class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`) at ``point`` (nodes, offs, glob),
    never held whole: one pass over its chunks for every J'R_i, one for every J z_i (module doc).

    Parameters
    ----------
    pb : ShootingProblem
        The fit's problem.
    point : tuple[numpy.ndarray, numpy.ndarray, numpy.ndarray]
        (nodes, offs, glob): where J is taken.
    solve : Callable[[numpy.ndarray], numpy.ndarray]
        The KKT system's solver (nz + nc,).
    R : numpy.ndarray, shape (k, S, rows)
        Residual-shaped responses (overwritten).

    Returns
    -------
    numpy.ndarray, shape (k, S, rows)
        R - J z, in ``R``'s memory.
    """
    k, nb, nv, nz = R.shape[0], pb.nb, pb.nv, pb.nz
    G = np.zeros((k, pb.n_int, nb + pb.ng))

    def products(sl: slice, J_c: np.ndarray, x_c: np.ndarray) -> None:
        G[:, sl] = (R[:, sl].transpose(1, 0, 2) @ J_c).transpose(1, 0, 2)  # (BLAS, not einsum's loops)
    pb.evaluate(*point, sink=products)
    Z = [solve(np.concatenate([assembled(g, 0.0, nb), np.zeros(pb.nc)]))[:nz] for g in G]
    G = None
    out = R  # in place: R's memory (the responses' copy, 60 MB for the hand's thumb at 600 s) held once

    def subtract(sl: slice, J_c: np.ndarray, x_c: np.ndarray) -> None:
        for i, z in enumerate(Z):  # a loop over the responses (four or five)
            out[i, sl] -= j_dot(J_c, z[:nv].reshape(-1, nb)[sl], z[nv:])
    pb.evaluate(*point, sink=subtract)
    return out
