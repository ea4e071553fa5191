"""The realism study on draws nobody tuned on (issue 38): the benchmark's seeds and distribution, the torque delay
undone against MuJoCo's delayed sensor, and the observer's check of an identified file against MuJoCo."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from alpes_dyn.control.plants import PlantEffects, mujoco_recording
from alpes_dyn.errors import InputError
from alpes_dyn.estimation.observers.replay import estimate_recording
from alpes_dyn.estimation.observers.torque_reading import advanced
from alpes_dyn.studies.realism import cases, parse_seeds, summarise


def test_parse_seeds_takes_ranges():
    assert parse_seeds("301-305,7") == [301, 302, 303, 304, 305, 7]
    assert parse_seeds("12") == [12]
    for bad in ("3-1", "a", "1,,2", "1-2-3", "-4", "2,2"):
        with pytest.raises(InputError, match="seeds"):
            parse_seeds(bad)


def _row(case, seed, flagged, ekf, m, verdict="adequate"):
    w = {"K": 0.5, "m": m, "F_s": 10.0, "F_v": 5.0}
    return {"case": case, "seed": seed, "ekf_rmse_deg": ekf,
            "extended": {"worst_error_common_scale_pct": w, "flagged": flagged, "fit_seconds_total": 10.0 + seed,
                         "verdict": verdict}}


def test_summarise_counts_silent_misses_and_refusals():
    rows = [_row("all", 1, False, [0.1, 0.2, 0.3], 2.0),  # adequate and right
            _row("all", 2, False, [0.1, 0.9, 0.3], 2.0),  # adequate, EKF off: a silent miss
            _row("all", 3, False, [0.1, 0.2, 0.3], 6.0),  # adequate, masses off: a silent miss
            _row("all", 4, True, [3.0, 0.2, 0.3], 9.0, "FLAGGED: inadequate"),  # refused
            {"case": "all", "seed": 5, "error": "ModelError: boom"},
            _row("stiction", 1, False, [0.4, 0.2, 0.3], 1.0)]
    s = summarise(rows)
    a = s["all"]
    assert a["n"] == 5 and a["adequate"] == 3
    assert [m["seed"] for m in a["silent_misses"]] == [2, 3]
    assert a["refusals"] == [{"seed": 4, "verdict": "FLAGGED: inadequate"}]
    assert a["errors"] == [(5, "ModelError: boom")]
    assert a["ekf_deg"] == {"median": pytest.approx(0.6), "worst": pytest.approx(3.0)}  # worst joints .3 .9 .3 3
    assert a["m_pct"] == {"median": pytest.approx(4.0), "worst": pytest.approx(9.0)}
    assert s["stiction"]["silent_misses"] == [] and s["stiction"]["ekf_deg"]["worst"] == pytest.approx(0.4)
    assert not a["goal"]["accuracy_met"] and s["stiction"]["goal"]["accuracy_met"]  # misses and a raised run
    assert s["stiction"]["goal"]["time_met"] == (s["stiction"]["fit_seconds"]["median"] <= 20.0)
    ok = summarise([_row("all", 1, False, [0.1, 0.2, 0.3], 2.0), _row("all", 4, True, [3.0, 0.2, 0.3], 9.0, "FLAGGED")])
    assert ok["all"]["goal"]["accuracy_met"]  # a refusal naming its cause is no miss


def test_cases_hold_the_slack_and_the_delay():
    c = cases(4e4, 10.0)
    assert c["slack"].tendon_dead_band == pytest.approx(0.002 * np.radians(0.5), rel=1e-12)  # r_m radians(0.5)
    assert c["slack"].tendon_stiffness == 4e4 and c["delay"].torque_delay == 1
    assert c["all"].torque_delay == 1 and c["all"].tendon_dead_band == c["slack"].tendon_dead_band


def test_advanced_undoes_mujocos_torque_delay():
    """MuJoCo's sensor reading the torque 2 samples late, read 2 samples earlier: the undelayed recording's torque
    (its noise included) but for the last 2 rows, and the encoder untouched."""
    t = np.arange(300) * 1e-3
    u = (0.02 + 0.002 * np.sin(2 * np.pi * 3 * t))[:, None]
    stick = PlantEffects(stiction=0.0005)  # MuJoCo's own dry friction: no Python callback, a fast run
    plain = mujoco_recording("finger3", None, u, 1e-3, seed=3, effects=stick)
    late = mujoco_recording("finger3", None, u, 1e-3, seed=3, effects=dataclasses.replace(stick, torque_delay=2))
    back = advanced(late, 2)
    np.testing.assert_array_equal(back.torque[:-2], plain.torque[:-2])
    np.testing.assert_array_equal(back.torque[-2:], np.repeat(late.torque[-1:], 2, axis=0))
    np.testing.assert_array_equal(back.encoder, late.encoder)
    assert advanced(late, 0) is late
    with pytest.raises(InputError, match="torque_delay"):
        advanced(late, -1)
    with pytest.raises(InputError, match="torque_delay"):
        advanced(late, 400)


def test_the_observer_check_passes_the_true_file_and_fails_a_wrong_one():
    """On MuJoCo's stick-slip finger3 drawn 20 % off (seed 302, 1.2 s of the study's validation run, MuJoCo's
    frictionloss), the EKF of the true file (the smooth law: 0.1 degree) predicts the encoder 20 ms ahead within
    12.5 times the sensor floor; the nominal file's EKF (5.5 degrees off) 140 times: refused, the reason naming the
    observer."""
    import alpes_dyn as ad
    from alpes_dyn.estimation.identification.observer_check import OBSERVER_THRESHOLDS, observer_statistics
    from alpes_dyn.model.mjcf import STICTION_TIMECONST
    from alpes_dyn.studies.realism import FINGER3, fresh_run, rig_design

    true = FINGER3.true_params(302)
    rec = fresh_run(true, PlantEffects(stiction=STICTION_TIMECONST), 302, rig_design("level", 1.2))
    good = observer_statistics(rec, ad.Model.alpes("finger3", friction=True, params=true))
    bad = observer_statistics(rec, ad.Model.alpes("finger3", friction=True))
    assert good.passed, good.reasons
    assert np.degrees(good.ekf_rmse).max() < 0.3 and np.degrees(bad.ekf_rmse).max() > 2.0
    assert not bad.passed and all(r.startswith("the EKF on the identified file") for r in bad.reasons)
    ratio = OBSERVER_THRESHOLDS["prediction_ratio"]
    assert good.prediction_rms < 0.9 * ratio * good.floor and bad.prediction_rms > 5 * ratio * bad.floor
    assert good.floor == pytest.approx(0.57, abs=0.05)  # quantisation 0.29 and 0.5 count of noise
    assert good.horizon_s == pytest.approx(0.02)


def test_mildly_coloured_is_the_ljung_box_alone():
    """A white residual with a slow AR(1) part (rho 0.9) of 8 % of its variance, 4000 samples: lags up to about
    0.067 (1.6 times the 99 % band 0.041) over some twenty lags, Ljung-Box p far below 1e-6: mildly coloured; the
    slow part as large as the white one (lags to 0.45) is not; nor a mild one far above the floor."""
    from scipy.signal import lfilter

    from alpes_dyn.estimation.identification.adequacy import assess, sensor_floor
    from alpes_dyn.estimation.identification.observer_check import mildly_coloured

    rng = np.random.default_rng(4)
    w, v = rng.standard_normal(4000), rng.standard_normal(4000)
    slow = lfilter([1.0], [1.0, -0.9], v)
    slow /= slow.std()

    def res(share):
        e = w + np.sqrt(share) * slow
        return (0.5 * e / e.std())[:, None]

    u = rng.standard_normal((4000, 1))
    floor = sensor_floor(np.zeros((4000, 1)), encoder_noise=0.5)
    mild, strong = assess(res(0.08), u, floor), assess(res(1.0), u, floor)
    assert mild.whiteness.p_value[0] < 1e-6 and mild.whiteness.max_acf[0] < 3 * mild.whiteness.band
    assert len(mild.reasons) == 1 and mildly_coloured(mild)
    assert not strong.adequate and not mildly_coloured(strong)
    loud = assess(4 * res(0.08), u, floor)  # 2 counts RMS against a floor of 0.5
    assert len(loud.reasons) == 2 and not mildly_coloured(loud)


_RAMP = np.linspace(0.01, 0.02, 50)[:, None]
"""N m: the stand-in recordings' torque, a ramp: how far a fit's torque was advanced reads off its first sample."""


def _ramp_recording():
    """A 50-sample recording of finger3's motor, its torque :data:`_RAMP` (for stand-in fits of fit_effects)."""
    from alpes_dyn.estimation.experiments.recording import Recording

    n = _RAMP.shape[0]
    return Recording(t=np.arange(n) * 1e-3, encoder=np.zeros((n, 1)), torque=_RAMP, motor_names=("finger",),
                     joint_names=("j1", "j2", "j3"))


def _advanced_by(data) -> int:
    """The samples by which a stand-in fit's recording had its torque read earlier (advanced)."""
    return int(round((data.torque[0, 0] - _RAMP[0, 0]) / (_RAMP[1, 0] - _RAMP[0, 0])))


def test_fit_effects_finds_the_torque_delay(monkeypatch):
    """auto's delay on stand-in fits: the first fit's verdict names a torque delay, so the fit is made again on the
    torque read 1 sample earlier (from the first fit); its verdict names nothing: kept, with EffectsFit.delay = 1 and
    the torque the fit saw the recorded one advanced by exactly one sample, 2 samples not tried."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.adequacy import SIGNATURES
    from alpes_dyn.model.params import load_params

    rec = _ramp_recording()
    seen = []

    def fake_identify(model, data, parameters, **kw):
        d = _advanced_by(data)
        seen.append((d, data.torque.copy(), kw.get("start")))
        ok = d == 1
        missing = [] if ok else [SIGNATURES["torque_rate"]]
        res = SimpleNamespace(residual_rms=0.6 + 0.1 * abs(d - 1), converged=True, reason="", names=(), values=[],
                              std=[], trustworthy=ok, adequacy=SimpleNamespace(adequate=ok, likely_missing=missing))
        return res

    monkeypatch.setattr(ident_mod, "identify", fake_identify)
    fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), rec, eff.parse_effects("auto"),
                          has_gravity=True)
    assert [d for d, _, _ in seen] == [0, 1]
    assert fit.delay == 1 and fit.effects == ("compliance", "tilt", "delay") and fit.result.residual_rms == 0.6
    np.testing.assert_array_equal(seen[1][1][:-1], _RAMP[1:])  # advanced by one sample, the last repeated
    assert seen[1][1][-1, 0] == _RAMP[-1, 0]
    assert seen[1][2] is not None  # from the first fit
    assert fit.observer is None  # a stand-in has no file to run the EKF on



def test_a_flagged_fit_naming_nothing_tries_the_delay_after_stiction_and_the_rotor(monkeypatch):
    """auto on stand-in fits whose verdict names no effect (as MuJoCo's hung all-effects finger3 of seeds 413 and
    416: a residual at 1.09 times the floor, mildly coloured): the stick-slip law and the rotor do not help, so the
    torque delay is tried last, found at 1 sample and kept; every effect one round at most."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.model.params import load_params

    rec = _ramp_recording()
    seen = []

    def fake_identify(model, data, parameters, **kw):
        d = _advanced_by(data)
        seen.append(d)
        ok = d == 1
        return SimpleNamespace(residual_rms=0.6 + 0.1 * abs(d - 1), converged=True, reason="", names=(), values=[],
                               std=[], trustworthy=ok, adequacy=SimpleNamespace(adequate=ok, likely_missing=[]))

    monkeypatch.setattr(ident_mod, "identify", fake_identify)
    fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), rec, eff.parse_effects("auto"),
                          has_gravity=True, observe=False)
    assert [e for e, _ in fit.rounds] == [("compliance", "tilt"), ("compliance", "tilt", "stiction"),
                                          ("compliance", "tilt", "rotor"), ("compliance", "tilt", "delay")]
    assert seen == [0, 0, 0, 1]  # each round on the torque as fitted; 2 samples not tried: 1 is adequate
    assert fit.delay == 1 and fit.effects == ("compliance", "tilt", "delay") and fit.result.trustworthy

def test_a_lost_first_fit_naming_a_joint_stop_still_gets_the_staged_start_and_autos_rounds(monkeypatch):
    """auto on stand-in fits shaped as MuJoCo's all-effects finger3 of seed 536 (in range on the plant): the first
    fit loses its basin and its verdict names a joint stop. A lost fit's trajectory is not believed: the staged
    start runs (its rigid fit lost too: noted), then auto's rounds; the rotor's converges, adequate, and is kept.
    (Before, the stop ended the fit at the first round, refused for the wrong cause.)"""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.adequacy import JOINT_STOP
    from alpes_dyn.model.params import load_params

    seen = []

    def fake_identify(model, data, parameters, **kw):
        seen.append(parameters)
        ok = len(seen) == 4  # the 4th fit: the rotor's round
        return SimpleNamespace(residual_rms=0.6 if ok else 14.4 + len(seen), converged=ok,
                               reason="converged" if ok else "lost basin: three Gauss-Newton steps in a row",
                               names=(), values=[], std=[], trustworthy=ok,
                               adequacy=SimpleNamespace(adequate=ok, likely_missing=[] if ok else [JOINT_STOP]))

    monkeypatch.setattr(ident_mod, "identify", fake_identify)
    fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), _ramp_recording(), eff.parse_effects("auto"),
                          has_gravity=True, observe=False)
    assert [e for e, _ in fit.rounds] == [("compliance", "tilt"), (), ("compliance", "tilt", "stiction"),
                                          ("compliance", "tilt", "rotor")]
    assert fit.effects == ("compliance", "tilt", "rotor") and fit.result.converged and fit.result.trustworthy
    assert fit.notes and "rigid fit itself did not converge" in fit.notes[0]


def test_the_observer_chooses_among_rounds_as_good_a_fit(monkeypatch):
    """auto on stand-in fits shaped as MuJoCo's all-effects finger3 of seed 541 (the torque 1 sample late): the rotor's
    round is kept on its residual, the delay's 1.5 % above it is not; the observer fails the kept fit (its EKF without
    the delay), so the rounds within OBSERVER_RESIDUAL_RATIO are judged too, lowest residual first: the delay's
    passes and is kept, with its delay; a round 10 % above is never judged."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification import observer_check as oc
    from alpes_dyn.model.params import load_params

    residual = {(): 0.75, ("stiction",): 0.80, ("rotor",): 0.594, ("delay",): 0.603, ("offset",): 0.66}
    judged = []

    def fake_identify(model, data, parameters, **kw):
        d = _advanced_by(data)
        extra = ("delay",) if d else next((k for k in residual if k and k[0] in model.name), ())
        return SimpleNamespace(residual_rms=residual[extra], converged=True, reason="", names=(), values=[], std=[],
                               trustworthy=extra != (), effects=extra,
                               adequacy=SimpleNamespace(adequate=extra != (), likely_missing=[]))

    def fake_judge(result, recording, torque_delay=0, thresholds=None):
        judged.append((result.residual_rms, torque_delay))
        passed = torque_delay == 1
        if not passed:  # as judge: the fit's verdict not adequate, naming the observer
            result.adequacy.adequate = result.trustworthy = False
        return SimpleNamespace(passed=passed)

    def model_of(effects):
        return SimpleNamespace(name="+".join(e for e in effects if e in ("stiction", "rotor", "offset")))

    monkeypatch.setattr(ident_mod, "identify", fake_identify)
    monkeypatch.setattr(oc, "judge", fake_judge)
    monkeypatch.setattr(eff, "effect_parameters", lambda *a, **k: ())
    fit = eff.fit_effects(model_of, _ramp_recording(), eff.parse_effects("auto"), has_gravity=True)
    assert fit.result.residual_rms == 0.603 and fit.delay == 1 and fit.effects[-1] == "delay"
    assert fit.observer.passed and fit.tried.residual_rms == 0.594
    assert (0.66, 0) not in judged and judged[-1] == (0.603, 1)  # 0.66 is 11 % above: not as good a fit


def test_the_true_file_passes_the_observer_check_on_the_models_own_structure():
    """The observer's check never refuses the truth: on our simulator's recording of finger2 seed 3 (the fitted
    model's exact structure) the true file's EKF predicts the encoder 20 ms ahead within the threshold (measured
    16.0 times the floor, which the first threshold, 15, refused), the nominal file's far beyond it (310 times)."""
    import alpes_dyn as ad
    from alpes_dyn.estimation.experiments.adapt import adapted_experiment
    from alpes_dyn.estimation.experiments.draws import perturbed_params
    from alpes_dyn.estimation.identification.observer_check import OBSERVER_THRESHOLDS, observer_statistics

    true = perturbed_params(spread=0.2, seed=3)
    rec, _ = adapted_experiment("finger2", true, seed=3)
    good = observer_statistics(rec, ad.Model.alpes("finger2", friction=True, params=true))
    bad = observer_statistics(rec, ad.Model.alpes("finger2", friction=True))
    ratio = OBSERVER_THRESHOLDS["prediction_ratio"]
    assert good.passed and 12 * good.floor < good.prediction_rms < 0.8 * ratio * good.floor
    assert not bad.passed and bad.prediction_rms > 10 * ratio * bad.floor




def test_the_delay_search_goes_on_while_the_verdict_names_it(monkeypatch):
    """Past the first sample, one more is tried only while the last fit's verdict still names the torque delay:
    stand-in fits two samples late (the residual lowest at 2, the verdict naming the delay below it) stop at 3, whose
    residual is higher; fits one sample late stop at 1 (its verdict names nothing), never fitting 2."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.adequacy import SIGNATURES
    from alpes_dyn.model.params import load_params

    rec = _ramp_recording()

    def search(late):
        seen = []

        def fake_identify(model, data, parameters, **kw):
            d = _advanced_by(data)
            seen.append(d)
            ok = d == late
            missing = [SIGNATURES["torque_rate"]] if d < late else ["a nonlinearity"] if d > late else []
            return SimpleNamespace(residual_rms=0.6 + 0.1 * abs(d - late), converged=True, reason="", names=(),
                                   values=[], std=[], trustworthy=ok,
                                   adequacy=SimpleNamespace(adequate=ok, likely_missing=missing))

        monkeypatch.setattr(ident_mod, "identify", fake_identify)
        fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), rec, eff.parse_effects("auto"),
                              has_gravity=True, observe=False)
        return seen, fit

    seen, fit = search(2)
    assert seen == [0, 1, 2] and fit.delay == 2 and fit.result.trustworthy and fit.result.residual_rms == 0.6
    seen, fit = search(1)
    assert seen == [0, 1] and fit.delay == 1 and fit.result.trustworthy


def test_a_verdict_naming_a_nonlinearity_gets_no_encoder_offset_round(monkeypatch):
    """auto on stand-in fits flagged naming a nonlinearity (the residual's power at the excitation's harmonics, as
    MuJoCo's all-effects finger3 turned halfway, seeds 588 and 606): stick-slip, the rotor and the delay are tried,
    not the encoder's offset (a constant in the output makes no harmonics; its round only nudged a borderline
    verdict there, the offset wrong-signed); the same fits naming nothing get the offset's round last."""
    from types import SimpleNamespace

    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.harmonics import NONLINEARITY
    from alpes_dyn.model.params import load_params

    for missing, last in (([NONLINEARITY], ("compliance", "tilt", "delay")),
                          ([], ("compliance", "tilt", "offset"))):
        def fake_identify(model, data, parameters, missing=missing, **kw):
            return SimpleNamespace(residual_rms=0.6, converged=True, reason="", names=(), values=[], std=[],
                                   trustworthy=False, adequacy=SimpleNamespace(adequate=False, likely_missing=missing))

        monkeypatch.setattr(ident_mod, "identify", fake_identify)
        fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), _ramp_recording(),
                              eff.parse_effects("auto"), has_gravity=True, observe=False)
        assert [e for e, _ in fit.rounds][-1] == last
        assert all("offset" not in e for e, _ in fit.rounds) == bool(missing)
