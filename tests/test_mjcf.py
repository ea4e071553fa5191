"""MJCF export against the library: MuJoCo's dynamics, tendons, motors and sensors on the exported model.

References: MuJoCo (an independent physics engine) computing qacc, tendon lengths, actuator forces and
a contact force on the text written by alpes_dyn.model.mjcf; alpes_dyn's Pinocchio model on the other side.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.model.mjcf import BLOCK_CONTACT_Q, block_normal, joint_permutation, load_mujoco, mjcf_string, palm_down_params

mujoco = pytest.importorskip("mujoco")


def _state(mj, d, perm, q, v, ctrl):
    d.qpos[perm], d.qvel[perm], d.ctrl[:] = q, v, ctrl
    mujoco.mj_forward(mj, d)


@pytest.mark.parametrize("name", ad.MODELS)
@pytest.mark.parametrize("rotor_inertia", [False, True])
def test_qacc_equals_library_forward_dynamics(name, rotor_inertia, rng):
    """Contact and limits off: MuJoCo's qacc = Model.forward_dynamics(q, v, S^T tau_m) to 1e-9 relative."""
    m = ad.Model.alpes(name, rotor_inertia=rotor_inertia)
    mj = load_mujoco(mjcf_string(name, rotor_inertia=rotor_inertia, limits=False, contact=False))
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, m.joint_names)
    tr = m.transmission
    lo = np.where(np.char.endswith(np.array(tr.motor_names), "abduction"), -0.05, 0.0)
    worst = 0.0
    for _ in range(20):
        q, v = m.random_state(rng, speed=3.0)
        q = q + rng.uniform(-0.3, 0.3, m.n)  # also outside the joint range: no stop acts
        tau_m = rng.uniform(lo, 0.05)
        _state(mj, d, perm, q, v, tau_m)
        a = m.forward_dynamics(q, v, tr.joint_torque(tau_m))
        worst = max(worst, float(np.max(np.abs(d.qacc[perm] - a)) / np.max(np.abs(a))))
        assert np.allclose(d.qfrc_actuator[perm], tr.joint_torque(tau_m), rtol=1e-12, atol=1e-15)
    assert worst <= 1e-9


@pytest.mark.parametrize("name", ["finger3", "hand"])
def test_rotor_inertia_on_the_tendon_equals_mujoco_mass_matrix(name, rng):
    """The rotor on the tendon: the fixed tendon's armature J_m / r_m^2 gives MuJoCo's M (mj_fullM) =
    A(q) + S^T diag(J_m) S of Model.inertia_matrix to 1e-10 relative, and the rotor fills whole chain blocks."""
    m = ad.Model.alpes(name, rotor_inertia=True)
    mj = load_mujoco(mjcf_string(name, rotor_inertia=True, limits=False, contact=False))
    p = ad.load_params()
    assert np.allclose(mj.tendon_armature, p.J_m / p.r_m**2, rtol=1e-15)
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, m.joint_names)
    M = np.zeros((mj.nv, mj.nv))
    for _ in range(5):
        q, v = m.random_state(rng)
        _state(mj, d, perm, q, v, np.zeros(mj.nu))
        mujoco.mj_fullM(mj, d, M)  # MuJoCo 4: (model, data, dst)
        ours = m.inertia_matrix(q)
        assert np.max(np.abs(M[np.ix_(perm, perm)] - ours)) <= 1e-10 * np.max(np.abs(ours))
    j1, j3 = (m.joint_index(j) for j in (("j1", "j3") if name == "finger3" else ("index_j1", "index_j3")))
    assert m.rotor_matrix[j1, j3] == pytest.approx((p.r / p.r_m) ** 2 * p.J_m, rel=1e-15)


@pytest.mark.parametrize("name", ad.MODELS)
def test_tendon_motor_and_sensor_mapping(name, rng):
    """Tendon length / r_m = encoder q_m = MuJoCo's actuatorpos; actuatorfrc = tau_m; tip site = tip frame."""
    p = ad.load_params()
    m = ad.Model.alpes(name)
    mj = load_mujoco(mjcf_string(name))
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, m.joint_names)
    tr = m.transmission
    for _ in range(5):
        q, v = m.random_state(rng)
        tau_m = rng.uniform(0.0, 0.05, tr.n_motors)
        _state(mj, d, perm, q, v, tau_m)
        qm = tr.motor_positions(q)
        for k, mn in enumerate(tr.motor_names):
            assert d.sensor(f"encoder_{mn}").data[0] == pytest.approx(qm[k], rel=1e-12, abs=1e-14)
            assert d.sensor(f"torque_{mn}").data[0] == pytest.approx(tau_m[k], rel=1e-12)
            if not mn.endswith("abduction"):
                assert d.sensor(f"tendon_{mn}").data[0] / p.r_m == pytest.approx(qm[k], rel=1e-12, abs=1e-14)
        for tip in m.tips:
            assert np.allclose(d.site(tip).xpos, m.fingertip_position(q, tip), atol=1e-15)


def test_stops_springs_pull_only_and_friction_written():
    p = ad.load_params()
    mj = load_mujoco(mjcf_string("hand", spring="report", friction=True))
    m = ad.Model.alpes("hand", spring="report")
    perm = joint_permutation(mj, m.joint_names)
    jids = [mj.joint(nm).id for nm in m.joint_names]
    assert np.allclose(mj.jnt_stiffness[jids], m.extras.stiffness, rtol=1e-15)
    assert np.all(mj.jnt_limited[jids] == 1)
    assert np.allclose(mj.jnt_range[jids, 0], m.lower) and np.allclose(mj.jnt_range[jids, 1], m.upper)
    assert np.allclose(mj.dof_damping[perm], p.F_v) and np.allclose(mj.dof_frictionloss[perm], p.F_s)
    flex = [mj.actuator(nm).id for nm in m.transmission.motor_names if not nm.endswith("abduction")]
    assert np.allclose(mj.actuator_ctrlrange[flex], [0.0, p.tau_max])
    d = mujoco.MjData(mj)
    d.ctrl[:] = -0.01  # a cable cannot push: MuJoCo clamps the flexion motors to 0
    mujoco.mj_forward(mj, d)
    assert np.all(d.actuator_force[flex] == 0.0) and d.actuator_force[mj.actuator("thumb_abduction").id] == -0.01


def test_block_contact_force_equals_static_balance():
    """Finger3 pressing the frictionless block: the touch sensor reads the F_z that balances the library's
    G(q) - S^T tau_m = J^T (-F_z n) (eq. 2.11), at MuJoCo's equilibrium."""
    p = palm_down_params(ad.load_params())
    m = ad.Model.alpes("finger3", params=p)
    mj = load_mujoco(mjcf_string("finger3", p, scene="block", friction=True))
    d = mujoco.MjData(mj)
    for k in range(8000):  # ramp the motor torque to 0.03 N m over 1 s, then hold it 1 s
        d.ctrl[0] = 0.03 * min(1.0, k / 4000)
        mujoco.mj_step(mj, d)
    F = d.sensor("flexiforce_finger").data[0]
    q = d.qpos.copy()
    n = block_normal(BLOCK_CONTACT_Q)
    rhs = m.gravity_torque(q) - m.transmission.joint_torque([0.03])
    jn = -(m.fingertip_jacobian(q).T @ n)
    F_static = float(jn @ rhs / (jn @ jn))
    assert 0.5 < F < 0.7
    assert F == pytest.approx(F_static, rel=1e-4)
    assert np.linalg.norm(rhs - jn * F_static) < 1e-5  # the contact force is normal to the block


def test_cli_mjcf(capsys, tmp_path):
    assert main(["mjcf", "--model", "finger3", "--scene", "block", "--palm-down"]) == 0
    out = capsys.readouterr().out
    assert out == mjcf_string("finger3", scene="block", palm_down=True)
    dest = tmp_path / "h.xml"
    assert main(["mjcf", "--model", "hand", "--scene", "cylinder", "-o", str(dest)]) == 0
    assert load_mujoco(dest.read_text()).nu == 6


@pytest.mark.parametrize("argv,needle", [
    (["mjcf", "--model", "finger7"], "unknown model 'finger7'"),
    (["mjcf", "--model", "hand", "--scene", "block"], "scene 'block' is for one finger"),
    (["mjcf", "--model", "finger3", "--scene", "table"], "invalid choice: 'table'"),
    (["mjcf", "--model", "finger3", "-o", "/nonexistent/dir/x.xml"], "-o: directory '/nonexistent/dir' of"),
])
def test_cli_mjcf_bad_input(capsys, argv, needle):
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 2 and out == "" and err.count("\n") == 1 and needle in err


def test_missing_mujoco_one_line(monkeypatch):
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ad.ModelError, match=r"^mujoco is not installed \(pip install 'alpes_dyn\[mujoco\]'\)$"):
        load_mujoco(mjcf_string("finger2"))
