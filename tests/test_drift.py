"""A slow drift of the encoder offsets fitted with the parameters (issue 39: identify(drift="offset"), module drift):
its basis against the piecewise-linear function it stands for, and a fit of a recording whose encoder drifts by a
known ramp, with and without the drift."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.experiments.recording import Recording, join_runs
from alpes_dyn.estimation.identification.adequacy import SIGNATURES
from alpes_dyn.estimation.identification.drift import drift_basis, recorded_time
from alpes_dyn.estimation.identification.identification import identify


def _rec(t: np.ndarray) -> Recording:
    n = t.shape[0]
    return Recording(t=t, encoder=np.arange(n, dtype=float)[:, None], torque=np.zeros((n, 1)),
                     motor_names=("finger",), joint_names=("j1", "j2"))


def test_the_drift_basis_is_the_piecewise_linear_interpolant_of_its_knots():
    """40 s at 10 ms: ceil(40 / 15) = 3 segments, knots at 0, 13.33, 26.67, 40 s; H d equals numpy's interpolation
    of (0, d1, d2, d3) at every sample. Two runs, the second's clock restarted: the recorded time runs on."""
    t = 0.01 * np.arange(4001)
    H = drift_basis(_rec(t))
    d = np.array([3.0, -2.0, 7.5])
    assert H.shape == (4001, 3)
    assert np.allclose(H @ d, np.interp(t, [0.0, 40 / 3, 80 / 3, 40.0], np.r_[0.0, d]), atol=1e-12)
    a, b = _rec(0.01 * np.arange(200)), _rec(0.01 * np.arange(300))
    tau = recorded_time(join_runs([a, b]))
    assert np.allclose(tau, 0.01 * np.arange(500), atol=1e-12)
    assert drift_basis(_rec(0.01 * np.arange(401))).shape == (401, 1)  # 4 s: a ramp, 1 at the end
    assert np.allclose(drift_basis(_rec(0.01 * np.arange(401)))[:, 0], np.linspace(0, 1, 401))


def test_a_drifting_encoder_is_fitted_with_the_drift_and_named_without_it():
    """finger2 +-20 % (seed 3), 1 s, the documented sensors (seed 1), its encoder drifting by a ramp of 20 counts.
    With drift="offset": converged, adequate, the ramp back within 1 count (19.5 measured), K and m within 0.3 %
    (0.20 % measured; the issue asks 3 and 5 %). Without: the verdict is not adequate and names the drift first,
    and the masses are further off (1.1 % measured, 2026-12-05)."""
    true = perturbed_params(spread=0.2, seed=3)
    f = ad.Model.alpes("finger2", friction=True)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2]]
    rec = experiment("finger2", true, ExperimentDesign(duration=1.0), seed=1)
    rec = dataclasses.replace(rec, encoder=rec.encoder + np.round(20.0 * rec.t / rec.t[-1])[:, None])
    lines = ExperimentDesign().lines
    fit = identify(f, rec, progress=False, excitation=lines, drift="offset")
    err = np.abs(fit.values[:4] / truth - 1)
    assert fit.trustworthy and np.max(err) < 3e-3
    assert fit.drift["knots_s"] == pytest.approx([0.0, 1.0]) and fit.drift["counts"]["finger"][1] == pytest.approx(20.0, abs=1.0)
    with pytest.warns(Warning):
        plain = identify(f, rec, progress=False, excitation=lines)
    assert not plain.adequacy.adequate and plain.adequacy.likely_missing[0] == SIGNATURES["drift"]
    assert plain.drift is None and np.max(np.abs(plain.values[:4] / truth - 1)) > 2 * np.max(err)


def test_a_drifting_torque_constant_is_fitted_with_the_gain_drift_and_flagged_without_it(monkeypatch):
    """finger2 +-20 % (seed 3), 1 s, the documented sensors (seed 1), the plant's torque constant ramping by 5 % (the
    torque applied 1 + 0.05 t / T times the recorded one: a warming motor). With drift="gain": converged, adequate,
    the scale at the end within a fifth of the ramp of 1.05 and 1 at the start (the relative drift), K and m within
    1 % (0.13 % measured, 2026-12-05). Without: the verdict is not adequate and names the torque constant's drift
    first (K and m 1.0-3.9 % off). Both drifts at once: the Jacobian test below."""
    import alpes_dyn.estimation.experiments.experiment as ex

    simulate = ex._simulate

    def warming(truth, design, u, G, seg):
        g = 1.0 + 0.05 * np.arange(u.shape[0]) / (u.shape[0] - 1)
        return simulate(truth, design, u * g[:, None], G, seg)
    monkeypatch.setattr(ex, "_simulate", warming)
    true = perturbed_params(spread=0.2, seed=3)
    f = ad.Model.alpes("finger2", friction=True)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2]]
    rec = experiment("finger2", true, ExperimentDesign(duration=1.0), seed=1)
    lines = ExperimentDesign().lines
    fit = identify(f, rec, progress=False, excitation=lines, drift="gain")
    err = np.abs(fit.values[:4] / truth - 1)
    scale = fit.drift["torque_scale"]["finger"]
    assert fit.trustworthy and np.max(err) < 0.01
    assert scale[0] == 1.0 and abs(scale[1] - 1.05) < 0.2 * 0.05 and "counts" not in fit.drift
    with pytest.warns(Warning):
        plain = identify(f, rec, progress=False, excitation=lines)
    assert not plain.adequacy.adequate and plain.drift is None
    assert plain.adequacy.likely_missing[0] == SIGNATURES["gain_drift"]


def test_the_gain_drifts_jacobian_against_central_differences():
    """The shooting problem with drift="offset,gain" (0.6 s of finger2, 50 ms intervals, the compliance on): the
    Jacobians of the residuals and defects in a line coefficient and the offset's knot equal central differences to
    1e-5 (exact), in the gain's knot to the documented approximation (the knot's hat taken at each interval's
    middle: within half an interval's share of the ramp, 25 / 600 here; 1.9 % measured); the torque's coefficients
    on the lines reproduce it (module drift, line_coefficients)."""
    from alpes_dyn.estimation.identification.shooting import ShootingProblem, torque_model
    from alpes_dyn.simulation.sensitivity import SensitivityModel

    f = ad.Model.alpes("finger2", friction=True)
    rec = experiment("finger2", perturbed_params(spread=0.2, seed=3), ExperimentDesign(duration=0.6), seed=1)
    tm = torque_model(rec, ExperimentDesign().lines, None)
    sens = SensitivityModel(f, "K,m,friction,tendon_compliance", dt=rec.dt, substeps=4, input_basis=tm.nphi)
    pb = ShootingProblem(f, rec, sens, 50, tm, 0.01, drift="offset,gain", start={"tendon_compliance_finger": 0.05})
    U = pb.Ub.reshape(-1, pb.nu)[:pb.N]
    assert np.abs(U - pb.Psib.reshape(-1, tm.nphi)[:pb.N] @ pb.Acoef[0].T).max() < 1e-12 * np.abs(U).max()
    nodes, offs = pb.initial_nodes(np.zeros(pb.n)), np.zeros((pb.n_int, 0))
    glob = 0.01 * np.random.default_rng(0).standard_normal(pb.ng)
    glob[-1] = 0.03
    e = pb.evaluate(nodes, offs, glob)
    for g, tol in ((pb.p + 3, 1e-5), (pb.ng - 2, 1e-5), (pb.ng - 1, 25 / 600)):  # a line, the offset's, the gain's
        t = [pb.evaluate(nodes, offs, glob + sgn * 1e-6 * np.eye(pb.ng)[g], jac=False) for sgn in (1, -1)]
        dr, dc = (t[0].r - t[1].r) / 2e-6, (t[0].c - t[1].c) / 2e-6
        assert np.abs(dr - e.J[:, :, pb.nb + g]).max() < tol * np.abs(dr).max()
        assert np.abs(dc - e.Cr[:, :, g]).max() <= tol * np.abs(dc).max()
    assert pb.gain(glob)[0, 0] == pytest.approx(1 + 0.03 * pb.Hs[0, 0]) and pb.gain(glob, per_sample=True)[0, 0, 0] == 1.0
