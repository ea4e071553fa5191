"""``alpes-dyn codegen --step`` on a URDF robot with its spec: the C step equal to the Python ForceStep of the same
Model (its tip pulled onto the block placed from its kinematics).

The readings: those of a closed-loop run of ``control`` on the robot (MuJoCo, the block scene): the joint angles
MuJoCo gave turned into encoder counts (S q, quantised), the motor torque and the fingertip force the loop read;
both steps replay them (open loop: the same readings into both). Tolerance 1e-9 absolute on the commands (N m), the
joint estimates (rad) and the forces fed back (N). Built at -O0 (the quickest build: 785 kB of the EKF's C, 2 s of
processor time; at -O1 14 s), the same numbers to rounding.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn import cli
from alpes_dyn.model.spec import example_spec_path

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")
TOL = 1e-9


def _robot():
    return str(ad.example_robot_urdf("finger_edu")), str(example_spec_path("finger_edu"))


@needs_cc
def test_codegen_step_on_a_urdf_equals_the_python_step(tmp_path, capsys):
    from alpes_dyn.control.cstep import read_step_output, step_main_input
    from alpes_dyn.control.finger_loop import run_control
    from alpes_dyn.control.step import ForceStep

    urdf, spec = _robot()
    d = tmp_path / "c"
    assert cli.main(["codegen", "--step", "--model", urdf, "--spec", spec, "--controller", "sensor", "--out-dir",
                     str(d), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    model = ad.Model.from_urdf_file(urdf, spec)
    step = ForceStep(model, controller="sensor", compiled=False)
    assert obj["frame"] == step.design.frame and obj["normal"] == pytest.approx(step.design.normal.tolist(), abs=1e-15)
    subprocess.run([CC, "-O0", "-std=c99", "-o", str(d / "main"), *sorted(str(p) for p in d.glob("*.c")), "-lm"],
                   check=True, capture_output=True, timeout=300)
    # the readings' loop on the step in CasADi's VM (compiled=False): its EKF's -O2 library (483 kB of C, tens of
    # seconds of gcc on a cold cache) is not what this test checks; the replay below reads the readings only
    r = run_control("sensor", model=model, duration=0.8, step_times=(0.5, 0.7), compiled=False)
    parts = step.parts()
    counts = np.round(r.q_true @ model.transmission.S.T / parts.rad_per_count)  # (N, m) the encoder's counts
    torque = r.tau_meas.reshape(len(r.t), -1)
    (d / "in.txt").write_text(step_main_input(counts, torque, r.F_meas, r.F_ref, parts.normal))
    out = subprocess.run([str(d / "main"), str(d / "in.txt")], check=True, capture_output=True, text=True).stdout
    U, Z, F = read_step_output(out, step.m, 2 * step.n)
    Up, Zp, Fp = [], [], []
    for k in range(len(r.t)):
        Up.append(step.step(counts[k], torque[k], float(r.F_meas[k]), float(r.F_ref[k])))
        Zp.append(step.state)
        Fp.append(step.force_estimate)
    assert r.F_meas.max() > 0.1 and np.max(Up) > 1e-3  # the tip pressed the block, the replay commands
    np.testing.assert_allclose(U, np.array(Up), rtol=0, atol=TOL)
    np.testing.assert_allclose(Z, np.array(Zp), rtol=0, atol=TOL)
    np.testing.assert_allclose(F, np.array(Fp), rtol=0, atol=TOL)
