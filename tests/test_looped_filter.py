"""The EKF's step built as loops over dense matrices (estimation.observers.looped, issue 51 item 4): against the
unrolled step on finger3 with friction (4 RK4 substeps) and on the Alpes hand (30 states), the size threshold on both
sides, its C export against its run, and its bad inputs."""

from __future__ import annotations

import shutil
import subprocess

import casadi as cs
import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.cexport.cexport import main_input, read_main_output, write_c_observer
from alpes_dyn.estimation.observers import observers
from alpes_dyn.estimation.observers.looped import LOOP_STATES
from alpes_dyn.estimation.observers.observers import ExtendedKalmanFilter, UnscentedKalmanFilter
from alpes_dyn.symbolic.statespace import StateSpace

CC = shutil.which("cc") or shutil.which("gcc")


def _pair(model, substeps, params=()):
    """The same EKF unrolled and looped, and a record of 300 samples for it (its steps' inputs)."""
    ss = StateSpace(model, input="motor", output="encoder")
    n, m = model.n, ss.n_inputs
    kw = dict(process_noise=[1e-12] * n + [1e-6] * n + [1e-8] * len(params), measurement_noise=[1e-6] * ss.n_outputs,
              input_noise=[1e-6] * m, substeps=substeps, parameters=params)
    unrolled, looped = ExtendedKalmanFilter(ss, 1e-3, looped=False, **kw), ExtendedKalmanFilter(ss, 1e-3, looped=True,
                                                                                                **kw)
    t = 1e-3 * np.arange(300)
    W = 0.05 * np.sin(2 * np.pi * np.outer(t, 1.0 + np.arange(m)))
    x = np.concatenate([model.rest_configuration() if hasattr(model, "rest_configuration") else np.zeros(n),
                        np.zeros(n)])
    return unrolled, looped, W, x


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    """The largest difference of b from a, relative to a's largest entry."""
    return float(np.abs(a - b).max() / max(np.abs(a).max(), 1e-300))


def _compare(unrolled, looped, W, x0):
    """The largest differences, relative to the entries' scale, of the linearisation (A, N) and of one whole step
    from the unrolled filter's own estimates, at each of the record's samples."""
    nz = unrolled.nz
    P0 = np.diag(np.full(nz, 1e-4))
    Y = np.zeros((W.shape[0] + 1, unrolled.ny))
    Y[:] = np.asarray(unrolled.model.output(np.concatenate([x0, np.ones(nz - x0.size)]))).reshape(-1)
    est = unrolled.run(np.concatenate([x0, np.ones(nz - x0.size)]), P0, W, Y)
    Z, Ps = est.z[:-1], est.P[:-1]
    z, w = cs.MX.sym("z", nz), cs.MX.sym("w", unrolled.nw)
    lin = [cs.Function("l", [z, w], [cs.densify(o) for o in f.linearized(z, w)]).map(W.shape[0])
           for f in (unrolled, looped)]
    (za, Aa, Na), (zb, Ab, Nb) = ([np.asarray(o) for o in f(Z.T, W.T)] for f in lin)
    S = np.hstack([Z, Ps.transpose(0, 2, 1).reshape(len(Z), -1)])
    WY = np.hstack([W, Y[1:]])
    sa, sb = (np.asarray(f.filter_step.map(W.shape[0])(S.T, WY.T)) for f in (unrolled, looped))
    return {"z_next": _rel(za, zb), "A": _rel(Aa, Ab), "N": _rel(Na, Nb), "z": _rel(sa[:nz], sb[:nz]),
            "P": _rel(sa[nz:], sb[nz:])}


def test_looped_step_equals_the_unrolled_on_a_finger_with_friction():
    """finger3 with its friction (4 RK4 substeps per period) and both gains as states: the looped linearisation
    (the chain rule over the stages) and step equal the unrolled expression's to 1e-12 (relative) at 300 states."""
    model = ad.Model.alpes("finger3", friction=True)
    unrolled, looped, W, x0 = _pair(model, 4, ("input_gain", "spring_gain"))
    assert not unrolled.looped and looped.looped and unrolled.exact_loops and not looped.exact_loops
    err = _compare(unrolled, looped, W, x0[: 2 * model.n])
    assert max(err.values()) <= 1e-12, err


def test_looped_step_equals_the_unrolled_on_the_alpes_hand():
    """The Alpes hand, 30 states (5 chains, 5 motors, one RK4 step): the same to 1e-12."""
    model = ad.Model.alpes("hand")
    unrolled, looped, W, x0 = _pair(model, 1)
    assert unrolled.nz == 30 and looped.filter_step_p.is_a("MXFunction")
    err = _compare(unrolled, looped, W, x0)
    assert max(err.values()) <= 1e-12, err


def test_the_size_threshold_on_both_sides(monkeypatch):
    """Looped by default from LOOP_STATES states on: one state under it unrolled, at it looped (the threshold moved
    to finger2's 4 states); the Alpes hand's 30 stay unrolled, the Shadow hand's 48 are looped."""
    assert 30 < LOOP_STATES <= 48
    ss = StateSpace(ad.Model.alpes("finger2"), input="motor", output="encoder")
    kw = dict(process_noise=[1e-10] * 4, measurement_noise=[1e-7])
    monkeypatch.setattr(observers, "LOOP_STATES", 5)
    assert not ExtendedKalmanFilter(ss, 1e-3, **kw).looped
    monkeypatch.setattr(observers, "LOOP_STATES", 4)
    f = ExtendedKalmanFilter(ss, 1e-3, **kw)
    assert f.looped and f.filter_step_p.is_a("MXFunction")
    assert not UnscentedKalmanFilter(ss, 1e-3, **kw).looped  # the UKF's step is unrolled


@pytest.mark.parametrize("bad, match", [("yes", "looped: expected True, False or None"),
                                        (1, "looped: expected True, False or None")])
def test_bad_looped(bad, match):
    ss = StateSpace(ad.Model.alpes("finger2"), input="motor", output="encoder")
    with pytest.raises(InputError, match=match):
        ExtendedKalmanFilter(ss, 1e-3, process_noise=[1e-10] * 4, measurement_noise=[1e-7], looped=bad)
    with pytest.raises(InputError, match="looped: the EKF's step only"):
        UnscentedKalmanFilter(ss, 1e-3, process_noise=[1e-10] * 4, measurement_noise=[1e-7], looped=True)


@pytest.mark.skipif(CC is None, reason="no C compiler (cc or gcc) on PATH: the exported C is not built")
@pytest.mark.parametrize("code", [None, "casadi"])
def test_c_export_of_a_looped_filter_equals_its_run(code, tmp_path):
    """finger3 with friction, looped: its C (the default "sparse": the substeps' loop and the covariance loops;
    "casadi": CasADi's code of the looped step, its matrix products as loops) equals its run to rounding."""
    model = ad.Model.alpes("finger3", friction=True)
    _, filt, W, x0 = _pair(model, 4)
    z0, P0 = x0, np.full(filt.nz, 1e-4)
    Y = np.tile(np.asarray(filt.model.output(z0)).reshape(-1), (W.shape[0] + 1, 1))
    d = write_c_observer(filt, tmp_path / "c", code=code, prefix="obs")["main.c"].parent
    exe = tmp_path / "main"
    subprocess.run([CC, "-O1", "-std=c99", "-o", str(exe), str(d / "main.c"), str(d / "obs.c"), "-lm"], check=True,
                   capture_output=True, text=True, timeout=300)
    (tmp_path / "in.txt").write_text(main_input(z0, P0, Y[0], W, Y[1:]))
    out = subprocess.run([str(exe), str(tmp_path / "in.txt")], check=True, capture_output=True, text=True).stdout
    Z, P = read_main_output(out, filt.nz)
    est = filt.run(z0, P0, W, Y)
    assert Z.shape == est.z.shape == (301, 6)
    assert np.abs(Z - est.z).max() <= 1e-9 * np.abs(est.z).max()
    assert np.abs(P - est.P).max() <= 1e-9 * np.abs(est.P).max()


def _short_run():
    """finger3 with friction's unrolled and looped filters (4 substeps), 60 samples of inputs and the unrolled
    filter's run on them from rest (P0 = 1e-4 I)."""
    model = ad.Model.alpes("finger3", friction=True)
    unrolled, looped, W, x0 = _pair(model, 4)
    W = W[:60]
    Y = np.repeat(np.asarray(unrolled.model.output(x0)).reshape(1, -1), W.shape[0] + 1, axis=0)
    return unrolled, looped, W, unrolled.run(x0, np.diag(np.full(unrolled.nz, 1e-4)), W, Y)


def test_predictions_ahead_and_linearisation_of_a_looped_filter_equal_the_unrolled():
    """The consistency checks' linearisation along a run and their predictions 5 samples ahead with covariance
    (estimation.observers.ahead): a looped filter (its chain rule) and the unrolled one (compiled, or the virtual
    machine) give the same numbers to 1e-10 (relative) on finger3 with friction."""
    from alpes_dyn.estimation.observers.ahead import linearised, predicted_ahead

    unrolled, looped, W, est = _short_run()
    for a, b in zip(linearised(unrolled, est.z, W), linearised(looped, est.z, W)):
        assert _rel(a, b) <= 1e-10
    starts = np.arange(0, 50, 7)
    ya, Sa = predicted_ahead(unrolled, est.z, W, starts, 5, est.P)
    yb, Sb = predicted_ahead(looped, est.z, W, starts, 5, est.P)
    assert ya.shape == yb.shape == (starts.size, unrolled.ny) and Sa.shape == Sb.shape
    assert _rel(ya, yb) <= 1e-10 and _rel(Sa, Sb) <= 1e-10


def test_one_step_prediction_of_a_looped_filter_shared_by_nees_and_nis():
    """The NEES's error model (predicted_covariance: A_k and P_k+1|k along the run) and the NIS's one-step
    prediction of a looped filter, from one compiled run (ahead.predicted_step), equal the unrolled filter's to 1e-10
    (relative) on finger3 with friction; P_k+1|k against numpy's A P A^T + G Sigma_w G^T + Q; the run is computed
    once for both (kept on the filter) and again for another run."""
    from alpes_dyn.estimation.observers import ahead
    from alpes_dyn.estimation.observers.consistency import predicted_covariance

    unrolled, looped, W, est = _short_run()
    for a, b in zip(predicted_covariance(unrolled, est, W), predicted_covariance(looped, est, W)):
        assert a.shape == b.shape and _rel(a, b) <= 1e-10
    zn, Pn, A, G = ahead.predicted_step(looped, est.z, W, est.P)
    assert _rel(A @ est.P[:60] @ A.transpose(0, 2, 1) + G @ looped.Sw @ G.transpose(0, 2, 1) + looped.Q, Pn) <= 1e-12
    starts = np.arange(3, 59, 2)
    for a, b in zip(ahead.predicted_ahead(unrolled, est.z, W, starts, 1, est.P),
                    ahead.predicted_ahead(looped, est.z, W, starts, 1, est.P)):
        assert _rel(a, b) <= 1e-10
    assert ahead.predicted_step(looped, est.z, W, est.P)[1] is Pn  # kept: the NIS reads the NEES's run
    assert ahead.predicted_step(looped, est.z, W[::-1].copy(), est.P)[1] is not Pn


def test_looped_run_keeps_its_prediction_for_the_nees_and_nis():
    """A looped filter's run keeps each step's prediction and Jacobians (ahead.kept_run): its estimates equal the
    plain step's loop (or the virtual machine's) to 1e-13 and the kept z_k+1|k, P_k+1|k, A_k, G_k those of the
    prediction stepped again from its estimates (ahead._looped) to 1e-12 (relative), on finger3 with friction; the
    NEES's and the NIS's prediction read them (no second run); another run's inputs are stepped again."""
    from alpes_dyn.estimation.observers import ahead

    model = ad.Model.alpes("finger3", friction=True)
    _, looped, W, x0 = _pair(model, 4)
    W = W[:80]
    Y = np.repeat(np.asarray(looped.model.output(x0)).reshape(1, -1), W.shape[0] + 1, axis=0)
    Y[40:] += 1e-3  # a step in the readings: an update that moves the estimate
    P0 = np.diag(np.full(looped.nz, 1e-4))
    est = looped.run(x0, P0, W, Y)
    kept = looped.__dict__["_predicted_step"][1]
    z, P = looped._update(x0, P0, Y[0])
    s0 = np.concatenate([np.asarray(z).reshape(-1), np.asarray(P).reshape(-1, order="F")])
    ref = np.asarray(looped.filter_step_p.mapaccum(W.shape[0])(s0, np.hstack([W, Y[1:]]).T, looped.model.values)).T
    nz = looped.nz
    assert _rel(ref[:, :nz], est.z[1:]) <= 1e-13
    assert _rel(ref[:, nz:], est.P[1:].transpose(0, 2, 1).reshape(W.shape[0], -1)) <= 1e-13
    again = ahead._looped(looped, est.z[:-1], est.P[:-1], W[:, None, :])
    for a, b in zip(again, kept):
        assert a.shape == b.shape and _rel(a, b) <= 1e-12
    assert np.abs(kept[2] - np.eye(nz)).max() > 1e-3  # (a step that moves: A is not I)
    assert ahead.predicted_step(looped, est.z, W, est.P)[1] is kept[1]  # the NEES's and the NIS's: read, not run
    assert ahead.predicted_step(looped, est.z, W[::-1].copy(), est.P)[1] is not kept[1]


def test_looped_run_too_long_to_keep_runs_the_plain_step(monkeypatch):
    """A record whose kept prediction would be over ahead.MAX_KEPT_BYTES runs the looped filter's plain compiled
    step (nothing kept on the filter): the same estimates as the kept run to 1e-13 (relative), on finger3 with
    friction, and the NEES's prediction then stepped again from the estimates, equal to the kept one's to 1e-12."""
    from alpes_dyn.estimation.observers import ahead
    from alpes_dyn.estimation.observers.looped import kept_size

    model = ad.Model.alpes("finger3", friction=True)
    _, looped, W, x0 = _pair(model, 4)
    W = W[:60]
    Y = np.repeat(np.asarray(looped.model.output(x0)).reshape(1, -1), W.shape[0] + 1, axis=0)
    Y[30:] += 1e-3
    P0 = np.diag(np.full(looped.nz, 1e-4))
    kept_est = looped.run(x0, P0, W, Y)
    kept = looped.__dict__.pop("_predicted_step")[1]
    monkeypatch.setattr(ahead, "MAX_KEPT_BYTES", 8 * kept_size(looped.model))  # under two samples
    est = looped.run(x0, P0, W, Y)
    assert "_predicted_step" not in looped.__dict__ and looped._online_loop is not None
    assert _rel(kept_est.z, est.z) <= 1e-13 and _rel(kept_est.P, est.P) <= 1e-13
    for a, b in zip(ahead.predicted_step(looped, est.z, W, est.P), kept):
        assert a.shape == b.shape and _rel(a, b) <= 1e-12
