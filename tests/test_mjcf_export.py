"""MJCF export of any Model (model_mjcf, Model.to_mjcf): the round trip through Model.from_mjcf, MuJoCo's own
mass matrix, bias, passive and actuator forces on the text, and what MuJoCo cannot express refused."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.model.description import example_robot_urdf
from alpes_dyn.model.spec import Motor, TransmissionSpec, example_spec_path

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf import joint_permutation  # noqa: E402
from alpes_dyn.model.mjcf_export import model_mjcf  # noqa: E402

# a revolute and a prismatic joint on unaligned axes, rotated joint origins, a fixed link merged into its parent,
# a rotated inertia, a tendon over both joints with a rotor, a direct motor, springs and friction
ARM_URDF = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.05 0.01 0" rpy="0.3 0.1 0"/><mass value="0.2"/>
    <inertia ixx="1e-4" ixy="1e-6" ixz="0" iyy="2e-4" iyz="2e-6" izz="2.5e-4"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.04 0 0.01"/><mass value="0.1"/>
    <inertia ixx="5e-5" ixy="0" ixz="0" iyy="6e-5" iyz="0" izz="7e-5"/></inertial></link>
  <link name="c"><inertial><origin xyz="0.02 0 0"/><mass value="0.05"/>
    <inertia ixx="2e-5" ixy="0" ixz="0" iyy="2e-5" iyz="0" izz="3e-5"/></inertial></link>
  <link name="pad"><inertial><origin xyz="0.01 0 0"/><mass value="0.01"/>
    <inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial></link>
  <link name="tip"/>
  <joint name="ja" type="revolute"><parent link="base"/><child link="a"/><origin xyz="0.01 0.02 0.1" rpy="0 0.785 0"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="jb" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.1 0.01 0" rpy="0.3 0 0.2"/>
    <axis xyz="0 0.6 0.8"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
  <joint name="jc" type="prismatic"><parent link="b"/><child link="c"/><origin xyz="0.08 0 0" rpy="0 0 0.4"/>
    <axis xyz="1 0 0"/><limit lower="-0.02" upper="0.03" effort="1" velocity="1"/></joint>
  <joint name="pad_fixed" type="fixed"><parent link="c"/><child link="pad"/><origin xyz="0.03 0 0" rpy="0.2 0 0"/></joint>
  <joint name="tip_fixed" type="fixed"><parent link="pad"/><child link="tip"/><origin xyz="0.02 0 0"/></joint>
</robot>
"""
ARM_SPEC = TransmissionSpec(
    motors=(Motor("tendon", {"ja": 1.5, "jb": -0.8}, rotor_inertia=3e-6), Motor("slider", {"jc": 40.0}, 1e-8)),
    stiffness={"ja": 0.3, "jc": 20.0}, coulomb={"jb": 0.002}, viscous={"ja": 0.01, "jc": 0.5},
    armature={"jb": 1e-5}, tips=("tip",), gravity=(0.5, -1.0, -9.7))


@functools.lru_cache(maxsize=None)
def robot(name: str) -> ad.Model:
    if name == "allegro":
        return ad.Model.from_urdf_file(example_robot_urdf("allegro_hand", "allegro_right_hand"), example_spec_path())
    if name == "arm":
        return ad.Model(ARM_URDF, ARM_SPEC)
    return ad.Model.alpes(name, friction=True, rotor_inertia=True)


ROUND_TRIP = ("finger3", "hand", "thumb", "allegro")


def _max(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))))


@pytest.mark.parametrize("name", ROUND_TRIP)
def test_round_trip_through_from_mjcf(name):
    m = robot(name)
    b = ad.Model.from_mjcf(m.to_mjcf())
    assert b.joint_names == m.joint_names and b.motor_names == m.motor_names
    assert sorted(b.tips) == sorted(m.tips)  # the import lists them in tree order
    assert _max(b.transmission.S, m.transmission.S) == 0
    assert _max(b.transmission.rotor_inertia, m.transmission.rotor_inertia) == 0
    assert _max(b.rotor_matrix, m.rotor_matrix) == 0
    for f in ("stiffness", "armature", "coulomb", "viscous"):
        assert _max(getattr(b.extras, f), getattr(m.extras, f)) == 0, f
    np.testing.assert_array_equal(b.lower, m.lower)
    np.testing.assert_array_equal(b.upper, m.upper)
    np.testing.assert_array_equal(b.gravity, m.gravity)
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, v = m.random_state(rng)
        tau = rng.normal(scale=0.05, size=m.n)
        assert _max(b.inertia_matrix(q), m.inertia_matrix(q)) <= 1e-12
        assert _max(b.coriolis_matrix(q, v) @ v, m.coriolis_matrix(q, v) @ v) <= 1e-12
        assert _max(b.gravity_torque(q), m.gravity_torque(q)) <= 1e-12
        qdd = m.forward_dynamics(q, v, tau)
        assert _max(b.forward_dynamics(q, v, tau), qdd) <= 1e-12 * max(1.0, float(np.max(np.abs(qdd))))
        for tip in m.tips:
            assert _max(b.fingertip_position(q, tip), m.fingertip_position(q, tip)) <= 1e-14


@pytest.mark.parametrize("name", ROUND_TRIP + ("arm",))
def test_mujoco_dynamics_on_the_export(name):
    """MuJoCo's M, bias, passive and actuator forces and sensors on the text = the library's terms."""
    m = robot(name)
    mj = mujoco.MjModel.from_xml_string(model_mjcf(m))
    d = mujoco.MjData(mj)
    assert mj.opt.timestep == 1e-4 and mj.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    np.testing.assert_array_equal(mj.opt.gravity, m.gravity)
    perm = joint_permutation(mj, m.joint_names)
    np.testing.assert_array_equal(perm, np.arange(m.n))  # MuJoCo's qpos order is the library's joint order
    S, k, rest = m.transmission.S, m.extras.stiffness, m.extras.rest
    rng = np.random.default_rng(11)
    for _ in range(5):
        q, v = m.random_state(rng)  # inside the ranges: no limit force
        tau_m = rng.normal(scale=0.05, size=S.shape[0])
        d.qpos[:], d.qvel[:], d.ctrl[:] = q, v, tau_m
        mujoco.mj_forward(mj, d)
        M = np.zeros((m.n, m.n))
        mujoco.mj_fullM(mj, M, d.qM) if hasattr(d, "qM") else mujoco.mj_fullM(mj, d, M)
        assert _max(M, m.inertia_matrix(q)) <= 1e-12  # A + armature + S^T diag(J_m) S
        assert _max(d.qfrc_bias, m.coriolis_matrix(q, v) @ v + m.gravity_torque(q) - k * (q - rest)) <= 1e-12
        assert _max(d.qfrc_passive, -k * (q - rest) - m.extras.viscous * v) <= 1e-12
        assert _max(d.qfrc_actuator, S.T @ tau_m) <= 1e-12
        for i, motor in enumerate(m.motor_names):
            assert abs(d.sensor(f"encoder_{motor}").data[0] - S[i] @ q) <= 1e-12
            assert abs(d.sensor(f"torque_{motor}").data[0] - tau_m[i]) <= 1e-15
        for tip in m.tips:
            assert _max(d.site(tip).xpos, m.fingertip_position(q, tip)) <= 1e-12
            assert d.sensor(f"touch_{tip}").data[0] == 0.0  # nothing to touch


def test_mujoco_steps_the_export_like_the_library():
    """One RK4 step of MuJoCo without friction constraints (frictionloss) = the library's acceleration."""
    m = ad.Model.alpes("finger3", rotor_inertia=True)
    mj = mujoco.MjModel.from_xml_string(m.to_mjcf(limits=False))
    d = mujoco.MjData(mj)
    q, v = np.array([0.3, 0.5, 0.2]), np.array([0.4, -0.2, 0.1])
    d.qpos[:], d.qvel[:], d.ctrl[:] = q, v, [0.02]
    mujoco.mj_forward(mj, d)
    np.testing.assert_allclose(d.qacc, m.forward_dynamics(q, v, m.transmission.joint_torque([0.02])),
                               rtol=1e-10, atol=1e-12)


def test_without_transmission_and_prismatic_import_limit():
    m = ad.Model(ARM_URDF)  # no spec: no motors, springs, friction; tips: the URDF's leaves
    text = model_mjcf(m, tip_radius=0.0)
    assert "<tendon>" not in text and "<actuator>" not in text and "<geom" not in text
    mj = mujoco.MjModel.from_xml_string(text)
    assert (mj.ntendon, mj.nu, mj.nsite, mj.ngeom) == (0, 0, 1, 0)
    assert mj.sensor(f"touch_{m.tips[0]}").type == mujoco.mjtSensor.mjSENS_TOUCH
    with pytest.raises(ModelError, match="joint 'jc' is a slide joint"):  # the import's limitation, named
        ad.Model.from_mjcf(text)


def test_no_limits_and_options():
    m = robot("finger3")
    text = model_mjcf(m, limits=False, timestep=2e-4, integrator="implicitfast")
    mj = mujoco.MjModel.from_xml_string(text)
    assert not mj.jnt_limited.any() and mj.opt.timestep == 2e-4
    assert mj.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    with pytest.raises(ModelError, match="joint 'j1' has no range"):  # the import needs ranges
        ad.Model.from_mjcf(text)
    assert model_mjcf(m) == m.to_mjcf()  # deterministic, the method is the function
    for kw, needle in (({"timestep": 0}, "timestep"), ({"integrator": "rk4"}, "integrator"),
                       ({"tip_radius": -1.0}, "tip_radius"), ({"limits": "yes"}, "limits")):
        with pytest.raises(InputError, match=needle):
            model_mjcf(m, **kw)
    with pytest.raises(ModelError, match="expected an alpes_dyn.Model"):
        model_mjcf(ARM_URDF)


def _with_inertial(mass: str, inertia: str) -> str:
    """ARM_URDF with link b's inertial replaced."""
    old = ('<inertial><origin xyz="0.04 0 0.01"/><mass value="0.1"/>\n    <inertia ixx="5e-5" ixy="0" ixz="0" '
           'iyy="6e-5" iyz="0" izz="7e-5"/></inertial>')
    assert old in ARM_URDF
    ixx, iyy, izz = inertia.split()
    return ARM_URDF.replace(old, f'<inertial><origin xyz="0.04 0 0.01"/><mass value="{mass}"/><inertia ixx="{ixx}" '
                                 f'ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>')


@pytest.mark.parametrize("mass, inertia, needle", [
    ("0", "0 0 0", "link 'b' moves but has mass 0; MuJoCo needs a positive mass"),
    ("0.1", "0 0 0", "link 'b' has a singular inertia"),
    ("0.1", "1e-5 1e-5 5e-5", "link 'b' has an inertia that breaks the triangle inequality"),
])
def test_what_mujoco_cannot_express_is_refused(mass, inertia, needle):
    m = ad.Model(_with_inertial(mass, inertia), ARM_SPEC)  # the library takes it (relaxed inertia check)
    with pytest.raises(ModelError, match=needle):
        m.to_mjcf()


def test_spec_without_mujoco_counterpart_is_not_written():
    """The encoder resolution and the smooth sign's v_s are not dynamics MuJoCo has: they change nothing."""
    a = ad.Model(ARM_URDF, ARM_SPEC)
    b = ad.Model(ARM_URDF, dataclasses.replace(ARM_SPEC, encoder_counts=100.0, smooth_velocity=0.5))
    assert a.to_mjcf() == b.to_mjcf()


def test_elastic_tendon_is_refused_by_name():
    """The tendon compliance (an encoder law, y = S q + C tau_m) has no MJCF form: refused, never dropped."""
    from dataclasses import replace

    from alpes_dyn.errors import ModelError
    from alpes_dyn.model.mjcf_export import model_mjcf
    from alpes_dyn.model.spec import Motor

    m = ad.Model.alpes("finger3")
    spec = replace(m.spec, motors=tuple(Motor(mo.name, mo.joints, 0.0, 6.3) for mo in m.spec.motors))
    with pytest.raises(ModelError, match="tendon_compliance: an elastic tendon"):
        model_mjcf(ad.Model(m.urdf, spec))


def test_cli_mjcf_of_a_urdf_with_its_spec(tmp_path, capsys):
    """``alpes-dyn mjcf PATH.urdf --spec FILE`` writes model_mjcf of that model (the Allegro and its shipped spec),
    ``--no-limits`` included; MuJoCo loads it."""
    from alpes_dyn.cli import main

    urdf = example_robot_urdf("allegro_hand", "allegro_right_hand")
    model = ad.Model.from_urdf_file(urdf, example_spec_path())
    assert main(["mjcf", "--model", str(urdf), "--spec", str(example_spec_path())]) == 0
    assert capsys.readouterr().out == model_mjcf(model)
    out = tmp_path / "allegro.xml"
    assert main(["mjcf", "--model", str(urdf), "--spec", str(example_spec_path()), "--no-limits", "-o", str(out)]) == 0
    assert out.read_text() == model_mjcf(model, limits=False)
    mj = mujoco.MjModel.from_xml_string(out.read_text())
    assert mj.nv == model.n and mj.ntendon == model.transmission.n_motors
