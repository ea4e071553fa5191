"""A tree's mass matrix kept sparse in the symbolic dynamics (issue 51, the whole hand sized): the entries between
joints on different branches are exactly zero (Featherstone's branch-induced sparsity), so they are left out of the
expressions, and :func:`~alpes_dyn.symbolic.dynamics.block_solve` factorises leaves first, root last (no fill-in).

The model is a small "hand": a free wrist and two fingers of two joints, off-axis inertias and tilted axes. The
references are Pinocchio's CRBA and ABA (the numeric model) and numpy's dense solve, not the code under test."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.spec import TransmissionSpec
from alpes_dyn.symbolic.dynamics import SymbolicDynamics
from alpes_dyn.symbolic.tree_sparsity import block_solve, elimination_order, tree_pattern
from alpes_dyn.symbolic.parametric import ParametricDynamics


def _link(name: str, mass: float, c: tuple[float, float, float]) -> str:
    return (f'<link name="{name}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{mass}"/>'
            f'<inertia ixx="2e-6" ixy="1e-7" ixz="0" iyy="3e-6" iyz="2e-7" izz="1.5e-6"/></inertial></link>')


def _joint(name: str, parent: str, child: str, xyz: str, axis: str) -> str:
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{xyz}" rpy="0.1 0 0.2"/><axis xyz="{axis}"/>'
            '<limit lower="-1" upper="1.2" effort="1" velocity="10"/></joint>')


SMALL_HAND = ('<?xml version="1.0"?><robot name="small_hand"><link name="base"/>'
              + _link("palm", 0.2, (0.0, 0.01, 0.04)) + _link("a1", 0.03, (0.0, 0.0, 0.02))
              + _link("a2", 0.02, (0.003, 0.0, 0.015)) + _link("b1", 0.04, (0.0, 0.002, 0.02))
              + _link("b2", 0.01, (0.0, 0.0, 0.01))
              + _joint("wrist", "base", "palm", "0 0 0", "0 1 0") + _joint("a_j1", "palm", "a1", "0.02 0 0.08", "1 0 0")
              + _joint("a_j2", "a1", "a2", "0 0 0.04", "0 1 0") + _joint("b_j1", "palm", "b1", "-0.02 0 0.08", "1 0 0")
              + _joint("b_j2", "b1", "b2", "0 0 0.04", "0 0 1") + "</robot>")
PARENTS = [-1, 0, 1, 0, 3]  # wrist; a_j1 <- wrist; a_j2 <- a_j1; b_j1 <- wrist; b_j2 <- b_j1


@pytest.fixture(scope="module")
def hand():
    return ad.Model(SMALL_HAND, TransmissionSpec.from_toml('gravity = [0.0, 0.0, -9.81]\n\n[stiffness]\na_j1 = 0.01\nb_j2 = 0.02\n'))


def _pattern(sp: cs.Sparsity) -> np.ndarray:
    out = np.zeros(sp.shape, dtype=bool)
    r, c = sp.get_triplet()
    out[r, c] = True
    return out


def test_tree_pattern_is_the_ancestor_relation():
    expected = np.array([[1, 1, 1, 1, 1], [1, 1, 1, 0, 0], [1, 1, 1, 0, 0], [1, 0, 0, 1, 1], [1, 0, 0, 1, 1]], bool)
    assert np.array_equal(_pattern(tree_pattern(PARENTS)), expected)
    assert tree_pattern([-1]).nnz() == 1  # one joint: its own entry


def test_mass_matrix_sparse_and_equal_to_crba(hand):
    assert list(hand.joint_names) == ["wrist", "a_j1", "a_j2", "b_j1", "b_j2"]
    sd = SymbolicDynamics(hand, backend="adam")
    q, v, tau = (cs.SX.sym(s, hand.n) for s in "qvt")
    M = sd.inertia_matrix(q)
    assert np.array_equal(_pattern(M.sparsity()), _pattern(tree_pattern(PARENTS)))
    fM = cs.Function("M", [q], [M])
    fd = cs.Function("fd", [q, v, tau], [sd.forward_dynamics(q, v, tau)])
    rng = np.random.default_rng(5)
    for _ in range(5):
        x, w = hand.random_state(rng)
        t = 0.01 * rng.standard_normal(hand.n)
        A = hand.inertia_matrix(x)
        assert np.abs(np.array(fM(x)) - A).max() <= 1e-12 * np.abs(A).max()
        assert np.allclose(A[np.ix_([1, 2], [3, 4])], 0.0, atol=1e-15)  # Pinocchio's zeros where the pattern has none
        ref = hand.forward_dynamics(x, w, t)
        assert np.abs(np.array(fd(x, w, t)).ravel() - ref).max() <= 1e-9 * np.abs(ref).max()


def test_parametric_forward_dynamics_matches_the_numeric_model(hand):
    pd = ParametricDynamics(hand, "m,K")
    q, v, tau = (cs.SX.sym(s, hand.n) for s in "qvt")
    f = cs.Function("fd", [q, v, tau], [pd.forward_dynamics(q, v, tau, cs.DM(pd.nominal))])
    rng = np.random.default_rng(6)
    x, w = hand.random_state(rng)
    t = 0.01 * rng.standard_normal(hand.n)
    ref = hand.forward_dynamics(x, w, t)
    assert np.abs(np.array(f(x, w, t)).ravel() - ref).max() <= 1e-9 * np.abs(ref).max()


def test_parametric_mass_matrix_keeps_the_tree_pattern(hand):
    """ParametricDynamics' M (what the fit's sensitivities and block_solve see) has the tree's pattern, not a dense
    one of structural zeros (it was summed from SX.zeros, which made the hand's fingers one block), and equals
    Pinocchio's CRBA at the nominal masses."""
    pd = ParametricDynamics(hand, "m,K")
    q = cs.SX.sym("q", hand.n)
    M = pd.inertia_matrix(q, pd.theta)
    assert np.array_equal(_pattern(M.sparsity()), _pattern(tree_pattern(PARENTS)))
    fM = cs.Function("M", [q, pd.theta], [M])
    rng = np.random.default_rng(8)
    for _ in range(3):
        x = hand.random_state(rng)[0]
        A = hand.inertia_matrix(x)
        assert np.abs(np.array(fM(x, pd.nominal)) - A).max() <= 1e-12 * np.abs(A).max()


def test_block_solve_leaves_first_no_fill():
    sp = tree_pattern(PARENTS)
    order = elimination_order(sp, range(5))
    assert order[-1] == 0  # the root (the wrist, every joint's ancestor) last
    rng = np.random.default_rng(7)
    A = rng.standard_normal((5, 5))
    A = A @ A.T + 5 * np.eye(5)
    A[~_pattern(sp)] = 0.0  # a tree-patterned SPD matrix
    A += 5 * np.eye(5)
    M = cs.SX.sym("M", sp)
    b = cs.SX.sym("b", 5)
    x = block_solve(M, b)
    f = cs.Function("s", [M, b], [x])
    rhs = rng.standard_normal(5)
    assert np.allclose(np.array(f(_dm(sp, A), rhs)).ravel(),
                       np.linalg.solve(A, rhs), rtol=1e-12, atol=1e-12)
    # no fill-in: the factor of a wrist with two fingers takes fewer operations than a dense factor of the same size
    dense = cs.SX.sym("D", 5, 5)
    n_sparse = cs.Function("s", [M, b], [x]).n_instructions()
    n_dense = cs.Function("d", [dense, b], [block_solve(dense, b)]).n_instructions()
    assert n_sparse < 0.7 * n_dense


def _dm(sp: cs.Sparsity, A: np.ndarray) -> cs.DM:
    r, c = sp.get_triplet()
    return cs.DM.triplet(r, c, cs.DM(A[r, c]), 5, 5)
