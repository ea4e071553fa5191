"""The standalone C export of the observer's step (issue 20): the exported C, compiled with the system compiler,
gives the Python path's numbers on the estimation scenario (1000 steps of finger3), and ``alpes-dyn codegen``
writes a whole directory or nothing."""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

from alpes_dyn import cli, fileio
from alpes_dyn.errors import InputError
from alpes_dyn.estimation import cexport
from alpes_dyn.estimation.cexport import c_sources, main_input, read_main_output, scenario_filter, write_c_observer

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")


def _build(d, prefix="alpes_ekf"):
    exe = d / f"{prefix}_main"
    subprocess.run([CC, "-O2", "-std=c99", "-Wall", "-o", str(exe), str(d / "main.c"), str(d / f"{prefix}.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=300)
    return exe


@needs_cc
def test_c_export_equals_the_python_filter_on_the_scenario(tmp_path):
    from alpes_dyn.estimation.scenario import run_estimation

    res = run_estimation("ekf", duration=1.0)  # 1000 steps of finger3, the Python path (CasADi's VM)
    filt, z0, P0 = scenario_filter("ekf", "finger3")
    d = write_c_observer(filt, tmp_path / "ekf", z0=z0, P0=P0)["main.c"].parent
    exe = _build(d)
    (tmp_path / "in.txt").write_text(main_input(z0, P0, res.y[0], res.u_meas, res.y[1:]))
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    Z, P = read_main_output(out, filt.nz)
    assert Z.shape == res.estimate.z.shape == (1001, 6)
    assert np.abs(Z - res.estimate.z).max() <= 1e-12
    assert np.abs(P - res.estimate.P).max() <= 1e-12
    timed = subprocess.run([str(exe), "-t", "2", str(tmp_path / "in.txt")], check=True, capture_output=True,
                           text=True).stdout
    assert timed.startswith("1000 steps x 2: ") and "us per step" in timed


def test_header_documents_the_api():
    filt, z0, P0 = scenario_filter("ekf-params", "finger2")
    files = c_sources(filt, z0=z0, P0=P0, about="finger2 for the test")
    assert sorted(files) == ["alpes_ekf.c", "alpes_ekf.h", "main.c"]
    h = files["alpes_ekf.h"]
    for text in ("#define ALPES_EKF_NZ 6", "#define ALPES_EKF_NW 1", "#define ALPES_EKF_NY 1", "ALPES_EKF_NWORK",
                 "int alpes_ekf_step(const double z[ALPES_EKF_NZ]", "int alpes_ekf_update(", "column-major",
                 "input_gain, spring_gain", "finger2 for the test", "dt = 0.001 s"):
        assert text in h, text
    assert "malloc" not in files["alpes_ekf.c"] and "#include <math.h>" in files["alpes_ekf.c"]
    with pytest.raises(InputError, match="prefix: expected a C identifier"):
        c_sources(filt, prefix="no-dash")


def test_codegen_writes_a_whole_directory_or_nothing(tmp_path, capsys, monkeypatch):
    assert cli.main(["codegen", "--model", "finger2", "-o", str(tmp_path / "c"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["files"] == ["alpes_ekf.c", "alpes_ekf.h", "main.c"] and obj["nz"] == 4
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == obj["files"]
    (tmp_path / "empty").mkdir()  # an empty directory is filled
    assert cli.main(["codegen", "--model", "finger2", "-o", str(tmp_path / "empty")]) == 0
    assert len(list((tmp_path / "empty").iterdir())) == 3

    def broken(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(fileio, "_write_file", broken)  # the directory writer (fileio.write_directory) fails
    capsys.readouterr()
    assert cli.main(["codegen", "--model", "finger2", "-o", str(tmp_path / "d")]) == 2
    assert "-o: cannot write" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c", "empty"]  # no partial or temporary directory


def _force_inputs(n, N=1000, seed=0):
    """A force loop's inputs: the step reference, a fed-back force that rises after an approach, with noise, drops
    to zero for 40 ms (the contact lost) and comes back, and q_hat about the block's contact angles."""
    from alpes_dyn.model.mjcf import BLOCK_CONTACT_Q

    rng = np.random.default_rng(seed)
    t = 1e-3 * np.arange(N)
    F_ref = np.where(t < 0.4, 0.2, np.where(t < 0.7, 1.0, 0.5))
    F_fb, f = np.zeros(N), 0.0
    for k in range(N):
        if k > 150:
            f += 0.05 * (F_ref[k] - f)
        F_fb[k] = max(0.0, f + 0.01 * rng.standard_normal())
    F_fb[500:540] = 0.0
    q = np.array(BLOCK_CONTACT_Q[:n]) + 0.01 * rng.standard_normal((N, n))
    return F_ref, F_fb, q


@needs_cc
@pytest.mark.parametrize("kind", ["sensor", "sensorless", "pi"])
def test_force_controller_c_export_equals_python(kind, tmp_path):
    from alpes_dyn.control.cexport import block_controller, controller_c_sources, force_main_input, read_force_output
    from alpes_dyn.control.controller import static_contact_force

    files = controller_c_sources(block_controller(kind, "finger3"))
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    exe = tmp_path / "fm"
    subprocess.run([CC, "-O2", "-std=c99", "-Wall", "-Werror", "-Wno-unused-parameter", "-o", str(exe),
                    str(tmp_path / "force_main.c"), str(tmp_path / "alpes_force.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=120)
    ctl = block_controller(kind, "finger3")
    F_ref, F_fb, q = _force_inputs(ctl.model.n)
    (tmp_path / "in.txt").write_text(force_main_input(F_ref, F_fb, q))
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    tau_c, Fz_c = read_force_output(out)
    tau, contact = [], []
    for k in range(len(F_ref)):
        tau.append(ctl.update(float(F_ref[k]), float(F_fb[k]), q[k] if kind != "pi" else None))
        contact.append(ctl.in_contact)
    contact = np.array(contact, int)
    assert contact.sum() > 500 and list(np.diff(contact)).count(-1) == 1  # the approach, the contact, a loss
    assert np.abs(tau_c - np.array(tau)).max() <= 1e-12
    Fz = [static_contact_force(ctl.model, q[k], np.array([tau[k]]), ctl.normal) for k in range(0, 1000, 50)]
    assert np.abs(Fz_c[::50] - np.array(Fz)).max() <= 1e-12  # N: Pinocchio's G and J against CasADi's


def test_codegen_with_the_controller(tmp_path, capsys):
    assert cli.main(["codegen", "--model", "finger3", "--controller", "sensor", "-o", str(tmp_path / "c"),
                     "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["files"] == ["alpes_ekf.c", "alpes_ekf.h", "alpes_force.c", "alpes_force.h", "force_main.c", "main.c"]
    h = (tmp_path / "c" / "alpes_force.h").read_text()
    assert "int alpes_force_update(alpes_force_state* s, double F_ref, double F_fb" in h and "kp 0.008" in h
