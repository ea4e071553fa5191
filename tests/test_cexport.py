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
from alpes_dyn.estimation.cexport import cexport
from alpes_dyn.estimation.cexport.cexport import c_sources, main_input, read_main_output, scenario_filter, write_c_observer

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")


def _build(d, prefix="alpes_ekf", opt="-O0"):
    """The exported observer and its main.c, built (-O0 by default: the quickest build; the same numbers to the
    bit, IEEE arithmetic without -ffast-math at any level; what these tests check is the numbers, not the speed)."""
    exe = d / f"{prefix}_main"
    subprocess.run([CC, opt, "-std=c99", "-Wall", "-o", str(exe), str(d / "main.c"), str(d / f"{prefix}.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=300)
    return exe


@needs_cc
def test_c_export_equals_the_python_filter_on_the_scenario(tmp_path):
    from alpes_dyn.estimation.observers.scenario import run_estimation

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
    assert cli.main(["codegen", "--model", "finger2", "--out-dir", str(tmp_path / "c"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["files"] == ["alpes_ekf.c", "alpes_ekf.h", "main.c"] and obj["nz"] == 4
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == obj["files"]
    (tmp_path / "empty").mkdir()  # an empty directory is filled
    assert cli.main(["codegen", "--model", "finger2", "--out-dir", str(tmp_path / "empty")]) == 0
    assert len(list((tmp_path / "empty").iterdir())) == 3

    def broken(*a, **k):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(fileio, "_write_file", broken)  # the directory writer (fileio.write_directory) fails
    capsys.readouterr()
    assert cli.main(["codegen", "--model", "finger2", "--out-dir", str(tmp_path / "d")]) == 2
    assert "--out-dir: cannot write" in capsys.readouterr().err
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
    assert cli.main(["codegen", "--model", "finger3", "--controller", "sensor", "--out-dir", str(tmp_path / "c"),
                     "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["files"] == ["alpes_ekf.c", "alpes_ekf.h", "alpes_force.c", "alpes_force.h", "force_main.c", "main.c"]
    h = (tmp_path / "c" / "alpes_force.h").read_text()
    assert "int alpes_force_update(alpes_force_state* s, double F_ref, double F_fb" in h and "kp 0.008" in h


def _run_main(exe, text, tmp_path, nz):
    (tmp_path / "in.txt").write_text(text)
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    return read_main_output(out, nz)


@needs_cc
def test_c_export_of_the_hand_equals_the_filter_bit_for_bit(tmp_path):
    """The hand (30 states, 6 encoders): the exported C -- CasADi's code of the model, the covariance arithmetic as
    loops over the Jacobians' nonzeros, skipping P's zeros -- gives run()'s estimates and covariances to the last
    bit, from a diagonal prior (P stays block-diagonal by chain: the zeros are skipped) and from a full one (none
    are). Built at -O0 (seconds for its 1 MB source; x86-64's SSE arithmetic is the same at any level, and
    -std=c99 contracts no multiply-add)."""
    import alpes_dyn as ad
    from alpes_dyn.estimation.observers.observers import make_observer
    from alpes_dyn.symbolic.statespace import StateSpace

    m = ad.Model.alpes("hand")
    n, p = m.n, m.transmission.n_motors
    filt = make_observer("ekf", StateSpace(m, input="motor", output="encoder"), 1e-3,
                         process_noise=[1e-18] * n + [4e-8] * n, measurement_noise=[1.96e-7] * p,
                         input_noise=[2.5e-7] * p)
    assert filt.exact_loops and (filt.nz, filt.ny) == (30, 6)
    files = write_c_observer(filt, tmp_path / "c")
    src = files["alpes_ekf.c"].read_text()
    assert "alpes_ekf_cs_model" in src and "alpes_ekf_cs_step" not in src  # the loops, not the whole step
    exe = tmp_path / "c" / "main"
    subprocess.run([CC, "-O0", "-std=c99", "-Wall", "-o", str(exe), str(files["main.c"]), str(files["alpes_ekf.c"]),
                    "-lm"], check=True, capture_output=True, text=True, timeout=300)
    rng = np.random.default_rng(3)
    N = 300
    W = 0.02 + 1e-3 * rng.standard_normal((N, p))
    Y = np.full(n, 0.3) @ m.transmission.S.T + 1e-3 * rng.standard_normal((N + 1, p))
    z0 = np.r_[np.full(n, 0.3), np.zeros(n)]
    B = rng.standard_normal((2 * n, 2 * n))
    P_full = np.diag([0.05**2] * n + [0.1**2] * n) + 1e-4 * (B @ B.T)
    for P0 in (np.diag([0.05**2] * n + [0.1**2] * n), 0.5 * (P_full + P_full.T)):
        est = filt.run(z0, P0, W, Y)
        Z, P = _run_main(exe, main_input(z0, P0, Y[0], W, Y[1:]), tmp_path, filt.nz)
        assert np.abs(est.z[1:, :n] @ m.transmission.S.T - Y[1:]).max() < 0.05  # it follows the encoders (rad)
        assert np.array_equal(Z, est.z) and np.array_equal(P, est.P)


@pytest.fixture(scope="module")
def scenario_03():
    """The estimation scenario's 0.3 s record of finger3 (simulated and filtered once for the three codes below)."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    return run_estimation("ekf", duration=0.3)


@needs_cc
@pytest.mark.parametrize("observer, code", [("ekf-params", "sparse"), ("ekf", "sparse"), ("ukf", None)])
def test_c_export_of_each_code_equals_the_filter(observer, code, tmp_path, scenario_03):
    """finger3: the EKF's loops (its default is CasADi's code of the whole step, tested above), with its gains as
    states too (constant rows in its Jacobian), and the UKF (only CasADi's code): each equal to the filter's run()
    on the scenario's record, bit for bit."""
    res = scenario_03
    filt, z0, P0 = scenario_filter(observer, "finger3")
    d = write_c_observer(filt, tmp_path / "c", code=code, prefix="obs")["main.c"].parent
    assert ("obs_cs_model" in (d / "obs.c").read_text()) == (code == "sparse")
    Z, P = _run_main(_build(d, "obs"), main_input(z0, P0, res.y[0], res.u_meas, res.y[1:]), tmp_path, filt.nz)
    est = filt.run(z0, P0, res.u_meas, res.y)
    assert Z.shape == (301, filt.nz) and np.array_equal(Z, est.z) and np.array_equal(P, est.P)


def test_folded_products_are_counted_and_refused_for_the_loops(monkeypatch):
    """CasADi folds a constant times (a constant times x) into one product, which rounds differently from the C's
    two: the filter counts such products in its arithmetic, and c_sources refuses the loops where there are some
    (by default it exports CasADi's code of the whole step there)."""
    import casadi as cs

    from alpes_dyn.estimation.observers.covariance import _count_folds

    x = cs.SX.sym("x")
    folds: list[int] = []
    X, Y = cs.SX(cs.DM([[0.1]])), cs.vertcat(3.0 * x).T
    assert str(cs.mtimes(X, Y)) == str(cs.SX(0.1 * 3.0) * x)  # one product where the C makes two
    _count_folds(X, Y, folds)
    assert folds == [1]
    _count_folds(cs.vertcat(x).T, cs.vertcat(3.0 * x).T, folds)
    _count_folds(cs.SX(cs.DM([[2.0]])), cs.vertcat(x * x).T, folds)
    assert folds == [1]  # a product of two expressions is kept
    filt, _, _ = scenario_filter("ekf", "finger2")
    assert "alpes_ekf_cs_step" in c_sources(filt)["alpes_ekf.c"]  # a small covariance: the whole step
    monkeypatch.setattr(cexport, "_LOOPS_FROM", 0)
    assert filt.exact_loops and "alpes_ekf_cs_model" in c_sources(filt)["alpes_ekf.c"]
    filt.exact_loops = False  # as on a model where CasADi folded some
    assert "alpes_ekf_cs_step" in c_sources(filt)["alpes_ekf.c"]
    with pytest.raises(InputError, match="code: 'sparse' would round differently"):
        c_sources(filt, code="sparse")


# ---- a URDF + spec robot (issue 17): finger_edu of example-robot-data with its shipped spec
def _finger_edu():
    import alpes_dyn as ad
    from alpes_dyn.model.spec import example_spec_path

    return str(ad.example_robot_urdf("finger_edu")), str(example_spec_path("finger_edu"))


@needs_cc
def test_c_export_of_a_urdf_robot_equals_estimate_on_its_recording(tmp_path, capsys):
    """``codegen --model finger_edu.urdf --spec ...``'s observer, compiled, gives what ``estimate --data`` gives on a
    recording of the robot (the Python path: estimate_recording) with the same noise settings, step for step."""
    from alpes_dyn import Model
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment
    from alpes_dyn.estimation.observers.replay import estimate_recording, recording_filter

    import re

    urdf, shipped = _finger_edu()
    spec = tmp_path / "smooth.toml"  # its spec without friction: one RK4 step per sample, C that builds in seconds
    spec.write_text(re.sub(r"\[(coulomb|viscous)\][^\[]*", "", open(shipped).read()))
    assert cli.main(["codegen", "--model", urdf, "--spec", str(spec), "--out-dir", str(tmp_path / "c"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["nz"] == 6 and obj["nw"] == 1 and obj["ny"] == 1 and obj["controller"] is None
    model = Model.from_urdf_file(urdf, str(spec))
    assert not model.extras.coulomb.any() and not model.extras.viscous.any()
    rec = model_experiment(model, design=ExperimentDesign(duration=0.5), seed=3)
    est = estimate_recording(rec, model, torque_noise=5e-4, encoder_noise_counts=0.5)
    _, z0, P0 = recording_filter(model, "ekf", rec.dt, torque_noise=5e-4, encoder_noise_counts=0.5, u0=rec.torque[0])
    step = 2 * np.pi / model.transmission.counts_per_rev
    Y = rec.encoder * step  # finger_edu's tendon is rigid: the reading is q_m itself
    exe = _build(tmp_path / "c", opt="-O0")  # half a megabyte of C: -O2 takes 15 s of processor time
    Z, P = _run_main(exe, main_input(z0, P0, Y[0], rec.torque[:-1], Y[1:]), tmp_path, 6)
    assert Z.shape == est.estimate.z.shape == (rec.n_samples, 6)
    assert np.abs(Z - est.estimate.z).max() <= 1e-12
    assert np.abs(P - est.estimate.P).max() <= 1e-12
    # the driven joints followed (a real estimate, not a constant): 0.27-0.36 degree over these 0.5 s, most of it the
    # transient from the rest state, where they swing 21-26 degrees (0.005-0.01 degree over 2 s)
    assert np.degrees(est.rmse[1:]).max() < 0.5


@needs_cc
def test_force_controller_c_export_of_a_urdf_robot_equals_python(tmp_path, capsys):
    """The controller of ``control --model finger_edu.urdf`` (its motor flexor, its frame finger_tip_link, the block
    placed from its kinematics), exported and compiled, commands what ForceController.update commands."""
    from alpes_dyn import Model
    from alpes_dyn.control.cexport import force_main_input, read_force_output, robot_controller
    from alpes_dyn.control.controller import static_contact_force

    urdf, spec = _finger_edu()
    assert cli.main(["codegen", "--model", urdf, "--spec", spec, "--controller", "sensorless", "--out-dir",
                     str(tmp_path / "c"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert (obj["motor"], obj["frame"]) == ("flexor", "finger_tip_link")
    d = tmp_path / "c"
    exe = d / "fm"
    subprocess.run([CC, "-O2", "-std=c99", "-Wall", "-Werror", "-Wno-unused-parameter", "-o", str(exe),
                    str(d / "force_main.c"), str(d / "alpes_force.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=120)
    ctl = robot_controller("sensorless", Model.from_urdf_file(urdf, spec))
    from alpes_dyn.model.block_scene import place_block

    q_c = place_block(Model.from_urdf_file(urdf, spec)).contact_q
    F_ref, F_fb, _ = _force_inputs(3)
    q = q_c + 0.01 * np.random.default_rng(1).standard_normal((len(F_ref), 3))
    (tmp_path / "in.txt").write_text(force_main_input(F_ref, F_fb, q))
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    tau_c, Fz_c = read_force_output(out)
    tau = np.array([ctl.update(float(F_ref[k]), float(F_fb[k]), q[k]) for k in range(len(F_ref))])
    assert tau.max() > 0.1 * ctl.tau_max  # it pressed: the feedforward and the PI at work
    assert np.abs(tau_c - tau).max() <= 1e-12
    Fz = [static_contact_force(ctl.model, q[k], np.array([tau[k]]), ctl.normal, ctl.tip) for k in range(0, 1000, 50)]
    assert np.abs(Fz_c[::50] - np.array(Fz)).max() <= 1e-12  # N: Pinocchio's G and J against CasADi's


_OTHER_MAIN = r"""#include <stdio.h>
#include "alpes_ekf.h"
%(numbers)s
static const double W[%(n)d] = {%(W)s};
static const double Y[%(n1)d] = {%(Y)s};
int main(void) {
  double z[ALPES_EKF_NZ] = {%(z0)s}, P[ALPES_EKF_NZ * ALPES_EKF_NZ] = {%(P0)s}, work[ALPES_EKF_NWORK];
  int k, i;
  if (alpes_ekf_update(z, P, Y, z, P, work)) return 1;
  for (k = 0; k < %(n)d; ++k) {
    if (alpes_ekf_step_p(z, P, W + k, Y + k + 1, xq_model_p, z, P, work)) return 1;
    for (i = 0; i < ALPES_EKF_NZ; ++i) printf("%%.17g ", z[i]);
    printf("\n");
  }
  return 0;
}
"""


@needs_cc
def test_c_export_takes_the_model_numbers_as_an_input(tmp_path):
    """finger3 and a finger3 of other masses, springs and friction: their exported C differ only in the array of the
    model's numbers, and the nominal's code given the other's array (its one line) (alpes_ekf_step_p) gives the other filter's
    run() bit for bit (the numbers reach the code; the code is the structure's)."""
    from alpes_dyn.estimation.experiments.experiment import perturbed_params
    from alpes_dyn.estimation.observers.scenario import run_estimation
    from alpes_dyn.model.params import write_params

    res = run_estimation("ekf", duration=0.2)
    toml = write_params(perturbed_params(spread=0.2, seed=7), tmp_path / "other.toml")
    nominal, z0, P0 = scenario_filter("ekf", "finger3")
    other, _, _ = scenario_filter("ekf", "finger3", params=toml)
    a = c_sources(nominal, code="sparse")["alpes_ekf.c"]
    b = c_sources(other, code="sparse", prefix="xq")["xq.c"]

    def without_numbers(src: str) -> str:
        lines = [ln for ln in src.splitlines() if not ln.startswith("const double alpes_ekf_model_p[")]
        assert len(lines) == src.count("\n") - 1  # one line of numbers
        return "\n".join(lines)

    assert without_numbers(a) == without_numbers(b.replace("xq", "alpes_ekf").replace("XQ", "ALPES_EKF"))
    assert a != b.replace("xq", "alpes_ekf").replace("XQ", "ALPES_EKF")
    assert np.any(nominal.model.values != other.model.values)
    d = write_c_observer(nominal, tmp_path / "c", code="sparse")["main.c"].parent
    numbers = next(ln for ln in b.splitlines() if ln.startswith("const double xq_model_p["))
    (d / "run.c").write_text(_OTHER_MAIN % dict(numbers=numbers.replace("XQ_NP", "ALPES_EKF_NP"),
        n=len(res.u_meas), n1=len(res.y), W=", ".join(repr(float(x)) for x in res.u_meas.ravel()),
        Y=", ".join(repr(float(x)) for x in res.y.ravel()), z0=", ".join(repr(float(x)) for x in z0),
        P0=", ".join(repr(float(x)) for x in np.diag(P0).ravel(order="F"))))
    exe = d / "run"
    subprocess.run([CC, "-O0", "-std=c99", "-Wall", "-o", str(exe), str(d / "run.c"), str(d / "alpes_ekf.c"), "-lm"],
                   check=True, capture_output=True, text=True, timeout=300)
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    Z = np.array([[float(x) for x in ln.split()] for ln in out.splitlines()])
    np.testing.assert_array_equal(Z, other.run(z0, P0, res.u_meas, res.y).z[1:])
    assert np.abs(Z - nominal.run(z0, P0, res.u_meas, res.y).z[1:]).max() > 1e-9
