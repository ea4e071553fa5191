"""``alpes-dyn import`` (an MJCF's URDF and spec for ``--model X.urdf --spec X.toml``), ``urdf --model FILE.xml``,
the ``--json`` of ``urdf`` and ``mjcf``, and their deprecated positional MODEL (issue 36)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf import mjcf_string  # noqa: E402

from test_mjcf_import import ARM  # noqa: E402  (the two-hinge arm with a spring, friction, a tendon and a motor)


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


@pytest.mark.parametrize("name", ["arm", "hand"])
def test_import_writes_a_pair_with_the_mjcf_dynamics(capsys, tmp_path, name):
    """The written URDF + spec, read back by ``dynamics --model X.urdf --spec X.toml``, give MuJoCo's own M(q) and
    bias C(q, v) v + gravity of the MJCF to 1e-12, and exactly what Model.from_mjcf gives."""
    xml = ARM if name == "arm" else mjcf_string("hand", friction=True, rotor_inertia=True)
    src = tmp_path / f"{name}.xml"
    src.write_text(xml)
    code, out, err = run(capsys, "import", "--model", str(src), "--out-dir", str(tmp_path / "out"), "--json")
    assert (code, err) == (0, "")
    obj = json.loads(out)
    urdf, spec = tmp_path / "out" / f"{name}.urdf", tmp_path / "out" / f"{name}.toml"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted([urdf.name, spec.name])
    assert (obj["urdf"], obj["spec"], obj["directory"]) == (str(urdf), str(spec), str(tmp_path / "out"))
    ref = ad.Model.from_mjcf(src)
    assert obj["joints"] == list(ref.joint_names) and obj["motors"] == list(ref.motor_names)
    assert src.read_text() == xml  # the input untouched
    mj = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(mj)
    rng = np.random.default_rng(11)
    for _ in range(2):
        q, v = ref.random_state(rng)
        tau = rng.normal(scale=0.01, size=ref.n)
        fmt = lambda x: ",".join(repr(float(a)) for a in x)  # noqa: E731
        code, out, err = run(capsys, "dynamics", "--model", str(urdf), "--spec", str(spec), f"--q={fmt(q)}",
                             f"--v={fmt(v)}", f"--tau={fmt(tau)}", "--json")
        assert code == 0, err
        r = json.loads(out)
        A, C, G, qdd = (np.array(r[k]) for k in ("A", "C", "G", "qdd"))
        np.testing.assert_array_equal(A, ref.inertia_matrix(q))  # the same Model, bit for bit
        np.testing.assert_array_equal(G, ref.gravity_torque(q))
        np.testing.assert_array_equal(qdd, ref.forward_dynamics(q, v, tau))
        d.qpos[:], d.qvel[:] = q, v
        mujoco.mj_forward(mj, d)
        M = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, d, M)
        np.testing.assert_allclose(A, M, rtol=0, atol=1e-12)
        # MuJoCo's bias is C v + gravity; the library's G holds the springs, MuJoCo's qfrc_spring is -K (q - q_ref)
        np.testing.assert_allclose(C @ v + G + d.qfrc_spring, d.qfrc_bias, rtol=0, atol=1e-12)
    # urdf --model FILE.xml prints the URDF the pair holds
    code, out, err = run(capsys, "urdf", "--model", str(src))
    assert (code, err) == (0, "") and out == urdf.read_text()


def test_import_text_names_the_flags_to_use(capsys, tmp_path):
    src = tmp_path / "arm.xml"
    src.write_text(ARM)
    code, out, err = run(capsys, "import", "--model", str(src), "--out-dir", str(tmp_path / "o"))
    assert (code, err) == (0, "")
    assert out.splitlines() == [f"arm: 2 joints, 1 motor (m), tips tip; written to {tmp_path / 'o'}/ (arm.urdf, "
                                "arm.toml)", f"  use: --model {tmp_path / 'o' / 'arm.urdf'} --spec "
                                f"{tmp_path / 'o' / 'arm.toml'}"]
    assert (tmp_path / "o" / "arm.toml").read_text().startswith("# the transmission spec of arm.xml (alpes-dyn "
                                                                "import)")


def test_import_writes_nothing_when_a_file_fails(capsys, tmp_path, monkeypatch):
    """No partial output: the second file failing (a full disk) leaves no directory, no temporary one."""
    import alpes_dyn.fileio as fileio

    src = tmp_path / "arm.xml"
    src.write_text(ARM)
    real = fileio._write_file

    def fail_on_spec(path: Path, text: str) -> None:
        if path.suffix == ".toml":
            raise OSError(28, "No space left on device")
        real(path, text)

    monkeypatch.setattr(fileio, "_write_file", fail_on_spec)
    code, out, err = run(capsys, "import", "--model", str(src), "--out-dir", str(tmp_path / "out"))
    assert code == 2 and out == "" and "--out-dir: cannot write" in err and "No space left on device" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.xml"]


@pytest.mark.parametrize("argv", [["urdf", "finger3"], ["urdf", "hand", "--params", "{params}"],
                                  ["mjcf", "finger3", "--scene", "block"], ["mjcf", "{urdf}", "--spec", "{spec}"]])
def test_positional_model_is_a_deprecated_alias(capsys, tmp_path, argv):
    """The positional MODEL of version 0.1 gives the output of --model MODEL, with one warning line naming
    --model; -o writes the same file."""
    from alpes_dyn.model.params import default_params_path

    urdf, spec = tmp_path / "robot.urdf", tmp_path / "robot.toml"
    urdf.write_text(ad.urdf_string("finger3"))
    spec.write_text('[[motor]]\nname = "flexor"\njoints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\n\n[stiffness]\nj1 = 0.04\n')
    paths = {"params": str(default_params_path()), "urdf": str(urdf), "spec": str(spec)}
    argv = [a.format(**paths) for a in argv]
    cmd, model, rest = argv[0], argv[1], argv[2:]
    code, new, err = run(capsys, cmd, "--model", model, *rest)
    assert (code, err) == (0, "")
    code, old, err = run(capsys, cmd, model, *rest)
    assert code == 0 and old == new
    assert err == (f"alpes-dyn: warning: DeprecationWarning: 'alpes-dyn {cmd} {model}': the positional model is "
                   f"deprecated, give --model {model}\n")
    assert run(capsys, cmd, model, *rest, "-o", str(tmp_path / "a"))[0] == 0
    assert run(capsys, cmd, "--model", model, *rest, "-o", str(tmp_path / "b"))[0] == 0
    assert (tmp_path / "a").read_text() == (tmp_path / "b").read_text() == new


def test_urdf_and_mjcf_default_model_is_finger3(capsys):
    assert run(capsys, "urdf")[1] == ad.urdf_string("finger3")
    assert run(capsys, "mjcf")[1] == mjcf_string("finger3")


@pytest.mark.parametrize("cmd, key, text", [("urdf", "urdf", lambda: ad.urdf_string("hand")),
                                            ("mjcf", "mjcf", lambda: mjcf_string("hand"))])
def test_urdf_and_mjcf_json(capsys, tmp_path, cmd, key, text):
    code, out, err = run(capsys, cmd, "--model", "hand", "--json")
    assert (code, err) == (0, "")
    assert json.loads(out) == {"model": "hand", "output": None, key: text()}
    dest = tmp_path / f"hand.{key}"
    code, out, err = run(capsys, cmd, "--model", "hand", "--json", "-o", str(dest))
    assert (code, err) == (0, "")
    assert json.loads(out) == {"model": "hand", "output": str(dest), key: None}
    assert dest.read_text() == text()
