"""A tree's joint-space mass matrix as a sparse symbolic matrix, and its solve (issue 51: the whole hand sized).

For a tree of joints the entry M_ij of the mass matrix is zero unless joint i is joint j, one of its ancestors or one
of its descendants (Featherstone's branch-induced sparsity): :func:`tree_pattern` is that pattern, which the backends
of :mod:`~alpes_dyn.symbolic.dynamics` keep structurally (ADAM's CRBA returns every entry, zeros included).
:func:`block_solve` solves M x = b block by block over the pattern's strongly connected components (the fingers of a
fixed palm) by an unrolled LDL^T, each block eliminated leaves first and root last (:func:`elimination_order`): no
fill-in, so a hand whose five fingers hang from a free wrist costs five finger factorisations and the wrist's rows,
not one dense 24 x 24 factorisation (on the Shadow hand the Jacobian of its forward dynamics fell from 514k to 75k
instructions).
"""

from __future__ import annotations

from typing import Any, Sequence

import casadi as cs
import numpy as np

__all__ = ["sparse_dm", "tree_pattern", "elimination_order", "block_solve"]


def sparse_dm(A: np.ndarray) -> cs.DM:
    """A numeric matrix as a CasADi DM with only its non-zero entries structural (a dense DM would make
    every entry structurally non-zero and merge the blocks of :func:`block_solve`).

    Parameters
    ----------
    A : array_like
        The matrix.

    Returns
    -------
    casadi.DM
        Its non-zero entries, structural.
    """
    A = np.asarray(A, dtype=float)
    rows, cols = np.nonzero(A)
    return cs.DM.triplet(rows.tolist(), cols.tolist(), cs.DM(A[rows, cols]), A.shape[0], A.shape[1])


def tree_pattern(parents: Sequence[int]) -> cs.Sparsity:
    """The structural pattern of a tree's joint-space mass matrix: entry (i, j) where joint i is joint j, its
    ancestor or its descendant (Featherstone's branch-induced sparsity; every other entry is exactly zero).

    Parameters
    ----------
    parents : sequence of int
        (n,) each joint's parent joint index (-1 for a joint on the base), joints in any order.

    Returns
    -------
    casadi.Sparsity
        (n, n) the pattern.
    """
    n = len(parents)
    mask = np.eye(n, dtype=bool)
    for i in range(n):  # (a loop over the joints, once per model)
        j, seen = int(parents[i]), 0
        while j >= 0 and seen < n:
            mask[i, j] = mask[j, i] = True
            j, seen = int(parents[j]), seen + 1
    rows, cols = np.nonzero(mask)
    return cs.Sparsity.triplet(n, n, rows.tolist(), cols.tolist())


def elimination_order(sp: cs.Sparsity, rows: Sequence[int]) -> list[int]:
    """The order in which :func:`block_solve` eliminates ``rows`` of a symmetric pattern ``sp``: by the number
    of structural entries of each row within ``rows``, fewest first (ties in their given order). On a tree's
    pattern (:func:`tree_pattern`) a descendant's row is a subset of its ancestor's, so this is leaves first,
    root last, and the factor has no entry outside the pattern (each row's later neighbours are its
    ancestors and its equals: a clique).

    Parameters
    ----------
    sp : casadi.Sparsity
        (n, n) the symmetric pattern.
    rows : sequence of int
        The rows of one block.

    Returns
    -------
    list of int
        ``rows`` reordered.
    """
    rows = [int(r) for r in rows]
    inside = np.zeros(sp.size1(), dtype=bool)
    inside[rows] = True
    row, colind = np.asarray(sp.row(), dtype=int), sp.colind()
    count = {r: int(inside[row[colind[r]:colind[r + 1]]].sum()) for r in rows}
    return sorted(rows, key=lambda r: count[r])


def block_solve(M: cs.SX, b: cs.SX) -> cs.SX:
    """Solve M x = b for a symbolic symmetric positive definite M (a mass matrix).

    Block by block over the structural strongly connected components of M (one per finger of the
    hand), each by an unrolled LDL^T factorisation: no square root, one division per pivot, fewer
    operations than a QR in generated code, and expressions that stay small under AD. Within a block the
    rows are eliminated in :func:`elimination_order` (a tree's leaves first, its root last: no fill-in, so
    a hand whose fingers hang from a free wrist costs each finger's factorisation and the wrist's, not a
    dense one over every joint).

    Parameters
    ----------
    M : casadi.SX
        (n, n) the matrix.
    b : casadi.SX
        (n,) or (n, k) the right side.

    Returns
    -------
    casadi.SX
        x, the shape of b.
    """
    nb, perm, offsets = M.sparsity().scc()
    x: list[Any] = [None] * M.shape[0]
    zero = cs.SX(0)
    for blk in range(nb):
        rows = elimination_order(M.sparsity(), perm[offsets[blk]:offsets[blk + 1]])
        A, r, n = M[rows, rows], b[rows], len(rows)
        L = [[zero] * n for _ in range(n)]
        D: list[Any] = [None] * n
        for j in range(n):
            D[j] = A[j, j] - sum((L[j][k] * L[j][k] * D[k] for k in range(j)), zero)
            for i in range(j + 1, n):
                L[i][j] = (A[i, j] - sum((L[i][k] * L[j][k] * D[k] for k in range(j)), zero)) / D[j]
        y: list[Any] = [None] * n
        for i in range(n):
            y[i] = r[i] - sum((L[i][k] * y[k] for k in range(i)), zero)
        xs: list[Any] = [None] * n
        for i in reversed(range(n)):
            xs[i] = y[i] / D[i] - sum((L[k][i] * xs[k] for k in range(i + 1, n)), zero)
        for i, row in enumerate(rows):
            x[row] = xs[i]
    return cs.vertcat(*x)
