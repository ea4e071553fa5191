"""Force control on any URDF + spec robot (issue 17): the block placed from the robot's kinematics, the closed loop
on MuJoCo against the touch sensor and the static balance written out here with Pinocchio, the command line.

The robot is test_anyrobot's two-joint tendon finger, its springs resting inside the joint ranges and without
Coulomb friction (so that the static balance holds exactly at rest; the viscous friction vanishes there)."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.control.controller import DEFAULT_GAINS, static_contact_force
from alpes_dyn.control.finger_loop import finger3_contact, run_control, scaled_gains
from alpes_dyn.model.block_scene import block_scene_mjcf, place_block
from alpes_dyn.model.mjcf_export import model_mjcf
from test_anyrobot import FINGER_URDF, finger_spec

K, REST, S = np.array([0.045, 0.035]), np.array([0.5, 0.5]), np.array([2.0, 1.5])  # the spec's springs, ratios
SPEC = finger_spec(Fs=(0.0, 0.0)) + "\n[rest_angle]\nmcp = 0.5\npip = 0.5\n"


@pytest.fixture(scope="module")
def finger(tmp_path_factory):
    d = tmp_path_factory.mktemp("urdfcontrol")
    (d / "finger.urdf").write_text(FINGER_URDF)
    (d / "finger.toml").write_text(SPEC)
    return d


@pytest.fixture(scope="module")
def model(finger):
    return ad.Model.from_urdf_file(finger / "finger.urdf", finger / "finger.toml")


def _pin_gravity_and_jacobian(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """G(q) (gravity + the spec's springs) and the fingertip's linear Jacobian (base axes), from the URDF alone."""
    pm = pin.buildModelFromXML(FINGER_URDF)
    pd = pm.createData()
    G = pin.computeGeneralizedGravity(pm, pd, q) + K * (q - REST)
    J = pin.computeFrameJacobian(pm, pd, q, pm.getFrameId("fingertip"), pin.LOCAL_WORLD_ALIGNED)[:3]
    return G, J


def test_block_placed_where_the_motor_brings_the_tip(model):
    b = place_block(model)
    assert (b.frame, b.motor) == ("fingertip", "flexor")
    G, J = _pin_gravity_and_jacobian(b.contact_q)
    tau_c = S @ G / (S @ S)  # q_c is an equilibrium under the motor alone: G(q_c) = S tau_c
    np.testing.assert_allclose(G, S * tau_c, atol=1e-10)
    rest_q = model.static_equilibrium(np.zeros(2))
    np.testing.assert_allclose(K * (rest_q - REST), -pin.computeGeneralizedGravity(
        pin.buildModelFromXML(FINGER_URDF), pin.buildModelFromXML(FINGER_URDF).createData(), rest_q), atol=1e-10)
    # the joints have covered 25 % of their way to the upper ends (the larger fraction of the two)
    assert np.max((b.contact_q - rest_q) / (1.5 - rest_q)) == pytest.approx(0.25, abs=1e-8)
    # the normal: the tip's displacement between two equilibria a little further along the pull (finite difference)
    q2 = model.static_equilibrium(S * tau_c * (1 + 1e-6), b.contact_q)
    d = model.fingertip_position(q2) - model.fingertip_position(b.contact_q)
    np.testing.assert_allclose(b.normal, d / np.linalg.norm(d), atol=1e-5)
    # the block's near face touches the tip sphere at q_c; the lever is S (J^T n) / |S|^2
    assert float(b.normal @ (b.center - b.tip_position)) == pytest.approx(b.tip_radius + b.half[2], rel=1e-12)
    assert b.lever == pytest.approx(S @ (J.T @ b.normal) / (S @ S), rel=1e-10)
    xml = block_scene_mjcf(model, b)
    assert xml.replace([ln for ln in xml.splitlines() if 'name="block"' in ln][0] + "\n", "") == model_mjcf(model)


def test_mujoco_sees_the_tip_touch_the_block_at_the_contact(model):
    """MuJoCo's own distance between the block and the tip's sphere: 0 at q_c, positive at rest, negative (pressed)
    a little further along the motor's pull."""
    mujoco = pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf import joint_permutation

    b = place_block(model)
    mj = mujoco.MjModel.from_xml_string(block_scene_mjcf(model, b))
    d = mujoco.MjData(mj)
    G, _ = _pin_gravity_and_jacobian(b.contact_q)
    further = model.static_equilibrium(S * (S @ G / (S @ S)) * 1.05, b.contact_q)

    def distance(q: np.ndarray) -> float:
        d.qpos[joint_permutation(mj, model.joint_names)] = q
        mujoco.mj_forward(mj, d)
        return mujoco.mj_geomDistance(mj, d, mj.geom("block").id, mj.geom("fingertip").id, 1.0, np.zeros(6))

    assert abs(distance(b.contact_q)) < 1e-12 and distance(b.rest_q) > 0.01 and distance(further) < 0


def test_force_held_on_the_urdf_and_equal_to_the_static_balance(model):
    r = run_control("sensor", model=model, duration=1.8, step_times=(0.8, 1.3))
    assert r.steady_state_error < 0.02 and max(r.q_rmse_deg) < 2.0
    n = r.block.normal
    for hi, level in zip((0.8, 1.3, 1.8), r.scenario.levels):  # each level's last 200 ms (0.2, 0.6, 0.2 N)
        w = (r.t >= hi - 0.2) & (r.t < hi)
        q, tau, F_touch = r.q_true[w].mean(0), r.tau_cmd[w].mean(), r.F_true[w].mean()
        assert F_touch == pytest.approx(level, rel=0.02)  # MuJoCo's touch sensor holds the reference
        G, J = _pin_gravity_and_jacobian(q)
        jn = J.T @ n
        residual = S * tau - G - F_touch * jn  # J^T F = S^T tau_m - G, F = -F_z n
        assert np.max(np.abs(residual)) < 0.01 * np.max(np.abs(S * tau))
        assert static_contact_force(model, q, np.array([tau]), n, "fingertip") == pytest.approx(F_touch, rel=0.01)
    # the controller that 'codegen --controller' exports (control.cexport.robot_controller) is the loop's: on the
    # loop's own inputs it commands the loop's torques, to the bit
    from alpes_dyn.control.cexport import robot_controller

    ctl = robot_controller("sensor", model)
    tau = [ctl.update(float(r.F_ref[k]), float(r.F_meas[k]), r.q_hat[k]) for k in range(len(r.t))]
    assert ctl.tau_max == r.tau_max and np.array_equal(np.array(tau), r.tau_cmd)


def test_gains_scaled_by_the_lever_and_the_contact_torque():
    lever, tau = finger3_contact()
    assert scaled_gains("sensor", lever, tau) == {**DEFAULT_GAINS["sensor"], "approach_rate": 0.03}
    g = scaled_gains("pi", 2 * lever, 3 * tau)
    assert (g["kp"], g["ki"], g["approach_rate"]) == pytest.approx((0.016, 1.6, 0.09))


def test_control_command_on_the_urdf(finger, capsys):
    rc = main(["control", "--model", str(finger / "finger.urdf"), "--spec", str(finger / "finger.toml"),
               "--frame", "fingertip", "--controller", "pi", "--duration", "1.8", "--json"])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0 and obj["model"] == "tendon_finger" and (obj["frame"], obj["motor"]) == ("fingertip", "flexor")
    assert obj["steady_state_error"] < 0.02 and obj["q_rmse_deg"] is None
    assert obj["tau_max_Nm"] == pytest.approx(2 * obj["lever_m"] * 1.0 + 2 * place_block_tau0(finger), rel=1e-9)


def place_block_tau0(finger) -> float:
    """The motor torque that holds the tip at the block's contact with no force, N m (S G(q_c) / |S|^2)."""
    m = ad.Model.from_urdf_file(finger / "finger.urdf", finger / "finger.toml")
    G, _ = _pin_gravity_and_jacobian(place_block(m).contact_q)
    return float(S @ G / (S @ S))


def test_one_motor_of_two_named_and_its_force_held(finger):
    """A second motor on the distal joint: the default motor is refused as ambiguous (both move the tip); the loop
    drives the one named (MuJoCo's other actuator at 0 N m) and holds the force."""
    two = SPEC.replace('[[motor]]\nname = "flexor"\njoints = { mcp = 2.0, pip = 1.5 }\n',
                       '[[motor]]\nname = "flexor"\njoints = { mcp = 2.0, pip = 1.5 }\n\n'
                       '[[motor]]\nname = "distal"\njoints = { pip = 1.0 }\n')
    (finger / "two.toml").write_text(two)
    m = ad.Model.from_urdf_file(finger / "finger.urdf", finger / "two.toml")
    with pytest.raises(ad.InputError, match="motor: 'tendon_finger' has 2 motors moving 'fingertip'"):
        run_control("pi", model=m, frame="fingertip")
    r = run_control("pi", model=m, motor="flexor", duration=1.8, step_times=(0.8, 1.3))
    assert r.steady_state_error < 0.02 and r.block.motor == "flexor" and r.tau_meas.shape == r.t.shape


def test_contact_q_given_places_the_same_block(model, finger, capsys):
    """--contact-q at the default q_c (the CLI's text of its floats) runs the same loop as the default."""
    q_c = place_block(model).contact_q
    argv = ["control", "--model", str(finger / "finger.urdf"), "--spec", str(finger / "finger.toml"), "--controller",
            "pi", "--duration", "0.6", "--json"]
    outs = []
    for extra in ([], ["--contact-q", ",".join(repr(float(x)) for x in q_c)]):
        assert main(argv + extra) == 0
        outs.append(json.loads(capsys.readouterr().out))
    assert outs[1]["contact_q"] == outs[0]["contact_q"] and outs[1]["force_rmse"] == outs[0]["force_rmse"]
