"""The observer's prediction ahead in compiled C (module estimation.observers.ahead; the observer check's cost, issue
50's study): the same numbers as the filter's own time update stepped in Python, and the observer check of a fit
the same, statistic by statistic and verdict, as in CasADi's virtual machine (the path before it was compiled).

References: :meth:`~alpes_dyn.estimation.observers.observers.KalmanFilter.predict` (the filter's time update, its
covariance arithmetic of module covariance, written apart from the prediction's) called H times and the
measurement's Jacobian of :attr:`KalmanFilter.measurement`; the virtual machine's map over the starts (``ahead._loop``
returning None: the fallback without a compiler).
"""

from __future__ import annotations

import threading
from unittest import mock

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.observers import ahead

pytest.importorskip("mujoco")


@pytest.fixture(scope="module")
def stick_slip_run():
    """1.2 s of MuJoCo's stick-slip finger3 drawn 20 % off (the study's validation torque), its true file, and the
    EKF of that file run on it (as the observer check runs it)."""
    from alpes_dyn.control.plants import PlantEffects
    from alpes_dyn.estimation.observers.replay import estimate_recording
    from alpes_dyn.model.mjcf import STICTION_TIMECONST
    from alpes_dyn.studies.realism import FINGER3, fresh_run, rig_design

    true = FINGER3.true_params(10244)
    rec = fresh_run(true, PlantEffects(stiction=STICTION_TIMECONST), 10244, rig_design("level", 1.2))
    model = ad.Model.alpes("finger3", friction=True, params=true)
    est = estimate_recording(rec, model, "ekf", transient=0.5, force=True)
    return rec, model, est


def test_the_prediction_ahead_is_the_filters_time_update_stepped_h_times(stick_slip_run):
    """From five starts, 20 samples ahead: the compiled prediction's measurement and its covariance H P H^T + R equal
    those of the filter's own :meth:`predict` called 20 times from z_k|k, P_k|k (relative 1e-9); the mean alone
    (no P) the same; the virtual machine's the same."""
    _, _, est = stick_slip_run
    filt, z, P, W = est.filter, est.estimate.z, est.estimate.P, est.inputs
    starts, H = np.array([500, 611, 700, 845, 1100]), 20
    y, S = ahead.predicted_ahead(filt, z, W, starts, H, P)
    for b, k in enumerate(starts):  # the reference: five starts, stepped in Python
        zk, Pk = z[k], P[k]
        for j in range(H):
            zk, Pk = filt.predict(zk, Pk, W[k + j])
        h, Hk = (np.asarray(a) for a in filt.measurement(zk))
        np.testing.assert_allclose(y[b], h.reshape(-1), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(S[b], Hk @ Pk @ Hk.T + filt.R, rtol=1e-9, atol=1e-18)
    y_mean, none = ahead.predicted_ahead(filt, z, W, starts, H)
    assert none is None
    np.testing.assert_allclose(y_mean, y, rtol=1e-12, atol=1e-15)
    with mock.patch.object(ahead, "_loop", lambda f, covariance: None):
        y_vm, S_vm = ahead.predicted_ahead(filt, z, W, starts, H, P)
    np.testing.assert_allclose(y_vm, y, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(S_vm, S, rtol=1e-10, atol=1e-20)


def test_the_observer_check_is_the_same_compiled_as_in_the_virtual_machine(stick_slip_run):
    """The observer check of the true file on the stick-slip run, and of the nominal file (5 degrees off, refused):
    compiled, each statistic (innovation, prediction, the three NIS) within 1e-9 of the virtual machine's, the same
    verdict and reasons."""
    from alpes_dyn.estimation.identification.observer_check import observer_statistics

    rec, model, _ = stick_slip_run
    passed = []
    for m in (model, ad.Model.alpes("finger3", friction=True)):
        new = observer_statistics(rec, m)
        passed.append(new.passed)
        with mock.patch.object(ahead, "_loop", lambda f, covariance: None):
            old = observer_statistics(rec, m)
        assert new.passed == old.passed and len(new.reasons) == len(old.reasons)
        for a, b in ((new.innovation_rms, old.innovation_rms), (new.prediction_rms, old.prediction_rms),
                     *((x.value, y.value) for x, y in ((new.nis, old.nis), (new.prediction_nis, old.prediction_nis),
                                                        (new.split_nis, old.split_nis)) if x is not None)):
            assert a == pytest.approx(b, rel=1e-9)
    assert passed == [True, False]  # the true file passes, the nominal one not


def test_the_linearisation_along_the_run_is_the_filters_and_a_finite_difference(stick_slip_run):
    """A_k = dF/dz compiled equals the filter's own linearisation (:attr:`linearized`, the expression its prediction
    is built from) at five samples, G_k = dF/dw a central finite difference of the model's step (relative 1e-5);
    the virtual machine's the same (relative 1e-12)."""
    _, _, est = stick_slip_run
    filt, z, W = est.filter, est.estimate.z, est.inputs
    A, G = ahead.linearised(filt, z, W)
    assert A.shape == (W.shape[0], filt.nz, filt.nz) and G.shape == (W.shape[0], filt.nz, filt.nw)
    for k in (500, 611, 845, 1100, 1150):
        np.testing.assert_allclose(A[k], np.asarray(filt.linearized(z[k], W[k])[1]), rtol=1e-10, atol=1e-13)
        h = 1e-6 * max(float(np.abs(W[k]).max()), 1e-3)
        fd = np.column_stack([(np.asarray(filt.model.step(z[k], W[k] + h * e)) - np.asarray(
            filt.model.step(z[k], W[k] - h * e))).reshape(-1) / (2 * h) for e in np.eye(filt.nw)])
        np.testing.assert_allclose(G[k], fd, rtol=1e-5, atol=1e-9 * np.abs(fd).max())
    with mock.patch.object(ahead, "_loop", lambda f, covariance: None):
        A_vm, G_vm = ahead.linearised(filt, z[:300], W[:299])
    np.testing.assert_allclose(A_vm, A[:299], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(G_vm, G[:299], rtol=1e-12, atol=1e-15)


def test_filters_of_one_structure_share_one_compiled_loop_with_their_own_noise(stick_slip_run):
    """The model error's calibration builds one filter per trial noise: a second filter of the same model with a
    process noise 100 times larger on the velocities reuses the first's compiled loop (built once: the same object),
    yet predicts with its own Q -- its prediction's covariance equals the virtual machine's of that filter, and
    differs from the first filter's; the first filter, run again after it, gets its own numbers back."""
    from alpes_dyn.estimation.observers.observers import make_observer

    _, _, est = stick_slip_run
    f1, z, P, W = est.filter, est.estimate.z, est.estimate.P, est.inputs
    Q2 = f1.Q.copy()
    Q2[3:6, 3:6] *= 100.0
    f2 = make_observer("ekf", f1.model.system, f1.dt, process_noise=Q2, measurement_noise=f1.R, input_noise=f1.Sw,
                       substeps=f1.model.substeps, friction_law=f1.model.friction_law)
    starts, H = np.array([500, 700, 1100]), 50
    y1, S1 = ahead.predicted_ahead(f1, z, W, starts, H, P)
    loop = ahead._loop(f1, True)
    y2, S2 = ahead.predicted_ahead(f2, z, W, starts, H, P)
    assert ahead._loop(f2, True) is loop and ahead._structure(f2) == ahead._structure(f1)
    with mock.patch.object(ahead, "_loop", lambda f, covariance: None):
        y2_vm, S2_vm = ahead.predicted_ahead(f2, z, W, starts, H, P)
    np.testing.assert_allclose(y2, y2_vm, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(S2, S2_vm, rtol=1e-10, atol=1e-20)
    assert np.all(np.trace(S2, axis1=1, axis2=2) > 1.5 * np.trace(S1, axis1=1, axis2=2))
    np.testing.assert_allclose(ahead.predicted_ahead(f1, z, W, starts, H, P)[1], S1, rtol=1e-14, atol=0)


def test_the_prediction_loops_are_built_at_O0_whatever_their_size(stick_slip_run):
    """The check's prediction loops (the mean, its covariance, the Jacobians) are run a few thousand steps per
    process: built at -O0 whatever their source's size (``level``; a finger's covariance loop, under the large-source
    size, took 2.0 s of gcc at -O3, 0.4 s at -O0, its runs the same numbers: test_buildcache); each loop asked
    once per structure in a thread."""
    from types import SimpleNamespace

    from alpes_dyn.simulation import integrate

    asked = []

    def fake(step, label, **kw):
        asked.append((label, kw.get("level"), kw.get("large_level")))
        return SimpleNamespace(parameters=np.zeros(ahead._values(filt, cov).size))

    filt = stick_slip_run[2].filter
    with mock.patch.object(integrate, "CompiledStepLoop", fake), mock.patch.object(ahead, "_LOOPS", threading.local()):
        for cov in (False, True, "jacobians", False):
            ahead._loop(filt, cov)
    name = filt.model.system.model.name
    assert asked == [(f"ahead{k}_{name}", "-O0", None) for k in ("", "_cov", "_jac")]
