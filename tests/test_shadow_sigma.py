"""Menagerie's Shadow first finger on MuJoCo with its own friction (``frictionloss`` 0.01 N m per joint, MuJoCo's
default friction constraint), the springless pair J2 + J1 seen through its sum (issue 50): ``estimate`` reports
each joint's sigma and flags the pair, the sigma it reports there covering the error the recording's true joints
show (the filter's own P does not)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main


@pytest.fixture(scope="module")
def shadow_recording(tmp_path_factory):
    """2 s of the identification experiment's torque (amplitude 1) on the finger exported to MJCF as the library
    writes it (its frictionloss and damping kept), replayed on MuJoCo; the URDF and spec the estimate reads."""
    pytest.importorskip("mujoco")
    from alpes_dyn.control.plants import mjcf_recording
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment_torque
    from alpes_dyn.estimation.experiments.recording import write_recording
    from alpes_dyn.model.mjcf_export import model_mjcf
    from alpes_dyn.model.mjcf_import import example_mjcf_path

    d = tmp_path_factory.mktemp("shadow")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        hand = ad.Model.from_mjcf(example_mjcf_path("shadow_hand"), hold=["rh_WRJ2", "rh_WRJ1"])
    finger = hand.subtree(["rh_A_FFJ4", "rh_A_FFJ3", "rh_A_FFJ0"])
    (d / "finger.urdf").write_text(finger.urdf)
    (d / "finger.toml").write_text(finger.spec.to_toml())
    truth = ad.Model.from_urdf_file(d / "finger.urdf", d / "finger.toml")
    xml = model_mjcf(truth)
    assert xml.count('frictionloss="0.01"') == 4
    _, u, x0 = model_experiment_torque(truth, truth, ExperimentDesign(duration=2.0, amplitude_fraction=1.0))
    rec = mjcf_recording(xml, truth, u, 1e-3, seed=9931, q0=x0[: truth.n])
    write_recording(rec, d / "rec.csv")
    return d, rec


def test_estimate_flags_the_pair_with_a_sigma_that_covers_its_error(shadow_recording, capsys, cli_text):
    """Each joint either within 1 degree of MuJoCo's and not flagged (J4, J3), or flagged as not observed with a
    reported sigma (``q_sigma_deg``) at least its RMSE (J2, J1, where the filter's own worst sqrt(P_ii) is below it:
    the gap this closes); the observed joints' sigma is the filter's. The table the command prints without
    ``--json`` is read from the same run (the ``cli_text`` fixture: one EKF run and one observability analysis
    instead of two)."""
    d, rec = shadow_recording
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["estimate", "--model", str(d / "finger.urdf"), "--spec", str(d / "finger.toml"),
                     "--data", str(d / "rec.csv"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    joints = ("rh_FFJ4", "rh_FFJ3", "rh_FFJ2", "rh_FFJ1")
    final = np.degrees(rec.true_q[-1])
    rmse = np.degrees(np.asarray(out["rmse"]))
    sigma, worst = np.asarray(out["q_sigma_deg"]), np.asarray(out["q_std_worst_deg"])
    assert tuple(out["joints"]) == joints and out["unobserved"] == ["rh_FFJ2", "rh_FFJ1"]
    assert np.all(rmse[:2] < 1.0) and np.array_equal(sigma[:2], worst[:2])
    assert np.all(rmse[2:] > 0.5) and np.all(worst[2:] < rmse[2:])  # the filter's own P over-confident there
    assert np.all(sigma[2:] >= rmse[2:]), (sigma, rmse)
    np.testing.assert_allclose(sigma[2:], out["observability"]["best_std_deg"][2:], rtol=1e-12)
    assert np.all(np.abs(np.degrees(out["final_q"])[2:] - final[2:]) < 3 * sigma[2:])
    (text,) = cli_text
    assert "sigma reported [deg]:" in text and text.count("not observed: the data's bound") == 2
