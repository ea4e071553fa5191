"""A refusal names a torque delay only where the data hold one (issue 50, item 4): on MuJoCo's default dry friction,
which creeps before it slides, a verdict had named a one-sample delay whose fit was worse than lag 0's.

References: stand-in fits whose residual at each lag is set here (the best match at lag 0, or at lag 1), and a
MuJoCo recording of the creeping friction (``solreffriction`` 0.02 s, MuJoCo's default) whose torque has no delay.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from test_realism_draws import _advanced_by, _ramp_recording


def _fits(best_lag: int, named_at: tuple[int, ...]):
    """A stand-in ``identify``: the residual 0.6 + 0.1 |lag - best_lag|, flagged everywhere, the verdict naming the
    torque delay at the lags ``named_at`` (a nonlinearity elsewhere)."""
    from alpes_dyn.estimation.identification.adequacy import SIGNATURES

    seen = []

    def fake_identify(model, data, parameters, **kw):
        d = _advanced_by(data)
        seen.append(d)
        missing = [SIGNATURES["torque_rate"]] if d in named_at else ["a nonlinearity"]
        return SimpleNamespace(residual_rms=0.6 + 0.1 * abs(d - best_lag), converged=True, reason="", names=(),
                               values=[], std=[], trustworthy=False,
                               adequacy=SimpleNamespace(adequate=False, likely_missing=list(missing)))

    return fake_identify, seen


def test_a_delay_whose_fit_is_worse_than_lag_0_is_not_named(monkeypatch):
    """The first fit's verdict names the torque delay, the fit a sample late leaves a larger residual: the fit kept
    at lag 0, flagged, no longer naming the delay, the note giving both residuals; where the late fit is better
    (a delay in the data) it is kept, and a verdict still naming the delay at a kept lag is left as it is."""
    from alpes_dyn.estimation.identification import effects as eff
    from alpes_dyn.estimation.identification import identification as ident_mod
    from alpes_dyn.estimation.identification.adequacy import SIGNATURES
    from alpes_dyn.model.params import load_params

    fake, seen = _fits(0, (0,))
    monkeypatch.setattr(ident_mod, "identify", fake)
    fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), _ramp_recording(),
                          eff.parse_effects("auto"), has_gravity=True, observe=False)
    assert 1 in seen and fit.delay == 0 and fit.result.residual_rms == pytest.approx(0.6)
    assert SIGNATURES["torque_rate"] not in fit.result.adequacy.likely_missing
    assert fit.result.adequacy.likely_missing == [] and not fit.result.trustworthy  # refused, naming no delay
    assert any("0.7 counts against 0.6 at lag 0: no torque delay" in n for n in fit.notes)
    fake, seen = _fits(1, (0, 1))
    monkeypatch.setattr(ident_mod, "identify", fake)
    fit = eff.fit_effects(eff.alpes_models("finger3", load_params()), _ramp_recording(), eff.parse_effects("auto"),
                          has_gravity=True, observe=False)
    assert fit.delay == 1 and SIGNATURES["torque_rate"] in fit.result.adequacy.likely_missing
    assert not any("no torque delay" in n for n in fit.notes)


def test_unmatched_delay_reads_only_the_rounds():
    """:func:`unmatched_delay` on its own: nothing changed for an adequate fit, a kept delay, a verdict not naming
    it, or no round made late."""
    from alpes_dyn.estimation.identification.adequacy import SIGNATURES
    from alpes_dyn.estimation.identification.effects import unmatched_delay

    def res(rms, names=True, adequate=False):
        return SimpleNamespace(residual_rms=rms, adequacy=SimpleNamespace(
            adequate=adequate, likely_missing=[SIGNATURES["torque_rate"]] if names else ["x"]))

    late = (("compliance", "delay"), res(0.9))
    assert unmatched_delay(res(0.6, adequate=True), [late], 0) is None
    assert unmatched_delay(res(0.6), [late], 1) is None
    assert unmatched_delay(res(0.6, names=False), [late], 0) is None
    assert unmatched_delay(res(0.6), [(("compliance",), res(0.6))], 0) is None
    assert unmatched_delay(res(0.95), [late], 0) is None  # the late fit better: a delay, kept named
    best = res(0.6)
    assert "no torque delay" in unmatched_delay(best, [late], 0) and best.adequacy.likely_missing == []
