"""MJCF spatial tendons as MuJoCo publishes them (issue 51, items 1-2): MuJoCo's sparse tendon Jacobian read as
such, a two-joint arm after MuJoCo's ``tendon_arm/arm26.xml`` (its muscles replaced by motors) imported exactly
where its tendons stay on their wrapping cylinders, and refused, the tendon and the reason named, where a tendon
leaves its cylinder or changes side of it over a joint's range (no polynomial of the joint angle follows the kink or
the jump of its moment arm)."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf_spatial import MjcfCurveWarning, tendon_jacobian  # noqa: E402

ARM26 = """<mujoco model="arm26">
  <default><joint type="hinge" pos="0 0 0" axis="0 0 1" limited="true" range="0 120" damping="0.1"/></default>
  <worldbody>
    <site name="s0" pos="-0.15 0 0"/><site name="x0" pos="0 -0.15 0"/>
    <body pos="0 0 0">
      <geom name="upper arm" type="capsule" size="0.045" fromto="0 0 0  0.5 0 0"/>
      <joint name="shoulder"/>
      <geom name="shoulder" type="cylinder" pos="0 0 0" size=".1 .05" mass="0"/>
      <site name="s1" pos="0.15 0.06 0"/><site name="s2" pos="0.15 -0.06 0"/>
      <site name="s3" pos="0.4 0.06 0"/><site name="s4" pos="0.4 -0.06 0"/>
      <site name="s5" pos="0.25 0.1 0"/><site name="s6" pos="0.25 -0.1 0"/><site name="x1" pos="0.5 -0.15 0"/>
      <body pos="0.5 0 0">
        <geom name="forearm" type="capsule" size="0.035" fromto="0 0 0  0.5 0 0"/>
        <joint name="elbow"/>
        <geom name="elbow" type="cylinder" pos="0 0 0" size=".08 .05" mass="0"/>
        <site name="s7" pos="0.11 0.05 0"/><site name="s8" pos="0.11 -0.05 0"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="SF"><site site="s0"/><geom geom="shoulder"/><site site="s1"/></spatial>
    <spatial name="SE"><site site="s0"/><geom geom="shoulder" sidesite="x0"/><site site="s2"/></spatial>
    <spatial name="EF"><site site="s3"/><geom geom="elbow"/><site site="s7"/></spatial>
    <spatial name="EE"><site site="s4"/><geom geom="elbow" sidesite="x1"/><site site="s8"/></spatial>
    <spatial name="BF"><site site="s0"/><geom geom="shoulder"/><site site="s5"/><geom geom="elbow"/><site site="s7"/>
    </spatial>
    <spatial name="BE"><site site="s0"/><geom geom="shoulder" sidesite="x0"/><site site="s6"/>
      <geom geom="elbow" sidesite="x1"/><site site="s8"/></spatial>
  </tendon>
  <actuator>
    <motor name="SF" tendon="SF"/><motor name="SE" tendon="SE"/><motor name="EF" tendon="EF"/>
    <motor name="EE" tendon="EE"/><motor name="BF" tendon="BF" gear="2"/><motor name="BE" tendon="BE" gear="2"/>
  </actuator>
</mujoco>"""
"""MuJoCo's ``model/tendon_arm/arm26.xml`` (Apache-2.0, DeepMind), its six muscles replaced by motors (two with a
gear of 2), visual attributes and the floor dropped: six spatial tendons on two hinges, four of them crossing one
joint only (MuJoCo stores their Jacobian sparse)."""


def only(xml: str, *tendons: str, ranges: str | None = None) -> str:
    """ARM26 with only the tendons (and their motors) named, the joints' range replaced by ``ranges``."""
    xml = re.sub(r'<spatial name="(\w+)">.*?</spatial>', lambda m: m.group(0) if m.group(1) in tendons else "",
                 xml, flags=re.S)
    xml = re.sub(r'<motor name="(\w+)"[^>]*/>', lambda m: m.group(0) if m.group(1) in tendons else "", xml)
    return xml.replace('range="0 120"', f'range="{ranges}"') if ranges else xml


def test_sparse_tendon_jacobian_against_finite_differences():
    """MuJoCo 3.3+ stores ten_J sparse (10 non-zeros for 6 tendons x 2 dofs here): tendon_jacobian's dense rows
    are the central differences of MuJoCo's own ten_length to 1e-8 m/rad at random states."""
    m = mujoco.MjModel.from_xml_string(ARM26)
    d = mujoco.MjData(m)
    mujoco.mj_fwdPosition(m, d)
    assert np.asarray(d.ten_J).size < m.ntendon * m.nv  # what a dense reshape failed on
    rng = np.random.default_rng(5)
    h = 1e-6
    for _ in range(4):
        q = m.jnt_range[:, 0] + np.ptp(m.jnt_range, axis=1) * rng.uniform(0.05, 0.95, 2)
        d.qpos[:] = q
        mujoco.mj_fwdPosition(m, d)
        J = tendon_jacobian(m, d)
        fd = np.zeros_like(J)
        for k in range(2):
            for s in (1, -1):
                d.qpos[:] = q + s * h * np.eye(2)[k]
                mujoco.mj_fwdPosition(m, d)
                fd[:, k] += s * d.ten_length / (2 * h)
        assert J.shape == (6, 2) and np.max(np.abs(J - fd)) < 1e-8
        assert np.all(J[[0, 1], 1] == 0) and np.all(np.abs(J[[2, 3], 0]) < 1e-15)  # one joint (MuJoCo rounds)


def test_arm_on_its_cylinders_imports_exactly():
    """Within 0..90 degrees SE, EE and BE stay wrapped on their cylinders (constant moment arms 0.1 and 0.08 m): the
    import is exact, no warning; at random states its ratios are MuJoCo's gear * ten_J and its forward dynamics
    MuJoCo's under the motors to 1e-9 relative."""
    xml = only(ARM26, "SE", "EE", "BE", ranges="0 90")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = ad.Model.from_mjcf(xml)
    assert [dict(mo.joints) for mo in model.spec.motors] == [
        {"shoulder": pytest.approx(0.1, rel=1e-12)}, {"elbow": pytest.approx(0.08, rel=1e-12)},
        {"shoulder": pytest.approx(0.2, rel=1e-12), "elbow": pytest.approx(0.16, rel=1e-12)}]
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    gear = m.actuator_gear[:, 0]
    rng = np.random.default_rng(6)
    for _ in range(8):
        q, v, u = np.radians(rng.uniform(0, 90, 2)), rng.normal(size=2), 0.5 * rng.normal(size=3)
        d.qpos[:], d.qvel[:], d.ctrl[:] = q, v, u
        mujoco.mj_forward(m, d)
        np.testing.assert_allclose(model.transmission.ratio(q), gear[:, None] * tendon_jacobian(m, d),
                                   rtol=0, atol=1e-9 * 0.2)
        qdd = model.forward_dynamics(q, v, model.transmission.joint_torque(u, q))
        assert np.max(np.abs(qdd - d.qacc)) < 1e-9 * np.max(np.abs(d.qacc))


@pytest.mark.parametrize("tendons, needle", [
    (("EE",), "it changes side of its wrapping geom 'elbow' between elbow = "),
    (("SF",), "it leaves its wrapping geom 'shoulder' between shoulder = "),
])
def test_a_tendon_off_its_cylinder_imported_as_its_path(tendons, needle):
    """Over 0..120 degrees these tendons leave their cylinder (a kink of the moment arm) or wrap it on its other
    side (a jump): the fit says why one polynomial per joint cannot follow them, and the import then carries the
    tendon's geometry (the spec's ``path``; its accuracy: tests/test_spatial_path.py) instead of a curve that far
    from MuJoCo's."""
    from alpes_dyn.model.mjcf_spatial import fit_spatial_tendon

    xml = only(ARM26, *tendons)
    m = mujoco.MjModel.from_xml_string(xml)
    fit = fit_spatial_tendon(mujoco, m, 0, 1.0, ["shoulder", "elbow"])
    assert needle in fit.reason and fit.error > 1e-3 * fit.scale
    assert ad.Model.from_mjcf(xml).spec.motors[0].path is not None


def test_smooth_inexact_tendons_carried_as_their_paths():
    """Two smooth tendons whose polynomial fits are not exact (a straight segment across a joint of 2.9 rad range,
    short of the angle where one ratio reaches 0): each is carried as its path, no warning, its ratios MuJoCo's
    ``gear ten_J`` to 1e-9 of the largest at random states over the range."""
    from test_ratio_curve import SITES

    wide = SITES.replace('range="-0.3 1.2"', 'range="-0.8 2.1"')
    second = ('<spatial name="short"><site site="s0"/><site site="s1a"/><site site="s1b"/><site site="s2a"/>'
              '</spatial>')
    xml = (wide.replace("</tendon>", second + "</tendon>")
           .replace('<motor name="flex"', '<motor name="short" tendon="short" gear="-10"/><motor name="flex"'))
    with warnings.catch_warnings():
        warnings.simplefilter("error", MjcfCurveWarning)
        model = ad.Model.from_mjcf(xml)
    assert all(mo.path is not None for mo in model.spec.motors)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    lo, hi = m.jnt_range[:, 0], m.jnt_range[:, 1]
    rng = np.random.default_rng(11)
    for _ in range(16):
        d.qpos[:] = lo + (hi - lo) * rng.random(m.njnt)
        mujoco.mj_forward(m, d)
        want = m.actuator_gear[:, 0][:, None] * tendon_jacobian(m, d)[m.actuator_trnid[:, 0]]
        got = model.transmission.ratio(d.qpos.copy())
        assert np.max(np.abs(got - want)) < 1e-9 * np.max(np.abs(want))


def test_curve_warnings_name_the_worst_first():
    """The polynomial fits that stay (their paths not carried) are said in one warning, the larger error first."""
    from alpes_dyn.model.mjcf_import import _curve_warning

    with pytest.warns(MjcfCurveWarning) as rec:
        _curve_warning([(1e-6, "tendon 'a' (1e-06 of the largest ratio)"), (3e-4, "tendon 'b' (0.0003 of the "
                        "largest ratio)")])
    assert len(rec) == 1
    text = str(rec[0].message)
    errors = [float(x) for x in re.findall(r"\(([0-9.e+-]+) of the largest ratio\)", text)]
    assert errors == [3e-4, 1e-6]


def test_spatial_tendon_over_a_tied_joint():
    """A spatial tendon over a joint tied by a joint equality: where its ratio there is constant (the flexor wrapped
    on j3's own axis, j3 = 0.5 j2) it folds onto j2, the ratio MuJoCo's G^T (gear ten_J) to 1e-9 of the largest at
    random states on the coupling; where it is curved (j2 tied to j1) the import refuses it by name."""
    from test_ratio_curve import FINGER

    def tie(eq):
        return FINGER.replace("<tendon>", f"<equality>{eq}</equality><tendon>")

    xml = tie('<joint joint1="j3" joint2="j2" polycoef="0 0.5 0 0 0"/>')
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # j3's range, named as not imported
        warnings.simplefilter("error", MjcfCurveWarning)  # the fit is exact
        model = ad.Model.from_mjcf(xml)
    assert model.joint_names == ("j1", "j2")
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    G = np.array([[1, 0], [0, 1], [0, 0.5]])
    rng = np.random.default_rng(8)
    for _ in range(6):
        q = np.array([rng.uniform(-0.3, 1.2), rng.uniform(-0.3, 0.5)])
        d.qpos[:] = G @ q
        mujoco.mj_fwdPosition(m, d)
        J = m.actuator_gear[0, 0] * tendon_jacobian(m, d)[0] @ G
        np.testing.assert_allclose(model.transmission.ratio(q)[0], J, rtol=0, atol=1e-9 * np.max(np.abs(J)))
    with pytest.raises(ModelError, match=r"actuator 'flex''s spatial tendon crosses joint 'j2', which a joint "
                                         r"equality ties to 'j1'; a curved ratio on a tied joint is not modelled"):
        ad.Model.from_mjcf(tie('<joint joint1="j2" joint2="j1" polycoef="0 0.5 0 0 0"/>'))
