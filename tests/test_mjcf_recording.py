"""``mjcf_recording``: MuJoCo stepped on the MJCF of any robot (what ``alpes-dyn mjcf`` writes), recorded through the
library's encoder and torque sensors (issue 17: the EKF's goal on a MuJoCo plant of the exported MJCF).

References: the library's own simulator on the same robot (a different integrator of the same equations: MuJoCo's
RK4 at 0.1 ms on its own mass matrix, bias forces and passive springs), and the encoder's law by hand
(counts = round(S q / (2 pi / counts_per_rev)) without noise)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.spec import TransmissionSpec
from alpes_dyn.simulation.integrate import simulate

mujoco = pytest.importorskip("mujoco")
from alpes_dyn.control.plants import mjcf_recording  # noqa: E402

SPEC = ('[[motor]]\nname = "flexor"\njoints = { j1 = 2.0, j2 = 2.0, j3 = 2.0 }\n\n'
        "[stiffness]\nj1 = 0.04\nj2 = 0.05\nj3 = 0.06\n\n[viscous]\nj1 = 1e-4\nj2 = 1e-4\nj3 = 1e-4\n")


def _robot() -> ad.Model:
    return ad.Model(ad.urdf_string("finger3").replace('name="alpes_finger3"', 'name="tendon_robot"', 1),
                    TransmissionSpec.from_toml(SPEC))


def test_mjcf_recording_follows_our_simulator_and_the_encoder_law(tmp_path):
    """A tendon finger (finger3's URDF, one motor over its three joints, springs, viscous friction), its exported MJCF
    written as a file, a torque ramp 0.02 -> 0.025 N m replayed for 0.5 s from the rest under 0.02 N m (inside the joint
    ranges throughout: no stop acts): MuJoCo's joints follow our RK4 to 1e-6 rad; without noise the counts are round(S q / step) of MuJoCo's joints and the torque the one given."""
    m = _robot()
    path = tmp_path / "plant.xml"
    path.write_text(m.to_mjcf())
    t = np.arange(501) * 1e-3
    u = (0.02 + 0.01 * t)[:, None]
    rec = mjcf_recording(path, m, u, 1e-3, encoder_noise_counts=0.0, torque_noise=0.0)
    x0 = np.concatenate([m.static_equilibrium(m.transmission.joint_torque(u[0]), np.zeros(m.n)), np.zeros(m.n)])
    ours = simulate(m, x0, u[:-1], duration=0.5, dt=1e-3, input="motor", output="joints", joint_range="ignore")
    assert np.max(np.abs(rec.true_q - ours.x[:, : m.n])) < 1e-6
    assert np.ptp(rec.true_q[:, 0]) > 0.05  # it moved: the comparison is not of two rests
    assert np.all(rec.true_q > m.lower) and np.all(rec.true_q < m.upper)
    step = 2 * math.pi / 4096
    np.testing.assert_array_equal(rec.encoder[:, 0], np.round(rec.true_q @ m.transmission.S[0] / step))
    np.testing.assert_array_equal(rec.torque, u)
    assert rec.motor_names == ("flexor",) and rec.joint_names == m.joint_names


def test_mjcf_recording_turned_mid_record_follows_our_simulator_turned():
    """gravity= (the foreign finger's two-orientation record): the same tendon finger palm up for 0.25 s, then
    turned so that gravity runs along its fingers-down axis (+x), MuJoCo's state carrying on through the turn;
    our RK4 integrating the two orientations in turn from the same state: the same joints to 1e-6 rad, and the turn
    is seen (the finger swings off where it was). A gravity of the wrong length is refused naming it."""
    m = _robot()
    u = np.full((501, 1), 0.02)
    G = np.repeat(np.array([[0.0, 0.0, -9.81]]), 501, axis=0)
    G[250:] = (9.81, 0.0, 0.0)
    rec = mjcf_recording(m.to_mjcf(), m, u, 1e-3, encoder_noise_counts=0.0, torque_noise=0.0, gravity=G)
    x0 = np.concatenate([m.static_equilibrium(m.transmission.joint_torque(u[0]), np.zeros(m.n)), np.zeros(m.n)])
    first = simulate(m, x0, u[:250], duration=0.25, dt=1e-3, input="motor", output="joints", joint_range="ignore")
    turned = m.copy(gravity=np.array([9.81, 0.0, 0.0]))
    second = simulate(turned, first.x[-1], u[250:-1], duration=0.25, dt=1e-3, input="motor", output="joints",
                      joint_range="ignore")
    ours = np.concatenate([first.x[:, : m.n], second.x[1:, : m.n]])
    assert rec.gravity is None and rec.true_q.shape == (501, m.n)
    assert np.abs(rec.true_q[400] - rec.true_q[250]).max() > 0.01  # it swings after the turn
    assert np.max(np.abs(rec.true_q - ours)) < 1e-6
    with pytest.raises(ad.InputError, match=r"gravity: expected finite gravity vectors .* shape \(501, 3\)"):
        mjcf_recording(m.to_mjcf(), m, u, 1e-3, gravity=G[:-1])


def test_exported_stiction_holds_a_joint_below_its_dry_friction():
    """model_mjcf(stiction=) on a URDF + spec robot (``alpes-dyn mjcf --stiction``): the joints with Coulomb friction
    (j1, j3) get MuJoCo's solreffriction of that time constant and solimpfriction 0.999 (the Alpes writer's), the
    other keeps MuJoCo's defaults (0.02 s; 0.9, 0.95). A torque step of 0.0005 N m (0.001 N m on each joint through
    the ratio 2, a fifth of F_s = 0.005 N m) held for 0.2 s: with stiction j1 stays stuck (measured 9.5e-5 deg; 0.010
    deg with the time constant alone), with MuJoCo's default constraint it creeps (0.39 deg) -- the soft friction the
    realism study's plants avoid."""
    spec = SPEC + "\n[coulomb]\nj1 = 0.005\nj3 = 0.005\n"
    m = ad.Model(ad.urdf_string("finger3"), TransmissionSpec.from_toml(spec))
    u = np.full((301, 1), 0.02)
    u[100:] = 0.0205
    moved = {}
    for st in (None, 5e-4):
        text = m.to_mjcf(stiction=st)
        mm = mujoco.MjModel.from_xml_string(text)
        np.testing.assert_allclose(mm.dof_solref[:, 0], [0.02, 0.02, 0.02] if st is None else [5e-4, 0.02, 5e-4])
        np.testing.assert_allclose(mm.dof_solimp[:, 0], [0.9, 0.9, 0.9] if st is None else [0.999, 0.9, 0.999])
        rec = mjcf_recording(text, m, u, 1e-3, encoder_noise_counts=0.0, torque_noise=0.0)
        moved[st] = math.degrees(abs(rec.true_q[300, 0] - rec.true_q[100, 0]))
    assert moved[5e-4] < 1e-3 and moved[None] > 0.2
    with pytest.raises(ad.InputError, match=r"stiction: expected a positive time constant in s"):
        m.to_mjcf(stiction=0.0)
