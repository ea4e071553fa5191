"""The identification experiment adapted to the finger it runs on (issue 35): ``alpes-dyn experiment``'s default.

The documented experiment (:class:`~alpes_dyn.estimation.experiments.design.ExperimentDesign`, palm up) is designed on the
nominal file and trimmed on the finger (:mod:`alpes_dyn.estimation.experiments.trim`), but no one design keeps every finger of
the +-20 % family off its stops palm up: a soft finger's static equilibria fold (gravity outgrows its springs) and
it rests on its 0 degree stop (five finger3 draws of fifty), or the excitation swings a soft joint past its 90
degree stop (two more). A fit cannot explain a stop its model does not have, and ``identify`` honestly refuses
such a recording ("the fitted joints leave their range"). :func:`adapted_experiment` therefore runs the design on the
finger and checks the whole record before anything is written: where a joint leaves its range (less
:data:`RANGE_MARGIN`) or the trim finds the finger folding, it tries, in order, the hand hung fingers down
(:func:`~alpes_dyn.model.mjcf.hanging_gravity`: gravity pulls along the finger and its equilibria do not fold; the
command's ``--rig hanging``), then the multisine and the dither scaled by :data:`AMPLITUDE_SCALES` (hung, then in
the design's orientation), and keeps the first that stays inside; it says what it chose
(:class:`Adaptation`). Where none does, the run that left its range least is kept and a
:class:`~alpes_dyn.model.stops.JointRangeWarning` names the flags that change it.

What the check reads is the finger's own joint angles in the run (the simulated hand's ``true_q``): on a bench,
what the experimenter sees of a finger on its stop; the design is changed before the recording is written, never
after it is fitted.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ...fileio import check_outputs
from ...model.mjcf import hanging_gravity
from ...model.params import HandParams, load_params
from ...model.robot import Model
from ...model.stops import JointRangeWarning
from .design import ExperimentDesign
from .recording import Recording, write_recording

__all__ = ["RANGE_MARGIN", "AMPLITUDE_SCALES", "RIGS", "Adaptation", "range_excess", "candidate_designs",
           "first_in_range", "adaptation_of", "adapted_experiment"]

RANGE_MARGIN = math.radians(1.0)
"""rad: how far inside its range every joint must stay over the whole record (a fit's range check is exact)."""
AMPLITUDE_SCALES: tuple[float, ...] = (0.7, 0.5)
"""The factors by which the multisine (``amplitude_fraction``, or ``torque_amplitude`` where given) and the dither
are scaled, in turn, where the full excitation leaves the range in every orientation tried."""
RIGS: tuple[str, ...] = ("auto", "level", "hanging", "both")
"""``alpes-dyn experiment --rig``: ``auto`` (the default: palm up unless the finger leaves its range there, then hung
fingers down), the orientation fixed (the amplitudes still adapt), or ``both``: the record's first half palm up,
the second hung fingers down, the hand turned between two runs of the excitation (each designed and trimmed in its
orientation: :func:`~alpes_dyn.estimation.experiments.experiment.experiment`); palm up alone, then hung alone,
where the finger leaves its range in one of them. Why ``both``: one orientation leaves the split of the masses
m_1 / m_2 to the friction and the cable's model error (on MuJoCo's all-effects finger3 the masses come out off
in opposite directions, well beyond the fit's own standard error, yet the fit is called adequate); gravity across
the finger, then along it, pins it (the fits with ``--rig both``: ``benchmarks/results/realism.json``)."""


@dataclass(frozen=True)
class Adaptation:
    """What :func:`adapted_experiment` chose: the ``rig`` (``level``: the design's own orientation; ``hanging``),
    the ``amplitude_scale`` of the multisine and the dither, ``excess_deg`` how far past its range (less the margin)
    the chosen run took its worst joint (0 inside), ``tried`` each run as (rig, scale, excess_deg), and ``note``:
    one sentence saying what changed and why ("" where the design ran as given)."""

    rig: str
    amplitude_scale: float
    excess_deg: float
    tried: tuple[tuple[str, float, float], ...]
    note: str

    @property
    def changed(self) -> bool:
        return bool(self.note)

    def to_dict(self) -> dict[str, Any]:
        return {"rig": self.rig, "amplitude_scale": self.amplitude_scale, "excess_deg": self.excess_deg,
                "in_range": self.excess_deg == 0.0, "note": self.note,
                "tried": [{"rig": r, "amplitude_scale": s, "excess_deg": e} for r, s, e in self.tried]}


def range_excess(q: np.ndarray, lower: np.ndarray, upper: np.ndarray, margin: float = RANGE_MARGIN
                 ) -> tuple[float, int, float]:
    """(how far, rad, the joints ``q`` (N, n) go past [lower + margin, upper - margin] at worst -- 0 inside --, the
    joint, its extreme angle, rad). Unbounded joints (an infinite limit) are not checked on that side.

    Parameters
    ----------
    q : numpy.ndarray, shape (N, n)
        The joint angles over the run, rad.
    lower, upper : numpy.ndarray, shape (n,)
        The joints' limits, rad (infinite: unbounded).
    margin : float, optional
        Kept inside each limit, rad (default :data:`RANGE_MARGIN`).

    Returns
    -------
    tuple of (float, int, float)
        (the excess, rad; the joint's index; its extreme angle, rad).
    """
    lo = np.where(np.isfinite(lower), lower + margin, -np.inf)
    hi = np.where(np.isfinite(upper), upper - margin, np.inf)
    below = np.max(lo - q, axis=0)
    above = np.max(q - hi, axis=0)
    worst = np.maximum(below, above)
    j = int(np.argmax(worst))
    extreme = float(q[:, j].min() if below[j] >= above[j] else q[:, j].max())
    return max(float(worst[j]), 0.0), j, extreme


def _scaled(design: ExperimentDesign, scale: float) -> ExperimentDesign:
    if scale == 1.0:
        return design
    amp = None if design.torque_amplitude is None else design.torque_amplitude * scale
    return dataclasses.replace(design, amplitude_fraction=design.amplitude_fraction * scale,
                               dither=design.dither * scale, torque_amplitude=amp)


def candidate_designs(design: ExperimentDesign, rig: str, gravity: np.ndarray,
                      scales: Sequence[float] = AMPLITUDE_SCALES) -> list[tuple[str, float, ExperimentDesign]]:
    """The designs to try, in order, as (rig, amplitude scale, design): ``design`` as given (``level``: its own
    orientation) and hung fingers down (``hanging``: :func:`~alpes_dyn.model.mjcf.hanging_gravity` of ``gravity``,
    the parameter file's, m/s^2) as ``rig`` (one of :data:`RIGS`) allows (``both``: the design's first orientation
    then hung, then each alone), then each scaled by ``scales``.

    Parameters
    ----------
    design : ExperimentDesign
        The design as given.
    rig : str
        One of :data:`RIGS`.
    gravity : numpy.ndarray, shape (3,)
        The parameter file's gravity, m/s^2.
    scales : sequence of float, optional
        The amplitude scales tried after the unscaled designs (default :data:`AMPLITUDE_SCALES`).

    Returns
    -------
    list of (str, float, ExperimentDesign)
        (rig, amplitude scale, design), in the order to try.
    """
    hung = tuple(float(x) for x in hanging_gravity(gravity))
    hanging = dataclasses.replace(design, orientations=(hung,))
    if rig == "hanging":
        base = [("hanging", hanging)]
    elif rig == "both":
        level = dataclasses.replace(design, orientations=design.orientations[:1])
        base = [("both", dataclasses.replace(design, orientations=(design.orientations[0], hung))), ("level", level),
                ("hanging", hanging)]
    elif rig == "level" or len(design.orientations) != 1:
        base = [("level", design)]
    else:
        base = [("level", design), ("hanging", hanging)]
    if rig == "auto" and len(base) == 2:
        order = [base[0], base[1]]
        scaled = [(r, s, _scaled(d, s)) for s in scales for r, d in (base[1], base[0])]
        return [(r, 1.0, d) for r, d in order] + scaled
    return [(r, 1.0, d) for r, d in base] + [(r, s, _scaled(d, s)) for s in scales for r, d in base]


def first_in_range(run: Callable[[str, ExperimentDesign], tuple[Any, np.ndarray]],
                   candidates: Sequence[tuple[str, float, ExperimentDesign]], lower: np.ndarray, upper: np.ndarray
                   ) -> tuple[tuple[Any, float, list, int], list[tuple[str, float, float, int, float, bool]]]:
    """Run ``candidates`` (:func:`candidate_designs`) in turn until one keeps the joints inside [lower, upper] (rad,
    less :data:`RANGE_MARGIN`) over the whole run and its trim does not find the equilibria folding.

    Parameters
    ----------
    run : callable
        ``run(rig, design)`` -> (its result, the joints' angles (N, n), rad): the library's simulated hand
        (:func:`adapted_experiment`) or any other plant (a MuJoCo finger:
        :func:`alpes_dyn.studies.realism.realism_case`).
    candidates : sequence of (str, float, ExperimentDesign)
        The designs to try (:func:`candidate_designs`).
    lower, upper : numpy.ndarray, shape (n,)
        The joints' limits, rad.

    Returns
    -------
    chosen : tuple
        (the chosen result, its excess in rad, its warnings, its index): the first run in range, else the one that
        left it least.
    tried : list of tuple
        Every run tried as (rig, scale, excess deg, joint, extreme angle rad, folded).
    """
    tried: list[tuple[str, float, float, int, float, bool]] = []
    best = None
    for r, scale, d in candidates:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out, q = run(r, d)
        excess, j, extreme = range_excess(q, lower, upper)
        folded = any(issubclass(w.category, JointRangeWarning) and "equilibria fold" in str(w.message) for w in caught)
        tried.append((r, scale, math.degrees(excess), j, extreme, folded))
        if best is None or excess < best[1] or (excess == 0.0 and not folded):
            best = (out, excess, list(caught), len(tried) - 1)
        if excess == 0.0 and not folded:
            break
    assert best is not None, "no candidate design"
    return best, tried


def adapted_experiment(model: str, true_params: HandParams | str | Path | None = None,
                       design: ExperimentDesign | None = None, seed: int = 0, path: str | Path | None = None,
                       nominal_params: HandParams | str | Path | None = None, chain: str | None = None,
                       rotor_inertia: bool = False, rig: str = "auto",
                       scales: Sequence[float] = AMPLITUDE_SCALES) -> tuple[Recording, Adaptation]:
    """:func:`~alpes_dyn.estimation.experiments.experiment.experiment` with the design adapted until the finger
    stays inside its range over the whole record (the module docstring). Each run tried costs one experiment's
    simulation (shorter than the record on a finger).

    Parameters
    ----------
    model, true_params, design, seed, path, nominal_params, chain, rotor_inertia : see experiment
        :func:`~alpes_dyn.estimation.experiments.experiment.experiment`'s (the recording written to ``path`` only
        once chosen).
    rig : str, optional
        One of :data:`RIGS` (``level``: ``design``'s own orientation, default palm up).
    scales : sequence of float, optional
        The amplitude factors to try after the full excitation (default :data:`AMPLITUDE_SCALES`; none: the
        orientation alone adapts).

    Returns
    -------
    tuple of (Recording, Adaptation)
        The recording and how the design was adapted.
    """
    from ...errors import InputError
    from .experiment import experiment

    if rig not in RIGS:
        raise InputError(f"rig: expected one of {', '.join(RIGS)}, got {rig!r:.40}")
    design = ExperimentDesign() if design is None else design
    if path is not None:  # the output policy before any work (experiment checks the rest)
        check_outputs([("path", path)], [(name, f) for name, f in (("true_params", true_params),
                                                                   ("nominal_params", nominal_params))
                                         if isinstance(f, (str, Path))])
    p_nom = nominal_params if isinstance(nominal_params, HandParams) else load_params(nominal_params)
    p_true = true_params if isinstance(true_params, HandParams) else load_params(true_params)
    limits = Model.alpes(model, params=p_true, chain=chain)

    def run(r: str, d: ExperimentDesign):
        rec = experiment(model, p_true, d, seed=seed, nominal_params=p_nom, chain=chain, rotor_inertia=rotor_inertia)
        return rec, rec.true_q

    best, tried = first_in_range(run, candidate_designs(design, rig, np.asarray(p_nom.gravity, dtype=float), scales),
                                 limits.lower, limits.upper)
    rec, excess, caught, k = best
    for w in caught:  # the chosen run's own warnings (small excursions...), once
        if not (excess == 0.0 and issubclass(w.category, JointRangeWarning)):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    adaptation = adaptation_of(tried, k, limits)
    if excess > 0.0:
        warnings.warn(JointRangeWarning(
            f"experiment: every design tried leaves the finger's range ({adaptation.note}); the recording is "
            "written as it ran, and identify will refuse it: try --rig hanging or --rig level, a shorter "
            "--duration, or another finger's --params"), stacklevel=2)
    if path is not None:
        write_recording(rec, path)
    return rec, adaptation


def adaptation_of(tried: list[tuple[str, float, float, int, float, bool]], k: int, model: Model) -> Adaptation:
    """The :class:`Adaptation` of the run ``k`` chosen among ``tried`` (rig, scale, excess deg, joint, extreme rad,
    folded), with its note.

    Parameters
    ----------
    tried : list of tuple
        Every run tried, as :func:`first_in_range` returns them.
    k : int
        The index of the run chosen.
    model : Model
        The finger (its joints' names and limits, for the note).

    Returns
    -------
    Adaptation
    """
    r, scale, excess, _, _, _ = tried[k]
    first = tried[0]
    why = (f"the finger left its range in the first run ({first[0]}, full excitation: joint "
           f"{model.joint_names[first[3]]!r} to {math.degrees(first[4]):.1f} deg, range "
           f"[{math.degrees(model.lower[first[3]]):g}, {math.degrees(model.upper[first[3]]):g}] deg"
           + (", its static equilibria folding" if first[5] else "") + ")")
    if k == 0 and excess == 0.0:
        note = ""
    elif excess == 0.0:
        how = {"hanging": "hung fingers down (as --rig hanging)", "level": "in the design's orientation"}[r]
        note = (f"{why}: ran {how}" + (f", the multisine and the dither scaled to {scale:g}" if scale != 1.0 else "")
                + f", which stays {math.degrees(RANGE_MARGIN):g} deg or more inside")
    else:
        note = f"{why}; the least bad of {len(tried)} runs ({r}, scale {scale:g}) still goes {excess:.1f} deg past it"
    return Adaptation(rig=r, amplitude_scale=scale, excess_deg=float(excess),
                      tried=tuple((t[0], t[1], float(t[2])) for t in tried), note=note)
