"""Spatial tendons that touch, leave or change side of their wrapping geoms, imported as their geometry (issue 51,
item 1): MuJoCo's ``tendon_arm/arm26`` (its muscles replaced by motors) over its whole range, a sphere wrap and side
sites, lengths and moment arms against MuJoCo's ``ten_length`` / ``ten_J`` to 1e-9 at random states on both sides of
each switch, and the dynamics (numeric and CasADi) under the tendons' motors against MuJoCo's ``qacc``."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import ModelError
from alpes_dyn.model.spec import TransmissionSpec

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.model.mjcf_spatial import tendon_jacobian  # noqa: E402
from test_mjcf_spatial import ARM26, only  # noqa: E402

SPHERE = """<mujoco model="ball">
  <default><joint type="hinge" axis="0 1 0" limited="true" range="-150 150" damping="0.1"/></default>
  <worldbody>
    <site name="a" pos="-0.2 0 0.05"/><site name="side" pos="0 0 0.3"/>
    <body pos="0 0 0">
      <joint name="j1"/><geom name="ball" type="sphere" size="0.06" mass="0.5"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
      <site name="b" pos="0.2 0.01 0.04"/>
      <body pos="0.3 0 0">
        <joint name="j2" axis="0 0 1"/><geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02"/>
        <site name="c" pos="0.15 0.03 0.02"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <spatial name="over"><site site="a"/><geom geom="ball" sidesite="side"/><site site="b"/></spatial>
    <spatial name="free"><site site="a"/><geom geom="ball"/><site site="c"/></spatial>
    <spatial name="split"><site site="a"/><site site="b"/><pulley divisor="2"/><site site="a"/><site site="c"/>
    </spatial>
  </tendon>
  <actuator><motor name="over" tendon="over" gear="3"/><motor name="free" tendon="free"/>
    <motor name="split" tendon="split" gear="-2"/></actuator>
</mujoco>"""
"""Two hinges (about y, then z), a sphere on the first body: a tendon over it on its side site's side, one without a
side site whose last segment spans both joints, and a pulley's two branches (divisor 2)."""


def against_mujoco(xml: str, draws: int, seed: int) -> tuple[float, float, float, float]:
    """The largest errors of the imported model against MuJoCo at ``draws`` random states over the joints' box:
    ratios (relative to the largest), motor angles g (L(q) - L(0)) (rad), numeric q̈ and CasADi q̈ (relative)."""
    from alpes_dyn.symbolic.statespace import StateSpace

    model = ad.Model.from_mjcf(xml)
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_fwdPosition(m, d)
    gear = m.actuator_gear[:, 0]
    d.qpos[:] = 0.0
    mujoco.mj_fwdPosition(m, d)
    L0 = d.ten_length.copy()
    ss = StateSpace(model, input="motor", output="encoder")
    tr, rng = model.transmission, np.random.default_rng(seed)
    lo, hi = m.jnt_range[:, 0], m.jnt_range[:, 1]
    err = np.zeros(4)
    for _ in range(draws):
        q, v, u = lo + (hi - lo) * rng.random(m.njnt), rng.normal(size=m.nv), 0.5 * rng.normal(size=m.nu)
        d.qpos[:], d.qvel[:], d.ctrl[:] = q, v, u
        mujoco.mj_forward(m, d)
        J = gear[:, None] * tendon_jacobian(m, d)
        h = 1e-6  # the rate product (drho/dt) qd by AD against a central difference of the ratios along qd
        fd = (tr.ratio(q + h * v) - tr.ratio(q - h * v)) @ v / (2 * h)
        assert np.max(np.abs(tr.curve.rate_product(q, v) - fd)) < 1e-6 * max(1.0, np.max(np.abs(fd)))
        qdd = model.forward_dynamics(q, v, tr.joint_torque(u, q))
        xdot = ss.f(np.r_[q, v], u)
        scale = np.max(np.abs(d.qacc))
        err = np.maximum(err, [np.max(np.abs(tr.ratio(q) - J)) / np.max(np.abs(J)),
                               np.max(np.abs(tr.curve.angle(q) - gear * (d.ten_length - L0))),
                               np.max(np.abs(qdd - d.qacc)) / scale, np.max(np.abs(xdot[m.nv:] - d.qacc)) / scale])
    return tuple(err)


def test_arm26_over_its_whole_range():
    """arm26 over 0..120 degrees: SF and EF leave their cylinders, SE and EE change side, BF and BE do both over two
    joints: each imported as its path; ratios, motor angles and q̈ (numeric and CasADi, all six motors driving)
    equal MuJoCo's to 1e-9 at random states, which fall on both sides of each switch."""
    model = ad.Model.from_mjcf(ARM26)
    assert all(mo.path is not None for mo in model.spec.motors)
    assert [sorted(mo.joints) for mo in model.spec.motors][4:] == [["elbow", "shoulder"]] * 2
    ratio, angle, qdd, sym = against_mujoco(ARM26, 24, 9811)
    assert ratio < 1e-9 and angle < 1e-9 and qdd < 1e-9 and sym < 1e-9


def test_both_sides_of_a_switch():
    """SE wraps its cylinder up to a shoulder angle near 1.95 rad, then goes straight (its side site no longer between
    its ends); EE's side solution changes near an elbow angle of 2 rad: the imported ratio follows MuJoCo's on a fine
    sweep through both switches, to 1e-9 m/rad."""
    model = ad.Model.from_mjcf(only(ARM26, "SE", "EE"))
    m = mujoco.MjModel.from_xml_string(only(ARM26, "SE", "EE"))
    d = mujoco.MjData(m)
    sweep = np.linspace(1.9, 2.09, 40)
    qs = np.stack([sweep, sweep], axis=1)
    R = model.transmission.ratio(qs)  # batched: (40, 2, 2)
    wraps = []
    for q, r in zip(qs, R):
        d.qpos[:] = q
        mujoco.mj_fwdPosition(m, d)
        wraps.append(tuple(d.ten_wrapnum))
        assert np.max(np.abs(r - tendon_jacobian(m, d))) < 1e-9
    assert len(set(w[0] for w in wraps)) == 2  # SE: wrapped, then straight


def test_sphere_side_site_pulley():
    """A sphere wrap with a side site, one without (its segment spans two joints) and a pulley: lengths and moment
    arms MuJoCo's to 1e-9, the dynamics too (numeric and CasADi)."""
    ratio, angle, qdd, sym = against_mujoco(SPHERE, 16, 9812)
    assert ratio < 1e-9 and angle < 1e-9 and qdd < 1e-9 and sym < 1e-9


def test_path_spec_round_trip_and_pickle():
    """The spec's ``path`` is written and read back unchanged; a pickled model gives the same ratios."""
    model = ad.Model.from_mjcf(ARM26)
    assert TransmissionSpec.from_toml(model.spec.to_toml()) == model.spec
    q = np.array([1.0, 1.9])
    np.testing.assert_allclose(pickle.loads(pickle.dumps(model)).transmission.ratio(q),
                               model.transmission.ratio(q), rtol=0, atol=1e-15)


@pytest.mark.parametrize("change, needle", [
    (lambda t: t.update(kind="cone"), "path.points[1].kind: expected one of cylinder, sphere"),
    (lambda t: t.update(radius=-1.0), "path.points[1].radius: expected a finite number > 0"),
    (lambda t: t.update(frame="nowhere"), "path.points[1].frame: 'nowhere' is not one of the path's frames"),
    (lambda t: t.update(extra=1), "path.points[1].extra: unknown key"),
])
def test_bad_path_tables_named(change, needle):
    """A spec's path with a bad field is refused in one line naming the motor and the field."""
    spec = ad.Model.from_mjcf(only(ARM26, "SE")).spec
    mo = spec.motors[0]
    table = mo.path.to_table()
    change(table["points"][1])
    with pytest.raises(ModelError, match=r"motor 'SE'\.") as info:
        ad.model.spec.Motor(mo.name, dict(mo.joints), path=table)
    assert needle in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("same_body", [True, False])
def test_side_site_inside_its_geom_refused(same_body):
    """A side site inside its wrapping cylinder (MuJoCo solves that path by Newton's method to 1e-6, no closed form),
    on the geom's body (seen in the file) or on another (seen at the checked states): refused, the tendon, the site and
    the geom named."""
    xml = only(ARM26, "SE")
    if same_body:
        xml = xml.replace('<geom name="shoulder" type="cylinder"', '<site name="in" pos="0 -0.05 0"/><geom '
                          'name="shoulder" type="cylinder"').replace('sidesite="x0"', 'sidesite="in"')
        site = "in"
    else:
        xml, site = xml.replace('<site name="x0" pos="0 -0.15 0"/>', '<site name="x0" pos="0.05 -0.05 0"/>'), "x0"
    with pytest.raises(ModelError, match=rf"spatial tendon 'SE' \(actuator 'SE'\): its side site '{site}' is inside "
                                         r"its wrapping geom 'shoulder'"):
        ad.Model.from_mjcf(xml)


@pytest.mark.parametrize("kind", ["cylinder", "sphere"])
@pytest.mark.parametrize("side", [False, True])
def test_wrap_in_closed_form_against_mujoco(kind, side):
    """The closed form of MuJoCo's wrapping (:func:`~alpes_dyn.model.wrap.wrap_length`) on random placements of the
    two end sites and the side site (each on three slide joints) about a tilted geom, wrapped or not, on either
    side: length MuJoCo's ``ten_length`` to 1e-14 m, its gradient by AD MuJoCo's ``ten_J`` to 1e-12."""
    import casadi as cs

    from alpes_dyn.model.wrap import wrap_length

    body = ('<body><joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/><joint type="slide" '
            'axis="0 0 1"/><geom size=".01" mass="1"/><site name="s{}"/></body>')
    xml = (f'<mujoco><worldbody><geom name="g" type="{kind}" size=".1 .05" euler="0.3 0.2 0.1" pos="0.01 0.02 0.03"/>'
           + "".join(body.format(i) for i in range(3)) + '</worldbody><tendon><spatial><site site="s0"/><geom geom="g" '
           + ('sidesite="s2"' if side else "") + '/><site site="s1"/></spatial></tendon></mujoco>')
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    mujoco.mj_fwdPosition(m, d)
    x = cs.SX.sym("x", 9)
    L = wrap_length(x[0:3], x[3:6], cs.DM(d.geom_xpos[0]), cs.DM(d.geom_xmat[0].reshape(3, 3)), 0.1, kind,
                    x[6:9] if side else None)
    rng = np.random.default_rng(9813)
    P = rng.uniform(-0.25, 0.25, (1500, 9))
    P = P[np.min(np.linalg.norm(P.reshape(-1, 3, 3) - d.geom_xpos[0], axis=2), axis=1) > 0.105]  # outside the geom
    Ls, Js = (np.asarray(v) for v in cs.Function("f", [x], [L, cs.jacobian(L, x)]).map(len(P))(P.T))
    wrapped = 0
    for k, p in enumerate(P):
        d.qpos[:] = p
        mujoco.mj_fwdPosition(m, d)
        wrapped += d.ten_wrapnum[0] == 4
        assert abs(Ls[0, k] - d.ten_length[0]) < 1e-14
        assert np.max(np.abs(Js[0, 9 * k:9 * k + 9] - tendon_jacobian(m, d)[0])) < 1e-12
    assert 0.1 * len(P) < wrapped < 0.9 * len(P)  # both branches drawn


def test_rotors_identification_model_and_equilibrium():
    """With rotor inertia on the path motors (set in the spec: MuJoCo allows no armature on a wrapping tendon): the
    rotors' velocity torque rho^T J_m (drho/dt) qd is Lagrange's (d/dt (M_r qd) - dT_r/dq, by central differences),
    the identification's parametric model (CasADi, rotor inertias as parameters) gives the numeric q̈, and the static
    equilibrium under a motor torque balances gravity (its Newton Jacobian d(rho^T tau_m)/dq a central difference's)."""
    import dataclasses

    import casadi as cs

    from alpes_dyn.symbolic.parametric import ParametricDynamics

    base = ad.Model.from_mjcf(SPHERE)
    spec = dataclasses.replace(base.spec, motors=tuple(dataclasses.replace(mo, rotor_inertia=1e-3 * (k + 1))
                                                       for k, mo in enumerate(base.spec.motors)))
    model = ad.Model(base.urdf, spec)
    tr, h = model.transmission, 1e-6
    q, v, u = np.array([0.4, 0.3]), np.array([0.7, -0.4]), np.array([0.05, 0.02, -0.01])
    M = tr.rotor_matrix_at
    lagrange = (M(q + h * v) - M(q - h * v)) @ v / (2 * h) - np.array(
        [(v @ M(q + h * e) @ v - v @ M(q - h * e) @ v) / (4 * h) for e in np.eye(2)])
    np.testing.assert_allclose(tr.rotor_bias(q, v), lagrange, rtol=1e-6)
    pd = ParametricDynamics(model, "m,J_m")
    Q, V, U = cs.SX.sym("q", 2), cs.SX.sym("v", 2), cs.SX.sym("u", 3)
    f = cs.Function("f", [Q, V, U, pd.theta], [pd.forward_dynamics(Q, V, pd.input_torque(Q, V, U))])
    qdd = model.forward_dynamics(q, v, tr.joint_torque(u, q))
    np.testing.assert_allclose(np.asarray(f(q, v, u, pd.nominal)).ravel(), qdd, rtol=1e-12, atol=1e-12)
    fd = np.stack([(tr.joint_torque(u, q + h * e) - tr.joint_torque(u, q - h * e)) / (2 * h) for e in np.eye(2)], 1)
    np.testing.assert_allclose(tr.curve.torque_jacobian(q, u), fd, atol=1e-8)
    qe = model.static_equilibrium(None, q0=[0.3, 0.2], tau_m=u)
    assert np.max(np.abs(model.gravity_torque(qe) - tr.joint_torque(u, qe))) < 1e-12
