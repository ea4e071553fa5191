"""Every friction law of the parameter file (``friction.law``: tanh, lugre, creep) through the C exports: the
observer's (``alpes-dyn codegen``: estimation.cexport, its default code for a friction model, built by
``compiled_c_step``: the project's build cache), the whole force step's (``codegen --step``: control.cstep, built with
the system compiler) and ``ForceStep(compiled=True)`` (the same C through ctypes), each against the Python filter or
step on finger3.

References: the Python filter (CasADi's virtual machine) on the same inputs; the law's own effect is checked too (the
estimates of a creep or LuGre file differ from the tanh file's by far more than the tolerance), so an export that fell
back to another law fails. Tolerances: the joint angles (rad) and the commands (N m) to 1e-9 absolute over the run;
the observer's whole state one step from the Python filter's state (the benchmarks' rule, benchmarks/c_step.py) to
1e-11 of its largest entry and its covariance to 1e-10 of its largest (measured 3e-12 and 3e-11: the C's loop over
one substep and its chain rule against CasADi's Jacobian of the whole step); free-running, the filter's gain on the
velocities (up to 12 rad/s here) carries that rounding to 1e-8 rad/s over 200 samples, which is not asserted. The
force step's whole state free-running to 1e-9 of its largest entry (measured 4e-11 rad/s).
"""

from __future__ import annotations

import json
import shutil
import subprocess
import time

import numpy as np
import pytest

from alpes_dyn import cli
from alpes_dyn.model.params import Param, load_params, with_values, write_params

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")
LAWS = ("tanh", "lugre", "creep")
OBSERVER_LAW = {"tanh": "smooth", "lugre": "lugre", "creep": "smooth"}  # creep: solved in the smooth law's dynamics
TOL = 1e-9


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The shipped file with each friction.law (creep_kappa, creep_rate, sigma0, sigma1 at their defaults)."""
    d = tmp_path_factory.mktemp("laws")
    return {law: str(write_params(with_values(load_params(), {"friction.law": Param(law, "-", "assumed", "test")}),
                                  d / f"{law}.toml")) for law in LAWS}


@pytest.fixture(scope="module")
def scenario_data():
    """200 samples of the estimation scenario with friction (its torque and encoder): the filters' inputs."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    res = run_estimation("ekf", duration=0.2, friction=True)
    return res.u_meas, res.y


def _c_run(filt, step, est, U, Y, one_step=False):
    """The compiled C step over the same inputs, (N+1, nz + nz^2) [z; P column-major]: from the Python filter's
    first estimate (a free run), or with ``one_step`` each step from the Python filter's state before it."""
    def state(k):
        return np.concatenate([est.z[k], est.P[k].reshape(-1, order="F")])

    s, S = state(0), [state(0)]
    for k in range(len(U)):
        s = step(state(k) if one_step else s, np.concatenate([np.atleast_1d(U[k]), Y[k + 1]]))
        S.append(s)
    return np.array(S)


@needs_cc
def test_observer_c_export_runs_the_file_law(files, scenario_data):
    """codegen's observer (scenario_filter) on each law's file: the law estimate --data runs (LuGre's bristles in the
    state), its C equal to the Python filter over 200 samples, and each law's estimates its own."""
    from alpes_dyn.estimation.cexport.cexport import compiled_c_step, scenario_filter

    U, Y = scenario_data
    q = {}
    for law in LAWS:
        filt, z0, P0 = scenario_filter("ekf", "finger3", params=files[law], friction=True)
        assert filt.model.friction_law == OBSERVER_LAW[law] and filt.nz == (9 if law == "lugre" else 6)
        assert z0.shape == P0.shape == (filt.nz,)
        est = filt.run(z0, P0, U, Y)
        t0 = time.perf_counter()
        step = compiled_c_step(filt, f"test_law_ekf_{law}")
        built = f"{law}: C built (or loaded from the cache) in {time.perf_counter() - t0:.1f} s"
        Z = _c_run(filt, step, est, U, Y)[:, :filt.nz]
        assert np.abs(Z[:, :3] - est.z[:, :3]).max() < TOL, built  # rad
        S = _c_run(filt, step, est, U, Y, one_step=True)  # the benchmarks' rule: one step from the same state
        assert np.abs(S[:, :filt.nz] - est.z).max() < 1e-11 * np.abs(est.z).max(), built
        assert np.abs(S[:, filt.nz:] - est.P.reshape(len(S), -1, order="F")).max() < 1e-10 * np.abs(est.P).max()
        q[law] = est.z[:, :3]
    for law in ("lugre", "creep"):  # rad: another law's estimate, not the tanh law's
        assert np.abs(q[law] - q["tanh"]).max() > 1e-3, law


def test_the_library_source_is_generated_once_per_structure(files, monkeypatch):
    """compiled_c_step's C is kept by its filter's structure (its step serialised): a second filter of the file (a
    ForceStep built again, the hand's fingers) gets, without generating it again, the very source c_sources makes
    for it afresh; a filter of another structure (finger2's) gets a source of its own."""
    import alpes_dyn.estimation.cexport.cexport as cx

    a, b, c = (cx.scenario_filter("ekf", model, params=files["tanh"], friction=True)[0]
               for model in ("finger3", "finger3", "finger2"))
    made, real = [], cx.c_sources
    monkeypatch.setattr(cx, "c_sources", lambda filt, **kw: made.append(filt) or real(filt, **kw))
    monkeypatch.setattr(cx, "_LIBRARY_SOURCES", {})
    sa, sb, sc = (cx._library_source(f) for f in (a, b, c))
    assert len(made) == 2 and made[0] is a and made[1] is c
    assert sa == sb and sc[0] != sa[0]
    monkeypatch.setattr(cx, "_LIBRARY_SOURCES", {})
    assert cx._library_source(b) == sb and made[-1] is b  # afresh, from b itself


def test_codegen_cli_exports_the_bristles(files, tmp_path, capsys):
    """``codegen --params lugre.toml --friction`` and ``codegen --step``: the bristles in the exported state (as
    estimate's observer)."""
    assert cli.main(["codegen", "--model", "finger3", "--params", files["lugre"], "--friction",
                     "--out-dir", str(tmp_path / "c"), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["nz"] == 9 and obj["states"][6:] == ["bristle_j1", "bristle_j2", "bristle_j3"]
    assert "#define ALPES_EKF_NZ 9" in (tmp_path / "c" / "alpes_ekf.h").read_text()
    assert cli.main(["codegen", "--step", "--model", "finger3", "--params", files["lugre"], "--controller", "sensor",
                     "--out-dir", str(tmp_path / "s"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["nz"] == 9
    assert "#define ALPES_STEP_NZ 9" in (tmp_path / "s" / "alpes_step.h").read_text()


@pytest.fixture(scope="module")
def bench_run(files):
    """300 ticks of finger3's sensor step (tanh file, Python) on the stand-in's block: the run (its readings
    replayed) and the tanh step's EKF states over it."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.control.bench_loop import run_on_bench
    from alpes_dyn.control.step import ForceStep

    step = ForceStep("finger3", files["tanh"], "sensor", compiled=False)
    run = run_on_bench(MujocoHand("finger3", scene="block", seed=9691), step, 0.4, 0.3)
    return run, _replay(step, run)[1]


def _replay(step, run):
    """The step over the recorded readings: (commands (N, m), its EKF's states (N, nz))."""
    step.reset()
    U, Z = [], []
    for k in range(len(run.t)):
        U.append(step.step(run.counts[k], run.torque[k], run.force[k], float(run.F_ref[k])))
        Z.append(step._s[:step.nz].copy())
    return np.array(U), np.array(Z)


@needs_cc
@pytest.mark.parametrize("law", ["lugre", "creep"])
def test_force_step_c_runs_the_file_law(law, files, bench_run, tmp_path):
    """ForceStep on each law's file: its EKF runs the law (LuGre: 3n states, the [q; qd] block its covariance), and
    ForceStep(compiled=True) and codegen --step's C (main.c over the readings) give the Python step's commands and
    estimates; the estimates differ from the tanh file's step."""
    from alpes_dyn.control.cstep import read_step_output, step_main_input, write_c_step
    from alpes_dyn.control.step import ForceStep

    run, Zt = bench_run
    py = ForceStep("finger3", files[law], "sensor", compiled=False)
    n = py.n
    assert py._ekf.model.friction_law == OBSERVER_LAW[law] and py.nz == (3 * n if law == "lugre" else 2 * n)
    assert py.covariance.shape == (2 * n, 2 * n) and py.parts().z0.shape == (py.nz,)
    U, Z = _replay(py, run)
    t0 = time.perf_counter()
    compiled = ForceStep("finger3", files[law], "sensor", compiled=True)
    built = f"{law}: ForceStep(compiled=True) built (or loaded from the cache) in {time.perf_counter() - t0:.1f} s"
    files_c = write_c_step(py, tmp_path / "c")
    t0 = time.perf_counter()
    subprocess.run([CC, "-O0", "-std=c99", "-o", str(tmp_path / "main"),
                    *[str(tmp_path / "c" / f) for f in sorted(files_c) if f.endswith(".c")], "-lm"],
                   check=True, capture_output=True, text=True, timeout=300)
    built += f"; the C step built in {time.perf_counter() - t0:.1f} s"
    (tmp_path / "in.txt").write_text(step_main_input(run.counts, run.torque, run.force, run.F_ref, py.design.normal))
    out = subprocess.run([str(tmp_path / "main"), str(tmp_path / "in.txt")], check=True, capture_output=True,
                         text=True).stdout
    Uc, Zc, _ = read_step_output(out, py.m, py.nz)
    for Ux, Zx in (_replay(compiled, run), (Uc, Zc)):
        assert np.abs(Ux - U).max() < TOL, built
        assert np.abs(Zx[:, :n] - Z[:, :n]).max() < TOL, built
        assert np.abs(Zx - Z).max() < TOL * np.abs(Z).max(), built
    assert np.abs(Z[:, :n] - Zt[:, :n]).max() > 1e-4  # rad: the law's own estimates
