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
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["SPREAD_WEIGHT", "other_law", "widen"]

SPREAD_WEIGHT = 1.0
"""w of (S1): the two laws' difference as one standard deviation of the model-form error (module doc)."""


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


def widen(result: Any, other: Any, weight: float = SPREAD_WEIGHT) -> np.ndarray:
    """``result``'s standard errors widened by (S1) with ``other`` (the fit with the other law), in place: its
    ``std``, and ``standard_errors.law_spread`` where it has one.

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit kept.
    other : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit with the other law (a parameter it does not hold, or holds with an infinite standard error, is
        left as it is).
    weight : float
        w of (S1).

    Returns
    -------
    (p,) array
        |theta_kept - theta_other| per parameter of ``result``, in its units (0 where ``other`` has no value).
    """
    theirs = {n: float(v) for n, v, s in zip(other.names, other.values, other.std) if np.isfinite(v)}
    spread = np.array([abs(float(v) - theirs[n]) if n in theirs else 0.0 for n, v in zip(result.names, result.values)])
    std = np.asarray(result.std, dtype=float)
    result.std = np.where(np.isfinite(std), np.hypot(std, weight * spread), std)
    se = getattr(result, "standard_errors", None)
    if se is not None:
        se.law_spread = spread
    return spread
