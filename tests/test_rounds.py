"""The rounds of ``--effects auto`` as data (:mod:`alpes_dyn.estimation.identification.rounds`): the table is the
module's documented one, each round's proposal and acceptance rule alone on stand-in fits, and one round played on
a short simulated recording with real fits."""

from __future__ import annotations

import dataclasses
import re
from types import SimpleNamespace

import numpy as np
import pytest

from alpes_dyn.estimation.identification import rounds as rd
from alpes_dyn.estimation.identification.adequacy import JOINT_STOP, SIGNATURES
from alpes_dyn.estimation.identification.harmonics import NONLINEARITY

ROW = {r.name: r for r in rd.ROUNDS}
KEPT = ("compliance", "tilt")


def fit(residual=0.6, ok=False, missing=(), converged=True, reason="", names=(), values=(), std=()):
    """A stand-in fit: what the rounds read of an IdentificationResult."""
    return SimpleNamespace(residual_rms=residual, converged=converged, reason=reason, trustworthy=ok,
                           names=tuple(names), values=list(values), std=list(std),
                           adequacy=SimpleNamespace(adequate=ok, likely_missing=list(missing),
                                                    floor_ratio=residual / 0.575))


def test_the_table_is_the_documented_one():
    """The module docstring's table lists the rounds of ROUNDS, in order, each with its stage; the fallback
    effects are the four the user guide names, in its order."""
    documented = re.findall(r"^``([a-z ]+)``\s+(\w+)\s", rd.__doc__, flags=re.M)
    assert documented == [(r.name, r.stage) for r in rd.ROUNDS]
    assert rd.FALLBACK == ("stiction", "rotor", "delay", "offset")
    assert [r.name for r in rd.rounds_of("auto")] == ["creep", "asked", "lugre", "stiction", "rotor", "delay", "offset"]
    assert all(r.start_from == "kept" for r in rd.rounds_of("auto") + rd.rounds_of("cable")
               if r.name not in ("lugre", "creep"))
    assert ROW["lugre"].start_from == ROW["creep"].start_from == "kept, its friction the file's"


def test_first_and_staged_rounds():
    """The first round fits the effects asked for and is kept whatever it is; the staged start is made only for a
    first fit that lost its basin with an effect beyond stiction and the rotor, each stage kept where it converged."""
    assert ROW["first"].proposal(None, KEPT) == KEPT and ROW["first"].accepts(fit(9.0), fit(0.1))
    lost = fit(14.4, converged=False, reason="lost basin: three steps", missing=[JOINT_STOP])
    assert ROW["staged"].proposal(lost, KEPT) == KEPT
    assert ROW["staged"].proposal(lost, ("stiction", "rotor")) is None
    assert ROW["staged"].proposal(fit(14.4, converged=False, reason="iteration cap"), KEPT) is None
    assert ROW["staged"].accepts(fit(9.0), lost) and not ROW["staged"].accepts(lost, fit(0.6))


def test_the_asked_round():
    """What the kept fit asks for: the effects its verdict names, not yet tried; the rotor where a compliance is
    above three standard errors, in place of a kept tendon-sheath friction; the tendon-sheath friction alone;
    nothing for an adequate fit. Kept on a lower residual."""
    asked = ROW["asked"]
    stick = "stick-slip / Coulomb friction"
    assert asked.proposal(fit(missing=[stick, SIGNATURES["torque_rate"]]), KEPT) == KEPT + ("stiction", "delay")
    assert asked.proposal(fit(missing=[stick]), KEPT, {"stiction"}) is None
    stretching = dict(names=("K_1", "tendon_compliance_finger"), values=[0.04, 6.0], std=[1e-4, 0.2])
    assert asked.proposal(fit(**stretching), KEPT) == KEPT + ("rotor",)
    assert asked.proposal(fit(ok=True, **stretching), KEPT) == KEPT + ("rotor",)  # adequate, but stretching
    assert asked.proposal(fit(**stretching), KEPT, {"rotor"}) is None
    within = dict(names=("tendon_compliance_finger",), values=[0.5], std=[0.2])  # 2.5 standard errors
    assert asked.proposal(fit(**within), KEPT) is None
    sheath = "tendon-sheath friction (a torque following the tension times the sign of the motor velocity)"
    assert asked.proposal(fit(missing=[stick, sheath], **stretching), KEPT) == KEPT + ("capstan",)
    # the rotor in place of a kept sheath friction (the thumb's walk: capstan kept, then the cable seen stretching)
    assert asked.proposal(fit(**stretching), KEPT + ("capstan",), {"capstan"}) == KEPT + ("rotor",)
    assert asked.proposal(fit(missing=[stick]), KEPT + ("capstan",), {"capstan"}) == KEPT + ("capstan", "stiction")
    assert asked.proposal(fit(ok=True, missing=[stick]), KEPT) is None
    assert asked.accepts(fit(0.59), fit(0.6)) and not asked.accepts(fit(0.6), fit(0.6))


def test_the_creep_round():
    """A fit not to be trusted that drove a joint's F_s below a tenth of the file's (a dry friction read as viscous)
    gets the creep law, the other friction laws taken off, once; not an adequate fit, not one whose F_s held, not a
    model without a parameter file; the verdict's creep word alone makes it too. Kept on a lower residual."""
    from alpes_dyn import Model
    from alpes_dyn.estimation.identification.creep import CREEP

    model = Model.alpes("finger3", friction=True)
    Fs = model.extras.coulomb
    gone = dict(names=("K_1", "F_s_1", "F_s_2"), values=[0.04, Fs[0], 0.05 * Fs[1]])
    held = dict(names=("K_1", "F_s_1", "F_s_2"), values=[0.04, Fs[0], 0.5 * Fs[1]])
    creep = ROW["creep"]
    assert creep.proposal(_with(fit(converged=False, **gone), model), KEPT + ("stiction",)) == KEPT + ("creep",)
    assert creep.proposal(_with(fit(**gone), model), KEPT, {"creep"}) is None
    assert creep.proposal(_with(fit(ok=True, **gone), model), KEPT) is None
    assert creep.proposal(_with(fit(**held), model), KEPT) is None
    assert creep.proposal(_with(fit(missing=[CREEP], **held), model), KEPT) == KEPT + ("creep",)
    assert creep.proposal(fit(**gone), KEPT) is None  # no model, no parameter file
    assert creep.accepts(fit(0.5), fit(9.6)) and not creep.accepts(fit(9.7), fit(9.6))


def test_the_creep_round_where_the_lost_basin_held_the_collapse():
    """The fit kept on a soft MuJoCo friction (the study's soft case): F_s_1 at a third of the file's (no collapse),
    F_s_2 and F_s_3 held at the file's after the fit's steps ran them towards 0 (runaway.friction_held's clause,
    which hid the collapse from the rule): the creep round is made, first of the auto rows (before the asked round's
    rotor and delay); not where the held F_s ran upwards, nor for a trusted fit, nor once tried; its verdict then
    names the creep first."""
    from alpes_dyn import Model
    from alpes_dyn.estimation.identification.creep import CREEP, RAN_DOWN, name_creep

    model = Model.alpes("finger3", friction=True)
    Fs = model.extras.coulomb
    names = ("K_1", "K_2", "K_3", "F_s_1", "F_v_1", "F_v_2", "F_v_3")
    values = [0.04, 0.06, 0.06, Fs[0] / 3.0, 2e-4, 7e-5, 2e-4]
    held = {f"F_s_{j}": f"held at the model's value: the fit's steps {RAN_DOWN}, to 3e-05 from 0.0005 (lost basin)"
            for j in (2, 3)}
    missing = ["rotor inertia (a torque following the motor acceleration)", SIGNATURES["torque_rate"]]

    def kept(ok=False, clauses=held):
        return _with(SimpleNamespace(**vars(fit(2.7, ok=ok, missing=missing, names=names, values=values)),
                                     not_identified=dict(clauses)), model)

    made = [(r.name, r.proposal(kept(), KEPT)) for r in rd.rounds_of("auto")]
    assert next((n, e) for n, e in made if e is not None) == ("creep", KEPT + ("creep",))
    up = {n: c.replace(f"{RAN_DOWN}, to 3e-05", "ran it off") for n, c in held.items()}
    assert ROW["creep"].proposal(kept(clauses=up), KEPT) is None
    assert ROW["creep"].proposal(kept(clauses={}), KEPT) is None
    assert ROW["creep"].proposal(kept(ok=True), KEPT) is None
    assert ROW["creep"].proposal(kept(), KEPT, {"creep"}) is None
    refused = kept()
    note = name_creep(refused, {"F_s_1": Fs[0], "F_s_2": Fs[1], "F_s_3": Fs[2]})
    assert "F_s_2 held at the file's value" in note and "F_s_3" in note and "F_s_1" not in note
    assert refused.adequacy.likely_missing[0] == CREEP and len(refused.adequacy.likely_missing) == 3


def _with(stand_in, model):
    stand_in.model = model
    return stand_in


@pytest.mark.parametrize("effect", ["stiction", "rotor", "delay", "offset"])
def test_the_flagged_rounds(effect):
    """A flagged fit asking for nothing gets each fallback effect once; an adequate one none; the offset not where
    the verdict names a nonlinearity (a constant in the output makes no harmonics)."""
    rnd = ROW[effect]
    assert rnd.proposal(fit(), KEPT) == KEPT + (effect,)
    assert rnd.proposal(fit(ok=True), KEPT) is None
    assert rnd.proposal(fit(), KEPT, {effect}) is None
    assert (rnd.proposal(fit(missing=[NONLINEARITY]), KEPT) is None) == (effect == "offset")
    assert rnd.accepts(fit(0.5), fit(0.6)) and not rnd.accepts(fit(0.7), fit(0.6))
    # a fit stopped by its cap never replaces a converged one, only one that did not converge either
    assert not rnd.accepts(fit(0.5, converged=False), fit(0.6))
    assert rnd.accepts(fit(0.5, converged=False), fit(0.6, converged=False))


def test_the_rigid_cable_round():
    """A compliance below minus three standard errors (a cable shortening under tension): the round without it,
    kept where it converges; within three standard errors, no round."""
    rnd = ROW["rigid cable"]
    short = dict(names=("K_1", "tendon_compliance_finger"), values=[0.04, -0.42], std=[1e-4, 0.1])
    assert rnd.proposal(fit(ok=True, **short), KEPT) == ("tilt",)
    assert rnd.proposal(fit(ok=True, **short), ("tilt",)) is None
    assert rnd.proposal(fit(ok=True, names=short["names"], values=[0.04, -0.25], std=short["std"]), KEPT) is None
    assert rnd.accepts(fit(0.9), fit(0.6)) and not rnd.accepts(fit(0.5, converged=False), fit(0.6))


def test_each_round_is_made_once_and_the_walk_follows_the_table():
    """The walk of the auto stage on stand-ins always flagged naming nothing: the fallback rounds in the table's
    order, each once, then none (every rule's proposal None)."""
    kept_effects, attempted, made = KEPT, set(KEPT), []
    flagged = fit()
    while (rnd := next((r for r in rd.rounds_of("auto") if r.proposal(flagged, kept_effects, attempted)), None)):
        effs = rnd.proposal(flagged, kept_effects, attempted)
        attempted.update(effs)
        made.append(rnd.name)
    assert made == list(rd.FALLBACK)


def test_one_round_played_on_a_simulated_recording():
    """One round alone with real fits: the first fit (compliance) on 1 s of our simulator's finger2 drawn 10 % off,
    then the rotor round (its proposal forced: the first fit is adequate) from it. The round starts from the kept
    fit (its values and trajectory), is recorded, and is kept exactly where its residual is lower (the acceptance rule),
    the other fit being ``tried``."""
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.effects import Kept, RoundWalker, alpes_models
    from alpes_dyn.model.params import load_params

    design = ExperimentDesign(duration=1.0)
    rec = experiment("finger2", perturbed_params(spread=0.1, seed=2), design=design, seed=2)
    starts, depth = [], []
    real = ident_mod.identify

    def spy(*args, **kw):  # the rounds' calls, not identify's own refit of a parameter it holds
        if not depth:
            starts.append(kw.get("start"))
        depth.append(1)
        try:
            return real(*args, **kw)
        finally:
            depth.pop()

    walk = RoundWalker(alpes_models("finger2", load_params()), rec, True, None, {"excitation": design.lines})
    mp = pytest.MonkeyPatch()
    mp.setattr(ident_mod, "identify", spy)
    try:
        kept = walk.first(("compliance",))
        first = kept.result
        assert first.converged and ROW["rotor"].proposal(first, kept.effects, walk.attempted) is None  # adequate
        forced = dataclasses.replace(ROW["rotor"], propose=lambda res, effs, att: effs + ("rotor",))
        assert walk.play(forced, kept)
    finally:
        mp.undo()
    (e1, r1), (e2, r2) = walk.rounds
    assert e1 == ("compliance",) and e2 == ("compliance", "rotor") and r1 is first
    assert len(starts) == 2 and starts[0] is None and starts[1] is first  # the rotor's round from the first fit
    lower = r2.residual_rms < r1.residual_rms
    assert (kept.result is r2) == lower and (kept.tried is (r1 if lower else r2))
    assert kept.effects == (e2 if lower else e1)
    assert np.isfinite(r2.residual_rms) and r2.converged


def test_kept_take_and_refuse():
    """Kept: a taken fit makes the former one ``tried``; a refused fit is ``tried``."""
    from alpes_dyn.estimation.identification.effects import Kept

    a, b, c = fit(0.6), fit(0.5), fit(0.7)
    k = Kept(a, KEPT)
    k.take(b, KEPT + ("rotor",))
    assert k.result is b and k.tried is a and k.tried_effects == KEPT
    k.refuse(c, KEPT + ("delay",))
    assert k.result is b and k.tried is c and k.tried_effects == KEPT + ("delay",)


def test_a_round_whose_fit_diverges_is_refused_the_kept_fit_stays(monkeypatch):
    """A round of the auto stage whose fit overflows (FitDiverged: ``experiment --rig both --duration 0.2``'s record,
    100 samples an orientation, diverged in a later round) is refused with a note, its overflow warnings dropped;
    the kept fit stays (the command wrote the fit before it, not "are the encoders in counts?"). Any other error
    still stops the walk."""
    import warnings

    from alpes_dyn.estimation.identification.effects import Kept, RoundWalker
    from alpes_dyn.estimation.identification.shooting import FitDiverged

    walk = RoundWalker(lambda effs: None, _recording(np.zeros((200, 1)), ("finger",)), True, None, {})
    kept = Kept(fit(0.6), KEPT)

    def diverging(effs, warm=None):
        warnings.warn("overflow encountered in exp", RuntimeWarning)
        raise FitDiverged("identify: the fit diverged")

    monkeypatch.setattr(walk, "run", diverging)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        assert walk.play(ROW["stiction"], kept) is True
    assert kept.result.residual_rms == pytest.approx(0.6) and kept.tried is None and not seen
    assert walk.notes == ["round stiction (compliance+tilt+stiction): identify: the fit diverged; the fit kept before "
                          "it stands"]
    monkeypatch.setattr(walk, "run", lambda effs, warm=None: (_ for _ in ()).throw(ValueError("other")))
    with pytest.raises(ValueError, match="other"):
        walk.play(ROW["rotor"], kept)


def _recording(torque, names):
    """A stand-in recording: what :func:`still_motors` reads (the torque (N, m), N m, and the motors' names)."""
    return SimpleNamespace(torque=np.asarray(torque, dtype=float), motor_names=tuple(names))


def test_still_motors_are_those_whose_torque_is_its_noise():
    """A motor held relaxed (its torque white noise about a constant, or exactly 0) did not move; an excited one
    (a slow sine under the same noise) did; the noise found is the noise drawn (within 5 %), the spread the
    column's standard deviation."""
    from alpes_dyn.estimation.identification.effects import MOVED_RATIO, still_motors

    rng = np.random.default_rng(0)
    t = np.arange(4000) * 1e-3
    noise = 5e-4 * rng.standard_normal((t.size, 3))
    tau = np.column_stack([0.02 + 0.004 * np.sin(2 * np.pi * 1.5 * t), 0.01 + 0 * t, 0 * t]) + noise
    tau[:, 2] = 0.0
    still = still_motors(_recording(tau, ("flexion", "held", "off")))
    assert list(still) == ["held", "off"]
    spread, found = still["held"]
    assert spread == pytest.approx(np.std(tau[:, 1]), rel=1e-9) and found == pytest.approx(5e-4, rel=0.05)
    assert still["off"] == (0.0, 0.0)
    # the excited motor's spread is many times its noise; a sine just below the ratio's spread is still
    assert np.std(tau[:, 0]) > 2.5 * MOVED_RATIO * 5e-4
    small = 0.01 + 5e-4 * rng.standard_normal(t.size) + 0.9 * 5e-4 * np.sqrt(2) * np.sin(2 * np.pi * 1.5 * t)
    assert list(still_motors(_recording(small[:, None], ("m",)))) == ["m"]


def test_compliance_of_a_still_motor_is_held_and_named():
    """The thumb (its flexion and ab/adduction motors): with the ab/adduction still, ``--effects`` compliance fits
    the flexion's compliance only (the catalogue's other names as selected without it); each fit the walker makes
    names the held one in ``not_identified``, with its spread and noise; without a still motor, the kind as before."""
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.effects import RoundWalker, alpes_models, effect_parameters
    from alpes_dyn.model.params import load_params
    from alpes_dyn.model.robot import Model
    from alpes_dyn.symbolic.parametric import select_parameters

    thumb = Model.alpes("thumb", friction=True)
    every = [p.name for p in select_parameters(thumb, effect_parameters(thumb, ("compliance",), True))]
    assert {"tendon_compliance_thumb", "tendon_compliance_thumb_abduction"} <= set(every)
    held = [p.name for p in select_parameters(thumb, effect_parameters(thumb, ("compliance",), True, None,
                                                                       ("thumb_abduction",)))]
    assert held == [n for n in every if n != "tendon_compliance_thumb_abduction"]
    assert effect_parameters(thumb, ("tilt",), True, None, ("thumb_abduction",)) is None  # no compliance asked

    rng = np.random.default_rng(1)
    t = np.arange(2000) * 1e-3
    tau = np.column_stack([0.02 + 0.004 * np.sin(2 * np.pi * t), np.zeros_like(t)]) + 5e-4 * rng.standard_normal(
        (t.size, 2))
    rec = _recording(tau, thumb.transmission.motor_names)
    seen = []

    def stand_in(model, recording, selection, **kw):  # what the walker asks of identify, a fit returned
        seen.append(selection)
        return SimpleNamespace(not_identified={"K_1": "kept"}, torque_delay=None)

    mp = pytest.MonkeyPatch()
    mp.setattr(ident_mod, "identify", stand_in)
    try:
        walk = RoundWalker(alpes_models("thumb", load_params()), rec, True, None, {})
        res = walk.one(("compliance", "tilt"), None, 0)
        plain = walk.one(("tilt",), None, 0)
    finally:
        mp.undo()
    assert list(walk.still) == ["thumb_abduction"]
    assert "tendon_compliance_thumb" in seen[0] and "tendon_compliance_thumb_abduction" not in seen[0]
    why = res.not_identified["tendon_compliance_thumb_abduction"]
    assert "did not move" in why and "held at 0" in why and res.not_identified["K_1"] == "kept"
    assert seen[1] is None and list(plain.not_identified) == ["K_1"]  # the default selection: no compliance


def test_the_creep_round_where_the_verdict_names_the_band():
    """The fits kept on two soft MuJoCo frictions (the study's soft case) held every F_s at 0.13-0.3 of the file's
    (no collapse, nothing held) and their verdicts named viscous friction and a friction with a state: the creep
    band's look, so the creep round is made, first of the auto rows; not for an adequate fit, not once tried, not
    where the verdict names neither (a stick-slip)."""
    from alpes_dyn import Model

    model = Model.alpes("finger3", friction=True)
    Fs = model.extras.coulomb
    shrunk = dict(names=("K_1", "F_s_1", "F_s_2", "F_s_3"), values=[0.035, 0.3 * Fs[0], 0.134 * Fs[1], 0.27 * Fs[2]])
    stateful = rd.STATEFUL_WORD + " (the residual at the velocity reversals or at the excitation's harmonics)"
    for missing in ([SIGNATURES["velocity"], stateful, NONLINEARITY], [stateful], [SIGNATURES["velocity"]]):
        made = [(r.name, r.proposal(_with(fit(2.66, missing=missing, **shrunk), model), KEPT + ("stiction",)))
                for r in rd.rounds_of("auto")]
        assert next((n, e) for n, e in made if e is not None) == ("creep", KEPT + ("creep",))
    assert ROW["creep"].proposal(_with(fit(ok=True, missing=[stateful], **shrunk), model), KEPT) is None
    assert ROW["creep"].proposal(_with(fit(missing=[stateful], **shrunk), model), KEPT, {"creep"}) is None
    stick = "stick-slip / Coulomb friction (a torque following the sign of the motor velocity)"
    assert ROW["creep"].proposal(_with(fit(missing=[stick], **shrunk), model), KEPT) is None
    # a stick-slip plant's smooth fit at 1.2 floors names a friction with a state too: not the band (BAND_FLOOR_RATIO)
    assert ROW["creep"].proposal(_with(fit(0.69, missing=[stateful], **shrunk), model), KEPT) is None


def test_a_refused_stick_slip_fit_names_the_friction_that_sticks():
    """A fit kept with the stick-slip law, refused naming a friction with a state within two sensor floors after the
    LuGre round was not kept (MuJoCo's stiff frictionloss at three times F_s): its verdict names the dry friction
    that sticks (the switched law, which the observer check did not choose on the record: friction.observer_law) in
    place of LuGre's presliding, the rest kept, and it stays refused; not where the LuGre law was not tried or was kept, not without the stick-slip law,
    not at the creep band's residual, not on an adequate fit or a verdict naming no friction with a state."""
    stateful = rd.STATEFUL_WORD + " (the residual at the velocity reversals or at the excitation's harmonics)"
    stick = KEPT + ("stiction",)
    tried = set(KEPT) | {"lugre", "stiction", "rotor"}
    refused = fit(0.615, missing=[SIGNATURES["velocity"], stateful, NONLINEARITY])  # 1.07 floors
    assert rd.sticking(refused, stick, tried)
    note = rd.name_sticking(refused, stick, tried)
    assert note is not None and "1.07x" in note and "friction.observer_law" in note
    assert "--friction-law stick" not in note  # the file says the law its observer runs: nothing to pass by hand
    assert refused.adequacy.likely_missing == [rd.STUCK_FRICTION, SIGNATURES["velocity"], NONLINEARITY]
    assert not refused.adequacy.adequate and "LuGre law;" not in " ".join(refused.adequacy.likely_missing)
    for result, effects, attempted in (
            (fit(0.615, missing=[stateful]), stick, tried - {"lugre"}),  # LuGre not tried
            (fit(0.615, missing=[stateful]), KEPT + ("lugre",), tried),  # LuGre kept
            (fit(0.615, missing=[stateful]), KEPT, tried),  # no stick-slip law
            (fit(1.3, missing=[stateful]), stick, tried),  # 2.26 floors: the creep band's
            (fit(0.615, missing=[NONLINEARITY]), stick, tried),  # no friction with a state named
            (fit(0.615, ok=True), stick, tried)):  # adequate
        before = list(result.adequacy.likely_missing)
        assert rd.name_sticking(result, effects, attempted) is None
        assert result.adequacy.likely_missing == before
