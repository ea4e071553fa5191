"""A long record simulated at its sample rate (issue 39: alpes_dyn.simulation.sampled) and written column by column:
the same numbers as the whole-run ``simulate`` and the row-by-row writer they replace."""

from __future__ import annotations

import math

import numpy as np
import pytest

import alpes_dyn as ad
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.experiments.experiment import perturbed_params
from alpes_dyn.estimation.experiments import recording
from alpes_dyn.estimation.experiments.recording import Recording, write_recording
from alpes_dyn.model.mjcf import hanging_gravity
from alpes_dyn.simulation import sampled
from alpes_dyn.simulation.integrate import simulate


@pytest.fixture(scope="module")
def finger():
    """finger3 +-20 % (seed 21) with friction, hung fingers down (another gravity: another structure than palm up),
    0.3 s of a multisine-like torque about a bias, 5 sub-steps per 1 ms sample."""
    m = ad.Model.alpes("finger3", friction=True, params=perturbed_params(spread=0.2, seed=21))
    m = m.copy(gravity=np.asarray(hanging_gravity(m.gravity), dtype=float))
    t = 1e-3 * np.arange(300)
    u = (0.025 + 0.006 * np.sin(2 * math.pi * 3.7 * t) + 0.002 * np.sin(2 * math.pi * 11.3 * t))[:, None]
    x0 = np.r_[m.static_equilibrium(None, np.zeros(3), tau_m=u[0]), np.zeros(3)]
    return m, x0, u


@pytest.mark.parametrize("compiled", [True, False])
def test_the_samples_are_simulates_states_to_the_bit(finger, compiled, monkeypatch):
    """The reference: simulate's RK4 in CasADi's virtual machine over every sub-step (the experiment's simulation
    before issue 39), its states every 5th step. Chunks of 64 sub-steps (not a multiple of 5 samples' worth: 12
    samples a chunk) so that the chunk joins are crossed; both the compiled loop and the virtual-machine fallback."""
    m, x0, u = finger
    sub, dt = 5, 1e-3
    monkeypatch.setattr(sampled, "CHUNK_STEPS", 64)
    ref = simulate(m, x0, np.repeat(u, sub, axis=0), u.shape[0] * dt, dt / sub, "rk4", input="motor",
                   output="encoder").x[::sub]
    x = sampled.sampled_rk4(m, x0, u, dt, sub, compiled=compiled)
    assert x.shape == ref.shape == (301, 6)
    assert np.ptp(x[:, :3], axis=0).min() > 1e-3 and (x[:, :3] > m.lower).all() and (x[:, :3] < m.upper).all()
    assert np.array_equal(x, ref)


def test_models_of_one_structure_share_the_loop_each_with_its_numbers(finger):
    """A finger of other numbers (springs, masses, friction drawn +-20 %) reuses the loop the first built (one
    generated C per step expression), its own numbers set: each run is simulate's on its own model (to 1e-12),
    and the first model's run again after the second gives its first states."""
    m, x0, u = finger
    other = ad.Model.alpes("finger3", params=perturbed_params(spread=0.2, seed=5), friction=True).copy(
        gravity=m.gravity)  # hung too: the same structure
    sub, dt = 5, 1e-3
    runs, built = [], []
    for model in (m, other, m):
        runs.append(sampled.sampled_rk4(model, x0, u, dt, sub))
        built.append(dict(sampled._LOOPS.loops))
        ref = simulate(model, x0, np.repeat(u, sub, axis=0), u.shape[0] * dt, dt / sub, "rk4", input="motor",
                       output="encoder").x[::sub]
        np.testing.assert_allclose(runs[-1], ref, rtol=0, atol=1e-12)
    assert built[0] == built[1] == built[2] and np.abs(runs[1] - runs[0]).max() > 1e-3
    np.testing.assert_allclose(runs[2], runs[0], rtol=0, atol=1e-14)


def test_a_diverging_run_and_bad_shapes_are_one_line_errors(finger):
    m, x0, u = finger
    with pytest.raises(InputError, match=r"simulation diverged \(non-finite state at t = "):
        sampled.sampled_rk4(m, x0, np.full_like(u, 1e200), 1e-3, 4)
    with pytest.raises(InputError, match=r"u: expected shape \(N, 1\)"):
        sampled.sampled_rk4(m, x0, u[:, 0], 1e-3, 4)
    with pytest.raises(InputError, match="substeps: expected a positive integer"):
        sampled.sampled_rk4(m, x0, u, 1e-3, 0)


def test_the_recording_is_written_as_the_row_by_row_writer_wrote_it(tmp_path, monkeypatch):
    """The reference: each row's cells as repr of the float ("" for NaN, the run an integer), joined by commas:
    the writer before issue 39, on a record with a run column, camera gaps, -0.0, a subnormal and a large value,
    written 300 rows at a time (the joins crossed)."""
    monkeypatch.setattr(recording, "WRITE_ROWS", 300)
    rng = np.random.default_rng(1)
    N = 2001
    q = np.full((N, 3), np.nan)
    q[::400] = rng.standard_normal((6, 3))
    torque = rng.standard_normal((N, 1)) * 1e-3
    torque[5], torque[6], torque[7] = -0.0, 5e-324, 1.2345678901234567e15
    rec = Recording(t=1e-3 * np.arange(N), encoder=np.round(rng.standard_normal((N, 1)) * 1000), torque=torque,
                    motor_names=("finger",), joint_names=("j1", "j2", "j3"), q=q,
                    true_q=rng.standard_normal((N, 3)), run=np.repeat([0.0, 1.0, 2.0], [700, 700, 601]))
    path = write_recording(rec, tmp_path / "rec.csv")
    cols = rec.columns()
    rows = [",".join(str(int(cols[c][k])) if c == "run" else ("" if math.isnan(cols[c][k]) else repr(float(cols[c][k])))
                     for c in cols) for k in range(N)]
    assert path.read_text() == ",".join(cols) + "\n" + "\n".join(rows) + "\n"


def test_the_effects_signatures_are_the_subsets_least_squares():
    """adequacy.signatures from one QR of the regressors against the reference it replaced: numpy's lstsq of the
    residual on each subset of the scaled columns (all, then each left out), a column collinear with two others
    and a zero one among them (lstsq's minimum-norm answer): shares and coefficients to 1e-9 (the zero column's
    share)."""
    from alpes_dyn.estimation.identification.adequacy import signatures

    rng = np.random.default_rng(4)
    N = 3000
    a, b = rng.standard_normal((N, 2)), rng.standard_normal((N, 2))
    resp = {"a": a, "b": b, "ab": a - 2 * b, "zero": np.zeros((N, 2)), "c": rng.standard_normal((N, 2))}
    e = 0.3 * a + 0.5 * resp["c"] + 0.05 + rng.standard_normal((N, 2))
    got = signatures(e, resp)
    A = np.column_stack([r.reshape(-1) for r in resp.values()] + [np.ones(2 * N)])
    scale = np.maximum(np.linalg.norm(A, axis=0), 1e-300)
    A, y = A / scale, e.reshape(-1)

    def sse(cols):
        c = np.linalg.lstsq(A[:, cols], y, rcond=None)[0]
        return float(np.sum((y - A[:, cols] @ c) ** 2)), c
    full, coef = sse(list(range(6)))
    for i, k in enumerate(list(resp) + ["bias"]):
        share = max(sse([j for j in range(6) if j != i])[0] - full, 0.0) / float(y @ y)
        assert got[k]["share"] == pytest.approx(share, rel=1e-9, abs=1e-12)
        if k != "zero":  # (its coefficient is a rounding of 0 over the 1e-300 scale, in both)
            assert got[k]["coefficient"] == pytest.approx(coef[i] / scale[i], rel=1e-9, abs=1e-12)
    assert got["c"]["share"] > 0.1 and got["a"]["share"] == 0.0 == got["zero"]["share"]  # a: in b and ab


@pytest.mark.parametrize("text", ["t,a\n0,1\n1,2\n", "t,a\r\n0,1\r\n1,2", "t,a\r0,1\n\n1,2\u2028x\n", "", "\n", "a"])
def test_the_recordings_lines_are_cut_as_stringio_cut_them(text):
    """csv_numbers.lines (the reader's lines, cut one at a time from the text) against io.StringIO's iteration, the
    reader's before: the same lines, "\\r", "\\r\\n" and "\\u2028" left inside them, a last line without "\\n"."""
    import io

    from alpes_dyn.estimation.experiments.csv_numbers import lines

    assert list(lines(text)) == list(io.StringIO(text))
