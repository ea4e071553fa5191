"""The linear algebra of the multiple-shooting fit (:mod:`alpes_dyn.estimation.identification.shooting`), sparse.

The fit's unknowns are S intervals' local variables (each interval's start state and torque correction, ``nb``
per interval) and ``ng`` global ones (the parameters and the line-coefficient corrections). Its Gauss-Newton
normal matrix is an arrow: S diagonal blocks (nb x nb), a dense border of ng columns, and the ng x ng corner;
the continuity Jacobian is block-bidiagonal with the same border. Held densely, the KKT matrix of a record of
T seconds at 50 ms intervals has (240 T)^2 entries, its memory quadratic and its solve cubic in the record. Held
sparse, its nonzeros are linear in S; factorised by SuperLU (:func:`scipy.sparse.linalg.splu`, COLAMD ordering)
its fill was not, and on a long record the factorisations took most of the fit (issue 39).
:func:`bordered_factorize` exploits the structure instead: with each interval's local variables and its continuity
multipliers taken together, interval after interval, the matrix less its border is banded (half-bandwidth
nb + nx - 1), factorised by LAPACK's band LU with partial pivoting, and the border by its dense ng x ng Schur
complement: time and memory O(S (nb + nx)^2 ng), linear in the record.

Every function takes the sizes of the problem, ``Shape``; ``dense=True`` gives the same matrices as arrays
(the reference the sparse path is tested against).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from .normal_blocks import NormalBlocks, blocks_of

__all__ = ["Shape", "normal_matrix", "continuity_jacobian", "kkt_matrix", "factorize", "bordered_factorize",
           "kkt_order", "kkt_from_blocks", "penalized_from_blocks", "DENSE_LIMIT", "minimum_norm"]

DENSE_LIMIT = 4000
"""Largest system solved by a dense least-squares fallback where the sparse factorisation finds it singular."""


Solver = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Shape:
    """Sizes of the shooting problem: ``n_int`` intervals, ``nb`` local variables per interval (the first ``nx``
    of them the state), ``ng`` global variables; ``nv = n_int nb``, ``nz = nv + ng``, ``nc = (n_int - 1) nx``.
    ``cut`` (n_int - 1,) bool or None: where interval j+1 starts a run of its own (a recording of several runs): no
    continuity between j and j+1. The constraint's rows stay (the layout is the same), with no entry but a unit
    diagonal in the KKT matrix's multiplier block and a zero defect: their multipliers are 0 and interval j+1's
    start state is free."""

    n_int: int
    nb: int
    nx: int
    ng: int
    cut: np.ndarray | None = field(default=None, compare=False)

    @property
    def keep(self) -> np.ndarray:
        """(n_int - 1,) 1.0 where continuity holds between interval j and j+1, 0.0 at a cut."""
        return np.ones(self.n_int - 1) if self.cut is None else 1.0 - np.asarray(self.cut, dtype=float)

    @property
    def dropped(self) -> np.ndarray:
        """(nc,) 1.0 on the rows of the constraints cut (:attr:`cut`), else 0.0."""
        return np.repeat(1.0 - self.keep, self.nx)

    @property
    def nv(self) -> int:
        return self.n_int * self.nb

    @property
    def nz(self) -> int:
        return self.nv + self.ng

    @property
    def nc(self) -> int:
        return (self.n_int - 1) * self.nx


def _block_diagonal(blocks: np.ndarray, row0: int = 0, col0: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets of (S, a, b) blocks laid along the diagonal from (row0, col0)."""
    S, a, b = blocks.shape
    i = row0 + np.arange(S)[:, None, None] * a + np.arange(a)[None, :, None]
    j = col0 + np.arange(S)[:, None, None] * b + np.arange(b)[None, None, :]
    return np.broadcast_to(i, blocks.shape).ravel(), np.broadcast_to(j, blocks.shape).ravel(), blocks.ravel()


def _raw_blocks(J: "np.ndarray | NormalBlocks", nb: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A'A (S, nb, nb), A'P (S, nb, ng), sum of P'P (ng, ng)) of J (S, rows, nb + ng), or a compact Jacobian's
    (:class:`~alpes_dyn.estimation.identification.normal_blocks.NormalBlocks`: the same numbers, A'A a copy, which
    :func:`_normal_blocks` damps in place)."""
    if isinstance(J, NormalBlocks):
        return J.AA.copy(), J.AP, J.PP
    return blocks_of(J, nb)


def normal_matrix(J: "np.ndarray | NormalBlocks", shape: Shape, mu: float, prior: np.ndarray, dense: bool = False):
    """The Gauss-Newton normal matrix J^T J of the interval-structured residuals, plus ``prior`` (ng,) on the
    global variables' diagonal, Levenberg-Marquardt damped: mu max(d, 1e-12 max(d_max, 1)) added to each diagonal
    entry d.

    Parameters
    ----------
    J : numpy.ndarray or NormalBlocks
        The residuals' Jacobian per interval, (S, rows, nb + ng), or its
        :class:`~alpes_dyn.estimation.identification.normal_blocks.NormalBlocks`.
    shape : Shape
        The problem's sizes.
    mu : float
        The Levenberg-Marquardt damping: mu max(d, 1e-12 max(d_max, 1)) added to each diagonal entry d.
    prior : numpy.ndarray, shape (ng,)
        Added on the global variables' diagonal.
    dense : bool, optional
        Return an array (default False: sparse).

    Returns
    -------
    scipy.sparse.csc_matrix or numpy.ndarray, shape (nz, nz)
        The damped normal matrix.
    """
    nb, nv, nz = shape.nb, shape.nv, shape.nz
    AA, AP, PP = _raw_blocks(J, nb)  # (S, nb, nb), (S, nb, ng), (ng, ng)
    PP = PP + np.diag(prior)
    i1, j1, v1 = _block_diagonal(AA)
    rows = np.arange(nv)
    i2 = np.repeat(rows, shape.ng)
    j2 = np.tile(nv + np.arange(shape.ng), nv)
    v2 = AP.reshape(nv, shape.ng).ravel()
    i3, j3 = np.meshgrid(nv + np.arange(shape.ng), nv + np.arange(shape.ng), indexing="ij")
    H = sp.csc_matrix((np.concatenate([v1, v2, v2, PP.ravel()]),
                       (np.concatenate([i1, i2, j2, i3.ravel()]), np.concatenate([j1, j2, i2, j3.ravel()]))),
                      shape=(nz, nz))
    D = H.diagonal()
    H = H + sp.diags(mu * np.maximum(D, 1e-12 * max(float(D.max(initial=0.0)), 1.0)), format="csc")
    return H.toarray() if dense else H


def continuity_jacobian(Cv: np.ndarray, Cr: np.ndarray, shape: Shape, dense: bool = False):
    """(nc, nz) Jacobian of the continuity defects x_end(j) - x_start(j+1): Cv (S-1, nx, nb) on interval j's
    local variables, -I on the next one's start state (0 at a cut, :attr:`Shape.cut`, where Cv and Cr are 0 too),
    Cr (S-1, nx, ng) on the global ones.

    Parameters
    ----------
    Cv : numpy.ndarray, shape (S-1, nx, nb)
        The continuity defects' Jacobian on each interval's local variables (0 at a cut).
    Cr : numpy.ndarray, shape (S-1, nx, ng)
        Their Jacobian on the global variables (0 at a cut).
    shape : Shape
        The problem's sizes.
    dense : bool, optional
        Return an array (default False: sparse).

    Returns
    -------
    scipy.sparse.csc_matrix or numpy.ndarray, shape (nc, nz)
        The continuity Jacobian.
    """
    nx, nb, nv = shape.nx, shape.nb, shape.nv
    m = shape.n_int - 1
    i1, j1, v1 = _block_diagonal(Cv[:m])
    i2 = np.arange(m * nx)
    j2 = (np.arange(m)[:, None] + 1) * nb + np.arange(nx)[None, :]
    i3 = np.repeat(np.arange(m * nx), shape.ng)
    j3 = np.tile(nv + np.arange(shape.ng), m * nx)
    C = sp.csc_matrix((np.concatenate([v1, -np.repeat(shape.keep, nx), Cr[:m].reshape(-1)]),
                       (np.concatenate([i1, i2, i3]), np.concatenate([j1, j2.ravel(), j3]))),
                      shape=(shape.nc, shape.nz))
    return C.toarray() if dense else C


def kkt_matrix(H, C, dropped: np.ndarray | None = None):
    """[[H, C^T], [C, D]]: the constrained Gauss-Newton system (sparse where H is, else an array); D = diag(``dropped``)
    (nc,), 1 on the rows of the constraints cut (:attr:`Shape.dropped`, their rows of C zero), else 0.

    Parameters
    ----------
    H : scipy.sparse matrix or numpy.ndarray, shape (nz, nz)
        The normal matrix (:func:`normal_matrix`).
    C : scipy.sparse matrix or numpy.ndarray, shape (nc, nz)
        The continuity Jacobian (:func:`continuity_jacobian`).
    dropped : numpy.ndarray, shape (nc,), optional
        1 on the rows of the constraints cut, else 0 (default None: zeros).

    Returns
    -------
    scipy.sparse.csc_matrix or numpy.ndarray, shape (nz + nc, nz + nc)
        The KKT matrix.
    """
    nz, nc = H.shape[0], C.shape[0]
    d = np.zeros(nc) if dropped is None else np.asarray(dropped, dtype=float)
    if sp.issparse(H):
        return sp.bmat([[H, C.T], [C, sp.diags(d) if d.any() else None]], format="csc")
    K = np.zeros((nz + nc, nz + nc))
    K[:nz, :nz], K[:nz, nz:], K[nz:, :nz] = H, C.T, C
    K[nz + np.arange(nc), nz + np.arange(nc)] = d
    return K


def factorize(M) -> Callable[[np.ndarray], np.ndarray]:
    """A solver x = M^-1 b for one factorisation of M, reused for every right-hand side (b: (n,) or (n, k)).

    Sparse M: SuperLU; where it finds M exactly singular, the least-squares (minimum-norm) solution of the dense
    matrix if it has at most :data:`DENSE_LIMIT` rows (a parameter the recording does not see, e.g. tilt_x at a
    level palm; :func:`minimum_norm`, decomposed once), else a ``numpy.linalg.LinAlgError``. Dense M: LU, the
    same least-squares fallback.

    Parameters
    ----------
    M : scipy.sparse matrix or numpy.ndarray, shape (n, n)
        The matrix.

    Returns
    -------
    Callable[[numpy.ndarray], numpy.ndarray]
        ``solve(b)``: x (n,) or (n, k) for b (n,) or (n, k).

    Raises
    ------
    numpy.linalg.LinAlgError
        A sparse M found singular with more than :data:`DENSE_LIMIT` rows.
    """
    if sp.issparse(M):
        try:
            lu = splu(sp.csc_matrix(M))
        except RuntimeError:  # "Factor is exactly singular"
            if M.shape[0] > DENSE_LIMIT:
                raise np.linalg.LinAlgError(f"the shooting fit's {M.shape[0]}-row system is singular") from None
            return minimum_norm(M.toarray())
        return lambda b: lu.solve(np.asarray(b, dtype=float))
    try:
        lu_d = _dense_lu(M)
    except np.linalg.LinAlgError:
        return minimum_norm(M)
    return lu_d


def minimum_norm(M: np.ndarray) -> Solver:
    """The minimum-norm least-squares solver of a square matrix, decomposed once for every right-hand side.

    The answer of ``numpy.linalg.lstsq(M, b, rcond=None)`` (the singular values at most eps n times the largest
    taken as zero), which decomposes M again at each call: the KKT system of a fit whose recording does not see
    a parameter (4000 rows) is solved for each effect's response of the adequacy check. A symmetric M (the KKT
    and normal matrices) by its eigendecomposition (its singular values are its eigenvalues' magnitudes), any
    other by its SVD.

    Parameters
    ----------
    M : numpy.ndarray
        (n, n) the matrix, singular or not.

    Returns
    -------
    callable
        ``solve(b)``: x (n,) or (n, k) for b (n,) or (n, k), the minimum-norm minimiser of ||M x - b||; its
        attribute ``decomposed`` is True.
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    cut = np.finfo(float).eps * n
    if np.array_equal(M, M.T):
        w, V = np.linalg.eigh(M)
        keep = np.abs(w) > cut * np.abs(w).max(initial=0.0)
        left, right, inv = V[:, keep], V[:, keep], 1.0 / w[keep]
    else:
        U, s, Vt = np.linalg.svd(M)
        keep = s > cut * s.max(initial=0.0)
        left, right, inv = U[:, keep], Vt[keep].T, 1.0 / s[keep]

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        c = left.T @ b.reshape(n, -1)
        return (right @ (c * inv[:, None])).reshape(b.shape)

    solve.decomposed = True  # type: ignore[attr-defined]  # (identification._conclude keeps it for the verdict)
    return solve


def _dense_lu(M: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    import warnings

    import scipy.linalg as sla

    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", sla.LinAlgWarning)  # a zero pivot: the least-squares fallback below
        lu, piv = sla.lu_factor(M, check_finite=False)
    if not np.all(np.isfinite(lu)) or np.any(np.diag(lu) == 0.0):
        raise np.linalg.LinAlgError("singular")
    return lambda b: sla.lu_solve((lu, piv), b, check_finite=False)


def kkt_order(shape: Shape) -> np.ndarray:
    """(nz + nc,) the KKT matrix's rows and columns (:func:`kkt_matrix`: local variables, global ones, multipliers)
    in the order that makes all but its last ng banded: interval j's local variables then its continuity
    multipliers (which tie them to interval j+1's start state), interval after interval, the global ones last.

    Parameters
    ----------
    shape : Shape
        The problem's sizes.

    Returns
    -------
    numpy.ndarray, shape (nz + nc,)
        The permutation of the KKT matrix's rows and columns.
    """
    nb, nx, nv, nz, m = shape.nb, shape.nx, shape.nv, shape.nz, shape.n_int - 1
    pairs = np.concatenate([np.arange(m)[:, None] * nb + np.arange(nb)[None, :],
                            nz + np.arange(m)[:, None] * nx + np.arange(nx)[None, :]], axis=1)
    return np.concatenate([pairs.reshape(-1), m * nb + np.arange(nb), nv + np.arange(shape.ng)])


def bordered_factorize(M, order: np.ndarray, border: int) -> Solver:
    """A solver x = M^-1 b (b: (n,) or (n, k)) for a sparse M whose rows and columns taken in ``order`` are banded
    but for the last ``border`` of them (an arrow: :func:`kkt_order`; the homotopy's normal matrix in its own
    order). The banded block A by LAPACK's band LU with partial pivoting (``dgbtrf``), the border by its Schur
    complement D - B' A^-1 B (dense, border x border, :func:`factorize`: its least-squares solution where it is
    singular, a parameter the recording does not see). Where A itself is singular, :func:`factorize` of M (SuperLU).
    Time O(n w (w + border)) and memory O(n (w + border)) for half-bandwidth w: linear in the record.

    Parameters
    ----------
    M : scipy.sparse matrix, shape (N, N)
        The matrix.
    order : numpy.ndarray, shape (N,)
        The permutation of its rows and columns that makes it banded but for its last ``border``.
    border : int
        The number of rows and columns of the border.

    Returns
    -------
    Callable[[numpy.ndarray], numpy.ndarray]
        ``solve(b)``: x (N,) or (N, k) for b (N,) or (N, k).
    """
    M = sp.csr_matrix(M)
    M.sum_duplicates()
    N = M.shape[0]
    n = N - border
    order = np.asarray(order)
    loc, bor = order[:n], order[n:]
    # the blocks taken by slicing (no triplets of the border's entries, most of M's: 5e6 at 600 s)
    rows_loc = M[loc]
    A = rows_loc[:, loc].tocoo()
    il, jl = A.row.astype(np.int64), A.col.astype(np.int64)
    kl, ku = int(max(np.max(il - jl, initial=0), 0)), int(max(np.max(jl - il, initial=0), 0))
    ab = np.zeros((2 * kl + ku + 1, n), order="F")  # Fortran order: dgbtrf factorises it in place, no copy
    ab[kl + ku + il - jl, jl] = A.data
    del A, il, jl
    B = rows_loc[:, bor].toarray()
    del rows_loc
    rows_bor = M[bor]
    Bt, D = rows_bor[:, loc].toarray(), rows_bor[:, bor].toarray()
    del rows_bor
    return _band_border_solver(ab, kl, ku, B, Bt, D, order, lambda: factorize(M))


def _band_border_solver(ab: np.ndarray, kl: int, ku: int, B: np.ndarray, Bt: np.ndarray, D: np.ndarray,
                        order: np.ndarray, fallback: Callable[[], Solver]) -> Solver:
    """The solver of :func:`bordered_factorize` from its blocks: the banded block A in LAPACK's band storage ``ab``
    (2 kl + ku + 1, n; overwritten), the border's columns B (n, border) and rows Bt (border, n), the corner D, and
    ``order`` (the rows and columns of the whole matrix in that order); ``fallback()`` where A is singular."""
    from scipy.linalg.lapack import dgbtrf, dgbtrs

    n, border = ab.shape[1], B.shape[1]
    N = n + border
    lu, piv, info = dgbtrf(ab, kl, ku, overwrite_ab=1)
    if info != 0 or not np.isfinite(lu[kl:]).all():
        return fallback()
    X = dgbtrs(lu, kl, ku, B, piv)[0] if border else B  # A^-1 B, (n, border)
    solve_S = factorize(D - Bt @ X) if border else None
    order = np.asarray(order)

    def solve(b: np.ndarray) -> np.ndarray:
        b = np.asarray(b, dtype=float)
        bp = b.reshape(N, -1)[order]
        y = dgbtrs(lu, kl, ku, bp[:n], piv)[0]
        x = np.empty_like(bp)
        if border:
            x2 = solve_S(bp[n:] - Bt @ y)
            x[n:], y = x2, y - X @ x2
        x[:n] = y
        out = np.empty_like(x)
        out[order] = x
        return out.reshape(b.shape)

    solve.band = (lu, piv)  # type: ignore[attr-defined]  # the band's LU (penalized_from_blocks' local solves)
    return solve


def _normal_blocks(J: "np.ndarray | NormalBlocks", shape: Shape, mu: float, prior: np.ndarray):
    """:func:`normal_matrix`'s blocks by the same operations: AA (S, nb, nb) the intervals' diagonal blocks, AP (S,
    nb, ng) their border, D (ng, ng) the corner (with ``prior``), the diagonal damped as there. J as there."""
    nb = shape.nb
    AA, AP, PP = _raw_blocks(J, nb)  # AA a copy: damped in place below
    PP = PP + np.diag(prior)
    diag_l, diag_g = np.einsum("sii->si", AA).copy(), np.diag(PP).copy()
    big = max(float(max(diag_l.max(initial=0.0), diag_g.max(initial=0.0))), 1.0)
    AA[:, np.arange(nb), np.arange(nb)] += mu * np.maximum(diag_l, 1e-12 * big)
    return AA, AP, PP + np.diag(mu * np.maximum(diag_g, 1e-12 * big))


def _band(blocks: np.ndarray, upper: np.ndarray | None, kl: int, ku: int) -> np.ndarray:
    """LAPACK band storage (2 kl + ku + 1, n) of a block-tridiagonal matrix: ``blocks`` (S, b, b) along the
    diagonal, ``upper`` (S-1, b, c) the block right of block j (its first c columns of block j+1) and its transpose
    below (None: none). A loop over the blocks' entries (b^2), each laid for every block at once."""
    S, b = blocks.shape[:2]
    n = S * b
    ab = np.zeros((2 * kl + ku + 1, n), order="F")  # Fortran order: dgbtrf factorises it in place, no copy
    for a in range(b):
        for c in range(b):
            ab[kl + ku + a - c, c::b] = blocks[:, a, c]
    if upper is not None:
        for a in range(b):
            for c in range(upper.shape[2]):
                ab[kl + ku + a - (b + c), b + c::b] = upper[:, a, c]  # row: block j's a, column: block j+1's c
                ab[kl + ku + (b + c) - a, a:(S - 1) * b:b] = upper[:, a, c]
    return ab


def penalized_from_blocks(J: np.ndarray, Cv: np.ndarray, Cr: np.ndarray, wv: np.ndarray, shape: Shape, mu: float,
                          prior: np.ndarray, hold: np.ndarray, fallback: Callable[[], Solver]):
    """The homotopy's system H + C' W C (:func:`normal_matrix` damped by ``mu``, the continuity Jacobian's rows
    weighted by ``wv`` (nx,), the same weights for every defect), plus 1e12 max(d, 1) on the diagonal of the global
    variables ``hold`` (indices in 0..ng-1; d that diagonal), factorised in its natural order by band and border from
    the intervals' blocks (no sparse matrix formed). Returns (the solver of the whole system, the solver of its
    local variables' block H[:nv, :nv] (the band's LU itself), that block's border H[:nv, nv:] (nv, ng)); the first
    is ``fallback()`` and the second raises ``numpy.linalg.LinAlgError`` where the band is singular.

    Parameters
    ----------
    J : numpy.ndarray or NormalBlocks
        The residuals' Jacobian per interval, (S, rows, nb + ng), or its
        :class:`~alpes_dyn.estimation.identification.normal_blocks.NormalBlocks`.
    Cv : numpy.ndarray, shape (S-1, nx, nb)
        The continuity defects' Jacobian on each interval's local variables (0 at a cut).
    Cr : numpy.ndarray, shape (S-1, nx, ng)
        Their Jacobian on the global variables (0 at a cut).
    wv : numpy.ndarray, shape (nx,)
        The weights of the continuity defects' rows (the same for every defect; none at a cut).
    shape : Shape
        The problem's sizes.
    mu : float
        The Levenberg-Marquardt damping: mu max(d, 1e-12 max(d_max, 1)) added to each diagonal entry d.
    prior : numpy.ndarray, shape (ng,)
        Added on the global variables' diagonal.
    hold : numpy.ndarray
        Indices in 0..ng-1 of the global variables held (1e12 max(d, 1) added to their diagonal).
    fallback : Callable[[], Callable[[numpy.ndarray], numpy.ndarray]]
        Called for the solver where the band is singular (the sparse path's).

    Returns
    -------
    tuple
        (the whole system's solver, its local block's solver, the border H[:nv, nv:] (nv, ng)).
    """
    nb, nx, ng, S = shape.nb, shape.nx, shape.ng, shape.n_int
    AA, AP, D = _normal_blocks(J, shape, mu, prior)
    W = shape.keep[:, None] * wv[None, :]**2  # (S-1, nx): no weight on a cut (Shape.cut)
    Cw = Cv * W[:, :, None]  # W Cv_j (S-1, nx, nb)
    AA[:-1] += np.einsum("sia,sib->sab", Cv, Cw)
    AA[1:, np.arange(nx), np.arange(nx)] += W
    upper = -Cw.transpose(0, 2, 1)  # (S-1, nb, nx): interval j's variables against interval j+1's start state
    B = AP.copy()
    B[:-1] += np.einsum("sia,sig->sag", Cw, Cr)
    B[1:, :nx] -= Cr * W[:, :, None]
    D = D + np.einsum("sig,sih->gh", Cr * W[:, :, None], Cr)
    d = np.diag(D)
    D[hold, hold] += 1e12 * np.maximum(d[hold], 1.0)
    kl = ku = nb + nx - 1
    ab = _band(AA, upper, kl, ku)
    B = B.reshape(S * nb, ng)
    from scipy.linalg.lapack import dgbtrs

    solve = _band_border_solver(ab, kl, ku, B, B.T, D, np.arange(S * nb + ng), fallback)
    band = getattr(solve, "band", None)

    def solve_local(b: np.ndarray) -> np.ndarray:
        if band is None:
            raise np.linalg.LinAlgError("the homotopy's local block is singular")
        return dgbtrs(band[0], kl, ku, np.asarray(b, dtype=float), band[1])[0]

    return solve, solve_local, B


def kkt_from_blocks(J: np.ndarray, Cv: np.ndarray, Cr: np.ndarray, shape: Shape, mu: float, prior: np.ndarray,
                    fallback: Callable[[], Solver]) -> Solver:
    """:func:`bordered_factorize` of :func:`kkt_matrix` (``normal_matrix(J, shape, mu, prior)``, ``continuity_jacobian(Cv,
    Cr, shape)``) in :func:`kkt_order`, its band and border laid out from the intervals' blocks directly: no sparse
    matrix is formed (on a long record its triplets, their CSC, CSR and slices were a peak above the Jacobian). The
    same numbers in the same band as the sparse path (the products J'J by the same einsums), so the same solution
    to rounding.

    Parameters
    ----------
    J : numpy.ndarray or NormalBlocks
        The residuals' Jacobian per interval, (S, rows, nb + ng), or its
        :class:`~alpes_dyn.estimation.identification.normal_blocks.NormalBlocks`.
    Cv : numpy.ndarray, shape (S-1, nx, nb)
        The continuity defects' Jacobian on each interval's local variables (0 at a cut).
    Cr : numpy.ndarray, shape (S-1, nx, ng)
        Their Jacobian on the global variables (0 at a cut).
    shape : Shape
        The problem's sizes.
    mu : float
        The Levenberg-Marquardt damping: mu max(d, 1e-12 max(d_max, 1)) added to each diagonal entry d.
    prior : numpy.ndarray, shape (ng,)
        Added on the global variables' diagonal.
    fallback : Callable[[], Callable[[numpy.ndarray], numpy.ndarray]]
        Called for the solver where the band is singular (the sparse path's).

    Returns
    -------
    Callable[[numpy.ndarray], numpy.ndarray]
        ``solve(b)``: x (nz + nc,) or (nz + nc, k) of the KKT system for b of that shape.
    """
    nb, nx, ng, S = shape.nb, shape.nx, shape.ng, shape.n_int
    m, w = S - 1, nb + nx
    AA, AP, D = _normal_blocks(J, shape, mu, prior)
    n = m * w + nb
    kl = ku = w - 1
    ab = np.zeros((2 * kl + ku + 1, n), order="F")  # Fortran order: dgbtrf factorises it in place, no copy
    blocks = np.zeros((m, w, w))  # interval j's local variables and its multipliers: [[AA_j, Cv_j'], [Cv_j, 0]]
    blocks[:, :nb, :nb] = AA[:m]
    blocks[:, :nb, nb:] = Cv[:m].transpose(0, 2, 1)
    blocks[:, nb:, :nb] = Cv[:m]
    blocks[:, np.arange(nb, w), np.arange(nb, w)] = 1.0 - shape.keep[:, None]  # a cut's multipliers: 0 (Shape.cut)
    for a in range(w):  # a loop over the block's entries (w^2), each laid for every interval at once
        for b in range(w):
            ab[kl + ku + a - b, b:m * w:w] = blocks[:, a, b]
    for a in range(nb):  # the last interval's local variables
        for b in range(nb):
            ab[kl + ku + a - b, m * w + b] = AA[m, a, b]
    keep = shape.keep
    for i in range(nx):  # the multipliers of interval j on interval j+1's start state: -I, both ways (0 at a cut)
        ab[kl + ku + (nb + i) - (w + i), w + i::w] = -keep  # row: multiplier j, column: state of j+1
        ab[kl + ku + (w + i) - (nb + i), nb + i:m * w:w] = -keep  # row: state of j+1, column: multiplier j
    B = np.empty((n, ng))
    B[:m * w].reshape(m, w, ng)[:, :nb] = AP[:m]
    B[:m * w].reshape(m, w, ng)[:, nb:] = Cr[:m]
    B[m * w:] = AP[m]
    return _band_border_solver(ab, kl, ku, B, B.T, D, kkt_order(shape), fallback)
