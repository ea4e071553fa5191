"""The Kalman filters' covariance arithmetic in one fixed order of operations, as CasADi expressions.

The EKF's prediction P_pred = A P A^T + G Sigma_w G^T + Q and the measurement update of both filters (S = H P
H^T + R, K = P H^T S^-1, z + K (y - h), the Joseph form (I - K H) P (I - K H)^T + K R K^T) are written here
scalar by scalar, over the nonzeros of the sparse Jacobians A, G, H and over one triangle of the symmetric
results, every sum in a stated order. The exported C (:mod:`~alpes_dyn.estimation.cexport_ekf`) runs the same
loops in the same order, so the filter's step and its C give the same numbers to the last bit (up to the sign of
an exact zero), with the arithmetic of sparse products and one triangle instead of dense ones (the hand: 134,000
operations per step before, 60,000 after; tested in ``tests/test_cexport.py``).

The loops (i, j rows and columns, k the summed index, column-major storage, "+=" a sum in the loop's order):

* ``add_sandwich(X, M, out)``: T = X M with T[i, j] += X[i, k] M[k, j] for j, then k ascending (the nonzeros
  of X's column k; a zero of a constant M is skipped), then out[i, j] += T[i, k] X[j, k] for i >= j, k
  ascending;
* the prediction: out = Q, add_sandwich(A, P), add_sandwich(G, Sigma_w), the lower triangle mirrored;
* the update: see :func:`updated_state`.

These build expressions once per filter (Python loops over the entries at construction, not per step).
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

__all__ = ["predicted_covariance", "updated_state"]


def _mul(a: Any, b: Any, folds: list[int]) -> Any:
    """a * b; counts in ``folds`` the products CasADi folds (a constant times a product with a constant becomes
    one product with the constants' product: another rounding than the C's two products)."""
    for c, x in ((a, b), (b, a)):
        if (isinstance(c, float) and c != 0.0) or (isinstance(c, cs.SX) and c.is_constant() and not c.is_zero()):
            if isinstance(x, cs.SX) and x.is_op(cs.OP_MUL) and (x.dep(0).is_constant() or x.dep(1).is_constant()):
                folds.append(1)
    return a * b


def _entries(M: Any, n: int, m: int) -> list[list[Any]]:
    """M (n x m, SX or numeric) as rows of scalars (SX 1x1 or floats)."""
    if isinstance(M, cs.SX):
        return [[M[i, j] for j in range(m)] for i in range(n)]
    a = np.asarray(M, float).reshape(n, m)
    return [[float(a[i, j]) for j in range(m)] for i in range(n)]


def _csc(X: cs.SX) -> tuple[list[int], list[int], list[cs.SX]]:
    sp = X.sparsity()
    return list(sp.colind()), list(sp.row()), [X.nz[a] for a in range(sp.nnz())]


def _add_sandwich(X: cs.SX, M: list[list[Any]], out: list[list[Any]], folds: list[int]) -> None:
    """out (lower triangle, in place) += X M X^T, X (n x nc) sparse, M (nc x nc); the order of the module
    docstring."""
    n, nc = X.shape
    colind, row, x = _csc(X)
    T: list[list[Any]] = [[cs.SX(0)] * nc for _ in range(n)]
    for j in range(nc):
        for k in range(nc):
            m = M[k][j]
            if isinstance(m, float) and m == 0.0:
                continue
            for a in range(colind[k], colind[k + 1]):
                T[row[a]][j] = T[row[a]][j] + _mul(x[a], m, folds)
    for k in range(nc):
        for a in range(colind[k], colind[k + 1]):
            j, v = row[a], x[a]
            for i in range(j, n):
                out[i][j] = out[i][j] + _mul(T[i][k], v, folds)


def _mirrored(L: list[list[Any]]) -> cs.SX:
    """The symmetric matrix of a lower triangle L[i][j], i >= j."""
    n = len(L)
    return cs.vertcat(*[cs.horzcat(*[cs.SX(L[i][j] if i >= j else L[j][i]) for j in range(n)]) for i in range(n)])


def predicted_covariance(A: cs.SX, N: cs.SX, P: cs.SX, folds: list[int]) -> cs.SX:
    """A P A^T + N (nz x nz, exactly symmetric): A (nz x nz) sparse, P (nz x nz), N the lower triangle of the
    noise's share G Sigma_w G^T + Q (sparse, computed with the model: the C runs CasADi's code of it); products
    CasADi folds are counted in ``folds`` (:func:`_mul`)."""
    nz = A.shape[0]
    out: list[list[Any]] = [[cs.SX(0)] * nz for _ in range(nz)]
    _add_sandwich(A, _entries(P, nz, nz), out, folds)
    colind, row, x = _csc(N)
    for j in range(nz):
        for a in range(colind[j], colind[j + 1]):
            out[row[a]][j] = out[row[a]][j] + x[a]
    return _mirrored(out)


def _column_sums(X: cs.SX, B: list[list[Any]], n: int, folds: list[int]) -> list[list[Any]]:
    """C = B X^T (n x ny), X (ny x nz) sparse: C[i][r] += B[i][k] X[r, k], k ascending."""
    colind, row, x = _csc(X)
    C: list[list[Any]] = [[cs.SX(0)] * X.shape[0] for _ in range(n)]
    for k in range(X.shape[1]):
        for a in range(colind[k], colind[k + 1]):
            for i in range(n):
                C[i][row[a]] = C[i][row[a]] + _mul(B[i][k], x[a], folds)
    return C


def _gain(PHt: list[list[Any]], S: list[list[Any]]) -> list[list[Any]]:
    """K = P H^T S^-1 (nz x ny): a division when ny = 1, else the Cholesky factor of S (its lower triangle) and
    a forward and a backward substitution per row of K."""
    nz, ny = len(PHt), len(S)
    if ny == 1:
        return [[PHt[i][0] / S[0][0]] for i in range(nz)]
    L = [[S[i][j] for j in range(ny)] for i in range(ny)]
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
    K: list[list[Any]] = []
    for i in range(nz):
        row: list[Any] = [None] * ny
        for r in range(ny):
            s = PHt[i][r]
            for k in range(r):
                s = s - L[r][k] * row[k]
            row[r] = s / L[r][r]
        for r in range(ny - 1, -1, -1):
            s = row[r]
            for k in range(r + 1, ny):
                s = s - L[k][r] * row[k]
            row[r] = s / L[r][r]
        K.append(row)
    return K


def updated_state(z: cs.SX, P: cs.SX, y: cs.SX, h: cs.SX, H: cs.SX, R: np.ndarray,
                  folds: list[int]) -> tuple[cs.SX, cs.SX]:
    """The measurement update: (z_upd (nz,), P_upd (nz x nz), exactly symmetric) from z, P, the measurement y
    (ny,), its prediction h (ny,), H = dh/dz (ny x nz, sparse) and R (ny x ny, numeric). In order:
    P H^T (:func:`_column_sums`), S = R + H (P H^T) (S[r][j] += H[r, k] PHt[k][j], k ascending), K
    (:func:`_gain`), z_upd[i] = z[i] + K[i][r] (y[r] - h[r]) for r ascending, M = P - K (P H^T)^T (M[i][j] -=
    K[i][r] PHt[j][r], r ascending), M H^T, K R (zeros of R skipped), and P_upd[i][j] = M[i][j] + (KR[i][r] -
    MH^T[i][r]) K[j][r], r ascending, for i >= j, mirrored. Products CasADi folds are counted in ``folds``."""
    nz, ny = P.shape[0], H.shape[0]
    Pe = _entries(P, nz, nz)
    PHt = _column_sums(H, Pe, nz, folds)
    Re = _entries(R, ny, ny)
    S = [[cs.SX(Re[r][j]) for j in range(ny)] for r in range(ny)]
    colind, row, x = _csc(H)
    for k in range(nz):
        for a in range(colind[k], colind[k + 1]):
            for j in range(ny):
                S[row[a]][j] = S[row[a]][j] + _mul(x[a], PHt[k][j], folds)
    K = _gain(PHt, S)
    zu = []
    for i in range(nz):
        s = z[i]
        for r in range(ny):
            s = s + K[i][r] * (y[r] - h[r])
        zu.append(s)
    M = []
    for i in range(nz):
        M.append([])
        for j in range(nz):
            s = Pe[i][j]
            for r in range(ny):
                s = s - K[i][r] * PHt[j][r]
            M[i].append(s)
    MHt = _column_sums(H, M, nz, folds)
    D = []
    for i in range(nz):
        D.append([])
        for r in range(ny):
            s = cs.SX(0)
            for k in range(ny):
                if Re[k][r] != 0.0:
                    s = s + _mul(K[i][k], Re[k][r], folds)
            D[i].append(s - MHt[i][r])
    out = [[None] * nz for _ in range(nz)]
    for j in range(nz):
        for i in range(j, nz):
            s = M[i][j]
            for r in range(ny):
                s = s + D[i][r] * K[j][r]
            out[i][j] = s
    return cs.vertcat(*zu), _mirrored(out)
