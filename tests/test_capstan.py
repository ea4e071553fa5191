"""Tendon-sheath friction (capstan, issue 37 part 3): the law against the capstan equation, the backends against each
other, the spec and the parameter file, and the fit that the verdict sends to it."""

from __future__ import annotations

import dataclasses
import math
import warnings

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import AlpesDynWarning
from alpes_dyn.model.mjcf import mjcf_string
from alpes_dyn.model.params import Param, load_params, with_values
from alpes_dyn.model.spec import TransmissionSpec
from alpes_dyn.model.transmission import capstan_torque, capstan_velocity
from alpes_dyn.symbolic.parametric import ParametricDynamics, parameter_catalogue, select_parameters
from alpes_dyn.symbolic.statespace import StateSpace

MU = 0.3  # mu theta: a cable on a sheath bent through 90 degrees with mu = 0.19


def _with_capstan(params, mu: float):
    return with_values(params, {"transmission.capstan": Param(mu, "-", "assumed", "test", "sheath friction")})


@pytest.fixture(scope="module")
def finger2():
    return ad.Model.alpes("finger2", friction=True, params=_with_capstan(load_params(), MU))


def test_the_joints_get_the_capstan_equations_torque_where_the_tendon_slides(finger2):
    """Where the tendon slides (|v_m| 20 times the smooth sign's scale, tanh = 1 to 1e-16), the joint torque the
    simulator's dynamics apply, read back by Pinocchio's inverse dynamics (RNEA, springs, smooth friction: another
    code), is the capstan equation's: S^T tau_m exp(-mu theta) while the motor pulls the cable in, S^T tau_m
    (2 - exp(-mu theta)) while the joints pull it out (the law's first-order mirror), 1e-9 relative."""
    m = finger2
    ss = StateSpace(m, input="motor", output="encoder")
    S = m.transmission.S
    v_c = capstan_velocity(S, m.extras.smooth_velocity)
    assert v_c.tolist() == [pytest.approx(2.0 * m.extras.smooth_velocity)]  # the ratio 2 of finger2's tendon
    q = np.array([0.4, 0.7])
    for direction, factor in ((1.0, math.exp(-MU)), (-1.0, 2.0 - math.exp(-MU))):
        v = direction * np.array([3.0, 1.0])  # v_m = 2 (3 + 1) = 8 rad/s, 40 v_c
        for tau_m in (0.05, 0.013):
            qdd = ss.f(np.r_[q, v], np.array([tau_m]))[m.n:]
            tau = m.inverse_dynamics(q, v, qdd, smooth=True)
            expected = S.T @ np.array([tau_m * factor])
            assert np.max(np.abs(tau - expected)) < 1e-9 * np.max(np.abs(expected))
    # at rest the sheath does not act (tanh 0): the statics are the rigid tendon's
    assert np.array_equal(capstan_torque(np.array([0.05]), np.zeros(1), np.array([MU]), v_c), np.array([0.05]))


def test_the_symbolic_and_parametric_paths_equal_the_numeric_one(finger2, rng):
    """qdd of the motor-input dynamics: the numeric (Pinocchio's ABA + the transmission's capstan), the state
    space's CasADi expression and the identification's parametric one (capstan_finger a symbol, at the model's value,
    and at another value against a model built with it) agree to 1e-9 relative; the sheath never feeds power in."""
    m = finger2
    ss = StateSpace(m, input="motor", output="encoder")
    pd = ParametricDynamics(m, "K,m,friction,capstan")
    assert pd.names[-1] == "capstan_finger" and pd.nominal[-1] == MU
    q, v, u = cs.SX.sym("q", m.n), cs.SX.sym("v", m.n), cs.SX.sym("u", 1)
    qdd = cs.Function("qdd", [q, v, u, pd.theta], [pd.forward_dynamics(q, v, pd.input_torque(q, v, u), pd.theta)])
    other = ad.Model.alpes("finger2", friction=True, params=_with_capstan(load_params(), 0.07))
    ss_other = StateSpace(other, input="motor", output="encoder")
    theta_other = pd.nominal.copy()
    theta_other[-1] = 0.07
    for _ in range(4):
        qs, vs = m.random_state(rng)
        us = rng.uniform(-0.06, 0.06, 1)
        x = np.r_[qs, vs]
        num = ss.f(x, us)[m.n:]
        scale = np.max(np.abs(num))
        assert np.max(np.abs(np.array(ss.f_function(x, us)).ravel()[m.n:] - num)) < 1e-9 * scale
        assert np.max(np.abs(np.array(qdd(qs, vs, us, pd.nominal)).ravel() - num)) < 1e-9 * scale
        num_other = ss_other.f(x, us)[m.n:]
        assert np.max(np.abs(np.array(qdd(qs, vs, us, theta_other)).ravel() - num_other)) < 1e-9 * np.max(np.abs(num_other))
        vm = m.transmission.motor_velocities(qs, vs)
        loss = us - m.transmission.transmitted(us, vm, m.extras.smooth_velocity)
        assert float(loss @ vm) >= 0.0 and np.all(np.abs(loss) <= (1 - math.exp(-MU)) * np.abs(us) + 1e-18)


def test_the_sheath_under_tension_asks_for_more_rk4_steps(finger2):
    """The sheath's friction slope S^T (1 - exp(-mu theta)) |tau_m| / v_c S grows with the tension: the RK4 steps per
    sample count it where the tension is given (the experiment, the fit and the observer give the recording's largest
    torque), and nothing changes without it or at zero tension."""
    from alpes_dyn.simulation.integrate import friction_rate, stable_substeps

    assert friction_rate(finger2, tension=0.0) == friction_rate(finger2) > 0
    assert stable_substeps(finger2, 1e-3) == 4 < stable_substeps(finger2, 1e-3, tension=0.03)
    assert friction_rate(finger2, tension=0.06) > friction_rate(finger2, tension=0.03) > friction_rate(finger2)


def test_mujoco_with_the_sheath_on_its_rigid_tendon_moves_as_our_simulator():
    """MuJoCo has no sheath friction: its plant adds the library's law through its passive-force callback (the
    actuator's torque as the tension, S qd as the tendon's velocity). finger2 drawn +-20 % with mu theta = 0.3 under
    a bias and two sines (the tendon sliding both ways), 0.3 s from rest: MuJoCo (RK4 at 0.1 ms) and our compiled RK4
    at the same step agree to 1e-9 rad (measured 1e-16); our finger without the sheath is degrees away."""
    from alpes_dyn.control.plants import mujoco_recording
    from alpes_dyn.estimation.experiments.experiment import perturbed_params
    from alpes_dyn.simulation.integrate import compile_rollout

    base = perturbed_params(spread=0.2, seed=3)
    true = _with_capstan(base, MU)
    t = 1e-3 * np.arange(301)
    u = (0.02 + 0.008 * np.sin(2 * np.pi * 4 * t) + 0.004 * np.sin(2 * np.pi * 11 * t))[:, None]  # N m
    model = ad.Model.alpes("finger2", friction=True, params=true)
    x0 = np.r_[model.static_equilibrium(None, tau_m=u[0]), 0.0, 0.0]
    rec = mujoco_recording("finger2", true, u, 1e-3, q0=x0[:2], encoder_noise_counts=0.0, torque_noise=0.0)
    U = np.repeat(u[:-1], 10, axis=0)[None]  # each sample's torque held over ten 0.1 ms steps
    q = np.asarray(compile_rollout(model, 1e-4, input="motor").rollout(x0[None], U))[0, ::10, :2]
    assert np.abs(q - rec.true_q).max() < 1e-9
    bare = compile_rollout(ad.Model.alpes("finger2", friction=True, params=base), 1e-4, input="motor")
    assert np.degrees(np.abs(np.asarray(bare.rollout(x0[None], U))[0, ::10, :2] - rec.true_q).max()) > 1.0


def test_the_spec_field_the_parameter_file_and_the_catalogue(tmp_path):
    """``capstan`` in a spec's [[motor]] entry: read, kept by to_toml, on the model's transmission; without it 0 and
    the model's dynamics bit for bit the rigid tendon's. The catalogue holds capstan_<motor> (kind capstan, nominal
    the model's, fitted as it is): the kind selects every motor's even at 0; a parameter file's
    transmission.capstan goes on the Alpes chains' tendons (not the ab/adduction gear)."""
    text = ('[[motor]]\nname = "a"\njoints = { j1 = 2.0, j2 = 1.5 }\ncapstan = 0.25\n'
            '[[motor]]\nname = "b"\njoints = { j3 = 1.0 }\n')
    spec = TransmissionSpec.from_toml(text)
    assert [mo.capstan for mo in spec.motors] == [0.25, 0.0]
    assert TransmissionSpec.from_toml(spec.to_toml()) == spec and "capstan = 0.25" in spec.to_toml()
    tr = spec.transmission(("j1", "j2", "j3"))
    assert tr.capstan.tolist() == [0.25, 0.0] and tr.has_capstan
    plain = ad.Model.alpes("finger2", friction=True)
    assert not plain.transmission.has_capstan
    cat = {p.name: p for p in parameter_catalogue(plain)}
    assert cat["capstan_finger"].kind == "capstan" and cat["capstan_finger"].nominal == 0.0
    assert cat["capstan_finger"].unit == "-" and cat["capstan_finger"].additive
    assert [p.name for p in select_parameters(plain, "capstan")] == ["capstan_finger"]
    x, u = np.r_[0.3, 0.5, 1.0, -2.0], np.array([0.04])
    assert np.array_equal(StateSpace(plain, input="motor").f(x, u),
                          StateSpace(ad.Model.alpes("finger2", friction=True, params=_with_capstan(load_params(), 0.0)),
                                     input="motor").f(x, u))
    with pytest.warns(AlpesDynWarning, match=r"transmission.capstan: MuJoCo has no tendon-sheath friction"):
        mjcf_string("finger2", _with_capstan(load_params(), 0.2))  # nothing silently dropped
    hand = ad.Model.alpes("hand", params=_with_capstan(load_params(), 0.2))
    mu = dict(zip(hand.transmission.motor_names, hand.transmission.capstan))
    assert mu["index"] == 0.2 and mu["thumb"] == 0.2 and mu["thumb_abduction"] == 0.0


@pytest.mark.filterwarnings("ignore::alpes_dyn.estimation.identification.adequacy.AdequacyWarning")
def test_the_verdict_names_the_sheath_friction_and_the_fit_finds_it(tmp_path):
    """Our simulator's finger2 (drawn +-20 %, seed 3) with mu theta = 0.02 on its tendon (2 % of the tension lost
    where the motor pulls), the documented experiment turned between level and hung fingers down (1 s each: the
    holding torque, hence the tension, changes; at one holding torque the sheath's friction and the joints' dry
    friction are one direction). ``--effects auto`` from the rigid fit: flagged, naming the tendon-sheath friction
    first; its round finds mu theta within 10 % (measured 0.0202), K within 3 %, m within 5 % (0.1 %, 0.04 %),
    adequate; the file written carries it, and a model built from it has it."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from alpes_dyn.estimation.identification.effects import alpes_models, fit_effects
    from alpes_dyn.model.mjcf import hanging_gravity

    mu = 0.02
    true = _with_capstan(perturbed_params(spread=0.2, seed=3), mu)
    level = ExperimentDesign(duration=1.0)
    design = dataclasses.replace(level, orientations=(level.orientations[0],
                                                      tuple(float(g) for g in hanging_gravity(np.array(true.gravity)))))
    rec = experiment("finger2", true, design, seed=3)
    fit = fit_effects(alpes_models("finger2", load_params()), rec, ("auto",), has_gravity=True,
                      excitation=design.lines, observe=False)
    rigid, res = fit.tried, fit.result
    assert fit.tried_effects == () and fit.effects == ("capstan",) and len(fit.rounds) == 2
    assert not rigid.adequacy.adequate and rigid.adequacy.likely_missing[0].startswith("tendon-sheath friction")
    assert res.converged and res.trustworthy and res.residual_rms < rigid.residual_rms
    got = dict(zip(res.names, res.values))
    assert abs(got["capstan_finger"] / mu - 1) < 0.10
    ch = true.chain("finger")
    assert max(abs(got[f"K_{i}"] / ch.K[i - 1] - 1) for i in (1, 2)) < 0.03
    assert max(abs(got[f"m_{i}"] / ch.m[i - 1] - 1) for i in (1, 2)) < 0.05
    back = ad.Model.alpes("finger2", friction=True, params=res.write(tmp_path / "ident.toml"))
    assert back.transmission.capstan[0] == pytest.approx(got["capstan_finger"], rel=1e-12)
    assert back.params.raw["transmission.capstan"].source == "identified"


def test_identified_spec_holds_the_fitted_sheath_friction():
    """``identify -o`` on a URDF + spec robot: a fitted capstan_<motor> goes into its [[motor]] entry and its standard
    error into [identified.capstan]; the spec written reads back (a made-up fit: the writing alone)."""
    from alpes_dyn.estimation.identification.identification import IdentificationResult
    from alpes_dyn.estimation.identification.identified_spec import identified_spec

    spec = TransmissionSpec.from_toml('[[motor]]\nname = "flexor"\njoints = { j1 = 2.0, j2 = 2.0 }\n\n'
                                      "[stiffness]\nj1 = 0.04\nj2 = 0.05\n")
    model = ad.Model(ad.urdf_string("finger2"), spec)  # finger2's URDF, its joints j1, j2 on one tendon
    names = ("K_1", "capstan_flexor")
    res = IdentificationResult(names=names, values=np.array([0.041, 0.023]), std=np.array([1e-5, 4e-4]),
                               initial=np.array([0.04, 0.0]), units=("N m/rad", "-"), correlation=np.eye(2),
                               residual_rms=0.5, iterations=1, converged=True, seconds=0.0, compile_seconds=0.0,
                               states=np.zeros((1, 4)), node_times=np.zeros(1), model=model)
    out = identified_spec(res, spec)
    assert out.motors[0].capstan == 0.023 and dict(out.identified["capstan"]) == {"flexor": 4e-4}
    back = TransmissionSpec.from_toml(out.to_toml())
    assert back.motors[0].capstan == 0.023 and back.identified["capstan"]["flexor"] == 4e-4
    assert ad.Model(ad.urdf_string("finger2"), back).transmission.capstan.tolist() == [0.023]


def test_identified_spec_writes_a_negative_tendon_compliance_at_its_bound():
    """A fit whose tendon compliance crossed its bound 0 (the whole Shadow hand's ``identify --force`` on a 0.5 s
    record: -6.6e-5 rad/(N m) on a wrist motor, then the written spec refused by its own check after the whole fit)
    writes the bound, 0, with the fit's standard error; a positive one as fitted; the spec reads back."""
    from alpes_dyn.estimation.identification.identification import IdentificationResult
    from alpes_dyn.estimation.identification.identified_spec import identified_spec

    spec = TransmissionSpec.from_toml('[[motor]]\nname = "flexor"\njoints = { j1 = 2.0, j2 = 2.0 }\n\n'
                                      "[stiffness]\nj1 = 0.04\nj2 = 0.05\n")
    model = ad.Model(ad.urdf_string("finger2"), spec)
    names = ("K_1", "tendon_compliance_flexor")
    for fitted, written in ((-6.6e-5, 0.0), (3e-4, 3e-4)):
        res = IdentificationResult(names=names, values=np.array([0.041, fitted]), std=np.array([1e-5, 2e-5]),
                                   initial=np.array([0.04, 0.0]), units=("N m/rad", "rad/(N m)"),
                                   correlation=np.eye(2), residual_rms=0.5, iterations=1, converged=True,
                                   seconds=0.0, compile_seconds=0.0, states=np.zeros((1, 4)), node_times=np.zeros(1),
                                   model=model)
        out = identified_spec(res, spec)
        assert out.motors[0].tendon_compliance == written
        assert dict(out.identified["tendon_compliance"]) == {"flexor": 2e-5}
        back = TransmissionSpec.from_toml(out.to_toml())
        assert back.motors[0].tendon_compliance == written
