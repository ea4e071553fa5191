"""The identification experiment on the hand (issue 49, item 2): the guarded session, the calibration and the
experiment through the hardware interface, on toys whose truth the test writes and on the MuJoCo stand-in."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from alpes_dyn.bench.interface import Loopback, Reading, check_command
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.calibration import (FOLD_WINDOW, SNAP_FRACTION, Calibration, calibrate,
                                                          load_calibration)
from alpes_dyn.estimation.experiments.design import ExperimentDesign
from alpes_dyn.estimation.experiments.hand_session import MAX_GAP, RELAX_SECONDS, GuardTripped, HandSession
from alpes_dyn.estimation.experiments.on_hand import designed_torque, run_experiment
from alpes_dyn.model.robot import Model


class ToyFinger:
    """A HardwareInterface whose truth the test knows: the encoder follows, with a first-order lag ``lag`` s, the
    static curve rest + g1 tau up to ``knee1`` counts, then the steeper g2 up to ``stop`` counts, where it stays
    (a stop); no noise. Written here (not a Loopback) so that a long calibration's every tick is O(1)."""

    motor_names = ("finger",)
    counts_per_rev = 4096
    tau_max = 0.05

    def __init__(self, rest=-150.0, knee1=None, g1=1e5, g2=1e5, stop=3000.0, lag=0.02, period=1e-3):
        self.rest, self.knee1, self.g1, self.g2, self.stop, self.lag = rest, knee1, g1, g2, stop, lag
        self.period, self.k, self.y, self.u = period, 0, rest, 0.0

    def static(self, tau: float) -> float:
        if self.knee1 is None:
            y = self.rest + self.g1 * tau
        else:
            t1 = (self.knee1 - self.rest) / self.g1
            y = self.rest + self.g1 * tau if tau <= t1 else self.knee1 + self.g2 * (tau - t1)
        return min(y, self.stop)

    def read(self) -> Reading:
        return Reading(self.k * self.period, np.array([round(self.y)]), np.array([self.u]))

    def write(self, command) -> None:
        self.u = float(check_command(command, 1, self.tau_max)[0])
        self.y += (self.static(self.u) - self.y) * (1 - math.exp(-self.period / self.lag))
        self.k += 1

    def close(self) -> None:
        pass


FINGER3 = Model.alpes("finger3", friction=True)


def test_calibration_finds_the_toys_rest_range_and_curve():
    """A toy with the Alpes finger3's shape palm up: a joint on its stop below 1500 counts (slope 1e5 counts per
    N m), free above (4e5), a stop at 4000 counts; 20 ms of lag."""
    toy = ToyFinger(rest=-150.0, knee1=1500.0, g1=1e5, g2=4e5, stop=4000.0)
    cal = calibrate(toy, FINGER3)
    t1 = (1500 + 150) / 1e5  # the torque at the lower knee, 0.0165 N m
    tau_s = t1 + (4000 - 1500) / 4e5  # at the stop, 0.02275 N m
    window = 0.05 * 0.05  # KNEE_WINDOW x the safe torque, N m
    assert cal.rest[0] == pytest.approx(-150.0, abs=1.0)
    assert cal.stop[0] and math.isnan(cal.fold_torque[0])
    # the upper end: the knee test fires once the window holds less than 30 % of the steep slope's growth
    assert 4000 - 0.35 * window * 4e5 - 20 <= cal.high[0] <= 4000
    assert cal.torque_high[0] == pytest.approx(tau_s, abs=0.35 * window + 2e-4)
    # the lower end: the knee at 1500 counts, within half a window of it (the middle of the window that holds it)
    assert cal.low[0] == pytest.approx(1500.0, abs=0.5 * window * 4e5)
    assert cal.torque_low[0] == pytest.approx(t1, abs=0.5 * window)
    # the curve: the static relation, within the lag (20 ms of the ramp, at most 500 counts/s on the steep part)
    keep = cal.curve_torque[:, 0] < tau_s - 1e-3
    for tau, c in zip(cal.curve_torque[keep, 0], cal.curve_counts[keep, 0]):
        assert c == pytest.approx(toy.static(tau), abs=30.0)
    assert cal.torque_at(np.array([2500.0]))[0] == pytest.approx(t1 + 1000 / 4e5, abs=2e-4)


def test_calibration_without_stop_ends_at_the_safe_torque_and_round_trips(tmp_path):
    toy = ToyFinger(rest=100.0, g1=4e4, stop=1e9)
    cal = calibrate(toy, FINGER3, safe_torque=0.02, rate=0.01)
    assert not cal.stop[0] and cal.torque_high[0] == pytest.approx(0.02, rel=1e-9)
    assert cal.high[0] == pytest.approx(100 + 4e4 * 0.02, abs=4e4 * 0.01 * 0.02 + 2)  # the lag: rate x 20 ms
    assert cal.rest[0] == cal.low[0] == pytest.approx(100.0, abs=1)  # no knee below: the rest is the lower end
    back = load_calibration(cal.save(tmp_path / "cal.json"))
    assert back.motor_names == cal.motor_names
    for f in ("rest", "low", "high", "torque_high", "curve_counts"):
        np.testing.assert_allclose(getattr(back, f), getattr(cal, f), rtol=1e-15)


class RunawayFinger(ToyFinger):
    """The encoder runs toward its stop at ``speed`` counts/s whenever the command is above ``hold`` N m (a soft
    finger past its fold), and stops moving otherwise."""

    def __init__(self, speed=3000.0, hold=0.01, **kw):
        super().__init__(**kw)
        self.speed, self.hold = speed, hold

    def write(self, command) -> None:
        self.u = float(check_command(command, 1, self.tau_max)[0])
        if self.u > self.hold:
            self.y = min(self.y + self.speed * self.period, self.stop)
        self.k += 1


def test_calibration_tells_a_snap_from_a_steep_stable_branch():
    """A fold is the encoder running at one held torque (:data:`FOLD_WINDOW`): the runaway toy, which runs to its
    stop whenever the command is above 0.015 N m, folds there; a steep but stable branch (1.2e6 counts per N m
    over 3000 counts, 0.0025 N m: q_1 sweeping its range as on the stand-in's finger3 palm up, 20 ms of lag), over
    which a window of 2 % of the safe torque grows by more than a quarter of the range, is no fold, and its
    curve is the toy's."""
    steep = ToyFinger(rest=-150.0, knee1=1500.0, g1=1e5, g2=1.2e6, stop=4500.0)
    cal = calibrate(steep, FINGER3)
    assert math.isnan(cal.fold_torque[0]) and cal.stop[0]
    assert 1.2e6 * 0.02 * cal.safe_torque > SNAP_FRACTION * (cal.high[0] - cal.rest[0])  # the old window's growth
    t1 = (1500 + 150) / 1e5
    assert cal.torque_at(np.array([3000.0]))[0] == pytest.approx(t1 + 1500 / 1.2e6, abs=2e-4)
    snap = calibrate(RunawayFinger(hold=0.015, rest=0.0, stop=3000.0), FINGER3)
    assert snap.fold_torque[0] == pytest.approx(0.015, abs=FOLD_WINDOW * snap.safe_torque + 1e-4)
    assert snap.high[0] == pytest.approx(3000.0, abs=60.0)


def test_guard_stops_before_the_stop_and_relaxes():
    hw = RunawayFinger(rest=1000.0, stop=3000.0)
    margin = 200.0
    s = HandSession(hw, low=np.array([1000.0 + margin]), high=np.array([3000.0 - margin]))
    with pytest.raises(GuardTripped, match=r"guard: motor finger: encoder at .* left the guard band") as exc:
        s.run(np.full((2000, 1), 0.02))  # 2 s of a pull that would carry it to the stop in 0.67 s
    trip = exc.value
    assert trip.reason == "stop"
    cmd = trip.log.command[:, 0]
    done = np.flatnonzero(~np.isnan(cmd))
    assert cmd[done[-1]] == 0.0  # relaxed: the last command is the rest torque
    ramp = cmd[np.searchsorted(trip.log.t, trip.t):done[-1] + 1]
    assert np.all(np.diff(ramp) <= 1e-15) and ramp.size >= RELAX_SECONDS / hw.period - 1  # a ramp down
    reached = trip.log.counts[:, 0].max()
    # it ran on while the ramp's command stayed above the 0.01 N m that holds it: half the ramp, and a tick
    assert 3000.0 - margin < reached <= 3000.0 - margin + hw.speed * (0.5 * RELAX_SECONDS + 2 * hw.period)
    assert reached < 3000.0  # inside the margin: the stop never reached
    assert trip.counts[0] == pytest.approx(3000.0 - margin, abs=hw.speed * hw.period + 1)


@dataclasses.dataclass
class LateLoopback(Loopback):
    """A Loopback whose clock skips ``skip`` periods at tick ``at`` (the driver missed its deadline)."""

    at: int = 50
    skip: float = 1.0

    def read(self) -> Reading:
        r = super().read()
        k = len(self._commands)
        return Reading(r.t + (self.skip * self.period if k >= self.at else 0.0), r.counts, r.torque, r.force)


@pytest.mark.parametrize("skip, trips", [(0.4, False), (0.6, True), (2.0, True)])
def test_guard_trips_on_a_missed_period(skip, trips):
    hw = LateLoopback(skip=skip)
    s = HandSession(hw)
    if not trips:  # 1.4 periods: inside MAX_GAP
        s.run(np.full((100, 1), 0.01))
        return
    with pytest.raises(GuardTripped, match="missed its period") as exc:
        s.run(np.full((100, 1), 0.01))
    assert exc.value.reason == "period" and MAX_GAP == 1.5
    assert exc.value.t == pytest.approx((50 + skip) * 1e-3)
    assert hw.commands[49, 0] == 0.01 and hw.commands[-1, 0] == 0.0  # relaxed after the 50th command
    assert np.all(np.diff(hw.commands[49:, 0]) <= 0)


def test_designed_torque_is_the_experiments_own():
    """The profile of --design-only: the simulated experiment's torque on the nominal finger itself (no trim to do
    there: trimmed on itself the bias is its own)."""
    from alpes_dyn.estimation.experiments.experiment import model_experiment_torque

    design = ExperimentDesign(duration=1.0)
    t, u, target = designed_torque(FINGER3, design)
    t2, u2, x0 = model_experiment_torque(FINGER3, design=design)
    np.testing.assert_allclose(t, t2, rtol=0, atol=1e-12)
    np.testing.assert_allclose(u, u2, rtol=1e-9, atol=1e-6)  # the trim's bisection: 1e-6 N m of the bias
    # the target: the nominal's encoder reading at rest under the bias, from its own rest state
    assert target[0] == pytest.approx(2 * x0[:3].sum() * 4096 / (2 * np.pi), abs=2.0)


def test_no_room_for_the_multisine_trips_the_guard_not_a_record(monkeypatch):
    """Where the stages leave the multisine no amplitude (scale 0: the dither alone fills the band, as on one hand
    chain of the bench_loop record, whose record at amplitude 0 then failed to converge), the run stops there: the
    finger relaxed, GuardTripped naming it, no recording."""
    import alpes_dyn.estimation.experiments.on_hand as on_hand

    toy = ToyFinger(rest=-150.0, knee1=1500.0, g1=1e5, g2=4e5, stop=4000.0)
    cal = calibrate(toy, FINGER3)
    monkeypatch.setattr(on_hand, "_stages", lambda s, clock, nominal, cal, bias, *a: (bias, 0.0, []))
    with pytest.raises(GuardTripped, match="no room for the multisine") as exc:
        run_experiment(toy, FINGER3, ExperimentDesign(duration=1.0), cal, hold=0.3, max_holds=2)
    assert exc.value.reason == "stop"
    cmd = exc.value.log.command[:, 0]
    assert cmd[np.flatnonzero(~np.isnan(cmd))[-1]] == 0.0  # relaxed


def test_run_experiment_refuses_bad_settings_before_the_hand_moves():
    hw = Loopback()
    with pytest.raises(InputError, match="orientations: the experiment on the hand runs in one orientation"):
        run_experiment(hw, FINGER3, ExperimentDesign(orientations=((0, 0, -9.81), (0, 0, 9.81))))
    with pytest.raises(InputError, match="design: dt 0.002 s is not the hand's period 0.001 s"):
        run_experiment(hw, FINGER3, ExperimentDesign(dt=2e-3))
    with pytest.raises(InputError, match="stages: expected non-decreasing fractions"):
        run_experiment(hw, FINGER3, stages=(0.5, 0.25))
    with pytest.raises(InputError, match="hw: its motors thumb_flexion, thumb_abduction are not the model's"):
        run_experiment(Loopback(motor_names=("thumb_flexion", "thumb_abduction")), Model.alpes("thumb", friction=True))
    assert hw.commands.shape == (0, 1)  # nothing written


def test_experiment_on_the_standin_stays_off_its_stops_and_near_the_design(tmp_path):
    """finger3 with a real hand's effects (stiction, elastic cable with slack, 3 degree tilt, torque constant 5 %
    off, encoder offset, torque delay), shortened to keep the test short (a faster calibration, 1 s stages and
    record; the fit of the documented 4 s run on fresh draws is the benchmark's): the guard would have raised had
    the encoder left its band; the true joints (peeked at by the test only) stay off their stops; the record's mean
    reading is the nominal design's within what the 1 s stages' means resolve."""
    pytest.importorskip("mujoco")
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.estimation.experiments.experiment import _simulate
    from alpes_dyn.estimation.experiments.recording import read_recording
    from alpes_dyn.model.mjcf import joint_permutation

    hw = MujocoHand("finger3", seed=3)
    perm = joint_permutation(hw._plant.mj, list(FINGER3.joint_names))
    cal = calibrate(hw, FINGER3, rate=0.0125, speed=1500.0)
    assert cal.stop[0] and cal.low[0] < 3072 < cal.high[0]  # the design's target inside the usable range
    assert math.isnan(cal.fold_torque[0])  # q_1 sweeps its range over 0.006 N m, steep but stable: no fold
    design = ExperimentDesign(duration=1.0)
    q = []
    write = hw.write
    hw.write = lambda u: (write(u), q.append(hw._data.qpos[perm].copy()))
    res = run_experiment(hw, FINGER3, design, cal, path=tmp_path / "rec.csv", stage_seconds=1.0, stages=(0.5, 1.0))
    rec = read_recording(tmp_path / "rec.csv", FINGER3)
    assert rec.n_samples == 1001 and rec.encoder.shape == (1001, 1)
    assert cal.low[0] < rec.encoder.min() and rec.encoder.max() < cal.high[0]
    rows = res.record_rows  # the session's log row r is the state after its (r - 1)-th write
    q = np.degrees(np.array(q))[rows.start - 1: rows.stop - 1]
    assert q.min() > 3.0 and q.max() < 87.0  # no joint near a stop (0 and 90 degrees) during the record
    # the designed trajectory: the nominal finger under the same excitation about the nominal bias, from its rest
    # one stage (1 s) before the record (the multisine's transient spent), its mean over the record
    lead = slice(rows.start - 1000, rows.stop)
    u = res.log.command[lead] - res.bias + res.nominal_bias
    G = np.repeat(np.asarray(design.orientations, dtype=float), u.shape[0], axis=0)
    y_nom = 2 * _simulate(FINGER3, design, u, G, np.zeros(u.shape[0], dtype=int))[1000:, :3].sum(axis=1) * 4096 / (2 * np.pi)
    assert abs(rec.encoder.mean() - y_nom.mean()) < 150.0  # counts: 6.6 degrees of the joints' sum (1 count: 0.044 degree)
    # the band holds a third of the designed swing: palm up the finger is near its fold, where j1 turns fast per
    # count, and the joints' band (joint_stops.joint_band) ends where the family's softest member's j1 comes within
    # the design's margin of its stop; below on_hand.ROOM_SHARE a user turns the hand (bench_loop.run_rigs)
    assert 0.25 <= res.amplitude_scale <= 1.0
    # the recorded torque is the command held over each period, read at the next tick (the stand-in's is measured
    # DELAY_SAMPLES late: the fit's delay effect)
    from alpes_dyn.bench.effects import DELAY_SAMPLES

    cmd = res.log.command[res.record_rows, 0]
    lag = int(np.argmax([np.corrcoef(rec.torque[d:, 0], cmd[: cmd.size - d])[0, 1] for d in range(6)]))
    assert lag == DELAY_SAMPLES


def test_cli_design_only_writes_the_documented_profile(tmp_path, capsys):
    """``experiment --design-only`` (in this process: the exit at the process boundary is test_bad_input's) writes
    the designed torque profile."""
    from alpes_dyn.cli import main

    out = tmp_path / "torque.csv"
    assert main(["experiment", "--design-only", "--duration", "1", "-o", str(out), "--json"]) == 0
    obj = json.loads(capsys.readouterr().out)
    assert obj["columns"] == ["t", "torque_finger"] and obj["units"] == {"t": "s", "torque_finger": "N m"}
    assert obj["rate_hz"] == 1000.0 and obj["samples"] == 1001
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    assert out.read_text().splitlines()[0] == "t,torque_finger"
    t, u, target = designed_torque(FINGER3, ExperimentDesign(duration=1.0))
    np.testing.assert_allclose(data[:, 0], t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(data[:, 1], u[:, 0], rtol=1e-15, atol=0)
    assert obj["target_counts"]["finger"] == pytest.approx(target[0])


def test_calibration_type_checks():
    with pytest.raises(InputError, match="safe_torque: expected a torque in"):
        calibrate(ToyFinger(), FINGER3, safe_torque=0.5)
    with pytest.raises(InputError, match="hw: its motors thumb_flexion, thumb_abduction are not the model's finger"):
        calibrate(Loopback(motor_names=("thumb_flexion", "thumb_abduction")), FINGER3)
    assert isinstance(Calibration, type)


def test_cli_bench_guard_trip_is_exit_3_one_line_no_file(tmp_path, monkeypatch, capfd):
    """The CLI's side of a trip (the trip itself: the guard tests above, and the stand-in's folding draws): the
    calibration and the run replaced by a toy's, the run raising as the guard does."""
    pytest.importorskip("mujoco")
    from alpes_dyn import cli
    from alpes_dyn.estimation.experiments import calibration as calib_mod
    from alpes_dyn.estimation.experiments import turned as turned_mod
    from alpes_dyn.estimation.experiments.hand_session import SessionLog

    def tripped(*a, **kw):
        raise GuardTripped("guard: motor finger: encoder at 4695 counts left the guard band [2055, 4678]", "stop",
                           1.0, np.array([4695.0]), SessionLog(*(np.zeros((1, 1)),) * 5))

    monkeypatch.setattr(calib_mod, "calibrate", lambda hw, model, **kw: None)
    monkeypatch.setattr(turned_mod, "run_experiment", tripped)  # the CLI's run: turned.run_turned, one rig
    out = tmp_path / "rec.csv"
    code = cli.main(["experiment", "--bench", "mujoco", "-o", str(out)])
    _, err = capfd.readouterr()
    assert code == 3 and not out.exists()
    assert err.count("\n") == 1 and "experiment stopped: rig level: guard: motor finger: encoder at 4695" in err
