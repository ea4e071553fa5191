"""A model's numbers as an input of the compiled code (issue 20): one library per structure, not per value.

References: closed forms for the lifted functions and the compiled loop (a * sin x + b * x, the linear recursion
x_k+1 = a x_k + b w_k); for the EKF, the same filter with its numbers as literals (``filter_step``, CasADi's VM) on
the default scenario's record, and the library's file in the cache.
"""

from __future__ import annotations

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.estimation.experiments.experiment import perturbed_params
from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter, UnscentedKalmanFilter
from alpes_dyn.simulation.codegen import CompiledStepLoop
from alpes_dyn.symbolic.lifted import lift_constants
from alpes_dyn.symbolic.statespace import StateSpace


def _code(f: cs.Function) -> str:
    cg = cs.CodeGenerator("f.c", {"with_header": False})
    cg.add(f)
    return cg.dump()


def test_lifted_function_is_the_function_with_its_constants_as_input():
    x = cs.SX.sym("x")
    f = cs.Function("f", [x], [2.5 * cs.sin(x) + 2.5 * x])  # one constant node, used twice
    g = cs.Function("f", [x], [2.5 * cs.sin(x) + 3.5 * x])  # two: the same structure
    fp, fv = lift_constants(f)
    gp, gv = lift_constants(g)
    assert fp.n_in() == 2 and fp.name_in(1) == "p"
    np.testing.assert_array_equal(fv, [2.5, 2.5])  # one entry per use
    np.testing.assert_array_equal(gv, [2.5, 3.5])
    for v in (0.3, -1.7):
        assert float(fp(v, fv)) == float(f(v)) and float(gp(v, gv)) == float(g(v))  # the same operations: same bits
        assert float(fp(v, [3.0, -4.0])) == pytest.approx(3.0 * np.sin(v) - 4.0 * v, rel=1e-15)
    assert _code(fp) == _code(gp)  # the same C, whatever the values
    assert _code(f) != _code(g)


def test_lift_refuses_what_is_not_an_sx_function():
    x = cs.MX.sym("x")
    with pytest.raises(ModelError, match="lift_constants: expected an SX casadi.Function, got Function"):
        lift_constants(cs.Function("f", [x], [2 * x]))
    with pytest.raises(ModelError, match="lift_constants: expected an SX casadi.Function, got str"):
        lift_constants("f")


def test_compiled_loop_reads_its_parameters_and_shares_its_library():
    """x_k+1 = a x_k + b w_k: two loops of other (a, b) load one library; each follows its own closed form."""
    x, w = cs.SX.sym("x"), cs.SX.sym("w")
    step, values = lift_constants(cs.Function("lin", [x, w], [0.9 * x + 0.05 * w]))
    np.testing.assert_array_equal(values, [0.9, 0.05])
    one = CompiledStepLoop(step, "t_lifted", threads=1, parameters=values)
    two = CompiledStepLoop(step, "t_lifted", threads=2, parameters=[0.5, 2.0])
    assert two.library == one.library and not two.compiled
    W = np.random.default_rng(0).standard_normal((3, 40, 1))
    for loop, (a, b) in ((one, (0.9, 0.05)), (two, (0.5, 2.0))):
        X = loop.run(np.ones((3, 1)), W)
        ref = np.ones(3)
        for k in range(40):
            ref = a * ref + b * W[:, k, 0]
            np.testing.assert_allclose(X[:, k + 1, 0], ref, rtol=1e-13, atol=1e-15)
    plain = cs.Function("plain", [x, w], [0.9 * x + 0.05 * w])
    with pytest.raises(InputError, match=r"parameters: expected 2 numbers, the step's input p, got '\[1.0\]'"):
        CompiledStepLoop(step, "t_lifted", parameters=[1.0])
    with pytest.raises(InputError, match="parameters: expected 2 numbers"):
        CompiledStepLoop(step, "t_lifted")
    with pytest.raises(InputError, match="parameters: contains NaN or inf"):
        CompiledStepLoop(step, "t_lifted", parameters=[np.nan, 1.0])
    with pytest.raises(InputError, match=r"parameters: the step \(x, w\) -> x_next takes none"):
        CompiledStepLoop(plain, "t_plain", parameters=[1.0])


KW = dict(process_noise=[1e-10] * 3 + [1e-6] * 3, measurement_noise=[1e-7], input_noise=[1e-8])


@pytest.fixture(scope="module")
def scenario_record():
    """The default estimation scenario's record (finger3, 1 s): measured torques (N, 1), encoder (N+1, 1), truth."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    r = run_estimation("ekf", duration=1.0, seed=3)
    return r.u_meas, r.y, r.x_true


def test_ekf_of_other_values_shares_the_compiled_library_and_equals_the_baked_step(scenario_record):
    """A finger3 of other masses, springs and friction (drawn +-20 %) loads the nominal one's EKF library (nothing
    compiled). Each compiled filter equals its step with the numbers as literals (``filter_step``, CasADi's VM) to
    1e-12 (relative to the largest entry) on the scenario's record from a prior at the truth, and step by step from
    each state of a run from a far prior (whose transient amplifies a last-bit difference, 1e-16 of CasADi's folded
    constant products, to 1e-8 before it decays); the two filters differ (the numbers do reach the compiled code)."""
    W, Y, x_true = scenario_record
    WY = np.hstack([W, Y[1:]])
    models = [ad.Model.alpes("finger3"), ad.Model.alpes("finger3", params=perturbed_params(spread=0.2, seed=5))]
    runs, libs = [], []
    for k, m in enumerate(models):
        ekf = ExtendedKalmanFilter(StateSpace(m, input="motor", output="encoder"), 1e-3, compiled=True, **KW)
        libs.append(ekf._loop.library)
        if k == 1:
            assert not ekf._loop.compiled and ekf._loop.compile_seconds == 0.0  # loaded, not compiled
        z0, P0 = x_true[0], [1e-4] * 3 + [1e-2] * 3
        est = ekf.run(z0, P0, W, Y)
        z, P = ekf._update(ekf._z(z0), ekf._P(P0), Y[0])
        s0 = np.concatenate([np.array(z).ravel(), np.array(P).ravel(order="F")])
        baked = np.array(ekf.filter_step.mapaccum(len(W))(s0, WY.T)).T  # literals, the VM
        S = np.hstack([est.z[1:], est.P[1:].transpose(0, 2, 1).reshape(len(W), -1)])
        assert np.abs(S - baked).max() <= 1e-12 * np.abs(S).max()
        far = ekf.run(x_true[0] + np.r_[0.1, -0.1, 0.1, 0, 0, 0], [0.04] * 3 + [1.0] * 3, W, Y)
        S = np.hstack([far.z[:-1], far.P[:-1].transpose(0, 2, 1).reshape(len(W), -1)])
        one = np.array(ekf.filter_step.map(len(W))(S.T, WY.T)).T  # one step from each state, literals
        # the compiled step from the same states
        mine = np.vstack([ekf._loop.run(S[i:i + 1], WY[None, i:i + 1])[0, 1] for i in range(0, len(W), 50)])
        assert np.abs(mine - one[::50]).max() <= 1e-12 * np.abs(S).max()
        runs.append(est.z)
    assert libs[0] == libs[1]
    assert np.abs(runs[0] - runs[1]).max() > 1e-6


def test_ukf_numbers_are_an_input_too():
    """The UKF's compiled step takes the model's numbers: finger2 and a finger2 of other values, one library."""
    kw = dict(process_noise=[1e-10] * 2 + [1e-6] * 2, measurement_noise=[1e-7], input_noise=[1e-8])
    a = UnscentedKalmanFilter(StateSpace(ad.Model.alpes("finger2"), input="motor", output="encoder"), 1e-3, **kw)
    b = UnscentedKalmanFilter(StateSpace(ad.Model.alpes("finger2", params=perturbed_params(spread=0.2, seed=2)),
                                         input="motor", output="encoder"), 1e-3, **kw)
    assert a.model.values.size == b.model.values.size and np.any(a.model.values != b.model.values)
    assert _code(a.filter_step_p) == _code(b.filter_step_p)
    assert _code(a.filter_step) != _code(b.filter_step)
