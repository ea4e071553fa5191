"""The whole hand's force step (alpes_dyn.control.hand_step) and its C (alpes_dyn.control.chand), and ForceStep.parts.

One closed-loop run of the Python step on the MuJoCo stand-in's cylinder scene (every effect of a real hand), shared
by the module; its readings and normals replayed through the compiled C test program. Tolerances: commands (N m),
estimates (rad, rad/s) and forces fed back (N) to 1e-9 absolute (the C is the Python step's operations but for
CasADi's G and J against Pinocchio's and the EKF's substep loop: rounding only); built at -O0, the quickest build.
"""

from __future__ import annotations

import json
import shutil
import subprocess

import numpy as np
import pytest

from alpes_dyn import cli
from alpes_dyn.errors import InputError

CC = shutil.which("cc") or shutil.which("gcc")
needs_cc = pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")
TOL = 1e-9
KEYS = ("counts", "torque", "force", "ref", "normals", "command", "z", "F_fb")


@pytest.fixture(scope="module")
def hand_run():
    """The sensor step of the hand (compiled EKFs, cached) closing the loop on the stand-in for 2.4 s: 0.3 N on every
    chain (the approach takes about 1.5 s), 0.4 N from 2 s; the readings, the normals the step used, its outputs;
    the truth's forces."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand, scoring_truth
    from alpes_dyn.control.hand_step import HandForceStep

    step = HandForceStep(controller="sensor")
    hw = MujocoHand("hand", scene="cylinder", seed=9741)
    assert hw.motor_names == step.motor_names and hw.counts_per_rev == step.chain_steps["index"].counts_per_rev
    rec = {k: [] for k in KEYS}
    F_true = []
    for k in range(2400):
        r = hw.read()
        ref = np.full(5, 0.3 if k < 2000 else 0.4)
        u = step.step(r.counts, r.torque, r.force, ref)
        hw.write(u)
        for key, v in zip(KEYS, (r.counts, r.torque, r.force, ref, step.normals, u, step.state, step.force_estimate)):
            rec[key].append(v)
        F_true.append(scoring_truth(hw)[1])
    return step, {k: np.array(v) for k, v in rec.items()}, np.array(F_true)


def test_hand_step_holds_every_fingertip(hand_run):
    """The four fingers' MuJoCo forces within 10 % of 0.3 N before the step (their pads on the cylinder); every
    chain's command in [0, tau_max], the ab/adduction's in [-tau_max, tau_max]; the ab/adduction driven (its command
    positive at the start) and held at its 35 degree target against the thumb's contact within 1 degree (its encoder
    over the last 0.2 s: a motor clipped at 0 let the contact push it to 59 degrees)."""
    step, rec, F_true = hand_run
    held = F_true[1700:2000].mean(axis=0)
    np.testing.assert_allclose(held[:4], 0.3, rtol=0.1)
    assert held[4] > 0.05  # the thumb reached the cylinder
    assert (rec["command"][:, :5] >= 0).all() and (np.abs(rec["command"]) <= step.tau_max).all()
    assert rec["command"][:50, 5].max() > 0
    abd = np.degrees(rec["counts"][-200:, 5] * step.abduction_rad_per_count)
    assert abs(abd.mean() - 35.0) < 1.0, abd.mean()
    assert step.motor_names == ("index", "middle", "ring", "little", "thumb", "thumb_abduction")


def test_hand_chains_take_the_hand_gains(hand_run):
    """Every chain's controller has the hand's settings (hand_gains): the cylinder's sensor integral, not the
    block's (DEFAULT_GAINS, set for the rise on the block), the fingers' 40 ms prefilter and the thumb's own 25 ms;
    the other controllers keep their own ki."""
    from alpes_dyn.control.controller import DEFAULT_GAINS
    from alpes_dyn.control.hand_grasp import HAND_CHAIN_GAINS, HAND_GAINS, hand_gains

    step = hand_run[0]
    for name, s in step.chain_steps.items():
        c, want = s.controller, hand_gains("sensor", None, name)
        prefilter = HAND_CHAIN_GAINS.get(name, {}).get("sensor", HAND_GAINS)["prefilter_s"]
        assert (c.ki, c.kp, c.prefilter_s, c.approach_rate) == (want["ki"], DEFAULT_GAINS["sensor"]["kp"], prefilter,
                                                                HAND_GAINS["approach_rate"])
        assert want["ki"] < DEFAULT_GAINS["sensor"]["ki"]
    assert step.chain_steps["thumb"].controller.prefilter_s < step.chain_steps["index"].controller.prefilter_s
    assert hand_gains("pi")["ki"] == DEFAULT_GAINS["pi"]["ki"] and hand_gains("pi", {"ki": 0.5}, "thumb")["ki"] == 0.5


@needs_cc
def test_c_hand_step_equals_the_python_step(hand_run, tmp_path):
    from alpes_dyn.control.chand import hand_main_input, read_hand_output, write_c_hand

    step, rec, _ = hand_run
    files = write_c_hand(step, tmp_path / "c")
    d = tmp_path / "c"
    assert "alpes_hand.h" in files and "alpes_hand_thumb_ekf.c" in files
    subprocess.run([CC, "-O0", "-std=c99", "-Wall", "-Werror", "-Wno-unused-function", "-Wno-unused-variable",
                    "-Wno-unused-but-set-variable", "-o", str(d / "main"),
                    *[str(d / n) for n in sorted(files) if n.endswith(".c")], "-lm"],
                   check=True, capture_output=True, text=True, timeout=600)
    (d / "in.txt").write_text(hand_main_input(rec["counts"], rec["torque"], rec["force"], rec["ref"], rec["normals"]))
    out = subprocess.run([str(d / "main"), str(d / "in.txt")], check=True, capture_output=True, text=True).stdout
    U, Z, F = read_hand_output(out)
    assert rec["command"][:, :5].max() > 0.02  # the chains pressed
    np.testing.assert_allclose(U, rec["command"], rtol=0, atol=TOL)
    np.testing.assert_allclose(Z, rec["z"], rtol=0, atol=TOL)
    np.testing.assert_allclose(F, rec["F_fb"], rtol=0, atol=TOL)
    # main -t 2: the record twice, each step timed (cstep.TIME_STEPS_C): its last command the free run's, each
    # step's minimum over the passes at most its median and at most the passes' wall clock per step
    timed = subprocess.run([str(d / "main"), "-t", "2", str(d / "in.txt")], check=True, capture_output=True,
                           text=True).stdout.replace(";", "").replace(",", "").replace(")", "").split()
    wall, u0, lo, med = (float(timed[i]) for i in (4, 15, 22, 26))
    assert u0 == pytest.approx(U[-1, 0], abs=1e-15) and 0 < lo <= med * (1 + 1e-9) and lo <= wall * (1 + 1e-9)
    bad = rec["counts"][:2].copy()
    bad[1, 2] = np.nan
    (d / "bad.txt").write_text(hand_main_input(bad, rec["torque"][:2], rec["force"][:2], rec["ref"][:2],
                                               rec["normals"][:2]))
    r = subprocess.run([str(d / "main"), str(d / "bad.txt")], capture_output=True, text=True)
    assert r.returncode == 1 and r.stderr.strip().endswith("line 2: alpes_hand_step returned 2")
    # main -s: each tick one C step from the Python step's state before it (hand_state_row of a replay with the
    # run's normals): the benchmarks' agreement rule (c_step.py's docstring), rounding of one step only
    from alpes_dyn.control.chand import hand_state_row

    step.reset()
    S = []
    for k in range(len(rec["counts"])):
        S.append(hand_state_row(step))
        step.step(rec["counts"][k], rec["torque"][k], rec["force"][k], rec["ref"][k], rec["normals"][k])
    S = np.array(S)
    args = (rec["counts"], rec["torque"], rec["force"], rec["ref"], rec["normals"])
    for states, close in ((S, True), (np.broadcast_to(S[0], S.shape), False)):  # the state read: from the rest
        (d / "in_s.txt").write_text(hand_main_input(*args, states=states))
        out = subprocess.run([str(d / "main"), "-s", str(d / "in_s.txt")], check=True, capture_output=True,
                             text=True).stdout
        U, Z, F = read_hand_output(out)
        if close:
            for a, b in ((U, rec["command"]), (Z, rec["z"]), (F, rec["F_fb"])):
                np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
        else:
            assert np.abs(Z[-100:] - rec["z"][-100:]).max() > 0.05
            assert np.abs(U[-100:] - rec["command"][-100:]).max() > 1e-3


def test_parts_are_the_step_settings():
    """ForceStep.parts: the settings the C generator reads, checked against the step's own behaviour."""
    from alpes_dyn.control.step import ForceStep

    step = ForceStep("finger2", controller="sensorless", compiled=False)
    parts = step.parts()
    assert parts.n == 2 and parts.m == 1 and parts.kind == "sensorless" and parts.observer_friction
    np.testing.assert_allclose(parts.z0, step.state, rtol=0, atol=1e-15)  # the prior is the first sample's state
    np.testing.assert_allclose(parts.P0.reshape(4, 4, order="F"), step.covariance, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(parts.normal), 1.0, rtol=1e-12)
    assert parts.controller is not step.controller and parts.controller.kp == pytest.approx(step.controller.kp)
    np.testing.assert_allclose(parts.rad_per_count * step.counts_per_rev, 2 * np.pi, rtol=1e-12)
    assert 0 < parts.sensorless_alpha < 1
    with pytest.warns(DeprecationWarning, match="force_scale"):  # the old name, one release
        assert parts.sensorless_scale == parts.force_scale
    pi = ForceStep("finger2", controller="pi", compiled=False).parts()
    assert pi.ekf is None and np.isnan(pi.z0).all() and pi.sensorless_alpha is None


def test_force_step_takes_the_normal_per_sample():
    """The normal given at each sample is the one a step built with it uses: the same commands."""
    from alpes_dyn.control.step import ForceStep

    n = [-0.9, 0.0, -0.3]
    a = ForceStep("finger2", controller="sensor", compiled=False)
    b = ForceStep("finger2", controller="sensor", compiled=False, normal=n)
    counts = a.parts().z0[:1] * 0
    for k in range(30):
        ua = a.step(counts + k, 0.0, 0.2, 0.4, normal=n)
        ub = b.step(counts + k, 0.0, 0.2, 0.4)
        np.testing.assert_allclose(ua, ub, rtol=0, atol=1e-15)
    with pytest.raises(InputError, match="^normal:"):
        a.step(counts, 0.0, 0.2, 0.4, normal=[0.0, 0.0, 0.0])


@pytest.mark.parametrize("kwargs, needle", [
    ({"controller": "pid"}, "^controller: unknown controller 'pid'"),
    ({"thumb_abduction": 3.0}, "^thumb_abduction: 3 rad is outside"),
    ({"abduction_kp": -1.0}, "^abduction_kp: expected a non-negative number"),
    ({"gains": {"kq": 1.0}}, "^gains: unknown setting"),
    ({"dt": 0.0}, "^dt: expected a positive number"),
])
def test_hand_step_bad_settings(kwargs, needle):
    from alpes_dyn.control.hand_step import HandForceStep

    with pytest.raises(InputError, match=needle):
        HandForceStep(**{"compiled": False, **kwargs})


def test_hand_step_bad_readings(hand_run):
    step, rec, _ = hand_run
    good = (rec["counts"][0], rec["torque"][0], rec["force"][0], 0.3)
    for i, bad, needle in ((0, [1.0] * 5, "^counts: expected encoder counts of shape"),
                           (1, [np.nan] * 6, "^torque: expected finite"),
                           (2, None, "^force: expected fingertip forces"),
                           (3, [0.3] * 4, "^reference: expected")):
        args = list(good)
        args[i] = bad
        with pytest.raises(InputError, match=needle):
            step.step(*args)
    with pytest.raises(InputError, match="^normals: expected contact normals of shape"):
        step.step(*good, normals=np.ones((4, 3)))
    with pytest.raises(InputError, match="^index: normal:"):
        step.step(*good, normals=np.zeros((5, 3)))


def test_codegen_step_hand_cli(tmp_path, capsys):
    assert cli.main(["codegen", "--step", "--model", "hand", "--controller", "pi", "--out-dir", str(tmp_path / "c"),
                     "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["motors"] == ["index", "middle", "ring", "little", "thumb", "thumb_abduction"]
    assert {"alpes_hand.c", "alpes_hand.h", "main.c", "alpes_hand_thumb.c", "alpes_hand_index_force.c"} <= set(
        obj["files"])
    h = (tmp_path / "c" / "alpes_hand.h").read_text()
    assert "int alpes_hand_step(alpes_hand_state* s, const double counts[6]" in h


@pytest.mark.parametrize("kwargs, needle", [
    ({"model": "finger3", "scene": "cylinder"}, "^scene: the cylinder scene is the hand's, got model 'finger3'"),
    ({"model": "hand", "scene": "cylinder", "q0": [0.0] * 15}, "^q0: the cylinder scene starts at the hand's rest"),
    ({"model": "hand", "scene": "block"}, "^scene: the block scene is a finger's"),
])
def test_stand_in_cylinder_bad_input(kwargs, needle):
    from alpes_dyn.bench.mujoco_hand import MujocoHand

    with pytest.raises(InputError, match=needle):
        MujocoHand(**kwargs)
