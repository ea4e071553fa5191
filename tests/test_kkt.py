"""The shooting fit's sparse linear algebra (alpes_dyn.estimation.identification.kkt) against matrices assembled by hand."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from alpes_dyn.estimation.identification.kkt import (Shape, bordered_factorize, continuity_jacobian, factorize,
                                                    kkt_from_blocks, kkt_matrix, kkt_order, minimum_norm,
                                                    normal_matrix, penalized_from_blocks)


def _full_jacobian(J: np.ndarray, shape: Shape) -> np.ndarray:
    """The whole residual Jacobian (all intervals' rows, all variables' columns), written out densely."""
    S, rows, _ = J.shape
    F = np.zeros((S * rows, shape.nz))
    for s in range(S):
        F[s * rows:(s + 1) * rows, s * shape.nb:(s + 1) * shape.nb] = J[s, :, :shape.nb]
        F[s * rows:(s + 1) * rows, shape.nv:] = J[s, :, shape.nb:]
    return F


def test_normal_and_continuity_matrices_equal_the_hand_assembled_ones():
    rng = np.random.default_rng(4)
    shape = Shape(n_int=7, nb=5, nx=4, ng=3)
    J = rng.normal(size=(7, 11, 8))
    prior = np.array([0.0, 1.0, 1.0])
    mu = 1e-2
    F = _full_jacobian(J, shape)
    H_ref = F.T @ F + np.diag(np.r_[np.zeros(shape.nv), prior])
    H_ref[np.diag_indices(shape.nz)] += mu * np.diag(H_ref)
    H = normal_matrix(J, shape, mu, prior)
    assert sp.issparse(H) and np.abs(H.toarray() - H_ref).max() <= 1e-12 * np.abs(H_ref).max()
    assert np.array_equal(normal_matrix(J, shape, mu, prior, dense=True), H.toarray())
    Cv, Cr = rng.normal(size=(6, 4, 5)), rng.normal(size=(6, 4, 3))
    C_ref = np.zeros((shape.nc, shape.nz))
    for j in range(6):
        C_ref[4 * j:4 * j + 4, 5 * j:5 * j + 5] = Cv[j]
        C_ref[4 * j:4 * j + 4, 5 * (j + 1):5 * (j + 1) + 4] -= np.eye(4)
        C_ref[4 * j:4 * j + 4, shape.nv:] = Cr[j]
    C = continuity_jacobian(Cv, Cr, shape)
    assert np.array_equal(C.toarray(), C_ref)
    # the KKT system solved sparse equals the dense solve
    K = kkt_matrix(H, C)
    K_ref = np.block([[H_ref, C_ref.T], [C_ref, np.zeros((shape.nc, shape.nc))]])
    b = rng.normal(size=(shape.nz + shape.nc, 2))
    x = factorize(K)(b)
    assert np.abs(K_ref @ x - b).max() < 1e-9 * np.abs(b).max()
    assert np.abs(x - np.linalg.solve(K_ref, b)).max() < 1e-8 * np.abs(x).max()


def test_a_singular_system_gets_its_minimum_norm_solution():
    """A variable the data do not see (a zero column: tilt_x at a level palm): the least-squares answer, not a crash."""
    M = sp.csc_matrix(np.diag([2.0, 0.0, 4.0]))
    assert np.allclose(factorize(M)(np.array([2.0, 0.0, 8.0])), [1.0, 0.0, 2.0])
    assert np.allclose(factorize(M.toarray())(np.array([2.0, 0.0, 8.0])), [1.0, 0.0, 2.0])


def test_minimum_norm_equals_numpys_lstsq_on_a_singular_kkt_system():
    """The least-squares fallback decomposed once equals numpy's lstsq (which decomposes at each call) on a KKT
    system with a parameter the data do not see (a zero column of J), symmetric (eigh) and not (SVD)."""
    rng = np.random.default_rng(11)
    shape = Shape(n_int=9, nb=5, nx=4, ng=3)
    J = rng.normal(size=(9, 11, 8))
    J[:, :, -1] = 0.0  # the last parameter unseen
    Cv, Cr = rng.normal(size=(8, 4, 5)), rng.normal(size=(8, 4, 3))
    Cr[:, :, -1] = 0.0
    K = kkt_matrix(normal_matrix(J, shape, 0.0, np.zeros(3)), continuity_jacobian(Cv, Cr, shape)).toarray()
    assert np.linalg.matrix_rank(K) < K.shape[0]
    b = rng.normal(size=(K.shape[0], 3))
    for M in (K, K + np.triu(rng.normal(scale=1e-3, size=K.shape), 1) * (K != 0)):  # symmetric, then not
        ref = np.linalg.lstsq(M, b, rcond=None)[0]
        solve = minimum_norm(M)
        assert np.abs(solve(b) - ref).max() < 1e-9 * np.abs(ref).max()
        assert np.abs(solve(b[:, 1]) - ref[:, 1]).max() < 1e-9 * np.abs(ref).max()
    assert np.abs(factorize(sp.csc_matrix(K))(b) - np.linalg.lstsq(K, b, rcond=None)[0]).max() < 1e-9 * np.abs(b).max()


def _problem(rng, shape: Shape, mu: float):
    J = rng.normal(size=(shape.n_int, 9, shape.nb + shape.ng))
    H = normal_matrix(J, shape, mu, np.r_[np.zeros(2), np.ones(shape.ng - 2)])
    m = shape.n_int - 1
    C = continuity_jacobian(rng.normal(size=(m, shape.nx, shape.nb)), rng.normal(size=(m, shape.nx, shape.ng)), shape)
    return H, C


def test_the_banded_and_bordered_factorisation_solves_as_the_dense_one():
    """The KKT system in its interleaved order (kkt_order: banded but for the global variables), the homotopy's
    H + C'C in its own order, and the local block without a border: each solved as numpy's dense solve does."""
    rng = np.random.default_rng(7)
    shape = Shape(n_int=9, nb=6, nx=4, ng=5)
    H, C = _problem(rng, shape, 1e-3)
    K = kkt_matrix(H, C)
    order = kkt_order(shape)
    assert sorted(order.tolist()) == list(range(shape.nz + shape.nc))
    # interval j's local variables and multipliers, then interval j+1's: half-bandwidth nb + nx - 1
    Kp = K.toarray()[np.ix_(order, order)][: -shape.ng, : -shape.ng]
    ii, jj = np.nonzero(Kp)
    assert np.max(np.abs(ii - jj)) == shape.nb + shape.nx - 1
    b = rng.normal(size=(shape.nz + shape.nc, 3))
    x = bordered_factorize(K, order, shape.ng)(b)
    ref = np.linalg.solve(K.toarray(), b)
    assert np.abs(x - ref).max() < 1e-9 * np.abs(ref).max()
    assert np.abs(bordered_factorize(K, order, shape.ng)(b[:, 0]) - ref[:, 0]).max() < 1e-9 * np.abs(ref).max()
    N = H + C.T @ C
    xn = bordered_factorize(N, np.arange(shape.nz), shape.ng)(b[:shape.nz])
    assert np.abs(xn - np.linalg.solve(N.toarray(), b[:shape.nz])).max() < 1e-9 * np.abs(xn).max()
    Nl = N[:shape.nv, :shape.nv]
    xl = bordered_factorize(Nl, np.arange(shape.nv), 0)(b[:shape.nv, 0])
    assert np.abs(xl - np.linalg.solve(Nl.toarray(), b[:shape.nv, 0])).max() < 1e-9 * np.abs(xl).max()


def test_a_blind_global_variable_gets_the_least_squares_answer_in_the_border():
    """A global variable no residual or defect sees (its row and column zero, undamped): the Schur complement is
    singular, its least-squares solution gives that variable 0 and the rest as the system without it."""
    rng = np.random.default_rng(8)
    shape = Shape(n_int=6, nb=4, nx=4, ng=3)
    J = rng.normal(size=(6, 7, 7))
    J[:, :, -1] = 0.0
    m = 5
    Cr = rng.normal(size=(m, 4, 3))
    Cr[:, :, -1] = 0.0
    K = kkt_matrix(normal_matrix(J, shape, 0.0, np.zeros(3)),
                   continuity_jacobian(rng.normal(size=(m, 4, 4)), Cr, shape))
    b = rng.normal(size=shape.nz + shape.nc)
    b[shape.nz - 1] = 0.0
    x = bordered_factorize(K, kkt_order(shape), shape.ng)(b)
    keep = np.arange(shape.nz + shape.nc) != shape.nz - 1
    ref = np.linalg.solve(K.toarray()[np.ix_(keep, keep)], b[keep])
    assert x[shape.nz - 1] == 0.0 and np.abs(x[keep] - ref).max() < 1e-9 * np.abs(ref).max()


def test_the_kkt_laid_out_from_the_blocks_solves_as_the_sparse_and_the_dense_one():
    """kkt_from_blocks (the band and border filled from J, Cv, Cr, no sparse matrix) against the sparse path
    (bordered_factorize of kkt_matrix: the same band, so the same solution to rounding) and numpy's dense solve of
    the matrix assembled by hand, damped and undamped; a singular band falls back to the given solver."""
    rng = np.random.default_rng(9)
    shape = Shape(n_int=8, nb=7, nx=4, ng=5)
    J = rng.normal(size=(8, 9, 12))
    Cv, Cr = rng.normal(size=(7, 4, 7)), rng.normal(size=(7, 4, 5))
    prior = np.r_[np.zeros(2), np.ones(3)]
    F = _full_jacobian(J, shape)
    C_ref = np.zeros((shape.nc, shape.nz))
    for j in range(7):
        C_ref[4 * j:4 * j + 4, 7 * j:7 * j + 7] = Cv[j]
        C_ref[4 * j:4 * j + 4, 7 * (j + 1):7 * (j + 1) + 4] -= np.eye(4)
        C_ref[4 * j:4 * j + 4, shape.nv:] = Cr[j]
    b = rng.normal(size=(shape.nz + shape.nc, 2))
    for mu in (0.0, 1e-2):
        H_ref = F.T @ F + np.diag(np.r_[np.zeros(shape.nv), prior])
        H_ref[np.diag_indices(shape.nz)] += mu * np.diag(H_ref)
        K_ref = np.block([[H_ref, C_ref.T], [C_ref, np.zeros((shape.nc, shape.nc))]])
        x = kkt_from_blocks(J, Cv, Cr, shape, mu, prior, lambda: None)(b)
        K = kkt_matrix(normal_matrix(J, shape, mu, prior), continuity_jacobian(Cv, Cr, shape))
        x_sparse = bordered_factorize(K, kkt_order(shape), shape.ng)(b)
        assert np.abs(x - x_sparse).max() <= 1e-12 * np.abs(x).max()
        assert np.abs(x - np.linalg.solve(K_ref, b)).max() < 1e-9 * np.abs(x).max()
    J0 = J.copy()
    J0[:, :, 0] = 0.0  # interval 0's first local variable seen by nothing but its multipliers' -I: none, the band singular
    Cv0 = Cv.copy()
    Cv0[:, :, 0] = 0.0
    assert kkt_from_blocks(J0, Cv0, Cr, shape, 0.0, prior, lambda: "fallback") == "fallback"


def test_the_homotopy_system_laid_out_from_the_blocks_solves_as_the_sparse_one():
    """penalized_from_blocks: H + C'WC with two global variables held (1e12 max(d, 1) on their diagonal), laid out
    from the blocks, against that matrix assembled sparse (normal_matrix, continuity_jacobian) and solved densely;
    its local solver against the dense solve of H[:nv, :nv], its border against H[:nv, nv:]."""
    rng = np.random.default_rng(10)
    shape = Shape(n_int=7, nb=6, nx=4, ng=5)
    J = rng.normal(size=(7, 9, 11))
    Cv, Cr = rng.normal(size=(6, 4, 6)), rng.normal(size=(6, 4, 5))
    prior, wv, hold, mu = np.r_[np.zeros(2), np.ones(3)], np.array([1.0, 3.0, 0.5, 2.0]), np.array([1, 4]), 1e-3
    C = sp.diags(np.tile(wv, 6)) @ continuity_jacobian(Cv, Cr, shape)
    H = (normal_matrix(J, shape, mu, prior) + C.T @ C).toarray()
    idx = shape.nv + hold
    H[idx, idx] += 1e12 * np.maximum(H[idx, idx], 1.0)
    solve, solve_local, border = penalized_from_blocks(J, Cv, Cr, wv, shape, mu, prior, hold, lambda: None)
    b = rng.normal(size=shape.nz)
    ref = np.linalg.solve(H, b)
    assert np.abs(solve(b) - ref).max() < 1e-9 * np.abs(ref).max()
    nv = shape.nv
    assert np.abs(border - H[:nv, nv:]).max() <= 1e-12 * np.abs(H[:nv, nv:]).max()
    ref_l = np.linalg.solve(H[:nv, :nv], b[:nv])
    assert np.abs(solve_local(b[:nv]) - ref_l).max() < 1e-9 * np.abs(ref_l).max()
