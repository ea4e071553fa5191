"""Any tendon-driven robot, end to end (issue 17): a two-joint planar tendon finger of the test's own (URDF + spec),
its identification experiment simulated on a perturbed robot (``experiment --true-spec``), the springs and
friction identified into a copy of its spec (``identify -o``), every command taking that spec back, and the
observer on the recording (``estimate --data``); the Allegro hand's experiment and observer on a short run."""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.errors import ModelError
from alpes_dyn.model.spec import TransmissionSpec, example_spec_path, load_spec

FINGER_URDF = """<?xml version="1.0"?>
<robot name="tendon_finger">
  <link name="palm"/>
  <link name="proximal">
    <inertial><origin xyz="0.022 0 0"/><mass value="0.028"/>
      <inertia ixx="9e-07" ixy="0" ixz="0" iyy="5e-06" iyz="0" izz="5e-06"/></inertial>
  </link>
  <joint name="mcp" type="revolute">
    <parent link="palm"/><child link="proximal"/><origin xyz="0 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0.0" upper="1.5" effort="1" velocity="20"/>
  </joint>
  <link name="distal">
    <inertial><origin xyz="0.014 0 0"/><mass value="0.018"/>
      <inertia ixx="6e-07" ixy="0" ixz="0" iyy="1.4e-06" iyz="0" izz="1.4e-06"/></inertial>
  </link>
  <joint name="pip" type="revolute">
    <parent link="proximal"/><child link="distal"/><origin xyz="0.045 0 0"/><axis xyz="0 -1 0"/>
    <limit lower="0.0" upper="1.5" effort="1" velocity="20"/>
  </joint>
  <link name="fingertip"/>
  <joint name="tip_joint" type="fixed"><parent link="distal"/><child link="fingertip"/><origin xyz="0.028 0 0"/></joint>
</robot>
"""


def finger_spec(K=(0.045, 0.035), Fs=(5e-4, 4e-4), Fv=(1e-4, 1e-4), motors=None) -> str:
    """The finger's spec: one tendon over both joints (ratios 2.0, 1.5), springs, Coulomb and viscous friction."""
    motors = motors or '[[motor]]\nname = "flexor"\njoints = { mcp = 2.0, pip = 1.5 }\n'
    return (f'name = "tendon_finger"\nencoder_counts = 4096\ntips = ["fingertip"]\n\n{motors}\n'
            f"[stiffness]\nmcp = {K[0]!r}\npip = {K[1]!r}\n\n[coulomb]\nmcp = {Fs[0]!r}\npip = {Fs[1]!r}\n\n"
            f"[viscous]\nmcp = {Fv[0]!r}\npip = {Fv[1]!r}\n")


TRUE_K = (0.05, 0.031)  # the true robot's springs: +11 % and -11 % off the spec's


@pytest.fixture(scope="module")
def robot(tmp_path_factory):
    d = tmp_path_factory.mktemp("anyrobot")
    (d / "finger.urdf").write_text(FINGER_URDF)
    (d / "finger.toml").write_text(finger_spec())
    (d / "true.toml").write_text(finger_spec(TRUE_K, (5.5e-4, 3.6e-4), (1.1e-4, 0.9e-4)))
    return d


def run(capsys, *argv: str) -> tuple[int, dict]:
    rc = main([*argv, "--json"])
    out = capsys.readouterr().out
    return rc, (json.loads(out) if out.strip() else {})


@pytest.fixture(scope="module")
def recording(robot):
    """``experiment --true-spec``: the recording of the perturbed finger (made once; --json read by the test)."""
    rc = main(["experiment", "--model", str(robot / "finger.urdf"), "--spec", str(robot / "finger.toml"),
               "--true-spec", str(robot / "true.toml"), "-o", str(robot / "rec.csv")])
    assert rc == 0
    return robot / "rec.csv"


def test_experiment_writes_a_recording_the_model_reads(robot, recording):
    from alpes_dyn.estimation.experiments.recording import read_recording

    model = ad.Model.from_urdf_file(robot / "finger.urdf", robot / "finger.toml")
    rec = read_recording(recording, model)
    assert rec.n_samples == 4001 and rec.motor_names == ("flexor",) and rec.joint_names == ("mcp", "pip")
    q = rec.true_q
    assert np.all(q >= model.lower) and np.all(q <= model.upper)
    assert np.ptp(q[:, 0]) > math.radians(20)  # the multisine swings the finger across its range
    assert rec.torque.min() > 0  # a tendon pulls only: the multisine stays above zero


def test_experiment_identify_estimate_end_to_end(robot, recording, capsys):
    """The goal figure: the springs within 1 % of the true robot's, the observer on the identified spec < 0.5 deg."""
    urdf, ident = str(robot / "finger.urdf"), robot / "ident.toml"
    rc, obj = run(capsys, "identify", "--model", urdf, "--spec", str(robot / "finger.toml"), "--data", str(recording),
                  "--parameters", "K,friction", "-o", str(ident))
    assert rc == 0 and obj["trustworthy"] and obj["output"] == str(ident)
    K = [obj["parameters"][f"K_{j}"]["value"] for j in ("mcp", "pip")]
    assert np.max(np.abs(np.array(K) / TRUE_K - 1)) < 0.01, K
    spec = load_spec(ident)  # the identified spec: the values, each with its std, and the fit's record
    assert spec.stiffness["mcp"] == pytest.approx(K[0], rel=1e-12)
    assert spec.identified["record"]["trustworthy"] is True
    assert set(spec.identified["stiffness"]) == {"mcp", "pip"} and set(spec.identified["viscous"]) == {"mcp", "pip"}
    raw = tomllib.loads(ident.read_text())
    assert raw["identified"]["source"] == "identified"
    assert TransmissionSpec.from_toml(spec.to_toml()) == spec
    rc, est = run(capsys, "estimate", "--data", str(recording), "--model", urdf, "--spec", str(ident))
    assert rc == 0 and max(est["rmse_deg"]) < 0.5, est
    # every command takes the identified spec back
    for argv in (["dynamics", "--model", urdf], ["linearize", "--model", urdf, "--input", "motor", "--output", "encoder"],
                 ["observability", "--model", urdf, "--input", "motor", "--output", "encoder", "--points", "2"],
                 ["identifiability", "--model", urdf, "--parameters", "K", "--design", "none", "--points", "2"]):
        assert main([*argv, "--spec", str(ident)]) == 0, argv
        capsys.readouterr()
    assert main(["mjcf", "--model", urdf, "--spec", str(ident), "-o", str(robot / "ident.xml")]) == 0


def test_estimate_friction_free_and_the_nominal_spec(robot, recording, capsys):
    urdf = str(robot / "finger.urdf")
    rc, nominal = run(capsys, "estimate", "--data", str(recording), "--model", urdf, "--spec", str(robot / "true.toml"))
    assert rc == 0
    rc, free = run(capsys, "estimate", "--data", str(recording), "--model", urdf, "--spec", str(robot / "true.toml"),
                   "--friction-free")
    assert rc == 0 and free["rmse"] != nominal["rmse"]


def test_identified_urdf_is_the_fits_parametrisation(robot):
    """identified_urdf writes the fitted mass on the joint's child link with its inertia scaled (CoM kept): the
    URDF + spec read back by Pinocchio give the fit's own CasADi dynamics (ParametricDynamics at the fitted theta:
    the link's spatial inertia times m / m0) at random states, to 1e-12."""
    import types

    import casadi as cs

    from alpes_dyn.estimation.identification.identified_spec import identified_urdf
    from alpes_dyn.symbolic.parametric import ParametricDynamics

    model = ad.Model.from_urdf_file(robot / "finger.urdf", robot / "finger.toml")
    theta = np.array([0.021, 0.0333])  # m_pip -> 0.021 kg (was 0.018), m_mcp -> 0.0333 (was 0.028)
    res = types.SimpleNamespace(model=model, names=("m_pip", "m_mcp"), values=theta, std=np.array([1e-4, 2e-4]),
                                recording_path="rec.csv", trustworthy=True)
    text = identified_urdf(res, FINGER_URDF)
    assert "distal: 0.021 kg (was 0.018, standard error 0.0001)" in text
    back = ad.Model(text, model.spec)
    P = ParametricDynamics(model, list(res.names))
    q, v, th = cs.SX.sym("q", 2), cs.SX.sym("v", 2), cs.SX.sym("th", 2)
    f = cs.Function("f", [q, v, th], [P.inertia_matrix(q, th), P.bias_torque(q, v, th, cs.DM(model.gravity))])
    rng = np.random.default_rng(3)
    for _ in range(3):
        qq, vv = back.random_state(rng)
        M, b = (np.array(x) for x in f(qq, vv, theta))
        np.testing.assert_allclose(back.inertia_matrix(qq), M, rtol=1e-12, atol=1e-15)
        ref = back.coriolis_matrix(qq, vv) @ vv + back.gravity_torque(qq) - back.extras.spring_torque(qq)
        np.testing.assert_allclose(ref, b.ravel(), rtol=1e-10, atol=1e-14)
    untrusted = types.SimpleNamespace(**{**vars(res), "trustworthy": False, "status": lambda: "lost basin -- x",
                                         "recording_path": "a--b.csv"})
    marked = identified_urdf(untrusted, FINGER_URDF)
    assert "<!-- NOT TRUSTWORTHY (written with identify's force option): lost basin - - x -->" in marked
    assert "<!-- identified by alpes_dyn from a- -b.csv" in marked  # "--" ends an XML comment
    assert ad.Model(marked, model.spec).inertia_matrix(np.zeros(2)) == pytest.approx(back.inertia_matrix(np.zeros(2)))
    with pytest.raises(ModelError, match="identified urdf: m_pip = -0.1 kg is not a positive mass"):
        identified_urdf(types.SimpleNamespace(**{**vars(res), "values": np.array([-0.1, 0.03])}), FINGER_URDF)


def test_identify_with_masses_writes_the_urdf_beside_the_spec(robot, recording, capsys):
    """``identify -o m.toml`` with masses in the fit (K, m, friction: one fit, no effects tried) writes m.urdf beside it
    (the masses, inertias scaled) and m.toml; the pair is the identified robot every command loads. With ``--mjcf``
    (the finger as an MJCF file, what ``import`` reads back into this URDF + spec) also m.xml: that file with the
    fitted values, which MuJoCo compiles to them and which imports as the identified robot (to 1e-12)."""
    import xml.etree.ElementTree as ET

    import mujoco

    urdf, out, src = str(robot / "finger.urdf"), robot / "m.toml", robot / "finger_mj.xml"
    assert main(["mjcf", "--model", urdf, "--spec", str(robot / "finger.toml"), "-o", str(src)]) == 0
    before = src.read_bytes()
    rc, obj = run(capsys, "identify", "--model", urdf, "--spec", str(robot / "finger.toml"), "--data",
                  str(recording), "--parameters", "K,m,friction", "-o", str(out), "--mjcf", str(src))
    assert rc == 0 and obj["trustworthy"] and obj["urdf_output"] == str(robot / "m.urdf")
    assert obj["mjcf_output"] == str(robot / "m.xml") and obj["mjcf_omitted"] == [] and src.read_bytes() == before
    mj, p = mujoco.MjModel.from_xml_path(str(robot / "m.xml")), obj["parameters"]
    assert mj.body_mass[-2:].tolist() == [p["m_mcp"]["value"], p["m_pip"]["value"]]  # (after the palm)
    assert mj.jnt_stiffness.tolist() == [p["K_mcp"]["value"], p["K_pip"]["value"]]
    assert mj.dof_frictionloss.tolist() == [p["F_s_mcp"]["value"], p["F_s_pip"]["value"]]
    assert mj.dof_damping.tolist() == [p["F_v_mcp"]["value"], p["F_v_pip"]["value"]]
    back, ident = ad.Model.from_mjcf(robot / "m.xml"), ad.Model.from_urdf_file(robot / "m.urdf", out)
    for q in (np.array([0.3, 0.4]), np.array([1.2, 0.1])):
        assert back.inertia_matrix(q) == pytest.approx(ident.inertia_matrix(q), rel=1e-12, abs=0)
        assert back.gravity_torque(q) == pytest.approx(ident.gravity_torque(q), rel=1e-12, abs=0)
        assert back.extras.spring_torque(q) == pytest.approx(ident.extras.spring_torque(q), rel=1e-12, abs=0)
    links = {k.get("name"): k for k in ET.parse(robot / "m.urdf").getroot().iter("link")}
    for j, link, m0, izz in (("mcp", "proximal", 0.028, 5e-6), ("pip", "distal", 0.018, 1.4e-6)):
        m = obj["parameters"][f"m_{j}"]["value"]
        assert float(links[link].find("inertial/mass").get("value")) == m
        assert float(links[link].find("inertial/inertia").get("izz")) == pytest.approx(izz * m / m0, rel=1e-15)
        assert m == pytest.approx(m0, rel=0.05)  # the true robot has the URDF's masses
    spec = load_spec(out)
    assert spec.stiffness["mcp"] == obj["parameters"]["K_mcp"]["value"]
    for argv in (["dynamics"], ["observability", "--input", "motor", "--output", "encoder", "--points", "2"]):
        assert main([argv[0], "--model", str(robot / "m.urdf"), "--spec", str(out), *argv[1:]]) == 0, argv
        capsys.readouterr()
    assert main(["mjcf", "--model", str(robot / "m.urdf"), "--spec", str(out), "-o", str(robot / "m_ex.xml")]) == 0
    assert ad.Model.from_mjcf(robot / "m_ex.xml").inertia_matrix(np.array([0.3, 0.4])) == pytest.approx(
        ad.Model.from_urdf_file(robot / "m.urdf", out).inertia_matrix(np.array([0.3, 0.4])), rel=1e-12)


def test_identify_mjcf_not_trustworthy_writes_nothing_unless_forced(robot, recording, capsys, monkeypatch, tmp_path):
    """``identify --mjcf`` on a fit that is not trustworthy (made up here: no fit run): exit 3, no file (neither the
    spec, the URDF nor the MJCF); with --force the MJCF is written, marked NOT TRUSTWORTHY as the spec is."""
    import alpes_dyn.estimation.identification.identification as ident
    from alpes_dyn.estimation.identification.fit_result import IdentificationResult

    src = tmp_path / "finger.xml"
    assert main(["mjcf", "--model", str(robot / "finger.urdf"), "--spec", str(robot / "finger.toml"), "-o",
                 str(src)]) == 0

    def fake(model, data, names, **kw):
        n = len(names)
        return IdentificationResult(tuple(names), np.array([0.05, 0.02]), np.full(n, 1e-4), np.array([0.045, 0.018]),
                                    ("N m/rad", "kg"), np.eye(n), 3.0, 50, False, 0.0, 0.0, np.zeros((1, 4)),
                                    np.zeros(1), model, reason="iteration limit")

    monkeypatch.setattr(ident, "identify", fake)
    out = tmp_path / "u.toml"
    argv = ["identify", "--model", str(robot / "finger.urdf"), "--spec", str(robot / "finger.toml"), "--data",
            str(recording), "--parameters", "K_mcp,m_pip", "-o", str(out), "--mjcf", str(src)]
    assert main(argv) == 3
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not trustworthy, nothing written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["finger.xml"]
    assert main([*argv, "--force"]) == 0
    assert "UntrustedFitWarning" in capsys.readouterr().err
    text = (tmp_path / "u.xml").read_text()
    assert "<!-- NOT TRUSTWORTHY (written with identify's force option): the fit did not converge" in text
    assert 'stiffness="0.05"' in text and 'mass="0.02"' in text and (tmp_path / "u.urdf").exists() and out.exists()


def test_chain_motor_keeps_that_motors_joints(robot):
    from alpes_dyn.cli.estimation_cmds import _motor_chain
    from alpes_dyn.symbolic.parametric import select_parameters

    two = '[[motor]]\nname = "flexor"\njoints = { mcp = 2.0, pip = 1.5 }\n\n[[motor]]\nname = "distal"\njoints = { pip = 1.0 }\n'
    (robot / "two.toml").write_text(finger_spec(motors=two))
    m = ad.Model.from_urdf_file(robot / "finger.urdf", robot / "two.toml")
    chosen = select_parameters(m, "K,friction,tendon_compliance,tilt_y")
    names = [p.name for p in _motor_chain(m, chosen, "distal")]
    assert names == ["K_pip", "F_s_pip", "F_v_pip", "tendon_compliance_distal", "tilt_y"]
    assert len(_motor_chain(m, chosen, "flexor")) == len(chosen) - 1  # all but the distal motor's compliance


def test_identifiability_of_the_robot(robot, capsys):
    rc, obj = run(capsys, "identifiability", "--model", str(robot / "finger.urdf"), "--spec", str(robot / "finger.toml"),
                  "--parameters", "K,friction", "--points", "2", "--duration", "1")
    assert rc == 0 and obj["design"] == "documented"
    rel = {n: p["std"] / p["value"] for n, p in obj["practical"]["parameters"].items()}
    assert set(rel) == {"K_mcp", "K_pip", "F_s_mcp", "F_s_pip", "F_v_mcp", "F_v_pip"}
    assert max(rel[k] for k in ("K_mcp", "K_pip")) < 0.01


def test_identified_section_validated_and_round_trips(robot):
    base = load_spec(robot / "finger.toml")
    spec = dataclasses.replace(base, identified={"record": {"recording": 'a"b\n', "converged": True},
                                                 "stiffness": {"mcp": 1e-5, "pip": math.inf}})
    assert TransmissionSpec.from_toml(spec.to_toml()) == spec
    assert spec != base
    text = base.to_toml()
    for extra, needle in (("[identified]\nfoo = 1\n", "identified.foo: unknown key"),
                          ("[identified.stiffness]\nxx = 1e-5\n", "identified.stiffness.xx: the spec has no stiffness"),
                          ("[identified.viscous]\nmcp = -1.0\n", "identified.viscous.mcp: expected a standard error"),
                          ("[identified.viscous]\nmcp = nan\n", "identified.viscous.mcp: expected a standard error"),
                          ("[identified]\nsource = \"cad\"\n", 'identified.source: expected "identified"'),
                          ("[identified]\nconverged = 1\n", "identified.converged: expected true or false"),
                          ("[identified.rotor_inertia]\nwrist = 1e-9\n", "identified.rotor_inertia.wrist: unknown motor"),
                          ("[identified]\nstiffness = 3\n", "identified.stiffness: expected a table joint name")):
        with pytest.raises(ModelError, match=None) as e:
            TransmissionSpec.from_toml(text + extra, "s.toml")
        assert needle in str(e.value), str(e.value)


def test_allegro_experiment_and_observer(tmp_path, capsys):
    """The shipped Allegro example: its 8 motors excited at once for 0.3 s (the ab/adduction's direct motors
    through zero), every joint inside its range, and the EKF on the recording (``estimate``: its NEES and NIS
    predictions in the virtual machine, the 16 joints' step over AHEAD_COMPILE_MAX; each sample costs, hence the
    short run: 0.3 s measured 0.27 degrees of worst RMSE)."""
    # (not its fit: the 16-joint sensitivity code takes minutes to compile)
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment

    urdf, spec = ad.example_robot_urdf("allegro_hand", "allegro_right_hand"), example_spec_path()
    m = ad.Model.from_urdf_file(urdf, spec)
    rec = model_experiment(m, design=ExperimentDesign(duration=0.3), path=tmp_path / "a.csv")
    assert np.all(rec.true_q >= m.lower) and np.all(rec.true_q <= m.upper)
    S = m.transmission.S
    mid = 0.5 * (m.lower + m.upper)
    centred = [k for k in range(S.shape[0]) if np.count_nonzero(S[k]) == 1 and abs(mid[np.flatnonzero(S[k])[0]]) < 1e-9]
    assert len(centred) == 3  # the ab/adduction joints, centred on zero: their direct motors swing both ways
    assert all(rec.torque[:, k].min() < 0 < rec.torque[:, k].max() for k in centred)
    rc, obj = run(capsys, "estimate", "--data", str(tmp_path / "a.csv"), "--model", str(urdf), "--spec", str(spec))
    assert rc == 0 and max(obj["rmse"]) < math.radians(0.5)


def test_experiment_true_model_and_amplitude(robot, capsys):
    """``experiment --true-model TRUE.urdf`` (a URDF robot whose links are 30 % heavier than the --model's) simulates
    that robot, its bias trimmed on it: the recording's true joints are those of the API's model_experiment(nominal,
    truth) for the same seed, not the nominal robot's (its rest differs by 2.65 degrees, measured). And
    ``--amplitude 1`` swings the finger twice as wide as the default 0.5 (a sprung motor's multisine: amplitude ratio
    2, measured swing ratio 1.98 on this finger's first joint)."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, model_experiment
    from alpes_dyn.estimation.experiments.recording import read_recording

    heavy = FINGER_URDF.replace('<mass value="0.028"/>', '<mass value="0.0364"/>').replace(
        '<mass value="0.018"/>', '<mass value="0.0234"/>')
    (robot / "heavy.urdf").write_text(heavy)
    base = ["--model", str(robot / "finger.urdf"), "--spec", str(robot / "finger.toml"), "--duration", "1"]
    swing = {}
    for amp in ("0.5", "1"):
        rc, obj = run(capsys, "experiment", *base, "--true-model", str(robot / "heavy.urdf"), "--amplitude", amp,
                      "-o", str(robot / f"heavy{amp}.csv"))
        assert rc == 0 and obj["true_model"] == str(robot / "heavy.urdf") and obj["amplitude"] == float(amp)
        nominal = ad.Model.from_urdf_file(robot / "finger.urdf", robot / "finger.toml")
        rec = read_recording(robot / f"heavy{amp}.csv", nominal)
        swing[amp] = np.ptp(rec.true_q[:, 0])
    truth = ad.Model.from_urdf_file(robot / "heavy.urdf", robot / "finger.toml")
    api = model_experiment(nominal, truth, ExperimentDesign(duration=1.0, amplitude_fraction=1.0), seed=0)
    np.testing.assert_allclose(rec.true_q, api.true_q, rtol=0, atol=1e-12)
    own = model_experiment(nominal, None, ExperimentDesign(duration=1.0, amplitude_fraction=1.0), seed=0)
    assert np.degrees(np.abs(own.true_q[0] - api.true_q[0]).max()) > 1.0
    assert 1.8 < swing["1"] / swing["0.5"] < 2.2, swing
    # the command without the sensors (model_experiment_torque): our RK4 from its x0 under it gives the recording's
    # true joints, and the recording's torque is it plus the sensor's white noise (5e-4 N m)
    from alpes_dyn.estimation.experiments.experiment import model_experiment_torque
    from alpes_dyn.simulation.integrate import simulate, stable_substeps

    design = ExperimentDesign(duration=1.0, amplitude_fraction=1.0)
    t, u, x0 = model_experiment_torque(nominal, truth, design)
    np.testing.assert_allclose(t, api.t, rtol=0, atol=1e-15)
    k = max(design.substeps, stable_substeps(truth, design.dt))
    sim = simulate(truth, x0, np.repeat(u[:-1], k, axis=0), 1.0, design.dt / k, input="motor")
    np.testing.assert_allclose(sim.x[::k, : truth.n], api.true_q, rtol=0, atol=1e-9)
    noise = api.torque - u
    assert abs(noise.std() / design.torque_noise - 1) < 0.1 and abs(noise.mean()) < 0.1 * design.torque_noise
