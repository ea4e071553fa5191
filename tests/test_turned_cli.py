"""``alpes-dyn experiment --rig hanging|both`` with --bench mujoco and --design-only (issue 49): both orientations on
the MuJoCo stand-in, joined into the recording that ``identify`` reads and fits in each run's orientation; one
torque profile per rig. Shortened (0.5 s records; the identify fit with two effects)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from alpes_dyn import cli
from alpes_dyn.estimation.experiments.design import ExperimentDesign
from alpes_dyn.estimation.experiments.on_hand import designed_torque
from alpes_dyn.estimation.experiments.recording import read_recording
from alpes_dyn.model.robot import Model

FINGER3 = Model.alpes("finger3", friction=True)


def _run(capsys, *argv: str) -> tuple[int, dict]:
    code = cli.main(list(argv))
    out = capsys.readouterr().out
    return code, json.loads(out)


def test_bench_both_rigs_joined_and_identify_fits_each_orientation(tmp_path, capsys):
    pytest.importorskip("mujoco")
    rec_path = tmp_path / "rec.csv"
    code, obj = _run(capsys, "experiment", "--model", "finger3", "--bench", "mujoco", "--rig", "both", "--duration",
                     "0.5", "-o", str(rec_path), "--json")
    assert code == 0 and obj["rigs"] == ["level", "hanging"]
    assert [r["rig"] for r in obj["runs"]] == ["level", "hanging"]
    for r in obj["runs"]:  # each run's calibration, trim and amplitude named
        assert {"rest_counts", "low_counts", "high_counts"} <= set(r["calibration"])
        assert len(r["bias_nm"]) == 1 and 0.0 < r["amplitude_scale"] <= 1.0 and r["samples"] == 501
    rec = read_recording(rec_path, FINGER3)
    assert rec.n_runs == 2 and obj["samples"] == rec.n_samples == 1002
    # identify on it: two runs, each in its own gravity (palm up; hung, a quarter turn about the joints' axes:
    # (0, 0, -g) turned by -90 degrees about y is (g, 0, 0)), and the palm's tilt fitted on top
    code, ident = _run(capsys, "identify", "--model", "finger3", "--data", str(rec_path), "--effects",
                       "compliance,tilt", "-o", str(tmp_path / "ident.toml"), "--json", "--force")
    assert code in (0, 3)  # a 1 s record: the verdict may say not adequate; the file is written with --force
    assert [r["samples"] for r in ident["runs"]] == [501, 501]
    np.testing.assert_allclose(ident["runs"][0]["gravity"], [0.0, 0.0, -9.81], atol=1e-12)
    np.testing.assert_allclose(ident["runs"][1]["gravity"], [9.81, 0.0, 0.0], atol=1e-9)
    assert "tilt_y" in ident["parameters"] and ident["converged"]
    assert abs(ident["parameters"]["tilt_y"]["value"]) < 0.2  # rad: the stand-in's few degrees, not a turn


def test_design_only_one_profile_per_rig(tmp_path, capsys):
    """--rig both: -o's name with _level and _hanging (-o itself not written), each the design in its rig's
    orientation, checked against designed_torque with the orientation written by hand; --rig hanging: -o."""
    out = tmp_path / "torque.csv"
    code, obj = _run(capsys, "experiment", "--design-only", "--rig", "both", "--duration", "1", "-o", str(out),
                     "--json")
    files = {r: tmp_path / f"torque_{r}.csv" for r in ("level", "hanging")}
    assert code == 0 and not out.exists() and obj["output"] == [str(files["level"]), str(files["hanging"])]
    hung = ExperimentDesign(duration=1.0, orientations=((9.81, 0.0, 0.0),))
    for rig, design in (("level", ExperimentDesign(duration=1.0)), ("hanging", hung)):
        data = np.loadtxt(files[rig], delimiter=",", skiprows=1)
        t, u, target = designed_torque(FINGER3, design)
        np.testing.assert_allclose(data[:, 0], t, atol=1e-12)
        np.testing.assert_allclose(data[:, 1], u[:, 0], rtol=1e-9, atol=1e-12)
        prof = next(p for p in obj["profiles"] if p["rig"] == rig)
        assert prof["target_counts"]["finger"] == pytest.approx(target[0], rel=1e-9)
    level, hanging = (np.loadtxt(files[r], delimiter=",", skiprows=1)[:, 1] for r in ("level", "hanging"))
    assert np.max(np.abs(level - hanging)) > 1e-4  # N m: hung, another bias (the springs hold the finger alone)
    one = tmp_path / "hung.csv"
    code, obj = _run(capsys, "experiment", "--design-only", "--rig", "hanging", "--duration", "1", "-o", str(one),
                     "--json")
    assert code == 0 and obj["rigs"] == ["hanging"] and obj["output"] == str(one)
    np.testing.assert_allclose(np.loadtxt(one, delimiter=",", skiprows=1)[:, 1], hanging, rtol=1e-12, atol=0)


def test_bench_both_trip_names_the_rig_and_the_other(tmp_path, monkeypatch, capfd):
    """--rig both where every rig trips (the run replaced by one that trips): exit 3, one line naming the last
    rig, no file."""
    pytest.importorskip("mujoco")
    from alpes_dyn.estimation.experiments import turned
    from alpes_dyn.estimation.experiments.hand_session import GuardTripped

    def tripped(hw, nominal, design, **kw):
        raise GuardTripped("guard: motor finger: encoder at 995 counts is below the guard band", "stop", 1.0,
                           np.array([995.0]), None)

    monkeypatch.setattr(turned, "run_experiment", tripped)
    out = tmp_path / "rec.csv"
    code = cli.main(["experiment", "--bench", "mujoco", "--rig", "both", "-o", str(out)])
    _, err = capfd.readouterr()
    assert code == 3 and not out.exists() and err.count("\n") == 1
    assert "experiment stopped: rig hanging: guard: motor finger: encoder at 995" in err


def test_bench_both_keeps_the_hung_run_where_palm_up_trips(tmp_path, monkeypatch, capsys):
    """--rig both where palm up trips (a soft finger near its fold, as on about half the +-20 % finger3 draws):
    the hung run is recorded alone (one run, the hung gravity), the trip named in --json's ``tripped`` and the
    text's note; exit 0 (the recording is sound, of one orientation)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.estimation.experiments import turned
    from alpes_dyn.estimation.experiments.hand_session import GuardTripped

    real = turned.run_experiment

    def palm_up_trips(hw, nominal, design, **kw):
        if design.orientations[0][2] < -9.0:  # palm up: gravity along -z
            raise GuardTripped("guard: motor finger: encoder at 957 counts is below the guard band", "stop", 0.5,
                               np.array([957.0]), None)
        return real(hw, nominal, design, **kw)

    monkeypatch.setattr(turned, "run_experiment", palm_up_trips)
    out = tmp_path / "rec.csv"
    code, obj = _run(capsys, "experiment", "--bench", "mujoco", "--rig", "both", "--duration", "0.5", "-o", str(out),
                     "--json")
    assert code == 0 and obj["rigs"] == ["hanging"] and [r["rig"] for r in obj["runs"]] == ["hanging"]
    assert obj["tripped"] == [{"rig": "level", "reason": "guard: motor finger: encoder at 957 counts is below the "
                                                         "guard band"}]
    assert "level: the guard stopped its run" in obj["note"]
    rec = read_recording(out, FINGER3)
    assert rec.n_runs == 1 and rec.n_samples == obj["samples"] == 501
    np.testing.assert_allclose(rec.gravity[0], [9.81, 0.0, 0.0], atol=1e-9)  # the hung orientation's
