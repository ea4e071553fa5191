"""The fitted parameters' model-form error: the spread between fits made with the two friction laws (issue 50).

A fit's covariance (the classical s^2 (J'J)^-1 or the HAC sandwich of
:mod:`~alpes_dyn.estimation.identification.robust_covariance`) is the noise's: it sees a model error only through
the colour it leaves in the residual. On MuJoCo's stick-slip finger3 the fits called adequate reach the sensor
floor with a short residual window, the sandwich is the classical covariance again, and the springs', masses'
and frictions' errors are still several of their standard errors (the friction study's ``stiff`` case): the error
is the friction law's, which the residual does not show.

What does show it is how much the parameters move when the law does. The fit is made again with the other of the
library's two memoryless laws -- the smooth sign tanh(qd / v_s) at the file's v_s, and the stick-slip law at
:data:`~alpes_dyn.model.extras.STICTION_VELOCITY` (``--effects stiction``) -- from the kept fit, and each
parameter's standard error becomes

    sigma^2 = sigma_noise^2 + (w |theta_kept - theta_other|)^2,                                   (S1)

w = :data:`SPREAD_WEIGHT` (Draper 1995, "Assessment and propagation of model uncertainty": the between-model
variance added to the within-model one; the truth's law is neither). On those draws the fraction of errors within
3 standard errors rises with w, and is closest to its nominal share at w = 1 (the unbiased variance of two values
would be w = 0.71): w = 1, the other law's value one standard error away. Where
the laws agree the fit's own covariance is left; where they disagree, so does the standard error. What it cannot
see: an error both laws share (there one joint's F_s stayed several standard errors high).

That shared error is the largest part on MuJoCo's stick-slip finger (the friction study's ``stiff`` case,
``benchmarks/realism.py --friction``): a bias of the memoryless laws against a friction none of the library's
laws is, of one sign draw after draw on the same joint, which no statistic of the recording shows -- the residual
is white at the sensor floor (the HAC sandwich, :mod:`~alpes_dyn.estimation.identification.robust_covariance`, at
any window moves the standard errors little) and the laws with a state fit that plant well above the floor, so
neither the residual's colour nor a third law covers it. So each parameter of a kind of :data:`MODEL_FORM` gets a
model-form term too,

    sigma^2 = sigma_noise^2 + (w |theta_kept - theta_other|)^2 + (c_kind theta)^2,                 (S2)

c_kind the RMS relative error left by the memoryless laws on those draws, beyond their noise and spread (the c
that makes the RMS of error / sigma 1 over each kind's 24 parameters): a prior of the laws' form, not of the
recording. Only where the spread is asked for (it is the friction study's, and ``identify --law-spread``): a fit
of a plant whose friction is the model's (the library's simulator) keeps its noise's standard errors.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...symbolic.parametric import parameter_catalogue

__all__ = ["SPREAD_WEIGHT", "MODEL_FORM", "other_law", "model_form", "widen"]

SPREAD_WEIGHT = 1.0
"""w of (S1): the two laws' difference as one standard deviation of the model-form error (module doc)."""
MODEL_FORM = {"K": 0.002, "m": 0.01, "F_s": 0.05, "F_v": 0.03}
"""c_kind of (S2), relative: the memoryless laws' model-form error per parameter kind (the module docstring: the c
that brings the RMS of error / sigma to 1 on the friction study's stiff draws, rounded)."""


def other_law(effects: tuple[str, ...]) -> tuple[str, ...]:
    """``effects`` with the other friction law.

    Parameters
    ----------
    effects : tuple of str
        A fit's effects (``--effects`` names).

    Returns
    -------
    tuple of str
        The smooth law where ``stiction`` or ``lugre`` is in (taken out), ``stiction`` added where neither is.
    """
    if "stiction" in effects or "lugre" in effects:
        return tuple(e for e in effects if e not in ("stiction", "lugre"))
    return effects + ("stiction",)


def model_form(result: Any) -> np.ndarray:
    """The model-form term c_kind |theta| of (S2) per parameter of ``result`` (0 for a kind not in
    :data:`MODEL_FORM`).

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        A fit: its ``names``, ``values`` and ``model`` (the kinds, :func:`~alpes_dyn.symbolic.parametric.
        parameter_catalogue`).

    Returns
    -------
    (p,) array
        c_kind |theta|, in the parameters' units.
    """
    kinds = {pp.name: pp.kind for pp in parameter_catalogue(result.model)}
    c = np.array([MODEL_FORM.get(kinds.get(n, ""), 0.0) for n in result.names])
    return c * np.abs(np.asarray(result.values, dtype=float))


def widen(result: Any, other: Any, weight: float = SPREAD_WEIGHT, form: bool = True) -> np.ndarray:
    """``result``'s standard errors widened by (S1) with ``other`` (the fit with the other law) and, with ``form``,
    the model-form term of (S2), in place: its ``std``, and ``standard_errors.law_spread`` and
    ``standard_errors.model_form`` where it has them.

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit kept.
    other : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit with the other law (a parameter it does not hold, or holds with an infinite standard error, is
        left as it is).
    weight : float
        w of (S1).
    form : bool, optional
        Add the model-form term of (S2) (default True; :func:`model_form`, ``result``'s ``model`` read).

    Returns
    -------
    (p,) array
        |theta_kept - theta_other| per parameter of ``result``, in its units (0 where ``other`` has no value).
    """
    theirs = {n: float(v) for n, v, s in zip(other.names, other.values, other.std) if np.isfinite(v)}
    spread = np.array([abs(float(v) - theirs[n]) if n in theirs else 0.0 for n, v in zip(result.names, result.values)])
    prior = model_form(result) if form else np.zeros_like(spread)
    std = np.asarray(result.std, dtype=float)
    result.std = np.where(np.isfinite(std), np.sqrt(std**2 + (weight * spread) ** 2 + prior**2), std)
    se = getattr(result, "standard_errors", None)
    if se is not None:
        se.law_spread = spread
        se.model_form = prior if form else None
    return spread
