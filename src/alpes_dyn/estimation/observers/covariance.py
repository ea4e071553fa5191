"""The Kalman filters' covariance arithmetic in one fixed order of operations, as CasADi expressions.

The EKF's prediction P_pred = A P A^T + G Sigma_w G^T + Q and the measurement update of both filters (S = H P
H^T + R, K = P H^T S^-1, z + K (y - h), the Joseph form (I - K H) P (I - K H)^T + K R K^T) are written here
over the nonzeros of the sparse Jacobians A, G, H and over one triangle of the symmetric results, every sum in a
stated order. The exported C (:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`) runs the same
loops in the same order, so the filter's step and its C give the same numbers to the last bit (up to the sign of
an exact zero), with the arithmetic of sparse products and one triangle instead of dense ones (the hand: 134,000
operations per step before, 60,000 after; tested in ``tests/test_cexport.py``).

The loops (i, j rows and columns, k the summed index, column-major storage, "+=" a sum in the loop's order):

* ``add_sandwich(X, M, out)``: T = X M with T[i, j] += X[i, k] M[k, j] for j, then k ascending (the nonzeros
  of X's column k; a zero of a constant M is skipped), then out[i, j] += T[i, k] X[j, k] for i >= j, k
  ascending;
* the prediction: out = Q, add_sandwich(A, P), add_sandwich(G, Sigma_w), the lower triangle mirrored;
* the update: see :func:`updated_state`.

They are built as CasADi matrix operations (``mtimes``, ``mac``, column and outer products) whose sums run in
these orders: CasADi's sparse product accumulates z[i, j] += x[i, k] y[k, j] over the nonzeros k of y's column j,
ascending, from z's entry (a structural zero, or R's in ``mac``) -- the same operations, the same numbers as the
scalar loops written out entry by entry before, built far faster (a few operations on matrices instead of one
Python call per entry; the whole build: ``benchmarks/results/observer_build.json``, its rows' ``build_first_s``).
The products by a constant that CasADi folds are found on the matrices' entries (:func:`_count_folds`), not by a Python call per product.
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

__all__ = ["predicted_covariance", "updated_state", "chol_sym"]


def _kinds(entries: list[Any]) -> tuple[list[bool], list[bool]]:
    """For each entry (SX 1x1): is it a nonzero constant; is it a product with a constant factor."""
    const = [bool(e.is_constant() and not e.is_zero()) for e in entries]
    scaled = [bool(e.is_op(cs.OP_MUL) and (e.dep(0).is_constant() or e.dep(1).is_constant())) for e in entries]
    return const, scaled


def _count_folds(X: cs.SX, Y: cs.SX, folds: list[int], lower: bool = False) -> None:
    """Count in ``folds`` the products X[i, k] Y[k, j] of ``mtimes(X, Y)`` (``lower``: only those with i >= j) that
    CasADi folds: a nonzero constant times a product with a constant factor (another rounding than the C's two
    products). Checked per summed index k on the nonzeros of X's column k and Y's row k."""
    xs, ys = X.sparsity(), Y.T.sparsity()
    xc, xm = _kinds(X.nonzeros())
    yc, ym = _kinds(Y.T.nonzeros())  # Y's rows as the columns of its transpose
    xcol, xrow, ycol, yrow = xs.colind(), xs.row(), ys.colind(), ys.row()
    for k in range(X.shape[1]):
        xa, ya = range(xcol[k], xcol[k + 1]), range(ycol[k], ycol[k + 1])
        for left, right in ((xc, ym), (xm, yc)):
            rows = [xrow[a] for a in xa if left[a]]
            cols = [yrow[b] for b in ya if right[b]]
            if rows and cols and (not lower or max(rows) >= min(cols)):
                folds.append(1)
                return


def _mirrored(L: cs.SX) -> cs.SX:
    """The dense symmetric matrix of the lower triangle of L (its upper entries ignored)."""
    low = cs.tril(L)
    return cs.densify(low + cs.tril(low, False).T)


def predicted_covariance(A: cs.SX, N: cs.SX, P: cs.SX, folds: list[int]) -> cs.SX:
    """A P A^T + N (nz x nz, dense, exactly symmetric). T = A P, then T A^T (lower triangle), then + N.

    Parameters
    ----------
    A : casadi.SX, shape (nz, nz)
        The step's Jacobian dF/dz (sparse).
    N : casadi.SX, shape (nz, nz)
        The lower triangle of the noise's share G Sigma_w G^T + Q (sparse, computed with the model: the C runs
        CasADi's code of it).
    P : casadi.SX, shape (nz, nz)
        The covariance before the predict.
    folds : list[int]
        A counter of the products CasADi folds (:func:`_count_folds`), appended to in place.

    Returns
    -------
    casadi.SX, shape (nz, nz)
        The predicted covariance.
    """
    T = cs.mtimes(A, P)
    _count_folds(A, P, folds)
    At = A.T
    _count_folds(T, At, folds, lower=True)
    return _mirrored(cs.tril(cs.mtimes(T, At)) + N)


def _gain(PHt: cs.SX, S: cs.SX) -> cs.SX:
    """K = P H^T S^-1 (nz x ny): a division when ny = 1, else the Cholesky factor of S (its lower triangle) and
    a forward and a backward substitution of K's columns (each entry's sums in the order of one row's)."""
    ny = S.shape[0]
    if ny == 1:
        return PHt / S[0, 0]
    L = [[S[i, j] for j in range(ny)] for i in range(ny)]
    for j in range(ny):
        d = L[j][j]
        for k in range(j):
            d = d - L[j][k] * L[j][k]
        L[j][j] = cs.sqrt(d)
        for i in range(j + 1, ny):
            s = L[i][j]
            for k in range(j):
                s = s - L[i][k] * L[j][k]
            L[i][j] = s / L[j][j]
    cols: list[Any] = [None] * ny
    for r in range(ny):
        s = PHt[:, r]
        for k in range(r):
            s = s - L[r][k] * cols[k]
        cols[r] = s / L[r][r]
    for r in range(ny - 1, -1, -1):
        s = cols[r]
        for k in range(r + 1, ny):
            s = s - L[k][r] * cols[k]
        cols[r] = s / L[r][r]
    return cs.horzcat(*cols)


def updated_state(z: cs.SX, P: cs.SX, y: cs.SX, h: cs.SX, H: cs.SX, R: np.ndarray,
                  folds: list[int]) -> tuple[cs.SX, cs.SX]:
    """The measurement update: (z_upd (nz,), P_upd (nz x nz), dense, exactly symmetric) from z, P, the measurement y
    (ny,), its prediction h (ny,), H = dh/dz (ny x nz, sparse) and R (ny x ny, numeric). In order:
    P H^T (PHt[i, r] += P[i, k] H[r, k], k ascending), S = R + H (P H^T) (S[r, j] from R[r, j], += H[r, k]
    PHt[k, j], k ascending), K (:func:`_gain`), z_upd[i] = z[i] + K[i, r] (y[r] - h[r]) for r ascending,
    M = P - K (P H^T)^T (M[i, j] -= K[i, r] PHt[j, r], r ascending), M H^T, K R (zeros of R skipped), and
    P_upd[i, j] = M[i, j] + (KR[i, r] - MH^T[i, r]) K[j, r], r ascending, for i >= j, mirrored.

    Parameters
    ----------
    z : casadi.SX, shape (nz,)
        The predicted state.
    P : casadi.SX, shape (nz, nz)
        The predicted covariance.
    y : casadi.SX, shape (ny,)
        The measurement.
    h : casadi.SX, shape (ny,)
        Its prediction h(z).
    H : casadi.SX, shape (ny, nz)
        dh/dz (sparse).
    R : numpy.ndarray, shape (ny, ny)
        The measurement noise's covariance (numeric).
    folds : list[int]
        A counter of the products CasADi folds (:func:`_count_folds`), appended to in place.

    Returns
    -------
    tuple[casadi.SX, casadi.SX]
        z_upd (nz,) and P_upd (nz, nz), dense, exactly symmetric.
    """
    ny = H.shape[0]
    Ht = H.T
    PHt = cs.mtimes(P, Ht)
    _count_folds(P, Ht, folds)
    R_dm = cs.DM(np.asarray(R, float).reshape(ny, ny))
    S = cs.mac(H, PHt, cs.densify(cs.SX(R_dm)))
    _count_folds(H, PHt, folds)
    K = _gain(PHt, S)
    zu = z
    for r in range(ny):
        zu = zu + K[:, r] * (y[r] - h[r])
    M = P
    for r in range(ny):
        M = M - cs.mtimes(K[:, r], PHt[:, r].T)
    MHt = cs.mtimes(M, Ht)
    _count_folds(M, Ht, folds)
    Rs = cs.SX(cs.sparsify(R_dm))
    KR = cs.mtimes(K, Rs)
    _count_folds(K, Rs, folds)
    D = KR - MHt
    out = M
    for r in range(ny):
        out = out + cs.mtimes(D[:, r], K[:, r].T)
    return zu, _mirrored(out)


def chol_sym(P: cs.SX) -> cs.SX:
    """Lower Cholesky factor of a symbolic symmetric positive definite matrix (unrolled).

    Parameters
    ----------
    P : casadi.SX, shape (n, n)
        The symmetric positive definite matrix (its lower triangle read; each pivot floored at 1e-300).

    Returns
    -------
    casadi.SX, shape (n, n)
        L, lower triangular, with L L^T = P.
    """
    n = P.shape[0]
    L = [[cs.SX(0) for _ in range(n)] for _ in range(n)]
    for j in range(n):
        d = P[j, j] - sum((L[j][k] * L[j][k] for k in range(j)), cs.SX(0))
        L[j][j] = cs.sqrt(cs.fmax(d, 1e-300))
        for i in range(j + 1, n):
            L[i][j] = (P[i, j] - sum((L[i][k] * L[j][k] for k in range(j)), cs.SX(0))) / L[j][j]
    return cs.vertcat(*[cs.horzcat(*row) for row in L])
