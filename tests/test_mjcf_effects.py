"""The MJCF export's realism options (stiction, series-elastic tendon, rotor on the tendon, tilted palm) against
independent references: the old export byte for byte, the dry-friction law's stick and slip, the cable's
tension k_t max(e, 0) from MuJoCo's own tendon length, the library's Model with the rotated gravity vector, and
M + J_m S^T S from the library's inertia matrix and transmission (MuJoCo's mj_fullM)."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.cli import main
from alpes_dyn.model.mjcf import STICTION_TIMECONST, joint_permutation, load_mujoco, mjcf_string, tilted_gravity

mujoco = pytest.importorskip("mujoco")

# sha256 of the export before the realism options existed (main at 668b65e), for four configurations
GOLDEN = [
    ("finger2", {}, "a603f152699b461f234ae0228ddf0d1892babd4a032ff64ce5e3b3e985491e54"),
    ("finger3", {"friction": True, "scene": "block"}, "fe57c2d0e842ef7fe6e9ae9ad69a2329e076c2de6916175e6402b466165168c8"),
    # (rotor_inertia=True changed meaning since: the rotor on the tendon, its armature J_m S^T S; tests/test_rotor.py)
    ("hand", {"scene": "cylinder", "palm_down": True},
     "89ede6387238851a9c03dac016d916377ee7feaa7de7f113a35e2212127524ca"),
    ("thumb", {"spring": "report", "limits": False, "contact": False},
     "b512de88c967a8d207e5b95283ac8c9c00f813759d2521a53dfc6682045ab83d"),
]


@pytest.mark.parametrize("name,kw,digest", GOLDEN)
def test_effects_off_export_unchanged(name, kw, digest):
    assert hashlib.sha256(mjcf_string(name, **kw).encode()).hexdigest() == digest
    off = dict(stiction=None, tendon_stiffness=None, tendon_damping=0.0, tendon_rotor=False, tilt=0.0)
    assert mjcf_string(name, **kw, **off) == mjcf_string(name, **kw)


def _free_finger(**kw):
    """finger3 without springs and gravity (a dry-friction test bench), limits and contact off."""
    mj = load_mujoco(mjcf_string("finger3", spring="none", limits=False, contact=False, timestep=1e-4, **kw))
    mj.opt.gravity[:] = 0.0
    mj.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    return mj, mujoco.MjData(mj)


def _run(mj, d, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """qvel (N, 3) and the constraint (friction) torque (N, 3) under motor torques tau (N,) held per step."""
    v, f = np.empty((tau.size, 3)), np.empty((tau.size, 3))
    for k, u in enumerate(tau):
        d.ctrl[0] = u
        mujoco.mj_step(mj, d)
        v[k], f[k] = d.qvel, d.qfrc_constraint
    return v, f


def test_stiction_sticks_below_F_s_and_slides_with_full_F_s():
    """Joint torque r tau_m / r_m = 0.8 F_s on each joint: the finger stays put (stick) with the stiff constraint,
    creeps with MuJoCo's default soft one (0.4 rad/s after 0.1 s); at 3 F_s it slides against the full F_s."""
    p = ad.load_params()
    Fs, ratio = p.F_s, p.r / p.r_m
    hold = np.full(1000, 0.8 * Fs / ratio)  # 0.1 s
    mj, d = _free_finger(stiction=STICTION_TIMECONST)
    v_stiff, _ = _run(mj, d, hold)
    mj0, d0 = _free_finger(friction=True)
    v_soft, _ = _run(mj0, d0, hold)
    assert np.abs(v_stiff).max() < 2e-4  # rad/s: stuck (1e-5 rad in the 0.1 s)
    assert np.abs(v_soft).max() > 0.1  # the soft constraint lets it creep
    slide = np.full(1000, 3 * Fs / ratio)
    v, f = _run(mj, d, slide)
    assert np.all(np.abs(v[-100:]) > 0.1)  # sliding (joint 1 backwards: the others' reaction)
    # friction on a sliding joint: -F_s sign(v) (dry; F_v v is the joint damping, passive, not in qfrc_constraint)
    assert np.allclose(f[-100:], -Fs * np.sign(v[-100:]), rtol=0.01)


def test_stiction_gives_stick_phases_under_a_sine():
    """A 2 Hz sine of the joint torque between -1.5 and 1.5 F_s: the joints stand still (|v| < 1e-4 rad/s) for
    stretches of at least 20 ms around the turning points, only where the torque is inside the stick band;
    they slide (|v| > 0.05 rad/s) elsewhere."""
    p = ad.load_params()
    t = 1e-4 * np.arange(5000)
    tau_j = 1.5 * p.F_s * np.sin(2 * np.pi * 2.0 * t)
    mj, d = _free_finger(stiction=STICTION_TIMECONST)
    v, _ = _run(mj, d, tau_j / (p.r / p.r_m))
    still = np.abs(v[:, 0]) < 1e-4
    runs, k = [], 0
    while k < still.size:
        if still[k]:
            e = k
            while e < still.size and still[e]:
                e += 1
            runs.append((k, e))
            k = e
        k += 1
    long = [(a, b) for a, b in runs if b - a >= 200]
    assert len(long) >= 2
    assert np.abs(v[:, 0]).max() > 0.05


def test_elastic_tendon_tension_from_mujoco_stretch(rng):
    """Series-elastic tendon: qfrc_passive = r T on each joint (after the joint springs k q) and -r_m T on the rotor,
    T = k_t max(e, 0) + c_t de/dt, e MuJoCo's own tendon length = r_m theta_m - r sum q; the encoder reads theta_m."""
    p = ad.load_params()
    k_t, c_t = 4e4, 2.0
    mj = load_mujoco(mjcf_string("finger3", tendon_stiffness=k_t, tendon_damping=c_t, limits=False, contact=False))
    d = mujoco.MjData(mj)
    m = ad.Model.alpes("finger3")
    perm = joint_permutation(mj, m.joint_names)
    rot = mj.joint("finger_rotor").qposadr[0]
    seen = set()
    for _ in range(12):
        q, v = m.random_state(rng, speed=1.0)
        e_want = rng.uniform(-2e-4, 2e-4)
        th = (p.r * q.sum() + e_want) / p.r_m
        w = rng.uniform(-5, 5)
        d.qpos[perm], d.qvel[perm], d.qpos[rot], d.qvel[rot] = q, v, th, w
        mujoco.mj_forward(mj, d)
        e = d.ten_length[mj.tendon("finger").id]
        assert e == pytest.approx(p.r_m * th - p.r * q.sum(), abs=1e-15)
        T = k_t * max(e, 0.0) + c_t * (p.r_m * w - p.r * v.sum())
        assert np.allclose(d.qfrc_passive[perm] - (-m.extras.stiffness * q), p.r * T, rtol=1e-9, atol=1e-12)
        assert d.qfrc_passive[rot] == pytest.approx(-p.r_m * T, rel=1e-9, abs=1e-12)
        assert d.sensor("encoder_finger").data[0] == pytest.approx(th, rel=1e-14)
        assert d.sensor("tendon_finger").data[0] == pytest.approx(e, abs=1e-16)
        seen.add(e > 0)
    assert seen == {True, False}  # taut and slack both tried
    assert mj.dof_armature[mj.joint("finger_rotor").dofadr[0]] == p.J_m


def test_elastic_tendon_rest_is_the_rigid_model_rest():
    """Under a constant motor torque the elastic finger settles where the library's rigid model rests,
    G(q) = S^T tau_m, with the cable stretched by tau_m / (r_m k_t)."""
    p = ad.load_params()
    k_t, tau = 4e4, 0.02
    mj = load_mujoco(mjcf_string("finger3", tendon_stiffness=k_t, tendon_damping=5.0, contact=False, limits=False,
                                 timestep=2.5e-4))
    d = mujoco.MjData(mj)
    m = ad.Model.alpes("finger3")
    perm = joint_permutation(mj, m.joint_names)
    mj.dof_damping[perm] = 2e-3  # a test bench: joint damping to settle fast (no dry friction: one rest)
    d.ctrl[0] = tau
    for _ in range(12000):  # 3 s
        mujoco.mj_step(mj, d)
    q_rest = m.static_equilibrium(m.transmission.joint_torque([tau]))
    assert np.abs(d.qpos[perm] - q_rest).max() < 2e-5
    assert d.ten_length[0] == pytest.approx(tau / (p.r_m * k_t), rel=0.02)


def test_tilted_gravity_matches_model_with_rotated_gravity(rng):
    """tilt = 3 deg: MuJoCo's qacc = Model(gravity = R_y(tilt) g).forward_dynamics (1e-9 relative); the untilted
    model is off by far more."""
    tilt = np.radians(3.0)
    for name in ("finger3", "hand"):
        m0 = ad.Model.alpes(name)
        m = m0.copy(gravity=tilted_gravity(m0.gravity, tilt))
        assert np.linalg.norm(m.gravity) == pytest.approx(np.linalg.norm(m0.gravity), rel=1e-15)
        mj = load_mujoco(mjcf_string(name, tilt=tilt, limits=False, contact=False))
        d = mujoco.MjData(mj)
        perm = joint_permutation(mj, m.joint_names)
        for _ in range(5):
            q, v = m.random_state(rng, speed=2.0)
            d.qpos[perm], d.qvel[perm] = q, v
            mujoco.mj_forward(mj, d)
            a = m.forward_dynamics(q, v, np.zeros(m.n))
            assert np.abs(d.qacc[perm] - a).max() <= 1e-9 * np.abs(a).max()
            d.qvel[:] = 0.0
            mujoco.mj_forward(mj, d)  # at rest qfrc_bias is gravity alone: G(q) minus the springs
            grav, grav0 = (mm.gravity_torque(q) - mm.extras.stiffness * q for mm in (m, m0))
            assert np.allclose(d.qfrc_bias[perm], grav, rtol=1e-9, atol=1e-12)
            assert np.abs(grav - grav0).max() > 0.03 * np.abs(grav).max()  # sin 3 deg = 0.052


@pytest.mark.parametrize("name", ["finger3", "hand"])
def test_tendon_rotor_is_J_m_S_T_S(name, rng):
    """tendon_rotor: MuJoCo's full mass matrix = the library's A(q) + J_m S^T S (S the transmission, the thumb's
    ab/adduction row included), not the diagonal N^2 J_m of rotor_inertia."""
    p = ad.load_params()
    m = ad.Model.alpes(name)
    S = m.transmission.S
    mj = load_mujoco(mjcf_string(name, tendon_rotor=True, limits=False, contact=False))
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, m.joint_names)
    dof = np.array([mj.jnt_dofadr[mj.joint(j).id] for j in m.joint_names])
    for _ in range(3):
        q, _ = m.random_state(rng)
        d.qpos[perm] = q
        mujoco.mj_forward(mj, d)
        M = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, d, M)
        want = m.inertia_matrix(q) + p.J_m * S.T @ S
        assert np.allclose(M[np.ix_(dof, dof)], want, rtol=1e-12, atol=1e-18)
    off = (S.T @ S)[0, 1]
    assert off != 0  # the off-diagonal entries are what rotor_inertia misses


def test_cli_mjcf_effects(capsys):
    assert main(["mjcf", "--model", "finger3", "--stiction", "--tendon-stiffness", "4e4", "--tendon-damping", "2",
                 "--tilt", "3"]) == 0
    out = capsys.readouterr().out
    assert out == mjcf_string("finger3", stiction=STICTION_TIMECONST, tendon_stiffness=4e4, tendon_damping=2.0,
                              tilt=np.radians(3.0))
    assert main(["mjcf", "--model", "hand", "--tendon-rotor"]) == 0
    assert capsys.readouterr().out == mjcf_string("hand", tendon_rotor=True)
