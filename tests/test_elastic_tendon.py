"""The series-elastic tendon with the rotor as a state (symbolic.elastic_tendon) against independent references:
MuJoCo on the exported MJCF (its tendon spring with a dead band, the rotor hinge: accelerations, the cable's pull and
trajectories under MuJoCo's own RK4), the rigid tendon with the rotor on the joints (J_m S^T S) as the cable
stiffens, the quasi-static compliance C = 1 / k_m at rest, and the numeric against the CasADi right-hand side."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.model.mjcf import _ROTOR_INERTIA, joint_permutation, load_mujoco, mjcf_string
from alpes_dyn.simulation import simulate
from alpes_dyn.symbolic.elastic_tendon import ElasticTendon, SeriesElasticSystem

K_T, C_T = 4e4, 2.0  # N/m, N s/m: the realism benchmark's cable (3.97e4 N/m), lightly damped


@pytest.fixture(scope="module")
def p():
    return ad.load_params()


@pytest.fixture(scope="module")
def finger(p):
    return ad.Model.alpes("finger3")


def _mujoco(dead_band: float = 0.0):
    mujoco = pytest.importorskip("mujoco")
    mj = load_mujoco(mjcf_string("finger3", tendon_stiffness=K_T, tendon_damping=C_T, tendon_dead_band=dead_band,
                                 limits=False, contact=False, timestep=1e-4))
    mj.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    return mujoco, mj, mujoco.MjData(mj)


def _system(finger, p, dead_band: float = 0.0) -> SeriesElasticSystem:
    # MuJoCo's rotor hinge carries a point body of inertia 1e-12 kg m^2 beside its armature J_m (the export's)
    return SeriesElasticSystem(finger, ElasticTendon.from_cable(1, K_T, p.r_m, C_T, dead_band),
                               rotor_inertia=p.J_m + _ROTOR_INERTIA)


@pytest.mark.parametrize("dead_band", [0.0, 1e-4])
def test_accelerations_and_pull_equal_mujoco(finger, p, rng, dead_band):
    """f(x, u) equals MuJoCo's qacc (joints and rotor) on the exported MJCF at random states, taut, slack and in
    the dead band, and the cable's pull T_m equals minus MuJoCo's passive force on the rotor."""
    mujoco, mj, d = _mujoco(dead_band)
    sy = _system(finger, p, dead_band)
    perm = joint_permutation(mj, finger.joint_names)
    rot, rdof = mj.joint("finger_rotor").qposadr[0], mj.joint("finger_rotor").dofadr[0]
    kinds = set()
    for _ in range(16):
        q, v = finger.random_state(rng, speed=1.0)
        e = rng.uniform(-2e-4, 3e-4)  # the cable's stretch, m
        th, w, u = (p.r * q.sum() + e) / p.r_m, rng.uniform(-5, 5), rng.uniform(0, 0.05)
        d.qpos[perm], d.qvel[perm], d.qpos[rot], d.qvel[rot], d.ctrl[0] = q, v, th, w, u
        mujoco.mj_forward(mj, d)
        x = np.r_[q, th, v, w]
        xd = sy.f(x, [u])
        assert np.allclose(xd[4:7], d.qacc[perm], rtol=1e-9, atol=1e-9)
        assert xd[7] == pytest.approx(d.qacc[rdof], rel=1e-9)
        assert sy.tension(x)[0] == pytest.approx(-d.qfrc_passive[rdof], rel=1e-9, abs=1e-15)
        assert sy.encoder(x)[0] == pytest.approx(d.sensor("encoder_finger").data[0], rel=1e-14)
        kinds.add("slack" if e < 0 else "band" if e < dead_band else "taut")
    assert kinds == ({"slack", "band", "taut"} if dead_band else {"slack", "taut"})


def test_trajectory_equals_mujoco_with_slack_phases(finger, p):
    """0.3 s of a multisine torque with a 10 ms release (the cable goes slack): SeriesElasticSystem.simulate (RK4,
    0.1 ms) and MuJoCo's RK4 at 0.1 ms give the same joints and rotor to 1e-10 rad."""
    mujoco, mj, d = _mujoco()
    sy = _system(finger, p)
    perm, rot = joint_permutation(mj, finger.joint_names), mj.joint("finger_rotor").qposadr[0]
    t = 1e-3 * np.arange(300)
    u = 0.02 + 0.004 * np.sin(2 * np.pi * 7 * t) + 0.002 * np.sin(2 * np.pi * 23 * t)
    u[(t > 0.15) & (t < 0.16)] = 0.0
    x0 = sy.equilibrium([u[0]])
    X = sy.simulate(x0, u, 1e-3, 10)
    d.qpos[perm], d.qpos[rot] = x0[:3], x0[3]
    Q = [np.r_[d.qpos[perm], d.qpos[rot]]]
    for uk in u:
        d.ctrl[0] = uk
        mujoco.mj_step(mj, d, nstep=10)
        Q.append(np.r_[d.qpos[perm], d.qpos[rot]])
    assert np.abs(np.array(Q) - X[:, :4]).max() < 1e-10
    stretch = X[:, 3] - sy.S[0] @ X[:, :3].T
    assert np.mean(stretch < 0) > 0.01  # slack phases were crossed
    assert np.ptp(X[:, :3], axis=0).min() > 0.3  # and the finger moved


def test_rigid_limit_is_the_rotor_on_the_joints(finger, p):
    """As the cable stiffens the joints converge, at first order in 1/k_t, to the rigid tendon with the rotor's
    inertia on the joints (Model.alpes(rotor_inertia=True): A + J_m S^T S), simulated by the library's RK4."""
    rigid = ad.Model.alpes("finger3", rotor_inertia=True)
    t = 1e-3 * np.arange(300)
    u = 0.02 + 0.004 * np.sin(2 * np.pi * 7 * t) + 0.002 * np.sin(2 * np.pi * 23 * t)
    x0 = np.r_[finger.static_equilibrium(finger.transmission.S.T @ u[:1]), np.zeros(3)]
    q_rigid = simulate(rigid, x0, np.repeat(u, 10)[:, None], 0.3, 1e-4, "rk4", input="motor").x[::10, :3]
    err = []
    for k_t in (4e5, 4e6):
        c_t = 2 * 0.7 * np.sqrt(k_t * p.J_m) / p.r_m  # the rotor-on-cable mode damped at 0.7
        sy = SeriesElasticSystem(finger, ElasticTendon.from_cable(1, k_t, p.r_m, c_t))
        X = sy.simulate(sy.equilibrium(u[:1]), u, 1e-3, 10)
        err.append(np.abs(X[:, :3] - q_rigid).max())
    assert err[1] < 2e-4
    assert 8 < err[0] / err[1] < 12  # first order in the compliance


def test_rest_is_the_quasi_static_compliance(finger, p):
    """At rest under u the cable pulls T_m = u, the state is stationary (f = 0) and the encoder reads the
    quasi-static S q + delta + C u with C = 1 / (k_t r_m^2): the Transmission's tendon_compliance reading."""
    band = 5e-5
    sy = SeriesElasticSystem(finger, ElasticTendon.from_cable(1, K_T, p.r_m, C_T, band))
    u = np.array([0.021])
    x = sy.equilibrium(u)
    assert np.abs(sy.f(x, u)).max() < 1e-8
    assert sy.tension(x) == pytest.approx(u, rel=1e-12)
    C = 1.0 / (K_T * p.r_m**2)
    assert sy.tendon.compliance == pytest.approx([C], rel=1e-15)
    elastic = dataclasses.replace(finger.transmission, tendon_compliance=sy.tendon.compliance)
    q = x[:3]
    assert sy.encoder(x) == pytest.approx(elastic.encoder_angles(q[None], u[None])[0] + band / p.r_m, rel=1e-13)
    assert np.abs(finger.gravity_torque(q) - finger.transmission.S.T @ u).max() < 1e-12


def _cable_file(p, tmp_path: Path) -> Path:
    """The shipped parameter file with the K_T cable's compliance C = 1 / (K_T r_m^2), as identify writes it."""
    C = 1.0 / (K_T * p.r_m**2)
    text = Path(p.path).read_text(encoding="utf-8").replace(
        "[transmission]\n", f'[transmission]\ntendon_compliance = {{ value = {C!r}, unit = "rad/(N m)", '
        'source = "identified", reason = "a test cable", description = "the cable" }\n', 1)
    path = tmp_path / "cable.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_of_reads_the_compliance_written_once(p, tmp_path):
    """ElasticTendon.of takes k_m = 1 / C from the model's tendon compliance, as a parameter file (or an identified
    one) holds it: the same cable as from_cable(k_t, r_m) where C = 1 / (k_t r_m^2); a rigid tendon is refused."""
    path = _cable_file(p, tmp_path)
    m = ad.Model.alpes("finger3", params=str(path))
    t = ElasticTendon.of(m, damping=C_T * p.r_m**2, dead_band=1e-2)
    ref = ElasticTendon.from_cable(1, K_T, p.r_m, C_T, 1e-2 * p.r_m)
    for a, b in ((t.stiffness, ref.stiffness), (t.damping, ref.damping), (t.dead_band, ref.dead_band)):
        assert a == pytest.approx(b, rel=1e-12)
    with pytest.raises(InputError, match="tendon_compliance: motor 'finger' has a rigid tendon"):
        ElasticTendon.of(ad.Model.alpes("finger3"))


def test_alpes_export_and_the_file_cable(p, tmp_path):
    """mjcf_string of a parameter file with a tendon compliance C: with tendon_stiffness = 1 / (C r_m^2) the same MJCF
    as from the shipped file (the cable written once); without it the rigid tendon with a warning naming that
    stiffness (not silently dropped); another stiffness refused."""
    from alpes_dyn.errors import AlpesDynWarning

    path = _cable_file(p, tmp_path)
    k_file = 1.0 / ((1.0 / (K_T * p.r_m**2)) * p.r_m**2)
    body = [ln for ln in mjcf_string("finger3", str(path), tendon_stiffness=k_file, tendon_damping=C_T).splitlines()
            if "<!--" not in ln]
    by_hand = [ln for ln in mjcf_string("finger3", tendon_stiffness=k_file, tendon_damping=C_T).splitlines()
               if "<!--" not in ln]
    assert body == by_hand
    with pytest.warns(AlpesDynWarning, match=r"tendon_compliance: the file's cable .* written as a rigid tendon; "
                                             r"its series-elastic plant is tendon_stiffness=40000 N/m with a tendon_damping "
                                             r"\(the command line's --tendon-stiffness 40000 --tendon-damping"):
        rigid = mjcf_string("finger3", str(path))
    assert "finger_rotor" not in rigid
    with pytest.raises(InputError, match="tendon_stiffness: 30000.0 N/m differs from the parameter file's cable"):
        mjcf_string("finger3", str(path), tendon_stiffness=3e4)


def test_numeric_equals_symbolic_with_friction(p, rng):
    """Model.forward_dynamics (Pinocchio ABA) and SymbolicDynamics (CasADi) give the same right-hand side, the
    smooth friction law included, at random states."""
    m = ad.Model.alpes("finger3", friction=True)
    sy = SeriesElasticSystem(m, ElasticTendon.from_cable(1, K_T, p.r_m, C_T, 2e-5))
    f = sy.f_function()
    for _ in range(8):
        q, v = m.random_state(rng, speed=2.0)
        x = np.r_[q, sy.S[0] @ q + rng.uniform(-1e-1, 1e-1), v, rng.uniform(-5, 5)]
        u = rng.uniform(0, 0.05, 1)
        a, b = sy.f(x, u), np.asarray(f(x, u)).ravel()
        assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()


def test_hand_is_its_chains(p, rng):
    """On the hand (6 motors, 15 joints) the index's joints and rotor move as on the index's own chain model
    (Model.alpes("finger3", chain="index"), another Pinocchio model): each cable pulls its own chain only."""
    hand = ad.Model.alpes("hand")
    index = ad.Model.alpes("finger3", chain="index")
    m = hand.transmission.n_motors
    cable = dict(cable_stiffness=K_T, shaft_radius=p.r_m, cable_damping=C_T)
    sh = SeriesElasticSystem(hand, ElasticTendon.from_cable(m, **cable))
    si = SeriesElasticSystem(index, ElasticTendon.from_cable(1, **cable))
    js = [hand.joint_names.index(j) for j in hand.joint_names if j.startswith("index_")]
    k = hand.transmission.motor_names.index("index")
    assert len(js) == 3
    for _ in range(4):
        q, v = hand.random_state(rng, speed=1.0)
        th, w = sh.S @ q + rng.uniform(-0.05, 0.1, m), rng.uniform(-5, 5, m)
        u = rng.uniform(0, 0.05, m)
        xd = sh.f(np.r_[q, th, v, w], u)
        xi = si.f(np.r_[q[js], th[k], v[js], w[k]], u[k:k + 1])
        n = hand.n
        assert np.allclose(xd[n + m:][js], xi[4:7], rtol=1e-10, atol=1e-9)
        assert xd[2 * n + m + k] == pytest.approx(xi[7], rel=1e-12)


@pytest.mark.parametrize("call, needle", [
    (lambda f, p: ElasticTendon.from_cable(1, -1.0, p.r_m), "cable_stiffness: expected 1 finite positive"),
    (lambda f, p: ElasticTendon.from_cable(1, 4e4, 0.0), "shaft_radius: expected 1 finite positive"),
    (lambda f, p: ElasticTendon.from_cable(1, 4e4, p.r_m, dead_band=-1e-4), "dead_band: expected 1 finite"),
    (lambda f, p: ElasticTendon.from_cable(0, 4e4, p.r_m), "n_motors: expected a positive integer"),
    (lambda f, p: ElasticTendon([1.0, 2.0], [0.0], [0.0]), "damping: expected 2 finite non-negative"),
    (lambda f, p: ElasticTendon(np.nan, 0.0, 0.0), "stiffness: expected 1 finite positive"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon([1.0, 1.0], [0.0, 0.0], [0.0, 0.0])),
     "tendon: expected 1 motors' values"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0), rotor_inertia=0.0),
     "rotor_inertia: expected 1 finite positive"),
    (lambda f, p: SeriesElasticSystem(f, "cable"), "tendon: expected an ElasticTendon"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0)).equilibrium([-0.01]),
     "u: a pull-only cable holds no negative motor torque"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0)).f(np.zeros(7), [0.0]), "x: expected 8 finite"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0)).f(np.zeros(8), [np.nan]),
     "u: expected 1 finite motor torques"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0)).simulate(np.zeros(8), [0.0], 1e-3, 1),
     "substeps: RK4 steps of 0.001 s are unstable on the rotor's mode"),
    (lambda f, p: SeriesElasticSystem(f, ElasticTendon(1.0, 0.0, 0.0)).simulate(np.zeros(8), [0.0], True),
     "dt: expected a positive number of seconds"),
])
def test_bad_input(finger, p, call, needle):
    with pytest.raises(InputError, match=needle.replace("(", r"\(").replace(")", r"\)").replace("^", r"\^")):
        call(finger, p)


def test_any_robot_export_equals_the_model(rng):
    """A URDF + spec robot (test_mjcf_export's arm: a tendon with a negative ratio over two joints, a geared slider,
    rotors, springs, friction, tilted gravity): model_mjcf(tendon=) writes a rotor hinge per motor and the cable as a
    one-sided spring; MuJoCo's accelerations and pull equal SeriesElasticSystem's, whose model leaves the spec's
    rotor inertia off the joints (it is each rotor's own); the cable's play included."""
    mujoco = pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf_export import _ROTOR_MASS, model_mjcf
    from test_mjcf_export import ARM_SPEC, ARM_URDF

    arm = ad.Model(ARM_URDF, ARM_SPEC)
    assert arm._rotor  # the spec's rotors sit on the joints (J_m S^T S) ...
    tendon = ElasticTendon([0.5, 30.0], [1e-3, 0.0], [0.01, 0.0])
    mj = mujoco.MjModel.from_xml_string(model_mjcf(arm, tendon=tendon, limits=False))
    d = mujoco.MjData(mj)
    sy = SeriesElasticSystem(arm, tendon, rotor_inertia=arm.transmission.rotor_inertia + _ROTOR_MASS)
    assert not sy.model._rotor  # ... and leave them for the system
    jq = [mj.joint(j).qposadr[0] for j in arm.joint_names]
    rq = [mj.joint(f"{mo}_rotor").qposadr[0] for mo in arm.transmission.motor_names]
    rv = [mj.joint(f"{mo}_rotor").dofadr[0] for mo in arm.transmission.motor_names]
    jv = [mj.joint(j).dofadr[0] for j in arm.joint_names]
    mj.dof_frictionloss[:] = 0.0  # MuJoCo's dry friction is a constraint: compare the smooth parts
    sy_nf = SeriesElasticSystem(ad.Model(ARM_URDF, dataclasses.replace(ARM_SPEC, coulomb={})), tendon,
                                rotor_inertia=arm.transmission.rotor_inertia + _ROTOR_MASS)
    for _ in range(10):
        q, v = arm.random_state(rng, speed=1.0)
        th = sy.S @ q + rng.uniform(-0.02, 0.05, 2)
        w, u = rng.uniform(-3, 3, 2), rng.uniform(-0.1, 0.1, 2)
        d.qpos[jq], d.qvel[jv], d.qpos[rq], d.qvel[rv], d.ctrl[:] = q, v, th, w, u
        mujoco.mj_forward(mj, d)
        x = np.r_[q, th, v, w]
        xd = sy_nf.f(x, u)
        assert np.allclose(xd[5:8], d.qacc[jv], rtol=1e-8, atol=1e-8)
        assert np.allclose(xd[8:], d.qacc[rv], rtol=1e-8, atol=1e-8)
        assert np.allclose(sy.tension(x), -d.qfrc_passive[rv], rtol=1e-10, atol=1e-14)
        assert np.allclose([d.sensor(f"encoder_{mo}").data[0] for mo in arm.transmission.motor_names], th)
    with pytest.raises(InputError, match="tendon: expected an ElasticTendon"):
        model_mjcf(arm, tendon="cable")
    with pytest.raises(InputError, match="tendon: expected the values of the model's 2 motors"):
        model_mjcf(arm, tendon=ElasticTendon(1.0, 0.0, 0.0))


def test_rotor_on_the_joints_moves_to_its_state(p, rng):
    """An Alpes model built with its rotor on the joints gives the same system as one without (the rotor J_m
    becomes the state's), and its export's round trip refuses nothing silently: an elastic model needs tendon=."""
    a = SeriesElasticSystem(ad.Model.alpes("finger3", rotor_inertia=True), ElasticTendon.from_cable(1, K_T, p.r_m))
    b = SeriesElasticSystem(ad.Model.alpes("finger3"), ElasticTendon.from_cable(1, K_T, p.r_m))
    assert a.rotor_inertia == pytest.approx(b.rotor_inertia, rel=0) and not a.model._rotor
    q, v = a.model.random_state(rng, speed=1.0)
    x = np.r_[q, a.S[0] @ q + 0.01, v, 1.0]
    assert np.array_equal(a.f(x, [0.02]), b.f(x, [0.02]))


def test_elastic_model_exports_its_cable_written_once():
    """A spec with a tendon compliance (as identify writes it) exports its cable (tendon=ElasticTendon.of(model),
    k_m = 1 / C) and nothing else: no tendon= is refused (the quasi-static stretch is no MJCF), nor a cable of
    another stiffness."""
    from alpes_dyn.errors import ModelError
    from alpes_dyn.model.mjcf_export import model_mjcf
    from test_mjcf_export import ARM_SPEC, ARM_URDF

    spec = dataclasses.replace(ARM_SPEC, motors=tuple(dataclasses.replace(m, tendon_compliance=c)
                                                      for m, c in zip(ARM_SPEC.motors, (2.0, 0.05))))
    arm = ad.Model(ARM_URDF, spec)
    with pytest.raises(ModelError, match=r"tendon_compliance: .* export its cable's dynamics"):
        model_mjcf(arm)
    text = model_mjcf(arm, tendon=ElasticTendon.of(arm, damping=1e-3))
    assert 'stiffness="0.5"' in text and 'stiffness="20.0"' in text and text.count("_rotor") >= 4
    with pytest.raises(InputError, match="tendon: its compliance 1/k_m"):
        model_mjcf(arm, tendon=ElasticTendon([0.5, 21.0], [0.0, 0.0], [0.0, 0.0]))
