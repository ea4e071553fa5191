"""The looped variational step with its linear algebra written out in C (simulation.variational_c, issue 51): on
finger3 with friction and an output-only parameter (an encoder offset), against CasADi's code of the same looped
step (kernel "casadi", itself tested against the written-out derivative and finite differences in
test_looped_sensitivity.py), for the chained periods' Jacobians, the sensitivities to every direction and to the
initial state alone, and a central finite difference of the states."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.simulation import sensitivity
from alpes_dyn.simulation.sensitivity import SensitivityModel

SPEC = "K,m,friction,encoder_offset"


def _inputs(sm, model, N, nb, seed):
    """x0 (2, nx), U (2, N, nu), G, the basis (2, N, nb), the coefficients (2, nu, nb) and theta, drawn."""
    rng = np.random.default_rng(seed)
    n = model.n
    x0 = np.tile(np.concatenate([model.random_state(rng)[0], np.zeros(n)]), (2, 1))
    x0 += 0.01 * rng.standard_normal((2, 2 * n))
    t = 1e-3 * np.arange(N)
    U = 0.05 * np.sin(2 * np.pi * np.outer(t, 1.0 + np.arange(sm.nu)))[None].repeat(2, axis=0)
    G = np.broadcast_to(np.array([0.0, 0.0, -9.81]), (2, N, 3))
    basis = np.stack([np.sin(2 * np.pi * (k + 1) * t) for k in range(nb)], axis=1)[None].repeat(2, axis=0)
    offset = 0.01 * rng.standard_normal((2, sm.nu, nb))
    theta = sm.nominal * (1 + 0.1 * rng.standard_normal(sm.p))
    return x0, U, G, basis, offset, theta


@pytest.mark.parametrize("nb", [2, sensitivity.CHAINED_BASIS + 1])
def test_c_kernel_equals_casadi_looped_step(monkeypatch, nb):
    """The same states bit for bit, every sensitivity (x0, the parameters, the correction's coefficients; the
    periods' own Jacobians chained where nb >= CHAINED_BASIS) and those to x0 alone to 1e-12 of their scale, the
    encoder offset's column exactly zero (left out of the arithmetic), and a mass's column against a central
    difference of the states (1e-5 relative)."""
    monkeypatch.setattr(sensitivity, "LOOPED_STATES", 1)  # finger3's step built as the large models' is
    model = ad.Model.alpes("finger3", friction=True)
    kw = dict(dt=1e-3, substeps=4, threads=1, input_basis=nb)
    ref = SensitivityModel(model, SPEC, kernel="casadi", **kw)
    fast = SensitivityModel(model, SPEC, **kw)
    assert fast.kernel == "c" and ref.kernel == "casadi" and fast.chained == (nb >= sensitivity.CHAINED_BASIS)
    j_off = fast.names.index("encoder_offset_finger")
    assert 2 * model.n + j_off not in set(fast._loop.live)
    x0, U, G, basis, offset, theta = _inputs(fast, model, 120, nb, 11)
    xa, Xa = ref.run(x0, U, G, theta, offset, basis=basis)
    xb, Xb = fast.run(x0, U, G, theta, offset, basis=basis)
    assert np.array_equal(xa, xb)
    scale = np.abs(Xa).max(axis=(0, 1, 2))
    assert scale.shape == (fast.nd,) and scale[:2 * model.n].min() > 0.5
    assert (np.abs(Xa - Xb).max(axis=(0, 1, 2)) <= 1e-12 * np.maximum(scale, 1e-300)).all()
    assert not Xb[..., 2 * model.n + j_off].any()
    xs_a, Sa = ref.run(x0, U, G, theta, offset, basis=basis, sensitivities="state")
    xs_b, Sb = fast.run(x0, U, G, theta, offset, basis=basis, sensitivities="state")
    assert np.array_equal(xs_a, xs_b) and np.array_equal(xs_b, xb)
    assert fast._state_loop.library == fast._loop.library  # one build for both steps
    xp, none = fast.run(x0, U, G, theta, offset, basis=basis, sensitivities=False)  # the states alone, built at -O1
    assert none is None and np.array_equal(xp, xb)
    assert np.abs(Sa - Sb).max() <= 1e-12 * np.abs(Sa).max()
    j = fast.names.index("m_2")
    d = 1e-6 * theta[j]
    hi, lo = theta.copy(), theta.copy()
    hi[j] += d
    lo[j] -= d
    fd = (fast.run(x0, U, G, hi, offset, basis=basis, sensitivities=False)[0]
          - fast.run(x0, U, G, lo, offset, basis=basis, sensitivities=False)[0]) / (2 * d)
    col = Xb[..., 2 * model.n + j]
    assert np.abs(fd - col).max() <= 1e-5 * np.abs(col).max()


def test_kernel_refused_by_name():
    """An unknown kernel, and the C kernel on a LuGre law's model, are InputErrors naming ``kernel``."""
    model = ad.Model.alpes("finger2", friction=True)
    with pytest.raises(InputError, match="kernel"):
        SensitivityModel(model, "K", kernel="fortran")
    lugre = ad.Model.alpes("finger2", friction=True, params=dataclasses.replace(model.params, friction_law="lugre"))
    with pytest.raises(InputError, match="kernel: 'c'"):
        SensitivityModel(lugre, "K", kernel="c")
