"""A large model's sensitivities by the implicit derivative of its dynamics (simulation.variational
looped_variational_rk4_step, issue 51 item 4): on finger3 with friction, against the written-out derivative of the
same step (variational_rk4_step) and a central finite difference of the states."""

from __future__ import annotations

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.simulation import sensitivity
from alpes_dyn.simulation.sensitivity import SensitivityModel


def _run(sm, x0, U, theta, offset=None, basis=None):
    """States and sensitivities of 2 segments."""
    G = np.broadcast_to(np.array([0.0, 0.0, -9.81]), U.shape[:2] + (3,))
    return sm.run(x0, U, G, theta, offset=offset, basis=basis)


@pytest.mark.parametrize("spec", ["K,m,friction", "K,m"])
def test_looped_sensitivities_equal_the_written_out_ones(monkeypatch, spec):
    """The same states bit for bit (the plain step's expression), the sensitivities to x0, the parameters and an
    input correction to 1e-9 (relative to their scale), and a parameter's column against a central difference of
    the states to 1e-5 (relative), on finger3 with friction over 200 samples (4 substeps)."""
    model = ad.Model.alpes("finger3", friction=True)
    kw = dict(dt=1e-3, substeps=4, threads=1, input_basis=2)
    written = SensitivityModel(model, spec, **kw)
    monkeypatch.setattr(sensitivity, "LOOPED_STATES", 1)
    looped = SensitivityModel(model, spec, **kw)
    assert looped._loop.library != written._loop.library  # another step, compiled
    rng = np.random.default_rng(3)
    n, N = model.n, 200
    x0 = np.tile(np.concatenate([model.random_state(rng)[0], np.zeros(n)]), (2, 1))
    x0 += 0.01 * rng.standard_normal((2, 2 * n))
    t = 1e-3 * np.arange(N)
    U = 0.05 * np.sin(2 * np.pi * np.outer(t, 1.0 + np.arange(written.nu)))[None].repeat(2, axis=0)
    basis = np.stack([np.ones(N), np.sin(2 * np.pi * 3 * t)], axis=1)[None].repeat(2, axis=0)
    offset = 0.01 * rng.standard_normal((2, written.nu, 2))
    theta = written.nominal * (1 + 0.1 * rng.standard_normal(written.p))
    xa, Xa = _run(written, x0, U, theta, offset, basis)
    xb, Xb = _run(looped, x0, U, theta, offset, basis)
    assert np.array_equal(xa, xb)
    assert np.abs(Xa - Xb).max() <= 1e-9 * np.abs(Xa).max()
    j = written.p // 2  # a parameter's column against a central difference of the states
    d = 1e-6 * max(abs(theta[j]), 1e-3)
    hi, lo = theta.copy(), theta.copy()
    hi[j] += d
    lo[j] -= d
    fd = (_run(looped, x0, U, hi, offset, basis)[0] - _run(looped, x0, U, lo, offset, basis)[0]) / (2 * d)
    col = Xb[:, :, :, 2 * n + j]
    assert np.abs(fd - col).max() <= 1e-5 * np.abs(col).max()


def test_chained_sensitivities_equal_the_written_out_ones(monkeypatch):
    """A looped step with many basis functions (simulation.variational: each period's own Jacobian with respect to
    (x, p, u), chained over the samples with the basis' values) gives the states of the written-out step bit for
    bit, its sensitivities to x0, the parameters and the correction's coefficients to 1e-9 (relative to their
    scale), and a coefficient's column a central difference of the states (1e-5), on finger3 with friction."""
    model = ad.Model.alpes("finger3", friction=True)
    nb = sensitivity.CHAINED_BASIS + 1
    kw = dict(dt=1e-3, substeps=4, threads=1, input_basis=nb)
    written = SensitivityModel(model, "K,m,friction", **kw)
    monkeypatch.setattr(sensitivity, "LOOPED_STATES", 1)
    chained = SensitivityModel(model, "K,m,friction", **kw)
    assert chained.chained and not written.chained and chained.nd == written.nd
    rng = np.random.default_rng(5)
    n, N = model.n, 150
    x0 = np.tile(np.concatenate([model.random_state(rng)[0], np.zeros(n)]), (2, 1))
    x0 += 0.01 * rng.standard_normal((2, 2 * n))
    t = 1e-3 * np.arange(N)
    U = 0.05 * np.sin(2 * np.pi * np.outer(t, 1.0 + np.arange(written.nu)))[None].repeat(2, axis=0)
    basis = np.stack([np.sin(2 * np.pi * (k + 1) * t) for k in range(nb)], axis=1)[None].repeat(2, axis=0)
    offset = 0.01 * rng.standard_normal((2, written.nu, nb))
    theta = written.nominal * (1 + 0.1 * rng.standard_normal(written.p))
    xa, Xa = _run(written, x0, U, theta, offset, basis)
    xb, Xb = _run(chained, x0, U, theta, offset, basis)
    assert np.array_equal(xa, xb)
    assert np.abs(Xa - Xb).max() <= 1e-9 * np.abs(Xa).max()
    k = written.nu * (nb - 1)  # coefficient (motor 0, last basis function): vec(C) column-major
    d = 1e-7
    hi, lo = offset.copy(), offset.copy()
    hi[:, 0, nb - 1] += d
    lo[:, 0, nb - 1] -= d
    fd = (_run(chained, x0, U, theta, hi, basis)[0] - _run(chained, x0, U, theta, lo, basis)[0]) / (2 * d)
    col = Xb[:, :, :, 2 * n + written.p + k]
    assert np.abs(fd - col).max() <= 1e-5 * np.abs(col).max()
