"""The experiment turned (estimation.experiments.turned.run_turned, issue 49): palm up then hung fingers down on the
MuJoCo stand-in, the runs joined with their gravity; a guard trip names its rig and joins nothing. Shortened
(0.5 s records, two 1 s stages); the fit of the documented runs is benchmarks/bench_loop.py's."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("mujoco")

from alpes_dyn.bench.interface import Reading  # noqa: E402
from alpes_dyn.bench.mujoco_hand import MujocoHand  # noqa: E402
from alpes_dyn.estimation.experiments.design import ExperimentDesign  # noqa: E402
from alpes_dyn.estimation.experiments.hand_session import GuardTripped  # noqa: E402
from alpes_dyn.estimation.experiments.recording import read_recording  # noqa: E402
from alpes_dyn.estimation.experiments.turned import RigTripped, run_turned  # noqa: E402
from alpes_dyn.model.robot import Model  # noqa: E402

FINGER3 = Model.alpes("finger3", friction=True)
FAST = {"stages": (0.5, 1.0), "stage_seconds": 1.0}


class Closing:
    """The stand-in, its close counted and its time stamps optionally skipping ``gap`` s after ``after`` reads (a
    loop that missed its period)."""

    def __init__(self, hw: MujocoHand, after: int | None = None, gap: float = 0.0) -> None:
        self.hw, self.after, self.gap, self.reads, self.closed = hw, after, gap, 0, 0
        self.period, self.motor_names = hw.period, hw.motor_names
        self.counts_per_rev, self.tau_max = hw.counts_per_rev, hw.tau_max

    def read(self) -> Reading:
        r = self.hw.read()
        self.reads += 1
        late = self.after is not None and self.reads > self.after
        return Reading(r.t + (self.gap if late else 0.0), r.counts, r.torque, r.force)

    def write(self, command) -> None:
        self.hw.write(command)

    def close(self) -> None:
        self.closed += 1
        self.hw.close()


@pytest.fixture(scope="module")
def turned(tmp_path_factory):
    asked = []

    def hand_in(rig):
        asked.append(Closing(MujocoHand("finger3", seed=3 + len(asked), rig=rig)))
        asked[-1].rig = rig
        return asked[-1]

    path = tmp_path_factory.mktemp("turned") / "rec.csv"
    res = run_turned(hand_in, FINGER3, ExperimentDesign(duration=0.5), path=path, **FAST)
    return res, asked, path


def test_two_runs_joined_with_their_gravity(turned):
    res, asked, path = turned
    assert res.rigs == ("level", "hanging") and [h.rig for h in asked] == ["level", "hanging"]
    assert [h.closed for h in asked] == [1, 1]  # each hand closed after its rig
    rec = read_recording(path, FINGER3)
    n = 501
    assert rec.n_samples == 2 * n and rec.run.tolist() == [0] * n + [1] * n
    np.testing.assert_array_equal(rec.encoder, res.recording.encoder)
    for k, run in enumerate(res.runs):  # each run's own recording, as recorded
        np.testing.assert_array_equal(rec.encoder[k * n:(k + 1) * n], run.recording.encoder)
        np.testing.assert_allclose(rec.torque[k * n:(k + 1) * n], run.recording.torque, rtol=1e-12)
    # palm up: the file's gravity written in; hung: turned by -90 degrees about the joints' axes (y), by hand:
    # R_y(-pi/2) (0, 0, -g) = (g, 0, 0), a quarter turn from palm up
    g = 9.81
    np.testing.assert_allclose(rec.gravity[:n], np.tile([0.0, 0.0, -g], (n, 1)), atol=1e-12)
    np.testing.assert_allclose(rec.gravity[n:], np.tile([g, 0.0, 0.0], (n, 1)), atol=1e-9)
    cos = rec.gravity[0] @ rec.gravity[-1] / g**2
    assert math.degrees(math.acos(cos)) == pytest.approx(90.0, abs=1e-6)
    # each rig calibrated in its own orientation: hung, the springs hold the finger straight (rest near 0 counts,
    # no joint on a stop at 0 N m) and its range is wider than palm up's (gravity along the finger, no fold)
    lv, hg = (r.calibration for r in res.runs)
    assert hg.high[0] - hg.low[0] > lv.high[0] - lv.low[0]
    assert all(0.0 < r.amplitude_scale <= 1.0 for r in res.runs)
    d = res.to_dict()
    assert [x["rig"] for x in d] == ["level", "hanging"]
    assert {"calibration", "bias_nm", "amplitude_scale", "trim_holds"} <= set(d[0])


def test_a_guard_trip_names_its_rig_and_joins_nothing(tmp_path):
    """Hung first, its loop missing a period during its calibration: RigTripped (a GuardTripped) naming the rig, no
    run before it, the hung hand closed, palm up never asked for, no file."""
    asked = []

    def hand_in(rig):
        after = 50 if rig == "hanging" else None
        asked.append(Closing(MujocoHand("finger3", seed=11, rig=rig), after=after, gap=0.01))
        return asked[-1]

    path = tmp_path / "rec.csv"
    with pytest.raises(RigTripped, match=r"^rig hanging: .*period") as e:
        run_turned(hand_in, FINGER3, ExperimentDesign(duration=0.5), ("hanging", "level"), path=path, **FAST)
    assert isinstance(e.value, GuardTripped) and e.value.rig == "hanging" and e.value.reason == "period"
    assert e.value.runs == [] and len(asked) == 1 and asked[0].closed == 1  # the level hand never asked for
    assert not path.exists()


def test_keep_going_where_every_rig_trips_names_each(tmp_path):
    """keep_going, both rigs' loops missing a period: the last rig's RigTripped, the earlier rig's trip in its
    ``tripped`` (the benchmark and the CLI name every rig left out), both hands closed, no file."""
    asked = []

    def hand_in(rig):
        asked.append(Closing(MujocoHand("finger3", seed=11, rig=rig), after=50, gap=0.01))
        return asked[-1]

    path = tmp_path / "rec.csv"
    with pytest.raises(RigTripped, match=r"^rig level: .*period") as e:
        run_turned(hand_in, FINGER3, ExperimentDesign(duration=0.5), ("hanging", "level"), path=path,
                   keep_going=True, **FAST)
    assert e.value.rig == "level" and e.value.runs == []
    assert [rig for rig, _ in e.value.tripped] == ["hanging"] and "period" in e.value.tripped[0][1]
    assert [h.closed for h in asked] == [1, 1] and not path.exists()
