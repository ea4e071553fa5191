"""The truth of a MuJoCo plant as a parameter file (:mod:`alpes_dyn.bench.truth`): every effect of a plant is in the
file read back with the plant's value -- checked against MuJoCo, not against the writer's own formulas -- or
named; and the EKF with the truth on a MuJoCo stick-slip plant with the rig's effects stays within its bound."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from alpes_dyn.bench.effects import PlantEffects, real_hand_effects
from alpes_dyn.bench.mujoco_plant import plant_mjcf
from alpes_dyn.bench.truth import TORQUE_UNITS, truth_params, write_truth
from alpes_dyn.control.plants import mujoco_recording
from alpes_dyn.errors import InputError
from alpes_dyn.model.mjcf import STICTION_TIMECONST, load_mujoco
from alpes_dyn.model.params import load_params
from alpes_dyn.model.robot import Model
from alpes_dyn.simulation.stick import observer_friction_law
from alpes_dyn.studies.realism import ekf_run

HELD = {"tilt", "encoder_offset", "torque_delay", "tendon_stiffness", "tendon_rotor", "torque_constant_error"}
"""The effects the file holds (each checked below)."""


def test_every_effect_is_in_the_file_or_named(tmp_path):
    """Every field of PlantEffects set (the stiff constraint, then the soft one): each is held (HELD, its value checked) or named in not_held -- a new effect
    that the writer neither holds nor names fails here. The file read back: the gravity is MuJoCo's (the plant's
    MJCF compiled), the delay, the compliance 1 / (k_t r_m^2), the torques' scale 1 + e."""
    e = dataclasses.replace(real_hand_effects(), torque_delay=2)
    true = load_params()
    t = write_truth(true, e, tmp_path / "truth.toml")
    seen = set()
    for plant in (e, dataclasses.replace(e, stiction=None, soft_stiction=True), PlantEffects(tendon_rotor=True)):
        on = {f.name for f in dataclasses.fields(PlantEffects) if getattr(plant, f.name) != f.default}
        named = {n.split(" ")[0] for n in truth_params(true, plant).not_held}
        assert on <= HELD | named and named <= on, (on, named)
        assert truth_params(true, plant).rotor
        seen |= on
    assert seen == {f.name for f in dataclasses.fields(PlantEffects)}
    back = load_params(t.path)
    np.testing.assert_allclose(back.gravity, load_mujoco(plant_mjcf("finger3", true, e)).opt.gravity, atol=1e-12)
    assert back.torque_delay == 2
    g = 1.0 + e.torque_constant_error
    np.testing.assert_allclose(back.tendon_compliance, 1.0 / (e.tendon_stiffness * true.r_m ** 2) / g, rtol=1e-12)
    np.testing.assert_allclose(back.finger.K, g * true.finger.K, rtol=1e-12)
    np.testing.assert_allclose(back.finger.m, g * true.finger.m, rtol=1e-12)
    np.testing.assert_allclose([back.J_m, back.F_s, back.tau_max], [g * true.J_m, g * true.F_s, g * true.tau_max],
                               rtol=1e-12)
    np.testing.assert_allclose(back.finger.L, true.finger.L, rtol=1e-12)  # lengths are not torques
    assert all(back.raw[k].unit not in TORQUE_UNITS for k in ("finger.L", "friction.smooth_velocity"))
    assert truth_params(true).not_held == () and not truth_params(true).rotor  # no effect: the drawn file itself


def test_the_file_rest_and_reading_are_the_plants(tmp_path):
    """MuJoCo's plant (the elastic cable with its rotor, the tilt, the torque constant, the encoder's zero; the
    library's smooth friction: one rest) settled under a torque step: the true file's model at rest under the torque
    *as read* (static_equilibrium; joint 1 held on its stop where MuJoCo's is) has MuJoCo's joint angles, and its encoder reading S q + C tau_read + offset is
    the recorded one, up to the one effect named that shifts it: the cable's slack, r_m radians(0.5) / r_m."""
    e = dataclasses.replace(real_hand_effects(), stiction=None, torque_delay=0)
    true = load_params()
    u = np.concatenate([np.full(200, 8e-3), np.full(1301, 12e-3)])[:, None]  # palm up: joint 1 on its stop
    rec = mujoco_recording("finger3", true, u, 1e-3, effects=e, encoder_noise_counts=0.0, torque_noise=0.0)
    t = write_truth(true, e, tmp_path / "truth.toml")
    model = Model.alpes("finger3", friction=True, rotor_inertia=t.rotor, params=t.path)
    tau_read = rec.torque[-1]
    np.testing.assert_allclose(tau_read, (1 + e.torque_constant_error) * u[-1], rtol=1e-12)
    S = model.transmission.S
    on_stop = [nm for nm, x in zip(model.joint_names, rec.true_q[-1]) if x < 0.01]  # held there by MuJoCo's stop
    assert on_stop == [model.joint_names[0]] and (rec.true_q[-1, 1:] > 0.1).all()
    q = model.static_equilibrium(S.T @ tau_read, q0=rec.true_q[-1], fixed=on_stop)
    np.testing.assert_allclose(q, rec.true_q[-1], atol=1e-3)  # rad (the torque constant left out: 0.02 rad off)
    step = 2 * np.pi / model.transmission.counts_per_rev
    y = model.transmission.encoder_angles(rec.true_q[-1], tau_read) + t.params.finger.encoder_offset
    assert any(n.startswith("tendon_dead_band") for n in t.not_held)
    np.testing.assert_allclose(rec.encoder[-1] * step - y, e.tendon_dead_band / true.r_m, atol=0.6 * step)


def test_bad_input_is_named():
    with pytest.raises(InputError, match="model"):
        truth_params(None, None, model="hand")
    with pytest.raises(InputError, match="torque_delay"):
        truth_params(None, PlantEffects(torque_delay=-1))


def test_the_ekf_with_the_truth_on_a_stick_slip_plant_stays_within_its_bound(tmp_path):
    """finger3 in MuJoCo with stick-slip (the stiff constraint), the rotor on the rigid tendon, the tilt, the
    encoder's zero, the torque constant and a one-sample delay, 3 s of the estimate scenario's torque: the EKF on
    the truth file (its rig side read from the file, the stick-slip law asked for) within 0.3 degree
    RMSE on every joint after 1 s; the drawn parameters alone (no effect in the file) are further off."""
    from alpes_dyn.studies.realism_friction import validation_torque

    e = PlantEffects(stiction=STICTION_TIMECONST, tendon_rotor=True, tilt=math.radians(3.0),
                     torque_constant_error=0.05, encoder_offset=4.0, torque_delay=1)
    true = load_params()
    u = validation_torque(1e-3)[:3001]
    rec = mujoco_recording("finger3", true, u, 1e-3, effects=e, seed=3)
    t = write_truth(true, e, tmp_path / "truth.toml")
    est = ekf_run(rec, str(t.path), None, 1.0, rotor=t.rotor, stops=True, friction_law="stick")
    s = est.settings  # the file's rig side read back, the stick-slip law asked for
    assert s["friction_law"] == "stick" and s["torque_delay_samples"] == 1
    np.testing.assert_allclose(s["encoder_offset_rad"], [4.0 * 2 * np.pi / 4096], rtol=1e-9)
    rmse = np.degrees(est.rmse)
    assert rmse.max() < 0.3, rmse


def test_the_observer_law_follows_the_file(tmp_path):
    """observer_friction_law: the shipped file smooth; a file whose smooth sign is the stick-slip law (identify's
    --effects stiction, the truth of a stiff stiction) smooth too (the stick law is asked for by name); a LuGre file
    lugre; a model without friction smooth."""
    base = load_params()
    assert observer_friction_law(Model.alpes("finger3", friction=True)) == "smooth"
    assert observer_friction_law(Model.alpes("finger3")) == "smooth"
    stiff = write_truth(base, PlantEffects(stiction=STICTION_TIMECONST), tmp_path / "stiff.toml")
    assert observer_friction_law(Model.alpes("finger3", friction=True, params=stiff.path)) == "smooth"
    soft = truth_params(base, PlantEffects(soft_stiction=True))
    assert observer_friction_law(Model.alpes("finger3", friction=True, params=soft.params)) == "smooth"
    lugre = dataclasses.replace(stiff.params, friction_law="lugre")
    assert observer_friction_law(Model.alpes("finger3", friction=True, params=lugre)) == "lugre"


def test_a_urdf_robot_keeps_the_smooth_law():
    """A model without an Alpes parameter file (a URDF robot's spec, whose smooth_velocity 0.01 rad/s is its own
    smoothing) keeps the smooth law by default."""
    m = Model.alpes("finger3", friction=True)
    urdf = Model(m.urdf, dataclasses.replace(m.spec, smooth_velocity=0.01), name="arm")
    assert urdf.params is None and np.any(urdf.extras.coulomb) and urdf.extras.smooth_velocity <= 0.02
    assert observer_friction_law(urdf) == "smooth"


def test_on_a_plant_with_every_effect_the_true_file_is_better_than_the_bare_draw(tmp_path):
    """finger3 in MuJoCo with every effect of a real hand (stick-slip, the elastic cable with its rotor, damping and
    slack, the tilt, the torque constant, the encoder's zero, the delay; real_hand_effects), 4 s of the estimate
    scenario's torque: the EKF on the truth file (its effects in identify's fields) is within 0.5 degree RMSE on
    every joint after 1 s -- the friction study's true file once lacked these effects and was 1.2-1.9 degrees off,
    worse than an identified file that holds them -- and the bare drawn parameters (no effect held) are worse on
    the worst joint."""
    from alpes_dyn.studies.realism_friction import validation_torque

    e = real_hand_effects()
    true = load_params()
    rec = mujoco_recording("finger3", true, validation_torque(1e-3)[:4001], 1e-3, effects=e, seed=7)
    t = write_truth(true, e, tmp_path / "truth.toml")
    bare = write_truth(true, None, tmp_path / "bare.toml")
    rmse = np.degrees(ekf_run(rec, str(t.path), None, 1.0, rotor=t.rotor, stops=True).rmse)
    rmse_bare = np.degrees(ekf_run(rec, str(bare.path), None, 1.0, stops=True).rmse)
    assert rmse.max() < 0.5, rmse
    assert rmse_bare.max() > rmse.max(), (rmse, rmse_bare)
