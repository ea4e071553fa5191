"""The identified robot written back as its MJCF (issue 37, part 4): a fit on a robot imported from an MJCF, written
into a copy of that MJCF (alpes_dyn.model.mjcf_update, identified_mjcf), read by MuJoCo (the values it compiles are
the fit's) and imported again (the same M(q), gravity and spring torques as the identified URDF + spec, to 1e-12);
the original untouched, everything else in the file as written."""

from __future__ import annotations

import difflib
import types
import warnings

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError
from alpes_dyn.estimation.identification.identified_spec import identified_mjcf, identified_spec, identified_urdf
from alpes_dyn.model.mjcf_import import example_mjcf_path

mujoco = pytest.importorskip("mujoco")


def _fake_fit(model, values: dict[str, float], trustworthy: bool = True):
    """A made-up fit of ``model`` with ``values`` (what identify's writers read of a result)."""
    return types.SimpleNamespace(model=model, names=tuple(values), values=np.array(list(values.values())),
                                 std=np.full(len(values), 1e-4), recording_path="rec.csv", trustworthy=trustworthy,
                                 converged=trustworthy, reason="made up", residual_rms=0.5, adequacy=None,
                                 not_identified={}, status=lambda: "made up -- not converged", standard_errors=None)


def _import(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the Shadow hand's servos are imported as torque motors (said, not tested)
        return ad.Model.from_mjcf(path)


def _same_robot(a, b, n: int = 3, seed: int = 0) -> None:
    """M(q), the gravity torque and the spring torque of ``a`` and ``b`` at random configurations, to 1e-12."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q, _v = a.random_state(rng)
        M = a.inertia_matrix(q)
        np.testing.assert_allclose(b.inertia_matrix(q), M, rtol=0, atol=1e-12 * np.abs(M).max())
        g = a.gravity_torque(q)
        np.testing.assert_allclose(b.gravity_torque(q), g, rtol=0, atol=1e-12 * max(np.abs(g).max(), 1e-300))
        np.testing.assert_allclose(b.extras.spring_torque(q), a.extras.spring_torque(q), rtol=1e-12, atol=1e-15)


def test_shadow_hand_written_back(tmp_path):
    """The shipped Shadow hand: masses (a phalanx and the wrist's body), a spring on a joint that had none, the
    friction and damping of another, the rotor of a joint's actuator and of a tendon's. (a) MuJoCo compiles the
    written file to those values; (b) imported again it is the identified URDF + spec; (c) the original is
    untouched, and only the lines of the elements changed differ (plus the comment naming the fit)."""
    src = example_mjcf_path("shadow_hand")
    before = src.read_bytes()
    model = _import(src)
    values = {"m_rh_FFJ1": 0.02, "m_rh_WRJ1": 0.45, "K_rh_FFJ1": 0.3, "K_rh_MFJ3": 0.12, "F_s_rh_FFJ2": 0.03,
              "F_v_rh_FFJ2": 0.08, "J_m_rh_A_FFJ0": 1e-5, "J_m_rh_A_WRJ2": 2e-5}
    fit = _fake_fit(model, values)
    out = tmp_path / "ident.xml"
    text, omitted = identified_mjcf(fit, model.spec, src, out)
    out.write_text(text)
    assert omitted == [] and src.read_bytes() == before
    m0, m = mujoco.MjModel.from_xml_path(str(src)), mujoco.MjModel.from_xml_path(str(out))

    def idx(kind, name):
        return mujoco.mj_name2id(m, kind, name)

    O = mujoco.mjtObj
    assert m.body_mass[idx(O.mjOBJ_BODY, "rh_ffdistal")] == 0.02
    assert m.body_mass[idx(O.mjOBJ_BODY, "rh_palm")] == 0.45  # m_rh_WRJ1: the child of the wrist's second joint
    b = idx(O.mjOBJ_BODY, "rh_palm")
    np.testing.assert_allclose(m.body_inertia[b], m0.body_inertia[b] * 0.45 / m0.body_mass[b], rtol=1e-15)
    assert m.jnt_stiffness[idx(O.mjOBJ_JOINT, "rh_FFJ1")] == 0.3 and m.jnt_stiffness[idx(O.mjOBJ_JOINT, "rh_MFJ3")] == 0.12
    d = m.jnt_dofadr[idx(O.mjOBJ_JOINT, "rh_FFJ2")]
    assert m.dof_frictionloss[d] == 0.03 and m.dof_damping[d] == 0.08
    t = m.actuator_trnid[idx(O.mjOBJ_ACTUATOR, "rh_A_FFJ0"), 0]
    assert m.tendon_armature[t] == 1e-5  # gear 1: the tendon's armature is J_m
    w = m.jnt_dofadr[idx(O.mjOBJ_JOINT, "rh_WRJ2")]
    assert m.dof_armature[w] == pytest.approx(m0.dof_armature[w] + 2e-5, rel=1e-15)
    unchanged = [i for i in range(m.nbody) if i not in (b, idx(O.mjOBJ_BODY, "rh_ffdistal"))]
    np.testing.assert_array_equal(m.body_mass[unchanged], m0.body_mass[unchanged])
    np.testing.assert_array_equal(m.geom_size, m0.geom_size)
    np.testing.assert_array_equal(m.actuator_gainprm, m0.actuator_gainprm)  # the servos kept
    # (b) the written MJCF imported again is the identified robot (URDF with the masses, spec with the rest)
    ident = ad.Model(identified_urdf(fit, model.urdf), identified_spec(fit, model.spec, masses="urdf"))
    back = _import(out)
    _same_robot(ident, back)
    assert dict(back.spec.stiffness) == dict(ident.spec.stiffness)
    assert back.spec.coulomb["rh_FFJ2"] == 0.03 and back.spec.viscous["rh_FFJ2"] == 0.08
    # (c) a minimal diff: the comment, two inertials, four joints, one tendon
    diff = [d for d in difflib.unified_diff(before.decode().splitlines(), text.splitlines(), n=0, lineterm="")
            if d[:1] in "+-" and not d.startswith(("+++", "---"))]
    added = [d for d in diff if d[0] == "+"]
    assert len(added) == 1 + 2 + 4 + 1 and len(diff) == 2 * len(added) - 1, diff
    assert added[0].startswith("+<!-- identified by alpes_dyn from rec.csv (model right_shadow_hand): m_rh_FFJ1 0.02 kg")


PART = """<mujoco><default><default class="sprung"><joint stiffness="0" springref="30" damping="0.01"/></default>
</default></mujoco>"""

SMALL = """<?xml version="1.0"?>
<!-- a two-hinge finger with its mass from the geoms, an unnamed body, angles in degrees, springs from a class -->
<mujoco model="small">
  <include file="part.xml"/>
  <worldbody>
    <body name="a" pos="0 0 0.1">
      <joint name="ja" axis="0 1 0" range="-60 60" stiffness="0.2" springref="10"/>
      <geom type="capsule" fromto="0 0 0 0.05 0 0" size="0.008" density="1100"/>
      <body pos="0.05 0 0">
        <joint name="jb" class="sprung" axis="0 1 0" range="0 90"/>
        <geom type="box" pos="0.02 0 0" size="0.02 0.006 0.005" mass="0.015"/>
        <site name="tip" pos="0.04 0 0"/>
      </body>
    </body>
  </worldbody>
  <tendon><fixed name="t"><joint joint="ja" coef="0.01"/><joint joint="jb" coef="0.008"/></fixed></tendon>
  <actuator><motor name="flexor" tendon="t" gear="100"/></actuator>
</mujoco>
"""


def test_classes_degrees_geoms_and_another_folder(tmp_path):
    """An MJCF written by the test: masses taken from the geoms (an <inertial> of the body's own written), an
    unnamed body (found by its index), angles in degrees, a spring's rest angle set by a class on a joint without
    a spring (the spec's rest 0: springref written as 0 where the fit gives it a spring), an <include> and the
    output in another folder (the file name rewritten relative to it). MuJoCo compiles the fit's values and the
    import of the written file is the identified URDF + spec, to 1e-12."""
    src_dir, out_dir = tmp_path / "src", tmp_path / "out"
    src_dir.mkdir(), out_dir.mkdir()
    (src_dir / "part.xml").write_text(PART)
    src = src_dir / "small.xml"
    src.write_text(SMALL)
    model = _import(src)
    assert model.spec.rest_angle == {"ja": pytest.approx(np.radians(10))} and "jb" not in model.spec.stiffness
    values = {"m_ja": 0.031, "m_jb": 0.012, "K_ja": 0.25, "K_jb": 0.07, "F_s_jb": 0.002, "F_v_ja": 0.02,
              "J_m_flexor": 3e-6}
    fit = _fake_fit(model, values, trustworthy=False)
    out = out_dir / "ident.xml"
    text, _ = identified_mjcf(fit, model.spec, src, out)
    out.write_text(text)
    assert src.read_text() == SMALL
    assert '<include file="../src/part.xml"/>' in text and "<!-- NOT TRUSTWORTHY (written with identify's force " \
        "option): made up - - not converged -->" in text
    assert 'springref="0.0"' in text and text.count("springref") == 2  # jb's rest from the class set to 0; ja's kept
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.body_mass.tolist()[1:] == [0.031, 0.012]
    assert m.jnt_stiffness.tolist() == [0.25, 0.07] and m.qpos_spring[1] == 0.0
    assert m.qpos_spring[0] == pytest.approx(np.radians(10), rel=1e-15)
    assert m.tendon_armature[0] == pytest.approx(3e-6 * 100**2, rel=1e-15)
    ident = ad.Model(identified_urdf(fit, model.urdf), identified_spec(fit, model.spec, masses="urdf"))
    _same_robot(ident, _import(out))


def test_what_cannot_be_written_is_refused(tmp_path):
    """A body in an included file, a compiler that takes masses from the geoms: one line each, nothing written."""
    from alpes_dyn.model.mjcf_update import updated_mjcf

    (tmp_path / "body.xml").write_text('<mujoco><body name="b"><joint name="jb" range="-1 1"/>'
                                       '<geom size="0.01"/></body></mujoco>')
    inc = tmp_path / "inc.xml"
    inc.write_text('<mujoco><compiler angle="radian"/><worldbody><include file="body.xml"/></worldbody></mujoco>')
    with pytest.raises(ModelError, match=r"mjcf: body 'b' is not written in .*inc.xml itself"):
        updated_mjcf(inc, tmp_path / "o.xml", masses={"b": 0.1})
    geoms = tmp_path / "geoms.xml"
    (tmp_path / "part.xml").write_text(PART)
    geoms.write_text(SMALL.replace('<mujoco model="small">', '<mujoco model="small"><compiler '
                                   'inertiafromgeom="true"/>'))
    with pytest.raises(ModelError, match='inertiafromgeom="true">: MuJoCo takes every mass from the geoms'):
        updated_mjcf(geoms, tmp_path / "o.xml", masses={"a": 0.1})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["body.xml", "geoms.xml", "inc.xml", "part.xml"]


TET = "v 0 0 0\nv 0.02 0 0\nv 0 0.02 0\nv 0 0 0.02\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.mark.parametrize("meshdir", [True, False])
def test_meshes_resolve_from_the_output_folder(tmp_path, meshdir):
    """A mesh geom (its file under <compiler meshdir>, or named relative to the MJCF's folder) whose body's mass
    MuJoCo computes from it: written into another folder, the meshdir (or the mesh's file) is rewritten relative
    to it, MuJoCo loads the file from there, and the body has the new mass with its inertia scaled."""
    from alpes_dyn.model.mjcf_update import updated_mjcf

    (tmp_path / "robot" / "assets").mkdir(parents=True)
    (tmp_path / "robot" / "assets" / "tet.obj").write_text(TET)
    (tmp_path / "out").mkdir()
    compiler = '<compiler angle="radian" meshdir="assets"/>' if meshdir else '<compiler angle="radian"/>'
    src = tmp_path / "robot" / "r.xml"
    src.write_text(f'<mujoco>{compiler}<asset><mesh name="tet" file="{"" if meshdir else "assets/"}tet.obj"/>'
                   '</asset><worldbody><body name="a"><joint name="ja" axis="0 1 0" range="-1 1"/>'
                   '<geom type="mesh" mesh="tet" density="1000"/></body></worldbody></mujoco>')
    m0 = mujoco.MjModel.from_xml_path(str(src))
    out = tmp_path / "out" / "r.xml"
    text = updated_mjcf(src, out, masses={"a": 2 * m0.body_mass[1]}, joints={"ja": {"damping": 0.1}})
    out.write_text(text)
    assert ('meshdir="../robot/assets"' if meshdir else 'file="../robot/assets/tet.obj"') in text
    m = mujoco.MjModel.from_xml_path(str(out))
    assert m.body_mass[1] == 2 * m0.body_mass[1] and m.dof_damping[0] == 0.1
    np.testing.assert_allclose(m.body_inertia[1], 2 * m0.body_inertia[1], rtol=1e-12)
    np.testing.assert_allclose(m.body_ipos[1], m0.body_ipos[1], rtol=0, atol=1e-15)


def test_a_rotor_on_a_spatial_tendon(tmp_path):
    """A motor's rotor on a spatial tendon (test_ratio_curve's finger): over sites it is the tendon's armature
    J_m gear^2 and the import of the written file is the identified robot (its rotor J_m back, M(q) to 1e-12, the
    ratio curve as before to 1e-10, its fit on MuJoCo's tendon Jacobian refitted); over wrapping cylinders MuJoCo allows no tendon armature: refused with MuJoCo's reason,
    nothing written."""
    from test_ratio_curve import FINGER, SITES

    for name, text in (("sites", SITES), ("wraps", FINGER)):
        src = tmp_path / f"{name}.xml"
        src.write_text(text)
        model = _import(src)
        fit = _fake_fit(model, {"J_m_flex": 2e-5, "K_2": 0.05, "m_3": 0.012})
        out = tmp_path / f"{name}_ident.xml"
        if name == "wraps":
            with pytest.raises(ModelError, match="MuJoCo cannot compile the updated MJCF .*geom wrapping not "
                                                 "supported by tendon armature"):
                identified_mjcf(fit, model.spec, src, out)
            continue
        out.write_text(identified_mjcf(fit, model.spec, src, out)[0])
        assert mujoco.MjModel.from_xml_path(str(out)).tendon_armature[0] == pytest.approx(2e-5 * 100**2, rel=1e-15)
        back = _import(out)
        ident = ad.Model(identified_urdf(fit, model.urdf), identified_spec(fit, model.spec, masses="urdf"))
        assert back.spec.motors[0].rotor_inertia == pytest.approx(2e-5, rel=1e-15)
        for j, c in model.spec.motors[0].ratio_curve.items():  # refitted on MuJoCo's ten_J: the same to rounding
            assert back.spec.motors[0].ratio_curve[j] == pytest.approx(c, rel=0, abs=1e-10)
        _same_robot(ident, back)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sites.xml", "sites_ident.xml", "wraps.xml"]


def test_tied_joint_values_written_as_each_joint_own(tmp_path):
    """A fit on a robot with a joint tied by a joint equality (tests/test_mjcf_import.py's TIED: the spec's values of
    k hold l's, folded on import): written back, k's own stiffness, springref, damping and frictionloss are the fit's
    less l's as in the file, so that the MJCF imported again gives the fitted spec values (to 1e-12) with l's own
    values untouched; a fitted value below what l holds is refused."""
    from test_mjcf_import import TIED

    src = tmp_path / "tied.xml"
    src.write_text(TIED)
    model = _import(src)
    values = {"K_k": 0.3, "F_s_k": 0.006, "F_v_k": 0.03, "K_j": 0.15}
    text, _ = identified_mjcf(_fake_fit(model, values), model.spec, src, tmp_path / "ident.xml")
    (tmp_path / "ident.xml").write_text(text)
    back = _import(tmp_path / "ident.xml")
    assert back.spec.stiffness == {"j": pytest.approx(0.15, rel=1e-12), "k": pytest.approx(0.3, rel=1e-12)}
    assert back.spec.coulomb["k"] == pytest.approx(0.006, rel=1e-12)
    assert back.spec.viscous["k"] == pytest.approx(0.03, rel=1e-12)
    for j in ("j", "k"):
        assert back.spec.rest_angle[j] == pytest.approx(model.spec.rest_angle[j], rel=1e-12)
    m0, m = mujoco.MjModel.from_xml_string(TIED), mujoco.MjModel.from_xml_path(str(tmp_path / "ident.xml"))
    assert (m.jnt_stiffness[2], m.dof_damping[2], m.dof_frictionloss[2]) == (
        m0.jnt_stiffness[2], m0.dof_damping[2], m0.dof_frictionloss[2])  # l as written
    with pytest.raises(ModelError, match=r"joint 'k''s damping 0.001 is below what the joints tied to it hold "
                                         r"\(0.0128\); not written"):
        identified_mjcf(_fake_fit(model, {"F_v_k": 0.001}), model.spec, src, tmp_path / "x.xml")
