"""MJCF import (Model.from_mjcf): the export's round trip, and a hand-written MJCF against MuJoCo itself."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf import mjcf_string  # noqa: E402


@pytest.mark.parametrize("name, kw", [("finger3", {}), ("finger3", {"friction": True, "rotor_inertia": True}),
                                      ("hand", {"friction": True}), ("thumb", {"friction": True})])
def test_export_import_round_trip(name, kw):
    m = ad.Model.alpes(name, **kw)
    b = ad.Model.from_mjcf(mjcf_string(name, **kw))
    assert b.joint_names == m.joint_names and b.tips == m.tips
    assert b.transmission.motor_names == m.transmission.motor_names
    np.testing.assert_allclose(b.transmission.S, m.transmission.S, rtol=1e-15, atol=0)
    np.testing.assert_allclose(b.transmission.rotor_inertia, m.transmission.rotor_inertia, rtol=1e-14, atol=0)
    for f in ("stiffness", "armature", "coulomb", "viscous"):
        np.testing.assert_allclose(getattr(b.extras, f), getattr(m.extras, f), rtol=1e-15, atol=0)
    rng = np.random.default_rng(7)
    for _ in range(3):
        q, v = m.random_state(rng)
        tau = rng.normal(scale=0.05, size=m.n)
        np.testing.assert_allclose(b.inertia_matrix(q), m.inertia_matrix(q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.coriolis_matrix(q, v), m.coriolis_matrix(q, v), rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.gravity_torque(q), m.gravity_torque(q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.forward_dynamics(q, v, tau), m.forward_dynamics(q, v, tau), rtol=0, atol=1e-9)


# two hinges off their bodies' origins, rotated bodies and a rotated inertial frame: MuJoCo's own M(q) and bias
ARM = """<mujoco model="arm">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="a" pos="0.01 0.02 0.1" quat="0.9238795 0 0.3826834 0">
      <joint name="ja" type="hinge" axis="0 1 0" pos="0.02 0 0" range="-1 1" stiffness="0.3" damping="0.01"
             armature="1e-4" frictionloss="0.002"/>
      <inertial pos="0.05 0.01 0" quat="0.7071068 0.7071068 0 0" mass="0.2" diaginertia="1e-4 2e-4 3e-4"/>
      <body name="b" pos="0.1 0 0" euler="0.3 0 0.2">
        <joint name="jb" type="hinge" axis="0 0.6 0.8" pos="0 0.01 0" range="-2 2"/>
        <inertial pos="0.04 0 0.01" mass="0.1" diaginertia="5e-5 6e-5 7e-5"/>
        <site name="tip" pos="0.08 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="t"><joint joint="ja" coef="0.01"/><joint joint="jb" coef="0.008"/></fixed></tendon>
  <actuator><motor name="m" tendon="t" gear="100"/></actuator>
</mujoco>"""


def test_hand_written_mjcf_against_mujoco():
    b = ad.Model.from_mjcf(ARM)
    mj = mujoco.MjModel.from_xml_string(ARM)
    d = mujoco.MjData(mj)
    assert b.joint_names == ("ja", "jb") and b.tips == ("tip",) and b.name == "arm"
    np.testing.assert_allclose(b.transmission.S, [[1.0, 0.8]], rtol=1e-15)
    np.testing.assert_allclose(b.extras.stiffness, [0.3, 0.0])
    np.testing.assert_allclose(b.extras.coulomb, [0.002, 0.0])
    np.testing.assert_array_equal(b.lower, [-1.0, -2.0])
    rng = np.random.default_rng(0)
    for _ in range(4):
        q, v = rng.uniform(-1, 1, 2), rng.uniform(-2, 2, 2)
        d.qpos[:], d.qvel[:] = q, v
        mujoco.mj_forward(mj, d)
        M = np.zeros((2, 2))
        mujoco.mj_fullM(mj, d, M)
        np.testing.assert_allclose(b.inertia_matrix(q), M, rtol=1e-6, atol=1e-12)  # armature in both
        # MuJoCo's bias: C qd + gravity (its springs and damping are passive forces, apart)
        cg = b.coriolis_matrix(q, v) @ v + b.gravity_torque(q) - b.extras.stiffness * q
        np.testing.assert_allclose(cg, d.qfrc_bias, rtol=1e-6, atol=1e-12)
        # the site: the same frame
        np.testing.assert_allclose(b.frame_position(q, "tip") if hasattr(b, "frame_position") else
                                   b.fingertip_position(q, "tip"), d.site_xpos[0], rtol=0, atol=1e-7)


TIED_LATER = object()  # TIED with a connect equality (a closed loop), defined below


@pytest.mark.parametrize("xml, needle", [
    ("<mujoco><worldbody><body><freejoint/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/></body>"
     "</worldbody></mujoco>", "is a free joint"),
    ("<mujoco><worldbody><body><joint type='slide' name='s'/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/>"
     "</body></worldbody></mujoco>", "joint 's' is a slide joint"),
    ("<mujoco><worldbody><body name='x'><joint name='a'/><joint name='b' axis='1 0 0'/>"
     "<inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/></body></worldbody></mujoco>", "body 'x' has 2 joints"),
    ("<mujoco><worldbody><body><joint name='u'/><inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/></body>"
     "</worldbody></mujoco>", "joint 'u' has no range"),
    ("<mujoco><worldbody><body></mujoco>", "mjcf: MuJoCo cannot compile it"),
    ("<robot name='x'/>", "expected MJCF text containing a <mujoco> element"),
    ("no/such/file.xml", "'no/such/file.xml' is not a file"),
    (ARM.replace('gear="100"', 'gear="0"'), "actuator 'm' has gear 0; a motor's gear (its ratio) must be a non-zero"),
    (ARM.replace('<motor name="m" tendon="t" gear="100"/>', '<muscle name="m" tendon="t"/>'),
     "actuator 'm' is a muscle; the library's motors are torque sources"),
    (TIED_LATER, "equality 'loop' is a connect between 'c' and 'world': a closed kinematic loop"),
    ("<mujoco><worldbody>" + "".join(f"<body pos='{i} 0 0'><joint range='-1 1'/><inertial pos='0 0 0' mass='1' "
                                     "diaginertia='1 1 1'/></body>" for i in range(201)) + "</worldbody></mujoco>",
     "mjcf: its tree (imported as a URDF): 201 moving joints, over the limit of 200"),
])
def test_bad_mjcf(xml, needle):
    xml = TIED.replace('<joint name="couple"', '<connect name="loop" body1="c" body2="world" anchor="0.3 0 0"/>'
                                                '<joint name="couple"') if xml is TIED_LATER else xml
    with pytest.raises(ModelError, match=re.escape(needle)):
        ad.Model.from_mjcf(xml)


def test_springref_is_the_rest_angle():
    """A joint spring's springref becomes the spec's [rest_angle] (MJCF angles are degrees by default: 0.3 deg is
    0.00523599 rad); a springref without stiffness is no spring and is dropped."""
    m = ad.Model.from_mjcf("<mujoco><worldbody><body><joint name='a' stiffness='1' springref='0.3' range='-90 90'/>"
                           "<inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/><body pos='1 0 0'>"
                           "<joint name='b' springref='10' range='-90 90'/><inertial pos='0 0 0' mass='1' "
                           "diaginertia='1 1 1'/></body></body></worldbody></mujoco>")
    assert m.spec.rest_angle == {"a": pytest.approx(math.radians(0.3), rel=1e-12)}
    assert m.spring_torque(np.array([0.0, 0.0]))[0] == pytest.approx(-math.radians(0.3), rel=1e-12)


TIED = """<mujoco model="tied"><compiler angle="radian"/><option gravity="0 0 -9.81"/><worldbody>
  <body name="a"><joint name="j" axis="0 1 0" range="-1 1" stiffness="0.1" springref="0.2"/>
    <inertial pos="0.05 0 0" mass="0.1" diaginertia="1e-4 2e-4 3e-4"/>
    <body name="b" pos="0.1 0 0"><joint name="k" axis="0 1 0" range="-1 1" stiffness="0.2" springref="-0.1"
        damping="0.01" armature="1e-5" frictionloss="0.003"/>
      <inertial pos="0.05 0 0.01" mass="0.08" diaginertia="1e-4 1e-4 1e-4"/>
      <body name="c" pos="0.1 0 0"><joint name="l" axis="0 0.6 0.8" range="-1 1" stiffness="0.05" springref="0.3"
          damping="0.02" armature="2e-5" frictionloss="0.002"/>
        <inertial pos="0.04 0 0" mass="0.05" diaginertia="5e-5 6e-5 7e-5"/><site name="tip" pos="0.05 0 0"/></body>
    </body></body></worldbody>
  <equality><joint name="couple" joint1="l" joint2="k" polycoef="0.05 0.8 0 0 0"/></equality>
  <tendon><fixed name="t"><joint joint="j" coef="0.01"/><joint joint="k" coef="0.01"/><joint joint="l" coef="0.005"/>
  </fixed></tendon>
  <actuator><motor name="m" tendon="t" gear="100"/><motor name="ml" joint="l" gear="3"/></actuator>
</mujoco>"""
"""Three hinges, the last tied to the second by a joint equality (q_l = 0.05 + 0.8 q_k), each with a spring, the
two coupled ones with damping, armature and friction, a fixed tendon over all three and a motor on the tied joint."""


def test_joint_equality_with_fixed_tendon_against_mujoco():
    """The tied joint's rows are moved onto the joint it follows, as the same energies: the import's model (2
    coordinates) equals MuJoCo's full model projected on q_full = G q + o (G^T M G, G^T bias, G^T springs, G^T of the
    actuators' forces, G^T D G) to 1e-12 at random states; Coulomb F_k + |a| F_l. The tied joint's range is named
    as not imported (the library's limits are the independent joints')."""
    from alpes_dyn.model.mjcf_import import MjcfImportWarning

    with pytest.warns(MjcfImportWarning, match=r"joints l \(tied by a joint equality\): range not imported"):
        model = ad.Model.from_mjcf(TIED)
    assert model.joint_names == ("j", "k") and model.spec.motors[0].joints == {"j": 1.0, "k": pytest.approx(1.4)}
    assert model.spec.motors[1].joints == {"k": pytest.approx(2.4)}
    np.testing.assert_allclose(model.extras.coulomb, [0.0, 0.003 + 0.8 * 0.002], rtol=1e-14)
    mj = mujoco.MjModel.from_xml_string(TIED)
    d = mujoco.MjData(mj)
    G, o = np.array([[1, 0], [0, 1], [0, 0.8]]), np.array([0, 0, 0.05])
    rng = np.random.default_rng(12)
    for _ in range(4):
        q, v, u = rng.uniform(-0.8, 0.8, 2), rng.normal(size=2), rng.normal(size=2)
        d.qpos[:], d.qvel[:], d.ctrl[:] = G @ q + o, G @ v, u
        mujoco.mj_forward(mj, d)
        M = np.zeros((3, 3))
        mujoco.mj_fullM(mj, d, M)
        np.testing.assert_allclose(model.inertia_matrix(q), G.T @ M @ G, rtol=0, atol=1e-12)
        cg = model.coriolis_matrix(q, v) @ v + model.gravity_torque(q)
        np.testing.assert_allclose(cg, G.T @ (d.qfrc_bias - d.qfrc_spring), rtol=0, atol=1e-12)
        np.testing.assert_allclose(model.transmission.joint_torque(u, q), G.T @ d.qfrc_actuator, rtol=0, atol=1e-12)
        np.testing.assert_allclose(-model.extras.viscous * v, G.T @ d.qfrc_damper, rtol=0, atol=1e-12)


def test_hinge_ref_keeps_mujoco_coordinates():
    """A hinge's ``ref`` (MuJoCo's angle where the body is as written) keeps MuJoCo's coordinates: the limits are
    the MJCF's range, the tip site and M(q) are MuJoCo's at the same q (to 1e-12), the spring's rest its springref."""
    xml = ARM.replace('range="-1 1"', 'range="-1 1" ref="0.3" springref="0.1"').replace('range="-2 2"',
                                                                                        'range="-2 2" ref="-0.4"')
    b = ad.Model.from_mjcf(xml)
    mj = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(mj)
    np.testing.assert_array_equal(b.lower, [-1.0, -2.0])
    assert b.spec.rest_angle == {"ja": pytest.approx(0.1, rel=1e-12)}
    for q in (np.array([0.3, -0.4]), np.array([-0.7, 1.5]), np.array([0.9, 0.2])):
        d.qpos[:] = q
        mujoco.mj_forward(mj, d)
        M = np.zeros((2, 2))
        mujoco.mj_fullM(mj, d, M)
        np.testing.assert_allclose(b.fingertip_position(q, "tip"), d.site_xpos[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.inertia_matrix(q), M, rtol=0, atol=1e-12)
        np.testing.assert_allclose(b.spring_torque(q), -d.qfrc_spring, rtol=0, atol=1e-12)


@pytest.mark.parametrize("old, new, needle", [
    ('<body name="b"', '<body name="b" gravcomp="1"', "bodies b: gravcomp (MuJoCo's gravity compensation"),
    ('range="-2 2"', 'range="-2 2" stiffness="0.1 0.5 0"', "joints jb: stiffness (a spring's terms beyond the linear"),
    ('damping="0.01"', 'damping="0.01 0 0.2"', "joints ja: damping (a damper's terms beyond the linear one"),
    ('range="-2 2"', 'range="-2 2" stiffness="0.1" springyield="5"', "joints jb: springyield (a plastic spring"),
    ('range="-2 2"', 'range="-2 2" actuatorfrcrange="-1 1"', "joints jb: actuatorfrcrange (a limit on the actuators"),
])
def test_dynamics_attributes_named_as_not_imported(old, new, needle):
    """What changes the dynamics and has no place in the spec -- MuJoCo's gravity compensation of a body, MuJoCo 4's
    nonlinear spring and damper terms, a plastic spring, a joint's actuator force limit -- is named in the import's
    warning and in ``not_imported``, the element given."""
    from alpes_dyn.model.mjcf_import import MjcfImportWarning, not_imported

    xml = ARM.replace(old, new, 1)
    with pytest.warns(MjcfImportWarning, match=re.escape(needle)):
        ad.Model.from_mjcf(xml)
    assert any(x.startswith(needle) for x in not_imported(mujoco.MjModel.from_xml_string(xml)))


def test_huge_or_deep_mjcf_refused_before_mujoco(monkeypatch):
    """A 200,000-site MJCF and a 500-deep chain are refused by the import's own scan (the URDF's limits), before
    MuJoCo's parser runs (it would spend 42 s and 650 MB on the sites, and stop at the depth with 'XML parse error
    18')."""
    def no_compile(*args, **kwargs):
        raise AssertionError("MuJoCo's parser was reached")

    monkeypatch.setattr(mujoco.MjModel, "from_xml_string", no_compile)
    body = '<body name="b{0}"><joint name="j{0}" range="-1 1"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'
    sites = ("<mujoco><worldbody>" + body.format(0) + "".join(f'<site name="s{i}"/>' for i in range(200_000))
             + "</body></worldbody></mujoco>")
    with pytest.raises(ModelError, match=r"^mjcf: over 1000 bodies and sites, the limit \(each a link of the "):
        ad.Model.from_mjcf(sites)
    deep = ("<mujoco><worldbody>" + "".join(body.format(i) for i in range(500)) + "</body>" * 500
            + "</worldbody></mujoco>")
    with pytest.raises(ModelError, match=r"^mjcf: bodies nested over 100 deep, the limit"):
        ad.Model.from_mjcf(deep)


def test_nan_named_and_no_mujoco_log(tmp_path, monkeypatch):
    """A NaN in an MJCF is refused naming the element and attribute (not Pinocchio's URDF parser), and MuJoCo's
    warning is not written as MUJOCO_LOG.TXT in the working folder, also where it comes from an included file."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ModelError, match=r"^mjcf: <body name='b'> pos='0.1 nan 0': a number is NaN$"):
        ad.Model.from_mjcf(ARM.replace('<body name="b" pos="0.1 0 0"', '<body name="b" pos="0.1 nan 0"'))
    (tmp_path / "part.xml").write_text('<mujoco><worldbody><body name="n" pos="nan 0 0"><joint name="jn" '
                                       'range="-1 1"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>'
                                       "</worldbody></mujoco>")
    (tmp_path / "main.xml").write_text('<mujoco><include file="part.xml"/></mujoco>')
    with pytest.raises(ModelError, match=r"^mjcf: a number is NaN \(XML contains a 'NaN'"):
        ad.Model.from_mjcf(tmp_path / "main.xml")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["main.xml", "part.xml"]
