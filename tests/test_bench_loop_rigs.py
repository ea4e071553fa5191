"""benchmarks/bench_loop.py's rig rule (on_hand.ROOM_SHARE, on_hand.roomier): palm up first; hung fingers down too
where palm up found no room or left less than ROOM_SHARE of the designed amplitude; of two runs the roomier kept.
finger3 (TURNED) recorded in both rigs through the public turned.run_turned, a rig whose guard trips dropped.

The stand-in and the experiment are replaced by fakes whose amplitude scale the test sets (the rule is the
benchmark's bookkeeping; the experiment itself is tested in test_on_hand.py and test_joint_stops.py).
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import numpy as np
import pytest

from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.hand_session import GuardTripped
from alpes_dyn.estimation.experiments.on_hand import ROOM_SHARE, OnHandResult, roomier

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _result(scale: float) -> OnHandResult:
    """A run that recorded ``scale`` of the designed amplitude (the fields the rule does not read left empty)."""
    return OnHandResult(None, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), scale, [], False, None, None,
                        slice(0, 0), [])


def test_roomier_keeps_the_larger_amplitude_and_the_first_on_a_tie():
    a, b = _result(0.22), _result(1.0)
    assert roomier(a, b) is b and roomier(b, a) is b
    c = _result(0.22)
    assert roomier(a, c) is a
    with pytest.raises(InputError, match="^b: expected an OnHandResult, got float$"):
        roomier(a, 1.0)


@pytest.fixture()
def bench_loop(monkeypatch):
    sys.path.insert(0, str(BENCH))
    try:
        mod = importlib.import_module("bench_loop")
    finally:
        sys.path.remove(str(BENCH))
    return mod


@pytest.mark.parametrize("level, hanging, kept", [
    (1.0, 1.0, "level"),           # room palm up: the hand not turned
    (ROOM_SHARE, 1.0, "level"),    # exactly the share: enough
    (0.22, 1.0, "hanging"),        # the silent miss of the issue: turned, the roomier kept
    (0.22, 0.1, "level"),          # turned, but hung is tighter: palm up kept
    (None, 0.6, "hanging"),        # no room palm up (the guard tripped): hung
    (0.3, None, "level"),          # hung tripped: palm up's small run kept
])
def test_rig_rule(bench_loop, monkeypatch, tmp_path, level, hanging, kept):
    scales = {"level": level, "hanging": hanging}
    calls = []

    class Hand:
        def __init__(self, model, truth, scene, seed, rig):
            self.rig = rig

    def experiment(hw, nominal, design):
        calls.append(hw.hw.rig)
        if scales[hw.hw.rig] is None:
            raise GuardTripped("guard: no room", "stop", 0.0, np.zeros(1), None)
        return _result(scales[hw.hw.rig])

    class Scored:
        def __init__(self, hw):
            self.hw, self.q = hw, []

    monkeypatch.setattr(bench_loop, "MujocoHand", Hand)
    monkeypatch.setattr(bench_loop, "Scored", Scored)
    monkeypatch.setattr(bench_loop, "run_experiment", experiment)
    got, tried = bench_loop.run_rigs("finger3", None, 1, None)
    turned = level is None or level < ROOM_SHARE
    assert calls == (["level", "hanging"] if turned else ["level"])
    assert got[0] == kept and got[2].amplitude_scale == scales[kept]
    assert len(tried) == (0 if not turned else 1 if None in (level, hanging) else 2 if kept == "level" else 1)


def test_finger3_is_recorded_in_both_rigs_and_joined(bench_loop, monkeypatch, tmp_path):
    """finger3 (bench_loop.TURNED) runs palm up and hung (the hung run's noise its own seed), the recordings joined
    as two runs, each with its gravity (the palm-up one's the file's, the hung one's as recorded): in one
    orientation finger3's masses trade with its cable's compliance (up to 5 % off at a 1 % standard error on the
    hand's record, under 1.1 % joined: the TURNED docstring). finger2 keeps the rig rule: one rig."""
    from alpes_dyn.estimation.experiments.recording import Recording, read_recording
    from alpes_dyn.model.robot import Model
    from alpes_dyn.estimation.experiments.turned import rig_design

    seeds, n = [], 200

    class Hand:
        def __init__(self, model, truth, scene, seed, rig):
            self.rig, nominal = rig, Model.alpes(model)
            seeds.append((rig, seed))
            self.q = [0.5 * (nominal.lower + nominal.upper)] * (n + 1)

    def experiment(hw, nominal, design):
        g = np.asarray(design.orientations[0], dtype=float)
        rec = Recording(t=1e-3 * np.arange(n), encoder=np.round(100 * np.sin(np.arange(n) / 9.0))[:, None],
                        torque=0.01 + 0.005 * np.sin(np.arange(n) / 9.0)[:, None], motor_names=nominal.transmission.motor_names,
                        joint_names=nominal.joint_names,
                        gravity=None if np.array_equal(g, nominal.gravity) else np.repeat(g[None], n, 0))
        res = _result(1.0)
        return OnHandResult(rec, *[getattr(res, f) for f in ("bias", "nominal_bias", "target", "rest_counts")], 1.0,
                            [], False, None, type("Log", (), {"t": np.zeros(n)})(), slice(0, n), [])

    class Scored:
        def __init__(self, hw):
            self.hw, self.q = hw, hw.q

    from alpes_dyn.estimation.experiments import turned

    monkeypatch.setattr(bench_loop, "MujocoHand", Hand)
    monkeypatch.setattr(bench_loop, "Scored", Scored)
    monkeypatch.setattr(turned, "run_experiment", experiment)  # the public turned experiment's (bench_loop's own: finger2)
    monkeypatch.setattr(bench_loop, "run_experiment", experiment)
    row, path = bench_loop.experiment_row("finger3", None, 7, tmp_path)
    assert seeds == [("level", 7), ("hanging", 8)] and row["rig"] == "level+hanging"
    assert [x["rig"] for x in row["runs"]] == ["level", "hanging"] and row["stop_reached"] is False
    rec = read_recording(path, Model.alpes("finger3"))
    assert rec.run.tolist() == [0] * n + [1] * n
    g0 = np.asarray(Model.alpes("finger3").gravity, dtype=float)
    g1 = np.asarray(rig_design("hanging").orientations[0], dtype=float)
    np.testing.assert_allclose(rec.gravity[:n], np.tile(g0, (n, 1)), atol=1e-12)
    np.testing.assert_allclose(rec.gravity[n:], np.tile(g1, (n, 1)), atol=1e-12)
    seeds.clear()
    row, _ = bench_loop.experiment_row("finger2", None, 7, tmp_path)
    assert seeds == [("level", 7)] and row["rig"] == "level" and "runs" not in row


@pytest.mark.parametrize("trips, kept, tried", [
    ((), ["level", "hanging"], []),
    (("level",), ["hanging"], ["level"]),   # palm up's guard tripped (the fold): hung alone, its own seed
    (("hanging",), ["level"], ["hanging"]),  # hung tripped: palm up's run kept
    (("level", "hanging"), [], ["level", "hanging"]),
])
def test_turned_falls_back_to_the_rig_that_recorded(bench_loop, monkeypatch, trips, kept, tried):
    """bench_loop.run_turned through the public turned.run_turned: a rig whose guard trips (RigTripped) is dropped,
    the other kept, each stand-in seeded the draw's seed plus its rig's index and closed after its run."""
    from alpes_dyn.estimation.experiments import turned

    made = []

    class Hand:
        def __init__(self, model, truth, scene, seed, rig):
            self.rig, self.seed, self.closed = rig, seed, False
            made.append(self)

        def close(self):
            self.closed = True

    class Scored:
        def __init__(self, hw):
            self.hw = hw

        def close(self):
            self.hw.close()

    def experiment(hw, nominal, design, **kw):
        if hw.hw.rig in trips:
            raise GuardTripped(f"guard: {hw.hw.rig} tripped", "stop", 0.0, np.zeros(1), None)
        return _result(1.0)

    monkeypatch.setattr(bench_loop, "MujocoHand", Hand)
    monkeypatch.setattr(bench_loop, "Scored", Scored)
    monkeypatch.setattr(turned, "run_experiment", experiment)
    monkeypatch.setattr(turned, "joined_runs", lambda runs, nominal: None)  # the fakes record nothing to join
    from alpes_dyn.model.robot import Model

    runs, why = bench_loop.run_turned("finger3", None, 7, Model.alpes("finger3", friction=True))
    assert [r for r, _, _ in runs] == kept and [w.split(":")[0] for w in why] == tried
    assert all(w.endswith(f"guard: {w.split(':')[0]} tripped") for w in why)
    assert [(h.rig, h.seed) for h in made] == [(r, 7 + ("level", "hanging").index(r)) for r in
                                               ("level", "hanging")] and all(h.closed for h in made)


def test_turned_stops_on_a_rigs_other_error(bench_loop, monkeypatch):
    """An error of a rig's run that is not a guard trip (its settings: no encoder counts left) stops the turned
    experiment as it stops ``experiment --rig both``: no run, the rig named with the error (the row's
    experiment_error), the next rig never turned to."""
    from alpes_dyn.estimation.experiments import turned
    from alpes_dyn.model.robot import Model

    made = []

    class Hand:
        def __init__(self, model, truth, scene, seed, rig):
            self.rig = rig
            made.append(rig)

        def close(self):
            pass

    class Scored:
        def __init__(self, hw):
            self.hw = hw

        def close(self):
            self.hw.close()

    def experiment(hw, nominal, design, **kw):
        raise InputError("margin: no encoder counts for the excitation")

    monkeypatch.setattr(bench_loop, "MujocoHand", Hand)
    monkeypatch.setattr(bench_loop, "Scored", Scored)
    monkeypatch.setattr(turned, "run_experiment", experiment)
    runs, why = bench_loop.run_turned("finger3", None, 7, Model.alpes("finger3", friction=True))
    assert runs == [] and why == ["level: margin: no encoder counts for the excitation"] and made == ["level"]
