"""The whole force step in C (alpes_dyn.control.cstep) against the Python ForceStep: the readings a run on the MuJoCo
stand-in recorded, replayed through the compiled test program; the normal given at run time.

Tolerances: the commands (N m) to 1e-9 absolute (they are about 0.03 N m), the joint estimates (rad, rad/s) to 1e-9
absolute, the forces fed back (N) to 1e-9 absolute. The C code is the Python step's operation for operation but for
the static balance (CasADi's G and J against Pinocchio's) and the EKF's substeps (a loop over one RK4 step, the
chain rule for its Jacobian): rounding only, which the friction EKF's predict with its stable substeps keeps at
1e-13 rad over a second of contact.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

from alpes_dyn import cli
from alpes_dyn.errors import InputError, ModelError

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")
TOL = 1e-9


def _build(step, d):
    """The test program of ``step``'s C in ``d`` (-O0: the same numbers as -O2, -std=c99, the quickest build)."""
    from alpes_dyn.control.cstep import write_c_step

    files = write_c_step(step, d)
    sources = [str(d / n) for n in sorted(files) if n.endswith(".c")]
    exe = d / "alpes_step_main"
    subprocess.run([CC, "-O0", "-std=c99", "-Wall", "-Werror", "-Wno-unused-parameter", "-Wno-unused-function",
                    "-Wno-unused-variable", "-Wno-unused-but-set-variable", "-o", str(exe), *sources, "-lm"],
                   check=True, capture_output=True, text=True, timeout=300)
    return exe


def _run(exe, step, run, normal, tmp):
    from alpes_dyn.control.cstep import read_step_output, step_main_input

    (tmp / "in.txt").write_text(step_main_input(run.counts, run.torque, run.force, run.F_ref, normal))
    out = subprocess.run([str(exe), str(tmp / "in.txt")], check=True, capture_output=True, text=True).stdout
    return read_step_output(out, step.m, 2 * step.n)


def _replay(step, run):
    """Python's step over the recorded readings: (commands (N, m), [q_hat; qd_hat] (N, 2n), F_fb (N,))."""
    step.reset()
    U, Z, F = [], [], []
    for k in range(len(run.t)):
        U.append(step.step(run.counts[k], run.torque[k], run.force[k], float(run.F_ref[k])))
        Z.append(step.state)
        F.append(step.force_estimate)
    return np.array(U), np.array(Z), np.array(F)


@pytest.fixture(scope="module")
def sensor(tmp_path_factory):
    """finger3's sensor step (its observer with the file's friction), built, and a run on the stand-in's block."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.control.bench_loop import run_on_bench
    from alpes_dyn.control.step import ForceStep

    from alpes_dyn.control.realism_loop import Compensation

    # a calibrated force_scale: the EKF's force input the sensor's reading times it, in Python and in C alike
    step = ForceStep("finger3", controller="sensor", compiled=False, compensation=Compensation(force_scale=1.05))
    assert step.design.observer_model is not None  # the EKF runs the file's friction
    exe = _build(step, tmp_path_factory.mktemp("sensor"))
    run = run_on_bench(MujocoHand("finger3", scene="block", seed=9691), step, 0.4, 1.0)
    return step, exe, run


@needs_cc
def test_c_step_equals_the_python_step_on_the_stand_in(sensor, tmp_path):
    step, exe, run = sensor
    U, Z, F = _run(exe, step, run, step.design.normal, tmp_path)
    assert run.force.max() > 0.3 and run.command.max() > 0.02  # the finger pressed the block
    np.testing.assert_allclose(U, run.command, rtol=0, atol=TOL)
    np.testing.assert_allclose(Z[:, :step.n], run.q_hat, rtol=0, atol=TOL)
    np.testing.assert_allclose(F, run.F_fb, rtol=0, atol=TOL)


@needs_cc
def test_c_step_timed_per_step(sensor, tmp_path):
    """``main -t 3``: the record three times, each step timed on its own; its last command the free run's (each
    pass from the first sample), each step's minimum over the passes (mean over the steps) at most its median and
    at most the passes' wall clock per step (a step's minimum is at most its mean; the steps' sum at most the
    passes' whole time)."""
    import re

    step, exe, run = sensor
    U, _, _ = _run(exe, step, run, step.design.normal, tmp_path)
    out = subprocess.run([str(exe), "-t", "3", str(tmp_path / "in.txt")], check=True, capture_output=True,
                         text=True).stdout
    m = re.fullmatch(r"(\d+) steps x 3: (\S+) us per step, (\S+) us of processor time \(command\[0\] = (\S+)\); "
                     r"each step's minimum over the passes (\S+) us, its median (\S+) us \(means over the steps\)\n",
                     out)
    assert m, out
    n, wall, cpu, u0, lo, med = (float(x) for x in m.groups())
    assert n == len(run.t) and u0 == pytest.approx(U[-1, 0], abs=1e-15)
    assert 0 < lo <= med * (1 + 1e-9) and lo <= wall * (1 + 1e-9) and cpu > 0


@needs_cc
def test_c_step_takes_the_normal_at_run_time(sensor, tmp_path):
    """Two other normals (one not of unit length) given to the same build: Python's ForceStep built with each."""
    from alpes_dyn.control.step import ForceStep

    step, exe, run = sensor
    results = []
    for normal in ([-0.9, 0.0, -0.3], [-2.0, 0.5, -1.0]):
        py = ForceStep("finger3", controller="sensor", compiled=False, normal=normal, compensation=step.compensation)
        U, Z, F = _replay(py, run)
        Uc, Zc, Fc = _run(exe, step, run, normal, tmp_path)
        np.testing.assert_allclose(Uc, U, rtol=0, atol=TOL)
        np.testing.assert_allclose(Zc[:, :py.n], Z[:, :py.n], rtol=0, atol=TOL)
        # rad/s: the EKF's velocities take the smooth law's model error as process noise, and its large gain on them
        # carries the build's last bits (a normal folded in or read at run time) to 1e-8
        np.testing.assert_allclose(Zc[:, py.n:], Z[:, py.n:], rtol=0, atol=1e-7)
        results.append(U)
    assert np.abs(results[0] - results[1]).max() > 2e-4  # N m: the normal changes the commands (2 % here)


def _states(step, run):
    """The Python step's state before each tick of a replay of ``run`` (cstep.step_state_row, (N, S))."""
    from alpes_dyn.control.cstep import step_state_row

    step.reset()
    S = []
    for k in range(len(run.t)):
        S.append(step_state_row(step))
        step.step(run.counts[k], run.torque[k], run.force[k], float(run.F_ref[k]))
    return np.array(S)


def _run_from(exe, step, run, states, tmp):
    """``main -s``: each tick one C step from the state given on its line."""
    from alpes_dyn.control.cstep import read_step_output, step_main_input

    (tmp / "in_s.txt").write_text(step_main_input(run.counts, run.torque, run.force, run.F_ref, step.design.normal,
                                                  states=states))
    out = subprocess.run([str(exe), "-s", str(tmp / "in_s.txt")], check=True, capture_output=True, text=True).stdout
    return read_step_output(out, step.m, 2 * step.n)


@needs_cc
def test_c_step_one_step_from_the_python_state(sensor, tmp_path):
    """``main -s``: at each tick the C step from the Python step's state before it (the benchmarks' agreement rule,
    c_step.py's docstring) gives the Python step's command, estimate (rad, rad/s) and force fed back to 1e-12: one
    step's rounding (the Python EKF in CasADi's VM, the C its loop over one substep); the state is read: every tick
    from the first tick's state (the rest) gives other estimates and commands once the finger moved."""
    step, exe, run = sensor
    S = _states(step, run)
    U, Z, F = _replay(step, run)
    Uc, Zc, Fc = _run_from(exe, step, run, S, tmp_path)
    np.testing.assert_allclose(Uc, U, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Zc, Z, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Fc, F, rtol=0, atol=1e-12)
    Ur, Zr, _ = _run_from(exe, step, run, np.broadcast_to(S[0], S.shape), tmp_path)
    assert np.abs(Zr[-100:, :step.n] - Z[-100:, :step.n]).min() > 0.05  # rad: from the rest, not the pressed finger
    assert np.abs(Ur[-100:] - U[-100:]).max() > 1e-3  # N m


@needs_cc
@pytest.mark.parametrize("kind", ["sensorless", "pi"])
def test_c_step_of_the_other_controllers(kind, sensor, tmp_path):
    """The sensorless step (its estimate of the force, its own gains; calibrated: the estimate divided by the
    force_scale, the EKF's input the estimate before it) and the pi baseline (no observer) on finger2, each over the
    readings of its own run on the stand-in."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.control.bench_loop import run_on_bench
    from alpes_dyn.control.realism_loop import Compensation
    from alpes_dyn.control.step import ForceStep

    step = ForceStep("finger2", controller=kind, compiled=False, compensation=Compensation(force_scale=0.95))
    exe = _build(step, tmp_path / "c")
    run = run_on_bench(MujocoHand("finger2", scene="block", seed=9692), step, 0.3, 0.6)
    U, Z, F = _run(exe, step, run, step.design.normal, tmp_path)
    assert run.command.max() > 0.005
    np.testing.assert_allclose(U, run.command, rtol=0, atol=TOL)
    np.testing.assert_allclose(F, run.F_fb, rtol=0, atol=TOL)
    if kind == "pi":
        assert np.isnan(Z).all()
    else:
        np.testing.assert_allclose(Z[:, :step.n], run.q_hat, rtol=0, atol=TOL)
    Uc, Zc, Fc = _run_from(exe, step, run, _states(step, run), tmp_path)  # one step from the Python state
    np.testing.assert_allclose(Uc, run.command, rtol=0, atol=1e-12)
    np.testing.assert_allclose(Fc, run.F_fb, rtol=0, atol=1e-12)
    if kind != "pi":
        np.testing.assert_allclose(Zc[:, :step.n], run.q_hat, rtol=0, atol=1e-12)


@needs_cc
def test_c_step_refuses_bad_readings(sensor, tmp_path):
    """A NaN count, a zero normal: alpes_step returns 2, the program says which line."""
    from alpes_dyn.control.cstep import step_main_input

    step, exe, run = sensor
    for counts, normal in ((np.nan, [0.0, 0.0, 1.0]), (0.0, [0.0, 0.0, 0.0])):
        (tmp_path / "in.txt").write_text(step_main_input([[0.0], [counts]], [[0.0], [0.0]], [0.0, 0.0], [0.2, 0.2],
                                                         [[0.0, 0.0, 1.0], normal]))
        r = subprocess.run([str(exe), str(tmp_path / "in.txt")], capture_output=True, text=True)
        assert r.returncode == 1 and r.stderr.strip().endswith("line 2: alpes_step returned 2")
        assert len(r.stdout.splitlines()) == 1


def test_step_sources_bad_input(tmp_path):
    from alpes_dyn.control.cstep import read_step_output, step_c_sources, write_c_step
    from alpes_dyn.control.step import ForceStep

    with pytest.raises(InputError, match=r"^step: expected a ForceStep, got str$"):
        step_c_sources("finger3")
    step = ForceStep("finger2", controller="pi", compiled=False)
    (tmp_path / "file").write_text("x")
    with pytest.raises(InputError, match="-o"):
        write_c_step(step, tmp_path / "file")
    (tmp_path / "full").mkdir()
    (tmp_path / "full" / "a").write_text("x")
    with pytest.raises(InputError, match="-o"):
        write_c_step(step, tmp_path / "full")
    assert (tmp_path / "file").read_text() == "x" and sorted(p.name for p in (tmp_path / "full").iterdir()) == ["a"]
    with pytest.raises(InputError, match="main.c output"):
        read_step_output("1 2\n", 1, 4)


def test_codegen_step_cli(tmp_path, capsys):
    assert cli.main(["codegen", "--step", "--model", "finger2", "--controller", "pi", "--out-dir", str(tmp_path / "c"),
                     "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["files"] == ["alpes_step.c", "alpes_step.h", "alpes_step_force.c", "alpes_step_force.h", "main.c"]
    h = (tmp_path / "c" / "alpes_step.h").read_text()
    assert "int alpes_step(alpes_step_state* s, const double counts[ALPES_STEP_NM]" in h


@pytest.mark.parametrize("argv, message", [
    (["--step", "--model", "finger3", "--controller", "bad"], "--controller: unknown controller 'bad'"),
    (["--step", "--model", "finger3"], "--step: needs --controller"),
    (["--step", "--model", "thumb", "--controller", "sensor"], "--step:"),
    (["--step", "--model", "finger3", "--controller", "sensor", "--friction"], "--friction:"),
    (["--step", "--model", "finger3", "--controller", "sensor", "--observer", "ukf"], "--observer:"),
])
def test_codegen_step_bad_input(argv, message, tmp_path, capsys):
    assert cli.main(["codegen", *argv, "--out-dir", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err
    assert not (tmp_path / "c").exists()


def test_codegen_step_refuses_an_untrusted_file(tmp_path, capsys):
    from alpes_dyn.control.step import ForceStep
    from alpes_dyn.model.params import default_params_path

    path = tmp_path / "p.toml"
    path.write_text(default_params_path().read_text(encoding="utf-8") + '\n[identification.finger]\nconverged = '
                    'false\nstop = "lost basin"\ntrustworthy = false\n')
    assert cli.main(["codegen", "--step", "--model", "finger2", "--controller", "pi", "--params", str(path), "--out-dir",
                     str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "marked" in err
    assert not (tmp_path / "c").exists()
    with pytest.raises(ModelError, match="params"):
        ForceStep("finger2", str(path), "pi", compiled=False)
