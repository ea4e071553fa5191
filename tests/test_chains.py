"""The hand chain by chain: per-finger parameters in the file, a finger or the thumb as a model of its own.

References: the hand model (Pinocchio on the whole 15-DoF tree) for the chain models -- on a fixed palm
the chains are dynamically independent, so a chain's mass matrix, gravity and accelerations are the
hand's block; MuJoCo on the exported MJCF for the per-finger values there.
"""

from __future__ import annotations

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.model.stops import JointRangeWarning
from alpes_dyn.errors import ModelError
from alpes_dyn.model.params import Param, chain_params, load_params, params_toml, with_values, write_params

R = "drawn for a test"


def _hand_with_overrides() -> ad.HandParams:
    """The shipped file with the index's springs, masses (inertias with them) and friction, and the ring's
    Coulomb friction of its own."""
    p = load_params()
    f = p.finger
    return with_values(p, {
        "finger.index.K": Param(f.K * np.array([1.15, 0.85, 1.1]), "N m/rad", "identified", R, "", np.full(3, 1e-4)),
        "finger.index.m": Param(f.m * np.array([1.1, 0.9, 1.2]), "kg", "assumed", R),
        "finger.index.I": Param(f.I * np.array([1.1, 0.9, 1.2]), "kg m^2", "assumed", R),
        "finger.index.F_v": Param(np.array([1e-4, 2e-4, 3e-4]), "N m s/rad", "assumed", R),
        "finger.ring.F_s": Param(np.array([4e-4, 5e-4, 6e-4]), "N m", "assumed", R),
    })


@pytest.fixture(scope="module")
def hand_params():
    return _hand_with_overrides()


def test_overrides_round_trip_through_the_file(hand_params, tmp_path):
    p = hand_params
    path = write_params(p, tmp_path / "hand.toml")
    text = path.read_text()
    assert text.index("[finger]") < text.index("[finger.index]") < text.index("[finger.ring]") < text.index("[thumb]")
    assert "[finger.middle]" not in text
    q = load_params(path)
    assert params_toml(q.raw) == params_toml(p.raw)
    assert q.raw["finger.index.K"].source == "identified" and q.raw["finger.index.K"].std.tolist() == [1e-4] * 3
    for name in p.finger_names:
        for k in ("K", "m", "I"):
            assert np.array_equal(getattr(q.chain(name), k), getattr(p.chain(name), k))
    assert np.array_equal(q.chain("index").K, load_params().finger.K * np.array([1.15, 0.85, 1.1]))
    assert q.chain("middle") is q.finger and q.chain("ring").F_s.tolist() == [4e-4, 5e-4, 6e-4]
    assert q.chain("index").F_s is None and q.chain("index").F_v.tolist() == [1e-4, 2e-4, 3e-4]
    # the shipped file has no per-finger values, and the projection on a chain merges the finger's own
    assert not any(k.count(".") == 2 for k in load_params().raw)
    c = chain_params(q, "index")
    assert not any(k.count(".") == 2 for k in c.raw)
    assert np.array_equal(c.finger.K, q.chain("index").K) and np.array_equal(c.raw["finger.m"].value, q.chain("index").m)
    assert load_params(write_params(c, tmp_path / "index.toml")).finger.I.tolist() == q.chain("index").I.tolist()


def test_hand_uses_each_fingers_values(hand_params):
    """Springs, friction and link masses of the hand model and of its URDF are each finger's own."""
    p = hand_params
    h = ad.Model.alpes("hand", friction=True, params=p)
    for name in p.finger_names:
        own = p.chain(name)
        idx = [h.joint_index(f"{name}_j{i}") for i in (1, 2, 3)]
        assert np.array_equal(h.extras.stiffness[idx], own.K)
        assert np.array_equal(h.extras.coulomb[idx], own.F_s if own.F_s is not None else np.full(3, p.F_s))
        assert np.array_equal(h.extras.viscous[idx], own.F_v if own.F_v is not None else np.full(3, p.F_v))
        masses = [h.pin_model.inertias[h.pin_model.getJointId(f"{name}_j{i}")].mass for i in (1, 2, 3)]
        assert np.allclose(masses, own.m, rtol=1e-15)
    assert h.extras.stiffness[h.joint_index("index_j1")] == pytest.approx(0.046, rel=1e-12)


def _block(h: ad.Model, names: tuple[str, ...]) -> np.ndarray:
    return np.array([h.joint_index(j) for j in names])


@pytest.mark.parametrize("chain", ["index", "ring", "thumb"])
def test_chain_model_is_the_hands_block(hand_params, chain, rng):
    """A(q), G(q) (gravity + springs), the Coriolis torques and the forward dynamics (friction on) of the
    chain model equal the hand's block, and the hand has no coupling between chains, for random states,
    palm up and tilted."""
    p = hand_params
    hand = ad.Model.alpes("hand", friction=True, params=p)
    if chain == "thumb":
        m = ad.Model.alpes("thumb", friction=True, params=p)
        names = ("thumb_abd", "thumb_j1", "thumb_j2")
        assert m.joint_names == names and m.motor_names == ("thumb", "thumb_abduction") and m.chain == "thumb"
    else:
        m = ad.Model.alpes("finger3", friction=True, params=p, chain=chain)
        names = tuple(f"{chain}_j{i}" for i in (1, 2, 3))
        assert m.chain == chain and m.params is p and m.motor_names == ("finger",)
    idx = _block(hand, names)
    rest = np.setdiff1d(np.arange(hand.n), idx)
    rows = [hand.motor_index(k) for k in (("thumb", "thumb_abduction") if chain == "thumb" else (chain,))]
    assert np.array_equal(hand.transmission.S[np.ix_(rows, idx)], m.transmission.S)
    assert np.array_equal(m.extras.stiffness, hand.extras.stiffness[idx])
    for g in (None, np.array([1.5, -2.0, -9.5])):
        h, c = (hand, m) if g is None else (hand.copy(gravity=g), m.copy(gravity=g))
        assert c.chain == m.chain
        for _ in range(4):
            qh, vh = h.random_state(rng, speed=3.0)
            tau = rng.normal(scale=0.02, size=hand.n)
            q, v = qh[idx], vh[idx]
            A = h.inertia_matrix(qh)
            assert np.allclose(A[np.ix_(idx, idx)], c.inertia_matrix(q), rtol=1e-12, atol=1e-16)
            assert np.max(np.abs(A[np.ix_(idx, rest)])) == 0.0
            assert np.allclose(h.gravity_torque(qh)[idx], c.gravity_torque(q), rtol=1e-12, atol=1e-15)
            Cv = h.coriolis_matrix(qh, vh) @ vh
            assert np.allclose(Cv[idx], c.coriolis_matrix(q, v) @ v, rtol=1e-12, atol=1e-15)
            a_h = h.forward_dynamics(qh, vh, tau, smooth=True)[idx]
            a_c = c.forward_dynamics(q, v, tau[idx], smooth=True)
            assert np.allclose(a_h, a_c, rtol=1e-10, atol=1e-9 * np.max(np.abs(a_c)))


def test_finger_chain_differs_from_the_shared_finger(hand_params):
    """The index built from its own values is not the shared finger; the middle (no own values) is."""
    p = hand_params
    q = np.array([0.3, 0.5, 0.4])
    shared = ad.Model.alpes("finger3", params=p)
    index = ad.Model.alpes("finger3", params=p, chain="index")
    middle = ad.Model.alpes("finger3", params=p, chain="middle")
    assert index.urdf != shared.urdf and middle.urdf == shared.urdf
    assert abs(index.gravity_torque(q)[0] / shared.gravity_torque(q)[0] - 1) > 0.01
    assert np.array_equal(middle.gravity_torque(q), shared.gravity_torque(q))


def test_thumb_urdf_is_the_hands_thumb():
    """The thumb model's URDF holds exactly the hand's thumb links and joints (text for text)."""
    hand, thumb = ad.urdf_string("hand"), ad.urdf_string("thumb")
    start = hand.index('  <link name="thumb_base">')
    assert thumb.endswith(hand[start:]) and '<robot name="alpes_thumb">' in thumb
    assert "index_" not in thumb


def test_mjcf_uses_each_fingers_values(hand_params):
    """MuJoCo's stiffness, damping, frictionloss and body masses on the exported hand are each finger's own;
    with friction and stops off, its qacc is the library's."""
    mujoco = pytest.importorskip("mujoco")
    from alpes_dyn.model.mjcf import joint_permutation, load_mujoco, mjcf_string

    p = hand_params
    h = ad.Model.alpes("hand", friction=True, params=p)
    mj = load_mujoco(mjcf_string("hand", p, friction=True))
    for j, name in enumerate(h.joint_names):
        jid = mj.joint(name).id
        dof = mj.jnt_dofadr[jid]
        assert mj.jnt_stiffness[jid] == h.extras.stiffness[j]
        assert mj.dof_damping[dof] == h.extras.viscous[j] and mj.dof_frictionloss[dof] == h.extras.coulomb[j]
        assert mj.body_mass[mj.jnt_bodyid[jid]] == pytest.approx(
            h.pin_model.inertias[h.pin_model.getJointId(name)].mass, rel=1e-15)
    m0 = ad.Model.alpes("hand", params=p)
    mj0 = load_mujoco(mjcf_string("hand", p, limits=False, contact=False))
    d = mujoco.MjData(mj0)
    perm = joint_permutation(mj0, m0.joint_names)
    q, v = m0.random_state(np.random.default_rng(3))
    d.qpos[perm], d.qvel[perm] = q, v
    mujoco.mj_forward(mj0, d)
    a = m0.forward_dynamics(q, v, np.zeros(m0.n))
    assert np.max(np.abs(d.qacc[perm] - a)) <= 1e-9 * np.max(np.abs(a))
    # a finger model of one chain is exported with that finger's values
    f = load_mujoco(mjcf_string("finger3", p, chain="index"))
    assert f.jnt_stiffness.tolist() == p.chain("index").K.tolist()


@pytest.mark.parametrize("edit,pattern", [
    ("[finger.pinky]\nK = { value = [0.04, 0.05, 0.06], unit = \"N m/rad\", source = \"report\" }\n",
     r"finger\.pinky: unknown key \(expected one of L, s, .*or a finger name for its own values: index, middle"),
    ("[finger.index]\nK = { value = [0.04, 0.05], unit = \"N m/rad\", source = \"report\" }\n",
     r"finger\.index\.K: value must be a list of 3 numbers"),
    ("[finger.index]\nL = { value = [0.04, 0.05, 0.02], unit = \"m\", source = \"report\" }\n",
     r"finger\.index\.L: unknown key \(a finger's own values are K, m, I, F_s, F_v, encoder_offset\)"),
    ("[finger.index]\nm = { value = [0.3, 0.02, 0.023], unit = \"kg\", source = \"report\" }\n",
     r"finger\.index\.I: not physically consistent"),
    ("[finger.index]\nF_s = { value = [0.001, -0.001, 0.0], unit = \"N m\", source = \"report\" }\n",
     r"finger\.index\.F_s: value must be >= 0 \(got -0.001 at index 1\)"),
    ("[finger.index]\nK = { value = [0.04, 0.05, 0.06], unit = \"N m/rad\", source = \"report\", std = [0, 0, 0] }\n",
     r"finger\.index\.K\.std: only an identified value has a standard error"),
])
def test_bad_per_finger_values(tmp_path, edit, pattern):
    text = open(load_params().path, encoding="utf-8").read()
    bad = text.replace("[thumb]", edit + "\n[thumb]", 1)
    path = tmp_path / "bad.toml"
    path.write_text(bad)
    with pytest.raises(ModelError, match=pattern) as e:
        load_params(path)
    assert "\n" not in str(e.value)


def test_bad_chain_names(hand_params):
    with pytest.raises(ModelError, match=r"chain: unknown finger 'pinky' \(expected one of index, middle, ring, little\)"):
        ad.Model.alpes("finger3", chain="pinky")
    with pytest.raises(ModelError, match=r"chain: only a finger model .* not 'hand' \(the thumb is model 'thumb'\)"):
        ad.Model.alpes("hand", chain="index")
    with pytest.raises(ModelError, match=r"chain: unknown finger 'thumb'"):
        ad.Model.alpes("finger2", chain="thumb")
    with pytest.raises(ModelError, match=r"chain: unknown chain 'pinky' \(expected one of index, middle, ring, little, "
                                         r"thumb\)"):
        chain_params(hand_params, "pinky")
    with pytest.raises(ModelError, match=r"finger\.pinky\.K: unknown parameter field"):
        with_values(hand_params, {"finger.pinky.K": hand_params.raw["finger.K"]})


def _result(model: ad.Model, names: tuple[str, ...], values: list[float], std: list[float]):
    """An IdentificationResult as identify() returns it (the fit itself is tested elsewhere)."""
    from alpes_dyn.estimation.identification.identification import IdentificationResult

    p = len(names)
    return IdentificationResult(names=names, values=np.array(values), std=np.array(std), initial=np.array(values),
                                units=("",) * p, correlation=np.eye(p), residual_rms=0.6, iterations=3, converged=True,
                                seconds=1.0, compile_seconds=0.0, states=np.zeros((1, 2 * model.n)),
                                node_times=np.zeros(1), model=model, recording_path="rec.csv")


def test_identified_values_go_to_the_chains_table(hand_params, tmp_path):
    """A finger model of the ring writes [finger.ring] (the fitted fields; its other own values and the shared
    [finger] untouched), and the hand built from the file has those values on the ring only."""
    from alpes_dyn.estimation.identification.identification import identified_params

    p = hand_params
    ring = ad.Model.alpes("finger3", friction=True, params=p, chain="ring")
    res = _result(ring, ("K_2", "m_3", "F_v_1"), [0.061, 0.025, 1.3e-4], [1e-4, 2e-4, 1e-6])
    out = identified_params(res)
    assert out.raw["finger.ring.K"].source == "identified" and out.raw["finger.ring.K"].std.tolist() == [0, 1e-4, 0]
    assert out.chain("ring").K.tolist() == [p.finger.K[0], 0.061, p.finger.K[2]]
    assert out.chain("ring").m[2] == 0.025 and out.chain("ring").I[2] == pytest.approx(p.finger.I[2] * 0.025 / 0.023)
    assert out.chain("ring").F_s.tolist() == [4e-4, 5e-4, 6e-4]  # its own, not fitted: kept
    assert out.chain("ring").F_v.tolist() == [1.3e-4, p.F_v, p.F_v]
    assert params_toml({k: v for k, v in out.raw.items() if not k.startswith("finger.ring.")}) == params_toml(
        {k: v for k, v in p.raw.items() if not k.startswith("finger.ring.")})
    back = load_params(write_params(out, tmp_path / "ident.toml"))
    h = ad.Model.alpes("hand", friction=True, params=back)
    assert h.extras.stiffness[h.joint_index("ring_j2")] == 0.061
    assert h.extras.stiffness[h.joint_index("middle_j2")] == p.finger.K[1]
    # another finger's table on request; the shared one without a chain
    assert identified_params(res, chain="little").chain("little").K[1] == 0.061
    shared = identified_params(_result(ad.Model.alpes("finger3", friction=True, params=p), ("K_2",), [0.07], [1e-4]))
    assert shared.finger.K[1] == 0.07 and shared.chain("ring").K[1] == 0.07 and shared.chain("index").K[1] != 0.07
    with pytest.raises(ModelError, match=r"chain: unknown finger 'thumb'"):
        identified_params(res, chain="thumb")


def test_identified_thumb_values_go_to_the_thumb(hand_params):
    from alpes_dyn.estimation.identification.identification import identified_params

    p = hand_params
    th = ad.Model.alpes("thumb", friction=True, params=p)
    res = _result(th, ("K_thumb_j2", "m_thumb_j1", "m_thumb_abd", "F_s_thumb_abd", "F_v_thumb_abd", "F_v_thumb_j2",
                       "K_thumb_abd"),
                  [0.055, 0.03, 0.006, 6e-4, 2e-4, 1.5e-4, 0.01], [1e-4, 1e-4, 5e-3, 1e-5, 4e-5, 1e-6, 1e-4])
    out = identified_params(res)
    assert out.abduction_K == 0.01 and out.raw["thumb.abduction_K"].source == "identified"
    assert ad.Model.alpes("thumb", params=out).extras.stiffness.tolist() == [0.01, p.thumb.K[0], 0.055]
    assert out.thumb.K.tolist() == [p.thumb.K[0], 0.055]
    assert out.thumb.m[0] == 0.03 and out.thumb.I[0] == pytest.approx(p.thumb.I[0] * 0.03 / 0.025, rel=1e-12)
    assert out.thumb_base_mass == 0.006 and out.raw["thumb.base_mass"].std == 5e-3
    assert (out.abduction_F_s, out.abduction_F_v) == (6e-4, 2e-4)
    assert out.thumb.F_v.tolist() == [p.F_v, 1.5e-4]
    m = ad.Model.alpes("thumb", friction=True, params=out)
    assert m.extras.coulomb.tolist() == [6e-4, p.F_s, p.F_s] and m.extras.viscous.tolist() == [2e-4, p.F_v, 1.5e-4]
    h = ad.Model.alpes("hand", friction=True, params=out)
    assert h.extras.coulomb[h.joint_index("thumb_abd")] == 6e-4
    with pytest.raises(ModelError, match=r"chain: the thumb model's values go to the thumb, not 'index'"):
        identified_params(res, chain="index")


def test_experiment_and_identify_cli_on_one_finger(tmp_path, capsys):
    """experiment --chain draws and simulates that finger; identify --chain fits it and writes its own table."""
    import json

    from alpes_dyn.cli import main

    p = load_params()
    base = write_params(with_values(p, {"finger.index.K": Param(p.finger.K * 1.2, "N m/rad", "assumed", R),
                                        "finger.ring.F_s": Param(np.full(3, 4e-4), "N m", "assumed", R)}),
                        tmp_path / "hand.toml")
    rec, true, ident = tmp_path / "rec.csv", tmp_path / "true.toml", tmp_path / "ident.toml"
    assert main(["experiment", "--model", "finger2", "--chain", "index", "--params", str(base), "--perturb", "0.1",
                 "--seed", "2", "--duration", "1", "--true-params-out", str(true), "-o", str(rec), "--json"]) == 0
    capsys.readouterr()
    t = load_params(true)
    assert not np.array_equal(t.chain("index").K, p.finger.K * 1.2) and np.array_equal(t.finger.K, p.finger.K)
    assert np.all(np.abs(t.chain("index").K / (p.finger.K * 1.2) - 1) <= 0.1)
    assert t.chain("ring").F_s.tolist() == [4e-4] * 3
    # K alone fitted while the finger's m and friction are 10 % off: not adequate (exit 3, nothing written)
    # unless --force, which writes it with the verdict recorded in [identification.index]
    assert main(["identify", "--model", "finger2", "--chain", "index", "--params", str(base), "--data", str(rec),
                 "--parameters", "K", "-o", str(ident), "--json", "--force"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["chain"] == "index" and set(res["parameters"]) == {"K_1", "K_2"}
    q = load_params(ident)
    assert q.untrusted == ["index"] and q.identification["index"]["adequate"] is False
    assert q.raw["finger.index.K"].source == "identified" and q.raw["finger.K"].source == "report"
    fitted = [res["parameters"][k]["value"] for k in ("K_1", "K_2")]
    assert q.chain("index").K.tolist() == fitted + [p.finger.K[2] * 1.2]
    assert np.all(np.abs(np.array(fitted) / t.chain("index").K[:2] - 1) < 0.1)
    assert q.chain("ring").F_s.tolist() == [4e-4] * 3 and np.array_equal(q.finger.K, p.finger.K)


def test_identify_the_thumb_from_noise_free_data():
    """The thumb, both motors excited at once, no sensor noise, unquantised encoders: the fit of its springs,
    phalanx masses and the friction of all three joints lands on the truth to 1e-6 (the base's mass, on the
    ab/adduction axis, is not fitted: the truth keeps the nominal one)."""
    import math

    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from alpes_dyn.estimation.identification.identification import identify

    true = perturbed_params(spread=0.2, seed=3, chains=("thumb",))
    true = with_values(true, {"thumb.base_mass": load_params().raw["thumb.base_mass"]})
    design = ExperimentDesign(duration=1.0, encoder_noise_counts=0.0, torque_noise=0.0)
    rec = experiment("thumb", true, design, seed=3)
    assert rec.motor_names == ("thumb", "thumb_abduction") and rec.encoder.shape == (1001, 2)
    # every joint moves, the ab/adduction too (3.5 degrees in this 1 s at 0.5 of its amplitude ceiling)
    assert np.ptp(rec.true_q, axis=0).min() > math.radians(3)
    model = ad.Model.alpes("thumb", friction=True)
    tr = model.transmission
    rec.encoder = rec.true_q @ tr.S.T / (2 * math.pi / tr.counts_per_rev)  # unquantised
    res = identify(model, rec, "K,m_thumb_j1,m_thumb_j2,friction", progress=False)
    t = true.thumb
    truth = np.r_[t.K, t.m, true.abduction_F_s, t.F_s, true.abduction_F_v, t.F_v]
    assert res.names == ("K_thumb_j1", "K_thumb_j2", "m_thumb_j1", "m_thumb_j2", "F_s_thumb_abd", "F_s_thumb_j1",
                         "F_s_thumb_j2", "F_v_thumb_abd", "F_v_thumb_j1", "F_v_thumb_j2")
    assert res.converged and res.residual_rms < 1e-3
    assert np.max(np.abs(res.values / truth - 1)) < 1e-6
    assert np.max(np.abs(res.initial / truth - 1)) > 0.1  # it did move
    out = res.params()
    assert out.raw["thumb.K"].source == "identified" and out.raw["thumb.abduction_F_v"].source == "identified"
    assert np.allclose(out.thumb.K, t.K, rtol=1e-6) and out.abduction_F_s == pytest.approx(true.abduction_F_s, rel=1e-6)


def test_experiment_and_identify_cli_on_the_thumb(tmp_path, capsys):
    """experiment --model thumb draws the thumb and excites both motors; identify --model thumb fits it (the
    documented multisine's lines, torque noise estimated) and writes [thumb]: springs within 1 %, masses 3 %."""
    import json

    from alpes_dyn.cli import main

    rec, true, ident = tmp_path / "rec.csv", tmp_path / "true.toml", tmp_path / "ident.toml"
    assert main(["experiment", "--model", "thumb", "--perturb", "0.1", "--seed", "4", "--duration", "1",
                 "--true-params-out", str(true), "-o", str(rec), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"encoder_thumb", "torque_thumb_abduction", "true_q_thumb_abd"} <= set(out["columns"])
    t = load_params(true)
    assert np.all(np.abs(t.thumb.K / load_params().thumb.K - 1) <= 0.1) and not np.array_equal(t.thumb.K,
                                                                                                 load_params().thumb.K)
    assert main(["identify", "--model", "thumb", "--data", str(rec), "-o", str(ident), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["chain"] == "thumb" and res["model"] == "thumb" and "m_thumb_abd" not in res["parameters"]
    assert 0.5 < res["residual_rms"] < 0.7
    q = load_params(ident)
    assert q.raw["thumb.K"].source == "identified" and q.raw["finger.K"].source == "report"
    assert q.thumb.K.tolist() == [res["parameters"][k]["value"] for k in ("K_thumb_j1", "K_thumb_j2")]
    assert "F_s_thumb_abd" not in res["parameters"] and q.abduction_F_s is None
    assert q.thumb.F_s.tolist() == [res["parameters"][k]["value"] for k in ("F_s_thumb_j1", "F_s_thumb_j2")]
    assert np.max(np.abs(q.thumb.K / t.thumb.K - 1)) < 0.01
    assert np.max(np.abs(q.thumb.m / t.thumb.m - 1)) < 0.03


def test_estimation_scenario_on_a_chain(hand_params):
    """run_estimation(chain=) is the scenario on that finger of the hand (the same run as on the file projected
    on it); on the thumb (friction on) the EKF with the exact model tracks all three joints, the ab/adduction
    creeping by degrees under its scaled sines."""
    from alpes_dyn.estimation.observers.scenario import run_estimation

    p = hand_params
    a = run_estimation("ekf", model="finger3", chain="index", friction=True, params=p, duration=1.0)
    b = run_estimation("ekf", model="finger3", friction=True, params=chain_params(p, "index"), duration=1.0)
    c = run_estimation("ekf", model="finger3", friction=True, params=p, duration=1.0)
    assert np.array_equal(a.rmse, b.rmse) and not np.allclose(a.x_true, c.x_true, rtol=1e-3)
    assert a.to_dict()["chain"] == "index"
    th = run_estimation("ekf", model="thumb", friction=True, params=p, duration=1.5)
    assert th.joint_names == ("thumb_abd", "thumb_j1", "thumb_j2")
    assert np.degrees(th.rmse).max() < 0.2
    assert 1.0 < np.degrees(np.ptp(th.q_true[:, 0])) < 20.0
    assert abs(th.q_true[0, 0] - np.pi / 4) <= 0.1  # starts mid-range (+- the scenario's offset)
    with pytest.raises(ad.InputError, match=r"friction: the thumb's scenario needs friction=True"):
        run_estimation("ekf", model="thumb", duration=1.0)


def test_experiment_stops_below_a_fold():
    """A little finger with K_1 18 % soft snaps through (a fold of its static equilibria) at 0.0215 N m, below
    the nominal's mid-range bias: the trimmed bias stays below the fold by 1.25 times the multisine's peak,
    and the recorded finger stays on its branch (q_1 under 80 degrees)."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from alpes_dyn.estimation.experiments.trim import _fold_torque

    nominal = load_params()
    true = perturbed_params(nominal, spread=0.2, seed=1, chains=nominal.chain_names)
    assert true.chain("little").K[0] / nominal.finger.K[0] == pytest.approx(0.82, abs=0.01)
    little = ad.Model.alpes("finger3", friction=True, params=true, chain="little")
    fold = _fold_torque(little, lambda c: np.array([c]), np.array([0.0, 0.0, -9.81]), 0.2)
    assert 0.0212 < fold < 0.0218
    with pytest.raises(ad.InputError, match="did not converge"):  # beyond it, no rest near q = 0
        little.static_equilibrium(little.transmission.joint_torque(np.array([fold + 3e-4])))
    with pytest.warns(JointRangeWarning, match=r"fold at 0\.021\d+ N m .* joint 'j1' rests at -\d+\.\d deg, outside its "
                      r"range \[0, 90\] deg: the experiment would excite it on its stop\. Hang the hand fingers down"):
        rec = experiment("finger3", true, ExperimentDesign(duration=0.5), seed=1, chain="little")
    assert rec.torque[:, 0].max() < fold
    assert np.degrees(rec.true_q[:, 0]).max() < 80
    assert np.degrees(rec.true_q[0, 0]) < 0  # the finger starts on its stop (the library's model has none)


def test_hanging_hand_has_no_fold():
    """Hung fingers down (hanging_gravity), gravity pulls along the finger: the same soft little finger's
    equilibria fold only past 0.15 N m (palm up: 0.0215 N m, below its mid-range bias), and its experiment, designed and trimmed in that orientation, rests it
    mid-range with no warning; the orientation is the palm turned -90 degrees about the joints' axes."""
    import warnings

    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment_torque, perturbed_params
    from alpes_dyn.estimation.experiments.trim import _fold_torque
    from alpes_dyn.model.mjcf import hanging_gravity

    nominal = load_params()
    true = perturbed_params(nominal, spread=0.2, seed=1, chains=nominal.chain_names)
    g = hanging_gravity(nominal.gravity)
    assert g == pytest.approx([9.81, 0.0, 0.0], abs=1e-12)
    little = ad.Model.alpes("finger3", friction=True, params=true, chain="little")
    assert _fold_torque(little, lambda c: np.array([c]), g, 0.2) > 0.15
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointRangeWarning)
        _, u, x0 = experiment_torque("finger3", true, ExperimentDesign(duration=0.5, orientations=(tuple(g),)),
                                     chain="little")
    assert np.all((np.degrees(x0[:3]) > 20) & (np.degrees(x0[:3]) < 70))


def test_control_chain_model_uses_the_fingers_values(hand_params):
    """The hand controller's per-chain model (control.chain_model) is that finger of the file: its own springs
    and masses, with the hand's gravity; its gravity torque is the hand's block."""
    from alpes_dyn.control import chain_model

    p = hand_params
    m = chain_model(p, "index")
    assert m.extras.stiffness.tolist() == p.chain("index").K.tolist()
    h = ad.Model.alpes("hand", params=p)
    idx = _block(h, ("index_j1", "index_j2", "index_j3"))
    qh = h.random_state(np.random.default_rng(0))[0]
    assert np.allclose(h.gravity_torque(qh)[idx], m.gravity_torque(qh[idx]), rtol=1e-12, atol=1e-15)


def test_cli_experiment_on_the_hanging_rig(tmp_path, capsys):
    """``alpes-dyn experiment --rig hanging`` on the soft draw of seed 32 (palm up it folds and rests q_1 at -15
    degrees, on its stop): the recording holds the hanging rig's gravity columns (9.81, 0, 0) m/s^2, the finger
    rests and moves inside its range, and no range warning is given."""
    import warnings

    from alpes_dyn.cli import main
    from alpes_dyn.estimation.experiments.recording import read_recording

    out = tmp_path / "r.csv"
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointRangeWarning)
        assert main(["experiment", "--perturb", "0.2", "--seed", "32", "--rig", "hanging", "--duration", "0.5",
                     "-o", str(out)]) == 0
    rec = read_recording(out, ad.Model.alpes("finger3"))
    assert rec.gravity == pytest.approx(np.tile([9.81, 0.0, 0.0], (rec.n_samples, 1)), abs=1e-12)
    q = np.degrees(rec.true_q)
    assert q.min() > 5 and q.max() < 85
