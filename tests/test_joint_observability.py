"""The joint observability's linearisation (analysis.joint_observability, issue 51 item 4: the whole hand's
``estimate`` sized): the implicit derivative of M qdd = r against CasADi's Jacobian of the forward dynamics through
the solve (what it replaced), and the zero-order hold against scipy's expm, sample by sample, on finger3 with friction
and on a small hand whose two fingers hang from a free wrist."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest
from scipy.linalg import expm

import alpes_dyn as ad
from alpes_dyn.analysis.joint_observability import _held, _jacobians, _linearised
from alpes_dyn.simulation.integrate import joint_accelerations
from alpes_dyn.symbolic.statespace import StateSpace


def _through_the_solve(model):
    """(x, u) -> (A_c, E_c): CasADi's Jacobians of [v; qdd] with a torque b on each joint with Coulomb friction."""
    ss = StateSpace(model, input="motor", output="encoder")
    n = model.n
    fr = np.flatnonzero(np.asarray(model.extras.coulomb) > 0)
    x, u, b = cs.SX.sym("x", 2 * n), cs.SX.sym("u", ss.n_inputs), cs.SX.sym("b", fr.size)
    Sb = np.zeros((n, fr.size))
    Sb[fr, np.arange(fr.size)] = 1.0
    tau = ss.input_torque(x[:n], u, x[n:]) + cs.mtimes(cs.DM(Sb), b)
    f = cs.vertcat(x[n:], joint_accelerations(ss, x[:n], x[n:], tau, None))
    return cs.Function("ref", [x, u, b], [cs.jacobian(f, x), cs.jacobian(f, b)]), fr.size


def _small_hand():
    from test_tree_sparsity import SMALL_HAND
    from alpes_dyn.model.spec import TransmissionSpec
    spec = ('gravity = [0.0, 0.0, -9.81]\nsmooth_velocity = 0.01\ntips = ["a2"]\n\n'
            '[[motor]]\nname = "m_w"\njoints = { wrist = 1.0 }\n\n[[motor]]\nname = "m_a"\njoints = { a_j1 = 1.0, a_j2 = 0.5 }\n\n'
            '[[motor]]\nname = "m_b"\njoints = { b_j1 = 1.0, b_j2 = 0.7 }\n\n'
            '[stiffness]\na_j1 = 0.01\nb_j2 = 0.02\n\n[coulomb]\nwrist = 0.002\na_j1 = 0.001\nb_j2 = 0.003\n\n'
            '[viscous]\nwrist = 0.01\na_j1 = 0.001\na_j2 = 0.001\nb_j1 = 0.001\nb_j2 = 0.001\n')
    return ad.Model(SMALL_HAND, TransmissionSpec.from_toml(spec))


@pytest.mark.parametrize("which", ["finger3", "small_hand"])
def test_linearisation_equals_the_jacobian_through_the_solve(which):
    """A_c and E_c to 1e-9 of their scale at random states and torques."""
    model = ad.Model.alpes("finger3", friction=True) if which == "finger3" else _small_hand()
    lin, nb, Sb = _linearised(model)
    ref, nb_ref = _through_the_solve(model)
    assert nb == nb_ref and nb > 0
    rng = np.random.default_rng(11)
    n = model.n
    for _ in range(4):
        q, v = model.random_state(rng)
        x = np.concatenate([q, v + 0.05 * rng.standard_normal(n)])
        u = 0.05 * rng.standard_normal(lin.size1_in(1))
        Mk, gx, _ = (np.asarray(a) for a in lin(x, u))
        Ac, Ec = _jacobians(Mk[None], gx[None], Sb)
        A_ref, E_ref = (np.asarray(a) for a in ref(x, u, np.zeros(nb)))
        assert np.abs(Ac[0] - A_ref).max() <= 1e-9 * np.abs(A_ref).max()
        assert np.abs(Ec[0] - E_ref).max() <= 1e-9 * np.abs(E_ref).max()


def test_held_equals_scipy_expm_per_sample():
    """exp([[A_c, E_c], [0, 0]] dt) by chunks and each sample's own scaling, to 1e-12 of its scale, on matrices from
    mild to stiff (1-norms 0.01 to 50 after dt), across a chunk's edge."""
    rng = np.random.default_rng(12)
    N, nx, nb = 600, 6, 3
    scale = np.geomspace(1e1, 5e4, N)[:, None, None]
    Ac = rng.standard_normal((N, nx, nx)) * scale
    Ec = rng.standard_normal((N, nx, nb)) * scale
    A, E = _held(Ac, Ec, 1e-3)
    for k in (0, 1, 300, 511, 512, 599):
        Z = np.zeros((nx + nb, nx + nb))
        Z[:nx, :nx], Z[:nx, nx:] = Ac[k] * 1e-3, Ec[k] * 1e-3
        ref = expm(Z)
        tol = 1e-12 * np.abs(ref).max()
        assert np.abs(A[k] - ref[:nx, :nx]).max() <= tol and np.abs(E[k] - ref[:nx, nx:]).max() <= tol
