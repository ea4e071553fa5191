"""The state space x' = f(x, u[, F]), y = h(x) (report eq. 3.1-3.3, 3.11, 3.13, 3.16).

The symbolic f (CasADi SX from ADAM) is checked against the numeric one (Pinocchio ABA), two independent
rigid-body codes, on finger3 (with every extra switched on), the hand and a UR5 of example-robot-data.
The input and output maps are checked against the report's formulas with the transmission ratio read
straight from the parameter file.
"""

from __future__ import annotations

import functools
import tomllib

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.params import default_params_path
from alpes_dyn.symbolic.statespace import StateSpace

RAW = tomllib.loads(default_params_path().read_text())
RATIO = RAW["finger"]["r"]["value"] / RAW["transmission"]["r_m"]["value"]  # r / r_m (Section 3)


@functools.lru_cache(maxsize=None)
def space(name: str, **kw) -> StateSpace:
    if name == "ur5":
        m = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"))
        return StateSpace(m, output=np.eye(m.n)[:2])
    extra = kw.pop("extra", False)
    m = ad.Model.alpes(name, friction=extra, rotor_inertia=extra)
    return StateSpace(m, **kw)


def sym_f(ss: StateSpace, x, u, F=None) -> np.ndarray:
    args = [x, u] + ([F] if F is not None else [])
    return np.asarray(ss.f_function(*args)).reshape(-1)


@pytest.mark.parametrize("name,kw", [
    ("finger3", {}),
    ("finger3", {"extra": True, "force": True}),
    ("finger3", {"input": "motor", "output": "encoder"}),
    ("hand", {}),
    ("hand", {"input": "motor"}),
    ("ur5", {}),
])
def test_symbolic_f_matches_pinocchio(name, kw, rng):
    ss = space(name, **kw)
    worst = 0.0
    for _ in range(10):
        q, v = ss.model.random_state(rng)
        x = np.concatenate([q, v])
        u = rng.normal(scale=0.05, size=ss.n_inputs)
        F = rng.normal(scale=0.5, size=3) if ss.force else None
        a, b = sym_f(ss, x, u, F), ss.f(x, u, F)
        assert a.shape == b.shape == (ss.n_states,)
        assert np.array_equal(b[: ss.n], v)  # x1' = x2 (eq. 3.3)
        worst = max(worst, float(np.max(np.abs(a - b)) / max(1.0, np.max(np.abs(b)))))
        assert np.allclose(np.asarray(ss.h_function(x)).reshape(-1), ss.h(x), rtol=0, atol=1e-15)
    assert worst <= 1e-9


def test_outputs_are_the_reports(rng):
    """y = q1 + q2 + q3 (eq. 3.3), q_m = (r / r_m)(q1 + q2 + q3) (Section 3, eq. 3.13)."""
    m = ad.Model.alpes("finger3")
    x = rng.normal(size=6)
    assert StateSpace(m).h(x) == pytest.approx([x[:3].sum()], rel=1e-15)
    assert StateSpace(m, output="encoder").h(x) == pytest.approx([RATIO * x[:3].sum()], rel=1e-15)
    assert np.allclose(StateSpace(ad.Model.alpes("finger2")).h(x[:4]), [x[0] + x[1]], rtol=1e-15)
    cal = StateSpace(m, output=lambda q, xp: xp.sin(q[0]) + q[2] ** 2)
    assert cal.n_outputs == 1
    assert float(cal.h_function(x)) == pytest.approx(np.sin(x[0]) + x[2] ** 2, rel=1e-15)


def test_hand_outputs_per_motor(rng):
    """Six encoders: one per finger (sum of its three joints), thumb flexion (j1 + j2), thumb ab/adduction."""
    ss = StateSpace(ad.Model.alpes("hand"), output="encoder")
    names = ss.model.joint_names
    q = rng.normal(size=15)
    y = ss.h(np.concatenate([q, np.zeros(15)]))
    idx = {j: i for i, j in enumerate(names)}
    expect = [RATIO * sum(q[idx[f"{f}_j{k}"]] for k in (1, 2, 3)) for f in ("index", "middle", "ring", "little")]
    expect += [RATIO * (q[idx["thumb_j1"]] + q[idx["thumb_j2"]]), RAW["transmission"]["abduction_ratio"]["value"]
               * q[idx["thumb_abd"]]]
    assert ss.n_outputs == 6
    assert np.allclose(y, expect, rtol=1e-15, atol=0)


def test_motor_input_is_the_tendon(rng):
    """One motor torque tau_m drives the finger's joints with Gamma = (r / r_m) tau_m on each (power balance)."""
    joint, motor = space("finger3"), space("finger3", input="motor", output="encoder")
    assert motor.n_inputs == 1
    q, v = joint.model.random_state(rng)
    x = np.concatenate([q, v])
    tau_m = 0.013
    assert np.allclose(motor.f(x, [tau_m]), joint.f(x, RATIO * tau_m * np.ones(3)), rtol=1e-14, atol=1e-12)
    assert np.allclose(sym_f(motor, x, [tau_m]), joint.f(x, RATIO * tau_m * np.ones(3)), rtol=1e-9, atol=1e-9)


def test_bad_input():
    m = ad.Model.alpes("finger3")
    with pytest.raises(ad.ModelError, match=r"unknown input 'current'"):
        StateSpace(m, input="current")
    with pytest.raises(ad.ModelError, match=r"unknown output 'tip'"):
        StateSpace(m, output="tip")
    with pytest.raises(ad.ModelError, match=r"output matrix: expected a finite \(p, 3\) or \(p, 6\) array, got shape \(1, 2\)"):
        StateSpace(m, output=np.ones((1, 2)))
    ur = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"))
    with pytest.raises(ad.ModelError, match=r"input 'motor' needs a tendon transmission"):
        StateSpace(ur, input="motor", output=np.eye(6)[:1])
    ss = space("finger3")
    with pytest.raises(ad.InputError, match=r"x: expected shape \(6,\), got \(5,\)"):
        ss.f(np.zeros(5), np.zeros(3))
    with pytest.raises(ad.InputError, match=r"u: expected shape \(3,\), got \(1,\)"):
        ss.f(np.zeros(6), np.zeros(1))
    with pytest.raises(ad.InputError, match=r"x: contains NaN"):
        ss.h(np.array([0, 0, np.nan, 0, 0, 0]))
