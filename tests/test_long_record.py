"""Long recordings (issue 39): the fit started from a window of the record (alpes_dyn.estimation.identification.long_record)."""

from __future__ import annotations

import math
import weakref

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.identification import identification as identification_module
from alpes_dyn.estimation.identification import long_record
from alpes_dyn.estimation.identification.shooting import ShootingProblem
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
from alpes_dyn.estimation.identification.gauss_newton import GaussNewton
from alpes_dyn.estimation.identification.identification import identify


@pytest.fixture(scope="module")
def clean():
    """finger2 +-20 % (seed 3), 1.2 s, no sensor noise, the encoder unquantised: exact recovery is the reference."""
    true = perturbed_params(spread=0.2, seed=3)
    finger2 = ad.Model.alpes("finger2", friction=True)
    rec = experiment("finger2", true, ExperimentDesign(duration=1.2, encoder_noise_counts=0.0, torque_noise=0.0),
                     seed=3)
    tr = finger2.transmission
    rec.encoder = rec.true_q @ tr.S.T / (2 * math.pi / tr.counts_per_rev)
    truth = np.r_[true.finger.K[:2], true.finger.m[:2], true.finger.F_s[:2], true.finger.F_v[:2]]
    return finger2, rec, truth


def test_window_cuts_every_per_sample_column(clean):
    _, rec, _ = clean
    w = long_record.window(rec, 0.3)
    assert w.n_samples == int(round(0.3 / rec.dt)) + 1 and w.dt == pytest.approx(rec.dt)
    assert np.array_equal(w.encoder, rec.encoder[:w.n_samples]) and np.array_equal(w.torque, rec.torque[:w.n_samples])
    assert np.array_equal(w.true_q, rec.true_q[:w.n_samples]) and w.motor_names == rec.motor_names


def test_a_long_record_fits_from_its_window_to_the_truth(clean, monkeypatch):
    """With the record 'long' (LONG_RECORD lowered to 0.6 s, a 0.5 s window): the whole fit runs on the window
    (the homotopy there only), the whole record gets the model's response at the window's values joined
    (GaussNewton.join_nodes: continuous to 1e-3 of the nodes' scale or better) and stage 3, and lands on the truth as
    the whole fit does: K, m within 1e-6; the friction within 5e-4 (stage 3 from a close start stops at the stopping
    rule's chi^2 step of 0.05 counts-units sooner than the cold fit's 3e-6: on these unquantised data a chi^2 of
    0.05 is far below any sensor's resolution; F_s is the least seen, 2.3e-4 off)."""
    finger2, rec, truth = clean
    monkeypatch.setattr(long_record, "LONG_RECORD", 0.6)
    monkeypatch.setattr(long_record, "WINDOW", 0.5)
    lengths, joined = [], []
    homotopy, join = GaussNewton.homotopy, GaussNewton.join_nodes

    def join_spy(pb, nodes, offs, glob, *a):
        out = join(pb, nodes, offs, glob, *a)
        e = pb.evaluate(out, offs, glob, jac=False)
        joined.append((pb.N, float(np.max(np.abs(e.c) / np.maximum(np.abs(out).max(axis=0), 1e-3)))))
        return out
    monkeypatch.setattr(GaussNewton, "homotopy",
                        lambda self, pb, *a, **k: lengths.append(pb.N) or homotopy(self, pb, *a, **k))
    monkeypatch.setattr(GaussNewton, "join_nodes", staticmethod(join_spy))
    # the window start's evaluation (its Jacobian: 190 MB at 600 s) is not held once stage 3 has stepped from it:
    # a weak reference to it, read at each evaluation with the Jacobians after it is handed over
    handed, alive = [], []
    start, evaluate = identification_module.window_start, ShootingProblem.evaluate

    def start_spy(*a, **k):
        out = start(*a, **k)
        handed.append(weakref.ref(out[0][3]))
        return out

    def evaluate_spy(self, *a, **k):
        if handed and k.get("jac", True) is True:
            alive.append(handed[0]() is not None)
        return evaluate(self, *a, **k)
    monkeypatch.setattr(identification_module, "window_start", start_spy)
    monkeypatch.setattr(ShootingProblem, "evaluate", evaluate_spy)
    res = identify(finger2, rec, progress=False)
    assert alive and not any(alive)
    # the window's homotopy in full (two starts at most), the whole record joined once, no homotopy of it
    assert res.converged and set(lengths) == {500} and len(joined) == 1 and joined[0][0] == 1200
    assert joined[0][1] < 1e-3
    assert np.max(np.abs(res.values[:4] / truth[:4] - 1)) < 1e-6 and np.max(np.abs(res.values / truth - 1)) < 5e-4
    assert np.max(np.abs(res.initial / truth - 1)) > 0.02  # the start reported is the model's, not the window's


def test_a_start_the_join_leaves_discontinuous_goes_through_the_homotopys_last_phase(clean, monkeypatch):
    """Where the joined start's defects exceed JOIN_LIMIT (lowered to 0 here: every join refused; the thumb's drifting
    response on a real record), stage 1's nodes and the homotopy's last phase of the whole record start stage 3,
    which lands on the truth as from the join: K, m within 1e-6, the friction within 5e-4."""
    finger2, rec, truth = clean
    monkeypatch.setattr(long_record, "LONG_RECORD", 0.6)
    monkeypatch.setattr(long_record, "WINDOW", 0.5)
    monkeypatch.setattr(long_record, "JOIN_LIMIT", 0.0)
    phases, homotopy = [], GaussNewton.homotopy
    monkeypatch.setattr(GaussNewton, "homotopy", lambda self, pb, *a, **k: phases.append(
        (pb.N, k.get("first", 0))) or homotopy(self, pb, *a, **k))
    res = identify(finger2, rec, progress=False)
    assert res.converged and (1200, long_record.SOFT_PHASES - 1) in phases and {n for n, _ in phases} == {500, 1200}
    assert np.max(np.abs(res.values[:4] / truth[:4] - 1)) < 1e-6 and np.max(np.abs(res.values / truth - 1)) < 5e-4


def test_the_whole_record_runs_in_chunks_give_the_same_states(clean, monkeypatch):
    """A long record's states-only runs go in pieces (the per-sample inputs 8 MiB at a time): the model's response
    from rest (ShootingProblem.initial_nodes: each piece from the last one's end) and the effects' responses
    (adequacy.effect_responses: the intervals in chunks), with the chunks made a few intervals long here, equal the
    runs in one piece bit for bit."""
    from alpes_dyn.estimation.identification import adequacy, shooting
    from alpes_dyn.estimation.identification.shooting import ShootingProblem, torque_model
    from alpes_dyn.simulation.sensitivity import SensitivityModel

    finger2, rec, _ = clean
    torque = torque_model(rec, ExperimentDesign().lines[:3], None)
    sens = SensitivityModel(finger2, None, dt=rec.dt, substeps=4, input_basis=torque.nphi)
    pb = ShootingProblem(finger2, rec, sens, 100, torque, 0.01)
    whole = pb.initial_nodes(np.zeros(pb.n))
    nodes = whole + 1e-3
    args = (sens, nodes, pb.Ub, pb.Gb, pb.theta0, pb.correction(np.full(pb.ng, 0.1), None), pb.Psib, pb.valid,
            rec.true_q[:, [0, 1, 0, 1]], pb.S_enc, pb.step, rec.dt)
    resp = adequacy.effect_responses(*args)
    small = 3 * 100 * sens.nw + 5  # three intervals' inputs
    monkeypatch.setattr(shooting, "JACOBIAN_CHUNK", small)
    assert np.array_equal(pb.initial_nodes(np.zeros(pb.n)), whole) and pb.n_int == 12
    resp_c = adequacy.effect_responses(*args, chunk_doubles=small)
    assert resp.keys() == resp_c.keys() and all(np.array_equal(resp[k], resp_c[k]) for k in resp)
    assert all(np.abs(resp[k]).max() > 0 for k in resp)


def test_a_long_records_lines_are_orthonormalised_as_householder_does():
    """shooting._thin_qr above CHOLESKY_QR_ROWS (Cholesky QR twice): Q R = Phi, Q'Q = I, R upper triangular, and Q
    numpy's Householder Q up to its columns' signs, on 40 s of the documented lines at 1 kHz; two equal columns
    (a singular basis) fall back to Householder's."""
    from alpes_dyn.estimation.identification.shooting import CHOLESKY_QR_ROWS, _thin_qr, line_basis

    t = np.arange(40001) * 1e-3
    Phi = line_basis(t, ExperimentDesign().lines)[:-1]
    assert Phi.shape[0] > CHOLESKY_QR_ROWS
    Q, R = _thin_qr(Phi)
    Qh, Rh = np.linalg.qr(Phi)
    k = Phi.shape[1]
    assert np.abs(Q.T @ Q - np.eye(k)).max() < 1e-13 and np.abs(Q @ R - Phi).max() < 1e-12
    assert np.array_equal(R, np.triu(R)) and np.all(np.diag(R) > 0)
    assert np.abs(Q - Qh * np.sign(np.diag(Rh))).max() < 1e-12
    Phi[:, 1] = Phi[:, 2]
    Q2, R2 = _thin_qr(Phi)
    Qh2, Rh2 = np.linalg.qr(Phi)
    assert np.array_equal(Q2, Qh2) and np.array_equal(R2, Rh2)
