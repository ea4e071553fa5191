"""A robot's sub-model on the branches some motors drive (issues 17 and 20: an Allegro finger fitted and observed on
its own branch): its dynamics equal the full Pinocchio model's rows and columns of the kept joints (an independent
reference), what would couple two branches is refused, and ``identify --chain`` / ``estimate --data --chain`` on a
two-finger hand of the test's own run on the chain's sub-model: the same fitted values as the whole robot's
chain fit, the whole robot's spec written back with the chain's values replaced."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.errors import ModelError, RecordingError
from alpes_dyn.model.spec import TransmissionSpec, example_spec_path, load_spec
from alpes_dyn.model.subtree import branch_joints, closed_motors, subtree_model


def _finger(s: str, parent: str, y: float, m1: float, m2: float) -> str:
    """A two-joint planar finger (joints mcp_<s>, pip_<s>) on ``parent`` at lateral offset ``y`` (m)."""
    return f"""
  <link name="proximal_{s}"><inertial><origin xyz="0.022 0.001 0"/><mass value="{m1}"/>
    <inertia ixx="9e-07" ixy="1e-8" ixz="0" iyy="5e-06" iyz="0" izz="5e-06"/></inertial></link>
  <joint name="mcp_{s}" type="revolute"><parent link="{parent}"/><child link="proximal_{s}"/>
    <origin xyz="0 {y} 0" rpy="0.1 0 0"/><axis xyz="0 -1 0"/><limit lower="0.0" upper="1.5" effort="1" velocity="20"/></joint>
  <link name="distal_{s}"><inertial><origin xyz="0.014 0 0.001"/><mass value="{m2}"/>
    <inertia ixx="6e-07" ixy="0" ixz="0" iyy="1.4e-06" iyz="0" izz="1.4e-06"/></inertial></link>
  <joint name="pip_{s}" type="revolute"><parent link="proximal_{s}"/><child link="distal_{s}"/>
    <origin xyz="0.045 0 0"/><axis xyz="0 -1 0"/><limit lower="0.0" upper="1.5" effort="1" velocity="20"/></joint>
  <link name="tip_{s}"/>
  <joint name="tip_joint_{s}" type="fixed"><parent link="distal_{s}"/><child link="tip_{s}"/><origin xyz="0.028 0 0"/></joint>"""


# a palm with finger a on it and finger b on a mount fixed to it (a fixed link between the base and a branch)
HAND_URDF = ('<?xml version="1.0"?>\n<robot name="two_fingers">\n  <link name="palm"><inertial><origin xyz="0 0 0"/><mass value="0.2"/>'
             '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial></link>\n'
             '  <link name="mount"/>\n  <joint name="mount_joint" type="fixed"><parent link="palm"/><child link="mount"/>'
             '<origin xyz="0 0.03 0.01"/></joint>'
             + _finger("a", "palm", -0.02, 0.028, 0.018) + _finger("b", "mount", 0.0, 0.031, 0.016) + "\n</robot>\n")


def hand_spec(K=(0.045, 0.035, 0.05, 0.03), coupling: bool = False) -> str:
    """Tendons flexor_a (mcp_a, pip_a) and flexor_b, a direct motor distal_a on pip_a; springs, friction, rotor
    inertia; with ``coupling`` a motor over mcp_a and mcp_b (a tendon across the two branches)."""
    extra = '[[motor]]\nname = "across"\njoints = { mcp_a = 1.0, mcp_b = 1.0 }\n\n' if coupling else ""
    return ('name = "two_fingers"\nencoder_counts = 4096\ntips = ["tip_a", "tip_b"]\n\n'
            '[[motor]]\nname = "flexor_a"\njoints = { mcp_a = 2.0, pip_a = 1.5 }\nrotor_inertia = 2e-7\n\n'
            '[[motor]]\nname = "flexor_b"\njoints = { mcp_b = 2.0, pip_b = 1.5 }\nrotor_inertia = 3e-7\n\n'
            '[[motor]]\nname = "distal_a"\njoints = { pip_a = 1.0 }\n\n' + extra
            + f"[stiffness]\nmcp_a = {K[0]!r}\npip_a = {K[1]!r}\nmcp_b = {K[2]!r}\npip_b = {K[3]!r}\n\n"
            "[rest_angle]\nmcp_a = 0.1\n\n[coulomb]\nmcp_a = 5e-4\npip_a = 4e-4\nmcp_b = 5e-4\npip_b = 4e-4\n\n"
            "[viscous]\nmcp_a = 1e-4\npip_a = 1e-4\nmcp_b = 1e-4\npip_b = 1e-4\n\n[armature]\nmcp_b = 1e-7\n")


@pytest.fixture(scope="module")
def hand():
    return ad.Model(HAND_URDF, TransmissionSpec.from_toml(hand_spec()))


def _random_states(m, rng, k=5):
    for _ in range(k):
        yield rng.uniform(m.lower, m.upper), rng.normal(0, 2.0, m.n), rng.normal(0, 0.05, m.n)


def test_sub_model_keeps_the_branch_and_the_motors_on_it(hand):
    sub = hand.subtree("flexor_a")
    assert sub.joint_names == ("mcp_a", "pip_a") and sub.motor_names == ("flexor_a", "distal_a")
    assert sub.tips == ("tip_a",) and sub.name == "two_fingers[flexor_a]"
    assert dict(sub.spec.stiffness) == {"mcp_a": 0.045, "pip_a": 0.035} and dict(sub.spec.rest_angle) == {"mcp_a": 0.1}
    assert dict(sub.spec.armature) == {}  # mcp_b's armature went with its branch
    assert "proximal_b" not in sub.urdf and "mount" in sub.urdf  # the fixed mount is the base's, kept
    assert hand.subtree("distal_a").joint_names == sub.joint_names  # any motor of the branch names it
    assert hand.subtree(["flexor_b", "flexor_a"]).joint_names == hand.joint_names
    assert branch_joints(hand, "flexor_b") == (("mcp_b", "pip_b"), ("flexor_b",))
    assert sub.subtree("flexor_a").joint_names == sub.joint_names  # the sub-model of a sub-model: itself


@pytest.mark.parametrize("motor", ["flexor_a", "flexor_b"])
def test_sub_model_dynamics_equal_the_full_pinocchio_rows(hand, motor):
    """A, the bias and gravity torques and the forward dynamics of the sub-model against the full Pinocchio
    model (its CRBA, RNEA and ABA on all four joints; the spec's extras added by hand) at random states."""
    sub = subtree_model(hand, motor)
    idx = [hand.joint_index(j) for j in sub.joint_names]
    out = [i for i in range(hand.n) if i not in idx]
    pm = pin.buildModelFromXML(HAND_URDF)  # the reference: built here, not by alpes_dyn
    pm.gravity.linear = np.array([0.0, 0.0, -9.81])
    pd = pm.createData()
    order = [pm.getJointId(j) - 1 for j in hand.joint_names]
    assert order == list(range(hand.n))  # Pinocchio's order is the model's
    arm = np.array([hand.spec.armature.get(j, 0.0) for j in hand.joint_names])
    R = hand.transmission.S.T @ np.diag(hand.transmission.rotor_inertia) @ hand.transmission.S
    k = np.array([hand.spec.stiffness.get(j, 0.0) for j in hand.joint_names])
    rest = np.array([hand.spec.rest_angle.get(j, 0.0) for j in hand.joint_names])
    Fv = np.array([hand.spec.viscous.get(j, 0.0) for j in hand.joint_names])
    rng = np.random.default_rng(7)
    for q, v, tau in _random_states(hand, rng):
        A = pin.crba(pm, pd, q).copy()
        A = np.triu(A) + np.triu(A, 1).T + np.diag(arm) + R
        assert np.max(np.abs(A[np.ix_(idx, out)])) == 0.0  # the branches do not share inertia
        ix = np.ix_(idx, idx)
        qs, vs = q[idx], v[idx]
        np.testing.assert_allclose(sub.inertia_matrix(qs), A[ix], rtol=0, atol=1e-12)
        bias = pin.rnea(pm, pd, q, v, np.zeros(hand.n))  # C qd + gravity
        grav = pin.computeGeneralizedGravity(pm, pd, q)
        np.testing.assert_allclose(sub.coriolis_matrix(qs, vs) @ vs + sub.gravity_torque(qs) - sub.spring_torque(qs),
                                   bias[idx], rtol=0, atol=1e-12)
        np.testing.assert_allclose(sub.gravity_torque(qs) - sub.spring_torque(qs), grav[idx], rtol=0, atol=1e-12)
        np.testing.assert_allclose(sub.spring_torque(qs), (k * (q - rest))[idx], rtol=0, atol=1e-15)
        # forward dynamics without Coulomb's sign (the smooth law at v far above v_s is a tanh, not a sign): the
        # reference's own solve of A qdd = tau - bias - springs - viscous - Coulomb
        Fs = np.array([hand.spec.coulomb.get(j, 0.0) for j in hand.joint_names]) * np.sign(v)
        qdd = np.linalg.solve(A, tau - bias - k * (q - rest) - Fv * v - Fs)
        np.testing.assert_allclose(sub.forward_dynamics(qs, vs, tau[idx]), qdd[idx], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(sub.forward_dynamics(qs, vs, tau[idx]), hand.forward_dynamics(q, v, tau)[idx],
                                   rtol=0, atol=1e-12)


def test_allegro_finger_sub_model_equals_the_full_hand():
    urdf, spec = ad.example_robot_urdf("allegro_hand", "allegro_right_hand"), example_spec_path("allegro_hand")
    full = ad.Model.from_urdf_file(urdf, spec)
    sub = full.subtree("index")
    assert sub.joint_names == ("joint_0.0", "joint_1.0", "joint_2.0", "joint_3.0")
    assert sub.motor_names == ("index", "index_abduction") and sub.tips == ("link_3.0_tip",)
    idx = [full.joint_index(j) for j in sub.joint_names]
    pm = pin.buildModelFromXML(full.urdf)
    pm.gravity.linear = full.gravity
    pd = pm.createData()
    ids = [pm.getJointId(j) - 1 for j in sub.joint_names]
    rng = np.random.default_rng(3)
    for q, v, tau in _random_states(full, rng, 3):
        A = pin.crba(pm, pd, q).copy()
        A = np.triu(A) + np.triu(A, 1).T
        R = sub.rotor_matrix + np.diag(sub.extras.armature)
        np.testing.assert_allclose(sub.inertia_matrix(q[idx]) - R, A[np.ix_(ids, ids)], rtol=0, atol=1e-12)
        bias = pin.rnea(pm, pd, q, v, np.zeros(full.n))
        qs, vs = q[idx], v[idx]
        np.testing.assert_allclose(sub.coriolis_matrix(qs, vs) @ vs + sub.gravity_torque(qs) - sub.spring_torque(qs),
                                   bias[ids], rtol=0, atol=1e-12)
        np.testing.assert_allclose(sub.forward_dynamics(qs, vs, tau[idx]), full.forward_dynamics(q, v, tau)[idx],
                                   rtol=1e-12, atol=1e-12)


def test_what_would_couple_two_branches_is_refused():
    coupled = ad.Model(HAND_URDF, TransmissionSpec.from_toml(hand_spec(coupling=True)))
    with pytest.raises(ModelError) as e:
        coupled.subtree("flexor_a")
    assert str(e.value) == ("motors flexor_a: motor 'across' drives joint 'mcp_a' of their branches and joint "
                            "'mcp_b' of another branch; a sub-model would cut its tendon (name 'across' too to keep "
                            "both branches)")
    assert coupled.subtree(["flexor_a", "across"]).joint_names == coupled.joint_names
    # what identify --chain and estimate --chain take instead: the branches closed under what couples them
    assert closed_motors(coupled, "flexor_a") == coupled.motor_names
    hand = ad.Model(HAND_URDF, TransmissionSpec.from_toml(hand_spec()))
    assert closed_motors(hand, "flexor_a") == ("flexor_a", "distal_a")
    mimic = HAND_URDF.replace('<joint name="pip_b" type="revolute">',
                              '<joint name="pip_b" type="revolute"><mimic joint="pip_a" multiplier="0.5"/>')
    m = ad.Model(mimic, TransmissionSpec.from_toml(hand_spec().replace("\npip_b = 0.03", "")
                                                   .replace("pip_b = 4e-4\n", "").replace("pip_b = 1e-4\n", "")
                                                   .replace("mcp_b = 2.0, pip_b = 1.5", "mcp_b = 2.0")))
    with pytest.raises(ModelError, match="mimic joint 'pip_b' follows 'pip_a', and joint 'pip_a' is in their "
                                         "branches, 'pip_b' in another"):
        m.subtree("flexor_a")
    with pytest.raises(ModelError, match="mimic joint 'pip_b' follows 'pip_a', and joint 'pip_b'"):
        m.subtree("flexor_b")
    assert closed_motors(m, "flexor_b") == m.motor_names


def test_read_recording_ignores_the_other_branches_columns(hand, tmp_path):
    from alpes_dyn.estimation.experiments.recording import Recording, read_recording, write_recording

    t = np.arange(200) * 1e-3
    rng = np.random.default_rng(1)
    q = 0.5 + 0.3 * np.sin(np.outer(t, [3.0, 4.0, 5.0, 6.0]))
    rec = Recording(t=t, encoder=np.round(q @ hand.transmission.S.T * 4096 / (2 * np.pi)),
                    torque=rng.uniform(0.01, 0.02, (200, 3)), motor_names=hand.motor_names,
                    joint_names=hand.joint_names, true_q=q)
    write_recording(rec, tmp_path / "r.csv")
    sub = hand.subtree("flexor_a")
    with pytest.raises(RecordingError, match="unknown column 'encoder_flexor_b'"):
        read_recording(tmp_path / "r.csv", sub)
    got = read_recording(tmp_path / "r.csv", sub, ignore_others_of=hand)
    assert got.motor_names == ("flexor_a", "distal_a") and got.joint_names == ("mcp_a", "pip_a")
    np.testing.assert_array_equal(got.encoder, rec.encoder[:, [0, 2]])
    np.testing.assert_array_equal(got.true_q, q[:, :2])
    with pytest.raises(RecordingError, match="ignore_others_of: expected an alpes_dyn Model"):
        read_recording(tmp_path / "r.csv", sub, ignore_others_of="hand")


TRUE_K = (0.05, 0.031, 0.045, 0.033)  # branch a's springs +11 % and -11 % off the spec's; b's too


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("subtree")
    (d / "hand.urdf").write_text(HAND_URDF)
    (d / "hand.toml").write_text(hand_spec())
    (d / "true.toml").write_text(hand_spec(TRUE_K))
    assert main(["experiment", "--model", str(d / "hand.urdf"), "--spec", str(d / "hand.toml"), "--true-spec",
                 str(d / "true.toml"), "--duration", "3", "-o", str(d / "rec.csv")]) == 0
    return d


def test_identify_chain_fits_on_the_sub_model_and_writes_the_whole_spec(files, capsys):
    """``identify --chain flexor_a`` on the sub-model, on a recording of the whole hand whose other finger's springs
    are off the spec's too: branch a's springs within 0.2 % of the truth, the whole spec written back with branch
    a's values replaced and b's as they were, which every command reads back. (The whole robot's chain fit, the
    baseline, takes minutes to compile and fit: ``benchmarks/allegro_identify.py`` compares the two.)"""
    capsys.readouterr()
    urdf, out = str(files / "hand.urdf"), files / "ident.toml"
    rc = main(["identify", "--model", urdf, "--spec", str(files / "hand.toml"), "--data", str(files / "rec.csv"),
               "--chain", "flexor_a", "--parameters", "K,F_v", "-o", str(out), "--json"])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0 and obj["trustworthy"] and obj["model"] == "two_fingers[flexor_a,distal_a]"
    names = list(obj["parameters"])
    assert names == ["K_mcp_a", "K_pip_a", "F_v_mcp_a", "F_v_pip_a"]
    got = np.array([obj["parameters"][n]["value"] for n in names])
    assert np.max(np.abs(got[:2] / TRUE_K[:2] - 1)) < 0.002, got  # measured: 0.004 % and 0.013 %
    assert np.max(np.abs(got[2:] / 1e-4 - 1)) < 0.01, got
    spec, base = load_spec(out), load_spec(files / "hand.toml")
    assert [m.name for m in spec.motors] == [m.name for m in base.motors]
    assert spec.stiffness["mcp_a"] == pytest.approx(got[0], rel=1e-12)
    assert spec.stiffness["mcp_b"] == base.stiffness["mcp_b"] and spec.viscous["pip_b"] == base.viscous["pip_b"]
    assert set(spec.identified["stiffness"]) == {"mcp_a", "pip_a"}
    assert main(["observability", "--model", urdf, "--spec", str(out), "--input", "motor", "--output", "encoder",
                 "--points", "2"]) == 0
    capsys.readouterr()


def test_estimate_chain_observes_the_sub_model(files, capsys):
    capsys.readouterr()
    rc = main(["estimate", "--data", str(files / "rec.csv"), "--model", str(files / "hand.urdf"), "--spec",
               str(files / "true.toml"), "--chain", "flexor_b", "--json"])
    obj = json.loads(capsys.readouterr().out)
    assert rc == 0 and obj["joints"] == ["mcp_b", "pip_b"] and obj["motors"] == ["flexor_b"] and obj["chain"] == "flexor_b"
    assert max(obj["rmse"]) < math.radians(0.5), obj["rmse"]
    rc = main(["estimate", "--data", str(files / "rec.csv"), "--model", str(files / "hand.urdf"), "--spec",
               str(files / "hand.toml"), "--chain", "thumb"])
    assert rc == 2 and "--chain: unknown motor 'thumb' of the URDF --model" in capsys.readouterr().err
