"""The alpes-dyn command line: outputs equal the library's, bad input exits 2 with one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name", ad.MODELS)
def test_urdf_command(capsys, tmp_path, name):
    code, out, _ = run(capsys, "urdf", "--model", name)
    assert code == 0 and out == (ROOT / "urdf" / f"{name}.urdf").read_text()
    dest = tmp_path / "x.urdf"
    assert run(capsys, "urdf", "--model", name, "-o", str(dest))[0] == 0
    assert dest.read_text() == out


@pytest.mark.parametrize("qarg", [["--q=-0.1,0.2,0.3"], ["--q", "-0.1,0.2,0.3"]])
def test_dynamics_json_negative_vectors(capsys, qarg):
    code, out, err = run(capsys, "dynamics", "--model", "finger3", *qarg, "--v=0.5,-1,2", "--tau", "-0.01,0,0.002",
                         "--force=0,0,1.5", "--spring", "report", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert {"model", "q", "v", "tau", "A", "C", "G", "J", "qdd"} <= set(d)
    m = ad.Model.alpes("finger3", spring="report")
    q, v, tau = np.array([-0.1, 0.2, 0.3]), np.array([0.5, -1, 2.0]), np.array([-0.01, 0, 0.002])
    assert d["q"] == q.tolist()
    assert np.allclose(d["A"], m.inertia_matrix(q), rtol=1e-15)
    assert np.allclose(d["C"], m.coriolis_matrix(q, v), rtol=1e-15)
    assert np.allclose(d["G"], m.gravity_torque(q), rtol=1e-15)
    assert np.allclose(d["J"], m.fingertip_jacobian(q), rtol=1e-15)
    assert np.allclose(d["qdd"], m.forward_dynamics(q, v, tau, [0, 0, 1.5]), rtol=1e-15)


def test_dynamics_readable_and_hand_tip(capsys):
    code, out, _ = run(capsys, "dynamics", "--model", "hand", "--tip", "thumb_tip")
    assert code == 0
    assert "A(q) [kg m^2]" in out and "thumb_tip" in out


@pytest.mark.parametrize("argv,needle", [
    (["dynamics", "--model", "finger9"], "unknown model 'finger9'"),
    (["dynamics", "--q=0.1,0.2"], "--q: model 'finger3' has 3 joints, got 2 values"),
    (["dynamics", "--q=0.1,x,0.2"], "--q: expected comma-separated numbers"),
    (["dynamics", "--q=0.1,nan,0.2"], "--q: contains NaN or inf"),
    (["dynamics", "--force=0,1"], "--force: expected 3 values"),
    (["dynamics", "--tip", "nail"], "unknown tip/frame 'nail'"),
    (["dynamics", "--spring", "cubic"], "invalid choice: 'cubic'"),
    (["dynamics", "--params", "/nonexistent.toml"], "cannot be read"),
    (["dynamics", "--model", "/nonexistent.urdf"], "cannot be read"),
    (["urdf", "--model", "finger7"], "unknown model 'finger7'"),
    (["frobnicate"], "invalid choice"),
    (["estimate", "--seed", "-1"], "--seed: expected an integer from 0 to 9223372036854775807, got -1"),
    (["observability", "--points", "0"], "--points: expected an integer from 1 to 10000, got 0"),
    (["report", "--points", "x"], "--points: expected an integer from 1 to 10000, got 'x'"),
    (["dynamics", "--spec", "/nonexistent.toml"], "--spec: applies to a URDF --model"),
    (["dynamics", "--model", "/nonexistent.urdf", "--friction"], "--friction: applies to the Alpes models"),
    (["dynamics", "--tau-m=0.1,0.2"], "--tau-m: model 'finger3' has 1 motors (finger), got 2 values"),
    (["observability", "--max-operations", "0"], "--max-operations: expected an integer >= 1, got 0"),
    (["observability", "--output", "encoder+"], "expected output names joined by '+'"),
    (["linearize", "--u=1,2"], "--u: input 'joint' of model 'finger3' has 3 entries"),
    (["linearize", "--model", "finger2", "--spec", "x.toml"], "--spec: applies to a URDF --model"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, needle):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and needle in err
    assert "Traceback" not in err


def test_console_script_help_shows_negative_vectors():
    exe = Path(sys.executable).with_name("alpes-dyn")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "alpes_dyn.cli"]
    r = subprocess.run(cmd + ["dynamics", "--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0 and "--q=-0.1,0.2,0.3" in r.stdout
    r = subprocess.run(cmd + ["dynamics", "--q", "-0.1,0.2"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 2 and "Traceback" not in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_help_description_is_the_package_docstring(capsys):
    """``alpes-dyn --help`` opens with the first line of the ``alpes_dyn.cli`` package's docstring."""
    import alpes_dyn.cli as cli
    from alpes_dyn.cli import parser

    assert parser.DESCRIPTION == cli.__doc__.splitlines()[0]
    with pytest.raises(SystemExit):
        main(["--help"])
    assert " ".join(capsys.readouterr().out.split()).count(" ".join(parser.DESCRIPTION.split())) == 1


def test_estimate_help_lists_every_observer(capsys):
    from alpes_dyn.estimation.observers.observers import OBSERVERS

    with pytest.raises(SystemExit) as e:
        main(["estimate", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert e.value.code == 0
    for name in OBSERVERS:
        assert name in out


def test_dynamics_text_labels_rows_and_columns(capsys):
    """Every printed row and column carries its joint (or axis) name, and the numbers are the library's."""
    code, out, _ = run(capsys, "dynamics", "--model", "hand", "--q=" + ",".join(["0.1"] * 15))
    assert code == 0
    m = ad.Model.alpes("hand")
    lines = out.splitlines()
    a = lines.index("A(q) [kg m^2]:")
    header = lines[a + 1].split()
    assert tuple(header) == m.joint_names
    row = lines[a + 1 + 1 + m.joint_index("thumb_abd")].split()
    assert row[0] == "thumb_abd"
    A = m.inertia_matrix(np.full(15, 0.1))
    assert np.allclose([float(x) for x in row[1:]], A[m.joint_index("thumb_abd")], rtol=1e-6, atol=0)
    j = lines.index("J(q) fingertip index_tip, linear, base axes [m]:")
    assert [ln.split()[0] for ln in lines[j + 2: j + 5]] == ["x", "y", "z"]


def test_dynamics_flags_q_outside_limits(capsys):
    code, out, _ = run(capsys, "dynamics", "--q=-0.1,0.2,1.7", "--json")
    assert code == 0 and json.loads(out)["outside_limits"] == ["j1", "j3"]
    code, out, _ = run(capsys, "dynamics", "--q=0.1,0.2,0.3")
    assert code == 0 and "outside the joint limits" not in out
    code, out, _ = run(capsys, "dynamics", "--q=0.1,0.2,1.7")
    assert "WARNING: q outside the joint limits at j3" in out
