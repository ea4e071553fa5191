"""Identification: parametric dynamics, recordings, the experiment, the multiple-shooting fit."""

from __future__ import annotations

import dataclasses
import math

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError, RecordingError
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.identification.identification import identify, project_torque
from alpes_dyn.symbolic.parametric import ParametricDynamics, select_parameters, tilted_gravity
from alpes_dyn.model.params import load_params, write_params
from alpes_dyn.model.transmission import torque_before
from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
from alpes_dyn.simulation.sensitivity import SensitivityModel


@pytest.fixture(scope="module")
def finger2():
    return ad.Model.alpes("finger2", friction=True)


def test_parametric_dynamics_equal_pinocchio_with_other_parameters(rng):
    """qdd with theta = a perturbed parameter set equals Pinocchio on a model built from that set."""
    nominal = ad.Model.alpes("finger3", friction=True, rotor_inertia=True)
    pd = ParametricDynamics(nominal, None, gravity_input=True)
    true = perturbed_params(spread=0.2, seed=4)
    g = np.array([1.0, -2.0, -9.5])
    m = ad.Model.alpes("finger3", friction=True, rotor_inertia=True, params=true).copy(gravity=g)
    assert np.array_equal(m.gravity, g) and m.motor_names == ("finger",)
    theta = np.r_[true.finger.K, true.finger.m, true.finger.F_s, true.finger.F_v]
    assert pd.names == ("K_1", "K_2", "K_3", "m_1", "m_2", "m_3", "F_s_1", "F_s_2", "F_s_3", "F_v_1", "F_v_2",
                        "F_v_3")
    q, v, tau = (cs.SX.sym(s, 3) for s in "qvt")
    f = cs.Function("f", [q, v, tau, pd.theta, pd.g], [pd.forward_dynamics(q, v, tau, pd.theta, pd.g)])
    for _ in range(5):
        qq, vv = m.random_state(rng)
        tt = rng.normal(scale=0.05, size=3)
        ref = m.forward_dynamics(qq, vv, tt, smooth=True)
        assert np.max(np.abs(np.array(f(qq, vv, tt, theta, g)).ravel() - ref)) < 1e-12 * np.max(np.abs(ref))


def test_parameter_selection(finger2):
    assert [p.name for p in select_parameters(finger2, "K")] == ["K_1", "K_2"]
    assert [p.name for p in select_parameters(finger2, "m_2,friction")] == ["m_2", "F_s_1", "F_s_2", "F_v_1", "F_v_2"]
    with pytest.raises(ModelError, match="unknown parameter 'K_9'"):
        select_parameters(finger2, "K_9")
    with pytest.raises(ModelError, match="selected twice"):
        select_parameters(finger2, "K,K_1")
    with pytest.raises(ModelError, match="selects nothing"):
        select_parameters(ad.Model.alpes("finger2"), "friction")


def test_identified_parameter_file_round_trip(tmp_path):
    p = perturbed_params(spread=0.2, seed=1)
    path = write_params(p, tmp_path / "true.toml")
    q = load_params(path)
    for k in ("K", "m", "I", "F_s", "F_v"):
        assert np.array_equal(getattr(q.finger, k), getattr(p.finger, k))
    assert ad.Model.alpes("finger3", friction=True, params=q).extras.coulomb.tolist() == p.finger.F_s.tolist()


def test_recording_round_trip_and_torque_projection(tmp_path):
    rec = experiment("finger2", perturbed_params(seed=2), ExperimentDesign(duration=0.5, camera_times=(0.25,)), seed=2)
    path = write_recording(rec, tmp_path / "rec.csv")
    back = read_recording(path, ad.Model.alpes("finger2"))
    assert np.array_equal(back.encoder, rec.encoder) and np.array_equal(back.torque, rec.torque)
    assert np.array_equal(np.isnan(back.q), np.isnan(rec.q)) and np.nansum(np.abs(back.q - rec.q)) == 0
    # the projection on the design's lines removes the torque noise off them
    design = ExperimentDesign(duration=0.5)
    clean = experiment("finger2", perturbed_params(seed=2), ExperimentDesign(duration=0.5, torque_noise=0.0), seed=2)
    proj = project_torque(rec.t, rec.torque, design.lines)
    assert np.std(proj - clean.torque) < 0.25 * np.std(rec.torque - clean.torque)


@pytest.fixture(scope="module")
def ok_lines(tmp_path_factory):
    """The lines of a valid finger2 recording's CSV (0.3 s, one line of excitation), written once for the rows of
    test_recording_errors (each edits its own copy)."""
    rec = experiment("finger2", None, ExperimentDesign(duration=0.3, torque_noise=0.0, frequencies=(2.0,),
                                                       torque_amplitude=0.0, dither=0.0), seed=0)
    return write_recording(rec, tmp_path_factory.mktemp("ok") / "ok.csv").read_text().splitlines()


@pytest.mark.parametrize("edit,pattern", [
    (lambda h, r: (h.replace("encoder_finger", "encoder_thumb"), r), r"unknown column 'encoder_thumb'"),
    (lambda h, r: (h.replace(",torque_finger", ""), [x.rsplit(",", 1)[0] if False else ",".join(
        x.split(",")[:2] + x.split(",")[3:]) for x in r]), r"needs exactly one of 'torque_finger'"),
    (lambda h, r: (h, [r[0].replace(r[0].split(",")[1], "abc", 1)] + r[1:]), r"'encoder_finger' line 2: not a number"),
    (lambda h, r: (h, [r[1]] + [r[0]] + r[2:]), r"t is not strictly increasing"),
    (lambda h, r: (h, r[:50]), r"too short \(50 samples"),
    (lambda h, r: (h, [",".join(x.split(",")[:1] + [str(float(x.split(",")[1]) * 0 + 7)] + x.split(",")[2:])
                       for x in r]), r"no excitation"),
])
def test_recording_errors(tmp_path, ok_lines, edit, pattern):
    header, rows = edit(ok_lines[0], list(ok_lines[1:]))
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join([header] + rows) + "\n")
    with pytest.raises(RecordingError, match=pattern) as exc:
        read_recording(bad, ad.Model.alpes("finger2"))
    assert "\n" not in str(exc.value)


def test_recording_unit_errors(tmp_path):
    rec = experiment("finger2", None, ExperimentDesign(duration=0.3), seed=0)
    rec.true_q = np.degrees(rec.true_q)
    with pytest.raises(RecordingError, match="must be in rad, not degrees"):
        write_recording(rec, tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


def test_variational_step_equals_the_derivative_of_the_rk4_step(finger2, rng):
    """The sensitivity step (RK4 on the variational equation, one right-hand side called four times) against
    CasADi's AD of the inlined RK4 step (the construction it replaced): the same states bit for bit, the
    same Jacobians to rounding, for the state, the parameters and an input-correction coefficient."""
    from alpes_dyn.simulation.integrate import rk4_expression
    from alpes_dyn.simulation.sensitivity import variational_rk4_step
    pd = ParametricDynamics(finger2, None, gravity_input=True)
    x, u, c = cs.SX.sym("x", 4), cs.SX.sym("u", 1), cs.SX.sym("c", 1)
    w = cs.vertcat(u, pd.g, pd.theta, c)
    rhs = cs.vertcat(x[2:], pd.forward_dynamics(x[:2], x[2:], cs.DM(finger2.transmission.actuation_matrix) @ (u + c),
                                                pd.theta, pd.g))
    h = 2.5e-4
    xn = rk4_expression(cs.Function("f", [x, w], [rhs]), x, w, h)
    ref = cs.Function("ref", [x, w], [xn, cs.jacobian(xn, cs.vertcat(x, pd.theta, c))])
    step = variational_rk4_step(rhs, x, w, cs.vertcat(pd.theta, c), h)
    nd = 4 + pd.p + 1
    for _ in range(3):
        x0 = np.r_[rng.uniform(0.1, 0.6, 2), rng.normal(0, 2.0, 2)]
        w0 = np.r_[0.02 * rng.uniform(), finger2.gravity, pd.nominal * (1 + 0.2 * rng.uniform(-1, 1, pd.p)),
                   1e-3 * rng.normal()]
        z0 = np.r_[x0, np.eye(4, nd).ravel(order="F")]
        out = np.array(step(z0, w0)).ravel()
        x_ref, J_ref = (np.array(a) for a in ref(x0, w0))
        assert np.array_equal(out[:4], x_ref.ravel())
        J = out[4:].reshape(nd, 4).T
        assert np.abs(J - J_ref).max() <= 1e-13 * np.abs(J_ref).max()


def test_sensitivities_equal_finite_differences_and_the_states_alone(finger2, rng):
    """The compiled forward sensitivities (RK4 on the variational equation) against central differences of
    the states-only run, for the initial state, the parameters and the input-correction coefficients;
    the states-only run gives the sensitivity run's states bit for bit."""
    sm = SensitivityModel(finger2, None, dt=1e-3, substeps=2, input_basis=2)
    B, N = 2, 60
    x0 = np.c_[rng.uniform(0.1, 0.6, (B, 2)), rng.normal(0, 0.5, (B, 2))]
    U = 0.02 + 0.005 * rng.normal(size=(B, N, 1))
    G = np.broadcast_to(finger2.gravity, (B, N, 3))
    phi = np.stack([np.ones((B, N)), np.sin(np.linspace(0, 3, N))[None].repeat(B, 0)], axis=-1)
    C = np.array([[1e-3, -2e-3]])
    th = sm.nominal * (1 + 0.1 * rng.uniform(-1, 1, sm.p))
    x, X = sm.run(x0, U, G, th, C, basis=phi)
    xs, none = sm.run(x0, U, G, th, C, basis=phi, sensitivities=False)
    assert none is None and np.array_equal(x, xs)
    xa, Xa = sm.run(x0, U, G, th, C, basis=phi, sensitivities="state")  # dx/dx0 alone: the same numbers
    assert np.array_equal(x, xa) and np.array_equal(Xa, X[..., :sm.nx])

    def states(x0_, th_, C_):
        return sm.run(x0_, U, G, th_, C_, basis=phi, sensitivities=False)[0]

    cols = []
    for j in range(sm.nx):
        h = 1e-6
        e = np.zeros(sm.nx)
        e[j] = h
        cols.append((states(x0 + e, th, C) - states(x0 - e, th, C)) / (2 * h))
    for j in range(sm.p):
        h = 1e-6 * th[j]
        e = np.zeros(sm.p)
        e[j] = h
        cols.append((states(x0, th + e, C) - states(x0, th - e, C)) / (2 * h))
    for j in range(sm.no):  # vec(C), column-major: (motor, basis function)
        h = 1e-7
        dC = np.zeros(sm.no)
        dC[j] = h
        dC = dC.reshape(sm.nb, sm.nu).T
        cols.append((states(x0, th, C + dC) - states(x0, th, C - dC)) / (2 * h))
    fd = np.stack(cols, axis=-1)
    scale = np.maximum(np.abs(X).max(axis=(0, 1, 2)), 1e-12)
    assert X.shape == fd.shape == (B, N + 1, sm.nx, sm.nd)
    assert np.max(np.abs(X - fd) / scale) < 1e-5


def test_line_corrections_trust_region_grows_only_on_a_crawl():
    """GaussNewton.next_radius: a step the line corrections alone cut (here a coefficient asking for 10 standard
    deviations, log theta still) and taken whole grows the streak; from the third in a row the region doubles, up
    to MAX_COEF_GROWTH; a shortened or failed step, a step log theta cuts, or one inside the region resets it."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification.gauss_newton import CRAWL_STEPS, MAX_COEF_GROWTH, GaussNewton

    assert (CRAWL_STEPS, MAX_COEF_GROWTH) == (3, 16.0)
    pb = SimpleNamespace(p=2, ncg=4, nv=3, nz=3 + 2 + 4, N=4000)  # 3 local variables, 2 parameters, 4 line coefficients
    d = np.zeros(pb.nz)
    d[pb.nv + pb.p + 1] = 10.0
    whole, short = (1.0, None, None, 0.0), (0.5, None, None, 0.0)
    radius, streak, seen = 1.0, 0, []
    for _ in range(7):
        radius, streak = GaussNewton.next_radius(pb, d, radius, streak, whole)
        seen.append((radius, streak))
    # at 16 the 10 sigma step is inside the region, not cut: the streak ends there and the region falls back to one
    assert seen == [(1.0, 1), (1.0, 2), (2.0, 3), (4.0, 4), (8.0, 5), (16.0, 6), (1.0, 0)]
    assert GaussNewton.next_radius(pb, d, 4.0, 5, short) == (1.0, 0)
    assert GaussNewton.next_radius(pb, d, 4.0, 5, None) == (1.0, 0)
    d_log = d.copy()
    d_log[pb.nv] = 0.3 * 20.0  # log theta asks for 20 of its steps, the line corrections for 10: log theta cuts
    assert GaussNewton.next_radius(pb, d_log, 1.0, 2, whole) == (1.0, 0)
    d_big = d * 4.0  # 40 sigma: the region doubles to its cap
    assert GaussNewton.next_radius(pb, d_big, 16.0, 9, whole) == (16.0, 10)
    # beyond 4 s the rule's sqrt(N / 4000) widens every radius: 10 sigma at 16 s is inside one
    assert GaussNewton.next_radius(SimpleNamespace(p=2, ncg=4, nv=3, nz=9, N=16000 * 100), d, 1.0, 2, whole) == (1.0, 0)


def test_line_search_corrects_a_curved_step_until_the_merit_takes_it(monkeypatch):
    """GaussNewton.line_search on a one-node problem whose constraint curves: cost 100 (g - 1)^2, continuity
    c = v + 0.05 v^2 - g^2 = 0, from v = g = 0 the Gauss-Newton step dg = 1 (dv = 0) lowers the cost to 0 but
    leaves c = -1, which the merit's penalty (1e6) refuses at every length down to 1/30. Second-order corrections
    from the same factorised system (here [I C^T; C 0] with C = [1, 0] at the start) remove the defect by
    Newton's iteration on v (defects 1, 0.05, 4.9e-3, 4.6e-4, 4.4e-5): with SOC_STEPS = 4 of them the merit takes
    the whole corrected step, landing on the manifold (v + 0.05 v^2 = 1: v = 10 (sqrt(1.2) - 1)); with one (the
    rule before) it finds no step."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import gauss_newton as gn

    def evaluate(nodes, offs, glob, jac=False):
        v, g = float(nodes[0, 0]), float(glob[0])
        r = np.array([10.0 * (g - 1.0)])
        return SimpleNamespace(r=r, c=np.array([[v + 0.05 * v * v - g * g]]), cost=float(r @ r))

    pb = SimpleNamespace(nx=1, nz=2, nv=1, n_int=1, nb=1, evaluate=evaluate)
    K = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # H = I, C = [1, 0] (dc/dg = -2g = 0)

    def solve_K(rhs):
        return np.linalg.solve(K, rhs)

    nodes, offs, glob = np.zeros((1, 1)), np.zeros((1, 0)), np.zeros(1)
    at = evaluate(nodes, offs, glob)
    assert at.cost == 100.0 and at.c[0, 0] == 0.0
    merit, nu = at.cost, 1e6
    dv, dg = np.zeros((1, 1)), np.array([1.0])
    assert gn.SOC_STEPS == 4
    found = gn.GaussNewton.line_search(pb, at, nodes, offs, glob, dv, dg, merit, nu, solve_K)
    assert found is not None
    alpha, sv, sg, cost_new = found
    v_star = 10.0 * (math.sqrt(1.2) - 1.0)
    assert alpha == 1.0 and sg[0] == 1.0 and cost_new == 0.0
    assert abs(sv[0, 0] - v_star) < 1e-4 and abs(sv[0, 0] + 0.05 * sv[0, 0] ** 2 - 1.0) * nu < merit
    monkeypatch.setattr(gn, "SOC_STEPS", 1)
    assert gn.GaussNewton.line_search(pb, at, nodes, offs, glob, dv, dg, merit, nu, solve_K) is None


def test_identify_recovers_exact_parameters_from_noise_free_data(finger2, monkeypatch):
    """No sensor noise, unquantised encoder: the fit lands on the truth (K, m, friction within 1e-6); from an
    earlier result (a warm start) the last stage alone does, from its trajectory; at another interval the
    trajectory does not fit the problem and the fit runs whole from the result's values."""
    true = perturbed_params(spread=0.2, seed=3)
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0)
    rec = experiment("finger2", true, design, seed=3)
    tr = finger2.transmission
    rec.encoder = rec.true_q @ tr.S.T / (2 * math.pi / tr.counts_per_rev)  # unquantised
    res = identify(finger2, rec, progress=False)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2], true.finger.F_s[:2], true.finger.F_v[:2]]
    assert res.names == ("K_1", "K_2", "m_1", "m_2", "F_s_1", "F_s_2", "F_v_1", "F_v_2")
    assert res.converged
    # K and m to 1e-6; the dry friction to 3e-6 (with the dither the joints rarely stop, F_s is the least seen: the
    # stopping rule's last chi^2 step of 0.1 leaves it 1.0e-6 off)
    assert np.max(np.abs(res.values[:4] / truth[:4] - 1)) < 1e-6 and np.max(np.abs(res.values / truth - 1)) < 3e-6
    assert np.max(np.abs(res.initial / truth - 1)) > 0.02  # it did move
    assert res.residual_rms < 1e-3  # counts; the stopping rule ends at chi^2 changes below 0.1
    ident = res.params()
    assert ident.raw["finger.K"].source == "identified" and ident.raw["finger.K"].std is not None
    assert np.allclose(ident.finger.I[:2] / ident.finger.m[:2], true.finger.I[:2] / true.finger.m[:2], rtol=1e-12)
    # start= (what fit_effects passes from one round to the next): the masses' start 10 % high, the rest the model's
    half = {"m_1": 1.1 * true.finger.m[0], "m_2": 1.1 * true.finger.m[1]}
    warm = identify(finger2, rec, progress=False, start=half)
    assert warm.initial[2:4].tolist() == [half["m_1"], half["m_2"]] and warm.initial[0] == res.initial[0]
    assert warm.converged and np.max(np.abs(warm.values / truth - 1)) < 1e-6
    # from far off (m_1 doubled, K_2 halved) the fit at 100 ms lands on the truth; from far off the other way (m_1
    # halved, K_2 doubled) both starts at 100 ms lose the basin (352 counts), and the fit runs again at 50 ms
    # intervals and lands on the truth
    far = identify(finger2, rec, progress=False, start={"m_1": 2 * true.finger.m[0], "K_2": true.finger.K[1] / 2})
    assert far.converged and "ms intervals" not in far.reason and np.max(np.abs(far.values / truth - 1)) < 1e-6
    far = identify(finger2, rec, progress=False, start={"m_1": true.finger.m[0] / 2, "K_2": 2 * true.finger.K[1]})
    assert far.converged and "(at 50 ms intervals; at 100 ms both starts missed" in far.reason
    assert np.max(np.abs(far.values / truth - 1)) < 1e-6
    # the dense KKT (the reference of the sparse default, alpes_dyn.estimation.identification.kkt): the same fit
    ref = identify(finger2, rec, progress=False, kkt="dense")
    assert ref.iterations == res.iterations and np.max(np.abs(ref.values / res.values - 1)) < 1e-9
    assert np.max(np.abs(ref.std / res.std - 1)) < 1e-6
    # SuperLU on the same sparse matrices (the reference of the banded-and-bordered factorisation, issue 39)
    gen = identify(finger2, rec, progress=False, kkt="superlu")
    assert gen.iterations == res.iterations and np.max(np.abs(gen.values / res.values - 1)) < 1e-9
    # a warm start from the result (fit_effects' rounds): stages 1-2 never run, the values and trajectory are kept
    from alpes_dyn.estimation.identification.gauss_newton import GaussNewton

    assert res.solution.nodes.shape == res.states.shape and res.solution.samples == 100
    from alpes_dyn.estimation.identification.shooting import ShootingProblem

    seen, runs = [], []
    monkeypatch.setattr(GaussNewton, "fit_nodes", staticmethod(lambda pb, nodes, *a, **k: seen.append(1) or nodes))
    cold = ShootingProblem.initial_nodes  # the model's own run over the whole record: only for a cold start
    monkeypatch.setattr(ShootingProblem, "initial_nodes", lambda pb, q0: runs.append(1) or cold(pb, q0))
    again = identify(finger2, rec, progress=False, start=res)
    assert not seen and not runs and again.converged and again.iterations <= 2 < res.iterations
    assert np.array_equal(again.initial, res.values) and np.max(np.abs(again.values[:4] / truth[:4] - 1)) < 1e-6
    assert np.max(np.abs(again.values / truth - 1)) < 3e-6  # as the first fit's
    other = identify(finger2, rec, progress=False, start=res, interval=0.05)  # cut at 50 ms: the values only
    assert seen and runs and other.converged and np.array_equal(other.initial, res.values)
    assert other.solution.samples == 50 and np.max(np.abs(other.values / truth - 1)) < 3e-6


def test_identify_recovers_an_encoder_offset_and_the_palm_tilt_from_noise_free_data(finger2):
    """The recording has no gravity columns but the palm is turned 3 degrees about y (in the finger's plane) and
    the encoder's zero is off by 0.2 rad of the motor shaft: K, m, friction, encoder_offset_finger and tilt_y
    are recovered (K, m, friction to 1e-6 relative, the offset and the angle, additive, from 0 to 1e-7 rad). The
    rigid fit without them converges too, 5.6 counts RMS off and m_1 56 % wrong."""
    true = perturbed_params(spread=0.2, seed=3)
    tilt_y, off = math.radians(3.0), 0.2
    g = tilted_gravity(np.array([0.0, 0.0, -9.81]), 0.0, tilt_y)
    assert np.allclose(g, 9.81 * np.array([math.sin(tilt_y), 0.0, -math.cos(tilt_y)]), rtol=0, atol=1e-15)
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0, orientations=(tuple(g),))
    rec = experiment("finger2", true, design, seed=3)
    assert rec.gravity is not None and np.allclose(rec.gravity, g)
    rec.gravity = None  # the palm's orientation unknown: what the fit must find
    tr = finger2.transmission
    rec.encoder = (rec.true_q @ tr.S.T + off) / (2 * math.pi / tr.counts_per_rev)  # unquantised, offset
    res = identify(finger2, rec, "K,m,friction,encoder_offset,tilt_y", progress=False)
    assert res.names[-2:] == ("encoder_offset_finger", "tilt_y") and res.units[-2:] == ("rad", "rad")
    truth = np.r_[true.finger.K[:2], true.finger.m[:2], true.finger.F_s[:2], true.finger.F_v[:2]]
    assert res.converged
    # K and m to 1e-6, the dry friction to 1e-5 (the least seen: the stopping rule's last chi^2 step of 0.1 leaves
    # F_s_1 3.2e-6 off)
    assert np.max(np.abs(res.values[:4] / truth[:4] - 1)) < 1e-6 and np.max(np.abs(res.values[:-2] / truth - 1)) < 1e-5
    assert abs(res.values[-2] - off) < 1e-7 and abs(res.values[-1] - tilt_y) < 1e-7  # rad (measured 5e-9, 3.5e-8)
    assert res.initial[-1] == 0.0 and res.residual_rms < 1e-3
    ident = res.params()  # the offset and the tilt belong to the recording, not to the parameter file
    assert np.allclose(ident.finger.K[:2], truth[:2], rtol=1e-6)
    with pytest.warns(UserWarning, match="tilt_x: no information in this recording"):
        both = identify(finger2, rec, "K,m,friction,encoder_offset,tilt", progress=False)  # tilt_x unseen
    assert both.values[-2] == 0.0 and both.std[-2] == math.inf and abs(both.values[-1] - tilt_y) < 1e-7


def test_identify_recovers_the_rotor_inertia_on_the_tendon_from_noise_free_data(tmp_path):
    """The rotor's J_m (30 % above the file's), on the tendon, fitted with K, m and friction: all to 1e-6; the
    identified file carries it as transmission.J_m."""
    from alpes_dyn.model.params import Param, with_values

    base = perturbed_params(spread=0.2, seed=3)
    J_true = 1.3 * base.J_m
    true = with_values(base, {"transmission.J_m": Param(J_true, "kg m^2", "assumed", "test", "rotor inertia J_m")})
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0)
    rec = experiment("finger2", true, design, seed=3, rotor_inertia=True)
    model = ad.Model.alpes("finger2", friction=True, rotor_inertia=True)
    tr = model.transmission
    rec.encoder = rec.true_q @ tr.S.T / (2 * math.pi / tr.counts_per_rev)
    res = identify(model, rec, "K,m,friction,J_m", progress=False)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2], true.finger.F_s[:2], true.finger.F_v[:2], J_true]
    assert res.names[-1] == "J_m_finger" and res.initial[-1] == base.J_m and res.converged
    assert np.max(np.abs(res.values / truth - 1)) < 1e-6
    ident = load_params(res.write(tmp_path / "ident.toml"))
    assert ident.raw["transmission.J_m"].source == "identified" and ident.J_m == pytest.approx(J_true, rel=1e-6)


def test_identify_finds_the_torque_constant_with_the_masses_held(finger2):
    """The torque constant 5 % off (the true motor torque is 1.05 times the recorded one): with the masses known
    (the maker's) and held, input_gain, K and friction are recovered to 1e-6; with every mass free too the scale
    is not seen, and identify refuses the selection."""
    from alpes_dyn.estimation.identification.identification import check_selection
    from alpes_dyn.model.params import with_values

    true = perturbed_params(spread=0.2, seed=3)
    # without the dither (with it F_s_2 stops 1.3e-6 off: the stopping rule's last chi^2 step)
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0, dither=0.0)
    rec = experiment("finger2", true, design, seed=3)
    tr = finger2.transmission
    rec.encoder = rec.true_q @ tr.S.T / (2 * math.pi / tr.counts_per_rev)
    rec.torque = rec.torque / 1.05
    known = with_values(load_params(), {k: true.raw[k] for k in ("finger.m", "finger.I")})
    model = ad.Model.alpes("finger2", friction=True, params=known)
    res = identify(model, rec, "K,friction,input_gain", progress=False)
    truth = np.r_[true.finger.K[:2], true.finger.F_s[:2], true.finger.F_v[:2], 1.05]
    assert res.names[-1] == "input_gain" and res.converged
    assert np.max(np.abs(res.values / truth - 1)) < 1e-6
    with pytest.raises(ModelError, match="input_gain with every mass, spring and friction"):
        check_selection(finger2, "K,m,friction,input_gain")
    check_selection(finger2, "K,m_1,friction,input_gain")  # one mass held fixes the scale


def test_fisher_information_of_the_offset_and_the_tilt(finger2):
    """What the encoder sees (the fit's selection, so its compiled code is shared): the offset's information is
    exactly (N + 1) / sigma^2 with the initial state known (dy/d offset = 1 at every sample); at a level palm
    tilt_x has none (a tilt about x puts gravity along the joint axes: seen only through cos tilt_x), tilt_y a
    finite bound; with the palm 3 degrees about x, tilt_x is seen too."""
    from alpes_dyn.analysis.identifiability import fisher_information

    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0)
    U = experiment("finger2", None, design, seed=0).torque[:-1]
    sel = "K,m,friction,encoder_offset,tilt_x,tilt_y"
    nominal = ad.load_params().finger
    th = np.r_[nominal.K[:2], nominal.m[:2], [ad.load_params().F_s] * 2, [ad.load_params().F_v] * 2, 0.0, 0.0, 0.0]
    level = fisher_information(finger2, sel, U=U, design=design, theta=th, initial_state="known")
    k = level.parameters.index("encoder_offset_finger")
    assert level.fim[k, k] == pytest.approx((U.shape[0] + 1) / level.encoder_std**2, rel=1e-12)
    assert level.rank == len(th) - 1 and level.std[-2] == math.inf and 0 < level.std[-1] < 1e-3  # rad
    th[-2] = math.radians(3.0)
    tilted = fisher_information(finger2, sel, U=U, design=design, theta=th, initial_state="known")
    assert tilted.rank == len(th) and tilted.std[-2] < 0.5 * th[-2]


def test_estimate_cli_with_parameter_files(tmp_path, capsys):
    """estimate --true-params/--observer-params: with the observer's file equal to the truth's the EKF is
    as good as with the exact model; with the shipped (nominal) file it is off by degrees."""
    import json

    from alpes_dyn.cli import main
    from alpes_dyn.estimation.observers.scenario import run_estimation

    true = write_params(perturbed_params(spread=0.2, seed=5), tmp_path / "true.toml")
    code = main(["estimate", "--friction", "--true-params", str(true), "--observer-params", str(true),
                 "--duration", "2", "--json"])
    exact = json.loads(capsys.readouterr().out)
    assert code == 0
    ref = run_estimation("ekf", friction=True, params=str(true), duration=2.0)
    assert np.allclose(exact["rmse"], ref.rmse, rtol=1e-12, atol=0)
    assert max(exact["rmse_deg"]) < 0.2
    code = main(["estimate", "--friction", "--true-params", str(true), "--duration", "2", "--json",
                 "--observer-params", str(load_params().path)])
    nominal = json.loads(capsys.readouterr().out)
    assert code == 0 and max(nominal["rmse_deg"]) > 1.0


def test_experiment_and_identify_cli(tmp_path, capsys):
    import json

    from alpes_dyn.cli import main

    rec, true, ident = tmp_path / "rec.csv", tmp_path / "true.toml", tmp_path / "ident.toml"
    assert main(["experiment", "--model", "finger2", "--perturb", "0.1", "--seed", "2", "--duration", "1",
                 "--true-params-out", str(true), "-o", str(rec), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["samples"] == 1001 and "true_q_j2" in out["columns"]
    # only K fitted while the true m and friction are 10 % off the starting file: the model cannot explain
    # the recording (coloured residual above the sensor floor), so nothing is written without --force
    assert main(["identify", "--model", "finger2", "--data", str(rec), "--parameters", "K", "-o", str(ident),
                 "--json"]) == 3
    res = json.loads(capsys.readouterr().out)
    assert not ident.exists() and res["output"] is None and res["adequacy"]["adequate"] is False
    assert main(["identify", "--model", "finger2", "--data", str(rec), "--parameters", "K", "-o", str(ident),
                 "--json", "--force"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert set(res["parameters"]) == {"K_1", "K_2"}
    p = load_params(ident)
    assert p.raw["finger.K"].source == "identified"
    assert np.allclose(p.finger.K[:2], [res["parameters"][k]["value"] for k in ("K_1", "K_2")], rtol=1e-12)
    assert p.finger.K[2] == load_params(true).finger.K[2] * 0 + load_params().finger.K[2]  # not fitted: kept


def test_identify_with_torque_noise_and_the_ekf_on_its_file(tmp_path):
    """The issue's pipeline on finger3, seed 2, 2 s: a finger 20 % off per link, the scenario's torque and
    encoder noise. The errors-in-variables fit lands within a few standard errors of the truth, the
    residual is the encoder noise (0.58 counts), and the EKF on the identified file is as good as on the
    true one, where the shipped file leaves it degrees off."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    true = perturbed_params(spread=0.2, seed=2)
    design = ExperimentDesign(duration=2.0)
    rec = experiment("finger3", true, design, seed=2)
    res = identify(ad.Model.alpes("finger3", friction=True), rec, excitation=design.lines, progress=False)
    truth = np.r_[true.finger.K, true.finger.m, true.finger.F_s, true.finger.F_v]
    assert 0.5 < res.residual_rms < 0.7
    assert np.all(np.abs(res.values - truth) < 4 * res.std)
    assert np.max(np.abs(res.values[:3] / truth[:3] - 1)) < 0.01  # K within 1 %
    assert np.max(np.abs(res.values[3:6] / truth[3:6] - 1)) < 0.05  # m within 5 %
    true_path = write_params(true, tmp_path / "true.toml")
    ident_path = res.write(tmp_path / "ident.toml")
    after = run_estimation("ekf", friction=True, params=str(true_path), observer_params=str(ident_path), duration=2.0)
    exact = run_estimation("ekf", friction=True, params=str(true_path), duration=2.0)
    before = run_estimation("ekf", friction=True, params=str(true_path), observer_params=str(load_params().path),
                            duration=2.0)
    assert np.degrees(after.rmse).max() < 0.5 < np.degrees(before.rmse).max()
    assert np.all(after.rmse < exact.rmse + math.radians(0.1))


def test_identify_recovers_the_tendon_compliance_from_noise_free_data(finger2, tmp_path):
    """A series-elastic tendon in its quasi-static limit: the encoder reads S q_k + C tau_m,k-1 (C = 6.3 rad/(N m), a
    3.97e4 N/m cable on the 2 mm motor pulley). Fitted from C = 0 with K, m and friction, all to 1e-6 (measured
    7e-8); the file written holds C as ``transmission.tendon_compliance``, which a model built from it reads back."""
    from alpes_dyn.model.params import Param, with_values

    C = 6.3
    true = with_values(perturbed_params(spread=0.2, seed=3),
                       {"transmission.tendon_compliance": Param(C, "rad/(N m)", "assumed", "test", "stretch")})
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0)
    rec = experiment("finger2", true, design, seed=3)
    tr = ad.Model.alpes("finger2", params=true).transmission
    assert tr.tendon_compliance.tolist() == [C]
    step = 2 * math.pi / tr.counts_per_rev
    # the stretch under the torque held before each reading (the cable's tension at t_k has seen u_k-1)
    before = torque_before(rec.torque)
    assert np.array_equal(before[1:], rec.torque[:-1]) and np.array_equal(before[0], rec.torque[0])
    assert np.abs(rec.encoder * step - tr.encoder_angles(rec.true_q, before)).max() <= step / 2
    rec.encoder = tr.encoder_angles(rec.true_q, before) / step  # unquantised
    res = identify(finger2, rec, "K,m,friction,tendon_compliance", progress=False)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2], true.finger.F_s[:2], true.finger.F_v[:2], C]
    assert res.names[-1] == "tendon_compliance_finger" and res.units[-1] == "rad/(N m)" and res.initial[-1] == 0.0
    # the compliance, K and m to 1e-6; the dry friction to 3e-6 (the dither: the least seen, see above)
    assert res.converged and np.max(np.abs(np.r_[res.values[:4], res.values[-1]] / np.r_[truth[:4], truth[-1]] - 1)) < 1e-6
    assert np.max(np.abs(res.values / truth - 1)) < 3e-6
    back = ad.Model.alpes("finger2", friction=True, params=res.write(tmp_path / "ident.toml"))
    assert back.transmission.tendon_compliance[0] == pytest.approx(C, rel=1e-6)
    assert back.params.raw["transmission.tendon_compliance"].source == "identified"
    rigid = identify(finger2, rec, progress=False)  # without it: the stretch is missed
    assert rigid.residual_rms > 100 * res.residual_rms


def test_identify_cli_fits_the_real_hands_effects_by_default(tmp_path, capsys):
    """``alpes-dyn identify`` without --parameters fits K, m, friction and the effects of --effects auto: the
    tendon compliance and the palm's tilt_y (the recording has no gravity columns); on our simulator's recording
    (rigid tendon, level palm, the smooth law) both come out within their standard errors of 0 (measured 1 sigma
    or less), the fit is adequate (no second fit with the stick-slip law). The compliance's 95 % interval reaches
    past 0: it is reported not identified (the data do not support an elastic tendon), fitted again held at 0, and
    the file does not hold it (issue 35: never a value the data cannot tell from none, nor a negative one).
    ``--effects none`` is the rigid fit."""
    import json

    from alpes_dyn.cli import main

    rec, true, ident = tmp_path / "rec.csv", tmp_path / "true.toml", tmp_path / "ident.toml"
    assert main(["experiment", "--model", "finger2", "--perturb", "0.1", "--seed", "2", "--duration", "2",
                 "--true-params-out", str(true), "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["identify", "--model", "finger2", "--data", str(rec), "-o", str(ident), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["effects"] == ["compliance", "tilt"] and res["tried"] is None and res["notes"] == []  # none failed
    assert [r["effects"] for r in res["rounds"]] == [["compliance", "tilt"]]  # one fit: adequate
    assert res["fit_seconds_total"] == res["rounds"][0]["seconds"] == res["seconds"] > 0
    names = list(res["parameters"])
    assert names[-1:] == ["tilt_y"] and len(names) == 9  # K, m, F_s, F_v of 2 joints, the tilt
    assert abs(res["parameters"]["tilt_y"]["value"]) < 3 * res["parameters"]["tilt_y"]["std"]
    why = res["not_identified"]["tendon_compliance_finger"]
    assert "the data do not support an elastic tendon" in why and ("reaches past 0" in why or "below" in why)
    p = load_params(ident)
    assert "transmission.tendon_compliance" not in p.raw and p.tendon_compliance == 0.0
    assert any("tendon_compliance_finger" in x for x in p.identification["finger"]["not_identified"])
    assert main(["identify", "--model", "finger2", "--data", str(rec), "--effects", "none", "--json"]) == 0
    rigid = json.loads(capsys.readouterr().out)
    assert rigid["effects"] == [] and list(rigid["parameters"]) == names[:-1]


def test_fit_effects_tries_the_stick_slip_law_where_the_verdict_names_it(monkeypatch):
    """The decision rule of --effects auto on stand-in fits: a second fit with the stick-slip law where the first
    is flagged (stick-slip named among the likely missing effects, or nothing named), none where it is adequate,
    the lower residual kept, each round started from the last one's values; while the kept fit is flagged, the
    next effect not yet tried (the rotor after the stick-slip law, then the torque delay and the encoder's offset),
    each effect once."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod

    def verdict(ok, missing=()):
        return SimpleNamespace(adequate=ok, likely_missing=list(missing))

    def fitted(residual, ok, missing=(), names=(), values=(), std=()):
        return SimpleNamespace(residual_rms=residual, adequacy=verdict(ok, missing), names=names, values=list(values),
                               std=list(std), trustworthy=ok, converged=True)

    from alpes_dyn.estimation.experiments.recording import Recording

    n = 20  # a stand-in recording: the fits are stand-ins too (the delay's round reads its torque)
    rec = Recording(t=np.arange(n) * 1e-3, encoder=np.zeros((n, 1)), torque=np.full((n, 1), 0.02),
                    motor_names=("finger",), joint_names=("j1", "j2"))
    calls, rotors, starts = [], [], []
    outcomes = {}

    def fake_identify(model, rec, parameters, **kw):
        stick = model.extras.smooth_velocity == eff.STICTION_VELOCITY
        calls.append((stick, parameters))
        rotors.append(model._rotor)
        starts.append(kw.get("start"))
        return outcomes[stick or model._rotor]  # the second fit's outcome: with the stick-slip law or the rotor

    monkeypatch.setattr(ident_mod, "identify", fake_identify)
    p = load_params()
    model_of = eff.alpes_models("finger2", p)  # the stick-slip law where the effects say, the rotor likewise

    stick_slip = "stick-slip / Coulomb friction (a torque following the sign of the motor velocity)"
    outcomes = {False: fitted(0.9, False, ["viscous friction", stick_slip]),
                True: fitted(0.6, True)}
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"))
    assert fit.effects == ("compliance", "tilt", "stiction") and fit.result is outcomes[True]
    assert fit.tried is outcomes[False] and fit.tried_effects == ("compliance", "tilt")
    assert calls == [(False, "K,m,friction,tendon_compliance,tilt_y"), (True, "K,m,friction,tendon_compliance,tilt_y")]
    calls.clear()
    outcomes[True] = fitted(1.5, False)  # worse: the first is kept, and (still flagged) the others tried on it
    rotors.clear()
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"))
    assert fit.effects == ("compliance", "tilt") and fit.result is outcomes[False] and len(calls) == 5
    assert rotors == [False, False, True, False, False] and [c[0] for c in calls] == [False, True, False, False, False]
    assert calls[-1][1].endswith("encoder_offset")  # then the torque delay and the encoder's offset
    assert fit.tried_effects == ("compliance", "tilt", "offset")  # every effect tried once: the rounds end
    calls.clear()
    outcomes[False] = fitted(0.6, False, ["viscous friction"])  # flagged, stick-slip not named: tried all the same
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert calls[:2] == [(False, "K,m,friction,tendon_compliance"), (True, "K,m,friction,tendon_compliance")]
    assert fit.result is outcomes[False] and fit.tried_effects == ("compliance", "tilt", "offset") and len(calls) == 5
    calls.clear()
    outcomes[False] = fitted(0.58, True)  # adequate: one fit
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert fit.tried is None and calls == [(False, "K,m,friction,tendon_compliance")]
    calls.clear()
    rotor = "rotor inertia (a torque following the motor acceleration; or a wrong inertia)"
    outcomes[False] = fitted(0.9, False, [rotor, stick_slip])
    outcomes[True] = fitted(0.6, True)
    rotors.clear()
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert fit.effects == ("compliance", "tilt", "stiction", "rotor") and rotors == [False, True]
    assert fit.result is outcomes[True] and len(calls) == 2
    calls.clear()
    rotors.clear()  # a compliance seen (above 3 standard errors): the rotor joins the second fit, unnamed
    outcomes[False] = fitted(0.7, False, ["viscous friction"], names=("K_1", "tendon_compliance_finger"),
                             values=[0.04, 6.0], std=[1e-4, 0.2])  # flagged, naming nothing, but stretching:
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)  # the rotor, alone
    assert fit.effects == ("compliance", "tilt", "rotor") and rotors == [False, True] and len(calls) == 2
    assert [c[0] for c in calls] == [False, False]  # no stick-slip law: the rotor's fit (0.6) is adequate
    assert starts[-1] is outcomes[False]  # the second round from the first (its values and trajectory)
    calls.clear()  # rounds: the stick-slip law named, then its fit sees the cable stretch: a third with the rotor
    outcomes[False] = fitted(0.9, False, [stick_slip])
    outcomes[True] = fitted(0.7, False, ["viscous friction"], names=("tendon_compliance_finger",), values=[6.0],
                            std=[0.2])
    starts.clear()
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert len(calls) == 5 and fit.effects == ("compliance", "tilt", "stiction")  # none after it lower: kept 2nd
    assert fit.tried_effects == ("compliance", "tilt", "stiction", "offset")  # the rotor, the delay, the offset
    assert starts[0] is None and starts[1] is outcomes[False] and starts[2] is outcomes[True]
    calls.clear()
    fit = eff.fit_effects(model_of, rec, ("stiction",))
    assert calls == [(True, None)] and fit.effects == ("stiction",)
    # a compliance below minus three standard errors (a cable shortening under tension): a last round without it
    calls.clear()
    starts.clear()
    outcomes[False] = fitted(0.6, True, names=("K_1", "tendon_compliance_finger"), values=[0.04, -0.42],
                             std=[1e-4, 0.1])
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert calls == [(False, "K,m,friction,tendon_compliance"), (False, None)] and fit.effects == ("tilt",)
    assert fit.tried_effects == ("compliance", "tilt") and starts[-1] is fit.tried
    calls.clear()  # within three standard errors of 0: kept as it is
    outcomes[False] = fitted(0.6, True, names=("tendon_compliance_finger",), values=[-0.25], std=[0.1])
    fit = eff.fit_effects(model_of, rec, eff.parse_effects("auto"), has_gravity=True)
    assert len(calls) == 1 and fit.effects == ("compliance", "tilt")


def test_identify_and_estimate_read_current_columns_with_a_torque_constant(tmp_path, capsys):
    """The documented current_<motor> columns (A) on the command line: --torque-constant N m/A makes them the
    motor torques; the fit and the observer are those of the same recording with torque_<motor> (N m)."""
    import json

    from alpes_dyn.cli import main
    from alpes_dyn.estimation.experiments.recording import write_recording

    kt = 0.05
    torque = write_recording(experiment("finger2", design=ExperimentDesign(duration=1.0), seed=1), tmp_path / "t.csv")
    lines = torque.read_text().splitlines()
    j = lines[0].split(",").index("torque_finger")
    rows = [lines[0].replace("torque_finger", "current_finger")]
    for line in lines[1:]:
        cells = line.split(",")
        cells[j] = repr(float(cells[j]) / kt)
        rows.append(",".join(cells))
    current = tmp_path / "c.csv"
    current.write_text("\n".join(rows) + "\n")
    fits = []
    for argv in (["--data", str(torque)], ["--data", str(current), "--torque-constant", str(kt)]):
        main(["identify", "--model", "finger2", *argv, "--json", "--force", "-o", str(tmp_path / "i.toml")])
        fits.append(json.loads(capsys.readouterr().out))
    a, b = ({k: v["value"] for k, v in f["parameters"].items()} for f in fits)
    sd = {k: v["std"] for k, v in fits[0]["parameters"].items()}
    # the same fit up to the torque's rounding (current / kt * kt): K, m, friction to 1e-8; the tendon's compliance,
    # about 0 on this rigid finger, 9e-8 relative apart (a millionth of its standard error): all within 1e-6 sigma
    assert a.keys() == b.keys() and all(abs(a[k] - b[k]) <= 1e-6 * sd[k] for k in a)
    assert all(np.isclose(a[k], b[k], rtol=1e-8, atol=1e-12) for k in a if k[0] in "KmF")
    assert f"from {current}" in (tmp_path / "i.toml").read_text().splitlines()[0]  # the header names the file
    est = []
    for argv in (["--data", str(torque)], ["--data", str(current), "--torque-constant", str(kt)]):
        assert main(["estimate", "--model", "finger2", "--friction", *argv, "--json"]) == 0
        est.append(json.loads(capsys.readouterr().out))
    assert np.allclose(est[0]["rmse_deg"], est[1]["rmse_deg"], rtol=1e-6)


@pytest.mark.parametrize("rotor", [False, True], ids=["rigid", "rotor"])
def test_shooting_problem_jacobians_equal_finite_differences(finger2, rotor):
    """The fit's problem alone (:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`): the Jacobians of its
    residuals and continuity defects, with respect to every node, torque line coefficient and parameter (log K, m,
    friction; the additive encoder offset; the compliance in its scale), equal central differences of the residuals
    themselves (relative 1e-5 of the largest entry), on 0.3 s of finger2 with camera columns and the lines' errors in
    variables: every term of the residual. With the rotor, the stretch is C (u - J_m S qdd)
    (:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.tension_torque`), its qdd the states'."""
    from alpes_dyn.estimation.identification.shooting import ShootingProblem, torque_model

    if rotor:
        finger2 = ad.Model.alpes("finger2", friction=True, rotor_inertia=True)

    true = perturbed_params(spread=0.2, seed=4)
    design = ExperimentDesign(duration=0.3)
    rec = experiment("finger2", true, design, seed=4)
    qm = rec.true_q.copy()
    qm[np.arange(len(qm)) % 9 != 0] = np.nan  # the camera: every 9th sample
    rec.q = qm
    sel = "K,m,friction,encoder_offset,tendon_compliance"
    torque = torque_model(rec, design.lines[:4], None)
    assert torque.lines and torque.noise > 0
    sens = SensitivityModel(finger2, sel, dt=rec.dt, substeps=4, input_basis=torque.nphi)
    pb = ShootingProblem(finger2, rec, sens, 100, torque, math.radians(0.1),
                         start={"tendon_compliance_finger": 2.0, "encoder_offset_finger": 0.01})
    rng = np.random.default_rng(0)
    nodes = pb.initial_nodes(np.zeros(pb.n)) + 1e-3 * rng.standard_normal((pb.n_int, pb.nx))
    offs = np.zeros((pb.n_int, pb.no))
    glob = 0.05 * rng.standard_normal(pb.ng)
    e = pb.evaluate(nodes, offs, glob)
    assert pb.q_mask.sum() > 0 and e.r.shape[1] > (pb.L + 1) * pb.ny  # camera residuals are in
    assert (pb.rotor is not None) == rotor
    if rotor:  # the rotor's share: J_m times the motor's acceleration over the period before each sample
        qd, u = e.xs[:, :, pb.n: 2 * pb.n], pb.torque_at(glob, offs)
        share = (u - pb.tension_torque(u, e.xs)) / finger2.transmission.rotor_inertia
        acc = (qd[:, 1:] - qd[:, :-1]).sum(axis=2) * 2.0 / rec.dt  # finger2: q_m = (r / r_m) (q_1 + q_2), r / r_m = 2
        assert np.allclose(share[:, 1:, 0], acc, rtol=1e-9, atol=1e-9 * np.abs(acc).max())
        # an interval's first sample: its first period's (the same formula on two evaluations of one period: equal
        # to rounding, which differs between builds of the compiled step)
        assert np.allclose(share[:, 0], share[:, 1], rtol=1e-12, atol=1e-12 * np.abs(share).max())
        assert np.abs(u - pb.tension_torque(u, e.xs)).max() > 1e-3 * np.abs(u).max()  # not negligible here
    h = 1e-6

    def fd(s, k, glob_index=None):
        """Central differences of (r, c) in interval s's node entry k, or in global variable glob_index."""
        out = []
        for sign in (1, -1):
            nd, gl = nodes.copy(), glob.copy()
            if glob_index is None:
                nd[s, k] += sign * h
            else:
                gl[glob_index] += sign * h
            t = pb.evaluate(nd, offs, gl, jac=False)
            out.append((t.r, t.c))
        return (out[0][0] - out[1][0]) / (2 * h), (out[0][1] - out[1][1]) / (2 * h)

    for s, k in ((0, 0), (1, 3), (2, 1)):
        dr, dc = fd(s, k)
        assert np.allclose(dr[s], e.J[s, :, k], rtol=0, atol=1e-5 * np.abs(e.J[s, :, k]).max())
        assert np.abs(np.delete(dr, s, axis=0)).max() == 0.0  # a node moves its own interval only
        if s < pb.n_int - 1:
            assert np.allclose(dc[s], e.Cv[s, :, k], rtol=0, atol=1e-5 * max(np.abs(e.Cv[s, :, k]).max(), 1e-9))
    for g in list(range(pb.p)) + [pb.p, pb.ng - 1]:  # every parameter and two line coefficients
        dr, dc = fd(None, None, g)
        col, ccol = e.J[:, :, pb.nb + g], e.Cr[:, :, g]
        assert np.allclose(dr, col, rtol=0, atol=1e-5 * np.abs(col).max()), sens.names[g] if g < pb.p else g
        assert np.allclose(dc, ccol, rtol=0, atol=1e-5 * max(np.abs(ccol).max(), 1e-12))
    es = pb.evaluate(nodes, offs, glob, jac="state")  # stage 1's: the start states' columns alone, the same numbers
    assert np.array_equal(es.r, e.r) and np.array_equal(es.J, e.J[:, :, :pb.nx]) and es.Cr is None
    assert np.array_equal(es.Cv, e.Cv[:, :, :pb.nx])  # (GaussNewton.join_nodes' continuity)
