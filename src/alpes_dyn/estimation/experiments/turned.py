"""The identification experiment on the hand in two orientations, the runs joined: palm up, then the hand turned and
hung fingers down (:func:`run_turned`).

In one orientation a finger's masses can trade off with its cable's compliance C: the encoder reads the cable's
stretch C tau_m beside S q (report eq. 3.13), and a model error of the quasi-static stretch moves finger3's three
masses along that direction (on the MuJoCo stand-in up to 5-9 % off at a standard error of 1 %, under a fit that
calls itself adequate). The second orientation's gravity loads the links differently for the same torque: recorded
palm up and hung, the runs joined (each with its gravity columns) and fitted together (the fit takes each run in
its own orientation and fits the palm's tilt on top), the masses come within about 1 %.

The hand is turned by the user between the runs: :func:`run_turned` asks ``hand_in(rig)`` for the hand set up in
each rig (turn it, then return its :class:`~alpes_dyn.bench.interface.HardwareInterface`), calibrates it and runs the
guarded experiment there (:func:`~alpes_dyn.estimation.experiments.on_hand.run_experiment`, designed in the rig's
orientation: :func:`rig_design`), closes it, and joins the runs
(:func:`~alpes_dyn.estimation.experiments.recording.join_runs`). A guard trip in either rig raises
:class:`RigTripped` naming the rig: nothing is joined or written. With ``keep_going=True`` a rig whose guard trips
is left out instead (named in :attr:`TurnedResult.tripped`) and the next rig is run: a finger that folds palm up
(its rest below the fold, no room for the excitation) is still recorded hung; :class:`RigTripped` only where no rig
recorded.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ...bench.interface import HardwareInterface
from ...bench.mujoco_hand import RIGS
from ...errors import InputError
from ...fileio import check_outputs
from ...model.mjcf import tilted_gravity
from ...model.params import load_params
from ...model.robot import Model
from .design import ExperimentDesign, _checked_design
from .hand_session import GuardTripped
from .on_hand import OnHandResult, run_experiment
from .recording import Recording, join_runs, write_recording

__all__ = ["RIGS", "TURNED_RIGS", "TurnedResult", "RigTripped", "rig_design", "run_turned", "joined_runs"]

TURNED_RIGS: tuple[str, ...] = ("level", "hanging")
"""The rigs of :func:`run_turned` by default, in order: palm up, then hung fingers down."""


class RigTripped(GuardTripped):
    """The guard stopped the run in the rig ``rig`` (the finger relaxed first; nothing joined): ``trip`` the
    :class:`~alpes_dyn.estimation.experiments.hand_session.GuardTripped` it raised (its ``reason``, ``t``,
    ``counts`` and ``log`` copied here), ``runs`` the rigs' runs that recorded before it, [(rig, OnHandResult)],
    ``tripped`` the rigs left out before it with ``keep_going`` ((rig, reason) each, as
    :attr:`TurnedResult.tripped`; this rig not among them)."""

    def __init__(self, rig: str, trip: GuardTripped, runs: list, tripped: Sequence[tuple[str, str]] = ()) -> None:
        super().__init__(f"rig {rig}: {trip}", trip.reason, trip.t, trip.counts, trip.log)
        self.rig, self.trip, self.runs, self.tripped = rig, trip, runs, tuple(tripped)


@dataclass
class TurnedResult:
    """What :func:`run_turned` did.

    Attributes
    ----------
    rigs : tuple of str
        The rigs, in the order run.
    runs : tuple of OnHandResult
        Each rig's run (its calibration, trim, amplitude and recording).
    recording : Recording
        The runs joined, one run each (``run`` 0, 1, ...), with the gravity columns (:func:`joined_runs`); one rig:
        its run's recording as it is.
    tripped : tuple of (str, str)
        With ``keep_going``: each rig left out, and its guard's reason (empty otherwise).
    """

    rigs: tuple[str, ...]
    runs: tuple[OnHandResult, ...]
    recording: Recording
    tripped: tuple[tuple[str, str], ...] = ()

    def to_dict(self) -> list[dict[str, Any]]:
        """Each run's figures as plain JSON types: ``rig``, ``calibration`` (its rest and range, counts; its fold,
        N m) and the run's (:meth:`~alpes_dyn.estimation.experiments.on_hand.OnHandResult.to_dict`)."""
        return [{"rig": rig, "calibration": {k: v for k, v in res.calibration.to_dict().items()
                                             if not k.startswith("curve")}, **res.to_dict()}
                for rig, res in zip(self.rigs, self.runs)]


def rig_design(rig: str = "level", duration: float | None = None, *, design: ExperimentDesign | None = None,
               gravity: Sequence[float] | None = None) -> ExperimentDesign:
    """The experiment's design in the rig's orientation (designed, trimmed and fitted there).

    Parameters
    ----------
    rig : str, optional
        One of :data:`RIGS` (default ``"level"``: ``design`` as it is).
    duration : float or None, optional
        The experiment's duration, s (None: the documented one); not with ``design``.
    design : ExperimentDesign, optional
        The design to turn (default the documented one); one orientation.
    gravity : sequence of float, optional
        (3,) m/s^2, the palm-up gravity the rig is turned from (default the shipped parameter file's), e.g. the
        nominal model's.

    Returns
    -------
    ExperimentDesign
        ``design`` with, for a rig other than ``level``, its orientation the gravity tilted by the rig's angle
        (:func:`~alpes_dyn.model.mjcf.tilted_gravity`).

    Raises
    ------
    InputError
        An unknown rig, a bad duration, a design not of one orientation, both ``duration`` and ``design``.
    """
    if rig not in RIGS:
        raise InputError(f"rig: expected one of {', '.join(RIGS)}, got {rig!r}")
    if design is not None and duration is not None:
        raise InputError("duration: give the design's duration in design (one of them)")
    if design is None:
        design = ExperimentDesign() if duration is None else ExperimentDesign(duration=duration)
    design = _checked_design(design)
    if len(design.orientations) != 1:
        raise InputError(f"design: expected one orientation to turn, got {len(design.orientations)}")
    if RIGS[rig]:
        g = load_params().gravity if gravity is None else gravity
        design = dataclasses.replace(design, orientations=(tuple(float(x) for x in tilted_gravity(g, RIGS[rig])),))
    return design


def joined_runs(runs: Sequence[OnHandResult], nominal: Model) -> Recording:
    """The runs' recordings as one of several runs (:func:`~alpes_dyn.estimation.experiments.recording.join_runs`),
    each with its gravity columns: a run in the nominal model's gravity, which the experiment leaves out as the
    file's, written with it; the fit then takes each run in its own orientation and fits the tilt.

    Parameters
    ----------
    runs : sequence of OnHandResult
        The runs, in order (one model's).
    nominal : Model
        The model they were designed on (its ``gravity``, m/s^2).

    Returns
    -------
    Recording
    """
    recs = []
    for res in runs:
        rec = res.recording
        if rec.gravity is None:
            rec = dataclasses.replace(rec, gravity=np.repeat(np.asarray(nominal.gravity, dtype=float)[None],
                                                             rec.n_samples, 0))
        recs.append(rec)
    return join_runs(recs)


def _checked_rigs(hand_in: Any, rigs: Any) -> tuple[str, ...]:
    if not callable(hand_in):
        raise InputError(f"hand_in: expected a callable rig -> HardwareInterface, got {type(hand_in).__name__}")
    if isinstance(rigs, str) or not isinstance(rigs, (tuple, list)) or not rigs:
        raise InputError(f"rigs: expected a sequence of rigs ({', '.join(RIGS)}), got {rigs!r}")
    for r in rigs:
        if r not in RIGS:
            raise InputError(f"rigs: expected each one of {', '.join(RIGS)}, got {r!r}")
    if len(set(rigs)) != len(rigs):
        raise InputError(f"rigs: each rig once, got {list(rigs)!r}")
    return tuple(rigs)


def run_turned(hand_in: Callable[[str], HardwareInterface], nominal: Model, design: ExperimentDesign | None = None,
               rigs: Sequence[str] = TURNED_RIGS, *, path: str | Path | None = None, keep_going: bool = False,
               **options: Any) -> TurnedResult:
    """Run the identification experiment on the hand in each rig, the hand turned between them; join the runs
    (the module docstring).

    Parameters
    ----------
    hand_in : callable
        ``hand_in(rig) -> HardwareInterface``: the user's; turns the hand into ``rig`` (e.g. asks the experimenter
        to, or drives a fixture), then returns its interface. Closed here after the rig's run (or its trip).
    nominal : Model
        The model the experiment is designed on (e.g. ``Model.alpes("finger3", friction=True)``).
    design : ExperimentDesign, optional
        The palm-up design (default the documented one), one orientation; each rig's is :func:`rig_design` of it,
        turned from ``nominal.gravity``.
    rigs : sequence of str, optional
        The rigs in order, each one of :data:`RIGS` once (default :data:`TURNED_RIGS`).
    path : str or Path, optional
        Write the joined recording there (CSV), checked before the hand moves.
    keep_going : bool, optional
        False (default): a guard trip stops it all (:class:`RigTripped`). True: the rig is left out (named in
        ``tripped``) and the next one run; :class:`RigTripped` (the last trip, the earlier ones in its ``tripped``)
        only where no rig recorded.
    **options
        Passed to :func:`~alpes_dyn.estimation.experiments.on_hand.run_experiment` in every rig (``margin``,
        ``stages``, ``stage_seconds``, ``hold``, ``max_holds``, ``tolerance``); each rig is calibrated first
        (:func:`~alpes_dyn.estimation.experiments.calibration.calibrate`).

    Returns
    -------
    TurnedResult
        Raises :class:`RigTripped` (the rig named, the finger relaxed, nothing joined or written) where the guard
        stopped a rig's run; :class:`~alpes_dyn.InputError` for bad settings, before the hand moves (any error of
        a rig's run or of ``hand_in`` itself as raised).
    """
    rigs = _checked_rigs(hand_in, rigs)
    if not isinstance(nominal, Model):
        raise InputError(f"nominal: expected an alpes_dyn Model, got {type(nominal).__name__}")
    if "calibration" in options:
        raise InputError("calibration: each rig is calibrated in its own orientation (not given)")
    designs = [rig_design(r, design=_checked_design(design), gravity=nominal.gravity) for r in rigs]
    if path is not None:
        check_outputs([("path", path)], extensions={"path": ("csv",)})
    runs: list = []
    tripped: list[tuple[str, str]] = []
    for rig, d in zip(rigs, designs):
        hw = hand_in(rig)
        try:
            runs.append((rig, run_experiment(hw, nominal, d, **options)))
        except GuardTripped as trip:
            last = RigTripped(rig, trip, list(runs), tripped)
            if not keep_going:
                raise last from trip
            tripped.append((rig, str(trip)))
        finally:
            close = getattr(hw, "close", None)
            if callable(close):
                close()
    if not runs:
        raise last
    results = tuple(res for _, res in runs)
    rec = results[0].recording if len(results) == 1 else joined_runs(results, nominal)
    if path is not None:
        write_recording(rec, path)
    return TurnedResult(tuple(r for r, _ in runs), results, rec, tuple(tripped))
