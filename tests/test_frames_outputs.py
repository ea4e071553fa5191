"""Frames, several contacts and general outputs (issue: any tendon-driven robot).

References: raw Pinocchio (its own model from the URDF file, getFrameJacobian, aba), finite differences of
frame poses (independent of any Jacobian code), and a hand-written RK4 over the numeric f.
"""

from __future__ import annotations

import functools

import casadi as cs
import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.model import Contact
from alpes_dyn.analysis.observability import ObservabilityMatrix
from alpes_dyn.simulation import simulate
from alpes_dyn.model.spec import example_spec_path
from alpes_dyn.symbolic.statespace import StateSpace
from alpes_dyn.symbolic import SymbolicDynamics

URDF = ad.example_robot_urdf("allegro_hand", "allegro_right_hand")
REFS = {"world": pin.WORLD, "local": pin.LOCAL, "local_world_aligned": pin.LOCAL_WORLD_ALIGNED}


@functools.lru_cache(maxsize=None)
def allegro() -> ad.Model:
    return ad.Model.from_urdf_file(URDF, example_spec_path())


@functools.lru_cache(maxsize=None)
def allegro_sym() -> tuple[SymbolicDynamics, dict]:
    S = SymbolicDynamics(allegro())
    q = cs.SX.sym("q", 16)
    funs = {(f, r): cs.Function("J", [q], [S.frame_jacobian(q, f, r)])
            for f in ("link_3.0_tip", "link_15.0_tip", "link_13.0") for r in REFS}
    return S, funs


def test_frame_jacobians_match_pinocchio_and_finite_differences(rng):
    m = allegro()
    pm = pin.buildModelFromUrdf(str(URDF))
    pd = pm.createData()
    _, funs = allegro_sym()
    for _ in range(3):
        q, _ = m.random_state(rng)
        pin.computeJointJacobians(pm, pd, q)
        pin.updateFramePlacements(pm, pd)
        for (frame, ref), fun in funs.items():
            J_ref = pin.getFrameJacobian(pm, pd, pm.getFrameId(frame), REFS[ref])
            J = m.frame_jacobian(q, frame, ref)
            assert J.shape == (6, 16) and np.max(np.abs(J - J_ref)) <= 1e-12
            assert np.array_equal(m.frame_jacobian(q, frame, ref, dim=3), J[:3])
            assert np.max(np.abs(np.asarray(fun(q)) - J_ref)) <= 1e-12  # ADAM + AD, an independent code
        # local_world_aligned by central differences of the pose: dp/dq and log(R(q + h e_j) R(q)^T) / h
        frame, h = "link_15.0_tip", 1e-6
        R0, _ = m.frame_placement(q, frame)
        J = m.frame_jacobian(q, frame)
        for j in range(16):
            e = np.zeros(16)
            e[j] = h
            (Rp, pp), (Rm, pm_) = m.frame_placement(q + e, frame), m.frame_placement(q - e, frame)
            assert np.allclose((pp - pm_) / (2 * h), J[:3, j], atol=1e-8)
            w = (pin.log3(Rp @ R0.T) - pin.log3(Rm @ R0.T)) / (2 * h)
            assert np.allclose(w, J[3:, j], atol=1e-8)


def test_several_contacts_in_both_backends(rng):
    """A pinch: a force at the index tip (base axes) and a wrench at the thumb tip (its own axes)."""
    m = allegro()
    pm = pin.buildModelFromUrdf(str(URDF))
    pm.armature = m.extras.armature.copy()
    pd = pm.createData()
    cts = [Contact("link_3.0_tip"), Contact("link_15.0_tip", 6, "local")]
    ss = StateSpace(m, input="motor", output="encoder", contacts=cts)
    assert ss.n_force == 9 and ss.force_names[3:] == tuple(f"{c}_link_15.0_tip" for c in
                                                          ("F_x", "F_y", "F_z", "M_x", "M_y", "M_z"))
    for _ in range(3):
        q, v = m.random_state(rng)
        tau_m = rng.normal(scale=0.05, size=8)
        F = rng.normal(size=9)
        J1 = pin.computeFrameJacobian(pm, pd, q, pm.getFrameId("link_3.0_tip"), pin.LOCAL_WORLD_ALIGNED)[:3]
        J2 = pin.computeFrameJacobian(pm, pd, q, pm.getFrameId("link_15.0_tip"), pin.LOCAL)
        tau = m.transmission.S.T @ tau_m + J1.T @ F[:3] + J2.T @ F[3:] - m.extras.stiffness * (q - m.extras.rest) \
            - m.extras.viscous * v
        qdd = pin.aba(pm, pd, q, v, tau)
        x = np.concatenate([q, v])
        assert np.max(np.abs(ss.f(x, tau_m, F)[16:] - qdd)) <= 1e-12 * max(1, np.abs(qdd).max())
        sym = np.asarray(ss.f_function(x, tau_m, F)).ravel()[16:]
        assert np.max(np.abs(sym - qdd)) <= 1e-9 * max(1, np.abs(qdd).max())
        # the dict form of the numeric model: {frame: force (3,) or wrench (6,)}, all in base axes
        Fd = {"link_3.0_tip": F[:3], "link_15.0_tip": F[3:]}
        J2w = pin.computeFrameJacobian(pm, pd, q, pm.getFrameId("link_15.0_tip"), pin.LOCAL_WORLD_ALIGNED)
        assert np.allclose(m.contact_torque(q, Fd), J1.T @ F[:3] + J2w.T @ F[3:], rtol=0, atol=1e-13)
    om = ObservabilityMatrix(ss)
    assert om.input_names[8:] == ss.force_names and om.m == 17


def test_simulation_with_several_contacts_is_rk4_of_the_numeric_f(rng):
    m = ad.Model.alpes("hand")
    cts = ["index_tip", Contact("thumb_tip", 6, "world")]
    ss = StateSpace(m, input="motor", output="encoder", contacts=cts)
    x0 = np.concatenate([m.random_state(rng)[0], np.zeros(15)])
    u, F, dt = 0.01 * np.ones(6), np.array([0, 0, -0.2, 0.1, 0, 0, 0, 0.002, 0]), 1e-3
    res = simulate(ss, x0, u, duration=3 * dt, dt=dt, force=F)
    x = x0
    for _ in range(3):
        k1 = ss.f(x, u, F)
        k2 = ss.f(x + dt / 2 * k1, u, F)
        k3 = ss.f(x + dt / 2 * k2, u, F)
        k4 = ss.f(x + dt * k3, u, F)
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    assert np.allclose(res.x[-1], x, rtol=0, atol=1e-10) and res.F.shape == (3, 9)
    with pytest.raises(ad.InputError, match=r"force: expected shape \(3, 9\)"):
        simulate(ss, x0, u, duration=3 * dt, dt=dt, force=np.zeros(3))


def test_output_presets_and_general_outputs(rng):
    m = ad.Model.alpes("finger3")
    x = np.concatenate(m.random_state(rng))
    q, v = x[:3], x[3:]
    cases = {
        "joints": q,
        "joints:j3,j1": q[[2, 0]],
        "tip_position:tip": m.fingertip_position(q),
        "encoder": m.transmission.S @ q,
    }
    for out, expect in cases.items():
        ss = StateSpace(m, output=out)
        assert np.allclose(ss.h(x), expect, rtol=0, atol=1e-15)
        assert np.allclose(np.asarray(ss.h_function(x)).ravel(), expect, rtol=0, atol=1e-12)
    H = np.array([[0, 0, 0, 1.0, 1.0, 1.0]])  # (p, 2n): the sum of the joint velocities
    assert StateSpace(m, output=H).h(x) == pytest.approx([v.sum()], rel=1e-14)
    assert StateSpace(m, output=H).H is None
    g = lambda q, v, xp: xp.sin(q[0]) * v[1]  # noqa: E731
    ss = StateSpace(m, output=g)
    assert float(ss.h_function(x)) == pytest.approx(np.sin(q[0]) * v[1], rel=1e-14)
    assert ss.h(x) == pytest.approx([np.sin(q[0]) * v[1]], rel=1e-14)
    both = StateSpace(m, output=["encoder", "tip_position:tip"])
    assert both.output_names == ("q_m_finger", "x_tip", "y_tip", "z_tip") and both.n_outputs == 4
    assert np.allclose(both.h(x), np.concatenate([m.transmission.S @ q, m.fingertip_position(q)]), atol=1e-15)
    # a velocity output makes the output derivatives one order lower: y = qd1 sees q1 through qdd1 ...
    r = ad.check_observability(StateSpace(m, output=np.array([[0, 0, 0, 1.0, 0, 0]])), points=3)
    assert r.n_outputs == 1 and r.rank == 6


@pytest.mark.parametrize("output,needle", [
    ("joints:j9", "unknown joint 'j9'"),
    ("tip_position:nail", "unknown tip/frame 'nail'"),
    ("tip_position", "unknown output 'tip_position'"),
    ("sum:x", "unknown output 'sum:x'"),
    ([], "output: an empty list"),
    (lambda a, b, c, d: a, "output function: expected g(q, xp) or g(q, v, xp), got 4 parameters"),
    (np.ones((1, 5)), r"output matrix: expected a finite (p, 3) or (p, 6) array, got shape (1, 5)"),
])
def test_bad_outputs(output, needle):
    with pytest.raises(ad.ModelError) as e:
        StateSpace(ad.Model.alpes("finger3"), output=output)
    assert needle in str(e.value)


def test_bad_contacts_and_frames():
    m = ad.Model.alpes("finger3")
    with pytest.raises(ad.ModelError, match=r"contact 'tip': dim must be 3 \(force\) or 6 \(wrench\), got 4"):
        Contact("tip", 4)
    with pytest.raises(ad.ModelError, match=r"contact 'tip': unknown reference 'body'"):
        Contact("tip", 3, "body")
    with pytest.raises(ad.ModelError, match=r"contacts: frame 'tip' appears twice"):
        StateSpace(m, contacts=["tip", "tip"])
    with pytest.raises(ad.ModelError, match=r"unknown tip/frame 'nail'"):
        StateSpace(m, contacts=["nail"])
    with pytest.raises(ad.ModelError, match=r"reference: unknown 'global'"):
        m.frame_jacobian(np.zeros(3), "tip", "global")
    with pytest.raises(ad.ModelError, match=r"dim: expected 3 \(linear rows\) or 6"):
        m.frame_jacobian(np.zeros(3), "tip", dim=2)
    with pytest.raises(ad.InputError, match=r"F\['tip'\]: expected a force \(3 values\) or a wrench \(6\), got 2"):
        m.forward_dynamics(np.zeros(3), np.zeros(3), np.zeros(3), F={"tip": [1.0, 2.0]})
    ss = StateSpace(m, contacts=[Contact("tip", 6)])
    with pytest.raises(ad.InputError, match=r"F: expected shape \(6,\), got \(3,\)"):
        ss.f(np.zeros(6), np.zeros(3), np.zeros(3))
    with pytest.raises(ad.InputError, match=r"F: this state space has contact forces as an input; pass F \(6,\)"):
        ss.f(np.zeros(6), np.zeros(3))
