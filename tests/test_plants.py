"""MuJoCo recording plants (alpes_dyn.control.plants) against independent references: the library's own
simulator for the plant with the model's structure, the sensors' documented laws, the rest of the elastic
tendon, the experiment's torque as experiment() applies it. Short runs (0.3 s)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.control.plants import PlantEffects, mujoco_recording, plant_mjcf, plant_model
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, experiment_torque
from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
from alpes_dyn.model.mjcf import tilted_gravity
from alpes_dyn.simulation.integrate import simulate

mujoco = pytest.importorskip("mujoco")

DT = 1e-3


def _torque(duration: float = 0.3) -> np.ndarray:
    t = DT * np.arange(int(round(duration / DT)) + 1)
    return (0.022 + 0.006 * np.sin(2 * np.pi * 3.0 * t) + 0.003 * np.sin(2 * np.pi * 11.0 * t))[:, None]


def test_plant_with_the_model_structure_is_the_library_simulator():
    """No effect: MuJoCo (RK4 0.1 ms, the smooth friction law by the passive callback) and the library's RK4 at
    0.1 ms on Model.alpes(friction=True) give the same joint angles (1e-6 rad over 0.3 s); the callback is gone
    after the run."""
    m = ad.Model.alpes("finger3", friction=True)
    u = _torque()
    rec = mujoco_recording("finger3", None, u, DT, encoder_noise_counts=0.0, torque_noise=0.0)
    q0 = m.static_equilibrium(m.transmission.joint_torque(u[0]))
    sim = simulate(m, np.r_[q0, np.zeros(3)], np.repeat(u[:-1], 10, axis=0), 0.3, 1e-4, "rk4", input="motor",
                   output="encoder")
    q_lib = sim.x[::10, :3]
    assert np.ptp(rec.true_q[:, 0]) > 0.05  # it moves
    assert np.abs(rec.true_q - q_lib).max() < 1e-6
    assert mujoco.get_mjcb_passive() is None


def test_sensors_torque_constant_and_encoder_offset():
    """Noise off: encoder counts = round(S q / step + offset) (the rigid tendon's rotor is S q), the recorded torque
    = (1 + e) x the true one exactly; the recording round-trips through the CSV format identify reads."""
    eff = PlantEffects(torque_constant_error=0.05, encoder_offset=3.3)
    u = _torque()
    rec = mujoco_recording("finger3", None, u, DT, effects=eff, encoder_noise_counts=0.0, torque_noise=0.0)
    m = ad.Model.alpes("finger3")
    step = 2 * np.pi / m.transmission.counts_per_rev
    qm = rec.true_q @ m.transmission.S.T
    exact = qm / step + 3.3
    assert np.abs(rec.encoder - exact).max() <= 0.5 + 1e-9  # rounding (a tie may flip: sensor vs S q by 1e-16)
    assert np.mean(rec.encoder == np.round(exact)) > 0.99
    assert np.array_equal(rec.torque, 1.05 * u)
    assert rec.gravity is None


def test_recording_round_trip(tmp_path):
    rec = mujoco_recording("finger3", None, _torque(0.2), DT, seed=3)
    back = read_recording(write_recording(rec, tmp_path / "r.csv"), ad.Model.alpes("finger3"))
    assert np.array_equal(back.encoder, rec.encoder) and np.allclose(back.true_q, rec.true_q, rtol=1e-15)
    noise = rec.torque - _torque(0.2)
    assert 3e-4 < noise.std() < 7e-4  # the 5e-4 N m sensor noise


def test_elastic_tendon_starts_at_rest_with_the_cable_stretched():
    """Series-elastic tendon under a constant torque from its rest: the joints stay at the rigid model's rest
    (2e-6 rad over 0.3 s), the encoder reads the rotor, S q + tau_m / (r_m^2 k_t) (the static stretch)."""
    p = ad.load_params()
    k_t = 1.2e4
    u = np.full((301, 1), 0.022)
    eff = PlantEffects(tendon_stiffness=k_t, tendon_damping=5.0)
    rec = mujoco_recording("finger3", p, u, DT, effects=eff, encoder_noise_counts=0.0, torque_noise=0.0)
    m = plant_model("finger3", p, eff)
    q_rest = m.static_equilibrium(m.transmission.joint_torque(u[0]))
    assert np.abs(rec.true_q - q_rest).max() < 2e-6
    step = 2 * np.pi / m.transmission.counts_per_rev
    rotor = float(m.transmission.S[0] @ q_rest) + 0.022 / (p.r_m**2 * k_t)
    assert np.all(rec.encoder == np.round(rotor / step))
    assert rotor - float(m.transmission.S[0] @ q_rest) > 20 * step  # the stretch is seen by the encoder


def test_torque_delay_shifts_the_recorded_torque_by_whole_samples_and_nothing_else():
    """A torque measured 2 samples late: the recorded torque is the true one of 2 samples before (the first rows
    repeat the first), exactly with the noise off; the encoder, which sees the applied torque, is unchanged."""
    u = _torque()
    kw = dict(encoder_noise_counts=0.0, torque_noise=0.0)
    rec = mujoco_recording("finger3", None, u, DT, **kw)
    late = mujoco_recording("finger3", None, u, DT, effects=PlantEffects(torque_delay=2), **kw)
    assert np.array_equal(late.torque[2:], u[:-2]) and np.array_equal(late.torque[:2], u[[0, 0]])
    assert np.array_equal(late.encoder, rec.encoder) and np.array_equal(late.true_q, rec.true_q)


def test_tendon_dead_band_is_an_encoder_shift_while_the_cable_is_taut():
    """A cable with play delta (m) under a torque that moves the finger but keeps the cable taut (0.022 +- 0.008 N m at
    3 Hz, the experiment's range), from its rest: the joints move as without the play (the tension is the same), the
    rotor turned further by delta / r_m all along (the slack taken up first). So a taut cable's slack is the encoder's
    offset, what ``--effects auto`` fits for it (:mod:`alpes_dyn.estimation.identification.effects`)."""
    p = ad.load_params()
    delta = p.r_m * np.radians(0.5)  # 0.5 degree of backlash at the motor shaft
    u = (0.022 + 0.008 * np.sin(2 * np.pi * 3.0 * DT * np.arange(301)))[:, None]
    kw = dict(encoder_noise_counts=0.0, torque_noise=0.0)
    tight = PlantEffects(tendon_stiffness=1.2e4, tendon_damping=5.0)
    rec = mujoco_recording("finger3", p, u, DT, effects=tight, **kw)
    slack = mujoco_recording("finger3", p, u, DT, effects=PlantEffects(tendon_stiffness=1.2e4, tendon_damping=5.0,
                                                                       tendon_dead_band=delta), **kw)
    m = plant_model("finger3", p, tight)
    step = 2 * np.pi / m.transmission.counts_per_rev
    assert np.abs(slack.true_q - rec.true_q).max() < 2e-6
    assert np.ptp(rec.true_q.sum(axis=1)) > np.radians(5.0)  # the finger moves
    assert np.abs((slack.encoder - rec.encoder) * step - np.radians(0.5)).max() <= step + 1e-12


def test_tilted_plant_rests_where_the_tilted_model_does():
    eff = PlantEffects(tilt=np.radians(3.0))
    m = plant_model("finger3", None, eff)
    assert np.allclose(m.gravity, tilted_gravity(ad.load_params().gravity, np.radians(3.0)))
    u = np.full((201, 1), 0.022)
    rec = mujoco_recording("finger3", None, u, DT, effects=eff, encoder_noise_counts=0.0, torque_noise=0.0)
    q_rest = m.static_equilibrium(m.transmission.joint_torque(u[0]))
    assert np.abs(rec.true_q - q_rest).max() < 2e-6
    level = ad.Model.alpes("finger3").static_equilibrium(m.transmission.joint_torque(u[0]))
    assert np.abs(q_rest - level).max() > 0.01
    assert 'gravity="' in plant_mjcf("finger3", None, eff)


def test_experiment_torque_is_the_experiments():
    """experiment_torque gives the torque experiment() records (minus its 5e-4 N m noise) and its initial state;
    with a tilted true gravity the bias is trimmed on the tilted finger: the same encoder reading at rest."""
    design = ExperimentDesign(duration=0.5, torque_amplitude=0.004)  # no amplitude search: a fast test
    p = ad.load_params()
    t, u, x0 = experiment_torque("finger3", p, design)
    rec = experiment("finger3", p, design, seed=2)
    assert np.array_equal(rec.t, t) and np.array_equal(rec.true_q[0], x0[:3])
    assert 4e-4 < np.std(rec.torque - u) < 6e-4 and abs(np.mean(rec.torque - u)) < 1e-4
    g = tilted_gravity(p.gravity, np.radians(3.0))
    _, u_t, x0_t = experiment_torque("finger3", p, design, true_gravity=g)
    S = ad.Model.alpes("finger3").transmission.S
    assert float(S[0] @ x0_t[:3]) == pytest.approx(float(S[0] @ x0[:3]), abs=1e-6)
    assert abs(u_t[0, 0] - u[0, 0]) > 1e-4  # a different bias holds it there


def test_elastic_tendon_encoder_is_the_compliance_model_while_moving():
    """The library's tendon compliance (the series-elastic tendon's quasi-static limit, y = S q + C tau_m with
    C = 1 / (r_m^2 k_t)) against MuJoCo's rotor on its elastic cable under a moving torque (3 and 11 Hz, the
    rotor on the cable at 110 Hz): from MuJoCo's own joint angles the model gives MuJoCo's encoder within 5 counts,
    1.5 on average (measured 4.3 and 1.5: quantisation, and the rotor's lag behind the torque), where the rigid
    tendon misses the stretch (about 300 counts) by more than 170 counts everywhere."""
    p = ad.load_params()
    k_t = 1.2e4
    u = _torque(0.3)
    eff = PlantEffects(tendon_stiffness=k_t, tendon_damping=2.0)
    rec = mujoco_recording("finger3", p, u, DT, effects=eff, encoder_noise_counts=0.0, torque_noise=0.0)
    C = 1.0 / (p.r_m**2 * k_t)
    spec = ad.Model.alpes("finger3").spec
    from dataclasses import replace

    from alpes_dyn.model.spec import Motor
    motors = tuple(Motor(mo.name, mo.joints, mo.rotor_inertia, C) for mo in spec.motors)
    m = ad.Model(ad.Model.alpes("finger3").urdf, replace(spec, motors=motors))
    assert m.transmission.tendon_compliance.tolist() == [C] and m.transmission.elastic
    step = 2 * np.pi / m.transmission.counts_per_rev
    y = rec.encoder[:, 0] * step
    model_err = np.abs(m.transmission.encoder_angles(rec.true_q, u)[:, 0] - y) / step
    rigid_err = np.abs(rec.true_q @ m.transmission.S[0] - y) / step
    assert model_err[20:].max() < 5.0 and model_err[20:].mean() < 2.0 and rigid_err.min() > 170
    assert np.allclose(m.transmission.unstretched(m.transmission.encoder_angles(rec.true_q, u), u),
                       rec.true_q @ m.transmission.S.T, rtol=0, atol=1e-15)


def test_dither_keeps_every_joint_sliding_on_a_stick_slip_plant():
    """The experiment's dither (20 breakaway torques at 20 Hz, :func:`dither_amplitude`): 20 max_j F_s_j / |S_j| on
    finger3 (a closed form), a line of the design; on MuJoCo's stick-slip finger (``frictionloss``, a stiff
    constraint) the multisine alone leaves q_3 stuck (|qd_3| < 0.01 rad/s) on a large share of the samples, with
    the dither on under 2 % of them on every joint."""
    from alpes_dyn.estimation.experiments.experiment import dither_amplitude
    from alpes_dyn.model.mjcf import STICTION_TIMECONST

    p = ad.load_params()
    m = ad.Model.alpes("finger3", friction=True)
    design = ExperimentDesign(duration=2.0)
    S = m.transmission.S
    assert dither_amplitude(m, design) == pytest.approx([20.0 * np.max(m.extras.coulomb / np.abs(S[0]))], rel=1e-12)
    assert design.lines == design.frequencies + (20.0,)
    assert ExperimentDesign(dither=0.0).lines == design.frequencies
    eff = PlantEffects(stiction=STICTION_TIMECONST)
    stuck = {}
    for d in (0.0, 20.0):
        des = ExperimentDesign(duration=2.0, dither=d)
        _, u, x0 = experiment_torque("finger3", p, des)
        assert np.ptp(u) > 0
        rec = mujoco_recording("finger3", p, u, des.dt, effects=eff, q0=x0[:3], encoder_noise_counts=0.0,
                               torque_noise=0.0)
        v = np.diff(rec.true_q, axis=0) / des.dt
        stuck[d] = (np.abs(v[200:]) < 0.01).mean(axis=0)  # after the first 0.2 s
    assert stuck[0.0][2] > 0.2
    assert np.all(stuck[20.0] < 0.02)


def _tilted_thumb():
    """The thumb of hand seed 5 (its chain drawn +-20 %), its palm 3 degrees off: the MuJoCo plant's effects and
    the gravity it feels."""
    import math

    from alpes_dyn.estimation.experiments.experiment import perturbed_params

    true = perturbed_params(ad.load_params(), spread=0.2, seed=5, chains="thumb")
    eff = PlantEffects(tilt=math.radians(3.0))
    return true, eff, plant_model("thumb", true, eff).gravity


def test_thumb_abduction_gets_no_dither_and_its_trimmed_torque_holds_it_on_a_tilted_palm():
    """The thumb's ab/adduction (no spring) is held only by its dry friction: the dither is 20 breakaway torques on
    the flexion motor (a closed form) and none on the ab/adduction's; the bias trimmed on the tilted thumb (its
    other parts constant: no multisine, no dither) holds it on MuJoCo's plant, which computes gravity on its own:
    under 0.05 degree of drift in 1 s, where the untrimmed bias (the gravity torque of the level palm, 0 there)
    let it creep 1.1 degrees (measured) under the smooth friction law."""
    from alpes_dyn.estimation.experiments.experiment import dither_amplitude

    m = ad.Model.alpes("thumb", friction=True)
    S = m.transmission.S
    flexion = [m.joint_index("thumb_j1"), m.joint_index("thumb_j2")]
    assert dither_amplitude(m, ExperimentDesign()) == pytest.approx(
        [20.0 * np.max(m.extras.coulomb[flexion] / np.abs(S[0, flexion])), 0.0], rel=1e-12, abs=0.0)
    true, eff, g = _tilted_thumb()
    des = ExperimentDesign(duration=1.0, torque_amplitude=0.0, dither=0.0)
    _, u, x0 = experiment_torque("thumb", true, des, true_gravity=g)
    assert np.ptp(u, axis=0) == pytest.approx([0.0, 0.0], abs=1e-15)
    assert abs(u[0, 1]) > 5e-5  # the tilt's torque at mid-range (1.2e-4 N m), balanced
    rec = mujoco_recording("thumb", true, u, des.dt, effects=eff, q0=x0[:3], encoder_noise_counts=0.0,
                           torque_noise=0.0)
    assert x0[0] == pytest.approx(np.pi / 4, abs=1e-12)  # placed mid-range
    assert np.degrees(np.abs(rec.true_q[:, 0] - x0[0]).max()) < 0.05


def test_thumb_experiment_keeps_the_abduction_mid_range_on_a_tilted_palm():
    """The identification experiment's torque (1 s) on MuJoCo's thumb with its palm 3 degrees off: the
    ab/adduction stays within 5 degrees of mid-range (measured 42.1-45.0), where with the dither on it and the
    level palm's bias it reached its 0 degree stop within the second (-1.7 degrees, measured)."""
    true, eff, g = _tilted_thumb()
    des = ExperimentDesign(duration=1.0)
    _, u, x0 = experiment_torque("thumb", true, des, true_gravity=g)
    rec = mujoco_recording("thumb", true, u, des.dt, effects=eff, q0=x0[:3], encoder_noise_counts=0.0,
                           torque_noise=0.0)
    abd = np.degrees(rec.true_q[:, 0])
    assert np.ptp(np.degrees(rec.true_q[:, 1:]), axis=0).min() > 20  # the flexion joints swing
    assert abd.min() > 40 and abd.max() < 50


def test_turned_plant_is_the_library_simulator_turned_at_the_same_sample():
    """gravity= (issue 38's two-orientation record): MuJoCo turned from palm up to hung fingers down at sample 150
    and the library's RK4 integrating the two orientations in turn from the same state give the same joint angles
    (1e-6 rad over 0.3 s), the state carrying on through the turn (the finger swings off: the turn is seen)."""
    from alpes_dyn.model.mjcf import hanging_gravity

    m = ad.Model.alpes("finger3", friction=True)
    u = _torque()
    g_hung = hanging_gravity(m.gravity)
    G = np.repeat(np.asarray(m.gravity, dtype=float)[None], u.shape[0], axis=0)
    G[150:] = g_hung
    rec = mujoco_recording("finger3", None, u, DT, encoder_noise_counts=0.0, torque_noise=0.0, gravity=G)
    q0 = m.static_equilibrium(m.transmission.joint_torque(u[0]))
    first = simulate(m, np.r_[q0, np.zeros(3)], np.repeat(u[:150], 10, axis=0), 0.15, 1e-4, "rk4", input="motor")
    hung = m.copy(gravity=g_hung)
    second = simulate(hung, first.x[-1], np.repeat(u[150:-1], 10, axis=0), 0.15, 1e-4, "rk4", input="motor")
    q_lib = np.concatenate([first.x[::10, :3], second.x[10::10, :3]])
    assert rec.gravity is None and rec.true_q.shape == (301, 3)
    assert np.abs(rec.true_q[200] - rec.true_q[150]).max() > 0.05  # it swings after the turn
    assert np.abs(rec.true_q - q_lib).max() < 1e-6
    with pytest.raises(ad.InputError, match=r"gravity: expected finite gravity vectors .* shape \(301, 3\)"):
        mujoco_recording("finger3", None, u, DT, gravity=G[:-1])


def test_turned_experiment_runs_each_orientation_trimmed_in_it():
    """A design with two orientations (palm up, then hung): the torque's second half is the experiment trimmed in
    the hung orientation (its bias differs from palm up's), and each half starts its multisine at the segment's
    first sample; orientation_segments splits the record evenly."""
    from alpes_dyn.estimation.experiments.experiment import orientation_segments
    from alpes_dyn.model.mjcf import hanging_gravity

    p = ad.load_params()
    level = ExperimentDesign(duration=0.5, torque_amplitude=0.004)
    hung = tuple(float(x) for x in hanging_gravity(p.gravity))
    both = dataclasses.replace(level, orientations=(tuple(level.orientations[0]), hung))
    seg = orientation_segments(both)
    assert seg.shape == (501,) and seg[250] == 0 and seg[251] == 1 and np.all(np.diff(seg) >= 0)
    _, u, x0 = experiment_torque("finger3", p, both)
    _, u_level, x0_level = experiment_torque("finger3", p, dataclasses.replace(level, duration=0.25))
    _, u_hung, _ = experiment_torque("finger3", p, dataclasses.replace(level, duration=0.25, orientations=(hung,)))
    np.testing.assert_array_equal(x0, x0_level)
    # the halves: each the single-orientation torque of that orientation, restarted (the trim's peak over the
    # segment: the same bias where the shorter design's amplitude search agrees)
    assert np.abs(u[:251] - u_level).max() < 1e-9
    assert np.abs(u[251:] - u_hung[:250]).max() < 1e-9
    assert abs(np.mean(u[251:]) - np.mean(u[:251])) > 1e-3  # hung asks for another bias
