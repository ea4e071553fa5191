"""The whole hand in one experiment (issue 35): one recording of its six motors, every chain fitted from it.

Independent references: the hand's own model (its mass matrix, gravity and spring torque are block diagonal by
chain, each block the chain model's: the premise that the six motors at once are the chains side by side); each
chain's columns of the hand's recording against that chain's experiment run alone, bit for bit; the fit of a
chain from the hand's file against the truth. The five-chain fit of ``alpes-dyn identify --model hand`` runs as the
identification guide's documented commands (CI's ``commands`` step: minutes).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.adapt import adapted_experiment
from alpes_dyn.estimation.experiments.design import ExperimentDesign
from alpes_dyn.estimation.experiments.draws import perturbed_params
from alpes_dyn.estimation.experiments.hand_experiment import (_chain_seeds, chain_names, chain_recording, hand_chains,
                                                  hand_experiment, hand_recording)
from alpes_dyn.estimation.experiments.recording import read_recording

DESIGN = ExperimentDesign(duration=1.0)


@pytest.fixture(scope="module")
def drawn():
    p = ad.load_params()
    return perturbed_params(p, 0.2, 5, chains=hand_chains(p))


@pytest.fixture(scope="module")
def hand_rec(drawn, tmp_path_factory):
    path = tmp_path_factory.mktemp("hand") / "hand.csv"
    rec, how = hand_experiment(drawn, DESIGN, seed=5, path=path)
    return rec, how, path


def test_the_hand_is_its_chains_side_by_side(drawn, rng):
    """The hand's A(q) and G(q) are block diagonal by chain, each block the chain model's (a finger with its own
    values, the thumb): no chain moves another, so six motors at once are five chains each under its own."""
    hand = ad.Model.alpes("hand", params=drawn)
    q = rng.uniform(0.1, 1.2, hand.n)
    A, G = hand.inertia_matrix(q), hand.gravity_torque(q)
    seen = np.zeros_like(A, dtype=bool)
    for chain in hand_chains(drawn):
        model = ad.Model.alpes("thumb" if chain == "thumb" else "finger3", params=drawn,
                               chain=None if chain == "thumb" else chain)
        idx = [hand.joint_index(chain_names(chain)[1][j]) for j in model.joint_names]
        qc = q[idx]
        assert np.allclose(A[np.ix_(idx, idx)], model.inertia_matrix(qc), rtol=1e-12, atol=1e-16)
        assert np.allclose(G[idx], model.gravity_torque(qc), rtol=1e-12, atol=1e-14)
        seen[np.ix_(idx, idx)] = True
    assert seen.sum() == 4 * 9 + 9 and np.all(A[~seen] == 0.0)


def test_each_chain_of_the_hand_recording_is_its_experiment_alone(drawn, hand_rec, tmp_path):
    """The hand's recording holds every chain's experiment as that chain alone gives it (same design, its own
    noise seed), bit for bit; cut back (chain_recording) and put together again (hand_recording), it is unchanged;
    the file reads back for the hand model."""
    rec, how, path = hand_rec
    hand = ad.Model.alpes("hand")
    assert rec.motor_names == hand.motor_names and rec.joint_names == hand.joint_names
    seeds = dict(zip(hand_chains(drawn), _chain_seeds(5, 5)))
    for chain in ("index", "thumb"):  # a finger and the thumb (the others are the same code: a second of each)
        alone, a = adapted_experiment("thumb" if chain == "thumb" else "finger3", drawn, DESIGN, seed=seeds[chain],
                                      chain=None if chain == "thumb" else chain, scales=())
        part = chain_recording(rec, chain)
        assert np.array_equal(part.encoder, alone.encoder) and np.array_equal(part.torque, alone.torque)
        assert np.array_equal(part.true_q, alone.true_q) and how[chain].rig == a.rig
    parts = {chain: chain_recording(rec, chain) for chain in hand_chains(drawn)}
    again = hand_recording(parts, hand)
    assert np.array_equal(again.encoder, rec.encoder) and np.array_equal(again.true_q, rec.true_q)
    back = read_recording(path, hand)
    assert np.array_equal(back.encoder, rec.encoder) and np.allclose(back.torque, rec.torque, rtol=1e-15)
    assert len(set(seeds.values())) == 5


def test_identify_a_chain_from_the_hand_recording(drawn, hand_rec, tmp_path, capsys):
    """``identify --model hand --chain index`` fits the index finger from the hand's file (its columns), and the
    file written holds that finger's own section: springs within 1 %, masses within 3 % of the drawn finger (1 s of it)."""
    from alpes_dyn.cli import main

    _, _, path = hand_rec
    out = tmp_path / "ident.toml"
    assert main(["identify", "--model", "hand", "--chain", "index", "--data", str(path), "-o", str(out),
                 "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert list(res["chains"]) == ["index"] and res["trustworthy"] and res["output"] == str(out)
    got, want = ad.load_params(out).chain("index"), drawn.chain("index")
    assert np.max(np.abs(got.K / want.K - 1)) < 0.01 and np.max(np.abs(got.m / want.m - 1)) < 0.03
    assert ad.load_params(out).chain("middle").K.tolist() == ad.load_params().chain("middle").K.tolist()


def test_identify_the_hand_from_a_file_of_two_runs(drawn, hand_rec, tmp_path, capsys):
    """A hand's recording of two excitation runs in one file (a ``run`` column: the 1 s record's halves, each its
    own run, its own time): read for the hand, each chain's columns keep the runs (chain_recording), and
    ``identify --model hand --chain index`` fits the index finger from it to the drawn finger (springs and masses
    within 3 %: two half-second runs, each its own start state and lines)."""
    import dataclasses

    from alpes_dyn.cli import main
    from alpes_dyn.estimation.experiments.recording import join_runs, write_recording

    rec, _, _ = hand_rec

    def part(a, b):
        return dataclasses.replace(rec, **{f.name: getattr(rec, f.name)[a:b] for f in dataclasses.fields(rec)
                                           if isinstance(getattr(rec, f.name), np.ndarray)})
    path = write_recording(join_runs([part(0, 501), part(501, None)]), tmp_path / "runs.csv")
    back = read_recording(path, ad.Model.alpes("hand"))
    index = chain_recording(back, "index")
    assert np.array_equal(index.run_starts(), [0, 501, 1001]) and np.array_equal(index.t[501:], rec.t[501:])
    assert np.array_equal(index.encoder, chain_recording(rec, "index").encoder)
    out = tmp_path / "ident.toml"
    assert main(["identify", "--model", "hand", "--chain", "index", "--data", str(path), "-o", str(out),
                 "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert list(res["chains"]) == ["index"] and res["trustworthy"]
    got, want = ad.load_params(out).chain("index"), drawn.chain("index")
    assert np.max(np.abs(got.K / want.K - 1)) < 0.03 and np.max(np.abs(got.m / want.m - 1)) < 0.03
