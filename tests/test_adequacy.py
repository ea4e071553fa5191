"""Model adequacy: the residual tests against closed forms, and the verdict on identified fits (issue 16 item
3, issue 19 item 1): a plant of the model's own structure passes, one with an effect the model lacks does not;
the CLI writes nothing from a fit not to be trusted unless --force."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from scipy import stats

import alpes_dyn as ad
from alpes_dyn.errors import InputError, ModelError
from alpes_dyn.estimation.identification.adequacy import (BAND_99, AdequacyWarning, cross_correlation, encoder_resolution, fit_percent, nrmse,
                                           sensor_floor, whiteness, white_noise_level)
from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, perturbed_params
from alpes_dyn.estimation.identification.identification import identify
from alpes_dyn.estimation.experiments.recording import read_recording, write_recording
from alpes_dyn.model.params import load_params, write_params
from alpes_dyn.model.robot import Model
from mismatch_plants import mismatched


def _acf_reference(e: np.ndarray, k: int) -> float:
    """r_ee(k) by its definition, one dot product (the module uses an FFT)."""
    e = e - e.mean()
    return float(e[k:] @ e[:-k] / (e @ e))


def test_whiteness_on_white_noise_equals_the_closed_form():
    """Gaussian white noise: r_ee(k) and the Ljung-Box Q equal their definitions, Q is chi^2_M distributed
    (its mean M over 40 draws within 3 standard errors), and the test does not reject."""
    rng = np.random.default_rng(0)
    N, M = 4000, 25
    qs = []
    for i in range(40):
        e = rng.standard_normal(N)
        w = whiteness(e, M)
        ref = np.array([_acf_reference(e, k) for k in range(1, M + 1)])
        assert np.max(np.abs(w.acf[:, 0] - ref)) < 1e-12
        q = N * (N + 2) * np.sum(ref**2 / (N - np.arange(1, M + 1)))
        assert w.ljung_box[0] == pytest.approx(q, rel=1e-10)
        assert w.p_value[0] == pytest.approx(stats.chi2.sf(q, M), rel=1e-10)
        qs.append(q)
    assert w.band == pytest.approx(2.5758293 / math.sqrt(N), rel=1e-7)
    assert abs(np.mean(qs) - M) < 3 * math.sqrt(2 * M / len(qs))


def test_whiteness_on_an_ar1_sequence_gives_rho_to_the_k():
    """e_t = rho e_t-1 + w_t: r_ee(k) = rho^k (within 4 / sqrt(N)), and whiteness is rejected (p ~ 0)."""
    rng = np.random.default_rng(1)
    N, rho = 20000, 0.6
    w = rng.standard_normal(N)
    e = np.zeros(N)
    e[0] = w[0]
    for t in range(1, N):  # the AR(1) recursion (test data, not a hot path)
        e[t] = rho * e[t - 1] + w[t]
    res = whiteness(e, 10)
    assert np.max(np.abs(res.acf[:, 0] - rho ** np.arange(1, 11))) < 4 / math.sqrt(N)
    assert res.p_value[0] < 1e-12 and res.outside[0] >= 5


def test_cross_correlation_of_a_delayed_copy():
    """e_t = u_(t-3) + small noise: r_eu peaks at lag +3 with the closed form 1 / sqrt(1 + s^2)."""
    rng = np.random.default_rng(2)
    u = rng.standard_normal(5000)
    s = 0.1
    e = np.r_[np.zeros(3), u[:-3]] + s * rng.standard_normal(5000)
    x = cross_correlation(e, u, 10)
    assert int(np.argmax(np.abs(x.xcorr[:, 0, 0]))) - 10 == 3
    assert x.xcorr[13, 0, 0] == pytest.approx(1 / math.sqrt(1 + s**2), abs=0.01)
    assert x.band == pytest.approx(BAND_99 / math.sqrt(5000))


def test_fit_percent_and_nrmse_by_hand():
    y = np.array([1.0, 2.0, 3.0, 4.0])
    yhat = np.array([1.0, 2.0, 3.0, 5.0])  # ||y - yhat|| = 1, ||y - mean y|| = sqrt(5)
    assert fit_percent(y, yhat)[0] == pytest.approx(100 * (1 - 1 / math.sqrt(5)), rel=1e-12)
    assert nrmse(y, yhat)[0] == pytest.approx(1 / math.sqrt(5), rel=1e-12)
    assert fit_percent(y, y)[0] == 100.0
    with pytest.raises(InputError, match="never moves"):
        fit_percent(np.ones(12), np.ones(12))


def test_sensor_floor_from_the_recordings_own_values():
    """A quantised sine with 0.5 count of Gaussian noise: step 1, quantisation 1/sqrt(12), white level
    sqrt(0.5^2 + 1/12) = 0.577 within 3 %, so the noise beyond quantisation is 0.5; 1/4-count data: step 0.25."""
    rng = np.random.default_rng(3)
    t = np.arange(4000) * 1e-3
    x = 800 * np.sin(2 * np.pi * 3 * t) + 300 * np.sin(2 * np.pi * 11 * t)
    counts = np.round(x + 0.5 * rng.standard_normal(t.size))
    assert encoder_resolution(counts) == 1.0
    assert white_noise_level(counts)[0] == pytest.approx(math.sqrt(0.25 + 1 / 12), rel=0.03)
    f = sensor_floor(counts)
    assert f.quantisation == pytest.approx(1 / math.sqrt(12)) and f.noise == pytest.approx(0.5, rel=0.06)
    assert f.total == pytest.approx(math.sqrt(0.25 + 1 / 12), rel=0.03)
    assert encoder_resolution(np.round(4 * x) / 4) == 0.25 and encoder_resolution(x) == 0.0
    assert sensor_floor(counts, 0.3, encoder_noise=0.0).total == pytest.approx(math.sqrt(1 / 12 + 0.09))


@pytest.fixture(scope="module")
def fits():
    """finger3 drawn +-20 % (seed 2), 1 s: a recording of the model's own structure and one whose plant has a
    rotor inertia (1e-6 kg m^2 on the tendon) the model lacks, each fitted; a held-out run of each. The rotor's
    without the dither (with it, the 20 Hz accelerations through ten times the file's J_m throw the fit 20 counts
    off, where no signature is read: flagged, naming nothing; ``test_a_dithered_rotor_mismatch_is_flagged``) and
    at 0.6 of the multisine's amplitude ceiling (the documented experiment's until 2026-12-03): at today's 0.5 the
    rigid fit of this draw loses its basin at iteration 11 (1.31 counts) and its residual's signature names an
    offset or a tilt, not the rotor (flagged all the same): a signature is read where the fit is in its basin."""
    true = perturbed_params(spread=0.2, seed=2)
    model = ad.Model.alpes("finger3", friction=True)
    out = {}
    for kind in ("match", "rotor"):
        dither, fraction = (0.0, 0.6) if kind == "rotor" else (None, None)
        rec = mismatched(kind, true, duration=1.0, seed=2, dither=dither, amplitude_fraction=fraction)
        val = mismatched(kind, true, duration=1.0, seed=102, dither=dither, amplitude_fraction=fraction)
        freqs = ExperimentDesign(dither=0.0).lines if kind == "rotor" else ExperimentDesign().lines
        # the rotor's fit does not converge (two starts of 50 iterations): 20 are enough to judge it
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = identify(model, rec, excitation=freqs, progress=False, validation=val,
                           max_iterations=50 if kind == "match" else 20)
        out[kind] = (rec, val, res, [w for w in caught if issubclass(w.category, AdequacyWarning)])
    return out


def test_adequate_on_the_models_own_structure(fits):
    rec, val, res, warned = fits["match"]
    a = res.adequacy
    assert warned == []
    assert res.converged and res.reason.startswith("converged")
    assert a.adequate and a.reasons == [] and a.likely_missing == [] and res.trustworthy
    assert 0.9 < a.floor_ratio < 1.1  # the residual is the sensor noise
    assert a.whiteness.max_acf[0] < 2 * a.whiteness.band
    assert a.validation.fit_percent[0] > 80
    d = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert d["adequacy"]["adequate"] is True and d["trustworthy"] is True


def test_not_adequate_with_a_rotor_inertia_the_model_lacks(fits):
    rec, val, res, warned = fits["rotor"]
    a = res.adequacy
    assert not a.adequate and not res.trustworthy
    assert len(warned) == 1 and "model NOT adequate" in str(warned[0].message)
    assert "\n" not in str(warned[0].message)
    assert any("coloured" in r for r in a.reasons) and a.floor_ratio > 2
    assert a.validation.fit_percent[0] < 30
    assert a.likely_missing and a.likely_missing[0].startswith("rotor inertia")
    json.dumps(res.to_dict(), allow_nan=False)  # finite numbers only


def test_a_dithered_rotor_mismatch_is_flagged():
    """The documented (dithered) experiment on a plant with ten times the file's rotor inertia: flagged, its
    residual far above the sensor floor."""
    true = perturbed_params(spread=0.2, seed=2)
    rec = mismatched("rotor", true, duration=1.0, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AdequacyWarning)
        res = identify(ad.Model.alpes("finger3", friction=True), rec, excitation=ExperimentDesign().lines,
                       progress=False, max_iterations=20)
    assert not res.trustworthy and not res.adequacy.adequate and res.adequacy.floor_ratio > 10


def test_identify_cli_refuses_an_untrusted_fit_and_force_marks_it(tmp_path, fits, capsys, monkeypatch):
    """Exit 3 and no file without --force; with it the file is written, says NOT TRUSTWORTHY, records the
    verdict, and every command that takes a parameter file reads it. (The CLI gets the fixture's fit of
    this recording instead of fitting it again: the fit itself is tested above.)"""
    import alpes_dyn.estimation.identification.identification as ident
    from alpes_dyn.cli import EXIT_UNTRUSTED, main

    rec = write_recording(fits["rotor"][0], tmp_path / "rotor.csv")
    fitted = fits["rotor"][2]
    seen = []

    def fake(model, data, *a, **kw):
        seen.append((model.name, data, kw.get("validation")))
        return fitted

    monkeypatch.setattr(ident, "identify", fake)
    out = tmp_path / "ident.toml"
    code = main(["identify", "--data", str(rec), "-o", str(out), "--json"])
    err = capsys.readouterr().err
    assert code == EXIT_UNTRUSTED == 3 and not out.exists()
    assert err.count("\n") == 1 and "not trustworthy, nothing written" in err and "rotor inertia" in err
    assert main(["identify", "--data", str(rec), "-o", str(out), "--force", "--json"]) == 0
    cap = capsys.readouterr()
    assert cap.err.count("\n") == 1 and "UntrustedFitWarning" in cap.err
    obj = json.loads(cap.out)
    assert obj["output"] == str(out) and obj["trustworthy"] is False and obj["adequacy"]["adequate"] is False
    text = out.read_text()
    assert "NOT TRUSTWORTHY" in text.splitlines()[1]
    p = load_params(out)
    assert p.untrusted == ["finger"] and p.identification["finger"]["adequate"] is False
    assert "NOT TRUSTWORTHY" in p.raw["finger.K"].reason
    assert p.identification["finger"]["likely_missing"][0].startswith("rotor inertia")
    for argv in (["urdf", "--model", "finger3", "--params", str(out), "-o", str(tmp_path / "f.urdf")],
                 ["dynamics", "--model", "finger3", "--params", str(out), "--json"],
                 ["observability", "--model", "finger2", "--params", str(out), "--json"],
                 ["estimate", "--friction", "--true-params", str(out), "--duration", "0.3", "--json"],
                 ["mjcf", "--params", str(out), "-o", str(tmp_path / "f.xml"), "--model", "finger3"],
                 ["identify", "--params", str(out), "--data", str(rec), "-o", str(tmp_path / "again.toml"),
                  "--force"]):
        code = main(argv)
        capsys.readouterr()
        assert code == 0, argv
    # --effects auto: the first fit lost its basin, so a staged start (the rigid fit; the stand-in's loses it
    # too: the first kept); its verdict names a friction with a state, well above two sensor floors, so each of
    # the three identify commands fits with the creep law (rounds.BAND_WORDS), then with the rotor it names, then
    # (the stand-in's residual not lower, the fit kept still flagged) with the LuGre law, the stick-slip law and the
    # torque delay (one sample: not lower, none longer tried); not the encoder's offset, as its verdict names a
    # nonlinearity too (the residual's power at the harmonics: a constant offset makes none): seven fits each, the
    # first kept and reported; each command read its --data once and gave every fit the same Recording (the file's
    # encoder column), the delay's round the torque one sample earlier
    assert any("nonlinearity" in m for m in fitted.adequacy.likely_missing)
    assert fitted.adequacy.floor_ratio >= 2.0
    assert len(seen) == 21 and all(m == "finger3" and v is None for m, _, v in seen)
    assert all(seen[0][1] is seen[k][1] for k in range(1, 6)) and seen[5][1] is not seen[6][1]
    assert np.array_equal(seen[6][1].torque[:-1], seen[0][1].torque[1:])
    assert np.array_equal(seen[0][1].encoder, read_recording(rec, Model.alpes("finger3")).encoder)
    # a file rewritten from it keeps the record; a trustworthy fit's file says so
    back = write_params(p, tmp_path / "copy.toml")
    assert load_params(back).identification == p.identification


def test_identified_file_of_a_trusted_fit_records_it(tmp_path, fits):
    _, _, res, _ = fits["match"]
    p = load_params(res.write(tmp_path / "ok.toml"))
    rec = p.identification["finger"]
    assert rec["converged"] is True and rec["adequate"] is True and rec["trustworthy"] is True
    assert rec["residual_rms"] == pytest.approx(res.residual_rms) and p.untrusted == []
    assert "NOT" not in p.raw["finger.K"].reason


@pytest.mark.parametrize("table,pattern", [
    ("[identification.pinky]\nconverged = true\n", r"identification.pinky: unknown chain"),
    ("[identification.finger]\nconverged = 1\n", r"identification.finger.converged: expected true or false"),
    ("[identification.finger]\nfoo = 1\n", r"identification.finger.foo: unknown key"),
    ("[identification.finger]\nresidual_rms = -1.0\n", r"residual_rms: expected a non-negative number"),
    ("[identification.finger]\nlikely_missing = [1]\n", r"likely_missing: expected a list of strings"),
    ("[identification.finger]\nstandard_errors = 1\n", r"standard_errors: expected a string"),
])
def test_identification_record_errors(tmp_path, table, pattern):
    path = tmp_path / "p.toml"
    path.write_text(load_params().path and open(load_params().path).read() + "\n" + table)
    with pytest.raises(ModelError, match=pattern):
        load_params(path)


def test_a_fit_that_stops_gives_its_reason():
    """One Gauss-Newton iteration allowed: the fit stops at the cap, says so, is not trustworthy, and the
    parameter file it would write records it (converged false, the stop reason)."""
    from alpes_dyn.estimation.experiments.experiment import experiment

    rec = experiment("finger2", perturbed_params(spread=0.2, seed=3), ExperimentDesign(duration=0.5), seed=3)
    with pytest.warns(AdequacyWarning, match="did not converge"):
        res = identify(ad.Model.alpes("finger2", friction=True), rec, max_iterations=1, progress=False)
    assert not res.converged and not res.trustworthy
    assert res.reason == "iteration cap: 1 Gauss-Newton iterations without meeting the stopping rule"
    assert res.to_dict()["reason"] == res.reason
    rec_ = res.params().identification["finger"]
    assert rec_["converged"] is False and rec_["stop"] == res.reason and rec_["trustworthy"] is False


def test_assess_rules_on_synthetic_residuals():
    """White noise at the floor: adequate. The same plus a constant: too large, the bias named. An AR(1)
    residual: coloured, unless the floor says the torque noise's (coloured) response dominates it."""
    from alpes_dyn.estimation.identification.adequacy import SensorFloor, assess

    rng = np.random.default_rng(4)
    N = 3000
    u = rng.standard_normal((N, 1))
    floor = SensorFloor(step=1.0, quantisation=1 / math.sqrt(12), noise=0.5, torque=0.0, noise_source="given")
    white = math.sqrt(0.25 + 1 / 12) * rng.standard_normal((N, 1))
    ok = assess(white, u, floor)
    assert ok.adequate and ok.notes == [] and abs(ok.floor_ratio - 1) < 0.05
    biased = assess(white + 1.0, u, floor)
    assert not biased.adequate and biased.likely_missing[0].startswith("an encoder offset")
    ar = np.zeros(N)
    w = rng.standard_normal(N) * 0.3
    for t in range(1, N):  # AR(1), rho 0.9 (test data)
        ar[t] = 0.9 * ar[t - 1] + w[t]
    coloured = assess(ar[:, None], u, floor)
    assert not coloured.adequate and "coloured" in coloured.reasons[0]
    torque_floor = SensorFloor(1.0, 1 / math.sqrt(12), 0.5, float(np.std(ar)), "given")
    judged = assess(ar[:, None], u, torque_floor)
    assert judged.adequate and "not judged" in judged.notes[0]


def test_reversal_ratio_sees_a_residual_at_velocity_reversals():
    """A residual of white noise: ratio ~1 (within 15 %); with bursts of 3x within 10 ms of each zero of
    the velocity (what sticking does): above 2, and assess names stick-slip first."""
    from alpes_dyn.estimation.identification.adequacy import SensorFloor, assess, reversal_ratio

    rng = np.random.default_rng(5)
    t = np.arange(4000) * 1e-3
    v = np.sin(2 * np.pi * 2.0 * t + 0.3)[:, None]
    e = rng.standard_normal((4000, 1))
    assert abs(reversal_ratio(e, v) - 1) < 0.15
    near = np.abs(np.sin(2 * np.pi * 2.0 * t + 0.3)) < np.sin(2 * np.pi * 2.0 * 0.01)
    stuck = e * np.where(near, 3.0, 1.0)[:, None]
    assert reversal_ratio(stuck, v) > 2
    floor = SensorFloor(1.0, 1 / math.sqrt(12), 0.5, 0.0, "given")
    a = assess(stuck, rng.standard_normal((4000, 1)), floor, velocity=v)
    assert not a.adequate and a.likely_missing[0].startswith("stick-slip")


def test_intermodulation_products_by_hand():
    """Lines 1 and 5 Hz: order 2 gives 2, 10, 6, 4; order 3 gives 3, 15, 7, |2 - 5| = 3, 11, |1 - 10| = 9."""
    from alpes_dyn.estimation.identification.harmonics import intermodulation

    assert intermodulation([1.0, 5.0], 100.0).tolist() == [2.0, 3.0, 4.0, 6.0, 7.0, 9.0, 10.0, 11.0, 15.0]
    assert intermodulation([1.0, 5.0], 100.0, orders=(2,)).tolist() == [2.0, 4.0, 6.0, 10.0]
    assert intermodulation([1.0, 5.0], 8.0).tolist() == [2.0, 3.0, 4.0, 6.0, 7.0]


def test_harmonic_ratio_sees_the_excitations_products():
    """White noise: the ratio is 1 within 0.3 (136 bins: its spread about 0.09) on five draws. The same plus the
    tones a friction reversing with the 20 Hz dither makes (3 x 20 Hz and 20 + 11.3 Hz, each of amplitude a):
    the products' bins gain a^2 N^2 / 4 per tone over 2 x 3 + ... bins of mean N sigma^2, so the ratio is 1 +
    that share; assess then names a nonlinearity, after the others."""
    from alpes_dyn.estimation.identification.adequacy import SensorFloor, assess
    from alpes_dyn.estimation.identification.harmonics import NONLINEARITY, harmonic_ratio, intermodulation

    lines = ExperimentDesign().lines
    dt, N = 1e-3, 4000  # 0.25 Hz bins: 60 and 31.25 Hz on bins
    t = np.arange(N) * dt
    rng = np.random.default_rng(11)
    for _ in range(5):
        assert abs(harmonic_ratio(rng.standard_normal(N) * 0.6, lines, dt) - 1) < 0.3
    sigma, a = 0.6, 0.2
    tones = a * (np.sin(2 * np.pi * 60.0 * t) + np.sin(2 * np.pi * 31.25 * t))
    e = rng.standard_normal(N) * sigma
    # the closed form: the products' bins (within 1 of each product, off the lines) hold on average
    # N sigma^2 of noise, plus (a N / 2)^2 on each of the two tones' bins
    f = np.fft.rfftfreq(N, dt)
    near = np.zeros(f.size, bool)
    for k in np.rint(intermodulation(lines, f[-1]) / f[1]).astype(int):
        near[max(k - 1, 0): k + 2] = True
    for k in np.rint(np.asarray(lines) / f[1]).astype(int):
        near[max(k - 2, 0): k + 3] = False
    near[:3] = False
    expected = 1 + 2 * (a * N / 2) ** 2 / (near.sum() * N * sigma**2)
    got = harmonic_ratio(e + tones, lines, dt)
    assert expected > 1.5 and abs(got - expected) < 0.3 * (expected - 1) + 0.3
    floor = SensorFloor(1.0, 1 / math.sqrt(12), 0.5, 0.0, "given")
    flagged = assess((e + tones + 0.8)[:, None], rng.standard_normal((N, 1)), floor, lines=lines, dt=dt)
    assert not flagged.adequate and flagged.likely_missing[-1] == NONLINEARITY
    assert flagged.signatures["harmonics"]["share"] == pytest.approx(got, rel=1e-12)
    plain = assess((e + 0.8)[:, None], rng.standard_normal((N, 1)), floor, lines=lines, dt=dt)
    assert not plain.adequate and NONLINEARITY not in plain.likely_missing


def test_a_fitted_trajectory_leaving_the_joint_range_names_a_joint_stop():
    """range_exit: the joints whose fitted angles pass a limit by more than RANGE_TOLERANCE (1 deg), each with how
    far; assess then fails the fit on it and names a joint stop first (MuJoCo's seed 32 drives q_1 to -15 deg into
    its stop; the fit of it left j1 at -23 to -28 deg and named the stop)."""
    from alpes_dyn.estimation.identification.adequacy import JOINT_STOP, RANGE_TOLERANCE, assess, range_exit, sensor_floor

    q = np.zeros((100, 3))
    q[:, 1] = np.linspace(0.0, 1.0, 100)
    lo, hi, names = np.zeros(3), np.full(3, math.radians(90)), ("j1", "j2", "j3")
    assert range_exit(q, lo, hi, names) is None  # inside
    q[10, 0] = -0.5 * RANGE_TOLERANCE  # within the tolerance: not reported
    assert range_exit(q, lo, hi, names) is None
    q[20, 0], q[30, 2] = math.radians(-15.0), math.radians(95.0)
    text = range_exit(q, lo, hi, names)
    assert text == "j1 down to -15.0 deg (limit 0); j3 up to 95.0 deg (limit 90)"
    assert range_exit(q, np.full(3, -np.inf), np.full(3, np.inf), names) is None  # no finite limits: not judged
    rng = np.random.default_rng(0)
    e = rng.standard_normal((2000, 1)) * 0.6
    u = rng.standard_normal((2000, 1))
    floor = sensor_floor(np.round(e * 10) / 10, 0.0, 0.5)
    ok = assess(e, u, floor)
    flagged = assess(e, u, floor, range_exit=text)
    assert flagged.reasons[-1] == f"the fitted joints leave their range ({text})" and not flagged.adequate
    assert flagged.likely_missing[0] == JOINT_STOP and flagged.reasons[:-1] == ok.reasons
