"""The MuJoCo stand-in (alpes_dyn.bench.mujoco_hand) against an independent path: the recording plant of
alpes_dyn.control.plants.mujoco_recording, which replays a whole torque record at once; the block scene presses its
block; the interface's checks; no parameter shows through the stand-in's public attributes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pytest.importorskip("mujoco")

from alpes_dyn.bench import HardwareInterface, MujocoHand, PlantEffects, play, real_hand_effects  # noqa: E402
from alpes_dyn.bench.effects import CABLE_STIFFNESS, cable_damping  # noqa: E402
from alpes_dyn.bench.mujoco_hand import SETTLE_S, scoring_truth  # noqa: E402
from alpes_dyn.bench.mujoco_plant import plant_model  # noqa: E402
from alpes_dyn.control.plants import mujoco_recording  # noqa: E402
from alpes_dyn.errors import InputError  # noqa: E402
from alpes_dyn.model.params import HandParams, load_params  # noqa: E402
from alpes_dyn.model.robot import Model  # noqa: E402

QUIET = {"encoder_noise_counts": 0.0, "torque_noise": 0.0, "force_noise": 0.0}


def _rest(model: str, effects: PlantEffects | None) -> np.ndarray:
    """The joints' rest under springs and gravity, motor off, stops ignored: the recording plant's default start,
    given to the stand-in as ``q0`` (its own default settles against the stops first)."""
    m = plant_model(model, None, effects)
    return m.static_equilibrium(None, np.zeros(m.n), fixed=m.springless_joints, tau_m=np.zeros(m.transmission.n_motors))


def _profile(n: int = 600, top: float = 0.02) -> np.ndarray:
    """(n, 1) N m: from 0 (the motor at rest) up a 150 ms ramp to ``top``, then a 7 Hz swing of 20 % around it."""
    t = 1e-3 * np.arange(n)
    return (top * np.minimum(t / 0.15, 1.0) * (1 + 0.2 * np.sin(2 * np.pi * 7 * t)))[:, None]


def _recorded(u: np.ndarray, effects: PlantEffects | None, **kw) -> object:
    """mujoco_recording of what the stand-in's motor gives for the commands ``u``: u / (1 + e), the driver's constant
    (1 + e) times the true one (the last command held one more row: a recording's last row is read only)."""
    e = effects or PlantEffects()
    applied = np.vstack([u, u[-1:]]) / (1.0 + e.torque_constant_error)
    return mujoco_recording("finger3", None, applied, 1e-3, effects=effects, **kw)


@pytest.mark.parametrize("effects", [real_hand_effects(), None], ids=["real_hand", "none"])
def test_free_scene_reads_what_the_recording_plant_records(effects):
    """Noise off: the stand-in's counts are the recording's, exactly; its torque at tick k + 1 is the recording's at
    k (the reading of a period comes at the tick that ends it; the recording pairs it with the period's start), to
    1e-12, with the torque delay and the torque constant's error of a real hand, or the smooth-friction callback."""
    u = _profile()
    out = play(MujocoHand("finger3", effects=effects, q0=_rest("finger3", effects), **QUIET), u)
    rec = _recorded(u, effects, encoder_noise_counts=0.0, torque_noise=0.0)
    assert out["counts"].shape == rec.encoder.shape == (601, 1)
    np.testing.assert_array_equal(out["counts"], rec.encoder)
    np.testing.assert_allclose(out["torque"][1:], rec.torque[:-1], rtol=0, atol=1e-12)
    assert out["torque"][0, 0] == 0.0 and np.isnan(out["force"]).all()
    np.testing.assert_allclose(out["t"], 1e-3 * np.arange(601), rtol=0, atol=1e-15)
    assert np.ptp(out["counts"]) > 500  # the finger moved: the comparison is not of a resting plant
    if effects is not None:  # the torque reads (1 + e) x (u / (1 + e)) = the command, one period late (delay 1)
        np.testing.assert_allclose(out["torque"][2:], u[:-1], rtol=0, atol=1e-12)


def test_the_hands_chains_read_what_each_chains_recording_plant_records():
    """The hand (free scene, a real hand's effects, noise off): the index's and the thumb's counts and torques those of
    the recording plant of that chain alone (finger3 on the index's parameters, the thumb with its abduction motor at
    0), the chains being apart in MuJoCo: to a count at a rounding's edge, the torques to 1e-12."""
    e, u = real_hand_effects(), _profile(300)
    hw = MujocoHand("hand", effects=e, q0=_rest("hand", e), **QUIET)
    assert hw.motor_names == ("index", "middle", "ring", "little", "thumb", "thumb_abduction")
    out = play(hw, np.hstack([np.repeat(u, 5, axis=1), 0 * u]))
    applied = np.vstack([u, u[-1:]]) / (1.0 + e.torque_constant_error)
    quiet = {"encoder_noise_counts": 0.0, "torque_noise": 0.0, "effects": e}
    index = mujoco_recording("finger3", None, applied, chain="index", **quiet)
    thumb = mujoco_recording("thumb", None, np.hstack([applied, 0 * applied]), **quiet)
    for rec, cols in ((index, [0]), (thumb, [4, 5])):
        d = out["counts"][:, cols] - rec.encoder
        assert np.abs(d).max() <= 1 and (d == 0).mean() > 0.99
        np.testing.assert_allclose(out["torque"][1:, cols], rec.torque[:-1], rtol=0, atol=1e-12)
    assert np.ptp(out["counts"][:, :5], axis=0).min() > 500 and np.isnan(out["force"]).all()


def test_free_scene_noise_is_seeded_and_of_the_recordings_size():
    """Noise on: the same seed gives the same readings, another seed others; the torque's and the encoder's noise
    (about the noise-free readings) of the size of the recording plant's, 5e-4 N m and sqrt(0.5^2 + 1/12) counts."""
    e, u = real_hand_effects(), _profile(800)
    q0 = _rest("finger3", e)
    a, b = play(MujocoHand(effects=e, seed=4, q0=q0), u), play(MujocoHand(effects=e, seed=4, q0=q0), u)
    c = play(MujocoHand(effects=e, seed=5, q0=q0), u)
    for key in ("counts", "torque"):
        np.testing.assert_array_equal(a[key], b[key])
    assert not np.array_equal(a["torque"], c["torque"])
    clean = play(MujocoHand(effects=e, q0=q0, **QUIET), u)
    rec, rec0 = _recorded(u, e, seed=4), _recorded(u, e, encoder_noise_counts=0.0, torque_noise=0.0)
    mine = (np.std(a["torque"] - clean["torque"]), np.std(a["counts"] - clean["counts"]))
    theirs = (np.std(rec.torque - rec0.torque), np.std(rec.encoder - rec0.encoder))
    assert mine[0] == pytest.approx(5e-4 * 1.05, rel=0.1) and mine[0] == pytest.approx(theirs[0], rel=0.15)
    assert mine[1] == pytest.approx(np.sqrt(0.25 + 1 / 12), rel=0.15) and mine[1] == pytest.approx(theirs[1], rel=0.2)


def test_block_scene_presses_and_checks_its_commands():
    """The block scene: no force hanging free, above 0.2 N once a 0.03 N m pull (half again the 0.012 N m that
    brings the fingertip to the block) has pressed it; the commands refused with one line naming ``command``."""
    hw = MujocoHand("finger3", scene="block", seed=1)
    assert hw.read().force < 0.02
    u = np.concatenate([np.linspace(0.0, 0.03, 300), np.full(200, 0.03)])[:, None]
    out = play(hw, u)
    assert out["force"][-100:].mean() > 0.2 and np.isfinite(out["force"]).all()
    assert out["torque"][-1, 0] == pytest.approx(0.03, abs=3e-3)  # (1 + e) x 0.03 / (1 + e) + noise
    for bad in (-1e-3, np.nan, [0.01, 0.01], [[0.01]], hw.tau_max * 1.01):
        with pytest.raises(InputError) as info:
            hw.write(bad)
        assert str(info.value).startswith("command:") and "\n" not in str(info.value)
    with pytest.raises(InputError, match="^commands:"):
        play(hw, -u)
    with pytest.raises(InputError, match="^commands:"):
        play(hw, np.zeros((3, 2)))
    hw.close()
    with pytest.raises(InputError, match="^write:"):
        hw.write([0.0])


def test_the_stand_in_is_an_interface_that_hides_its_truth(tmp_path):
    """A HardwareInterface whose public attributes hold no parameters: no HandParams, Model or effects, and no
    number of the true file but its encoder and its motor's limit (what a driver shows)."""
    p = dataclasses.replace(load_params(), tau_max=0.06)
    hw = MujocoHand("finger2", p, effects=real_hand_effects(), scene="free")
    assert isinstance(hw, HardwareInterface)
    public = {k: v for k, v in vars(hw).items() if not k.startswith("_")}
    assert set(public) <= {"model", "scene", "period", "motor_names", "counts_per_rev", "tau_max", "closed",
                           "both_ways"}
    assert not any(isinstance(v, (HandParams, Model, PlantEffects)) for v in public.values())
    assert hw.tau_max == 0.06 and hw.counts_per_rev == 4096 and hw.motor_names == ("finger",)
    assert hw.read().counts.shape == (1,) and hw.period == 1e-3


@pytest.mark.parametrize("kw, field", [
    ({"model": "finger4"}, "model"), ({"model": "thumb_abduction"}, "model"), ({"scene": "table"}, "scene"),
    ({"model": "hand", "scene": "block"}, "scene"),
    ({"seed": -1}, "seed"), ({"seed": 1.5}, "seed"), ({"seed": True}, "seed"), ({"effects": "all"}, "effects"),
    ({"effects": 3}, "effects"), ({"encoder_noise_counts": -1.0}, "encoder_noise_counts"),
    ({"force_noise": float("nan")}, "force_noise"), ({"params": 5}, "params"), ({"q0": [0.1]}, "q0"),
    ({"effects": PlantEffects(torque_delay=-1)}, "torque_delay"), ({"rig": "upside"}, "rig"),
    ({"rig": "hanging", "scene": "block"}, "rig")])
def test_bad_constructor_inputs_are_one_line(kw, field):
    with pytest.raises(InputError) as info:
        MujocoHand(**kw)
    assert str(info.value).startswith(f"{field}:") and "\n" not in str(info.value)


def test_real_hand_cable_is_the_realism_studys():
    """The bench's recorded cable, the realism study's derivation on the documented experiment (the same k_t and c_t:
    one real hand for ``--plant-effects all``, the study's ``all`` case and the stand-in)."""
    from alpes_dyn.cli.control_cmds import realism_effects
    from alpes_dyn.studies.realism import cases, rig_design, tendon_stiffness

    k_t, c_t, _ = tendon_stiffness(rig_design("level"))
    assert CABLE_STIFFNESS == pytest.approx(k_t, rel=1e-9) and cable_damping(CABLE_STIFFNESS) == pytest.approx(c_t)
    assert realism_effects() == real_hand_effects()
    study = cases(k_t, c_t)["all"]
    assert dataclasses.replace(study, tendon_stiffness=CABLE_STIFFNESS, tendon_damping=cable_damping(CABLE_STIFFNESS)) \
        == real_hand_effects()


def test_free_finger_starts_settled_against_its_stops():
    """Palm up, the springs' and gravity's rest lies beyond the lower stops (the recording plant starts there); the
    stand-in's default start is the finger left to rest for SETTLE_S against them: every joint within 5 degrees of
    its range, still (the encoder and the joints unchanged over 0.3 s of rest)."""
    free = _rest("finger3", real_hand_effects())
    m = plant_model("finger3")
    assert (free < m.lower - np.radians(10)).any()  # the case this start is for
    hw = MujocoHand("finger3", **QUIET)
    q = scoring_truth(hw)[0]
    assert (q > m.lower - np.radians(5)).all() and (q < m.upper).all()
    out = play(hw, np.zeros((300, 1)))
    assert np.ptp(out["counts"]) <= 2 and np.abs(scoring_truth(hw)[0] - q).max() < np.radians(0.05)
    assert SETTLE_S >= 0.5


def test_hung_on_its_rig_the_finger_rests_along_gravity():
    """rig="hanging": the palm turned -90 degrees (fingers down), the real hand's 3 degree tilt on top: the settled
    finger hangs straight (every joint within 3 degrees of 0, where palm up the springs' rest lies past the stops)."""
    hw = MujocoHand("finger3", rig="hanging", **QUIET)
    q = np.degrees(scoring_truth(hw)[0])
    assert np.abs(q).max() < 3.0, q


def test_palm_up_finger3_sweeps_q1_steeply_but_stably():
    """Palm up, the stand-in's finger3 has no fold (what its calibration relies on, FOLD_WINDOW): ramped slowly
    (0.004 N m/s) through q_1's sweep, 0.021 -> 0.025 -> 0.021 N m, each level held 0.7 s, q_1 lifts off its stop and
    crosses half its range over 0.004 N m (a steep branch, more than 3.5e5 counts per N m), and each level's reading
    is on the way down what it was on the way up within 30 % of the sweep (the joints' dry friction: 360 counts of
    a sweep of 2430 measured; a fold's snap would leave the finger on its upper stop, the whole sweep above)."""
    hw = MujocoHand("finger3", **QUIET)
    play(hw, np.linspace(0.0, 0.019, 1000))
    up, down, q, last = {}, {}, {}, 0.019
    for tau, side in ((0.021, up), (0.023, up), (0.025, up), (0.023, down), (0.021, down)):
        out = play(hw, np.concatenate([np.linspace(last, tau, 500), np.full(700, tau)]))
        side[tau], last = float(np.mean(out["counts"][-200:])), tau
        q.setdefault(tau, np.degrees(scoring_truth(hw)[0]))
    assert up[0.021] < up[0.023] < up[0.025] and (up[0.025] - up[0.021]) / 0.004 > 3.5e5, up
    assert q[0.021][0] > 0.5 and q[0.025][0] > 45.0, q  # q_1 off its 0 stop, then past half its range
    sweep = up[0.025] - up[0.021]
    for tau in (0.021, 0.023):
        assert abs(down[tau] - up[tau]) < 0.3 * sweep, (tau, up, down)
