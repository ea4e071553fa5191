"""A fit that runs away (issue 49): what :func:`~alpes_dyn.estimation.identification.identification.identify` does
where its start overflows (:func:`diverged`: the units named only where the recording's checks say so) and where it
lost its basin on a joint's friction (:func:`friction_held`: the fit again with it held). The solver's side (a step
that overflows refused) is :meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.trial`, the rounds'
(a round that diverges is a failed round) :meth:`~alpes_dyn.estimation.identification.effects.RoundWalker.attempt`."""

from __future__ import annotations

import time
import warnings
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ...model.robot import Model
from ...symbolic.parametric import parameter_catalogue
from ..experiments.recording import Recording
from .adequacy import AdequacyWarning
from .bounds import EFFECT_OF
from .creep import RAN_DOWN
from .fit_result import IdentificationResult
from .shooting import FitDiverged, FitSingular

__all__ = ["RUNAWAY_KINDS", "diverged", "friction_held"]


def diverged(exc: Exception, rec: Recording, model: Model) -> Exception:
    """The error of a fit that overflowed where no step was left to refuse (its start): the recording's unit
    checks (:mod:`~alpes_dyn.estimation.experiments.units`, which ``identify`` does not make on a Recording object)
    raise the :class:`~alpes_dyn.errors.RecordingError` naming the column and the likely unit where the data
    say so; else the fit itself is named, not the units (the error returned, for the caller to raise): a
    singular system (a ``numpy.linalg.LinAlgError``, no least-squares fallback for it) as a
    :class:`~alpes_dyn.estimation.identification.shooting.FitSingular`.

    Parameters
    ----------
    exc : Exception
        The FitDiverged, or the LinAlgError of a singular system (the normal matrices of a fit whose trial steps
        were refused, or the covariance's KKT system at the fit's end).
    rec : Recording
        The recording fitted (encoders in counts, torques in N m).
    model : Model
        The model fitted (its joints' ranges, its motors' limits).

    Returns
    -------
    Exception
        The error to raise.

    Raises
    ------
    RecordingError
        Where a column's values are implausible in its unit (naming the column and the likely unit).
    """
    from ..experiments.units import check_units

    check_units(rec, model)
    if isinstance(exc, np.linalg.LinAlgError):
        return FitSingular(f"identify: {exc}: a state or parameter the recording does not see (e.g. a LuGre "
                           "bristle deflection relaxed within an interval); fewer effects or parameters may hold")
    return FitDiverged(f"{exc} from its start, on a recording of plausible units (its encoders within the "
                       "joints' ranges, its torques within the motors' limits): fewer effects or parameters may hold")


RUNAWAY_KINDS = ("F_s", "F_v")
"""The kinds of parameter a lost basin's farthest step may name for the fit to be made again with it held
(:func:`friction_held`): a joint's friction the data do not see (a joint that moves over a small part of its
range: its F_s asks for steps of hundreds in log theta, each cut to the trust region, and every round loses its
basin)."""


def friction_held(fit: Callable[..., IdentificationResult], model: Model, recording: Recording | str | Path,
                  result: IdentificationResult, settings: dict[str, Any], t_start: float) -> IdentificationResult:
    """``result`` where it did not lose its basin on a friction parameter (the farthest step's, named in its
    reason: :data:`RUNAWAY_KINDS`); else the fit again from the model's values with that one held at the model's
    value, named in :attr:`~.fit_result.IdentificationResult.not_identified` (with
    :data:`~.creep.RAN_DOWN` where the lost fit had driven it below that value: the creep round's trigger,
    :func:`~.creep.ran_down`), kept where it converged or fits better.

    Parameters
    ----------
    fit : callable
        :func:`~alpes_dyn.estimation.identification.identification.identify`, called as ``fit(model, recording,
        names, **settings)``.
    model : Model
        The model fitted.
    recording : Recording, str or pathlib.Path
        The recording fitted.
    result : IdentificationResult
        The fit that may have lost its basin.
    settings : dict
        ``fit``'s other keyword arguments, as the first fit had them.
    t_start : float
        ``time.perf_counter()`` at the start of the whole fit, s (the kept fit's ``seconds`` counts from it).

    Returns
    -------
    IdentificationResult
        ``result``, or the fit again with the friction parameter held.
    """
    far = result.reason.rpartition("the farthest: ")[2].rstrip(")") if result.reason.startswith("lost basin") else ""
    catalogue = {pp.name: pp for pp in parameter_catalogue(model)}
    kind = catalogue[far].kind if far in catalogue else None
    keep = [n for n in result.names if n != far]
    if kind not in RUNAWAY_KINDS or not keep:
        return result
    with warnings.catch_warnings():  # the verdict is reported on the fit kept
        warnings.simplefilter("ignore", AdequacyWarning)
        again = fit(model, recording, keep, **settings)
    if not (again.converged or again.residual_rms < result.residual_rms):
        return result
    lost_at, nominal = float(result.values[list(result.names).index(far)]), catalogue[far].nominal
    way = f"{RAN_DOWN}, to {lost_at:.2g} from {nominal:.2g}" if lost_at < nominal else "ran it off"
    again.not_identified = {far: f"held at the model's value: the fit's steps {way} (lost basin; the data do "
                                 f"not see {EFFECT_OF[kind]} there)", **again.not_identified}
    again.iterations += result.iterations
    again.seconds = time.perf_counter() - t_start
    again.reason += f" (fitted again with {far} held: {result.reason})"
    return again
