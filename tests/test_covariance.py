"""The filters' covariance arithmetic (estimation.observers.covariance) built as CasADi matrix operations: its numbers
against numpy's closed forms of the prediction and the Joseph-form update, and its count of the products CasADi folds
against the definition checked product by product."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

from alpes_dyn.estimation.observers.covariance import _count_folds, predicted_covariance, updated_state


def _sparse_sym(name: str, mask: np.ndarray) -> cs.SX:
    """A symbolic matrix with nonzeros where ``mask`` is True."""
    rows, cols = np.nonzero(mask)
    return cs.SX.sym(name, cs.Sparsity.triplet(mask.shape[0], mask.shape[1], rows.tolist(), cols.tolist()))


def _on(a: np.ndarray, X: cs.SX) -> cs.DM:
    """``a``'s entries on X's sparsity (column-major nonzeros)."""
    sp = X.sparsity()
    return cs.DM(sp, [float(a[r, c]) for r, c in zip(sp.row(), sp.get_col())])


@pytest.mark.parametrize("ny", [1, 3])
def test_update_and_prediction_equal_the_closed_forms(ny):
    rng = np.random.default_rng(ny)
    nz = 7
    A_mask = (rng.random((nz, nz)) < 0.4) | np.eye(nz, dtype=bool)
    H_mask = rng.random((ny, nz)) < 0.5
    H_mask[np.arange(ny), np.arange(ny)] = True
    A, H, N = _sparse_sym("A", A_mask), _sparse_sym("H", H_mask), _sparse_sym("N", np.tril(np.ones((nz, nz))) > 0)
    z, P, y, h = cs.SX.sym("z", nz), cs.SX.sym("P", nz, nz), cs.SX.sym("y", ny), cs.SX.sym("h", ny)
    R = np.diag(rng.uniform(0.5, 2.0, ny))
    if ny > 1:
        R[0, -1] = R[-1, 0] = 0.1  # a correlated pair: K R runs over R's nonzeros
    folds: list[int] = []
    zu, Pu = updated_state(z, P, y, h, H, R, folds)
    Pp = predicted_covariance(A, N, P, folds)
    f = cs.Function("f", [z, P, y, h, A, H, N], [zu, Pu, Pp])
    An = np.where(A_mask, rng.standard_normal((nz, nz)), 0.0)
    Hn = np.where(H_mask, rng.standard_normal((ny, nz)), 0.0)
    B, C = rng.standard_normal((nz, nz)), rng.standard_normal((nz, nz))
    Pn, Nn = B @ B.T + np.eye(nz), C @ C.T
    zn, yn, hn = rng.standard_normal(nz), rng.standard_normal(ny), rng.standard_normal(ny)
    zu_n, Pu_n, Pp_n = (np.array(o) for o in f(zn, Pn, yn, hn, _on(An, A), _on(Hn, H), _on(np.tril(Nn), N)))
    K = Pn @ Hn.T @ np.linalg.inv(Hn @ Pn @ Hn.T + R)
    IKH = np.eye(nz) - K @ Hn
    assert np.allclose(zu_n.ravel(), zn + K @ (yn - hn), rtol=0, atol=1e-12)
    assert np.allclose(Pu_n, IKH @ Pn @ IKH.T + K @ R @ K.T, rtol=0, atol=1e-12)
    assert np.allclose(Pp_n, An @ Pn @ An.T + Nn, rtol=0, atol=1e-12)
    assert np.array_equal(Pu_n, Pu_n.T) and np.array_equal(Pp_n, Pp_n.T)  # one triangle, mirrored
    assert Pu.is_dense() and Pp.is_dense()  # the filter's state s = [z; vec P] stays dense
    assert folds == []  # symbols everywhere: nothing to fold


def _folds_by_product(X: cs.SX, Y: cs.SX, lower: bool) -> int:
    """The definition: the products X[i, k] Y[k, j] (i >= j if ``lower``) of a nonzero constant and a product with
    a constant factor, counted one by one."""
    def const(e):
        return e.is_constant() and not e.is_zero()

    def scaled(e):
        return e.is_op(cs.OP_MUL) and (e.dep(0).is_constant() or e.dep(1).is_constant())

    n = 0
    for i in range(X.shape[0]):
        for j in range(Y.shape[1]):
            for k in range(X.shape[1]):
                if (i >= j or not lower) and X.sparsity().has_nz(i, k) and Y.sparsity().has_nz(k, j):
                    a, b = X[i, k], Y[k, j]
                    n += bool((const(a) and scaled(b)) or (const(b) and scaled(a)))
    return n


def test_fold_count_equals_the_definition():
    rng = np.random.default_rng(0)
    x = cs.SX.sym("x", 4)
    kinds = [lambda: cs.SX(0.5 + rng.random()), lambda: x[rng.integers(4)] * (2.5 + rng.random()),
             lambda: x[rng.integers(4)] * x[rng.integers(4)], lambda: x[rng.integers(4)]]

    def matrix(n: int, m: int) -> cs.SX:
        M = cs.SX(n, m)
        for i in range(n):
            for j in range(m):
                if rng.random() < 0.3:
                    M[i, j] = kinds[rng.integers(4)]()
        return M

    seen = set()
    for _ in range(40):
        X, Y = matrix(4, 3), matrix(3, 4)
        for lower in (False, True):
            folds: list[int] = []
            _count_folds(X, Y, folds, lower=lower)
            expected = _folds_by_product(X, Y, lower) > 0
            assert bool(folds) == expected
            seen.add(expected)
    assert seen == {True, False}  # both cases drawn
