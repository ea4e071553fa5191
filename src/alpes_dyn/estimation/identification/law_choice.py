"""The observer's friction law chosen by measurement, not by rule (issue 50).

A file's observer may run several dry-friction laws (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`): the smooth
tanh law, the switched stick-slip law that holds a stuck joint, LuGre's bristles on a LuGre file. Which one serves a
file best depends on the plant and on the motion: on MuJoCo's stiff stick-slip the stick law holds the joints where
they stick on a slow motion, while on the identification record's dither (the joints sliding nearly all the time)
the smooth law's RK4 predicts the encoder closer. So the observer check walks the candidate laws
(:data:`CHECK_LAWS`, as data) on the record it judges, each with its model error calibrated
(:func:`~alpes_dyn.estimation.identification.noise_calibration.calibrate_model_error`), and keeps the law whose
filter passes the check and predicts the encoder best ``split_horizon_s`` ahead (:data:`~.observer_check.
OBSERVER_THRESHOLDS`: the longest horizon the check makes, the one that sees the joints' split the encoder reads
the sum of), from what a user has (the encoder, the torque, the filter's own covariance; never the true joints).
A law that fails the check is kept only where every law fails (then the first candidate: the file's own).
``identify`` writes the law kept as ``friction.observer_law``
(:attr:`~alpes_dyn.estimation.identification.fit_result.IdentificationResult.observer_law`).

The check reads the torque as recorded (:data:`~.observer_check.CHECK_TORQUE_WINDOW` = 1, its white noise as
measured) for every law: the stick and LuGre laws' 10-sample causal average
(:data:`~alpes_dyn.estimation.observers.torque_reading.STICK_TORQUE_WINDOW`) lags the identification record's 20 Hz dither
by 4.5 samples, and its innovation was 12x the sensor floor for a file whose innovation with the torque as recorded
is 2x.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from ...model.friction import lugre_of
from ...model.robot import Model

__all__ = ["CHECK_LAWS", "LAW_CALIBRATION", "law_calibration", "candidate_laws", "LawChoice", "law_score", "choose_law"]

CHECK_LAWS: tuple[str, ...] = ("smooth", "stick", "lugre")
"""The laws the observer check walks (after the file's own law, which comes first and wins a tie): ``lugre`` only on
a LuGre file (the law's sigma0 and sigma1 are the file's), every law only where the file has dry friction."""

LAW_CALIBRATION: dict[str, tuple[dict[str, float], ...]] = {
    "smooth": ({},),
    "stick": ({"own_first": 0.0, "start": 0.25, "innovation_only": 1.0}, {"own_first": 0.0, "start": 0.25}),
    "lugre": ({},)}
"""Each law's model-error searches, in turn (overrides of :data:`~alpes_dyn.estimation.identification.
noise_calibration.CALIBRATION`): the first whose filter passes the check is the law's (else the last's), so each law
is handed its own model error, never another law's. The smooth law: the file's own noise first (the library's
default, a quarter of F_s, is the smooth law's: the stick phases it cannot hold), else the smallest e that makes
all three statistics consistent. The stick law holds a stuck joint, and a model error lets its filter move the
split of the joints the encoder reads the sum of: first the smallest e that makes its own innovations consistent
(within their 99 % band; MuJoCo's stiff stick-slip finger2 at 3x F_s on the experiment's stiction ramp, true file:
e 0, EKF 0.20 degree, 100 ms prediction 14.3 counts, against 0.33 degree and 23.2 counts at the e all three
statistics ask for, 1 F_s), then, where its predictions are over-confident there, the smallest e that makes all
three consistent (its search from a quarter of F_s down to 1/64, then 0, the file's own noise not tried)."""


def law_calibration(calibrate: Callable[[Mapping[str, float]], Any], law: str) -> Any:
    """The model error of ``law`` (:data:`LAW_CALIBRATION`): its searches in turn, the first whose check passes.

    Parameters
    ----------
    calibrate : callable
        ``calibrate(settings)``: the :class:`~alpes_dyn.estimation.identification.noise_calibration.
        ModelErrorCalibration` of the law's filter on the record with those search settings.
    law : str
        The law (one of :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`; an unknown one: the default search).

    Returns
    -------
    ModelErrorCalibration
        The first search whose check passes (no reason), else the last.
    """
    cal = None
    for settings in LAW_CALIBRATION.get(law, ({},)):  # one or two searches
        cal = calibrate(settings)
        if cal.check is not None and cal.check.passed and not cal.reason:
            break
    return cal


def candidate_laws(model: Model) -> tuple[str, ...]:
    """The laws the check walks for ``model``: its own law first
    (:func:`~alpes_dyn.simulation.stick.observer_friction_law`), then those of :data:`CHECK_LAWS` that apply; the
    file's own alone where the model has no dry friction (no choice to make).

    Parameters
    ----------
    model : Model
        The observer's model (with its parameter file).

    Returns
    -------
    tuple of str
        The candidate laws, each of :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`.
    """
    from ...simulation.stick import observer_friction_law

    own = observer_friction_law(model)
    if not np.any(np.asarray(model.extras.coulomb) > 0):
        return (own,)
    lugre = lugre_of(model) is not None
    return (own,) + tuple(law for law in CHECK_LAWS if law != own and (law != "lugre" or lugre))


def law_score(check: Any) -> float:
    """The encoder's prediction error ``split_horizon_s`` ahead (its RMS over the encoders, counts; the
    ``horizon_s`` one where the record is too short for it): what the choice ranks the passing laws by.

    Parameters
    ----------
    check : ObserverCheck
        An observer check (:class:`~alpes_dyn.estimation.identification.observer_check.ObserverCheck`).

    Returns
    -------
    float
        Counts RMS (lower is better).
    """
    split = getattr(check, "split_rms", None)
    return float(check.prediction_rms if split is None else split)


@dataclass
class LawChoice:
    """The laws walked on a record and the one kept.

    Attributes
    ----------
    law : str
        The law kept.
    calibrations : dict of str to ModelErrorCalibration
        Each law's calibrated model error and its check (:class:`~alpes_dyn.estimation.identification.
        noise_calibration.ModelErrorCalibration`), in the order walked.
    scores : dict of str to float
        Each law's :func:`law_score`, counts.
    """

    law: str
    calibrations: dict[str, Any] = field(default_factory=dict)
    scores: dict[str, float] = field(default_factory=dict)

    @property
    def calibration(self) -> Any:
        """The kept law's calibration."""
        return self.calibrations[self.law]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: per law walked, ``passed``, ``model_error`` (F_s), ``score_counts``, ``prediction_ratio``,
        ``innovation_ratio`` and its first reason; ``law`` the one kept."""
        out = {}
        for law, cal in self.calibrations.items():
            c = cal.check
            out[law] = {"passed": bool(c.passed and not cal.reason), "model_error": cal.value,
                        "score_counts": self.scores[law],
                        "innovation_ratio": c.innovation_rms / c.floor if c.floor > 0 else None,
                        "prediction_ratio": c.prediction_rms / c.floor if c.floor > 0 else None,
                        "reason": (c.reasons + [cal.reason])[0] if (c.reasons or cal.reason) else ""}
        return {"law": self.law, "laws": out}


def choose_law(model: Model, calibrate: Callable[[Model, str], Any], laws: tuple[str, ...] | None = None) -> LawChoice:
    """Each candidate law's model error calibrated, and the law kept (module docstring): among those whose check
    passes, the lowest :func:`law_score` (the first walked on a tie); where none passes, the first walked.

    Parameters
    ----------
    model : Model
        The observer's model.
    calibrate : callable
        ``calibrate(model, law)``: the :class:`~alpes_dyn.estimation.identification.noise_calibration.
        ModelErrorCalibration` of the EKF with that law on the record judged
        (:func:`~alpes_dyn.estimation.identification.observer_check.calibrate_observer`).
    laws : tuple of str or None, optional
        The laws to walk (default :func:`candidate_laws` of ``model``).

    Returns
    -------
    LawChoice
        The law kept, each law's calibration and score.
    """
    laws = candidate_laws(model) if laws is None else laws
    choice = LawChoice(laws[0])
    for law in laws:  # a few laws, each its calibration's few EKF runs
        cal = calibrate(model, law)
        choice.calibrations[law] = cal
        choice.scores[law] = law_score(cal.check)
    passing = [law for law in laws if choice.calibrations[law].check.passed and not choice.calibrations[law].reason]
    if passing:
        choice.law = min(passing, key=lambda law: (choice.scores[law], laws.index(law)))
    return choice
