"""The observer on a recording (estimation.observers.replay, ``alpes-dyn estimate --data``): against the recorded true
joints of a simulated experiment, a torque bias absorbed by the disturbance state (closed form: d -> -bias), and
the command line."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
from alpes_dyn.estimation.observers.replay import estimate_recording


@pytest.fixture(scope="module")
def drawn():
    """A finger3 drawn 20 % off (seed 21), its 2 s identification experiment (our simulator, friction on)."""
    true = perturbed_params(spread=0.2, seed=21)
    rec = experiment("finger3", true_params=true, design=ExperimentDesign(duration=2.0), seed=21)
    return true, rec


def test_true_model_tracks_the_recorded_joints(drawn):
    true, rec = drawn
    res = estimate_recording(rec, ad.Model.alpes("finger3", friction=True, params=true))
    assert res.rmse is not None and res.rmse.shape == (3,)
    assert np.degrees(res.rmse).max() < 0.2  # quantisation 0.09 deg of motor shaft, torque noise 5e-4 N m
    # the torque noise is estimated from the recording: the experiment's 5e-4 N m
    assert res.settings["torque_noise_Nm"] == pytest.approx(5e-4, rel=0.05)
    # the nominal model (20 % off) is worse: the test can tell a wrong model
    nominal = estimate_recording(rec, ad.Model.alpes("finger3", friction=True))
    assert nominal.rmse.max() > 3 * res.rmse.max()


def test_a_torque_bias_goes_into_the_disturbance_state(drawn):
    true, rec = drawn
    bias = 1.5e-3  # N m: the torque sensor reads this much too high (4 % of the holding torque)
    biased = dataclasses.replace(rec, torque=rec.torque + bias)
    model = ad.Model.alpes("finger3", friction=True, params=true)
    plain = estimate_recording(biased, model)
    dist = estimate_recording(biased, model, disturbance=True)
    assert dist.disturbance is not None and dist.disturbance.shape == (rec.n_samples, 1)
    # the filter learns d = -bias (the true torque is the recorded one minus the bias)
    k = rec.n_samples // 2
    assert np.mean(dist.disturbance[k:, 0]) == pytest.approx(-bias, rel=0.1)
    assert dist.rmse.max() < 0.5 * plain.rmse.max()
    assert np.degrees(dist.rmse).max() < 0.3


def test_constant_gravity_columns_set_the_orientation(drawn):
    true, rec = drawn
    g = np.array([0.0, 0.0, -9.81])
    with_g = dataclasses.replace(rec, gravity=np.tile(g, (rec.n_samples, 1)))
    model = ad.Model.alpes("finger3", friction=True, params=true)
    a = estimate_recording(with_g, model)
    b = estimate_recording(rec, model)
    np.testing.assert_allclose(a.estimate.z, b.estimate.z, rtol=0, atol=1e-12)
    g2 = with_g.gravity.copy()
    g2[::50] = [0.0, 1.0, -9.76]  # changing every 50 samples: no rig holds it, the observer has no gravity input
    with pytest.raises(ad.RecordingError, match="gravity_x,_y,_z vary"):
        estimate_recording(dataclasses.replace(rec, gravity=g2), model)


def test_turned_recording_runs_each_orientation_in_turn():
    """A record turned halfway from palm up to hung fingers down (experiment --rig both's design, our simulator):
    the EKF of the true file runs each orientation in its own model, the estimate carried over the turn, within
    0.2 degree on every joint; the same record read as palm up throughout is far off after the turn (the test can
    tell the orientations apart)."""
    from alpes_dyn.model.mjcf import hanging_gravity

    true = perturbed_params(spread=0.2, seed=22)
    level = ExperimentDesign(duration=2.0)
    hung = tuple(float(x) for x in hanging_gravity(ad.load_params().gravity))
    rec = experiment("finger3", true_params=true, design=dataclasses.replace(
        level, orientations=(tuple(level.orientations[0]), hung)), seed=22)
    model = ad.Model.alpes("finger3", friction=True, params=true)
    turned = estimate_recording(rec, model)
    assert np.degrees(turned.rmse).max() < 0.2 and turned.estimate.z.shape == (rec.n_samples, 6)
    wrong = estimate_recording(dataclasses.replace(rec, gravity=None), model)
    assert wrong.rmse.max() > 10 * turned.rmse.max()


def test_cli_estimate_data(drawn, tmp_path, capsys):
    """``estimate --data`` (in this process: the command's exit at the process boundary is test_bad_input's and
    test_cli's) prints the API's RMSE and logs its estimate."""
    true, rec = drawn
    from alpes_dyn.cli import main
    from alpes_dyn.model.params import write_params

    write_recording(rec, tmp_path / "rec.csv")
    write_params(true, tmp_path / "true.toml")
    assert main(["estimate", "--data", str(tmp_path / "rec.csv"), "--params", str(tmp_path / "true.toml"),
                 "--friction", "--json", "--log", str(tmp_path / "est.csv")]) == 0
    obj = json.loads(capsys.readouterr().out)
    api = estimate_recording(read_recording(tmp_path / "rec.csv", ad.Model.alpes("finger3", friction=True)),
                             ad.Model.alpes("finger3", friction=True, params=tmp_path / "true.toml"))
    assert obj["joints"] == ["j1", "j2", "j3"] and len(obj["rmse"]) == 3
    np.testing.assert_allclose(obj["rmse"], api.rmse, rtol=1e-9)
    log = np.genfromtxt(tmp_path / "est.csv", delimiter=",", names=True)
    assert log.dtype.names[:4] == ("t", "q_hat_j1", "q_hat_j2", "q_hat_j3")
    np.testing.assert_allclose(log["q_hat_j2"], api.q_hat[:, 1], rtol=0, atol=1e-12)
