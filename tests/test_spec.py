"""Transmission spec for any URDF (alpes_dyn.model.spec): the Allegro hand of example-robot-data with a tendon spec.

Reference: raw Pinocchio on the URDF *file* (its own parser entry point), with the spec's numbers read by
tomllib straight from the shipped TOML and placed by Pinocchio's joint ids, the motor torques applied as
Gamma = S^T tau_m: every quantity of the alpes_dyn model must equal it to 1e-12.
"""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.model.spec import Motor, TransmissionSpec, example_spec_path, load_spec
from alpes_dyn.symbolic.statespace import StateSpace

URDF = ad.example_robot_urdf("allegro_hand", "allegro_right_hand")
SPEC = example_spec_path("allegro_hand")
RAW = tomllib.loads(SPEC.read_text())


def raw_pinocchio():
    """Pinocchio model + S, k, F_v, armature placed by Pinocchio's own joint ids (independent of alpes_dyn)."""
    pm = pin.buildModelFromUrdf(str(URDF))
    n = pm.nv
    col = lambda j: pm.joints[pm.getJointId(j)].idx_v  # noqa: E731
    S = np.zeros((len(RAW["motor"]), n))
    for k, m in enumerate(RAW["motor"]):
        for j, r in m["joints"].items():
            S[k, col(j)] = r
    per = {}
    for t in ("stiffness", "viscous", "armature", "rest_angle"):
        a = np.zeros(n)
        for j, x in RAW.get(t, {}).items():
            a[col(j)] = x
        per[t] = a
    pm.armature = per["armature"]
    return pm, pm.createData(), S, per["stiffness"], per["viscous"], per["rest_angle"]


@pytest.fixture(scope="module")
def allegro():
    return ad.Model.from_urdf_file(URDF, SPEC)


def test_allegro_every_quantity_equals_raw_pinocchio(allegro, rng):
    pm, pd, S, k, fv, rest = raw_pinocchio()
    m = allegro
    assert m.n == 16 and m.joint_names == tuple(pm.names[1:])
    assert m.motor_names == tuple(mm["name"] for mm in RAW["motor"])
    assert m.tip_names == tuple(RAW["tips"])
    assert np.array_equal(m.transmission.S, S) and np.array_equal(m.transmission.actuation_matrix, S.T)
    ss = StateSpace(m, input="motor", output="encoder")
    tol = 1e-12
    for _ in range(10):
        q, v = m.random_state(rng)
        tau_m = rng.normal(scale=0.05, size=8)
        a = rng.normal(size=16)
        tau = S.T @ tau_m
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert np.max(np.abs(m.inertia_matrix(q) - M)) <= tol
        assert np.max(np.abs(m.coriolis_matrix(q, v) - pin.computeCoriolisMatrix(pm, pd, q, v))) <= tol
        G = pin.computeGeneralizedGravity(pm, pd, q) + k * (q - rest)
        assert np.max(np.abs(m.gravity_torque(q) - G)) <= tol
        dG = pin.computeGeneralizedGravityDerivatives(pm, pd, q) + np.diag(k)
        assert np.max(np.abs(m.gravity_jacobian(q) - dG)) <= tol
        qdd = pin.aba(pm, pd, q, v, tau - k * (q - rest) - fv * v)
        assert np.max(np.abs(m.forward_dynamics(q, v, m.transmission.joint_torque(tau_m)) - qdd)) <= tol * max(
            1.0, np.abs(qdd).max())
        xdot = ss.f(np.concatenate([q, v]), tau_m)
        assert np.array_equal(xdot[:16], v) and np.max(np.abs(xdot[16:] - qdd)) <= tol * max(1.0, np.abs(qdd).max())
        assert np.max(np.abs(ss.h(np.concatenate([q, v])) - S @ q)) <= tol
        tau_id = pin.rnea(pm, pd, q, v, a) + k * (q - rest) + fv * v
        assert np.max(np.abs(m.inverse_dynamics(q, v, a) - tau_id)) <= tol
        for tip in m.tip_names:
            J = pin.computeFrameJacobian(pm, pd, q, pm.getFrameId(tip), pin.LOCAL_WORLD_ALIGNED)[:3]
            assert np.max(np.abs(m.fingertip_jacobian(q, tip) - J)) <= tol
            pin.framesForwardKinematics(pm, pd, q)
            assert np.max(np.abs(m.fingertip_position(q, tip) - pd.oMf[pm.getFrameId(tip)].translation)) <= tol
        U = pin.computePotentialEnergy(pm, pd, q) + 0.5 * k @ ((q - rest) * (q - rest))
        assert abs(m.potential_energy(q) - U) <= tol
        assert abs(m.kinetic_energy(q, v) - 0.5 * v @ M @ v) <= tol


def test_allegro_symbolic_f_matches_pinocchio(allegro, rng):
    """The CasADi f (ADAM, an independent rigid-body code) with motor input agrees with raw Pinocchio."""
    pm, pd, S, k, fv, rest = raw_pinocchio()
    ss = StateSpace(allegro, input="motor", output="encoder", smooth=False)
    for _ in range(5):
        q, v = allegro.random_state(rng)
        tau_m = rng.normal(scale=0.05, size=8)
        qdd = pin.aba(pm, pd, q, v, S.T @ tau_m - k * (q - rest) - fv * v)
        f = np.asarray(ss.f_function(np.concatenate([q, v]), tau_m)).ravel()
        assert np.max(np.abs(f[16:] - qdd)) <= 1e-9 * max(1.0, np.abs(qdd).max())


def test_python_object_equals_file_and_round_trips():
    py = TransmissionSpec(
        motors=tuple(Motor(m["name"], m["joints"], m.get("rotor_inertia", 0.0)) for m in RAW["motor"]),
        stiffness=RAW["stiffness"], viscous=RAW["viscous"], armature=RAW["armature"], rest_angle=RAW["rest_angle"],
        encoder_counts=4096, smooth_velocity=0.01, gravity=(0.0, 0.0, -9.81), tips=tuple(RAW["tips"]),
        name="allegro_tendon")
    assert load_spec(SPEC) == py
    assert TransmissionSpec.from_toml(py.to_toml()) == py
    m1, m2 = ad.Model.from_urdf_file(URDF, py), ad.Model(URDF.read_text(), SPEC)
    assert np.array_equal(m1.transmission.S, m2.transmission.S)
    for f in ("stiffness", "armature", "coulomb", "viscous"):
        assert np.array_equal(getattr(m1.extras, f), getattr(m2.extras, f))
    assert m1.copy().motor_names == m1.motor_names and m1.copy().spec == py


def test_alpes_models_go_through_a_spec():
    """Model.alpes builds its spec from the parameter file; the same spec on the generated URDF gives the same model."""
    hand = ad.Model.alpes("hand", friction=True, rotor_inertia=True)
    assert isinstance(hand.spec, TransmissionSpec) and hand.spec.name == "hand"
    again = ad.Model(ad.urdf_string("hand"), TransmissionSpec.from_toml(hand.spec.to_toml()))
    assert np.array_equal(again.transmission.S, hand.transmission.S)
    for f in ("stiffness", "armature", "coulomb", "viscous"):
        assert np.array_equal(getattr(again.extras, f), getattr(hand.extras, f))
    p = tomllib.loads(ad.model.params.default_params_path().read_text())
    ratio = p["finger"]["r"]["value"] / p["transmission"]["r_m"]["value"]
    assert hand.transmission.S[hand.motor_index("ring"), hand.joint_index("ring_j2")] == ratio
    # rotor inertia on the tendons: every motor has the file's J_m, no joint-side armature
    J_m = p["transmission"]["J_m"]["value"]
    assert np.array_equal(hand.transmission.rotor_inertia, np.full(6, J_m)) and not hand.extras.armature.any()
    a = hand.joint_index("thumb_abd")
    assert hand.rotor_matrix[a, a] == p["transmission"]["abduction_ratio"]["value"] ** 2 * J_m
    i, j = hand.joint_index("ring_j1"), hand.joint_index("ring_j3")
    assert hand.rotor_matrix[i, j] == ratio**2 * J_m and hand.rotor_matrix[i, hand.joint_index("index_j1")] == 0


@pytest.mark.parametrize("text,needle", [
    ("colour = 1", "colour: unknown key"),
    ("[[motor]]\nname = 'a'", "motor[0].joints: missing field"),
    ("[[motor]]\nname = 'a'\njoints = {j = 1}\ngear = 2", "motor[0].gear: unknown key"),
    ("[[motor]]\nname = 'a'\njoints = {j = 0}", "motor 'a'.joints.j: a ratio must be non-zero"),
    ("[[motor]]\nname = 'a'\njoints = {j = 'x'}", "motor 'a'.joints.j: expected a number"),
    ("[[motor]]\nname = 'a'\njoints = {j = 1}\nrotor_inertia = -1e-7",
     "motor 'a'.rotor_inertia: expected a number >= 0, got -1e-07"),
    ("[[motor]]\nname = 'a'\njoints = {j = 1}\nrotor_inertia = 'big'", "motor 'a'.rotor_inertia: expected a number"),
    ("[[motor]]\nname = 'a'\njoints = {j = 1}\nrotor_inertia = inf", "motor 'a'.rotor_inertia: expected a finite"),
    ("[[motor]]\nname = 'a'\njoints = {j = 1}\n[[motor]]\nname = 'a'\njoints = {k = 1}", "motor name 'a' appears twice"),
    ("[stiffness]\nj = -1", "stiffness.j: expected a number >= 0, got -1"),
    ("[viscous]\nj = nan", "viscous.j: expected a finite number"),
    ("encoder_counts = 0", "encoder_counts: expected a number > 0, got 0"),
    ("gravity = [0, 1]", "gravity: expected 3 numbers"),
    ("tips = 'a'", "tips: expected a non-empty list of frame names"),
    ("x = [", "invalid TOML"),
])
def test_bad_spec_text(text, needle):
    with pytest.raises(ad.ModelError, match=None) as e:
        TransmissionSpec.from_toml(text, "s.toml")
    assert needle in str(e.value) and "\n" not in str(e.value) and "'s.toml'" in str(e.value)


def test_bad_spec_against_urdf(tmp_path):
    with pytest.raises(ad.ModelError, match=r"motor 'a'.joints: unknown joint 'joint_99' \(URDF joints: joint_0.0"):
        ad.Model.from_urdf_file(URDF, TransmissionSpec(motors=(Motor("a", {"joint_99": 1.0}),)))
    with pytest.raises(ad.ModelError, match=r"armature.knee: unknown joint 'knee'"):
        ad.Model.from_urdf_file(URDF, TransmissionSpec(armature={"knee": 1.0}))
    with pytest.raises(ad.ModelError, match=r"tips: unknown frame 'nail'"):
        ad.Model.from_urdf_file(URDF, TransmissionSpec(tips=("nail",)))
    with pytest.raises(ad.ModelError, match=r"spec file '/nonexistent.toml': cannot be read"):
        ad.Model.from_urdf_file(URDF, "/nonexistent.toml")
    with pytest.raises(ad.ModelError, match=r"extras: given together with a spec"):
        ad.Model(URDF.read_text(), SPEC, extras=ad.JointExtras.zeros(16))
    with pytest.raises(ad.ModelError, match=r"gravity: given both as an argument and in the spec"):
        ad.Model(URDF.read_text(), SPEC, gravity=[0, 0, -1.0])
    with pytest.raises(ad.ModelError, match=r"spec: expected a TransmissionSpec or the path"):
        ad.Model(URDF.read_text(), 3)
    with pytest.raises(ad.ModelError, match=r"motors: expected a sequence of Motor"):
        TransmissionSpec(motors=("index",))


# ----------------------------------------------------------------------------- command line
def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_dynamics_with_spec_and_motor_torques(capsys, allegro):
    tau_m = np.array([0.02, -0.01, 0.0, 0.01, 0.0, 0.003, 0.0, -0.002])
    q = np.linspace(0.0, 0.3, 16)
    code, out, err = run(capsys, "dynamics", "--model", URDF, "--spec", SPEC, "--q=" + ",".join(map(str, q.tolist())),
                         "--tau-m=" + ",".join(map(str, tau_m.tolist())), "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["motors"] == list(allegro.motor_names) and d["joints"] == list(allegro.joint_names)
    assert np.allclose(d["tau"], allegro.transmission.S.T @ tau_m, rtol=0, atol=1e-15)
    assert np.allclose(d["qdd"], allegro.forward_dynamics(q, np.zeros(16), allegro.transmission.S.T @ tau_m),
                       rtol=1e-14, atol=0)
    assert np.allclose(d["q_m"], allegro.transmission.S @ q, rtol=1e-15, atol=0)
    assert d["spring"] == "torsional"


def test_cli_observability_allegro(capsys):
    code, out, err = run(capsys, "observability", "--model", URDF, "--spec", SPEC, "--input", "motor",
                         "--output", "encoder", "--json", "--points", "4")
    assert code == 0, err
    d = json.loads(out)
    assert (d["n_states"], d["n_outputs"], d["rank"], d["observable"]) == (32, 8, 32, True)


@pytest.mark.parametrize("extra,needle", [
    (["--spring", "none"], "--spring: applies to the Alpes models"),
    (["--friction"], "--friction: applies to the Alpes models"),
    (["--rotor-inertia"], "--rotor-inertia: applies to the Alpes models"),
    (["--params", "x.toml"], "--params: applies to the Alpes models"),
    (["--spec", "/nonexistent.toml"], "spec file '/nonexistent.toml': cannot be read"),
    (["--tau-m=1,2"], "--tau-m: model 'allegro_hand_right' has no motors"),
])
def test_cli_urdf_refuses_options_that_do_not_apply(capsys, extra, needle):
    code, out, err = run(capsys, "dynamics", "--model", URDF, *extra)
    assert code == 2 and out == "" and err.count("\n") == 1 and needle in err


@pytest.mark.parametrize("argv,needle", [
    (["dynamics", "--model", "hand", "--spec", str(SPEC)], "--spec: applies to a URDF --model"),
    (["observability", "--model", "finger3", "--spec", str(SPEC)], "--spec: applies to a URDF --model"),
    (["estimate", "--model", "finger3", "--spec", str(SPEC)], "--spec: applies to a URDF --model"),
    (["dynamics", "--model", str(URDF), "--spec", str(SPEC), "--tau-m=1,2"], "--tau-m: model 'allegro_tendon' has 8 motors"),
    (["dynamics", "--model", str(URDF), "--spec", str(SPEC), "--tau-m=1,2,3,4,5,6,7,8", "--tau=" + ",".join(["0"] * 16)],
     "--tau-m: give joint torques --tau or motor torques --tau-m, not both"),
])
def test_cli_spec_errors(capsys, argv, needle):
    code, out, err = run(capsys, *argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and needle in err


def test_driven_joints_are_the_specs_motor_joints(allegro):
    """Transmission.driven: the joints some motor's table names with a non-zero ratio (read from the TOML by tomllib),
    the others passive; on finger_edu the ab/adduction joint has no motor."""
    named = {j for m in RAW["motor"] for j, r in m["joints"].items() if r != 0}
    assert {j for j, d in zip(allegro.joint_names, allegro.transmission.driven) if d} == named
    assert len(named) == 16
    edu_spec = example_spec_path("finger_edu")
    edu = tomllib.loads(edu_spec.read_text())
    edu_model = ad.Model.from_urdf_file(ad.example_robot_urdf("finger_edu"), edu_spec)
    passive = [j for j, d in zip(edu_model.joint_names, edu_model.transmission.driven) if not d]
    assert passive == [j for j in edu_model.joint_names if all(j not in m["joints"] for m in edu["motor"])]
    assert len(passive) == 1
