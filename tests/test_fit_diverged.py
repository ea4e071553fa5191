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


def _singular_kkt_error(monkeypatch):
    """The LinAlgError of the shooting fit's undamped KKT system whose band is singular and too large for the dense
    least-squares fallback (the joined two-rig record's LuGre round: interval 0's last state, a bristle deflection
    relaxed within the interval, seen by nothing): the sparse fallback of a matrix over DENSE_LIMIT rows."""
    from alpes_dyn.estimation.identification import kkt

    shape = kkt.Shape(n_int=6, nb=3, nx=2, ng=2)
    rng = np.random.default_rng(1)
    J = rng.normal(size=(shape.n_int, 5, shape.nb + shape.ng))
    Cv = rng.normal(size=(shape.n_int - 1, shape.nx, shape.nb))
    Cr = rng.normal(size=(shape.n_int - 1, shape.nx, shape.ng))
    J[0, :, shape.nb - 1] = 0.0  # interval 0's last local variable: no residual sees it, nor its continuity
    Cv[0, :, shape.nb - 1] = 0.0
    prior = np.zeros(shape.ng)
    K = kkt.kkt_matrix(kkt.normal_matrix(J, shape, 0.0, prior), kkt.continuity_jacobian(Cv, Cr, shape))
    monkeypatch.setattr(kkt, "DENSE_LIMIT", K.shape[0] - 1)  # the record's 5805 rows against 4000, made small
    with pytest.raises(np.linalg.LinAlgError, match=f"{K.shape[0]}-row system is singular") as err:
        kkt.kkt_from_blocks(J, Cv, Cr, shape, 0.0, prior, lambda: kkt.factorize(K))
    return err.value


@pytest.mark.parametrize("where", ["solve", "conclude"])
def test_a_singular_system_beyond_the_fallback_is_a_failed_round_not_an_internal_error(monkeypatch, where):
    """Issue 49's internal error (``the shooting fit's 5805-row system is singular`` out of the LuGre round of a
    joined two-rig record): the LinAlgError of a singular KKT system too large for the least-squares fallback, in
    the solver or in the covariance at the fit's end, leaves ``identify`` as a FitSingular (a FitDiverged, an
    InputError: exit 2 with one line), and a round of ``--effects auto`` that raises it is a failed round, named."""
    from alpes_dyn import Model
    from alpes_dyn.errors import InputError
    from alpes_dyn.estimation.experiments.experiment import ExperimentDesign, experiment
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.shooting import FitSingular, ShootingProblem

    exc = _singular_kkt_error(monkeypatch)
    model = Model.alpes("finger2", friction=True)
    rec = experiment("finger2", design=ExperimentDesign(duration=0.2), seed=3)

    def singular(*args, **kw):
        raise exc

    if where == "solve":
        monkeypatch.setattr(GaussNewton, "solve", singular)
    else:  # the fit converged; the covariance's undamped system is the singular one
        done = SimpleNamespace(iterations=3, reason="converged", at=SimpleNamespace(r=None))
        monkeypatch.setattr(GaussNewton, "solve", lambda *a, **kw: done)
        monkeypatch.setattr(ShootingProblem, "encoder_rms", lambda self, r: 0.0)
        monkeypatch.setattr(ident_mod, "_conclude", singular)
    with pytest.raises(FitSingular) as err:
        ident_mod.identify(model, rec, "K", interval=0.05)
    assert isinstance(err.value, InputError) and isinstance(err.value, FitDiverged)
    msg = str(err.value)
    assert "system is singular" in msg and "does not see" in msg and "\n" not in msg
    first, rotor = fit(0.9), fit(0.7)

    def one(effs):
        if "lugre" in effs:
            raise err.value
        return rotor if effs[-1] == "rotor" else fit(0.8)

    walk = walker(one)
    assert walk.attempt("lugre", KEPT + ("lugre",), first) is None
    assert walk.notes == [f"round lugre (compliance+tilt+lugre): {msg}; the fit kept before it stands"]
