"""The robot's own sizes (issue 17, item 4): springs that rest at an angle of the spec's ``[rest_angle]`` table,
a default tip only where it is not ambiguous, joint stops sized to the robot's own weight and inertia.

The references are computed here by hand (a one-joint pendulum's equilibrium k (q - q0) = m g l cos q solved by
bisection, the spring energy's derivative by finite differences, MuJoCo's own passive force and its settled
state), not by the code under test."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.model.spec import TransmissionSpec
from alpes_dyn.model.stops import ALPES_STOP, STOP_PENETRATION, JointStops, sized_stops

MASS, ARM, G0 = 0.1, 0.05, 9.81  # the pendulum: 0.1 kg at 5 cm from its axis
IYY = 1e-5  # kg m^2 about its centre of mass (the axis' direction)
PENDULUM_URDF = f"""<?xml version="1.0"?>
<robot name="pendulum">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="{ARM} 0 0"/><mass value="{MASS}"/>
      <inertia ixx="{IYY}" ixy="0" ixz="0" iyy="{IYY}" iyz="0" izz="{IYY}"/></inertial>
  </link>
  <joint name="hinge" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="1" velocity="20"/>
  </joint>
  <link name="tip"/>
  <joint name="tip_joint" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.1 0 0"/></joint>
</robot>
"""
# rotation q about +y takes the arm's x axis to (cos q, 0, -sin q): its centre of mass sits at z = -l sin q, so
# gravity's torque on the joint (the G of eq. 2.11) is -m g l cos q, and the spring's k (q - q0) balances it at
# k (q - q0) = m g l cos q.
K, Q0 = 0.2, 0.3


def pendulum_spec(rest: float | None = Q0, viscous: float = 0.0) -> str:
    text = f'gravity = [0.0, 0.0, -9.81]\n\n[stiffness]\nhinge = {K!r}\n'
    if rest is not None:
        text += f"\n[rest_angle]\nhinge = {rest!r}\n"
    if viscous:
        text += f"\n[viscous]\nhinge = {viscous!r}\n"
    return text


def hand_equilibrium(q0: float) -> float:
    """The root of k (q - q0) - m g l cos q on [-1.5, 1.5] by bisection (it increases with q: k > m g l)."""
    f = lambda q: K * (q - q0) - MASS * G0 * ARM * math.cos(q)  # noqa: E731
    a, b = -1.5, 1.5
    assert f(a) < 0 < f(b)
    for _ in range(200):
        c = 0.5 * (a + b)
        a, b = (c, b) if f(c) < 0 else (a, c)
    return 0.5 * (a + b)


def pendulum(rest: float | None = Q0, viscous: float = 0.0) -> ad.Model:
    return ad.Model(PENDULUM_URDF, TransmissionSpec.from_toml(pendulum_spec(rest, viscous)))


# ----------------------------------------------------------------------------- rest angles
def test_rest_angle_balances_gravity_where_the_hand_computation_says():
    """k (q - q0) = m g l cos q: q = 0.51361 rad with q0 = 0.3 (0.23832 with q0 = 0), Newton and bisection agree
    (to 1e-10 rad: Newton stops at 1e-12 N m)."""
    m = pendulum()
    assert m.extras.rest.tolist() == [Q0] and m.spec.rest_angle == {"hinge": Q0}
    q = m.static_equilibrium(np.zeros(1))
    assert q[0] == pytest.approx(hand_equilibrium(Q0), abs=1e-10)
    assert q[0] == pytest.approx(0.51361, abs=1e-5)
    q_zero = pendulum(None).static_equilibrium(np.zeros(1))
    assert q_zero[0] == pytest.approx(hand_equilibrium(0.0), abs=1e-10)
    assert q_zero[0] == pytest.approx(0.23832, abs=1e-5)
    np.testing.assert_array_equal(m.spring_torque(np.array([Q0])), [0.0])  # no torque at the rest angle
    assert m.spring_torque(np.array([1.0]))[0] == pytest.approx(K * (1.0 - Q0), rel=1e-15)
    assert m.potential_energy(np.array([Q0])) == pytest.approx(-MASS * G0 * ARM * math.sin(Q0), rel=1e-12)


def test_rest_angle_zero_is_bit_identical():
    """``[rest_angle]`` left out or 0: the same numbers, bit for bit (the spring k q)."""
    a, b = pendulum(None), pendulum(0.0)
    rng = np.random.default_rng(1)
    for _ in range(5):
        q, v = rng.uniform(-1.5, 1.5, 1), rng.uniform(-2, 2, 1)
        tau = rng.normal(scale=0.05, size=1)
        assert np.array_equal(a.forward_dynamics(q, v, tau), b.forward_dynamics(q, v, tau))
        assert np.array_equal(a.gravity_torque(q), b.gravity_torque(q))
        assert a.potential_energy(q) == b.potential_energy(q)



def two_joint_finger(scale: float = 1.0, rest: tuple[float, float] | None = (0.2, -0.1), viscous: float = 0.0,
                     tips: bool = True) -> ad.Model:
    """A planar two-joint finger (limits 0-1.5 rad, one tendon over both joints), masses and inertias x ``scale``
    (its springs, 0.045 and 0.035 N m/rad, not)."""
    urdf = f"""<?xml version="1.0"?>
<robot name="finger">
  <link name="palm"/>
  <link name="proximal">
    <inertial><origin xyz="0.022 0 0"/><mass value="{0.028 * scale!r}"/>
      <inertia ixx="{9e-07 * scale!r}" ixy="0" ixz="0" iyy="{5e-06 * scale!r}" iyz="0" izz="{5e-06 * scale!r}"/></inertial>
  </link>
  <joint name="mcp" type="revolute">
    <parent link="palm"/><child link="proximal"/><origin xyz="0 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0.0" upper="1.5" effort="1" velocity="20"/>
  </joint>
  <link name="distal">
    <inertial><origin xyz="0.014 0 0"/><mass value="{0.018 * scale!r}"/>
      <inertia ixx="{6e-07 * scale!r}" ixy="0" ixz="0" iyy="{1.4e-06 * scale!r}" iyz="0" izz="{1.4e-06 * scale!r}"/></inertial>
  </link>
  <joint name="pip" type="revolute">
    <parent link="proximal"/><child link="distal"/><origin xyz="0.045 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0.0" upper="1.5" effort="1" velocity="20"/>
  </joint>
  <link name="fingertip"/>
  <joint name="tip_joint" type="fixed"><parent link="distal"/><child link="fingertip"/><origin xyz="0.028 0 0"/></joint>
  <link name="nail"/>
  <joint name="nail_joint" type="fixed"><parent link="distal"/><child link="nail"/><origin xyz="0.02 0 0.005"/></joint>
</robot>
"""
    spec = ('[[motor]]\nname = "flexor"\njoints = { mcp = 2.0, pip = 1.5 }\n\n'
            "[stiffness]\nmcp = 0.045\npip = 0.035\n")
    if tips:
        spec = 'tips = ["fingertip"]\n' + spec
    if rest is not None:
        spec += f"\n[rest_angle]\nmcp = {rest[0]!r}\npip = {rest[1]!r}\n"
    if viscous:
        spec += f"\n[viscous]\nmcp = {viscous!r}\npip = {viscous!r}\n"
    return ad.Model(urdf, TransmissionSpec.from_toml(spec))


def test_symbolic_numeric_parametric_agree_with_a_rest_angle():
    """Pinocchio + extras, the CasADi model and the parametric model (K symbolic, at its nominal values) give one
    qdd with rest angles (0.2, -0.1) rad; the spring's energy is the potential whose gradient G's spring part is."""
    import casadi as cs

    from alpes_dyn.symbolic.dynamics import SymbolicDynamics
    from alpes_dyn.symbolic.parametric import ParametricDynamics

    m = two_joint_finger()
    sym = SymbolicDynamics(m)
    par = ParametricDynamics(m, "K")
    q, v, tau = cs.SX.sym("q", 2), cs.SX.sym("v", 2), cs.SX.sym("tau", 2)
    f_sym = cs.Function("f", [q, v, tau], [sym.forward_dynamics(q, v, tau)])
    f_par = cs.Function("f", [q, v, tau, par.theta], [par.forward_dynamics(q, v, tau)])
    rng = np.random.default_rng(7)
    for _ in range(5):
        qn, vn = m.random_state(rng)
        tn = rng.normal(scale=0.02, size=2)
        a = m.forward_dynamics(qn, vn, tn)
        np.testing.assert_allclose(np.asarray(f_sym(qn, vn, tn)).ravel(), a, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(np.asarray(f_par(qn, vn, tn, par.nominal)).ravel(), a, rtol=1e-9, atol=1e-9)
        # the spring's torque by hand, and the energy's gradient
        np.testing.assert_allclose(m.spring_torque(qn), [0.045 * (qn[0] - 0.2), 0.035 * (qn[1] + 0.1)], rtol=1e-14)
        h = 1e-6
        grad = [(m.potential_energy(qn + h * e) - m.potential_energy(qn - h * e)) / (2 * h) for e in np.eye(2)]
        np.testing.assert_allclose(grad, m.gravity_torque(qn), rtol=1e-6, atol=1e-10)
    # the parametric spring's torque with K fitted away from nominal: K (q - q_rest)
    qn = np.array([0.7, 0.4])
    ps = cs.Function("p", [q, par.theta], [par.passive_torque(q, cs.DM.zeros(2), par.theta)])
    np.testing.assert_allclose(np.asarray(ps(qn, [0.06, 0.02])).ravel(), [0.06 * 0.5, 0.02 * 0.5], rtol=1e-14)


def test_mjcf_export_springref_stepped_in_mujoco():
    """The export writes springref = q0; MuJoCo's passive force is -k (q - q0) and, stepped with a viscous joint,
    the pendulum settles at the hand-computed equilibrium (0.51361 rad). The import reads the rest angle back."""
    mujoco = pytest.importorskip("mujoco")
    m = pendulum(viscous=5e-3)
    xml = m.to_mjcf(timestep=5e-4)
    assert re.search(r'<joint name="hinge"[^>]* springref="0.3"', xml)
    mj = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(mj)
    d.qpos[0], d.qvel[0] = 1.0, 0.0
    mujoco.mj_forward(mj, d)
    assert d.qfrc_passive[0] == pytest.approx(-K * (1.0 - Q0), rel=1e-12)
    d.qpos[0] = 0.0
    for _ in range(8000):  # 4 s: the mode (about 26 rad/s) damped at zeta ~ 0.1 settles within 2 s
        mujoco.mj_step(mj, d)
    assert d.qpos[0] == pytest.approx(hand_equilibrium(Q0), abs=1e-6)
    assert abs(d.qvel[0]) < 1e-5
    back = ad.Model.from_mjcf(xml)
    assert back.spec.rest_angle == {"hinge": Q0}
    assert back.static_equilibrium(np.zeros(1))[0] == pytest.approx(hand_equilibrium(Q0), abs=1e-10)
    assert 'springref="0"' in pendulum(None).to_mjcf()


def test_rest_angle_round_trips_the_spec_and_pickle():
    import pickle

    spec = TransmissionSpec.from_toml(pendulum_spec(-0.25))
    assert "[rest_angle]\nhinge = -0.25" in spec.to_toml()
    assert TransmissionSpec.from_toml(spec.to_toml()) == spec
    assert spec != TransmissionSpec.from_toml(pendulum_spec(0.25))
    m = pickle.loads(pickle.dumps(ad.Model(PENDULUM_URDF, spec)))
    assert m.extras.rest.tolist() == [-0.25]


SHIPPED_SPEC_URDFS = {"allegro_hand_spec.toml": ("allegro_hand", "allegro_right_hand"),
                      "finger_edu_spec.toml": ("finger_edu", "finger_edu")}
"""Each shipped transmission spec (``alpes_dyn/data/*_spec.toml``) and its example-robot-data URDF."""


def test_every_shipped_spec_rests_inside_its_joint_ranges():
    """With the motors off (zero motor torque) and the spec's gravity, every shipped spec's static equilibrium
    G(q) = 0 is inside every joint's range: no spring holds a joint on its stop for ever."""
    from pathlib import Path

    from alpes_dyn.model.spec import load_spec

    data = Path(ad.__file__).parent / "data"
    assert {p.name for p in data.glob("*_spec.toml")} == set(SHIPPED_SPEC_URDFS)  # a new spec needs its URDF here
    for name, (robot, urdf) in SHIPPED_SPEC_URDFS.items():
        m = ad.Model.from_urdf_file(ad.example_robot_urdf(robot, urdf), load_spec(data / name))
        q = m.static_equilibrium(np.zeros(m.n))
        np.testing.assert_allclose(m.gravity_torque(q), 0.0, atol=1e-12)  # the balance itself, zero motor torque
        outside = [(j, float(x)) for j, x, lo, hi in zip(m.joint_names, q, m.lower, m.upper) if not lo <= x <= hi]
        assert not outside, (name, outside)
    # the Allegro spec's two rest angles: the rule of its header, q_rest = q* + g(q*) / k with q* 5 % inside the range
    m = ad.Model.from_urdf_file(ad.example_robot_urdf("allegro_hand", "allegro_right_hand"),
                                load_spec(data / "allegro_hand_spec.toml"))
    q = m.static_equilibrium(np.zeros(m.n))
    for j in ("joint_12.0", "joint_14.0"):
        i = m.joint_index(j)
        assert m.lower[i] + 0.04 * (m.upper[i] - m.lower[i]) <= q[i] <= m.lower[i] + 0.06 * (m.upper[i] - m.lower[i])


def test_range_warning_names_the_rest_angle_field():
    """The Allegro spec with joint_12.0's spring resting at 0 (as shipped before its [rest_angle] table), below its
    range [0.263, 1.396]: simulate's range warning says so and names [rest_angle]."""
    from alpes_dyn.model.spec import example_spec_path
    from alpes_dyn.model.stops import JointRangeWarning
    from alpes_dyn.simulation import simulate

    text = example_spec_path().read_text(encoding="utf-8")
    assert '"joint_12.0" = 0.33\n' in text
    spec = TransmissionSpec.from_toml(text.replace('"joint_12.0" = 0.33\n', ""), "allegro, joint_12.0 resting at 0")
    m = ad.Model(ad.example_robot_urdf("allegro_hand", "allegro_right_hand").read_text(), spec)
    x0 = np.concatenate([m.static_equilibrium(np.zeros(m.n)), np.zeros(m.n)])
    with pytest.warns(JointRangeWarning, match=r"the spring of 'joint_12.0' rests at 0 rad, outside \[0.263, 1.396\]: "
                                               r"set its rest angle inside the range in the spec's \[rest_angle\]"):
        simulate(m, x0, 0.0, duration=0.002, dt=1e-3, input="motor")


# ----------------------------------------------------------------------------- the default tip
def test_default_tip_refused_where_the_first_leaf_is_ambiguous():
    """UR5 without a spec: three leaves (base, ee_link, tool0), no default tip; named, or a single leaf: fine."""
    ur = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"))
    q = np.zeros(ur.n)
    assert ur.tips == ("base", "ee_link", "tool0") and not ur.tips_named
    msg = ("tip: model 'ur5' names no tip and its URDF has 3 leaf frames (base, ee_link, tool0); name it: "
           'tips = ["<frame>"] in the spec, or tip=<frame>')
    for call in (lambda: ur.fingertip_jacobian(q), lambda: ur.default_tip, lambda: ur.contact_torque(q, 1.0)):
        with pytest.raises(ModelError, match=re.escape(msg)):
            call()
    assert np.abs(ur.fingertip_jacobian(q, "tool0")).max() > 0.1  # the real tip moves; the base (the old default) not
    named = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"), TransmissionSpec(tips=("tool0",)))
    assert named.default_tip == "tool0"
    np.testing.assert_array_equal(named.fingertip_jacobian(q), ur.fingertip_jacobian(q, "tool0"))
    assert ad.Model.from_urdf_file(ad.example_robot_urdf("double_pendulum")).default_tip == "link2"  # one leaf
    f = two_joint_finger(tips=False)
    with pytest.raises(ModelError, match=r"2 leaf frames \((fingertip, nail|nail, fingertip)\)"):
        f.fingertip_position(np.zeros(2))
    assert ad.Model.alpes("hand").default_tip == "index_tip"  # the layout names them


def test_symbolic_state_space_refuses_the_ambiguous_tip():
    from alpes_dyn.symbolic.statespace import StateSpace

    ur = ad.Model.from_urdf_file(ad.example_robot_urdf("ur", "ur5_robot"))
    with pytest.raises(ModelError, match=r"names no tip and its URDF has 3 leaf frames"):
        StateSpace(ur, output=np.eye(ur.n)[:1], force=True)
    assert StateSpace(ur, output=np.eye(ur.n)[:1]).tip is None  # no contact force: no tip needed
    assert StateSpace(ur, output=np.eye(ur.n)[:1], force=True, tip="tool0").tip == "tool0"


# ----------------------------------------------------------------------------- sized stops
def test_alpes_stops_keep_their_numbers():
    for name in ("finger2", "finger3", "thumb", "hand"):
        st = JointStops.of(ad.Model.alpes(name))
        assert (st.stiffness, st.damping) == ALPES_STOP == (2.0, 4e-3)
    k, d = sized_stops(ad.Model.alpes("finger3"))  # what the rule would give (documented)
    assert k == pytest.approx(1.6726, rel=1e-4) and d == pytest.approx(2.92e-3, rel=1e-3)


def test_sized_stops_scale_with_the_robot():
    """k = tau* / 1.4 deg, d = 2 sqrt(k I_min): a finger 50 times as heavy gets stops 50 times as stiff and damped."""
    light, heavy = two_joint_finger(1.0, rest=None), two_joint_finger(50.0, rest=None)
    kl, dl = sized_stops(light)
    kh, dh = sized_stops(heavy)
    # tau*: the finger flat at its lower stops, its weight on mcp (by hand: sum of m g x_com)
    tau = 9.81 * (0.028 * 0.022 + 0.018 * (0.045 + 0.014))
    assert kl == pytest.approx(tau / STOP_PENETRATION, rel=1e-9)
    assert kh / kl == pytest.approx(50.0, rel=1e-9) and dh / dl == pytest.approx(50.0, rel=1e-9)
    Ainv = np.linalg.inv(light.inertia_matrix(np.full(2, 0.75)))
    assert dl == pytest.approx(2.0 * math.sqrt(kl / Ainv.diagonal().max()), rel=1e-12)
    st = JointStops.of(heavy, stiffness=100.0)
    assert st.stiffness == 100.0 and st.damping == pytest.approx(dh * math.sqrt(100.0 / kh), rel=1e-12)


def test_sized_stops_hold_a_heavy_finger_at_its_limit():
    """A finger 50 times as heavy dropped from 0.3 rad onto its lower stops: the sized stops hold it within
    1.4 degrees (its weight over the stop's k and its spring's), the Alpes stop's 2 N m/rad lets it sink 23 degrees
    through."""
    from alpes_dyn.simulation import simulate

    m = two_joint_finger(50.0, rest=None, viscous=0.02)
    x0 = np.array([0.3, 0.3, 0.0, 0.0])
    sized = simulate(m, x0, 0.0, duration=1.0, dt=5e-4, input="motor", stops=JointStops.of(m))
    p = -sized.q[-1]  # the penetration below the lower stops (0 rad)
    assert np.all(p > 0) and np.all(p <= STOP_PENETRATION * 1.0001)
    tau = 50 * 9.81 * (0.028 * 0.022 + 0.018 * (0.045 + 0.014))  # mcp carries the whole weight: the rule's tau*
    k = JointStops.of(m).stiffness
    assert k == pytest.approx(tau / STOP_PENETRATION, rel=1e-9)
    assert p[0] == pytest.approx(tau / (k + 0.045), rel=1e-3)  # 1.397 degrees: the stop and the spring
    assert np.all(sized.q >= -np.radians(10.0))  # even on impact
    soft = simulate(m, x0, 0.0, duration=1.0, dt=5e-4, input="motor", stops=JointStops.of(m, 2.0, 4e-3))
    assert -soft.q[-1, 0] == pytest.approx(tau / (2.0 + 0.045), rel=1e-2)  # 23 degrees
    assert np.degrees(-soft.q[-1, 0]) > 20.0


def test_stops_refused_where_nothing_sizes_them():
    weightless = ad.Model(PENDULUM_URDF, TransmissionSpec(gravity=(0.0, 0.0, 0.0), stiffness={"hinge": 0.2}))
    with pytest.raises(InputError, match=r"nothing pushes model 'pendulum' into its joint stops .*pass stiffness="):
        JointStops.of(weightless)
    st = JointStops.of(weightless, stiffness=1.0)  # given k: d sized from it (the pendulum's own inertia)
    assert st.damping == pytest.approx(2.0 * math.sqrt(1.0 * (IYY + MASS * ARM**2)), rel=1e-12)
    # a spring resting beyond a stop pushes into it: that sizes the stop without gravity
    beyond = ad.Model(PENDULUM_URDF, TransmissionSpec(gravity=(0.0, 0.0, 0.0), stiffness={"hinge": 0.2},
                                                      rest_angle={"hinge": 2.0}))
    assert JointStops.of(beyond).stiffness == pytest.approx(0.2 * 0.5 / STOP_PENETRATION, rel=1e-12)


def test_per_joint_stops_hold_each_joint_at_the_documented_depth():
    """Per joint, k_i = tau*_i / 1.4 deg: the finger flat on its lower stops (its springs resting there, at 0) settles
    where the hand-written balance says, 9.81 [m1 c1 cos q1 + m2 (l1 cos q1 + c2 cos(q1 + q2))] = (k_1 + ks_1) p_1 and
    9.81 m2 c2 cos(q1 + q2) = (k_2 + ks_2) p_2 (q = -p): each joint gives p* k_i / (k_i + ks_i) to within the cosines,
    the light distal joint as much as the heavy proximal one; with one k for the robot (the proximal joint's) the
    distal joint gives 6.6 times less."""
    from alpes_dyn.simulation import simulate

    scale = 50.0
    m = two_joint_finger(scale, rest=None, viscous=0.02)
    m1, m2, c1, c2, l1, ks = 0.028 * scale, 0.018 * scale, 0.022, 0.014, 0.045, np.array([0.045, 0.035])
    tau = G0 * np.array([m1 * c1 + m2 * (l1 + c2), m2 * c2])  # the weights on mcp and pip, the finger flat
    st = JointStops.of(m, per_joint=True)
    np.testing.assert_allclose(st.stiffness, tau / STOP_PENETRATION, rtol=1e-9)
    Ainv = np.linalg.inv(m.inertia_matrix(np.full(2, 0.75)))
    np.testing.assert_allclose(st.damping, 2.0 * np.sqrt(st.stiffness / np.diag(Ainv)), rtol=1e-12)

    def balance(p: np.ndarray) -> np.ndarray:
        q1, q2 = -p
        g = G0 * np.array([m1 * c1 * math.cos(q1) + m2 * (l1 * math.cos(q1) + c2 * math.cos(q1 + q2)),
                           m2 * c2 * math.cos(q1 + q2)])
        return g - (st.stiffness + ks) * p

    p = tau / (st.stiffness + ks)
    for _ in range(50):  # fixed point: the cosines change p by parts in 1e4
        p = p + balance(p) / (st.stiffness + ks)
    assert np.max(np.abs(balance(p))) < 1e-14
    np.testing.assert_allclose(p, STOP_PENETRATION * st.stiffness / (st.stiffness + ks), rtol=2e-3)  # cos(p1 + p2)
    x0 = np.array([0.3, 0.3, 0.0, 0.0])
    settled = simulate(m, x0, 0.0, duration=1.0, dt=5e-4, input="motor", stops=st).q[-1]
    np.testing.assert_allclose(-settled, p, rtol=1e-4)
    np.testing.assert_allclose(m.gravity_torque(settled), st.torque(settled, np.zeros(2)), rtol=1e-6)
    scalar = JointStops.of(m)
    assert scalar.stiffness == pytest.approx(st.stiffness[0], rel=1e-12)
    p_scalar = -simulate(m, x0, 0.0, duration=1.0, dt=5e-4, input="motor", stops=scalar).q[-1]
    assert p_scalar[0] == pytest.approx(p[0], rel=1e-3)
    assert p_scalar[1] == pytest.approx(tau[1] / (scalar.stiffness + ks[1]), rel=2e-3)  # 0.21 deg, not 1.4
    assert p_scalar[1] < p[1] / 6


def test_per_joint_stops_given_and_sized():
    """Given k per joint, d is sized per joint from it; the Alpes models keep their stop unless per_joint; the
    Allegro hand, whose springs now hold every joint off its stops, is sized by its weight on them."""
    from alpes_dyn.model.spec import example_spec_path

    m = two_joint_finger(1.0, rest=None)
    st = JointStops.of(m, stiffness=[3.0, 1.0])
    Ainv = np.linalg.inv(m.inertia_matrix(np.full(2, 0.75)))
    np.testing.assert_allclose(st.damping, 2.0 * np.sqrt(np.array([3.0, 1.0]) / np.diag(Ainv)), rtol=1e-12)
    assert not st.stiffness.flags.writeable
    st = JointStops.of(m, stiffness=[3.0, 1.0], damping=0.01)
    assert st.damping == 0.01 and st.torque(np.array([-0.1, -0.2]), np.zeros(2)).tolist() == pytest.approx([0.3, 0.2])
    f3 = ad.Model.alpes("finger3")
    assert (JointStops.of(f3).stiffness, JointStops.of(f3).damping) == ALPES_STOP
    k = JointStops.of(f3, per_joint=True).stiffness
    assert k[0] == pytest.approx(sized_stops(f3)[0], rel=1e-12) and k[0] > k[1] > k[2]
    hand = ad.Model.from_urdf_file(ad.example_robot_urdf("allegro_hand", "allegro_right_hand"), example_spec_path())
    k, d = sized_stops(hand)
    assert k == pytest.approx(1.913, rel=1e-3) and d == pytest.approx(8.94e-3, rel=1e-2)
