"""An observer's uncertainty from its friction law: the spread of the joints' estimates between the library's
friction laws, added to the filter's own covariance.

A Kalman filter's P is the noise's: the torque sensor's and the encoder's seen through its model. Where the model's
friction law is not the plant's (MuJoCo's dry-friction constraint is none of the library's laws), the error it
leaves is not in P: on MuJoCo's stick-slip finger3 (the friction study's ``stiff`` case, the true parameter file,
the smooth law) the joints' errors were 0.13-0.23 degree and their NEES 5-11 against a band of about 0.7-1.3. The
user cannot see the plant's law either, but can see how much the estimate moves when the law does: the same
recording run through the filter with each other law of the library,
:data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS` (the smooth sign, the stick-slip law, LuGre's bristles, the creep
of MuJoCo's soft dry friction: each the same file with the law's ``friction.law``, no refit), and each joint's
variance widened by it,

    sigma_i,k^2 = P_ii,k + w^2 / L sum_{l != kept} (q_hat^l_i,k - q_hat^kept_i,k)^2,                    (L1)

L the number of other laws, w = :data:`LAW_SIGMA_WEIGHT` (Draper 1995, "Assessment and propagation of model
uncertainty": the between-model variance, the laws equally likely, added to the within-model one; a mean, so a law
more in the library does not widen sigma by its count). Nothing in it reads the true joints: only the recording and
the file.

On MuJoCo's stick-slip finger3 (the true file, the smooth law kept; ``tests/test_law_sigma.py``) the joints' NEES
with P alone is 4-8, with (L1) over the three other laws 0.6-1.2 (a sum instead of the mean: 0.3-0.45, cautious);
on MuJoCo's soft dry friction with a creep file (the creep law kept) 0.5-0.9. Not into the band on every joint:
it is an opt-in check (``estimate --data --law-spread``, four observer runs instead of one), not the filter's own
sigma.
The kept law is named as the file's (:func:`~alpes_dyn.simulation.stick.library_law`: a creep file's smooth-law run
is ``creep``, and the plain smooth law is among the others).
What it cannot see: an error that every law shares (the identified file's own parameters' error; the fit's
covariance is not drawn here).
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from ...errors import InputError
from ...simulation.stick import LIBRARY_LAWS
from .observers import Estimate

__all__ = ["LAW_SIGMA_WEIGHT", "LawSigma", "law_sigma"]

LAW_SIGMA_WEIGHT = 1.0
"""w of (L1): the other friction laws' mean squared distance from the kept one's estimate as one variance of the
law's error (module docstring)."""


@dataclasses.dataclass(frozen=True)
class LawSigma:
    """The joints' spread between friction laws along a run (:func:`law_sigma`, (L1) of the module docstring).

    Attributes
    ----------
    kept : str
        The law of the estimate reported (a key of :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`).
    others : tuple of str
        The other laws run (keys of :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`).
    spread : numpy.ndarray
        (N, n) rad^2, w^2 / L sum_l (q_hat^l - q_hat^kept)^2 per sample and joint (L the others' count).
    """

    kept: str
    others: tuple[str, ...]
    spread: np.ndarray

    def widened(self, estimate: Estimate) -> Estimate:
        """``estimate`` (the kept law's) with the spread added to its joints' variances (the diagonal of P's
        joints' block; the rest of P as it was).

        Parameters
        ----------
        estimate : Estimate
            The kept law's estimate: ``z`` (N, nz) with the n joints' angles first (rad), ``P`` (N, nz, nz).

        Returns
        -------
        Estimate
            The same estimate, its joints' variances (rad^2) widened by :attr:`spread`.

        Raises
        ------
        InputError
            ``estimate`` not of N samples with at least n joints.
        """
        from .band_sigma import with_joint_variance

        return with_joint_variance(estimate, self.spread)

    def to_dict(self, start: int = 0) -> dict[str, Any]:
        """JSON: ``kept``, ``others``, ``spread_rms_deg`` (per joint, the RMS of sqrt of the spread from sample
        ``start`` on).

        Parameters
        ----------
        start : int, optional
            The first sample counted (e.g. past the observer's transient); default 0.

        Returns
        -------
        dict
            The JSON object.
        """
        rms = np.sqrt(np.mean(self.spread[start:], axis=0))
        return {"kept": self.kept, "others": list(self.others), "spread_rms_deg": np.degrees(rms).tolist()}


def law_sigma(run: Callable[[str], Any], kept: Any, weight: float = LAW_SIGMA_WEIGHT,
              laws: tuple[str, ...] = tuple(LIBRARY_LAWS), kept_law: str | None = None) -> LawSigma:
    """The joints' spread between friction laws, (L1) of the module docstring.

    Parameters
    ----------
    run : callable
        ``run(law)`` runs the observer on the same recording and file with the library's law ``law`` (a key of
        :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`; the model and the observer's law for it by
        :func:`~alpes_dyn.simulation.stick.law_model`) and returns its
        :class:`~alpes_dyn.estimation.observers.replay.RecordingEstimate` (the other options as for ``kept``).
    kept : RecordingEstimate
        The estimate reported.
    weight : float, optional
        w of (L1), finite and >= 0.
    laws : tuple of str, optional
        The laws to compare (default every one of :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`).
    kept_law : str or None, optional
        ``kept``'s law, a key of :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`
        (:func:`~alpes_dyn.simulation.stick.library_law` of its model and observer's law); default its
        ``settings["friction_law"]`` (the observer's law: ``smooth`` on a creep file, which is the creep law).

    Returns
    -------
    LawSigma
        The spread per sample and joint.

    Raises
    ------
    InputError
        ``weight`` not a finite number >= 0, ``laws`` or ``kept_law`` not of
        :data:`~alpes_dyn.simulation.stick.LIBRARY_LAWS`, or a run whose estimate is not the kept one's shape.
    """
    if isinstance(weight, bool) or not isinstance(weight, (int, float, np.floating)) or not (
            np.isfinite(weight) and weight >= 0):
        raise InputError(f"weight: expected a finite number >= 0, got {weight!r:.40}")
    bad = [law for law in laws if law not in LIBRARY_LAWS]
    if bad:
        raise InputError(f"laws: expected laws of {', '.join(LIBRARY_LAWS)}, got {bad[0]!r:.40}")
    law = kept.settings["friction_law"] if kept_law is None else kept_law
    if law not in LIBRARY_LAWS:
        raise InputError(f"kept_law: expected one of {', '.join(LIBRARY_LAWS)}, got {law!r:.40}")
    q = kept.q_hat
    others = tuple(other for other in laws if other != law)
    spread = np.zeros_like(q)
    for other in others:  # a loop over the few other laws, each a whole run
        q_other = run(other).q_hat
        if q_other.shape != q.shape:
            raise InputError(f"run: the {other} law's estimate is {q_other.shape}, the kept one's {q.shape}")
        spread += (q_other - q) ** 2
    return LawSigma(law, others, weight ** 2 * spread / max(len(others), 1))
