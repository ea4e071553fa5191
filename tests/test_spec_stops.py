"""The spec's ``[stops]`` table (issue 17, item 4): joint stops a user gives, robot-wide or per joint, used by our
simulator (``JointStops.of``), the MJCF export (MuJoCo's ``solreflimit``) and ``alpes-dyn dynamics``' stop table.

References by hand: the one-joint pendulum of ``test_robot_sizes`` (0.1 kg at 5 cm, inertia m l^2 + I_yy about its
axis, spring 0.2 N m/rad resting at 0.3 rad) pushed into its upper stop (1.5 rad) by a constant torque settles where
tau - k_s (q - q0) + m g l cos q = k (q - 1.5), solved here by bisection; a critically damped stop's d = 2 sqrt(k I).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.spec import TransmissionSpec
from alpes_dyn.model.stops import JointStops, sized_stops, stop_table
from alpes_dyn.simulation.integrate import simulate
from test_robot_sizes import ARM, G0, IYY, K, MASS, PENDULUM_URDF, Q0, pendulum_spec

INERTIA = MASS * ARM**2 + IYY  # kg m^2 about the hinge
TAU = 0.5  # N m pushing the pendulum into its upper stop


def _pendulum(stops: str, viscous: float = 0.01) -> ad.Model:
    return ad.Model(PENDULUM_URDF, TransmissionSpec.from_toml(pendulum_spec(viscous=viscous) + stops))


def _hand_rest_on_stop(k: float) -> float:
    """q (rad) where TAU - K (q - Q0) + m g l cos q = k (q - 1.5), by bisection on [1.5, 2.5]."""
    f = lambda q: TAU - K * (q - Q0) + MASS * G0 * ARM * math.cos(q) - k * (q - 1.5)  # noqa: E731
    a, b = 1.5, 2.5
    assert f(a) > 0 > f(b)
    for _ in range(200):
        c = 0.5 * (a + b)
        a, b = (c, b) if f(c) > 0 else (a, c)
    return 0.5 * (a + b)


def test_spec_stops_parse_write_and_order():
    """A joint's own value over the robot-wide one, NaN where none; the TOML written reads back equal."""
    spec = TransmissionSpec.from_toml('[stiffness]\nj1 = 0.1\n\n[stops]\nstiffness = 4.0\n\n[stops.joints]\n'
                                      'j2 = { stiffness = 9.0, damping = 0.02 }\nj3 = { damping = 0.0 }\n')
    k, d = spec.stop_values(["j1", "j2", "j3"])
    np.testing.assert_array_equal(k, [4.0, 9.0, 4.0])
    np.testing.assert_array_equal(d, [np.nan, 0.02, 0.0])
    assert TransmissionSpec.from_toml(spec.to_toml()) == spec
    assert TransmissionSpec.from_toml(spec.to_toml()).stops["joints"]["j3"] == {"damping": 0.0}
    assert spec != TransmissionSpec.from_toml('[stiffness]\nj1 = 0.1\n')


def test_spec_stops_in_the_simulator_against_the_hand_equilibrium():
    """stiffness and damping from the spec as given; the pendulum pushed into its stop by TAU settles where the hand
    computation says (to 1e-7 rad); a spec giving only k gets d = 2 sqrt(k I), I the pendulum's inertia by hand."""
    k, d = 3.0, 0.02
    m = _pendulum(f"\n[stops]\nstiffness = {k}\ndamping = {d}\n")
    st = JointStops.of(m)
    assert (st.stiffness, st.damping) == (k, d)
    r = simulate(m, [1.5, 0.0], TAU, duration=3.0, dt=1e-4, output="joints", stops=st)
    assert r.x[-1, 0] == pytest.approx(_hand_rest_on_stop(k), abs=1e-7)
    assert abs(r.x[-1, 1]) < 1e-6
    only_k = JointStops.of(_pendulum(f"\n[stops]\nstiffness = {k}\n"))
    assert only_k.stiffness == k and only_k.damping == pytest.approx(2 * math.sqrt(k * INERTIA), rel=1e-9)
    explicit = JointStops.of(m, stiffness=1.0)  # an argument over the spec
    assert explicit.stiffness == 1.0 and explicit.damping == d


def test_spec_stops_per_joint_with_the_others_sized():
    """finger_edu with a stop on its distal joint only: that joint's values, the others the robot's sized k (the same
    as without the table) and d = 2 sqrt(k I_min); the stop table says where each comes from."""
    from alpes_dyn.model.spec import example_spec_path, load_spec
    import dataclasses

    urdf = ad.example_robot_urdf("finger_edu").read_text()
    spec = load_spec(example_spec_path("finger_edu"))
    plain = ad.Model(urdf, spec)
    k0, d0 = sized_stops(plain)
    m = ad.Model(urdf, dataclasses.replace(spec, stops={"joints": {"finger_middle_to_lower_joint": {
        "stiffness": 7.0, "damping": 0.05}}}))
    st = JointStops.of(m)
    np.testing.assert_allclose(st.stiffness, [k0, k0, 7.0], rtol=1e-12)
    np.testing.assert_allclose(st.damping, [d0, d0, 0.05], rtol=1e-12)
    t = stop_table(m)
    assert t["source"] == ["sized", "sized", "spec"] and t["stiffness"][2] == 7.0
    wide = ad.Model(urdf, dataclasses.replace(spec, stops={"stiffness": 2.5}))
    assert stop_table(wide)["source"] == ["spec k, sized d"] * 3 and JointStops.of(wide).stiffness == 2.5


def test_mjcf_export_writes_the_spec_stops_and_mujoco_holds_them():
    """The export's solreflimit is -k/I and -d/I with I the pendulum's inertia by hand (MuJoCo's dof_invweight0 =
    1/I); MuJoCo's settled state against the stop is the hand equilibrium, to 2e-4 of the penetration (the
    constraint's impedance 1e-4 takes that share); the library's simulation and MuJoCo's bounce agree. Without
    [stops] the export is unchanged (MuJoCo's default limit)."""
    mujoco = pytest.importorskip("mujoco")
    k, d = 3.0, 0.02
    m = _pendulum(f"\n[stops]\nstiffness = {k}\ndamping = {d}\n")
    mj = mujoco.MjModel.from_xml_string(m.to_mjcf())
    np.testing.assert_allclose(mj.jnt_solref[0], [-k / INERTIA, -d / INERTIA], rtol=1e-12)
    assert mj.dof_invweight0[0] == pytest.approx(1 / INERTIA, rel=1e-12)
    data = mujoco.MjData(mj)
    data.qpos[0] = 1.5
    data.qfrc_applied[0] = TAU
    q_mj = []
    for _ in range(30):
        mujoco.mj_step(mj, data, nstep=1000)  # 0.1 s
        q_mj.append(float(data.qpos[0]))
    q_hand = _hand_rest_on_stop(k)
    assert (q_mj[-1] - 1.5) == pytest.approx(q_hand - 1.5, rel=2e-4)
    r = simulate(m, [1.5, 0.0], TAU, duration=3.0, dt=1e-4, output="joints", stops=JointStops.of(m))
    ours = r.x[1000::1000, 0]
    assert np.max(np.abs(ours - np.array(q_mj))) < 1e-3 * (q_hand - 1.5) + 1e-6
    plain = _pendulum("")
    assert "solreflimit" not in plain.to_mjcf() and ad.Model.from_mjcf(plain.to_mjcf()).spec.stops is None
    back = ad.Model.from_mjcf(m.to_mjcf()).spec.stops["joints"]["hinge"]  # the import reads the stop back
    assert back["stiffness"] == pytest.approx(k, rel=1e-12) and back["damping"] == pytest.approx(d, rel=1e-12)


def test_dynamics_command_says_spec(tmp_path, capsys):
    from alpes_dyn.cli import main

    u, s = tmp_path / "p.urdf", tmp_path / "p.toml"
    u.write_text(PENDULUM_URDF)
    s.write_text(pendulum_spec() + "\n[stops]\nstiffness = 3.0\ndamping = 0.02\n")
    assert main(["dynamics", "--model", str(u), "--spec", str(s), "--json"]) == 0
    stops = json.loads(capsys.readouterr().out)["stops"]
    for table in (stops["robot"], stops["per_joint"]):
        assert table["source"] == ["spec"] and table["stiffness"] == [3.0] and table["damping"] == [0.02]


def test_subtree_keeps_its_joints_stops():
    """A sub-model's spec keeps the robot-wide values and its own joints' rows."""
    from test_bad_input import BRANCHES_SPEC, BRANCHES_URDF

    m = ad.Model(BRANCHES_URDF, TransmissionSpec.from_toml(
        BRANCHES_SPEC.replace("[[motor]]\nname = \"across\"\njoints = { ja = 1.0, jb = 0.5 }\n\n", "")
        + "\n[stops]\ndamping = 0.01\n\n[stops.joints]\nja = { stiffness = 5.0 }\njb = { stiffness = 6.0 }\n"))
    sub = m.subtree("fa")
    assert sub.spec.stops == {"damping": 0.01, "joints": {"ja": {"stiffness": 5.0}}}
    assert JointStops.of(sub).stiffness == 5.0 and JointStops.of(sub).damping == 0.01
