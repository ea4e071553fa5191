"""The command line made consistent (issue 52, item 5): ``--out-dir DIR`` for the commands that write a directory
(``codegen``, ``import``; ``-o DIR`` their deprecated alias for one release, ``-o`` a file everywhere else), and the
observer's friction read from the parameter file that ``identify`` wrote (``--friction`` / ``--no-friction``
override it, one warning line where they contradict it)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from alpes_dyn.cli import main
from alpes_dyn.model.params import default_params_path, load_params
from alpes_dyn.model.trust import fitted_friction

SHIPPED = default_params_path().read_text(encoding="utf-8")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _file(tmp_path, name: str, record: str) -> str:
    path = tmp_path / name
    path.write_text(SHIPPED + f"\n[identification.{record}]\n", encoding="utf-8")
    return str(path)


@pytest.fixture
def friction_files(tmp_path):
    """A file whose fit had friction, one whose fit had none (the shipped values, only the record differs)."""
    return {"yes": _file(tmp_path, "f.toml", "finger]\nfriction = true\n#"),
            "no": _file(tmp_path, "nf.toml", "finger]\nfriction = false\n#")}


def _codegen(capsys, tmp_path, name, *argv):
    code, out, err = run(capsys, "codegen", "--model", "finger3", "--out-dir", str(tmp_path / name), "--json", *argv)
    assert code == 0, err
    return json.loads(out), err, {p.name: p.read_text() for p in (tmp_path / name).iterdir()}


def test_codegen_o_is_a_deprecated_alias_of_out_dir(capsys, tmp_path):
    """``-o DIR`` writes the same files as ``--out-dir DIR``, with one DeprecationWarning line naming --out-dir;
    ``--out-dir`` warns nothing."""
    new, err, files = _codegen(capsys, tmp_path, "new")
    assert err == "" and new["directory"] == str(tmp_path / "new")
    code, out, err = run(capsys, "codegen", "--model", "finger3", "-o", str(tmp_path / "old"), "--json")
    assert code == 0
    assert err == (f"alpes-dyn: warning: DeprecationWarning: 'alpes-dyn codegen -o {tmp_path / 'old'}': -o for a "
                   f"directory is deprecated (-o names a file in every other command), give --out-dir "
                   f"{tmp_path / 'old'}\n")
    assert json.loads(out)["directory"] == str(tmp_path / "old")
    assert {p.name: p.read_text() for p in (tmp_path / "old").iterdir()} == files


def test_import_o_is_a_deprecated_alias_of_out_dir(capsys, tmp_path):
    pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf import mjcf_string

    src = tmp_path / "arm.xml"
    src.write_text(mjcf_string("finger2"))
    code, _, err = run(capsys, "import", "--model", str(src), "--out-dir", str(tmp_path / "new"))
    assert (code, err) == (0, "")
    code, _, err = run(capsys, "import", "--model", str(src), "-o", str(tmp_path / "old"))
    assert code == 0 and err.count("\n") == 1 and "give --out-dir" in err and "DeprecationWarning" in err
    for name in ("arm.urdf", "arm.toml"):
        assert (tmp_path / "old" / name).read_text() == (tmp_path / "new" / name).read_text()


def test_fitted_friction_reads_the_record(friction_files):
    """The record's ``friction`` for the chain; a finger of the hand falls back to the shared ``finger`` record;
    None where no record says (the shipped file)."""
    yes, no = load_params(friction_files["yes"]), load_params(friction_files["no"])
    assert [fitted_friction(yes, c) for c in ("finger", "index", "thumb")] == [True, True, None]
    assert fitted_friction(no, "middle") is False
    assert fitted_friction(load_params(), "finger") is None


def test_codegen_takes_the_friction_the_file_says(capsys, tmp_path, friction_files):
    """The C written from a file whose fit had friction, without --friction, is the C of --friction on the shipped
    values (the same text but for the file's name in the header comment); from a file whose fit had none, or the
    shipped file, the C without friction. --friction / --no-friction override the file, one warning line where
    they contradict it, none where they agree."""
    ref_on, _, c_on = _codegen(capsys, tmp_path, "ref_on", "--friction")
    ref_off, _, c_off = _codegen(capsys, tmp_path, "ref_off")
    assert (ref_on["friction"], ref_off["friction"]) == (True, False) and c_on["alpes_ekf.c"] != c_off["alpes_ekf.c"]

    def body(files):  # the step's code, the header comment (which names the file) cut
        return files["alpes_ekf.c"].split("*/", 1)[1]

    for name, path, want, flag, warns in [("a", friction_files["yes"], True, (), False),
                                          ("b", friction_files["no"], False, (), False),
                                          ("c", friction_files["yes"], False, ("--no-friction",), True),
                                          ("d", friction_files["no"], True, ("--friction",), True),
                                          ("e", friction_files["yes"], True, ("--friction",), False)]:
        obj, err, files = _codegen(capsys, tmp_path, name, "--params", path, *flag)
        assert obj["friction"] is want, name
        assert body(files) == body(c_on if want else c_off), name
        if warns:
            assert err.count("\n") == 1 and f"{flag[0]} overrides --params {path}, whose fit had" in err, err
        else:
            assert err == "", err


def test_the_scenario_takes_the_observer_file_s_friction(capsys, friction_files):
    """``estimate`` (the simulated scenario) with ``--observer-params`` a file whose fit had friction: the run of
    ``--friction`` (the same joints' RMSE to 1e-12), not the frictionless one."""
    def rmse(*argv):
        code, out, err = run(capsys, "estimate", "--duration", "0.3", "--json", *argv)
        assert code == 0, err
        return np.asarray(json.loads(out)["rmse_deg"])

    from_file = rmse("--observer-params", friction_files["yes"])
    np.testing.assert_allclose(from_file, rmse("--observer-params", friction_files["yes"], "--friction"), rtol=1e-12)
    assert not np.allclose(from_file, rmse("--observer-params", friction_files["yes"], "--no-friction"), rtol=1e-6)
