"""The observer's model error calibrated on the identification record, not hand-set (issue 50).

An observer built on a parameter file reports a covariance that covers its error only where its process noise holds
the model's error: a smooth friction law on a joint that sticks, a joint that creeps, what the fit left. The
library's default (:mod:`~alpes_dyn.estimation.observers.friction_noise`: a quarter of F_s where the torque noise
covers the law's band) was chosen on the library's own plant; on MuJoCo's dry friction the filter with the *true*
file is over-confident several times over (its joints' NEES). Here the model error is measured on the record the file was
fitted on, from what a user has (the encoder, the torque, the filter's own covariance; never the true joints):

* the model error is a white torque per sample of e F_s,i on each joint i (``friction.model_error`` = e, in units of
  F_s: :func:`~alpes_dyn.estimation.observers.friction_noise.model_error_noise`), one number per file;
* for a trial e, the EKF of ``alpes-dyn estimate --data`` on the file (its law, the fit's encoder offsets, tilt and
  delay) runs on the record's first ``window_s`` s (the observer check's)
  (:func:`~alpes_dyn.estimation.identification.observer_check.observer_statistics`), and its consistency statistic
  is the largest of its normalised innovation squared and of its predictions' 20 and 100 ms ahead, each over its
  degrees of freedom (1 for a consistent filter; the 100 ms one sees the split of the joints the encoder reads the sum
  of, :mod:`~alpes_dyn.estimation.identification.observer_check`);
* e is the smallest value of a geometric search (factor 2 from ``start``, then one halving of the bracket in log)
  whose statistic is at most ``target`` (covariance matching, Mehra 1972, on the statistic that sees the unobserved
  direction: the innovation's alone stays in its band while the split is wrong); 0 where the filter with no model
  error is already consistent, and nothing (the file's own noise kept: its ``friction.model_error``, else the
  library's default) where the filter with the file's own noise is, which is tried first. Where none up to ``ceiling`` is, the file's observer is inconsistent whatever its
  noise: :attr:`ModelErrorCalibration.reason` names it and ``identify``'s observer check refuses the file.

``identify`` writes e to the file it writes (``friction.model_error``, unit ``F_s``); every command that builds an
observer from the file (``estimate``, ``control``, :class:`~alpes_dyn.control.step.ForceStep`,
:class:`~alpes_dyn.control.hand_step.HandForceStep`, ``codegen --step``) reads it through
:func:`~alpes_dyn.estimation.observers.observers.make_observer`, so the Python step and its C carry the same Q.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

from ...model.robot import Model
from ..observers.friction_noise import with_model_error

__all__ = ["CALIBRATION", "ModelErrorCalibration", "consistency_statistic", "calibrate_model_error"]

CALIBRATION: dict[str, float] = {"start": 1.0, "ceiling": 16.0, "target": 1.0, "own_first": 1.0,
                                 "innovation_only": 0.0}
"""The search's settings: the first trial ``start`` (in units of F_s), doubled or halved from there up to
``ceiling`` (the largest model error a file may need: above it the observer is judged inconsistent), down to
``start`` / 16 (below: 0); the consistency statistic's ``target`` (1: the covariance the filter reports matches its
errors); ``own_first`` 1: the file's own noise tried first and kept where consistent, 0: not tried (the search
alone: the smallest consistent e, the law's own; a law whose error the library's default, the smooth law's, would
over-state, :data:`~alpes_dyn.estimation.identification.law_choice.LAW_CALIBRATION`); ``innovation_only`` 1: the
statistic the filter's normalised innovation squared alone, a trial consistent where it is within its chi-square
band (``target`` unused), 0: the largest of the three statistics (:func:`consistency_statistic`) at most
``target``."""


@dataclass
class ModelErrorCalibration:
    """The calibrated model error of a file on a record (module docstring).

    Attributes
    ----------
    value : float or None
        e, in units of each joint's F_s (0: none needed); None where the file's own noise is consistent (nothing to
        write) or, with a ``reason``, where none up to the ceiling is.
    tried : list of (float or None, float)
        Each trial's (e, the consistency statistic); e None: the file's own noise, tried first.
    reason : str
        Why the observer is inconsistent (empty where ``value`` is found).
    seconds : float
        The calibration's time, s.
    check : ObserverCheck or None
        The observer's statistics at ``value`` (at the ceiling where none is consistent; with the file's own noise
        where it is).
    """

    value: float | None
    tried: list[tuple[float, float]] = field(default_factory=list)
    reason: str = ""
    seconds: float = 0.0
    check: Any = field(default=None, repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``model_error`` (F_s), ``unit``, ``tried`` ([e, statistic] pairs, null where not finite),
        ``reason``, ``seconds``."""
        return {"model_error": self.value, "unit": "F_s",
                "tried": [[e, s if np.isfinite(s) else None] for e, s in self.tried],
                "reason": self.reason, "seconds": self.seconds}


def consistency_statistic(check: Any, innovation_only: bool = False) -> float:
    """The largest of an observer check's normalised innovation squared and its predictions'.

    Parameters
    ----------
    check : ObserverCheck
        The :class:`~alpes_dyn.estimation.identification.observer_check.ObserverCheck` of an EKF on a record (its
        ``nis``, ``prediction_nis`` and ``split_nis``, each None where not made).
    innovation_only : bool, optional
        The normalised innovation squared alone, over its band's upper end (1 at the band's edge; default False:
        the largest of the three over its degrees of freedom).

    Returns
    -------
    float
        The largest statistic over its degrees of freedom (1 for a consistent filter); nan where none was made.
    """
    if innovation_only:
        v = check.nis
        return float(v.value / v.high) if v is not None and v.high > 0 else float("nan")
    vals = [v.value / v.dof for v in (check.nis, check.prediction_nis, check.split_nis) if v is not None]
    return float(max(vals)) if vals else float("nan")


def calibrate_model_error(model: Model, statistics: Callable[[Model], Any],
                          settings: Mapping[str, float] | None = None) -> ModelErrorCalibration:
    """The smallest model error e that makes the EKF of ``model`` consistent on a record (module docstring).

    Parameters
    ----------
    model : Model
        The observer's model from the file (:func:`~alpes_dyn.estimation.identification.observer_check.
        identified_model`); its own ``friction.model_error`` is replaced by each trial's.
    statistics : callable
        ``statistics(model)``: the :class:`~alpes_dyn.estimation.identification.observer_check.ObserverCheck` of the
        EKF of a trial's model on the record (:func:`~alpes_dyn.estimation.identification.observer_check.
        observer_check` gives :func:`~alpes_dyn.estimation.identification.observer_check.observer_statistics` with
        the fit's encoder offsets, tilt and delay, on the record's first ``window_s`` s).
    settings : mapping, optional
        Overrides of :data:`CALIBRATION`.

    Returns
    -------
    ModelErrorCalibration
        e (None with the reason where none up to the ceiling is consistent), the trials.
    """
    st = {**CALIBRATION, **(settings or {})}
    t0 = time.perf_counter()
    tried: list[tuple[float | None, float]] = []
    checks: dict[float | None, Any] = {}

    def stat(e: float | None) -> float:
        m = model
        if e is not None:
            m = model.copy()
            m.params = with_model_error(model.params, e)
        checks[e] = statistics(m)
        tried.append((e, consistency_statistic(checks[e], True) if st["innovation_only"] else
                      consistency_statistic(checks[e])))
        return tried[-1][1]

    def done(value: float | None, reason: str = "") -> ModelErrorCalibration:
        return ModelErrorCalibration(value, tried, reason, time.perf_counter() - t0,
                                     checks[tried[-1][0] if reason else value])

    target = 1.0 if st["innovation_only"] else st["target"]  # innovation_only: the statistic is over its band
    ok = lambda s: bool(np.isfinite(s) and s <= target)  # noqa: E731
    # the file's own noise (its model error, else the library's default) tried first where the law's search says so
    if st["own_first"] and ok(stat(None)):
        return done(None)
    lo, hi = None, None  # the largest e found inconsistent, the smallest found consistent
    e = float(st["start"])
    if ok(stat(e)):
        hi = e
        while e > st["start"] / 16 and ok(stat(e / 2)):
            e = hi = e / 2
        if e <= st["start"] / 16:
            return done(0.0 if ok(stat(0.0)) else hi)
        lo = e / 2
    else:
        lo = e
        while e < st["ceiling"] and hi is None:
            e *= 2
            lo, hi = (lo, e) if ok(stat(e)) else (e, None)
        if hi is None:
            return done(None, f"no model error up to {st['ceiling']:g} F_s makes the EKF on the file consistent on "
                              f"its record (its normalised innovation or prediction error squared "
                              f"{min(s for _, s in tried):.3g} times what it reports at best)")
    mid = float(np.sqrt(lo * hi))
    return done(mid if ok(stat(mid)) else hi)
