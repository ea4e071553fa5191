"""Models, state spaces, observers and compiled roll-outs pickle and deep-copy by their description
(alpes_dyn.rebuild), and compute the same numbers after the round trip."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.observers.observers import make_observer
from alpes_dyn.model.spec import example_spec_path
from alpes_dyn.simulation.integrate import compile_rollout
from alpes_dyn.symbolic.statespace import StateSpace


def _allegro():
    from alpes_dyn.model.description import example_robot_urdf

    return ad.Model(example_robot_urdf("allegro_right_hand"), example_spec_path("allegro_hand"))


MODELS = {
    "finger3": lambda: ad.Model.alpes("finger3", friction=True, rotor_inertia=True),
    "index": lambda: ad.Model.alpes("finger3", chain="index"),
    "hand": lambda: ad.Model.alpes("hand"),
    "tilted": lambda: ad.Model.alpes("finger2").copy(gravity=[0.0, 1.0, -9.76]),
}


@pytest.mark.parametrize("name", sorted(MODELS))
@pytest.mark.parametrize("clone", ["pickle", "deepcopy"])
def test_model_round_trip(name, clone):
    m = MODELS[name]()
    c = pickle.loads(pickle.dumps(m)) if clone == "pickle" else copy.deepcopy(m)
    assert c is not m and c.pin_data is not m.pin_data
    rng = np.random.default_rng(3)
    q, v, tau = rng.uniform(0.1, 1.0, (3, m.n))
    for f in ("inertia_matrix", "gravity_torque"):
        np.testing.assert_array_equal(getattr(c, f)(q), getattr(m, f)(q))
    np.testing.assert_array_equal(c.forward_dynamics(q, v, tau), m.forward_dynamics(q, v, tau))
    assert (c.name, c.joint_names, c.tips, c.chain) == (m.name, m.joint_names, m.tips, m.chain)
    np.testing.assert_array_equal(c.gravity, m.gravity)
    if m.transmission is not None:
        np.testing.assert_array_equal(c.transmission.S, m.transmission.S)


def test_urdf_model_with_spec_round_trip():
    pytest.importorskip("example_robot_data")
    m = _allegro()
    c = pickle.loads(pickle.dumps(m))
    q = np.linspace(0.1, 0.5, m.n)
    np.testing.assert_array_equal(c.gravity_torque(q), m.gravity_torque(q))
    np.testing.assert_array_equal(c.transmission.S, m.transmission.S)


def test_statespace_and_observer_round_trip():
    m = ad.Model.alpes("finger3")
    ss = StateSpace(m, input="motor", output="encoder")
    ss2 = pickle.loads(pickle.dumps(ss))
    x, u = np.array([0.3, 0.5, 0.4, 0.1, -0.2, 0.3]), np.array([0.02])
    np.testing.assert_array_equal(np.asarray(ss2.f(x, u)), np.asarray(ss.f(x, u)))
    assert ss2.input_names == ss.input_names and ss2.output_names == ss.output_names
    for kind in ("ekf", "ukf-params"):
        n_par = 2 if kind.endswith("params") else 0
        f = make_observer(kind, ss, 1e-3, process_noise=[1e-18] * 3 + [4e-8] * 3 + [1e-10] * n_par,
                          measurement_noise=[1e-6], input_noise=[2.5e-7], **({"alpha": 0.5} if "ukf" in kind else {}))
        g = copy.deepcopy(f)
        assert type(g) is type(f) and g.model.parameters == f.model.parameters
        rng = np.random.default_rng(0)
        W = 0.02 + 1e-3 * rng.standard_normal((50, 1))
        Y = 0.01 * rng.standard_normal((51, 1))
        z0 = np.concatenate([[0.3, 0.8, 0.7, 0, 0, 0], np.ones(n_par)])
        P0 = [0.25] * 3 + [1.0] * 3 + [0.04] * n_par
        np.testing.assert_array_equal(g.run(z0, P0, W, Y).z, f.run(z0, P0, W, Y).z)


def test_compiled_rollout_round_trip():
    ro = compile_rollout(ad.Model.alpes("finger2"), 1e-3, input="motor", threads=1)
    ro2 = pickle.loads(pickle.dumps(ro))
    X0 = np.array([[0.3, 0.5, 0.0, 0.0], [0.2, 0.4, 0.1, 0.0]])
    U = np.full((2, 20, 1), 0.02)
    np.testing.assert_array_equal(ro2.rollout(X0, U), ro.rollout(X0, U))
