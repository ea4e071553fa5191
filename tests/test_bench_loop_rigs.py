"""benchmarks/bench_loop.py's rig rule (on_hand.ROOM_SHARE, on_hand.roomier): palm up first; hung fingers down too
where palm up found no room or left less than ROOM_SHARE of the designed amplitude; of two runs the roomier kept.

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
