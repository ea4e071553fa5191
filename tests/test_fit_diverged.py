"""A fit that runs away (its parameters or states overflowing to NaN or inf): the solver refuses the step that
makes it, a round of ``--effects auto`` whose fit diverges is a failed round (the kept fit stands, the walk goes on,
the round named in the notes), and ``identify`` names the units only where the recording's are implausible."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from alpes_dyn.errors import RecordingError
from alpes_dyn.estimation.identification import rounds as rd
from alpes_dyn.estimation.identification.effects import Kept, RoundWalker
from alpes_dyn.estimation.identification.gauss_newton import GaussNewton
from alpes_dyn.estimation.identification.shooting import FitDiverged

KEPT = ("compliance", "tilt")


def fit(residual, ok=False):
    """A stand-in fit, flagged and asking for nothing (what the rounds read of an IdentificationResult)."""
    return SimpleNamespace(residual_rms=residual, converged=True, reason="converged", trustworthy=ok, names=(),
                           values=[], std=[], model=None,
                           adequacy=SimpleNamespace(adequate=ok, likely_missing=[]))


def walker(one):
    """A RoundWalker on a stand-in recording (two motors whose torque moved) whose fits are ``one(effs)``."""
    rec = SimpleNamespace(torque=np.column_stack([np.sin(np.arange(200.0)), np.cos(np.arange(200.0))]),
                          motor_names=("a", "b"))
    walk = RoundWalker(lambda effs: None, rec, False, None, {})

    def made(effs, warm, delay):
        res = one(effs)
        walk.rounds.append((effs, res))
        walk.delays[id(res)] = delay
        return res

    walk.one = made
    return walk


def test_a_round_that_diverges_is_a_failed_round_and_the_walk_goes_on():
    """The auto stage on a flagged fit asking for nothing: the stick-slip round's fit overflows (FitDiverged, as the
    LuGre round's did on a bench recording); the kept fit stands, the note names the round, and the next rounds
    (the rotor, which fits better and is kept; the delay) are made from the kept fit."""
    first, rotor = fit(0.9), fit(0.7)

    def one(effs):
        if "stiction" in effs:
            raise FitDiverged("identify: the fit diverged (its parameters or states overflowed to NaN or inf)")
        return rotor if effs[-1] == "rotor" else fit(0.8)

    walk = walker(one)
    kept = Kept(first, KEPT)
    walk.attempted.update(KEPT)
    walk.auto(kept)
    made = [e[-1] for e, _ in walk.rounds]
    assert made == ["rotor", "delay", "offset"]  # the walk went on after the stick-slip round failed
    assert kept.result is rotor and kept.effects == KEPT + ("rotor",)
    assert "stiction" in walk.attempted  # not tried again
    assert len(walk.notes) == 1 and walk.notes[0].startswith("round stiction (compliance+tilt+stiction): identify: "
                                                             "the fit diverged")
    assert "stands" in walk.notes[0]


def test_a_diverging_stage_keeps_the_last_converged_one():
    """The staged start: the rigid fit converges, adding the compliance runs away: the rigid fit is kept, named."""
    rigid = fit(0.9)

    def one(effs):
        if effs:
            raise FitDiverged("identify: the fit diverged (its parameters or states overflowed to NaN or inf)")
        return rigid

    walk = walker(one)
    lost = SimpleNamespace(converged=False, reason="lost basin", residual_rms=30.0)
    best, effs = walk.staged(KEPT, lost)
    assert best is rigid and effs == ()
    assert any(n.startswith("round staged (compliance)") for n in walk.notes)
    assert any("adding compliance to the converged rigid fit broke it (it diverged)" in n for n in walk.notes)


class _Overflowing:
    """A stand-in shooting problem whose every evaluation beyond ``limit`` in the first parameter overflows."""

    n_int, nx, nb, nv, nz, limit = 2, 1, 1, 2, 3, 5.0

    def evaluate(self, nodes, offs, glob, jac=True):
        if abs(glob[0]) > self.limit:
            raise FitDiverged("identify: the fit diverged (its parameters or states overflowed to NaN or inf)")
        return SimpleNamespace(r=np.array([[glob[0]]]), c=np.zeros((1, 1)), cost=0.5 * float(glob[0]) ** 2)


def test_the_solver_refuses_a_step_that_overflows():
    """GaussNewton.trial: None where the point overflows (a refused step, not an error), the evaluation where
    finite; the continuity correction (restore) that would overflow restores nothing (it ended a bench fit)."""
    pb, z = _Overflowing(), np.zeros((2, 1))
    assert GaussNewton.trial(pb, z, z, np.array([1e3])) is None
    ok = GaussNewton.trial(pb, z, z, np.array([2.0]))
    assert ok is not None and ok.cost == pytest.approx(2.0)
    at = SimpleNamespace(c=np.ones((1, 1)), cost=0.0, J=None, Cv=None, Cr=None, normal=None, point=None)

    def solve_K(rhs):  # a correction whose parameter part runs away (a lost basin's linearisation)
        return np.array([0.0, 0.0, 1e300, 0.0])

    assert GaussNewton.restore(pb, z, z, np.zeros(1), at, solve_K, np.ones(1), 1.0) is None


def test_identify_names_units_only_where_the_data_say_so(monkeypatch):
    """A fit that overflows from its start on a recording of plausible units: the error names the fit, not the
    units; on an encoder column far beyond the joints' ranges (a Recording object, not read by the reader's
    checks): the RecordingError naming the column."""
    import dataclasses

    from alpes_dyn import Model
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment
    from alpes_dyn.estimation.identification import identification as ident_mod

    model = Model.alpes("finger2", friction=True)
    rec = experiment("finger2", design=ExperimentDesign(duration=0.2), seed=3)

    def runaway(self, *args, **kw):
        raise FitDiverged("identify: the fit diverged (its parameters or states overflowed to NaN or inf)")

    monkeypatch.setattr(GaussNewton, "solve", runaway)
    with pytest.raises(FitDiverged) as err:
        ident_mod.identify(model, rec, "K", interval=0.05)
    msg = str(err.value)
    assert "plausible units" in msg and "in counts" not in msg and "N m?" not in msg
    enc = rec.encoder.copy()
    enc[50:] = 1e15
    with pytest.raises(RecordingError, match="counts is beyond what the joint ranges allow"):
        ident_mod.identify(model, dataclasses.replace(rec, encoder=enc), "K", interval=0.05)


def test_a_basin_lost_on_a_friction_is_fitted_again_with_it_held():
    """A fit that lost its basin with a joint's dry friction asking for the farthest steps (named in its reason):
    the fit again from the model's values without it, it named not identified; a lost basin on a mass is left as
    it is (the staged start's), as is a converged fit."""
    from alpes_dyn import Model
    from alpes_dyn.estimation.identification import runaway
    from alpes_dyn.estimation.identification.creep import RAN_DOWN

    model = Model.alpes("finger2", friction=True)
    names = ("K_1", "K_2", "m_1", "m_2", "F_s_1", "F_s_2")
    calls = []

    def again(model, recording, parameters, **kw):
        calls.append((tuple(parameters), kw))
        return SimpleNamespace(converged=True, residual_rms=2.3, not_identified={}, iterations=9, seconds=1.0,
                               reason="converged")

    lost = "lost basin: three Gauss-Newton steps in a row asked log theta to move by more than 30 (iteration 13; " \
           "the farthest: {})"
    Fs = model.extras.coulomb
    first = SimpleNamespace(names=names, converged=False, residual_rms=39.2, iterations=13, reason=lost.format("F_s_1"),
                            values=np.array([0.04, 0.06, 0.02, 0.01, 3.0 * Fs[0], Fs[1]]))
    out = runaway.friction_held(again, model, "rec.csv", first, {"interval": 0.05}, 0.0)
    assert calls == [(("K_1", "K_2", "m_1", "m_2", "F_s_2"), {"interval": 0.05})]
    assert out.converged and list(out.not_identified) == ["F_s_1"] and "dry friction" in out.not_identified["F_s_1"]
    assert RAN_DOWN not in out.not_identified["F_s_1"]  # it ran upwards: not the creep round's trigger
    falling = SimpleNamespace(**{**vars(first), "values": np.array([0.04, 0.06, 0.02, 0.01, 0.3 * Fs[0], Fs[1]])})
    clause = runaway.friction_held(again, model, "rec.csv", falling, {}, 0.0).not_identified["F_s_1"]
    assert f"{RAN_DOWN}, to {0.3 * Fs[0]:.2g} from {Fs[0]:.2g}" in clause
    assert "fitted again with F_s_1 held" in out.reason and out.iterations == 22
    on_mass = SimpleNamespace(**{**vars(first), "reason": lost.format("m_2")})
    assert runaway.friction_held(again, model, "rec.csv", on_mass, {}, 0.0) is on_mass
    done = SimpleNamespace(**{**vars(first), "converged": True, "reason": "converged"})
    assert runaway.friction_held(again, model, "rec.csv", done, {}, 0.0) is done and len(calls) == 2
