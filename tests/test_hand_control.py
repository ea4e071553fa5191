"""The whole hand's force loops: chain models against the hand's, the cylinder's normal against MuJoCo's contact,
and a short closed loop on the cylinder.

References: Pinocchio on the hand's URDF (the chain models are built from other URDFs: finger3, and finger2 with
the thumb's table); MuJoCo's contact frames; MuJoCo's touch sensors in the closed loop.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.control import (ForceController, HAND_LEVELS, chain_frame, chain_model, cylinder_normal, hand_chains,
                               run_hand_control)
from alpes_dyn.cli import main
from alpes_dyn.model.mjcf import CYLINDER, joint_permutation, load_mujoco, mjcf_string, palm_down_params

mujoco = pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def tilted():
    """The shipped parameters with gravity off the palm normal (so that the thumb's frame turns it)."""
    return dataclasses.replace(ad.load_params(), gravity=np.array([3.0, -4.0, -8.0]))


@pytest.mark.parametrize("abd", [0.0, 0.6])
def test_chain_models_are_the_hands_chains(tilted, abd):
    """Each chain model (finger3, or finger2 with the thumb's table; gravity turned into the chain's frame) has
    the hand's G(q), tip position and tip Jacobian on that chain's joints, expressed in the chain's frame."""
    hand = ad.Model.alpes("hand", params=tilted)
    rng = np.random.default_rng(3)
    q = rng.uniform(0.0, 1.4, hand.n)
    q[hand.joint_names.index("thumb_abd")] = abd
    G = hand.gravity_torque(q)
    for c in hand_chains(tilted):
        m = chain_model(tilted, c, abd)
        R, p = chain_frame(tilted, c, abd)
        idx = [hand.joint_names.index(f"{c}_{j}") for j in m.joint_names]
        qc = q[idx]
        assert np.allclose(m.gravity_torque(qc), G[idx], rtol=1e-12, atol=1e-14), c
        assert np.allclose(R.T @ (hand.fingertip_position(q, f"{c}_tip") - p), m.fingertip_position(qc), atol=1e-14)
        assert np.allclose(R.T @ hand.fingertip_jacobian(q, f"{c}_tip")[:, idx], m.fingertip_jacobian(qc), atol=1e-14)
        q0 = q.copy()
        q0[idx[0]] = 0.0  # the chain's base frame is its first body's frame at q_1 = 0
        Rh, ph = hand.frame_placement(q0, f"{c}_p1")
        assert np.allclose(Rh, R, atol=1e-14) and np.allclose(ph, p, atol=1e-14)


def test_chain_frame_and_normal_bad_input():
    p = ad.load_params()
    with pytest.raises(ad.InputError, match="chain: unknown chain 'pinky'"):
        chain_frame(p, "pinky")
    m = chain_model(p, "index")
    tip = m.fingertip_position(np.zeros(3))
    with pytest.raises(ad.InputError, match="on the cylinder's axis"):
        cylinder_normal(m, np.zeros(3), tip)


def test_controller_takes_a_moving_normal():
    m = chain_model(palm_down_params(ad.load_params()), "index")
    q = np.array([1.2, 0.8, 0.7])
    n1, n2 = np.array([-1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    c = ForceController("sensor", m, n1, 1e-3, 0.05, prefilter_s=0.0)
    c.update(0.3, 0.0, q, normal=2 * n2)
    assert np.allclose(c.normal, n2)
    assert c.feedforward(q, 0.3) == pytest.approx(ad.control.static_motor_torque(m, q, 0.3, n2))
    c.update(0.3, 0.0, q, normal=[1e200, 0.0, 1e200])  # huge entries: normalised without overflow
    assert np.allclose(c.normal, [math.sqrt(0.5), 0.0, math.sqrt(0.5)])


@pytest.fixture(scope="module")
def grasp():
    """A short run: contact by about 1.4 s, the reference steps up at 2.0 s (0.6 s of loop time, 2.3 s simulated)."""
    return run_hand_control("sensor", duration=2.3, step_time=2.0, settle=1.7)


def test_hand_grasp_holds_each_force(grasp):
    """Each of the five loops holds its reference within 2 % over the last 200 ms of each level, its EKF within
    1.5 deg RMS during contact; commands within [0, tau_max]; the thumb opposite the cylinder (35 deg)."""
    r = grasp
    assert set(r.chains) == {"index", "middle", "ring", "little", "thumb"}
    for c, x in r.chains.items():
        a, b = HAND_LEVELS[c]
        for t0, level in ((1.8, a), (2.1, b)):
            k = (x.t >= t0) & (x.t < t0 + 0.2)
            assert abs(np.mean(x.F_true[k]) - level) < 0.02 * level, (c, level, np.mean(x.F_true[k]))
        assert x.steady_state_error < 0.02
        assert max(x.q_rmse_deg) < 1.5, (c, x.q_rmse_deg)
        assert np.all((x.tau_cmd >= 0.0) & (x.tau_cmd <= x.tau_max))
        assert np.all(x.F_true[x.t < 0.2] == 0.0)  # the approach starts in free motion
    assert abs(math.degrees(r.q_abduction[-1]) - 35.0) < 1.0
    rows = r.table()
    assert [row["chain"] for row in rows] == list(r.chains) and all(row["saturated"] == 0.0 for row in rows)
    assert r.to_dict()["chains"][0]["F_ref"] == HAND_LEVELS["index"][1]


def test_cylinder_normal_is_mujocos_contact_normal(grasp):
    """At the grasp's final joint angles, MuJoCo's contact normal between each fingertip and the cylinder is the
    cylinder's normal at the chain model's tip (turned into the palm frame) to 1e-4 (MuJoCo's convex collision
    of a capsule and a cylinder is iterative: 1.6e-5 seen)."""
    p = palm_down_params(ad.load_params())
    mj = load_mujoco(mjcf_string("hand", p, scene="cylinder"))
    d = mujoco.MjData(mj)
    abd = float(grasp.q_abduction[-1])
    d.qpos[mj.joint("thumb_abd").qposadr[0]] = abd
    for c, x in grasp.chains.items():
        d.qpos[joint_permutation(mj, x.joint_names)] = x.q_true[-1]
    mujoco.mj_forward(mj, d)
    cyl = mj.geom("cylinder").id
    seen = set()
    for i in range(d.ncon):
        con = d.contact[i]
        other = con.geom2 if con.geom1 == cyl else con.geom1 if con.geom2 == cyl else None
        if other is None:
            continue
        name = mj.geom(other).name
        c = name.rsplit("_", 1)[0]
        assert name.endswith("_p3") or name == "thumb_p2", name  # only the distal phalanges touch
        x = grasp.chains[c]
        m = chain_model(p, c, abd)
        R, pos = chain_frame(p, c, abd)
        n = R @ cylinder_normal(m, x.q_true[-1], R.T @ (np.asarray(CYLINDER["center"]) - pos), R.T @ [0.0, 1.0, 0.0])
        n_mj = con.frame[:3] * (1.0 if con.geom1 == cyl else -1.0)  # MuJoCo's: geom1 to geom2; n_mj: cylinder to tip
        assert np.allclose(-n_mj, n, atol=1e-4), (c, n_mj, n)
        seen.add(c)
    assert seen == set(grasp.chains)


def test_missing_mujoco_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(ad.ModelError, match=r"needs mujoco \(pip install 'alpes_dyn\[mujoco\]'\)"):
        run_hand_control("pi")


def test_cli_control_hand_json_log_plot(capsys, tmp_path):
    """``alpes-dyn control --model hand``: per-chain JSON, a CSV with every chain's columns, a figure."""
    pytest.importorskip("matplotlib")
    log, fig = tmp_path / "h.csv", tmp_path / "h.png"
    code = main(["control", "--model", "hand", "--controller", "pi", "--duration", "2.75", "--log", str(log),
                 "--plot", str(fig), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert d["model"] == "hand" and d["plant"] == "mujoco" and d["duration_s"] == 2.75
    assert [c["chain"] for c in d["chains"]] == list(HAND_LEVELS)
    for c in d["chains"]:  # the PI holds each force within 3 % after 0.25 s on the new level
        assert abs(c["F_held"] - c["F_ref"]) < 0.03 * c["F_ref"] and c["q_rmse_deg"] is None, c
    rows = list(csv.reader(log.open()))
    assert len(rows) == 2751 and rows[0][0] == "t_s" and rows[0][-1] == "q_thumb_abd_rad"
    assert "thumb_F_mujoco_N" in rows[0] and "q_hat_index_j3_rad" in rows[0] and len(rows[0]) == 1 + 6 * 5 + 2 * 14 + 1
    assert fig.stat().st_size > 10_000


def test_hand_reference_ramps_over_ramp_s():
    """``ramp_s`` > 0: each chain's reference rises linearly from its first level to its second between
    ``step_time`` and ``step_time + ramp_s`` (the grasp probe's reference), exactly, sample by sample."""
    lv = {c: (0.1, 0.3) for c in HAND_LEVELS}
    r = run_hand_control("pi", duration=0.6, settle=0.0, step_time=0.25, ramp_s=0.2, levels=lv, compiled=False)
    for x in r.chains.values():
        assert np.allclose(x.F_ref, 0.1 + 0.2 * np.clip((x.t - 0.25) / 0.2, 0.0, 1.0), atol=1e-15)


def test_grasp_limits_reads_where_each_pad_lets_go(monkeypatch):
    """:func:`grasp_limits` on made-up traces (the loop replaced): the MuJoCo force follows the ramp, then falls to 0
    where a chain lets go (index at 0.42 N, after a 30 % spike over 5 ms; thumb at 1.2 N) or never (the others: the
    ramp's top); the limit read is that reference within 1 % (the 20 ms mean centred on the drop leads it by up to
    10 ms of ramp, 0.4-0.7 N/s), not the spike; :func:`grasp_levels` then scales the index's two levels by
    0.8 x 0.42 / 0.4 and keeps the others."""
    from alpes_dyn.control import grasp_calibration as hl  # grasp_limits' module (it runs run_hand_control)

    let_go = {"index": 0.42, "thumb": 1.2}
    seen = {}

    def fake(controller, sc, **kw):
        seen.update(controller=controller, ramp=sc.ramp_s, levels=kw["levels"])
        t = np.arange(0.0, sc.duration, sc.dt)
        chains = {}
        for c, (a, b) in kw["levels"].items():
            ref = a + (b - a) * np.clip((t - sc.step_time) / sc.ramp_s, 0.0, 1.0)
            F = ref.copy()
            if c in let_go:
                i = int(np.argmax(ref >= let_go[c]))
                F[i:] = 0.0
                if c == "index":  # the pad's slip spikes the force before it falls
                    F[i - 5:i] *= 1.3
            chains[c] = type("R", (), {"t": t, "F_true": F, "F_ref": ref})()
        return type("H", (), {"chains": chains})()

    monkeypatch.setattr(hl, "run_hand_control", fake)
    lim = hl.grasp_limits()
    assert seen["controller"] == "sensor" and seen["ramp"] == hl.GRASP_PROBE_RAMP_S
    for c, (a, b) in HAND_LEVELS.items():
        assert seen["levels"][c] == (a, hl.GRASP_PROBE_TOP * b)
        want = let_go.get(c, hl.GRASP_PROBE_TOP * b)
        assert abs(lim[c] - want) < 0.01 * want, (c, lim[c], want)
    lv = hl.grasp_levels(lim)
    s = 0.8 * lim["index"] / HAND_LEVELS["index"][1]
    assert np.allclose(lv["index"], np.array(HAND_LEVELS["index"]) * s) and s < 0.9
    assert all(lv[c] == HAND_LEVELS[c] for c in HAND_LEVELS if c != "index")
