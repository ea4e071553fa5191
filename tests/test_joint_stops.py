"""The joints' own stops as a bound on the encoder (estimation/experiments/joint_stops.joint_band) and the guard of
the experiment on the hand that uses it (on_hand.run_experiment's band).

References: the model's static equilibrium solved directly by bisection on the motor torque (no sweep, no stop
held) at the named joint's margin; the MuJoCo stand-in's true joints (read by the test only, scoring_truth).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import alpes_dyn.estimation.experiments.joint_stops as joint_stops
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.trim import _mean_equilibrium, _reading
from alpes_dyn.model.robot import Model

FINGER2 = Model.alpes("finger2", friction=True)
MARGIN = math.radians(3.0)
TAU_MAX = 0.05


def _counts(model: Model, q: np.ndarray) -> float:
    return float(np.atleast_1d(_reading(model, q))[0]) * model.transmission.counts_per_rev / (2 * np.pi)


def test_upper_bound_is_where_the_joint_reaches_its_margin(monkeypatch):
    """The nominal finger alone: ``high`` is the reading at which the named joint comes within MARGIN of its upper
    stop, the sweep's first torque past it (conservative by at most one step of the sweep)."""
    monkeypatch.setattr(joint_stops, "FAMILY_DRAWS", 0)
    g = FINGER2.gravity
    low, high, who = joint_stops.joint_band(FINGER2, g, MARGIN, TAU_MAX)
    j = FINGER2.joint_names.index(who[1])
    a, b = 0.0, TAU_MAX  # bisection: q_j(tau) = upper - margin, the other joints off their stops there
    for _ in range(60):
        mid = 0.5 * (a + b)
        a, b = (mid, b) if _mean_equilibrium(FINGER2, mid, g)[j] < FINGER2.upper[j] - MARGIN else (a, mid)
    q = _mean_equilibrium(FINGER2, b, g)
    assert np.all(q <= FINGER2.upper + 1e-9) and np.all(q >= FINGER2.lower - 1e-9)
    ref = _counts(FINGER2, q)
    step = TAU_MAX / (joint_stops.SWEEP_POINTS - 1)
    slack = _counts(FINGER2, _mean_equilibrium(FINGER2, b + step, g)) - ref
    assert ref - 1e-6 <= high[0] <= ref + slack + 1e-6
    assert low[0] < high[0] and who[0] in FINGER2.joint_names


def test_family_bound_is_inside_the_nominal_one(monkeypatch):
    """The tolerance family's band lies inside the nominal finger's (the bound over all its members)."""
    monkeypatch.setattr(joint_stops, "FAMILY_DRAWS", 0)
    lo0, hi0, _ = joint_stops.joint_band(FINGER2, FINGER2.gravity, MARGIN, TAU_MAX)
    monkeypatch.setattr(joint_stops, "FAMILY_DRAWS", 3)
    lo, hi, _ = joint_stops.joint_band(FINGER2, FINGER2.gravity, MARGIN, TAU_MAX)
    assert lo0[0] <= lo[0] < hi[0] <= hi0[0]


@pytest.mark.parametrize("model, margin, tau_max, match", [
    (Model.alpes("thumb", friction=True), MARGIN, TAU_MAX, "^nominal: the joints' stops are bounded for a finger of one motor$"),
    (FINGER2, -1.0, TAU_MAX, "^margin: expected a positive number, got -1.0$"),
    (FINGER2, MARGIN, float("nan"), "^tau_max: expected a positive number, got nan$"),
    (FINGER2, True, TAU_MAX, "^margin: expected a positive number, got True$"),
])
def test_bad_input(model, margin, tau_max, match):
    with pytest.raises(InputError, match=match):
        joint_stops.joint_band(model, FINGER2.gravity, margin, tau_max)
