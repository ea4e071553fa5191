"""A real hand from MuJoCo Menagerie (issue 37): the Shadow Hand E3M5 shipped in ``alpes_dyn/data/shadow_hand``
(its kinematics and dynamics as published, meshes replaced by primitives), imported as a URDF + spec and checked
against MuJoCo on the MJCF itself: the mass matrix, the bias, the passive damping, a pulled tendon's joint torques
and the forward dynamics, at random states. Nothing is downloaded."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf_import import MjcfImportWarning, example_mjcf_path, mjcf_to_urdf  # noqa: E402

TENDONS = {"rh_A_FFJ0": ("rh_FFJ2", "rh_FFJ1"), "rh_A_MFJ0": ("rh_MFJ2", "rh_MFJ1"),
           "rh_A_RFJ0": ("rh_RFJ2", "rh_RFJ1"), "rh_A_LFJ0": ("rh_LFJ2", "rh_LFJ1")}


@pytest.fixture(scope="module")
def shadow():
    path = example_mjcf_path("shadow_hand")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        urdf, spec = mjcf_to_urdf(path)
    model = ad.Model(urdf, spec)
    mj = mujoco.MjModel.from_xml_path(str(path))
    return model, mj, caught


def _mj_joints(mj) -> list[str]:
    return [mujoco.mj_id2name(mj, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(mj.njnt)]


def test_shadow_hand_imports_with_its_couplings_and_says_what_it_drops(shadow):
    model, mj, caught = shadow
    assert model.n == 24 and len(model.motor_names) == 20 and model.name == "right_shadow_hand"
    assert sorted(_mj_joints(mj)) == sorted(model.joint_names)  # Pinocchio orders them its own way
    S = model.transmission.S
    for motor, joints in TENDONS.items():  # the fixed tendon: q_m = q_J2 + q_J1
        row = S[model.motor_names.index(motor)]
        assert {model.joint_names[i]: row[i] for i in np.flatnonzero(row)} == {j: 1.0 for j in joints}
    assert np.count_nonzero(S) == 16 + 8  # 16 one-joint servos, 4 tendons over 2 joints
    for field, value in (("armature", 2e-4), ("coulomb", 0.01)):
        np.testing.assert_array_equal(getattr(model.extras, field), np.full(24, value))
    assert model.extras.viscous[model.joint_names.index("rh_WRJ1")] == 0.5  # the wrist class's damping
    assert model.tip_names == ("rh_ffdistal", "rh_mfdistal", "rh_rfdistal", "rh_lfdistal", "rh_thdistal")
    msgs = [str(w.message) for w in caught if issubclass(w.category, MjcfImportWarning)]
    assert len(msgs) == 1 and "gainprm/biasprm" in msgs[0] and "forcerange" in msgs[0], msgs


def test_shadow_hand_dynamics_equal_mujoco(shadow):
    """M(q) (armature in both), the bias C(q, v) v + g(q), the damping's passive force, the actuators' joint torques
    (a pulled tendon: S^T of MuJoCo's actuator forces is its qfrc_actuator, nonzero on the tendon's two joints only)
    and the forward dynamics, to 1e-9 (relative to each term's size) at random states."""
    model = shadow[0]
    mj = mujoco.MjModel.from_xml_path(str(example_mjcf_path()))  # a copy of its own: changed below
    mj.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_FRICTIONLOSS | mujoco.mjtDisableBit.mjDSBL_CONTACT)
    d = mujoco.MjData(mj)
    rng = np.random.default_rng(37)
    nu = mj.nu
    p = [model.joint_names.index(j) for j in _mj_joints(mj)]  # MuJoCo's joint k is the model's p[k]
    for k in range(4):
        q, v = model.random_state(rng)  # inside the ranges: no limit active
        d.qpos[:], d.qvel[:] = q[p], v[p]
        mujoco.mj_kinematics(mj, d)
        mujoco.mj_comPos(mj, d)
        mujoco.mj_tendon(mj, d)
        mujoco.mj_transmission(mj, d)
        d.ctrl[:] = d.actuator_length + rng.uniform(-0.2, 0.2, nu)  # every servo pulls (forcerange clips some)
        if k == 0:  # one pulled tendon alone: the first finger's, the other servos at their set point
            d.ctrl[:] = d.actuator_length
            d.ctrl[model.motor_names.index("rh_A_FFJ0")] += 1.0
        mujoco.mj_forward(mj, d)
        assert d.nefc == 0  # no limit, contact or friction constraint: the plain equations of motion
        M = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, d, M)
        A = model.inertia_matrix(q)[np.ix_(p, p)]
        assert np.max(np.abs(A - M)) <= 1e-9 * np.max(np.abs(M))
        bias = (model.coriolis_matrix(q, v) @ v + model.gravity_torque(q))[p]
        assert np.max(np.abs(bias - d.qfrc_bias)) <= 1e-9 * np.max(np.abs(d.qfrc_bias))
        np.testing.assert_allclose((-model.extras.viscous * v)[p], d.qfrc_passive, rtol=1e-12, atol=1e-15)
        tau = model.transmission.joint_torque(d.actuator_force)  # Gamma = S^T tau_m (motors in MuJoCo's order)
        assert np.max(np.abs(tau[p] - d.qfrc_actuator)) <= 1e-12 * np.max(np.abs(d.qfrc_actuator))
        if k == 0:
            moved = np.flatnonzero(np.abs(d.qfrc_actuator) > 1e-12)
            assert {_mj_joints(mj)[i] for i in moved} == set(TENDONS["rh_A_FFJ0"])
            assert np.all(d.qfrc_actuator[moved] > 0.1)  # pulled by kp (ctrl - length) = 0.5 N m, clipped to 1
        # the library's Coulomb friction cancelled (MuJoCo's frictionloss, a constraint, is disabled here)
        qdd = model.forward_dynamics(q, v, tau + model.extras.coulomb * np.sign(v))
        assert np.max(np.abs(qdd[p] - d.qacc)) <= 1e-9 * np.max(np.abs(d.qacc))


def test_shadow_hand_import_cli(capsys, tmp_path):
    """``alpes-dyn import`` on the shipped file: the pair written, the JSON's "not_imported" naming the servo gains,
    the force ranges and the geoms; one warning line on stderr; the pair loads as the model Model.from_mjcf gives."""
    code = main(["import", "--model", str(example_mjcf_path()), "--out-dir", str(tmp_path / "out"), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    obj = json.loads(out)
    assert err.startswith("alpes-dyn: warning: MjcfImportWarning: mjcf: not imported: actuators rh_A_WRJ2")
    lost = obj["not_imported"]
    assert len(lost) == 3 and "gainprm/biasprm" in lost[0] and "forcerange" in lost[1] and lost[2].startswith("geoms")
    m = ad.Model.from_urdf_file(obj["urdf"], obj["spec"])
    assert m.joint_names == tuple(obj["joints"]) and len(obj["motors"]) == 20 and obj["held"] == []
    assert main(["import", "--model", str(example_mjcf_path()), "--out-dir", str(tmp_path / "held"), "--hold",
                 "rh_WRJ2,rh_WRJ1", "--json"]) == 0
    held = json.loads(capsys.readouterr().out)
    assert held["held"] == ["rh_WRJ2", "rh_WRJ1"] and len(held["joints"]) == 22 and "rh_A_WRJ2" not in held["motors"]
    # the pair exported back to MJCF (its root link is named "world": MuJoCo's own world body, not a second one)
    assert main(["mjcf", "--model", obj["urdf"], "--spec", obj["spec"], "-o", str(tmp_path / "back.xml")]) == 0
    back = ad.Model.from_mjcf(tmp_path / "back.xml")
    q = m.random_state(np.random.default_rng(1))[0]
    assert back.joint_names == m.joint_names and back.motor_names == m.motor_names
    np.testing.assert_allclose(back.inertia_matrix(q), m.inertia_matrix(q), rtol=0, atol=1e-15)
    np.testing.assert_allclose(back.gravity_torque(q), m.gravity_torque(q), rtol=0, atol=1e-14)


def test_a_pulled_tendon_moves_the_same_joints_as_in_mujoco(shadow):
    """MuJoCo steps the MJCF (RK4, 0.1 ms) with one tendon pulled at 0.3 N m, the other servos off and gravity, limits,
    contacts and frictionloss off; the imported model integrated by the same RK4 on tau = S^T f (the spec without
    its Coulomb friction) follows it over 30 ms to 1e-9 rad, and the tendon's two joints move the most."""
    import dataclasses

    model = shadow[0]
    mj = mujoco.MjModel.from_xml_path(str(example_mjcf_path()))  # a copy of its own: changed below
    free = ad.Model(model.urdf, dataclasses.replace(model.spec, coulomb={}, gravity=(0.0, 0.0, 0.0)))
    D = mujoco.mjtDisableBit
    mj.opt.disableflags |= int(D.mjDSBL_FRICTIONLOSS | D.mjDSBL_CONTACT | D.mjDSBL_LIMIT | D.mjDSBL_GRAVITY)
    mj.opt.integrator, mj.opt.timestep = int(mujoco.mjtIntegrator.mjINT_RK4), 1e-4
    a = model.motor_names.index("rh_A_FFJ0")
    mj.actuator_gainprm[:] = 0.0
    mj.actuator_biasprm[:] = 0.0
    mj.actuator_gainprm[a, 0] = 1.0  # force = ctrl along the tendon, every other servo off
    mj.actuator_forcelimited[:] = 0
    mj.actuator_ctrllimited[:] = 0
    d = mujoco.MjData(mj)
    p = [model.joint_names.index(j) for j in _mj_joints(mj)]
    q0 = 0.5 * (model.lower + model.upper)
    d.qpos[:] = q0[p]
    d.ctrl[a] = 0.3
    f = np.zeros(len(model.motor_names))
    f[a] = 0.3
    tau = free.transmission.joint_torque(f)
    x, h = np.concatenate([q0, np.zeros(model.n)]), 1e-4

    def rhs(x):
        return np.concatenate([x[model.n:], free.forward_dynamics(x[:model.n], x[model.n:], tau)])
    for _ in range(300):
        mujoco.mj_step(mj, d)
        k1 = rhs(x)
        k2 = rhs(x + h / 2 * k1)
        k3 = rhs(x + h / 2 * k2)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + rhs(x + h * k3))
    np.testing.assert_allclose(x[:model.n][p], d.qpos, rtol=0, atol=1e-9)  # seen: 1e-18
    moved = np.abs(x[:model.n] - q0)
    top = {model.joint_names[i] for i in np.argsort(moved)[-2:]}
    assert top == set(TENDONS["rh_A_FFJ0"]) and moved.max() > 1e-3, moved


def test_what_changes_the_motors_and_is_not_imported_is_named():
    """A tendon's length limit, activation dynamics and a force range: one MjcfImportWarning naming each field (the
    spec's motors are torque sources on the same transmission, S unchanged); a plain motor gets none."""
    xml = """<mujoco><worldbody><body><joint name="a" range="-1 1"/><inertial pos="0.1 0 0" mass="1"
      diaginertia="1e-3 1e-3 1e-3"/></body></worldbody>
      <tendon><fixed name="t" range="-0.5 0.5"><joint joint="a" coef="0.01"/></fixed></tendon>
      <actuator><general name="g" tendon="t" dyntype="filter" dynprm="0.05" gear="50" forcerange="-2 2"/>
      </actuator></mujoco>"""
    with pytest.warns(MjcfImportWarning) as caught:
        m = ad.Model.from_mjcf(xml)
    (msg,) = [str(w.message) for w in caught]
    for needle in ("actuators g: activation dynamics (dyntype)", "actuators g: forcerange",
                   "tendons t: range (a tendon length limit)"):
        assert needle in msg, msg
    assert "gainprm" not in msg  # a general actuator of gain 1 and no bias is a torque source
    np.testing.assert_allclose(m.transmission.S, [[0.5]], rtol=1e-15)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ad.Model.from_mjcf(xml.replace(' dyntype="filter" dynprm="0.05"', "").replace(' forcerange="-2 2"', "")
                           .replace(' range="-0.5 0.5"', ""))


def test_held_wrist_makes_each_finger_a_branch(shadow):
    """``hold`` welds the wrist: 22 joints, 18 motors, the same M and bias as MuJoCo on the MJCF with the two wrist
    joints and servos deleted from its text; the first finger's tendon then closes over its own 4 joints only."""
    import re

    from alpes_dyn.model.subtree import closed_motors

    text = example_mjcf_path().read_text()
    text = re.sub(r'\s*<joint class="wrist_[xy]" name="rh_WRJ[12]"/>', "", text)
    text = re.sub(r'\s*<position name="rh_A_WRJ[12]"[^>]*/>', "", text)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MjcfImportWarning)
        held = ad.Model.from_mjcf(example_mjcf_path(), hold=["rh_WRJ2", "rh_WRJ1"])
    assert held.n == 22 and len(held.motor_names) == 18 and "rh_A_WRJ1" not in held.motor_names
    mj = mujoco.MjModel.from_string(text) if hasattr(mujoco.MjModel, "from_string") else \
        mujoco.MjModel.from_xml_string(text)
    assert mj.nq == 22
    d = mujoco.MjData(mj)
    p = [held.joint_names.index(j) for j in _mj_joints(mj)]
    q, v = held.random_state(np.random.default_rng(5))
    d.qpos[:], d.qvel[:] = q[p], v[p]
    mujoco.mj_forward(mj, d)
    M = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, d, M)
    assert np.max(np.abs(held.inertia_matrix(q)[np.ix_(p, p)] - M)) <= 1e-12 * np.max(np.abs(M))
    bias = (held.coriolis_matrix(q, v) @ v + held.gravity_torque(q))[p]
    assert np.max(np.abs(bias - d.qfrc_bias)) <= 1e-12 * np.max(np.abs(d.qfrc_bias))
    assert set(closed_motors(held, "rh_A_FFJ0")) == {"rh_A_FFJ4", "rh_A_FFJ3", "rh_A_FFJ0"}
    assert len(closed_motors(shadow[0], "rh_A_FFJ0")) == 20  # with the wrist free: the whole hand


def test_a_springless_hand_s_rest_refused_with_what_the_user_gives(shadow):
    """The published hand has no spring (its joints held by position servos, imported as torque motors): with the
    motors off gravity alone places the joints, 13 of 24 past their ranges. The force loop's block refuses that rest
    naming every such joint's count and what the spec needs (springs, rest angles inside the ranges); the same hand
    with springs at mid-range rests inside its ranges, where gravity and the springs balance (to 1e-9 N m)."""
    import dataclasses

    from alpes_dyn.model.block_scene import place_block

    model = shadow[0]
    with pytest.raises(ad.InputError) as err:
        place_block(model, "rh_ffdistal", "rh_A_FFJ0")
    msg = str(err.value)
    assert "joint 'rh_WRJ2' at 0.7108 rad" in msg and "(and 12 more:" in msg, msg
    assert "13 of them have no spring" in msg and "[stiffness]" in msg and "[rest_angle]" in msg, msg
    mid = {j: 0.5 * (lo + hi) for j, lo, hi in zip(model.joint_names, model.lower, model.upper)}
    spec = dataclasses.replace(model.spec, stiffness={j: 1.0 for j in model.joint_names}, rest_angle=mid,
                               spring=None)
    sprung = ad.Model(model.urdf, spec)
    scene = place_block(sprung, "rh_ffdistal", "rh_A_FFJ0")
    rest = sprung.static_equilibrium(np.zeros(sprung.n))
    assert np.all((sprung.lower <= rest) & (rest <= sprung.upper))
    spring = 1.0 * (rest - np.array([mid[j] for j in sprung.joint_names]))  # k (q - q_rest), k = 1 N m/rad
    assert np.max(np.abs(model.gravity_torque(rest) + spring)) < 1e-9  # the springless hand's gravity alone
    assert np.allclose(scene.rest_q, rest, atol=1e-12)
