"""Mimic joints (URDF ``<mimic>``) as constraints q_k = a q_J + b: the reduced model against a Lagrangian written by
hand, Pinocchio's own mimic model, the same tree with the mimic joint welded (a = 0), MuJoCo on the exported MJCF
with its joint equality, the MJCF round trip, the symbolic (ADAM) path, and Panda's gripper."""

from __future__ import annotations

import site
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import alpes_dyn as ad
from alpes_dyn.model.spec import TransmissionSpec

A_MIMIC, B_MIMIC = 0.7, 0.1  # the DIP follows the PIP: q_dip = 0.7 q_pip + 0.1 rad

# (mass kg, centre of mass in the link frame m, Iyy kg m^2, the next joint's (or the tip's) origin m) of l1, l2, l3
LINKS = ((0.05, (0.0, 0.0, -0.02), 1.2e-5, (0.0, 0.0, -0.04)),
         (0.03, (0.0, 0.0, -0.015), 6e-6, (0.0, 0.0, -0.03)),
         (0.02, (0.002, 0.0, -0.01), 3e-6, (0.0, 0.0, -0.02)))


def finger_urdf(multiplier: float = A_MIMIC, offset: float = B_MIMIC, welded: bool = False) -> str:
    """A planar 3-link finger (every axis y) whose DIP mimics its PIP; ``welded``: the DIP a fixed joint at ``offset``."""
    inertia = ('ixx="1e-5" iyy="1.2e-5" izz="0.5e-5"', 'ixx="5e-6" iyy="6e-6" izz="3e-6"',
               'ixx="2.5e-6" iyy="3e-6" izz="1e-6"')
    links = "".join(f'<link name="l{i + 1}"><inertial><origin xyz="{" ".join(map(str, c))}"/><mass value="{m}"/>'
                    f'<inertia {inertia[i]} ixy="0" ixz="0" iyz="0"/></inertial></link>'
                    for i, (m, c, _, _) in enumerate(LINKS))
    lim = '<limit lower="-1.5" upper="1.5" effort="1" velocity="10"/>'
    dip = (f'<joint name="dip" type="fixed"><parent link="l2"/><child link="l3"/><origin xyz="0 0 -0.03" '
           f'rpy="0 {offset!r} 0"/></joint>' if welded else
           f'<joint name="dip" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="0 0 -0.03"/>'
           f'<axis xyz="0 1 0"/>{lim}<mimic joint="pip" multiplier="{multiplier!r}" offset="{offset!r}"/></joint>')
    return (f'<?xml version="1.0"?><robot name="finger3m"><link name="base"/>{links}<link name="tip"/>'
            f'<joint name="mcp" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0"/>'
            f'<axis xyz="0 1 0"/>{lim}</joint>'
            f'<joint name="pip" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 -0.04"/>'
            f'<axis xyz="0 1 0"/>{lim}</joint>{dip}'
            f'<joint name="tip_joint" type="fixed"><parent link="l3"/><child link="tip"/><origin xyz="0 0 -0.02"/>'
            f'</joint></robot>')


SPEC = TransmissionSpec.from_dict({"motor": [{"name": "flexor", "joints": {"mcp": 0.01, "pip": 0.008}}],
                                   "stiffness": {"mcp": 0.05, "pip": 0.03}, "rest_angle": {"pip": 0.2},
                                   "viscous": {"mcp": 1e-4, "pip": 1e-4}})


def _states(m: ad.Model, k: int = 4, seed: int = 3):
    rng = np.random.default_rng(seed)
    for _ in range(k):
        q, v = m.random_state(rng)
        yield q, v, rng.normal(scale=0.02, size=m.n)


# ------------------------------------------------------------------ (a) a Lagrangian written by hand
def _hand_terms(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A (2, 2), gravity torque (2,), tip position (3,), tip Jacobian (3, 2)) of the planar finger with q_dip =
    a q_pip + b, from its links' masses, centres of mass and Iyy: A = sum m Jc^T Jc + Iyy Jw^T Jw, g = dV/dq."""
    G = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, A_MIMIC]])
    qf = G @ q + np.array([0.0, 0.0, B_MIMIC])
    phi = np.cumsum(qf)  # each link's absolute angle about y

    def rot(a: float) -> np.ndarray:
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])

    origins = [np.zeros(3)]
    for i, (_, _, _, nxt) in enumerate(LINKS):
        origins.append(origins[i] + rot(phi[i]) @ np.array(nxt))

    def jac(p: np.ndarray, i: int) -> np.ndarray:  # d p / d q_full of a point of link i: y x (p - o_k), k <= i
        J = np.zeros((3, 3))
        for k in range(i + 1):
            r = p - origins[k]
            J[:, k] = (r[2], 0.0, -r[0])
        return J @ G

    A, g = np.zeros((2, 2)), np.zeros(2)
    for i, (mass, c, Iyy, _) in enumerate(LINKS):
        Jc = jac(origins[i] + rot(phi[i]) @ np.array(c), i)
        Jw = (np.arange(3) <= i).astype(float) @ G  # d phi_i / d q
        A += mass * Jc.T @ Jc + Iyy * np.outer(Jw, Jw)
        g += mass * 9.81 * Jc[2]
    return A, g, origins[3], jac(origins[3], 2)


def _hand_coriolis(q: np.ndarray, v: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """C_ij = sum_k 1/2 (dA_ij/dq_k + dA_ik/dq_j - dA_jk/dq_i) v_k (Christoffel), dA by central differences."""
    dA = np.stack([(_hand_terms(q + h * e)[0] - _hand_terms(q - h * e)[0]) / (2 * h) for e in np.eye(2)])  # [k, i, j]
    return 0.5 * (np.einsum("kij,k->ij", dA, v) + np.einsum("jik,k->ij", dA, v) - np.einsum("ijk,k->ij", dA, v))


def test_against_a_hand_written_lagrangian():
    m = ad.Model(finger_urdf())
    assert m.n == 2 and m.joint_names == ("mcp", "pip") and m.mimic.mimic_names == ("dip",)
    for q, v, tau in _states(m):
        A, g, p, J = _hand_terms(q)
        C = _hand_coriolis(q, v)
        np.testing.assert_allclose(m.inertia_matrix(q), A, rtol=0, atol=1e-18)
        np.testing.assert_allclose(m.gravity_torque(q), g, rtol=0, atol=1e-15)
        np.testing.assert_allclose(m.fingertip_position(q, "tip"), p, rtol=0, atol=1e-16)
        np.testing.assert_allclose(m.fingertip_jacobian(q, "tip"), J, rtol=0, atol=1e-16)
        np.testing.assert_allclose(m.coriolis_matrix(q, v), C, rtol=0, atol=1e-13)
        qdd = np.linalg.solve(A, tau - C @ v - g)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), qdd, rtol=1e-8, atol=0)
        # the potential energy's gradient is the gravity torque, and Newton's Jacobian is its derivative
        dV = [(m.potential_energy(q + 1e-6 * e) - m.potential_energy(q - 1e-6 * e)) / 2e-6 for e in np.eye(2)]
        np.testing.assert_allclose(dV, g, rtol=1e-7)
        dG = np.stack([(m.gravity_torque(q + 1e-6 * e) - m.gravity_torque(q - 1e-6 * e)) / 2e-6 for e in np.eye(2)]).T
        np.testing.assert_allclose(m.gravity_jacobian(q), dG, rtol=1e-7, atol=1e-12)


def test_against_pinocchio_mimic_model_and_christoffel_property():
    """Pinocchio's own mimic model's CRBA and nonLinearEffects (its Coriolis matrix is not used: it disagrees with
    its own nonLinearEffects); the model's C is Christoffel-consistent: C qd + g = nle, A_dot - 2C skew."""
    urdf = finger_urdf()
    m = ad.Model(urdf)
    pm = pin.buildModelFromXML(urdf, mimic=True)
    pd = pm.createData()
    for q, v, tau in _states(m):
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T
        nle = pin.nonLinearEffects(pm, pd, q, v)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), np.linalg.solve(M, tau - nle), rtol=1e-12)
        C = m.coriolis_matrix(q, v)
        np.testing.assert_allclose(C @ v + m.gravity_torque(q), nle, rtol=0, atol=1e-16)
        Adot = (m.inertia_matrix(q + 1e-7 * v) - m.inertia_matrix(q - 1e-7 * v)) / 2e-7
        N = Adot - 2 * C
        np.testing.assert_allclose(N + N.T, 0, atol=1e-12)


# ------------------------------------------------------------------ (c) a = 0: the mimic joint welded
def test_zero_multiplier_is_the_welded_tree():
    m, w = ad.Model(finger_urdf(0.0, 0.3)), ad.Model(finger_urdf(0.0, 0.3, welded=True))
    assert m.joint_names == w.joint_names == ("mcp", "pip")
    for q, v, tau in _states(m):
        np.testing.assert_allclose(m.inertia_matrix(q), w.inertia_matrix(q), rtol=1e-13, atol=0)
        np.testing.assert_allclose(m.coriolis_matrix(q, v), w.coriolis_matrix(q, v), rtol=0, atol=1e-17)
        np.testing.assert_allclose(m.gravity_torque(q), w.gravity_torque(q), rtol=0, atol=1e-16)
        np.testing.assert_allclose(m.gravity_jacobian(q), w.gravity_jacobian(q), rtol=0, atol=1e-16)
        np.testing.assert_allclose(m.fingertip_jacobian(q, "tip"), w.fingertip_jacobian(q, "tip"), rtol=0, atol=1e-16)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), w.forward_dynamics(q, v, tau), rtol=1e-12)
        assert m.potential_energy(q) == pytest.approx(w.potential_energy(q), rel=1e-13)


def _middle_mimic_urdf(multiplier: float, offset: float, welded: bool = False) -> str:
    """The shipped finger3 whose middle joint j2 follows j1 (q_j2 = a q_j1 + b) while j3 below it moves on its own;
    ``welded``: j2 a fixed joint turned by ``offset`` about its axis (0 -1 0)."""
    urdf = ad.urdf_string("finger3")
    head = '<joint name="j2" type="revolute">'
    assert head in urdf
    if not welded:
        return urdf.replace(head, head + f'<mimic joint="j1" multiplier="{multiplier!r}" offset="{offset!r}"/>')
    start = urdf.index(head)
    end = urdf.index("</joint>", start) + len("</joint>")
    j2 = urdf[start:end]
    parent = j2[j2.index("<parent"):j2.index("/>", j2.index("<parent")) + 2]
    child = j2[j2.index("<child"):j2.index("/>", j2.index("<child")) + 2]
    xyz = j2[j2.index('xyz="', j2.index("<origin")) + 5:j2.index('"', j2.index('xyz="', j2.index("<origin")) + 5)]
    fixed = (f'<joint name="j2" type="fixed">{parent}{child}<origin xyz="{xyz}" rpy="0 {-offset!r} 0"/></joint>')
    return urdf[:start] + fixed + urdf[end:]


def test_a_mimic_joint_with_a_moving_child_on_repeated_calls():
    """A mimic joint in the middle of the chain (j3 below it moves on its own): Pinocchio 4.1's CRBA on its mimic
    model adds to the coupled entries on every call after the first, so A and the forward dynamics must not come
    from it. (a) a = 0 against the tree with j2 welded at the offset, over repeated calls at the same state; (b) a =
    0.8 against Pinocchio's mimic model on a fresh Data per call (right on a first call: it equals (a)'s welded
    tree at a = 0)."""
    m, w = ad.Model(_middle_mimic_urdf(0.0, 0.3)), ad.Model(_middle_mimic_urdf(0.0, 0.3, welded=True))
    assert m.joint_names == w.joint_names == ("j1", "j3")
    q, v, tau = np.array([0.4, 0.9]), np.array([0.5, -1.0]), np.array([0.01, -0.002])
    for _ in range(3):  # the same state thrice: the same numbers thrice
        np.testing.assert_allclose(m.inertia_matrix(q), w.inertia_matrix(q), rtol=1e-13, atol=0)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), w.forward_dynamics(q, v, tau), rtol=1e-11)
    urdf = _middle_mimic_urdf(0.8, 0.1)
    m = ad.Model(urdf)
    pm = pin.buildModelFromXML(urdf, mimic=True)
    for q, v, tau in list(_states(m)) * 2:
        pd = pm.createData()
        M = pin.crba(pm, pd, q)
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_allclose(m.inertia_matrix(q), M, rtol=1e-13, atol=0)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), np.linalg.solve(M, tau - pin.nonLinearEffects(
            pm, pd, q, v)), rtol=1e-11)


# ------------------------------------------------------------------ the spec on the independent joints
def test_spec_rows_act_on_the_independent_joint():
    m, bare = ad.Model(finger_urdf(), SPEC), ad.Model(finger_urdf())
    assert m.transmission.S.shape == (1, 2)
    for q, v, tau in _states(m):
        k, rest = np.array([0.05, 0.03]), np.array([0.0, 0.2])
        passive = k * (q - rest) + 1e-4 * v
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), bare.forward_dynamics(q, v, tau - passive),
                                   rtol=1e-12)
    q = m.static_equilibrium(np.zeros(2))
    np.testing.assert_allclose(m.gravity_torque(q), 0, atol=1e-12)
    c = m.copy()
    assert c.mimic.mimics == m.mimic.mimics and c.n == 2


# ------------------------------------------------------------------ (b) MuJoCo on the exported MJCF
def test_mujoco_with_the_joint_equality():
    mujoco = pytest.importorskip("mujoco")
    m = ad.Model(finger_urdf(), SPEC)
    text = m.to_mjcf()
    assert '<joint joint1="dip" joint2="pip" polycoef="0.1 0.7 0 0 0"' in text
    mj = mujoco.MjModel.from_xml_string(text)
    d = mujoco.MjData(mj)
    G = m.mimic.G
    on_independent = np.array([[float(f == j) for j in m.joint_names] for f in m.mimic.full_names])  # G^T E = I
    worst = 0.0
    for q, v, tau in _states(m):
        d.qpos[:], d.qvel[:], d.ctrl[:] = m.mimic.full_q(q), m.mimic.full_v(v), [0.0]
        d.qfrc_applied[:] = on_independent @ tau
        mujoco.mj_forward(mj, d)
        M = np.zeros((3, 3))
        mujoco.mj_fullM(mj, M, d.qM) if hasattr(d, "qM") else mujoco.mj_fullM(mj, d, M)
        bias = d.qfrc_bias - d.qfrc_passive
        np.testing.assert_allclose(G.T @ M @ G, m.inertia_matrix(q), rtol=1e-12, atol=0)
        np.testing.assert_allclose(G.T @ bias, m.inverse_dynamics(q, v, np.zeros(2)), rtol=1e-12, atol=1e-16)
        qdd = m.forward_dynamics(q, v, tau)
        # MuJoCo's constrained accelerations: a soft constraint (impedance 0.9999) gives way a little
        scale = np.max(np.abs(qdd))
        np.testing.assert_allclose(d.qacc, G @ qdd, rtol=0, atol=5e-3 * scale)  # 2.3e-3 over 20 states
        worst = max(worst, float(np.max(np.abs(d.qacc - G @ qdd)) / scale))
    assert worst > 0  # MuJoCo's solver, not a copy of ours


def test_mjcf_round_trip_keeps_the_mimic():
    pytest.importorskip("mujoco")
    m = ad.Model(finger_urdf(), SPEC)
    b = ad.Model.from_mjcf(m.to_mjcf())
    assert b.joint_names == m.joint_names and b.mimic.mimics == m.mimic.mimics
    for q, v, tau in _states(m):
        np.testing.assert_allclose(b.inertia_matrix(q), m.inertia_matrix(q), rtol=0, atol=1e-17)
        np.testing.assert_allclose(b.coriolis_matrix(q, v), m.coriolis_matrix(q, v), rtol=0, atol=1e-16)
        np.testing.assert_allclose(b.gravity_torque(q), m.gravity_torque(q), rtol=0, atol=1e-15)
        np.testing.assert_allclose(b.forward_dynamics(q, v, tau), m.forward_dynamics(q, v, tau), rtol=1e-12)


# ------------------------------------------------------------------ the symbolic path
def test_symbolic_adam_agrees():
    cs = pytest.importorskip("casadi")
    from alpes_dyn.symbolic.dynamics import SymbolicDynamics

    m = ad.Model(finger_urdf(), SPEC)
    sd = SymbolicDynamics(m, "adam")
    q, v, t = (cs.SX.sym(s, 2) for s in "qvt")
    f = cs.Function("f", [q, v, t], [sd.forward_dynamics(q, v, t, smooth=False), sd.inertia_matrix(q),
                                     sd.gravity_torque(q), sd.fingertip_jacobian(q, "tip")])
    for qn, vn, tn in _states(m):
        fd, A, g, J = (np.array(x) for x in f(qn, vn, tn))
        np.testing.assert_allclose(fd.ravel(), m.forward_dynamics(qn, vn, tn), rtol=1e-11)
        np.testing.assert_allclose(A, m.inertia_matrix(qn), rtol=0, atol=1e-17)
        np.testing.assert_allclose(g.ravel(), m.gravity_torque(qn), rtol=0, atol=1e-15)
        np.testing.assert_allclose(J, m.fingertip_jacobian(qn, "tip"), rtol=0, atol=1e-16)


# ------------------------------------------------------------------ Panda's gripper (example-robot-data)
PANDA = (Path(site.getsitepackages()[0]) / "cmeel.prefix/share/example-robot-data/robots/panda_description/urdf/"
         "panda.urdf")


@pytest.mark.skipif(not PANDA.is_file(), reason="example-robot-data's Panda not installed")
def test_panda_gripper_loads_with_its_finger_as_a_mimic():
    urdf = PANDA.read_text()
    full = pin.buildModelFromXML(urdf)
    m = ad.Model(urdf)
    assert full.nq == 9 and m.n == 8
    assert m.mimic.mimic_names == ("panda_finger_joint2",) and m.joint_names[-1] == "panda_finger_joint1"
    fd = full.createData()
    G = m.mimic.G
    for q, v, tau in _states(m, 2):
        M = pin.crba(full, fd, m.mimic.full_q(q))
        M = np.triu(M) + np.triu(M, 1).T
        b = pin.nonLinearEffects(full, fd, m.mimic.full_q(q), G @ v)
        np.testing.assert_allclose(m.inertia_matrix(q), G.T @ M @ G, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(m.forward_dynamics(q, v, tau), np.linalg.solve(G.T @ M @ G, tau - G.T @ b),
                                   rtol=1e-9, atol=1e-9)
    assert '<joint joint1="panda_finger_joint2" joint2="panda_finger_joint1" polycoef="0.0 1.0 0 0 0"' in m.to_mjcf()


def test_cli_names_the_mimic(tmp_path, capsys):
    from alpes_dyn.cli import main

    path = tmp_path / "finger3m.urdf"
    path.write_text(finger_urdf())
    assert main(["dynamics", "--model", str(path), "--q", "0.1,0.2"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("model finger3m (2 joints in Pinocchio's order), spring model none; dip mimics pip "
                          "(q = 0.7 q_pip + 0.1)")


GRIPPER_SPEC = ('encoder_counts = 4096\ntips = ["panda_leftfinger"]\n\n[[motor]]\nname = "gripper"\n'
                'joints = { panda_finger_joint1 = 1.0 }\n\n[stiffness]\npanda_finger_joint1 = 50.0\n')


@pytest.mark.skipif(not PANDA.is_file(), reason="example-robot-data's Panda not installed")
def test_panda_gripper_experiment_refused_in_one_line(tmp_path, capsys):
    """A tendon on Panda's gripper (its two fingers one mimic pair): the arm's seven joints have neither a motor nor a
    spring, nothing holds them still, and the experiment says so naming them (it used to say that "the nominal
    finger's equilibrium at 1 N m leaves its joint range": the design's 0.05 margin inside each limit left the
    fingers' 0.04 m travel an empty range; the margin is now at most a tenth of a joint's range). Welded, the
    gripper alone is refused by the symbolic backend in one line (ADAM's recursive Newton-Euler fails on this tree)."""
    from alpes_dyn.cli import main
    from alpes_dyn.estimation.experiments.experiment import _joint_margins

    spec = tmp_path / "gripper.toml"
    spec.write_text(GRIPPER_SPEC)
    m = ad.Model.from_urdf_file(PANDA, spec)
    margins = _joint_margins(m, 0.05)
    assert margins[-1] == pytest.approx(0.004, rel=1e-12) and np.all(margins[:-1] == 0.05)
    assert main(["experiment", "--model", str(PANDA), "--spec", str(spec), "--duration", "0.5",
                 "-o", str(tmp_path / "rec.csv")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("alpes-dyn: error: model: panda_joint1, panda_joint2, panda_joint3, panda_joint4, "
                          "panda_joint5, panda_joint6, panda_joint7 have neither a motor nor a spring, so nothing "
                          "holds them still") and "\n" not in err
    assert not (tmp_path / "rec.csv").exists()
    welded = PANDA.read_text()
    for i in range(1, 8):
        welded = welded.replace(f'<joint name="panda_joint{i}" type="revolute">', f'<joint name="panda_joint{i}" '
                                'type="fixed">')
    g = ad.Model(welded, m.spec)
    assert g.joint_names == ("panda_finger_joint1",)
    with pytest.raises(ad.ModelError, match="backend 'adam': adam-robotics cannot compute the bias forces of model"):
        from alpes_dyn.symbolic.statespace import StateSpace

        StateSpace(g, input="motor", output="encoder")
