"""Rotor inertia on the tendon coordinate (eq. 2.8): A(q) + S^T diag(J_m) S in every path."""

from __future__ import annotations

import casadi as cs
import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.model.spec import Motor, TransmissionSpec
from alpes_dyn.symbolic.dynamics import SymbolicDynamics
from alpes_dyn.symbolic.parametric import ParametricDynamics
from alpes_dyn.symbolic.statespace import StateSpace

# a planar 2R arm about z: link 1 (m1, COM at c1, I1 about its COM), joint 2 at l1, link 2 (m2, c2, I2)
M1, C1, I1, L1, M2, C2, I2 = 0.3, 0.04, 2e-4, 0.1, 0.2, 0.03, 1e-4
TOY = f"""<robot name="toy">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="{C1} 0 0"/><mass value="{M1}"/>
    <inertia ixx="1e-5" iyy="1e-5" izz="{I1}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><origin xyz="{C2} 0 0"/><mass value="{M2}"/>
    <inertia ixx="1e-5" iyy="1e-5" izz="{I2}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="q1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="{L1} 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""
J_M, RATIOS, ARM2, K = 3e-6, (2.0, -1.5), 4e-6, (0.05, 0.02)


def toy(J_m: float = J_M) -> ad.Model:
    spec = TransmissionSpec(motors=(Motor("m", {"q1": RATIOS[0], "q2": RATIOS[1]}, J_m),),
                            armature={"q2": ARM2}, stiffness={"q1": K[0], "q2": K[1]}, gravity=(0.0, 0.0, 0.0))
    return ad.Model(TOY, spec)


def toy_closed_form(q, v):
    """M (with the rotor and the armature) and C qd of the 2R arm, by hand."""
    c, s = np.cos(q[1]), np.sin(q[1])
    a11 = I1 + M1 * C1**2 + I2 + M2 * (L1**2 + C2**2 + 2 * L1 * C2 * c)
    a12 = I2 + M2 * (C2**2 + L1 * C2 * c)
    a22 = I2 + M2 * C2**2
    r1, r2 = RATIOS
    M = np.array([[a11 + J_M * r1 * r1, a12 + J_M * r1 * r2], [a12 + J_M * r1 * r2, a22 + J_M * r2 * r2 + ARM2]])
    h = M2 * L1 * C2 * s
    Cqd = np.array([-h * (2 * v[0] * v[1] + v[1] ** 2), h * v[0] ** 2])
    return M, Cqd


def test_two_joint_toy_against_the_closed_form(rng):
    m = toy()
    for _ in range(5):
        q, v = rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        tau = rng.normal(scale=0.05, size=2)
        M, Cqd = toy_closed_form(q, v)
        assert np.max(np.abs(m.inertia_matrix(q) - M)) < 1e-14 * np.max(np.abs(M))
        a_ref = np.linalg.solve(M, tau - Cqd - np.array(K) * q)
        a = m.forward_dynamics(q, v, tau)
        assert np.max(np.abs(a - a_ref)) < 1e-12 * np.max(np.abs(a_ref))
        assert np.max(np.abs(m.inverse_dynamics(q, v, a_ref) - tau)) < 1e-12 * np.max(np.abs(tau))
        assert m.kinetic_energy(q, v) == pytest.approx(0.5 * v @ M @ v, rel=1e-13)


def test_the_hand_against_raw_pinocchio_plus_the_added_matrix(rng):
    m = ad.Model.alpes("hand", friction=True, rotor_inertia=True)
    p = ad.load_params()
    pm = pin.buildModelFromXML(m.urdf)
    pm.gravity.linear = m.gravity
    pd = pm.createData()
    S = m.transmission.S
    R = S.T @ np.diag(np.full(S.shape[0], p.J_m)) @ S
    for _ in range(5):
        q, v = m.random_state(rng)
        tau = rng.normal(scale=0.05, size=m.n)
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T + R
        assert np.max(np.abs(m.inertia_matrix(q) - M)) < 1e-15 * np.max(np.abs(M))
        rhs = tau - pin.nonLinearEffects(pm, pd, q, v) - m.extras.stiffness * q - m.friction_torque(v)
        a_ref = np.linalg.solve(M, rhs)
        a = m.forward_dynamics(q, v, tau)
        assert np.max(np.abs(a - a_ref)) < 1e-12 * np.max(np.abs(a_ref))


def test_no_rotor_inertia_is_todays_model_and_one_joint_motors_are_an_armature(rng):
    """J_m = 0 is the rigid model, number for number; a motor on one joint (ratio N) is the armature N^2 J_m
    (the CRBA + Cholesky path against Pinocchio's ABA)."""
    zero, none = toy(0.0), ad.Model(TOY, TransmissionSpec(motors=(Motor("m", {"q1": 2.0, "q2": -1.5}),),
                                                          armature={"q2": ARM2}, stiffness={"q1": K[0], "q2": K[1]},
                                                          gravity=(0.0, 0.0, 0.0)))
    assert not zero.rotor_matrix.any()
    for _ in range(3):
        q, v = rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        tau = rng.normal(scale=0.05, size=2)
        assert np.array_equal(zero.forward_dynamics(q, v, tau), none.forward_dynamics(q, v, tau))
        assert np.array_equal(zero.inertia_matrix(q), none.inertia_matrix(q))
        assert np.array_equal(zero.inverse_dynamics(q, v, tau), none.inverse_dynamics(q, v, tau))
    motors = TransmissionSpec(motors=(Motor("m1", {"q1": 2.0}, J_M), Motor("m2", {"q2": 3.0}, J_M)))
    diag = TransmissionSpec(motors=(Motor("m1", {"q1": 2.0}), Motor("m2", {"q2": 3.0})),
                            armature={"q1": 4.0 * J_M, "q2": 9.0 * J_M})
    a, b = ad.Model(TOY, motors), ad.Model(TOY, diag)
    assert a._rotor and not b._rotor
    for _ in range(3):
        q, v = rng.uniform(-2, 2, 2), rng.uniform(-3, 3, 2)
        tau = rng.normal(scale=0.05, size=2)
        ref = b.forward_dynamics(q, v, tau)
        assert np.max(np.abs(a.forward_dynamics(q, v, tau) - ref)) < 1e-12 * np.max(np.abs(ref))


def test_symbolic_parametric_and_state_space_equal_the_numeric_model(rng):
    """The hand with the rotors: SymbolicDynamics, the state space's f and ParametricDynamics (J_m fitted)
    give the numeric model's accelerations to 1e-12."""
    m = ad.Model.alpes("hand", rotor_inertia=True)
    sym = SymbolicDynamics(m)
    q, v, tau = (cs.SX.sym(s, m.n) for s in "qvt")
    fd = cs.Function("fd", [q, v, tau], [sym.forward_dynamics(q, v, tau, smooth=False)])
    ss = StateSpace(m, input="motor", output="encoder")
    fs = cs.Function("fs", [ss.x, ss.u], [ss.f_expr])  # the state space's symbolic f (eq. 3.3)
    pd = ParametricDynamics(m, "J_m,K")
    assert pd.names[:6] == tuple(f"J_m_{k}" for k in m.motor_names)
    theta = np.r_[m.transmission.rotor_inertia, m.extras.stiffness[m.extras.stiffness != 0]]
    fp = cs.Function("fp", [q, v, tau, pd.theta], [pd.forward_dynamics(q, v, tau, pd.theta)])
    for _ in range(3):
        qq, vv = m.random_state(rng)
        tm = rng.uniform(0, 0.05, m.transmission.n_motors)
        tt = m.transmission.joint_torque(tm)
        ref = m.forward_dynamics(qq, vv, tt)
        scale = np.max(np.abs(ref))
        assert np.max(np.abs(np.array(fd(qq, vv, tt)).ravel() - ref)) < 1e-12 * scale
        assert np.max(np.abs(np.array(fp(qq, vv, tt, theta)).ravel() - ref)) < 1e-12 * scale
        xd = np.array(fs(np.r_[qq, vv], tm)).ravel()
        assert np.max(np.abs(xd[m.n:] - ref)) < 1e-12 * scale


def test_a_tendon_across_two_branches_takes_the_dense_solve(rng):
    """A tendon over two fingers (not one branch of the tree): the dense Cholesky path, against raw Pinocchio;
    the in-place factorisation of the serial path leaves inertia_matrix untouched."""
    urdf = ad.urdf_string("hand")
    spec = TransmissionSpec(motors=(Motor("pair", {"index_j1": 2.0, "middle_j2": 1.5}, 2e-6),
                                    Motor("ring", {"ring_j1": 2.0, "ring_j2": 2.0}, 1e-6)))
    m, serial = ad.Model(urdf, spec), ad.Model.alpes("hand", rotor_inertia=True)
    assert not m._rotor_tree and serial._rotor_tree
    pm = pin.buildModelFromXML(urdf)
    pd = pm.createData()
    S = m.transmission.S
    R = S.T @ np.diag([2e-6, 1e-6]) @ S
    for _ in range(3):
        q, v = m.random_state(rng)
        tau = rng.normal(scale=0.05, size=m.n)
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T + R
        a_ref = np.linalg.solve(M, tau - pin.nonLinearEffects(pm, pd, q, v))
        assert np.max(np.abs(m.forward_dynamics(q, v, tau) - a_ref)) < 1e-12 * np.max(np.abs(a_ref))
        before = serial.inertia_matrix(q)
        serial.forward_dynamics(q, v, tau)
        assert np.array_equal(serial.inertia_matrix(q), before)
