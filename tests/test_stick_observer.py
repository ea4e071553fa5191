"""The observers' stick-slip law (alpes_dyn.simulation.stick, friction_law="stick") against independent references.

References: the friction step's velocity against a brute-force enumeration written here in numpy (every joint stuck,
sliding forwards or backwards; the one consistent mode of the strictly convex step) on the numeric model's own mass
matrix and frictionless forward dynamics (Pinocchio, not the symbolic expressions); the stuck mode against the exact
static condition |tau - G(q)| <= F_s; the slip mode against the smooth law's forward dynamics where tanh(v / v_s) is
1; and the EKF with the true file against MuJoCo's stiff stick-slip friction (``frictionloss`` with the 0.5 ms
``solreffriction``), which the library did not write.
"""

from __future__ import annotations

import dataclasses
import itertools

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.discrete import DiscreteModel
from alpes_dyn.estimation.observers.observers import make_observer
from alpes_dyn.simulation.stick import coulomb_velocity
from alpes_dyn.symbolic.statespace import StateSpace

H = 1e-3  # s, one step of the observers' 1 kHz


@pytest.fixture(scope="module")
def finger3():
    model = ad.Model.alpes("finger3", friction=True)
    ss = StateSpace(model, input="motor", output="encoder")
    return model, ss, DiscreteModel(ss, H, friction_law="stick")


def brute_force(A: np.ndarray, b: np.ndarray, limit: np.ndarray) -> np.ndarray:
    """The v of A v = b - f, |f_i| <= limit_i, f_i = limit_i sign(v_i) where v_i != 0: every mode tried."""
    n = b.size
    for mode in itertools.product((0, 1, -1), repeat=n):
        sl = [i for i in range(n) if mode[i]]
        v = np.zeros(n)
        if sl:
            v[sl] = np.linalg.solve(A[np.ix_(sl, sl)], b[sl] - limit[sl] * np.array([mode[i] for i in sl]))
        lam = b - A @ v
        if all(abs(lam[i]) <= limit[i] * (1 + 1e-12) if mode[i] == 0 else np.sign(v[i]) == mode[i] for i in range(n)):
            return v
    raise AssertionError("no consistent mode")


def numeric_step(model, ss, q, v, u, h=H):
    """The step's v+ from the numeric model: N = M qdd_frictionless, A = M + h diag(F_v), b = M v + h N."""
    free = ad.Model.alpes("finger3", friction=False)
    tau = ss.B @ u
    M = model.inertia_matrix(q)
    N = M @ free.forward_dynamics(q, v, tau)
    ex = model.extras
    return brute_force(M + h * np.diag(ex.viscous), M @ v + h * N, h * ex.coulomb)


def test_velocity_is_the_exact_minimiser():
    """coulomb_velocity on symbolic (A, b) against the brute force, on mass matrices of finger3 and momenta that put
    the joints in every mode."""
    model = ad.Model.alpes("finger3", friction=True)
    A_s, b_s = cs.SX.sym("A", 3, 3), cs.SX.sym("b", 3)
    limit = H * np.array([5e-4, 4e-4, 6e-4])
    f = cs.Function("v", [A_s, b_s], [coulomb_velocity(A_s, b_s, limit)])
    rng = np.random.default_rng(3)
    modes = set()
    for _ in range(300):
        A = model.inertia_matrix(rng.uniform(0.1, 1.4, 3)) + H * 1e-4 * np.eye(3)
        b = A @ (rng.normal(0.0, 0.05, 3) * rng.integers(0, 2, 3)) + H * rng.normal(0.0, 1e-3, 3)
        ref = brute_force(A, b, limit)
        np.testing.assert_allclose(np.array(f(A, b)).ravel(), ref, rtol=1e-9, atol=1e-12)
        modes.add(tuple(np.sign(ref).astype(int)))
    assert len(modes) >= 15  # stuck, forwards and backwards on each joint, in most combinations


def test_stuck_mode_holds_under_the_static_condition(finger3):
    """From rest, a motor torque whose net joint torque |tau - G(q)| is below F_s on every joint keeps every
    v = 0 and q where it is; a torque that exceeds F_s on a joint moves the joints as the brute force says."""
    model, ss, dm = finger3
    Fs = model.extras.coulomb
    u_eq = np.array([0.02])
    q = model.static_equilibrium(ss.B @ u_eq)  # the frictionless rest under u_eq: there tau - G(q) = 0
    G = model.gravity_torque(q)
    for du in (0.0, 2e-4, -2e-4, 3e-3, -3e-3):
        u = u_eq + du
        net = ss.B @ u - G
        z = np.array(dm.step(np.r_[q, np.zeros(3)], u)).ravel()
        held = bool(np.all(np.abs(net) <= Fs))
        ref = numeric_step(model, ss, q, np.zeros(3), u)
        np.testing.assert_allclose(z[3:], ref, rtol=1e-7, atol=1e-12)
        if held:
            assert np.all(z[3:] == 0.0) and np.all(z[:3] == q)
        else:
            assert np.any(z[3:] != 0.0)
    assert np.all(np.abs(ss.B @ (u_eq + 2e-4) - G) <= Fs)  # the cases held...
    assert np.any(np.abs(ss.B @ (u_eq + 3e-3) - G) > Fs)  # ... and slipped were both tried


def test_moving_step_matches_the_numeric_model(finger3):
    """From moving states (some joints nearly at rest), the step's velocity is the brute force's on Pinocchio's
    mass matrix and dynamics."""
    model, ss, dm = finger3
    rng = np.random.default_rng(5)
    for _ in range(20):
        q = rng.uniform(0.2, 1.2, 3)
        v = rng.normal(0.0, 0.02, 3) * rng.integers(0, 2, 3)
        u = rng.uniform(0.0, 0.03, 1)
        z = np.array(dm.step(np.r_[q, v], u)).ravel()
        vn = numeric_step(model, ss, q, v, u)
        np.testing.assert_allclose(z[3:], vn, rtol=1e-7, atol=1e-11)
        np.testing.assert_allclose(z[:3], q + H * vn, rtol=0, atol=1e-14)


def test_slip_mode_matches_the_smooth_law(finger3):
    """At |v| >> v_s (tanh = 1 to 1e-8) the stick law's acceleration (v+ - v) / h over a short step is the smooth
    law's forward dynamics, to O(h)."""
    model, ss, _ = finger3
    h = 1e-5
    dm = DiscreteModel(ss, h, friction_law="stick")
    rng = np.random.default_rng(7)
    for _ in range(5):
        q = rng.uniform(0.3, 1.0, 3)
        v = rng.choice([-1.0, 1.0], 3) * rng.uniform(2.0, 3.0, 3)
        u = rng.uniform(0.0, 0.03, 1)
        z = np.array(dm.step(np.r_[q, v], u)).ravel()
        a_stick = (z[3:] - v) / h
        a_smooth = model.forward_dynamics(q, v, ss.B @ u, smooth=True)
        np.testing.assert_allclose(a_stick, a_smooth, rtol=2e-3, atol=1e-3 * np.abs(a_smooth).max())


def test_step_is_built_once_per_structure(finger3):
    """The model's numbers (F_s among them) are the step's input p: a finger of other friction and masses runs the
    same step code (one compiled library), its values only differ."""
    _, ss, dm = finger3
    p = ad.load_params()
    other = dataclasses.replace(p, F_s=3 * p.F_s, F_v=2 * p.F_v)
    dm2 = DiscreteModel(StateSpace(ad.Model.alpes("finger3", friction=True, params=other), input="motor",
                                   output="encoder"), H, friction_law="stick")
    assert dm.step_p.n_instructions() == dm2.step_p.n_instructions()
    assert dm.values.size == dm2.values.size and not np.allclose(dm.values, dm2.values)
    z, w = np.r_[0.4, 0.5, 0.6, 0.01, -0.02, 0.0], np.r_[0.02]
    np.testing.assert_array_equal(np.array(dm2.step_p(z, w, dm2.values)), np.array(dm2.step(z, w)))
    assert dm.friction_law == "stick" and dm.substeps == 1


def test_friction_law_checked(finger3):
    _, ss, _ = finger3
    with pytest.raises(InputError, match="friction_law: expected one of smooth, stick, lugre"):
        DiscreteModel(ss, H, friction_law="dahl")
    with pytest.raises(InputError, match="friction_law"):
        make_observer("ekf", ss, H, process_noise=1e-9, measurement_noise=1e-7, friction_law=None)
    # a model without dry friction: the stick law is the smooth law's RK4
    free = StateSpace(ad.Model.alpes("finger3"), input="motor", output="encoder")
    assert DiscreteModel(free, H, friction_law="stick").friction_law == "smooth"


@pytest.fixture(scope="module")
def stick_slip_recording():
    """finger2 on MuJoCo with stiff stick-slip (0.5 ms solreffriction) and a strong dry friction (10 times the file's
    F_s: a 3 degree dead band per joint), a torque that ramps up, holds, ramps half-way down and holds (4 s): the
    joints stay stuck away from their frictionless rest."""
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.estimation.experiments.draws import perturbed_params
    from alpes_dyn.model.mjcf import STICTION_TIMECONST

    p = perturbed_params(spread=0.2, seed=9002)
    p = dataclasses.replace(p, finger=dataclasses.replace(p.finger, F_s=10 * p.finger.F_s))
    t = 1e-3 * np.arange(4001)
    u = np.interp(t, [0, 0.3, 0.8, 1.8, 2.3, 4.0], [0.020, 0.020, 0.028, 0.028, 0.024, 0.024])[:, None]
    rec = mujoco_recording("finger2", p, u, 1e-3, effects=PlantEffects(stiction=STICTION_TIMECONST), seed=10002)
    return rec, ad.Model.alpes("finger2", friction=True, params=p)


def test_ekf_holds_stuck_joints_on_mujoco(stick_slip_recording):
    """The EKF with the true file on MuJoCo's stick-slip: the smooth law creeps back to the frictionless rest (over
    1 degree RMS on every joint), the stick law holds the joints where they stuck (within 0.5 degree)."""
    from alpes_dyn.estimation.observers.replay import estimate_recording

    rec, model = stick_slip_recording
    smooth = np.degrees(estimate_recording(rec, model, "ekf").rmse)
    res = estimate_recording(rec, model, "ekf", friction_law="stick")
    stick = np.degrees(res.rmse)
    assert np.all(smooth > 1.0), smooth
    assert np.all(stick < 0.5), stick
    assert res.settings["friction_law"] == "stick" and res.settings["torque_window_samples"] == 10


def test_torque_average_is_causal_and_checked(stick_slip_recording):
    """averaged: row k is the mean of rows k-w+1..k (np.convolve here), the rows before the recording the mean of its
    first w; its white noise divided by about sqrt(w); bad windows and laws refused with one line naming them."""
    from alpes_dyn.estimation.observers.replay import estimate_recording
    from alpes_dyn.estimation.observers.torque_reading import averaged

    rec, model = stick_slip_recording
    w = 10
    tau = rec.torque[:, 0]
    ref = np.convolve(np.r_[np.full(w - 1, tau[:w].mean()), tau], np.ones(w) / w, "valid")
    np.testing.assert_allclose(averaged(rec, w).torque[:, 0], ref, rtol=0, atol=1e-12)  # a running sum
    assert averaged(rec, 1) is rec
    noise = rec.torque[:, 0] - np.interp(rec.t, [0, 0.3, 0.8, 1.8, 2.3, 4.0],
                                         [0.020, 0.020, 0.028, 0.028, 0.024, 0.024])
    ratio = np.std(np.convolve(noise, np.ones(w) / w, "valid")) / np.std(noise)
    assert abs(ratio - 1 / np.sqrt(w)) < 0.05
    for bad in (0, 101, 2.5, True):
        with pytest.raises(InputError, match="torque_window: expected a whole number of samples from 1 to 100"):
            averaged(rec, bad)
    with pytest.raises(InputError, match="friction_law: expected one of smooth, stick, lugre, got 'dahl'"):
        estimate_recording(rec, model, "ekf", friction_law="dahl")


def test_prior_is_the_dead_band():
    """The stick law's prior on the joints at rest: the extent sum_j |J^-1_ij| F_s,j of the box |J dq| <= F_s about the
    frictionless rest (J = dG/dq here by central differences of the numeric gravity and springs), with the rest's
    torque noise in quadrature; the smooth law's 0.5 rad where that is wider."""
    from alpes_dyn.estimation.observers.replay import _rest_spread

    model = ad.Model.alpes("finger3", friction=True)
    ss = StateSpace(model, input="motor", output="encoder")
    q0 = model.static_equilibrium(ss.B @ np.array([0.02]))
    eps = 1e-6
    J = np.column_stack([(model.gravity_torque(q0 + eps * e) - model.gravity_torque(q0 - eps * e)) / (2 * eps)
                         for e in np.eye(3)])
    Ji = np.linalg.inv(J)
    sigma = 5e-4 / np.sqrt(10)
    ref = np.hypot(np.abs(Ji) @ model.extras.coulomb, np.abs(Ji @ ss.B).sum(axis=1) * sigma)
    sd = _rest_spread(model, q0, ss.B, sigma)
    np.testing.assert_allclose(sd, ref, rtol=1e-5)
    assert np.all(sd < 0.1) and np.all(sd > 0.005)  # a few tenths of a degree to a few degrees, not 0.5 rad
    assert np.all(_rest_spread(model, q0, ss.B, 1.0) == 0.5)  # a torque noise of 1 N m: no better than the smooth law


def test_hand_resolved_finger_by_finger():
    """The hand's 15 joints (a mass matrix dense in structure from the symbolic backend, block diagonal in value):
    :func:`mass_blocks` finds the fingers and the thumb's two blocks, and the step is the brute force's per block
    on the numeric model."""
    from alpes_dyn.simulation.stick import mass_blocks

    model = ad.Model.alpes("hand", friction=True)
    free = ad.Model.alpes("hand", friction=False)
    blocks = mass_blocks(model)
    assert sorted(map(len, blocks)) == [1, 2, 3, 3, 3, 3] and sorted(sum(blocks, [])) == list(range(15))
    ss = StateSpace(model, input="motor", output="encoder")
    dm = DiscreteModel(ss, H, friction_law="stick")
    from alpes_dyn.estimation.observers.scenario import rest_with_held_joints

    u = np.array([0.02 if mn != "thumb_abduction" else 0.0 for mn in model.transmission.motor_names])
    q = rest_with_held_joints(model, u)  # every finger at its frictionless rest: held, ...
    q[:3] += 0.05  # ... but the index, pulled off it by 3 degrees: let go
    v = np.zeros(15)
    z = np.array(dm.step(np.r_[q, v], u)).ravel()
    M = model.inertia_matrix(q)
    N = M @ free.forward_dynamics(q, v, ss.B @ u)
    A, b, lim = M + H * np.diag(model.extras.viscous), M @ v + H * N, H * model.extras.coulomb
    ref = np.zeros(15)
    for rows in blocks:
        ref[rows] = brute_force(A[np.ix_(rows, rows)], b[rows], lim[rows])
    np.testing.assert_allclose(z[15:], ref, rtol=1e-7, atol=1e-11)
    assert np.all(z[18:] == 0.0) and np.all(z[15:18] != 0.0)  # the other fingers held, the index moving


def test_the_observer_with_the_joint_stops_holds_a_joint_on_its_stop():
    """finger3 drawn +-20 % (this draw's first joint reaches its 90 degree stop under the estimate scenario's torque)
    on MuJoCo's stiff stick-slip plant, the EKF with the TRUE file: without the stops in its model the joints are
    degrees off (the plant's stop holds the joint, the model lets it go on); with them (estimate_recording(stops=True),
    JointStops.of the model) within half a degree on every joint."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.plants import PlantEffects, mujoco_recording
    from alpes_dyn.estimation.experiments.draws import perturbed_params
    from alpes_dyn.estimation.observers.replay import estimate_recording
    from alpes_dyn.estimation.observers.scenario import EstimationScenario, _torque
    from alpes_dyn.model.mjcf import STICTION_TIMECONST

    sc = EstimationScenario(duration=5.0)
    t = sc.dt * np.arange(5001)
    p = perturbed_params(spread=0.2, seed=9005)
    obs = ad.Model.alpes("finger3", friction=True, params=p)
    rec = mujoco_recording("finger3", p, _torque(sc, t, 1), sc.dt, effects=PlantEffects(stiction=STICTION_TIMECONST),
                           seed=10005)
    assert np.degrees(rec.true_q[:, 0].max()) > 90.0  # the plant's first joint on its stop
    free = np.degrees(estimate_recording(rec, obs, "ekf").rmse)
    held = np.degrees(estimate_recording(rec, obs, "ekf", stops=True).rmse)
    assert free.max() > 1.0 and held.max() < 0.5, (free, held)
