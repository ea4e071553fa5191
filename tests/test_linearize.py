"""Linearisation, python-control export and equilibria of a state space.

References: central finite differences of the numeric f and h (Pinocchio, not the CasADi expressions
that are differentiated), a closed-form damped oscillator, and python-control's own ``sample_system``.
"""

from __future__ import annotations

import functools

import control
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model import Contact
from alpes_dyn.estimation.observers.scenario import static_equilibrium
from alpes_dyn.model.spec import example_spec_path
from alpes_dyn.symbolic.statespace import StateSpace

URDF = ad.example_robot_urdf("allegro_hand", "allegro_right_hand")
OSC = """<robot name="osc"><link name="base"/>
  <link name="bar"><inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="0.2"/>
    <inertia ixx="1e-4" ixy="0" ixz="0" iyy="2e-3" iyz="0" izz="2e-3"/></inertial></link>
  <joint name="j" type="revolute"><parent link="base"/><child link="bar"/><origin xyz="0 0 0" rpy="0 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="10"/></joint>
</robot>"""


@functools.lru_cache(maxsize=None)
def allegro_ss() -> StateSpace:
    return StateSpace(ad.Model.from_urdf_file(URDF, example_spec_path()), input="motor", output="encoder")


def fd_jacobians(ss: StateSpace, x, u, F=None, h=1e-6):
    """Central differences of the numeric f(x, w) and h(x), w = [u; F]."""
    m = ss.n_inputs
    w = np.concatenate([u, F]) if F is not None else u
    f = lambda x, w: ss.f(x, w[:m], w[m:] if F is not None else None)  # noqa: E731
    A = np.column_stack([(f(x + h * e, w) - f(x - h * e, w)) / (2 * h) for e in np.eye(x.size)])
    B = np.column_stack([(f(x, w + h * e) - f(x, w - h * e)) / (2 * h) for e in np.eye(w.size)])
    C = np.column_stack([(ss.h(x + h * e) - ss.h(x - h * e)) / (2 * h) for e in np.eye(x.size)])
    return A, B, C


@pytest.mark.parametrize("case", ["allegro", "finger3_friction_contact"])
def test_continuous_linearization_equals_finite_differences(case, rng):
    if case == "allegro":
        ss, F = allegro_ss(), None
    else:
        ss = StateSpace(ad.Model.alpes("finger3", friction=True, rotor_inertia=True), input="motor",
                        output=["encoder", "tip_position:tip"], contacts=[Contact("tip", 6, "local")])
        F = rng.normal(scale=0.1, size=6)
    q, v = ss.model.random_state(rng)
    x = np.concatenate([q, v])
    u = rng.normal(scale=0.02, size=ss.n_inputs)
    A, B, C, D = ss.linearize(x, u, F)
    nw = ss.n_inputs + ss.n_force
    assert A.shape == (ss.n_states,) * 2 and B.shape == (ss.n_states, nw)
    assert C.shape == (ss.n_outputs, ss.n_states) and D.shape == (ss.n_outputs, nw) and not D.any()
    Af, Bf, Cf = fd_jacobians(ss, x, u, F)
    for M, Mf in ((A, Af), (B, Bf), (C, Cf)):
        assert np.max(np.abs(M - Mf)) <= 1e-6 * max(1.0, np.abs(Mf).max())
    n = ss.n
    assert np.array_equal(A[:n, n:], np.eye(n)) and not A[:n, :n].any()  # x1' = x2


def test_oscillator_closed_form_and_python_control():
    """I q'' + c q' + k q = tau: A = [[0, 1], [-k/I, -c/I]], B = [0, 1/I]; zoh as control.sample_system."""
    I, k, c = 2e-3 + 0.2 * 0.1**2, 0.5, 4e-3
    extras = ad.JointExtras(stiffness=np.array([k]), armature=np.zeros(1), coulomb=np.zeros(1), viscous=np.array([c]))
    ss = StateSpace(ad.Model(OSC, extras=extras, gravity=[0.0, 0.0, 0.0]), output="joints")
    A, B, C, D = ss.linearize([0.3, -1.0], [0.01])
    assert np.allclose(A, [[0, 1], [-k / I, -c / I]], rtol=1e-14, atol=0)
    assert np.allclose(B, [[0], [1 / I]], rtol=1e-14, atol=0) and np.array_equal(C, [[1.0, 0.0]])
    sys_c = ss.to_control([0.3, -1.0], [0.01])
    assert isinstance(sys_c, control.StateSpace) and sys_c.dt == 0
    assert sys_c.state_labels == ["q_j", "qd_j"] and sys_c.input_labels == ["tau_j"] and sys_c.output_labels == ["q_j"]
    w0, zeta = np.sqrt(k / I), c / (2 * np.sqrt(k * I))
    poles = np.sort_complex(sys_c.poles())
    assert np.allclose(poles, np.sort_complex(w0 * (-zeta + np.array([-1j, 1j]) * np.sqrt(1 - zeta**2))), rtol=1e-12)
    for dt in (1e-3, 0.05):
        Ad, Bd, Cd, Dd = ss.linearize([0.3, -1.0], [0.01], dt=dt)
        ref = control.sample_system(control.ss(A, B, C, D), dt, method="zoh")
        assert np.allclose(Ad, ref.A, rtol=1e-12, atol=1e-14) and np.allclose(Bd, ref.B, rtol=1e-12, atol=1e-16)
        sys_d = ss.to_control([0.3, -1.0], [0.01], dt=dt)
        assert sys_d.dt == dt and np.allclose(sys_d.A, ref.A, rtol=1e-12, atol=1e-14)
        Ae, Be, _, _ = ss.linearize([0.3, -1.0], [0.01], dt=dt, method="euler")
        assert np.array_equal(Ae, np.eye(2) + A * dt) and np.array_equal(Be, B * dt)


def test_allegro_to_control_discrete_names():
    ss = allegro_ss()
    x0 = ss.equilibrium(0.02 * np.ones(8))
    sys_d = ss.to_control(x0, 0.02 * np.ones(8), dt=1e-3)
    assert sys_d.nstates == 32 and sys_d.ninputs == 8 and sys_d.noutputs == 8 and sys_d.dt == 1e-3
    assert sys_d.input_labels[0] == "tau_m_index" and sys_d.output_labels[-1] == "q_m_thumb_rotation"
    # the linearised plant is observable from the encoders (Kalman rank), as the nonlinear test says
    assert np.linalg.matrix_rank(control.obsv(sys_d.A, sys_d.C)) == 32


def test_equilibrium(rng):
    ss = allegro_ss()
    m = ss.model
    u = rng.uniform(-0.02, 0.05, size=8)
    x = ss.equilibrium(u)
    assert x.shape == (32,) and not x[16:].any()
    assert np.max(np.abs(m.gravity_torque(x[:16]) - m.transmission.S.T @ u)) < 1e-12
    assert np.max(np.abs(ss.f(x, u))) < 1e-7
    f3 = ad.Model.alpes("finger3")
    tau = f3.transmission.joint_torque([0.02])
    assert np.array_equal(static_equilibrium(f3, tau), f3.static_equilibrium(tau))  # the former name
    # with a contact force: G(q) = B u + J^T F at rest
    ssc = StateSpace(f3, input="motor", output="encoder", contacts=[Contact("tip", 6, "local")])
    F = np.array([0.05, 0.0, -0.1, 0.0, 0.001, 0.0])
    xc = ssc.equilibrium([0.02], F)
    assert np.max(np.abs(ssc.f(xc, [0.02], F))) < 1e-7
    resid = f3.gravity_torque(xc[:3]) - tau - f3.contact_torque(xc[:3], F, contacts=ssc.contacts)
    assert np.max(np.abs(resid)) < 1e-12


def test_bad_input():
    ss = StateSpace(ad.Model.alpes("finger2"))
    x, u = np.zeros(4), np.zeros(2)
    with pytest.raises(ad.InputError, match=r"dt: expected a positive number of seconds or None, got 0"):
        ss.linearize(x, u, dt=0)
    with pytest.raises(ad.InputError, match=r"method: expected 'zoh' or 'euler', got 'tustin'"):
        ss.linearize(x, u, dt=0.01, method="tustin")
    with pytest.raises(ad.InputError, match=r"u: expected shape \(2,\), got \(3,\)"):
        ss.linearize(x, np.zeros(3))
    with pytest.raises(ad.InputError, match=r"x: contains NaN"):
        ss.linearize([0, np.nan, 0, 0], u)
    with pytest.raises(ad.InputError, match=r"F: this state space has no contact-force input"):
        ss.linearize(x, u, np.zeros(3))
    with pytest.raises(ad.InputError, match=r"F: this state space has contact forces as an input; pass F \(3,\)"):
        StateSpace(ad.Model.alpes("finger2"), force=True).linearize(x, u)
    with pytest.raises(ad.InputError, match=r"static equilibrium: singular stiffness"):
        StateSpace(ad.Model(OSC, gravity=[0.0, 0.0, 0.0]), output="joints").equilibrium([0.1])


# ----------------------------------------------------------------------------- command line
def test_cli_linearize(capsys):
    import json

    from alpes_dyn.cli import main

    argv = ["linearize", "--model", str(URDF), "--spec", str(example_spec_path()), "--input", "motor",
            "--output", "encoder", "--u=" + ",".join(["0.02"] * 8), "--dt", "0.001", "--json"]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    ss = allegro_ss()
    x0 = ss.equilibrium(0.02 * np.ones(8))
    Ad, Bd, Cd, _ = ss.linearize(x0, 0.02 * np.ones(8), dt=1e-3)
    assert np.allclose(d["x0"], x0, rtol=0, atol=1e-15) and np.allclose(d["A"], Ad, rtol=1e-14, atol=1e-15)
    assert np.allclose(d["B"], Bd, rtol=1e-14, atol=1e-18) and np.allclose(d["C"], Cd, rtol=0, atol=0)
    assert d["inputs"][0] == "tau_m_index" and d["states"][16] == "qd_joint_0.0"
    assert main(["linearize", "--model", "finger2", "--output", "joints+tip_position:tip"]) == 0
    out = capsys.readouterr().out
    assert "  z_tip " in out and "  qd_j2 " in out


@pytest.mark.parametrize("argv,needle", [
    (["--u=1,2,3"], "--u: input 'joint' of model 'finger2' has 2 entries (tau_j1, tau_j2), got 3 values"),
    (["--v=0,0"], "--v: give --q with it"),
    (["--q=0,0,0"], "--q: model 'finger2' has 2 joints, got 3 values"),
    (["--dt", "-1"], "--dt: expected a positive number of seconds, got -1.0"),
    (["--dt", "x"], "argument --dt: invalid float value: 'x'"),
    (["--output", "nose"], "unknown output 'nose'"),
    (["--output", "sum+"], "expected output names joined by '+'"),
])
def test_cli_linearize_errors(capsys, argv, needle):
    from alpes_dyn.cli import main

    assert main(["linearize", "--model", "finger2", *argv]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and needle in err
