"""The excitation's lines over a recording turned between orientations (issue 38): one block of the basis per
segment of constant gravity, and the fit of such a record."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, experiment_torque
from alpes_dyn.estimation.experiments.recording import MAX_SEGMENTS, segment_starts
from alpes_dyn.estimation.identification.torque_lines import line_basis
from alpes_dyn.estimation.identification.torque_lines import torque_model
from alpes_dyn.model.mjcf import hanging_gravity


def _both(duration: float = 2.0, **kw) -> ExperimentDesign:
    g = ad.load_params().gravity
    level = ExperimentDesign(duration=duration, **kw)
    return dataclasses.replace(level, orientations=(tuple(level.orientations[0]),
                                                    tuple(float(x) for x in hanging_gravity(g))))


def test_segment_starts_are_where_piecewise_constant_gravity_changes():
    G = np.zeros((100, 3))
    G[:, 2] = -9.81
    assert segment_starts(None).tolist() == [0] and segment_starts(G).tolist() == [0]
    G[40:] = (9.81, 0.0, 0.0)
    G[70:] = (0.0, 0.0, -9.81)
    assert segment_starts(G).tolist() == [0, 40, 70]
    wobbling = G + 1e-3 * np.sin(np.arange(100))[:, None]  # an IMU's reading: one segment, not a hundred
    assert 99 >= MAX_SEGMENTS and segment_starts(wobbling).tolist() == [0]


def test_each_segment_has_the_single_basis_from_its_own_start():
    t = 1e-3 * np.arange(1001)
    f = (0.7, 3.1)
    Phi = line_basis(t, f, [0, 400])
    assert Phi.shape == (1001, 10)
    np.testing.assert_array_equal(Phi[:400, :5], line_basis(t[:400], f))
    np.testing.assert_array_equal(Phi[400:, 5:], line_basis(t[400:], f))  # time from the segment's start
    assert not Phi[:400, 5:].any() and not Phi[400:, :5].any()
    np.testing.assert_array_equal(line_basis(t, f), line_basis(t, f, [0]))
    with pytest.raises(ad.InputError, match=r"excitation: 2 frequencies are too many for 15 samples in the segment "
                                             r"from t = 0\.986 s"):
        line_basis(t, f, [0, 986])


@pytest.mark.filterwarnings("ignore::alpes_dyn.model.stops.JointRangeWarning")  # the torque alone is checked
def test_turned_record_torque_model_keeps_each_runs_torque():
    """The torque of a record turned halfway (each half its own multisine and bias) projected on the lines: per
    segment it is the true torque within the sensor's noise (5e-4 N m); one basis over the whole record deforms it
    by far more (the torque model the fit took before segments)."""
    p = ad.load_params()
    design = _both(torque_amplitude=0.004)
    _, u, _ = experiment_torque("finger3", p, design)
    rec = experiment("finger3", p, design, seed=3)
    assert segment_starts(rec.gravity).tolist() == [0, 1001]
    tm = torque_model(rec, design.lines, None)
    err = np.sqrt(np.mean((tm.U - u[:-1]) ** 2))
    assert err < 1.5e-4 and 3e-4 < tm.noise < 7e-4
    one = rec.torque[:-1] - u[:-1]
    Q = np.linalg.qr(line_basis(rec.t, design.lines)[:-1])[0]
    err_one = np.sqrt(np.mean((Q @ (Q.T @ rec.torque[:-1]) - u[:-1]) ** 2))
    assert err_one > 5 * err and np.std(one) == pytest.approx(5e-4, rel=0.1)


def test_turned_record_fits_the_springs_and_masses():
    """finger3 drawn +-20 % (seed 7), 1 s palm up then 1 s hung, on our own simulator: the default fit (K, m,
    friction, the documented lines) converges with the springs and masses within 1 %."""
    from alpes_dyn.estimation.identification.identification import identify
    from alpes_dyn.estimation.experiments.draws import perturbed_params
    from alpes_dyn.symbolic.parametric import parameter_catalogue

    true = perturbed_params(spread=0.2, seed=7)
    design = _both()
    rec = experiment("finger3", true, design, seed=7)
    nominal = ad.Model.alpes("finger3", friction=True)
    fit = identify(nominal, rec, excitation=design.lines, progress=False)
    truth = {pp.name: pp.nominal for pp in parameter_catalogue(ad.Model.alpes("finger3", friction=True, params=true))}
    worst = max(abs(v / truth[n] - 1) for n, v in zip(fit.names, fit.values) if n[:2] in ("K_", "m_"))
    assert fit.converged and worst < 0.01


def test_harmonics_part_by_part_on_a_turned_record():
    """A white residual (0.5 count) plus what the excitation's lines leave in it at 0.5 count (the dither's 20 Hz
    and 3.7 Hz), their phases restarting where the hand turned (2 s): over the whole record the restart's jump
    spreads their power into the harmonics' bins (ratio 2.2: a nonlinearity falsely named past the 1.5
    threshold); part by part it is white (1.0)."""
    from alpes_dyn.estimation.identification.adequacy import THRESHOLDS
    from alpes_dyn.estimation.identification.harmonics import harmonic_ratio

    lines = ExperimentDesign().lines
    t = 1e-3 * np.arange(4000)
    local, phase = np.where(t < 2.0, t, t - 2.0), np.where(t < 2.0, 0.0, 1.9)
    e = (0.5 * np.random.default_rng(0).standard_normal(4000) + 0.5 * np.sin(2 * np.pi * 20.0 * local + phase)
         + 0.5 * np.sin(2 * np.pi * 3.7 * local + 2 * phase))
    assert harmonic_ratio(e, lines, 1e-3) > THRESHOLDS["harmonic_ratio"]
    assert harmonic_ratio(e, lines, 1e-3, runs=[0, 2000, 4000]) < 1.1
