"""Effort control: the static balance against MuJoCo, the controller's logic, and short closed loops.

References: MuJoCo's touch sensor at a contact equilibrium (an independent contact solver); the
closed loop's force measured by MuJoCo, not by the controller.
"""

from __future__ import annotations

import csv
import json
import sys

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.control.controller import DEFAULT_LEVELS
from alpes_dyn.control import (ForceController, reference_profile, run_control, static_contact_force,
                               static_motor_torque)
from alpes_dyn.model.mjcf import BLOCK_CONTACT_Q, block_normal, load_mujoco, mjcf_string, palm_down_params

mujoco = pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def finger():
    return ad.Model.alpes("finger3", params=palm_down_params(ad.load_params()))


def test_static_balance_against_mujoco(finger):
    """At MuJoCo's contact equilibrium under 0.035 N m, static_contact_force = the touch sensor, and
    static_motor_torque gives back the motor torque for that force."""
    p = finger.params
    mj = load_mujoco(mjcf_string("finger3", p, scene="block", friction=True))
    d = mujoco.MjData(mj)
    for k in range(8000):
        d.ctrl[0] = 0.035 * min(1.0, k / 4000)
        mujoco.mj_step(mj, d)
    F, q, n = d.sensor("flexiforce_finger").data[0], d.qpos.copy(), block_normal(BLOCK_CONTACT_Q)
    assert 0.7 < F < 1.0
    assert static_contact_force(finger, q, np.array([0.035]), n) == pytest.approx(F, rel=1e-4)
    assert static_motor_torque(finger, q, F, n) == pytest.approx(0.035, rel=1e-4)


def test_controller_approach_bumpless_and_limits(finger):
    n = block_normal(BLOCK_CONTACT_Q)
    q = np.array([0.9, 0.5, 0.5])
    c = ForceController("sensor", finger, n, 1e-3, 0.05, prefilter_s=0.0)
    taus = [c.update(0.5, 0.0, q) for _ in range(100)]
    assert np.allclose(np.diff(taus), 0.03e-3) and not c.in_contact  # approach: 0.03 N m/s
    before = taus[-1]
    after = c.update(0.5, 0.1, q)  # contact: the PI starts where the approach ended
    assert c.in_contact and abs(after - before) < 1e-4
    for _ in range(3000):
        tau = c.update(5.0, 0.1, q)  # unreachable force: saturates at tau_max, no windup beyond it
    assert tau == 0.05 and c.integral < 0.05
    assert c.update(0.0, 3.0, q) == 0.0  # a cable cannot push: never below 0
    with pytest.raises(ad.InputError, match="controller: unknown controller 'pid'"):
        ForceController("pid", finger, n, 1e-3, 0.05)


def test_reference_profiles():
    t = np.array([0.0, 0.99, 1.0, 1.5, 2.0, 2.5])
    assert np.allclose(reference_profile("step", t), [0.2, 0.2, 0.6, 0.6, 0.2, 0.2])  # DEFAULT_LEVELS
    assert np.allclose(reference_profile("ramp", t), [0.2, 0.2, 0.2, 0.4, 0.6, 0.6])
    assert np.allclose(reference_profile("step", t, levels=(0.2, 1.0, 0.5)), [0.2, 0.2, 1.0, 1.0, 0.5, 0.5])
    assert np.allclose(reference_profile("ramp", t, levels=(0.2, 1.0, 0.5)), [0.2, 0.2, 0.2, 0.6, 1.0, 1.0])
    assert np.allclose(reference_profile("sine", np.array([1.25, 1.75])), [0.8, 0.3])
    with pytest.raises(ad.InputError, match="reference: unknown reference 'square'"):
        reference_profile("square", t)


def test_closed_loop_step_reaches_the_reference():
    """finger3 on MuJoCo with the FlexiForce loop: 0.2 N then 1.0 N at t = 1 s (the step the gains were tuned on),
    held within 2 %, with the goals of issue 9 on this up-step (overshoot < 10 %, 10-90 % rise < 100 ms, RMSE below
    the PI's); the default step, 0.2 -> 0.6 -> 0.2 N, held within 2 % too."""
    levels = (0.2, 1.0, 0.5)
    r = run_control("sensor", duration=2.0, levels=levels)
    late = r.t >= 1.8
    assert abs(np.mean(r.F_true[late]) - 1.0) < 0.02
    assert r.steady_state_error < 0.02 and r.overshoot < 0.10 and 0.05 < r.rise_time_s < 0.10
    assert max(r.q_rmse_deg) < 3.0  # the EKF follows the joints during contact
    assert np.all((r.tau_cmd >= 0) & (r.tau_cmd <= r.tau_max))
    pi = run_control("pi", duration=2.0, levels=levels)  # the baseline, the same noise draws
    assert r.force_rmse < 0.9 * pi.force_rmse and pi.rise_time_s > r.rise_time_s
    d = run_control("sensor", duration=3.0)  # the default reference
    for hi, level in zip((1.0, 2.0, 3.0), DEFAULT_LEVELS):
        assert abs(np.mean(d.F_true[(d.t >= hi - 0.2) & (d.t < hi)]) - level) < 0.02 * level


def test_setpoint_weight_and_prefilter_order(finger):
    """The 2-DOF structure in the controller's arithmetic: after a reference step, in contact, the
    proportional term sees the raw error (b = 1) or the prefiltered one (b = 0); the first-order prefilter
    moves by dt / (tau + dt) of the step."""
    n, q = block_normal(BLOCK_CONTACT_Q), np.array([0.9, 0.5, 0.5])
    taus = {}
    for b in (0.0, 1.0):
        c = ForceController("sensor", finger, n, 1e-3, 0.05, kp=0.01, ki=0.0, prefilter_s=0.009,
                            prefilter_order=1, setpoint_weight=b)
        c.update(0.2, 0.2, q)  # contact at 0.2 N, integrator set for a continuous torque
        c.update(0.2, 0.2, q)
        assert c.in_contact
        taus[b] = c.update(1.0, 0.2, q) - static_motor_torque(finger, q, 0.2 + 0.8 * 0.1, n) - c.integral
    assert taus[0.0] == pytest.approx(0.01 * 0.8 * 0.1)  # kp x prefiltered error (0.1 of the step)
    assert taus[1.0] == pytest.approx(0.01 * 0.8)  # kp x raw error
    with pytest.raises(ad.InputError, match="prefilter_order: expected 1 or 2"):
        ForceController("sensor", finger, n, 1e-3, 0.05, prefilter_order=3)
    with pytest.raises(ad.InputError, match="setpoint_weight: expected a number in"):
        ForceController("sensor", finger, n, 1e-3, 0.05, setpoint_weight=1.5)


def test_saturation_and_pull_only_respected():
    r = run_control("pi", duration=1.6, levels=(0.2, 3.0, 0.5))  # 3 N is beyond the motor's 0.05 N m
    assert np.all(r.tau_cmd >= 0.0) and np.all(r.tau_cmd <= r.tau_max)
    assert np.all(r.tau_meas <= r.tau_max + 5 * 5e-4)
    assert r.tau_cmd.max() == r.tau_max and r.saturated > 0.01  # it did saturate


def test_cli_control_json_log(capsys, tmp_path):
    log = tmp_path / "c.csv"
    code = main(["control", "--controller", "pi", "--duration", "0.6", "--log", str(log), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert {"controller", "plant", "force_rmse", "steady_state_error", "overshoot", "rise_time_s",
            "q_rmse_deg"} <= set(d)
    assert d["controller"] == "pi" and d["plant"] == "mujoco" and d["q_rmse_deg"] is None
    rows = list(csv.reader(log.open()))
    assert rows[0][:3] == ["t_s", "F_ref_N", "F_mujoco_N"] and len(rows) == 601


@pytest.mark.parametrize("argv,needle", [
    (["control", "--controller", "pid"], "--controller: unknown controller 'pid'"),
    (["control", "--reference", "square"], "--reference: unknown reference 'square'"),
    (["control", "--model", "finger9"], "--model: the control scenario is defined for one finger"),
    (["control", "--model", "hand", "--reference", "sine"], "--reference: the hand's loops follow step references"),
    (["control", "--model", "hand", "--duration", "2"], "--duration: the hand's run needs at least 2.75 s"),
    (["control", "--duration", "0"], "--duration: expected a positive number of seconds"),
    (["control", "--log", "/nonexistent/x.csv"], "--log: directory '/nonexistent'"),
    (["control", "--params", "/nonexistent.toml"], "cannot be read"),
])
def test_cli_control_bad_input(capsys, argv, needle):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and needle in err


def test_missing_mujoco_one_line(capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    code = main(["control"])
    out, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and "pip install 'alpes_dyn[mujoco]'" in err


def test_short_step_segments_give_no_overshoot_and_no_crash():
    """Both step segments under 0.25 s (duration 0.7 s, steps at 0.4 and 0.6 s): no overshoot to measure (None,
    not a crash on an empty list); the force RMSE is still measured."""
    r = run_control("pi", duration=0.7, step_times=(0.4, 0.6))
    assert r.overshoot is None and np.isfinite(r.force_rmse)
