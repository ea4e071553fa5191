"""The thumb's chain on the bench: its calibration and guarded experiment through the hardware interface on the MuJoCo
stand-in of the thumb (flexion and ab/adduction motors), the ab/adduction held relaxed; the ab/adduction's motor
pushing both ways through the interface.

References: the stand-in's true joint angles (read by the test only, never by the workflow); the nominal design
(:func:`~alpes_dyn.estimation.experiments.on_hand.designed_torque`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from alpes_dyn.bench.interface import check_command
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.calibration import calibrate
from alpes_dyn.estimation.experiments.design import ExperimentDesign
from alpes_dyn.estimation.experiments.on_hand import designed_torque, run_experiment
from alpes_dyn.model.robot import Model

THUMB = Model.alpes("thumb", friction=True)


def test_thumb_experiment_holds_the_abduction_and_keeps_the_flexion_off_its_stops(tmp_path):
    """The thumb's chain on the stand-in (every effect of a real hand), shortened (a faster calibration, shorter
    holds, one 0.5 s stage, a 0.5 s record): the ab/adduction is not ramped (its range its rest, its curve 0 N m) and its command is 0 N m from
    the first tick to the last; its true joint stays within 0.5 degree of where it rested; the flexion's true joints
    stay off their stops (0 and 90 degrees) during the record and its encoder inside the calibrated range; the
    recording has both motors' columns, the ab/adduction's reading its rest within the guard's margin."""
    pytest.importorskip("mujoco")
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.estimation.experiments.recording import read_recording
    from alpes_dyn.model.mjcf import joint_permutation

    hw = MujocoHand("thumb", seed=11)
    assert hw.motor_names == ("thumb", "thumb_abduction") and hw.both_ways == (False, True)
    perm = joint_permutation(hw._plant.mj, list(THUMB.joint_names))
    q = [hw._data.qpos[perm].copy()]
    write = hw.write
    hw.write = lambda u: (write(u), q.append(hw._data.qpos[perm].copy()))
    cal = calibrate(hw, THUMB, rate=0.0125, speed=1500.0, settle=0.3)
    assert cal.low[1] == cal.high[1] == cal.rest[1] and cal.low[0] < cal.high[0]
    assert cal.torque_at(np.array([cal.rest[0], cal.rest[1] + 100.0]))[1] == 0.0
    res = run_experiment(hw, THUMB, ExperimentDesign(duration=0.5), cal, path=tmp_path / "rec.csv",
                         stage_seconds=0.5, stages=(1.0,), hold=0.5, max_holds=4, tolerance=100.0)
    assert res.bias[1] == 0.0 and res.nominal_bias[1] == 0.0 and res.bias[0] > 0.0
    written = res.log.command[~np.isnan(res.log.command[:, 1])]
    assert np.all(written[:, 1] == 0.0) and written[:, 0].max() > res.bias[0]  # the flexion excited, the abd not
    q = np.degrees(np.array(q))
    off = len(q) - len(res.log.t)  # the experiment's log row r is the truth after its (r - 1)-th write
    rows = slice(off + res.record_rows.start, off + res.record_rows.stop)
    assert np.abs(q[:, 0] - q[0, 0]).max() < 0.5  # the ab/adduction never dragged off its rest
    assert q[rows, 1:].min() > 1.0 and q[rows, 1:].max() < 89.0
    rec = read_recording(tmp_path / "rec.csv", THUMB)
    assert rec.encoder.shape == (501, 2) and rec.motor_names == ("thumb", "thumb_abduction")
    assert cal.low[0] < rec.encoder[:, 0].min() and rec.encoder[:, 0].max() < cal.high[0]
    margin = 0.05 * THUMB.transmission.counts_per_rev / (2 * math.pi)  # the design's joint margin, in counts
    assert np.abs(rec.encoder[:, 1] - cal.rest[1]).max() < margin


def test_thumb_designed_torque_holds_the_abduction_at_zero():
    """The profile a user plays: the ab/adduction's column 0 N m, the flexion's the nominal design's (its mean the
    bias, above 0)."""
    t, u, target = designed_torque(THUMB)
    assert u.shape == (t.size, 2) and np.all(u[:, 1] == 0.0)
    assert u[:, 0].min() >= 0.0 and u[:, 0].mean() > 0.005 and target.shape == (2,)


def test_check_command_both_ways():
    """A motor marked both ways takes [-tau_max, tau_max]; the others [0, tau_max]; one line naming ``command``."""
    np.testing.assert_allclose(check_command([0.01, -0.02], 2, 0.05, both_ways=[False, True]), [0.01, -0.02],
                               rtol=0, atol=0)
    for bad in ([-0.01, 0.0], [0.0, -0.06], [0.06, 0.0]):
        with pytest.raises(InputError, match=r"^command: motor torques must lie in \[0, 0.05\] N m"):
            check_command(bad, 2, 0.05, both_ways=[False, True])
    with pytest.raises(InputError, match=r"^command: motor torques must lie in \[0, 0.05\] N m \(a cable only pulls; "
                                         r"tau_max\), got"):
        check_command([0.0, -0.01], 2, 0.05)


def test_thumb_stand_in_bad_scene():
    pytest.importorskip("mujoco")
    from alpes_dyn.bench.mujoco_hand import MujocoHand

    with pytest.raises(InputError, match="^scene: the block scene is a finger's .* the thumb's is free"):
        MujocoHand("thumb", scene="block")
    with pytest.raises(InputError, match="^scene: the cylinder scene is the hand's, got model 'thumb'"):
        MujocoHand("thumb", scene="cylinder")


def test_thumb_hung_records_with_its_abduction_where_gravity_holds_it(tmp_path):
    """``experiment --bench mujoco --model thumb --rig hanging``'s run (turned.run_turned in the hung rig, the
    stand-in turned, shortened): hung fingers down, gravity swings the relaxed ab/adduction off its palm-up stop
    to where it hangs; the calibration finds that rest (its counts the stand-in's true ab/adduction angle through
    the pulley, within a count), the ab/adduction's command stays 0 N m, its true joint stays within 0.5 degree of
    where it hung, the flexion's true joints stay off their stops during the record, and the recording carries the
    hung gravity (the file's turned a quarter turn about y: (g, 0, 0))."""
    pytest.importorskip("mujoco")
    from alpes_dyn.bench.effects import OFFSET_COUNTS, SLACK_DEG
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.estimation.experiments.recording import read_recording
    from alpes_dyn.estimation.experiments.turned import run_turned
    from alpes_dyn.model.mjcf import joint_permutation

    q, hands = [], []

    def hand_in(rig):
        hw = MujocoHand("thumb", seed=12, rig=rig)
        perm = joint_permutation(hw._plant.mj, list(THUMB.joint_names))
        write = hw.write
        hw.write = lambda u: (write(u), q.append(hw._data.qpos[perm].copy()))
        hands.append(hw)
        return hw

    res = run_turned(hand_in, THUMB, ExperimentDesign(duration=0.5), ("hanging",), path=tmp_path / "rec.csv",
                     stage_seconds=0.5, stages=(1.0,), hold=0.5, max_holds=4, tolerance=100.0)
    run = res.runs[0]
    cal, tr = run.calibration, THUMB.transmission
    assert res.rigs == ("hanging",) and res.tripped == ()
    q = np.array(q)
    off = len(q) - len(run.log.t)  # q[off]: the truth when the experiment's log starts (after the calibration)
    per_rad = float(np.abs(tr.S[1]).sum()) * tr.counts_per_rev / (2 * math.pi)
    counts = float(tr.S[1] @ q[off]) * tr.counts_per_rev / (2 * math.pi)  # the abd's true angle through its pulley
    assert math.degrees(q[off, 0]) > 10.0  # hung: off its palm-up stop at 0
    # the rest read against the truth: the stand-in's encoder zero off by OFFSET_COUNTS, the relaxed cable's slack
    assert abs(cal.rest[1] - counts) <= OFFSET_COUNTS + per_rad * math.radians(SLACK_DEG) + 2.0
    written = run.log.command[~np.isnan(run.log.command[:, 1])]
    assert np.all(written[:, 1] == 0.0) and run.bias[1] == 0.0
    assert np.degrees(np.abs(q[off:, 0] - q[off, 0])).max() < 0.5
    rows = slice(off + run.record_rows.start, off + run.record_rows.stop)
    assert np.degrees(q[rows, 1:]).min() > 1.0 and np.degrees(q[rows, 1:]).max() < 89.0
    rec = read_recording(tmp_path / "rec.csv", THUMB)
    np.testing.assert_allclose(rec.gravity, np.tile([9.81, 0.0, 0.0], (rec.n_samples, 1)), atol=1e-9)
