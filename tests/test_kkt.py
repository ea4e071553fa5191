"""The shooting fit's sparse linear algebra (alpes_dyn.estimation.identification.kkt) against matrices assembled by hand."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from alpes_dyn.estimation.identification.kkt import Shape, continuity_jacobian, factorize, kkt_matrix, normal_matrix


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
