"""A long record's Jacobian held compact (issue 39, alpes_dyn.estimation.identification.normal_blocks): its normal
blocks and J'r accumulated chunk by chunk equal those of the whole J; the verdict's projections by two passes equal
those from the whole J; the fit on them is the same fit."""

from __future__ import annotations

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.identification import normal_blocks, shooting
from alpes_dyn.estimation.identification.identification import identify
from alpes_dyn.estimation.identification.normal_blocks import NormalBlocks, remainders
from alpes_dyn.estimation.identification.shooting import ShootingProblem, torque_model
from alpes_dyn.simulation.sensitivity import SensitivityModel


@pytest.fixture(scope="module")
def noisy():
    """finger3 +-20 % (seed 731), 1 s of the documented experiment with its sensors, the excitation's lines (the
    2 s design's 19 basis functions: the same compiled sensitivities; 20 intervals, three chunks in the test
    below)."""
    design = ExperimentDesign(duration=1.0)
    rec = experiment("finger3", perturbed_params(spread=0.2, seed=731), design, seed=731)
    return ad.Model.alpes("finger3", friction=True), rec, design.lines


def _problem(model, rec, lines, monkeypatch, compact: bool) -> ShootingProblem:
    monkeypatch.setattr(normal_blocks, "COMPACT_BYTES", 0 if compact else 2**40)
    sens = SensitivityModel(model, None, dt=rec.dt, substeps=4, input_basis=2 * len(lines) + 1)
    pb = ShootingProblem(model, rec, sens, 50, torque_model(rec, lines, None), np.radians(0.1))
    assert pb.compact is compact
    return pb


def test_the_compact_blocks_are_the_whole_jacobians(noisy, monkeypatch):
    """At one point off the optimum (the nodes on the model's response, the parameters 5 % off, line corrections
    drawn): r, c, Cv, Cr the same; no J held; A'A, A'P, sum P'P and each interval's J'r equal the einsums of the whole
    J to 1e-12 of their size (the chunks' sums in another order); the KKT step from the blocks equal to the step from
    J to 1e-9; the remainders R - J z of two passes equal those from the whole J to 1e-9."""
    model, rec, lines = noisy
    monkeypatch.setattr(shooting, "JACOBIAN_CHUNK", 2**14)  # several chunks on this short record
    whole = _problem(model, rec, lines, monkeypatch, False)
    comp = _problem(model, rec, lines, monkeypatch, True)
    rng = np.random.default_rng(5)
    nodes = whole.initial_nodes(np.zeros(whole.n))
    offs = np.zeros((whole.n_int, whole.no))
    glob = np.r_[0.05 * rng.standard_normal(whole.p), 0.3 * rng.standard_normal(whole.ng - whole.p)]
    e, f = whole.evaluate(nodes, offs, glob), comp.evaluate(nodes, offs, glob)
    assert e.normal is None and isinstance(f.normal, NormalBlocks) and f.J is None and e.J is not None
    assert f.normal.AA.nbytes + f.normal.AP.nbytes < e.J.nbytes / 5
    for a, b in ((e.r, f.r), (e.c, f.c), (e.Cv, f.Cv), (e.Cr, f.Cr), (e.xs, f.xs)):
        assert np.array_equal(a, b)
    nb = whole.nb
    A, P = e.J[:, :, :nb], e.J[:, :, nb:]
    ref = {"AA": np.einsum("ski,skj->sij", A, A), "AP": np.einsum("ski,skj->sij", A, P),
           "PP": np.einsum("ski,skj->ij", P, P), "gs": np.einsum("sk,skd->sd", e.r, e.J)}
    for name, want in ref.items():
        got = getattr(f.normal, name)
        assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want)), name
    g_e, g_f = whole.gradient(e), comp.gradient(f)
    assert np.max(np.abs(g_f - g_e)) <= 1e-12 * np.max(np.abs(g_e))
    rhs = np.concatenate([-g_e, -e.c.reshape(-1)])
    solve_e = whole.kkt_solver(whole.normal_of(e), e.Cv, e.Cr, 1e-3)
    d_e, d_f = solve_e(rhs), comp.kkt_solver(comp.normal_of(f), f.Cv, f.Cr, 1e-3)(rhs)
    assert np.max(np.abs(d_f - d_e)) <= 1e-9 * np.max(np.abs(d_e))
    R = rng.standard_normal((3,) + e.r.shape)
    want = np.empty_like(R)
    for i in range(3):
        z = solve_e(np.concatenate([whole.grad(R[i], e.J, np.zeros(whole.ng)), np.zeros(whole.nc)]))[:whole.nz]
        want[i] = R[i] - (np.einsum("skd,sd->sk", A, z[:whole.nv].reshape(-1, nb)) + P @ z[whole.nv:])
    got = remainders(comp, (nodes, offs, glob), solve_e, R.copy())  # (R overwritten)
    assert np.max(np.abs(got - want)) <= 1e-9 * np.max(np.abs(want))
    assert np.max(np.abs(want - R)) > 1e-3 * np.max(np.abs(R))  # the projection is not nothing


def test_the_fit_on_the_compact_jacobian_is_the_same_fit(noisy, monkeypatch):
    """identify with the Jacobian held compact (every evaluation's) and whole: the same iterations, values within
    1e-9, standard errors within 1e-7, the same residual; the verdict's statistics (its regressions by two passes)
    within 1e-4 and the same verdict."""
    model, rec, lines = noisy
    out = {}
    for compact in (False, True):
        monkeypatch.setattr(normal_blocks, "COMPACT_BYTES", 0 if compact else 2**40)
        out[compact] = identify(model, rec, excitation=lines, progress=False)
    a, b = out[False], out[True]
    assert a.converged and b.converged and a.iterations == b.iterations
    np.testing.assert_allclose(b.values, a.values, rtol=1e-9)
    np.testing.assert_allclose(b.std, a.std, rtol=1e-7)
    assert b.residual_rms == pytest.approx(a.residual_rms, rel=1e-9)
    assert b.trustworthy == a.trustworthy and b.adequacy.adequate == a.adequacy.adequate
    for key in ("whiteness", "cross_correlation"):
        va, vb = a.adequacy.to_dict()[key], b.adequacy.to_dict()[key]
        flat_a = np.asarray(list(_numbers(va)))
        np.testing.assert_allclose(np.asarray(list(_numbers(vb))), flat_a, rtol=1e-4, atol=1e-8)
    sa, sb = a.adequacy.to_dict()["signatures"], b.adequacy.to_dict()["signatures"]
    np.testing.assert_allclose(np.asarray(list(_numbers(sb))), np.asarray(list(_numbers(sa))), rtol=1e-4, atol=1e-6)


def _numbers(obj):
    """Every finite number in a nested dict / list, in order."""
    if isinstance(obj, dict):
        for k in sorted(obj):
            yield from _numbers(obj[k])
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from _numbers(v)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool) and np.isfinite(obj):
        yield float(obj)


@pytest.mark.parametrize("ng", [0, 3])
def test_the_blocks_are_the_products_of_the_stacked_rows(ng):
    """blocks_of's BLAS products against the written-out sums, with global variables and without (a fit whose
    every variable is an interval's own: ng = 0)."""
    J = np.random.default_rng(5).standard_normal((4, 7, 2 + ng))
    AA, AP, PP = normal_blocks.blocks_of(J, 2)
    A, P = J[:, :, :2], J[:, :, 2:]
    np.testing.assert_allclose(AA, np.einsum("ski,skj->sij", A, A), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(AP, np.einsum("ski,skj->sij", A, P), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(PP, sum(P[s].T @ P[s] for s in range(4)) if ng else np.zeros((0, 0)), rtol=1e-12,
                               atol=1e-12)
    assert PP.shape == (ng, ng)
