"""Structure of the generated models, the hand, example-robot-data robots, the transmission."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy

import alpes_dyn as ad

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ad.MODELS)
def test_checked_in_urdf_is_current(name):
    """urdf/*.urdf equal what the generator makes from the shipped parameter file now."""
    assert (ROOT / "urdf" / f"{name}.urdf").read_text() == ad.urdf_string(name)


@pytest.mark.parametrize("name,dof", [("finger2", 2), ("finger3", 3), ("hand", 15)])
def test_urdf_loads_and_validates(name, dof):
    path = ROOT / "urdf" / f"{name}.urdf"
    robot = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=False)
    assert robot.validate()
    assert len(robot.actuated_joint_names) == dof
    model = pin.buildModelFromUrdf(str(path))
    assert model.nv == dof
    tips = [f.name for f in model.frames if f.name.endswith("tip")]
    assert len(tips) == (1 if dof < 15 else 5)


@pytest.mark.parametrize("name", ["finger2", "finger3"])
def test_inertia_about_joint_axis_is_the_tables(name):
    """URDF holds the COM inertia; moved to the joint axis it is the table's I_i = m_i L_i^2 / 3."""
    p = ad.load_params()
    robot = yourdfpy.URDF.load(str(ROOT / "urdf" / f"{name}.urdf"), build_scene_graph=False, load_meshes=False)
    for i, link in enumerate(sorted(l for l in robot.link_map if l.startswith("p"))):
        inert = robot.link_map[link].inertial
        d = inert.origin[0, 3]
        I_joint = inert.inertia[1, 1] + inert.mass * d**2
        assert I_joint == pytest.approx(p.finger.I[i], rel=1e-12)
        assert I_joint == pytest.approx(p.finger.m[i] * p.finger.L[i] ** 2 / 3, rel=1e-12)
        assert inert.mass == p.finger.m[i]


@pytest.mark.parametrize("name", ad.MODELS)
def test_inertia_matrix_symmetric_positive_definite(name, rng):
    m = ad.Model.alpes(name, rotor_inertia=True)
    for _ in range(10):
        q, _ = m.random_state(rng)
        A = m.inertia_matrix(q)
        assert np.array_equal(A, A.T)
        assert np.linalg.eigvalsh(A).min() > 0


@pytest.mark.parametrize("name", ad.MODELS)
def test_coriolis_skew_symmetry(name, rng):
    """A_dot - 2C is skew-symmetric; A_dot by central finite differences along qd."""
    m = ad.Model.alpes(name)
    for _ in range(5):
        q, v = m.random_state(rng)
        h = 1e-6
        Adot = (m.inertia_matrix(q + h * v) - m.inertia_matrix(q - h * v)) / (2 * h)
        N = Adot - 2 * m.coriolis_matrix(q, v)
        assert np.max(np.abs(N + N.T)) < 1e-7 * np.max(np.abs(Adot))


@pytest.mark.parametrize("name", ad.MODELS)
def test_gravity_is_gradient_of_potential(name, rng):
    """G(q) = dU/dq (gravity + springs), U from Pinocchio's potential energy + 1/2 k q^2, central differences."""
    m = ad.Model.alpes(name)
    q, _ = m.random_state(rng)
    h = 1e-6
    E = np.eye(m.n)
    grad = np.array([(m.potential_energy(q + h * e) - m.potential_energy(q - h * e)) / (2 * h) for e in E])
    assert np.max(np.abs(grad - m.gravity_torque(q))) < 1e-8


@pytest.mark.parametrize("name", ad.MODELS)
def test_gravity_jacobian_matches_finite_differences(name, rng):
    m = ad.Model.alpes(name)
    q, _ = m.random_state(rng)
    h = 1e-6
    fd = np.column_stack([(m.gravity_torque(q + h * e) - m.gravity_torque(q - h * e)) / (2 * h) for e in np.eye(m.n)])
    assert np.max(np.abs(m.gravity_jacobian(q) - fd)) < 1e-8 * max(1.0, np.max(np.abs(fd)))


def test_hand_fingers_equal_finger3_and_decouple(rng):
    """The hand's index block equals finger3 (same orientation, gravity and springs); blocks do not couple."""
    hand = ad.Model.alpes("hand")
    f3 = ad.Model.alpes("finger3")
    idx = {j: i for i, j in enumerate(hand.joint_names)}
    for _ in range(5):
        q, v = hand.random_state(rng)
        A = hand.inertia_matrix(q)
        for ch in hand.layout.chains:
            cols = [idx[j] for j in ch.joints] + ([idx[ch.abduction]] if ch.abduction else [])
            others = [i for i in range(hand.n) if i not in cols]
            assert np.all(A[np.ix_(cols, others)] == 0)
        for finger in ("index", "middle", "ring", "little"):
            sel = [idx[f"{finger}_j{k}"] for k in (1, 2, 3)]
            assert np.allclose(A[np.ix_(sel, sel)], f3.inertia_matrix(q[sel]), rtol=1e-12, atol=0)
            assert np.allclose(hand.gravity_torque(q)[sel], f3.gravity_torque(q[sel]), rtol=1e-12, atol=1e-18)
            tau = rng.normal(scale=0.05, size=hand.n)
            a = hand.forward_dynamics(q, v, tau)
            assert np.allclose(a[sel], f3.forward_dynamics(q[sel], v[sel], tau[sel]), rtol=1e-10, atol=1e-9)


def test_hand_thumb_abduction_has_no_gravity_torque(rng):
    """Ab/adduction about the palm normal z, gravity along -z: no gravity torque on that joint (assumed axis)."""
    hand = ad.Model.alpes("hand", spring="none")
    i = hand.joint_names.index("thumb_abd")
    for _ in range(5):
        q, _ = hand.random_state(rng)
        assert abs(hand.gravity_torque(q)[i]) < 1e-15


def test_fingertip_positions_at_rest():
    """At q = 0 each finger lies along +x from its base on the palm (parameter file)."""
    p = ad.load_params()
    hand = ad.Model.alpes("hand")
    q = np.zeros(hand.n)
    for name, (x, y) in zip(p.finger_names, p.finger_xy):
        assert np.allclose(hand.fingertip_position(q, f"{name}_tip"), [x + p.finger.L.sum(), y, 0.0], atol=1e-15)
    c, s = np.cos(p.thumb_yaw), np.sin(p.thumb_yaw)
    expect = p.thumb_xyz + p.thumb.L.sum() * np.array([c, s, 0.0])
    assert np.allclose(hand.fingertip_position(q, "thumb_tip"), expect, atol=1e-15)


def test_transmission_is_power_consistent(rng):
    hand = ad.Model.alpes("hand")
    tr = hand.transmission
    p = hand.params
    assert tr.motor_names == ("index", "middle", "ring", "little", "thumb", "thumb_abduction")
    assert tr.actuation_matrix.shape == (15, 6)
    q = rng.uniform(0, 1, 15)
    idx = {j: i for i, j in enumerate(hand.joint_names)}
    qm = tr.motor_positions(q)
    assert qm[0] == pytest.approx(p.r / p.r_m * sum(q[idx[f"index_j{k}"]] for k in (1, 2, 3)), rel=1e-14)
    assert qm[4] == pytest.approx(p.r / p.r_m * (q[idx["thumb_j1"]] + q[idx["thumb_j2"]]), rel=1e-14)
    assert qm[5] == pytest.approx(p.abduction_ratio * q[idx["thumb_abd"]], rel=1e-14)
    tau_m, qd = rng.normal(size=6), rng.normal(size=15)
    # tau_m . qdot_m == tau . qdot
    assert tau_m @ tr.motor_positions(qd) == pytest.approx(tr.joint_torque(tau_m) @ qd, rel=1e-13)
    step = 2 * np.pi / tr.counts_per_rev
    qq = tr.quantize(qm)
    assert np.all(np.abs(qq - qm) <= step / 2 + 1e-15) and np.allclose(qq / step, np.round(qq / step))


@pytest.mark.parametrize("robot,urdf", [("ur", "ur5_robot"), ("double_pendulum", None)])
def test_example_robot_data(robot, urdf, rng):
    """Any fixed-base URDF tree works; checked against Pinocchio's own RNEA and energy."""
    m = ad.Model.from_urdf_file(ad.example_robot_urdf(robot, urdf))
    tip = "tool0" if robot == "ur" else None  # UR5's three leaves name no default tip; the pendulum's one leaf does
    for _ in range(5):
        q, v = m.random_state(rng)
        tau = rng.normal(size=m.n)
        a = m.forward_dynamics(q, v, tau)
        assert np.allclose(m.inverse_dynamics(q, v, a), tau, rtol=1e-9, atol=1e-9)
        A = m.inertia_matrix(q)
        assert np.linalg.eigvalsh(A).min() > 0
        assert m.kinetic_energy(q, v) == pytest.approx(pin.computeKineticEnergy(m.pin_model, m.pin_data, q, v), rel=1e-12)
        J = m.fingertip_jacobian(q, tip)
        h = 1e-7
        Jfd = np.column_stack([(m.fingertip_position(q + h * e, tip) - m.fingertip_position(q - h * e, tip)) / (2 * h)
                               for e in np.eye(m.n)])
        assert np.max(np.abs(J - Jfd)) < 1e-7 and np.max(np.abs(J)) > 0.05


def test_gravity_is_passed_once():
    m = ad.Model.alpes("finger3", spring="none")
    assert np.array_equal(m.pin_model.gravity.linear, [0.0, 0.0, -9.81])
    m2 = ad.Model(m.urdf, gravity=[0.0, 0.0, -9.80665])
    q = np.array([0.3, 0.2, 0.1])
    assert np.allclose(m2.gravity_torque(q) / m.gravity_torque(q), 9.80665 / 9.81, rtol=1e-13)


def test_names_and_indices():
    """Joint order is Pinocchio's (depth first, siblings by child link name); motors and tips keep theirs."""
    import pinocchio as pin

    hand = ad.Model.alpes("hand")
    raw = pin.buildModelFromXML(hand.urdf)
    assert hand.joint_names == tuple(raw.names[1:])
    assert hand.joint_names[:4] == ("index_j1", "index_j2", "index_j3", "little_j1")  # not anatomical
    assert hand.motor_names == ("index", "middle", "ring", "little", "thumb", "thumb_abduction")
    assert hand.tip_names == ("index_tip", "middle_tip", "ring_tip", "little_tip", "thumb_tip")
    for j in ("thumb_abd", "ring_j2", "index_j1"):
        assert hand.joint_index(j) == raw.getJointId(j) - 1
    assert hand.motor_index("thumb") == 4
    # the column of a joint in S is the one joint_index names
    S = hand.transmission.S
    assert S[hand.motor_index("thumb_abduction"), hand.joint_index("thumb_abd")] == 1.0
    with pytest.raises(ad.ModelError, match=r"unknown joint 'thumb_j3' \(joints: index_j1, "):
        hand.joint_index("thumb_j3")
    with pytest.raises(ad.ModelError, match=r"unknown motor 'pinky' \(motors: index, "):
        hand.motor_index("pinky")
    ur = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"))
    assert ur.motor_names == ()
    with pytest.raises(ad.ModelError, match=r"unknown motor 'm' \(motors: none\)"):
        ur.motor_index("m")
