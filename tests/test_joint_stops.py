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


def _narrowed_standin(upper: float):
    """finger3's stand-in (every effect of a real hand) and the nominal model, both with joint j2's upper stop at
    ``upper`` rad (the others at 90 degrees): j2 reaches its stop while the encoder still rises."""
    from alpes_dyn.bench.mujoco_hand import MujocoHand
    from alpes_dyn.model.mjcf import joint_permutation

    nominal = Model.alpes("finger3", friction=True)
    nominal.pin_model.upperPositionLimit[1] = upper
    hw = MujocoHand("finger3", seed=3)
    mj = hw._plant.mj
    mj.jnt_range[mj.dof_jntid[joint_permutation(mj, list(nominal.joint_names))[1]]][1] = upper
    return hw, nominal


class _Hit(Exception):
    """The test's peek saw a joint at its stop."""


def _run(hw, nominal, cal, monkeypatch, guard: bool):
    """The shortened experiment on ``hw``; the true joints after every write (the test's peek), deg, and the
    result or the guard's trip."""
    import alpes_dyn.estimation.experiments.on_hand as on_hand
    from alpes_dyn.bench.mujoco_hand import scoring_truth
    from alpes_dyn.estimation.experiments.design import ExperimentDesign
    from alpes_dyn.estimation.experiments.hand_session import GuardTripped

    if not guard:  # the encoder's band alone, as before the joints' stops bounded it
        monkeypatch.setattr(on_hand, "joint_band", lambda *a: (np.array([-np.inf]), np.array([np.inf]), ["", ""]))
    q, write = [], hw.write

    def peek(u):
        write(u)
        q.append(scoring_truth(hw)[0])
        if not guard and q[-1][1] > nominal.upper[1] - math.radians(0.5):
            raise _Hit  # the stop reached: the rest of this run is not needed

    hw.write = peek
    try:
        out = on_hand.run_experiment(hw, nominal, ExperimentDesign(duration=1.0), cal, stage_seconds=1.0,
                                     stages=(0.5, 1.0), hold=0.5, max_holds=3)
    except (GuardTripped, _Hit) as e:
        out = e
    monkeypatch.undo()
    return np.degrees(np.array(q)), out


def test_guard_keeps_a_joint_off_its_own_stop_on_the_standin(monkeypatch):
    """j2's stop at 55 degrees, the encoder's calibrated range unchanged by it (the other joints go on): with the
    encoder's band alone the experiment drives j2 onto its stop (the stand-in's truth, read by the test only); with
    the joints' band no true joint comes within 0.5 degree of it, whether the run completes at a smaller amplitude
    or the guard stops it (the finger relaxed)."""
    pytest.importorskip("mujoco")
    from alpes_dyn.estimation.experiments.calibration import calibrate

    upper = math.radians(55.0)
    hw, nominal = _narrowed_standin(upper)
    cal = calibrate(hw, nominal, rate=0.0125, speed=1500.0)
    q, out = _run(*_narrowed_standin(upper), cal, monkeypatch, guard=False)
    assert isinstance(out, _Hit) and q[:, 1].max() > 55.0 - 0.5  # a joint would hit its stop
    q, out = _run(*_narrowed_standin(upper), cal, monkeypatch, guard=True)
    assert q[:, 1].max() < 55.0 - 0.5 and q[:, [0, 2]].max() < 90.0 - 0.5
    if not hasattr(out, "amplitude_scale"):  # stopped by the guard: the finger relaxed
        cmd = out.log.command[:, 0]
        assert out.reason == "stop" and cmd[np.flatnonzero(~np.isnan(cmd))[-1]] == 0.0
