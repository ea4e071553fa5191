"""The observer's uncertainty (issue 50, item 3): each joint's reported sigma, the NEES and its band, and the joints a
motion does not observe.

References: sigma is sqrt of the diagonal of the filter's P, read here from P itself; the NEES is the quadratic form
written here with numpy, its band without the filter scipy.stats' chi-square quantiles, and the band's count of
independent samples a Monte Carlo of a lightly damped linear oscillator simulated here in numpy with exactly the
filter's noises (the spread of 60 runs' NEES against the spread the filter predicts); the consistency on MuJoCo,
a simulator the library did not write; the unobserved joints the Shadow finger's J2 + J1 pair that its one tendon
moves together (Menagerie's MJCF, no spring: only the friction holds their split).
"""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.analysis.joint_observability import joint_observability
from alpes_dyn.cli import main
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.consistency import joint_sigma, nees
from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter
from alpes_dyn.estimation.observers.scenario import run_estimation
from alpes_dyn.model.extras import JointExtras
from alpes_dyn.symbolic.statespace import StateSpace

from test_simulation import C_OSC, I_OSC, K_OSC, OSC_URDF

DEG = math.pi / 180


@pytest.fixture(scope="module")
def finger3_run():
    """finger3, exact model, no friction: the estimation scenario (5 s, as ``estimate``'s default)."""
    return run_estimation("ekf", duration=5.0, seed=9101)


def test_estimate_reports_each_joints_sigma_from_P(finger3_run, capsys, cli_text):
    """``estimate --json``: q_std_median_deg and q_std_worst_deg are the median and the largest of sqrt(P_ii) after
    the transient, read here from the run's P; the table prints them."""
    assert main(["estimate", "--seed", "9101", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    r = finger3_run
    sd = np.sqrt(np.diagonal(r.estimate.P, axis1=1, axis2=2))[int(round(r.scenario.transient_s / 1e-3)):, :3]
    np.testing.assert_allclose(out["q_std_median_deg"], np.degrees(np.median(sd, axis=0)), rtol=1e-9)
    np.testing.assert_allclose(out["q_std_worst_deg"], np.degrees(sd.max(axis=0)), rtol=1e-9)
    med, worst = joint_sigma(r.estimate, 3, r.scenario.transient_s)
    np.testing.assert_allclose(np.degrees(worst), out["q_std_worst_deg"], rtol=1e-12)
    assert 0.01 < min(out["q_std_median_deg"]) and max(out["q_std_worst_deg"]) < 0.5
    assert out["unobserved"] == [] and out["nees"]["verdict"] == "consistent"
    n_eff = out["nees"]["measured_effective_samples"]  # the count the series shows, beside the filter's
    assert 1 <= n_eff <= out["nees"]["samples"] and len(out["nees"]["joint_measured_effective_samples"]) == 3
    text = cli_text[0]  # the table of the same run, without --json
    assert "sigma median/worst [deg]:" in text and "NEES of the joints:" in text and "WARNING" not in text
    assert "the series itself shows" in text


def test_nees_on_our_simulator_is_in_its_band(finger3_run):
    """The exact model on our simulator: the NEES of the joints in its 95 % band, equal to the quadratic form
    computed here; the filter's error model counts fewer independent samples than the decimated ones (the
    frictionless finger's internal mode rings for seconds); without the filter the band is scipy's chi-square of
    n M degrees of freedom over M."""
    from scipy.stats import chi2

    r = finger3_run
    v = nees(r.estimate, r.q_true, r.filter, r.u_meas, start=r.scenario.transient_s)
    k = np.arange(1000, 5001, 100)
    e = r.q_hat[k] - r.q_true[k]
    eps = [x @ np.linalg.inv(P[:3, :3]) @ x for x, P in zip(e, r.estimate.P[k])]
    assert v.value == pytest.approx(np.mean(eps), rel=1e-9) and v.samples == k.size and v.dof == 3
    assert v.consistent and v.low < 3.0 < v.high
    assert 3 < v.effective < 0.6 * k.size
    free = nees(r.estimate, r.q_true, start=r.scenario.transient_s)
    assert free.value == pytest.approx(v.value) and free.effective == k.size
    np.testing.assert_allclose([free.low, free.high], chi2.ppf([0.025, 0.975], 3 * k.size) / k.size, rtol=1e-9)


def oscillator_runs(dt: float, N: int, Q: np.ndarray, R: float, P0: np.ndarray, runs: int, seed: int):
    """A lightly damped oscillator (test_simulation's) seen through its angle, ``runs`` draws of N periods of dt s
    simulated here with exactly a filter's process noise Q (2, 2) and measurement noise R (rad^2), the initial state
    drawn from N(0, P0) (its RK4 step is the Taylor polynomial of exp(A dt)): (its state space, A_d, the true states
    (runs, N + 1, 2), the measurements (runs, N + 1, 1))."""
    extras = JointExtras(stiffness=np.array([K_OSC]), armature=np.zeros(1), coulomb=np.zeros(1),
                         viscous=np.array([C_OSC]))
    ss = StateSpace(ad.Model(OSC_URDF, extras=extras, gravity=[0.0, 0.0, 0.0]), input="joint", output=np.eye(1))
    A = np.array([[0.0, 1.0], [-K_OSC / I_OSC, -C_OSC / I_OSC]])
    Ad = sum(np.linalg.matrix_power(A * dt, k) / math.factorial(k) for k in range(5))
    rng = np.random.default_rng(seed)
    X = np.zeros((runs, N + 1, 2))
    X[:, 0] = rng.multivariate_normal(np.zeros(2), P0, runs)
    for k in range(N):  # the truth, every run at once
        X[:, k + 1] = X[:, k] @ Ad.T + rng.multivariate_normal(np.zeros(2), Q, runs)
    Y = X[:, :, :1] + rng.normal(0.0, math.sqrt(R), (runs, N + 1, 1))
    return ss, Ad, X, Y


def test_nees_band_predicts_the_spread_of_a_linear_filter():
    """A lightly damped oscillator (1.3 Hz, damping ratio 0.03) seen through its angle, simulated here with exactly
    the filter's process and measurement noises (its RK4 step is the Taylor polynomial of exp(A dt)): over 150 runs
    the NEES averages 1 and its spread across runs is the one the band assumes, 2 n / M_eff (within the Monte Carlo
    error of a heavy-tailed variance: 1.30 and 1.11 on 200 runs of two other draws), where independent samples
    would give a tenth of it: M_eff is 3.5 of the 31 decimated samples."""
    dt, N, Q, R = 1e-3, 2000, np.diag([0.0, 1e-8]), np.array([[1e-4]])
    runs, P0 = 150, np.diag([1e-2, 1e-1])
    ss, _, X, Y = oscillator_runs(dt, N, Q, float(R[0, 0]), P0, runs, seed=9101)
    f = ExtendedKalmanFilter(ss, dt, process_noise=Q, measurement_noise=R)
    W = np.zeros((N, 1))
    values, pred = [], []
    for i in range(runs):  # a filter run per draw
        est = f.run(np.zeros(2), np.diag(P0), W, Y[i])
        v = nees(est, X[i, :, :1], f, W, start=0.5, every=0.05)
        values.append(v.value)
        pred.append(2.0 / v.effective)
    assert v.samples == 31 and 2 < v.effective < 0.2 * v.samples
    assert np.mean(values) == pytest.approx(1.0, abs=0.15)
    assert 0.65 < np.var(values, ddof=1) / np.mean(pred) < 1.5


def _mujoco_nees(torque_noise: float, seed: int = 9101, encoder_noise_counts: float = 0.0):
    """finger3 on MuJoCo with the library's smooth friction law (PlantEffects() default: the model is right), the
    estimation scenario's torque for 2 s, its torque sensor of ``torque_noise`` N m, the observer with the true file
    (told the encoder's noise beyond quantisation, counts): the NEES of the joints."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.plants import mujoco_recording
    from alpes_dyn.estimation.observers.replay import estimate_recording
    from alpes_dyn.estimation.observers.scenario import EstimationScenario, _torque

    u = _torque(EstimationScenario(), 1e-3 * np.arange(2001), 1)
    rec = mujoco_recording("finger3", None, u, 1e-3, seed=seed, torque_noise=torque_noise)
    r = estimate_recording(rec, ad.Model.alpes("finger3", friction=True), torque_noise=torque_noise,
                           encoder_noise_counts=encoder_noise_counts)
    return nees(r.estimate, rec.true_q, r.filter, r.inputs, start=r.settings["transient_s"])


def test_nees_on_a_mujoco_smooth_friction_plant():
    """With a noiseless torque sensor the NEES on MuJoCo's smooth-friction plant is in its band."""
    v = _mujoco_nees(0.0)
    assert v.consistent, v.to_dict()


def test_nees_on_a_mujoco_smooth_friction_plant_with_torque_noise():
    """The same plant with the estimation scenario's torque noise (5e-4 N m), the filter told the plant's encoder
    noise (0.5 count beyond quantisation, :func:`~alpes_dyn.control.plants.mujoco_recording`'s): in its band with
    the smooth law's model error as process noise (:mod:`~alpes_dyn.estimation.observers.friction_noise`; without it
    15-22, over-confident)."""
    v = _mujoco_nees(5e-4, encoder_noise_counts=0.5)
    assert v.consistent, v.to_dict()
    assert v.value > 1.5 and v.per_joint.max() < 2.0


def test_the_shadow_fingers_coupled_pair_is_flagged_and_finger3_is_not(finger3_run):
    """Menagerie's Shadow first finger on a held palm (its MJCF imported: J4, J3 and the pair J2 + J1 on one tendon,
    no spring, dry friction 0.01 N m each), moved by the identification experiment's torque on our simulator: the
    encoders pin J4 and J3 within 0.1 degree, the pair's split not within 1 degree (flagged). finger3 on the
    estimation scenario, with and without its friction: every joint within a tenth of a degree."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment_torque
    from alpes_dyn.model.mjcf_import import example_mjcf_path
    from alpes_dyn.simulation.integrate import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        hand = ad.Model.from_mjcf(example_mjcf_path("shadow_hand"), hold=["rh_WRJ2", "rh_WRJ1"])
    finger = hand.subtree(["rh_A_FFJ4", "rh_A_FFJ3", "rh_A_FFJ0"])
    _, u, x0 = model_experiment_torque(finger, finger, ExperimentDesign(duration=3.0, amplitude_fraction=1.0))
    run = simulate(finger, x0, u[:-1], duration=3.0, dt=1e-3, input="motor", output="joints", joint_range="ignore")
    step = 2 * np.pi / finger.transmission.counts_per_rev
    o = joint_observability(finger, run.x, u[:-1], 1e-3, np.full(3, step**2 / 12 + (0.5 * step) ** 2))
    assert finger.joint_names == ("rh_FFJ4", "rh_FFJ3", "rh_FFJ2", "rh_FFJ1") and not finger.extras.stiffness.any()
    assert o.unobserved == ("rh_FFJ2", "rh_FFJ1") and o.friction == finger.joint_names
    assert np.all(o.best[2:] > 2 * DEG) and np.all(o.best[:2] < 0.1 * DEG)
    assert o.to_dict()["unobserved"] == ["rh_FFJ2", "rh_FFJ1"]
    r = finger3_run
    o3 = joint_observability(r.filter.model.system.model, r.estimate.z, r.u_meas, 1e-3, r.filter.R)
    assert o3.unobserved == () and np.all(o3.best < 0.1 * DEG) and o3.friction == ()
    rf = run_estimation("ekf", duration=3.0, seed=9101, friction=True)
    of = joint_observability(rf.filter.model.system.model, rf.estimate.z, rf.u_meas, 1e-3, rf.filter.R)
    assert of.unobserved == () and np.all(of.best < 0.2 * DEG) and of.friction == ("j1", "j2", "j3")


def test_bad_inputs_name_their_argument(finger3_run, capsys):
    r = finger3_run
    for kw, word in (({"true_q": r.q_true[:-1]}, "true_q"), ({"true_q": r.q_true * np.nan}, "true_q"),
                     ({"start": 5.0}, "start"), ({"every": 1e-4}, "every"), ({"level": 1.0}, "level"),
                     ({"every": 4.9, "start": 0.5}, "every"), ({"inputs": r.u_meas[:-1]}, "inputs")):
        args = {"true_q": r.q_true, "inputs": r.u_meas, **kw}
        with pytest.raises(InputError, match=f"^{word}:"):
            nees(r.estimate, args.pop("true_q"), r.filter, args.pop("inputs"), **args)
    m = r.filter.model.system.model
    for kw, word in (({"states": r.estimate.z[:, :2]}, "states"), ({"inputs": r.u_meas[1:]}, "inputs"),
                     ({"measurement_noise": [0.0]}, "measurement_noise"), ({"window": 0.0}, "window"),
                     ({"limit": float("nan")}, "limit")):
        args = {"states": r.estimate.z, "inputs": r.u_meas, "measurement_noise": r.filter.R, **kw}
        with pytest.raises(InputError, match=f"^{word}:"):
            joint_observability(m, args.pop("states"), args.pop("inputs"), 1e-3, args.pop("measurement_noise"),
                                **args)
    for bad in ("0", "-1", "nan", "200"):
        assert main(["estimate", "--duration", "1", "--sigma-limit", bad]) == 2
        err = capsys.readouterr().err
        assert "--sigma-limit: expected degrees in (0, 180]" in err and err.count("\n") == 1
