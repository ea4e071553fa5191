"""Simulation (RK4, CVODES, IDAS) and the compiled batched rollout, against independent references.

References: the closed-form damped harmonic oscillator; energy conservation computed by Pinocchio
(Model.kinetic_energy / potential_energy); an RK4 loop written here on Pinocchio's ABA
(Model.forward_dynamics), independent of the CasADi expressions that simulate() integrates.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.model.extras import JointExtras
from alpes_dyn.simulation import compile_rollout, rk4_step_function, simulate
from alpes_dyn.symbolic.statespace import StateSpace

# a 1-DoF bar about z: inertia about the joint axis I = izz + m d^2 = 2e-3 + 0.5 * 0.1^2 = 7e-3 kg m^2
OSC_URDF = """<?xml version="1.0"?>
<robot name="oscillator">
  <link name="base"/>
  <link name="bar">
    <inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="0.5"/>
      <inertia ixx="1e-4" ixy="0" ixz="0" iyy="2e-3" iyz="0" izz="2e-3"/></inertial>
  </link>
  <joint name="j" type="revolute"><parent link="base"/><child link="bar"/><origin xyz="0 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="10"/></joint>
</robot>
"""
I_OSC, K_OSC, C_OSC = 7e-3, 0.5, 4e-3


def oscillator(viscous: float = C_OSC) -> StateSpace:
    extras = JointExtras(stiffness=np.array([K_OSC]), armature=np.zeros(1), coulomb=np.zeros(1),
                         viscous=np.array([viscous]))
    return StateSpace(ad.Model(OSC_URDF, extras=extras, gravity=[0.0, 0.0, 0.0]), input="joint", output=np.eye(1))


def damped_closed_form(t: np.ndarray, q0: float, v0: float, tau: float) -> np.ndarray:
    """I q'' + c q' + k q = tau: q(t) in closed form (underdamped)."""
    w0 = np.sqrt(K_OSC / I_OSC)
    zeta = C_OSC / (2 * np.sqrt(K_OSC * I_OSC))
    wd = w0 * np.sqrt(1 - zeta**2)
    qs = tau / K_OSC
    A = q0 - qs
    B = (v0 + zeta * w0 * A) / wd
    return qs + np.exp(-zeta * w0 * t) * (A * np.cos(wd * t) + B * np.sin(wd * t))


@pytest.fixture(scope="module")
def osc() -> StateSpace:
    return oscillator()


@pytest.mark.parametrize("method,tol", [("rk4", 2e-7), ("cvodes", 1e-8), ("idas", 1e-8)])
def test_damped_oscillator_closed_form(osc, method, tol):
    r = simulate(osc, [0.3, -0.5], 0.1, duration=1.0, dt=1e-3, method=method)
    ref = damped_closed_form(r.t, 0.3, -0.5, 0.1)
    assert np.max(np.abs(r.q[:, 0] - ref)) < tol
    assert np.allclose(r.y[:, 0], r.q[:, 0])
    assert r.u.shape == (1000, 1) and np.all(r.u == 0.1)


def test_rk4_is_fourth_order(osc):
    errs = []
    for dt in (4e-3, 2e-3):
        r = simulate(osc, [0.3, 0.0], None, duration=0.8, dt=dt)
        errs.append(abs(r.q[-1, 0] - damped_closed_form(np.array([0.8]), 0.3, 0.0, 0.0)[0]))
    assert 12.0 < errs[0] / errs[1] < 20.0  # 2^4 = 16


def test_energy_conserved_rk4():
    """No friction, torsional springs: relative energy drift < 1e-6 over 2 s at dt = 1e-4 (RK4)."""
    m = ad.Model.alpes("finger3", spring="torsional", friction=False)
    x0 = np.array([0.3, 0.5, 0.4, 1.0, -1.0, 2.0])
    r = simulate(m, x0, None, duration=2.0, dt=1e-4, method="rk4")
    E = np.array([m.kinetic_energy(x[:3], x[3:]) + m.potential_energy(x[:3]) for x in r.x[::50]])
    assert abs(E[0]) > 1e-3
    assert np.max(np.abs(E - E[0])) / abs(E[0]) < 1e-6
    # the motion is not trivial: the joints swing by tenths of radians
    assert np.ptp(r.q, axis=0).min() > 0.1


def _pinocchio_rk4(m: ad.Model, x0, U, F, dt):
    """An RK4 loop on Pinocchio's ABA (Model.forward_dynamics), motor torques through S^T."""
    n = m.n
    S = m.transmission.S
    x = np.array(x0, dtype=float)
    out = [x.copy()]

    def f(x, u, Fk):
        return np.concatenate([x[n:], m.forward_dynamics(x[:n], x[n:], S.T @ u, Fk, smooth=True)])

    for u, Fk in zip(U, F):
        k1 = f(x, u, Fk)
        k2 = f(x + 0.5 * dt * k1, u, Fk)
        k3 = f(x + 0.5 * dt * k2, u, Fk)
        k4 = f(x + dt * k3, u, Fk)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        out.append(x.copy())
    return np.array(out)


def test_motor_input_friction_and_contact_force_match_pinocchio():
    m0 = ad.Model.alpes("finger3", friction=True)
    # a stiff smooth Coulomb sign (v_s = 0.01 rad/s, ten times the file's): small explicit steps
    m = ad.Model(m0.urdf, dataclasses.replace(m0.extras, smooth_velocity=0.01), m0.gravity, m0.name, m0.layout,
                 m0.params, m0.spring)
    dt, N = 2e-5, 250
    x0 = np.array([0.2, 0.4, 0.3, 0.5, -0.2, 0.1])
    tau_m = lambda t: [0.02 + 0.01 * np.sin(40 * t)]  # noqa: E731
    Fz = lambda t: -0.3 * t / (N * dt)  # noqa: E731
    r = simulate(m, x0, tau_m, duration=N * dt, dt=dt, input="motor", output="encoder", force=Fz)
    U = np.array([tau_m(t) for t in r.t[:-1]])
    F = [np.array([0.0, 0.0, Fz(t)]) for t in r.t[:-1]]
    ref = _pinocchio_rk4(m, x0, U, F, dt)
    assert np.max(np.abs(r.x - ref)) < 1e-10 * max(1.0, np.abs(ref).max())
    assert np.allclose(r.F[:, 2], [Fz(t) for t in r.t[:-1]]) and np.all(r.F[:, :2] == 0)
    # encoder output q_m = (r/r_m) sum q (Section 3)
    assert np.allclose(r.y[:, 0], m.params.r / m.params.r_m * r.q.sum(axis=1), rtol=0, atol=1e-14)
    # an adaptive implicit method agrees with the fine RK4
    rc = simulate(m, x0, tau_m, duration=N * dt, dt=dt, method="cvodes", input="motor", force=Fz)
    assert np.max(np.abs(rc.x - ref)) < 1e-7 * np.abs(ref).max()


def test_array_and_callable_inputs_agree(osc):
    t = 1e-3 * np.arange(100)
    U = 0.05 * np.sin(30 * t)[:, None]
    a = simulate(osc, [0.0, 0.0], U, duration=0.1, dt=1e-3)
    b = simulate(osc, [0.0, 0.0], lambda s: 0.05 * np.sin(30 * s), duration=0.1, dt=1e-3)
    assert np.array_equal(a.x, b.x)


def test_simulate_errors(osc):
    with pytest.raises(InputError, match="x0"):
        simulate(osc, [np.nan, 0.0], None, 0.1, 1e-3)
    with pytest.raises(InputError, match="x0"):
        simulate(osc, [0.0, 0.0, 0.0], None, 0.1, 1e-3)
    with pytest.raises(InputError, match="inputs"):
        simulate(osc, [0.0, 0.0], np.zeros((7, 1)), 0.1, 1e-3)
    with pytest.raises(InputError, match="inputs"):
        simulate(osc, [0.0, 0.0], np.full((100, 1), np.inf), 0.1, 1e-3)
    with pytest.raises(InputError, match="method"):
        simulate(osc, [0.0, 0.0], None, 0.1, 1e-3, method="euler")
    with pytest.raises(InputError, match="duration"):
        simulate(osc, [0.0, 0.0], None, 0.1005, 1e-3)
    with pytest.raises(InputError, match="dt"):
        simulate(osc, [0.0, 0.0], None, 0.1, -1e-3)
    with pytest.raises(InputError, match="force"):
        simulate(osc, [0.0, 0.0], None, 0.1, 1e-3, force=1.0)
    with pytest.raises(InputError, match="callable"):
        simulate(osc, [0.0, 0.0], lambda t: [1.0, 2.0], 0.1, 1e-3)


# ----------------------------------------------------------------------------- compiled rollout
@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ALPES_DYN_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"


@pytest.mark.parametrize("name", ["finger3", "hand"])
def test_rollout_equals_simulate(cache, name):
    m = ad.Model.alpes(name)
    ro = compile_rollout(m, 1e-3, input="motor", threads=2)
    assert ro.compiled and ro.library.parent == cache and ro.library.exists()
    rng = np.random.default_rng(3)
    B, N = 5, 300
    X0 = np.array([np.concatenate(m.random_state(rng, speed=0.5)) for _ in range(B)])
    U = 0.02 + 0.005 * rng.standard_normal((B, N, ro.system.n_inputs))
    X = ro.rollout(X0, U)
    assert X.shape == (B, N + 1, 2 * m.n)
    for b in (0, B - 1):
        r = simulate(ro.system, X0[b], U[b], duration=N * 1e-3, dt=1e-3, method="rk4")
        assert np.max(np.abs(X[b] - r.x)) < 1e-10 * max(1.0, np.abs(r.x).max())
    # the RK4 step itself against Pinocchio's ABA on one step
    x1 = _pinocchio_rk4(m, X0[0], U[0, :1], [None], 1e-3)[1]
    assert np.max(np.abs(X[0, 1] - x1)) < 1e-9
    # threads do not change the numbers; a second build loads the cached library
    ro1 = compile_rollout(m, 1e-3, input="motor", threads=1)
    assert not ro1.compiled and ro1.compile_seconds == 0.0 and ro1.library == ro.library
    assert np.array_equal(ro1.rollout(X0, U), X)


def test_rollout_force_broadcast_progress_and_errors(cache, capsys):
    m = ad.Model.alpes("finger3")
    ss = StateSpace(m, input="motor", output="encoder", force=True)
    ro = compile_rollout(ss, 1e-3)
    N = 50
    x0 = np.array([0.3, 0.2, 0.1, 0.0, 0.0, 0.0])
    U = np.full((N, 1), 0.02)
    F = np.zeros((2, N, 3))
    F[1, :, 2] = -0.5
    X = ro.rollout(x0, U, F, progress=True)  # x0 and U broadcast over the batch of F
    assert X.shape == (2, N + 1, 6)
    assert "rollout finger3" in capsys.readouterr().err
    step = rk4_step_function(ss, 1e-3)
    assert np.allclose(np.array(step(x0, [0.02, 0, 0, -0.5])).ravel(), X[1, 1], rtol=0, atol=1e-14)
    assert not np.allclose(X[0, -1], X[1, -1])  # the contact force acts
    with pytest.raises(InputError, match="F_batch"):
        ro.rollout(x0, U)
    with pytest.raises(InputError, match="U_batch"):
        ro.rollout(x0, np.zeros((2, N, 3)), F)
    with pytest.raises(InputError, match="x0_batch"):
        ro.rollout(np.zeros((2, 5)), U, F)
    with pytest.raises(InputError, match="x0_batch"):
        ro.rollout(np.full(6, np.nan), U, F)
    with pytest.raises(InputError, match="batch size"):
        ro.rollout(np.zeros((3, 6)), U, F)


def test_step_loop_simd_lanes_equal_scalar_code(cache):
    """The two-lane SIMD driver computes bit for bit what CasADi's scalar code computes."""
    import casadi as cs

    from alpes_dyn.simulation import CompiledStepLoop

    ss = StateSpace(ad.Model.alpes("finger3", friction=True), input="motor", output="encoder")
    step = rk4_step_function(ss, 1e-4)
    vec = CompiledStepLoop(step, "t_vec", threads=2)
    sca = CompiledStepLoop(step, "t_sca", threads=1, vectorize=False)
    assert vec.lanes == 2 and sca.lanes == 1
    rng = np.random.default_rng(5)
    x0 = rng.uniform(0.0, 1.0, (3, 6))
    W = 0.02 + 0.005 * rng.standard_normal((3, 40, 1))
    Xv, Xs = vec.run(x0, W), sca.run(x0, W)
    assert np.array_equal(Xv, Xs)
    ref = np.array(step.mapaccum(40)(x0[2], W[2].T)).T  # CasADi's virtual machine
    assert np.max(np.abs(Xs[2, 1:] - ref)) < 1e-12 * np.abs(ref).max()
    # a construct the SIMD rewrite does not handle (a conditional) falls back to scalar code
    x, w = cs.SX.sym("x", 2), cs.SX.sym("w", 1)
    clip = cs.Function("clip", [x, w], [cs.vertcat(cs.if_else(x[0] > 0, x[0] + w, -x[0]), x[1] * w)])
    loop = CompiledStepLoop(clip, "t_clip")
    assert loop.lanes == 1
    X = loop.run(np.array([[0.5, 2.0], [-1.0, 1.0]]), np.full((2, 3, 1), 0.5))
    assert np.allclose(X[0, :, 0], [0.5, 1.0, 1.5, 2.0]) and np.allclose(X[1, :, 0], [-1.0, 1.0, 1.5, 2.0])
    assert np.allclose(X[0, :, 1], [2.0, 1.0, 0.5, 0.25])


def test_joint_range_warns_errs_and_stops_hold():
    """0.02 N m on every hand motor for 1 s: without stops thumb_abd turns by > 100 rad and simulate warns
    (or errs); with JointStops no joint goes more than 10 degrees past a stop, even on impact (stiffness 2 N m/rad)."""
    from alpes_dyn.model.stops import JointRangeWarning, JointStops

    m = ad.Model.alpes("hand")
    x0 = np.zeros(2 * m.n)
    with pytest.warns(JointRangeWarning, match=r"left its range .*worst: 'thumb_abd' 1\d\d rad outside"):
        simulate(m, x0, 0.02, duration=1.0, dt=1e-3, input="motor")
    with pytest.raises(InputError, match=r"joint '.*' left its range"):
        simulate(m, x0, 0.02, duration=0.1, dt=1e-3, input="motor", joint_range="error")
    r = simulate(m, x0, 0.02, duration=1.0, dt=1e-3, input="motor", stops=JointStops.of(m))
    assert np.all(r.q >= m.lower - np.radians(10)) and np.all(r.q <= m.upper + np.radians(10))
    # the stop holds thumb_abd against its motor: k * penetration = abduction_ratio * 0.02 N m (no spring)
    k = list(m.joint_names).index("thumb_abd")
    assert np.mean(r.q[-200:, k]) - m.upper[k] == pytest.approx(0.02 * m.params.abduction_ratio / 2.0, rel=0.05)
    with pytest.raises(InputError, match="joint_range: expected one of warn, error, ignore"):
        simulate(m, x0, 0.0, duration=0.01, dt=1e-3, input="motor", joint_range="clip")


def test_stop_torque_numpy_equals_casadi():
    import casadi as cs

    from alpes_dyn.model.stops import JointStops

    st = JointStops(np.zeros(3), np.full(3, 1.5), 2.0, 4e-3)
    q, v = np.array([-0.1, 0.7, 1.6]), np.array([-0.5, 1.0, 2.0])
    tn = st.torque(q, v)
    assert np.allclose(tn, [2.0 * 0.1 + 4e-3 * 0.5, 0.0, -(2.0 * 0.1 + 4e-3 * 2.0)])
    qs, vs = cs.SX.sym("q", 3), cs.SX.sym("v", 3)
    f = cs.Function("f", [qs, vs], [st.torque(qs, vs, cs)])
    assert np.allclose(np.array(f(q, v)).ravel(), tn, rtol=1e-15)


@pytest.mark.parametrize("backend", ["casadi", "casadi-jit"])
def test_casadi_fallback_equals_the_generated_driver(backend):
    """CasADi's stock path (mapaccum + threaded map, VM or JIT) gives the generated C driver's states."""
    from alpes_dyn.simulation import compile_rollout

    m = ad.Model.alpes("finger2")
    rng = np.random.default_rng(5)
    X0 = np.array([np.concatenate(m.random_state(rng, speed=0.5)) for _ in range(3)])
    U = rng.normal(scale=0.005, size=(3, 40, 2))
    ref = compile_rollout(m, 1e-3, threads=1).rollout(X0, U)
    fb = compile_rollout(m, 1e-3, threads=2, backend=backend)
    assert fb.backend == backend
    np.testing.assert_allclose(fb.rollout(X0, U), ref, rtol=1e-13, atol=1e-15)


def test_rollout_backend_refused():
    from alpes_dyn.simulation import compile_rollout

    with pytest.raises(InputError, match="backend: expected one of c, casadi, casadi-jit, got 'gpu'"):
        compile_rollout(ad.Model.alpes("finger2"), 1e-3, backend="gpu")


@pytest.mark.parametrize("method", ["cvodes", "idas"])
def test_sundials_on_time_varying_inputs(method):
    """A piecewise-constant input at 1 ms (steps, a sampled sine): the solver restarts where the input
    changes (one run over the grid failed with CV_ERR_FAILURE at the first jump), and agrees with RK4 at a
    tenth of the step on the same held input."""
    m = ad.Model.alpes("finger3", friction=False)
    x0 = np.array([0.6, 0.9, 0.8, 0.0, 0.0, 0.0])
    steps = np.repeat([[0.01], [0.02], [0.005], [0.015]], 50, axis=0) * np.ones((1, 3))
    sine = 0.01 + 0.005 * np.sin(20e-3 * np.arange(200))[:, None] * np.ones((1, 3))
    for W in (steps, sine):
        r = simulate(m, x0, W, duration=0.2, dt=1e-3, method=method, joint_range="ignore")
        held = lambda t, W=W: W[min(int(t / 1e-3 + 1e-6), len(W) - 1)]  # noqa: E731
        ref = simulate(m, x0, held, duration=0.2, dt=1e-4, method="rk4", joint_range="ignore")
        assert np.max(np.abs(r.q - ref.q[::10])) < 1e-6
    b = simulate(m, x0, lambda t: 0.01 + 0.005 * np.sin(20 * t) * np.ones(3), duration=0.2, method=method, joint_range="ignore")
    assert np.allclose(b.q, r.q, atol=1e-12)  # the callable sampled at the steps: the same held input


def test_sundials_failure_is_one_line():
    """A torque ramp far past anything physical: CVODES gives up after its max_num_steps in the second output
    interval (a ramp of 1e11 N m/s fails there; 1e8 failed in the fourth, after three intervals of grinding: twice the
    time for the same message)."""
    m = ad.Model.alpes("finger3", friction=False)
    with pytest.raises(ad.InputError) as e:
        simulate(m, np.array([0.6, 0.9, 0.8, 0.0, 0.0, 0.0]), lambda t: np.full(3, 1e11 * t), duration=0.01,
                 method="cvodes", joint_range="ignore")
    msg = str(e.value)
    assert msg.startswith("integrator cvodes failed on [") and "CV_TOO_MUCH_WORK" in msg
    assert "\n" not in msg and ".cpp" not in msg and "At t =" not in msg and msg.endswith("or use method='rk4'")
