"""The effects of a real hand that a fit takes beyond the rigid, smooth-friction model (issue 16).

A real tendon-driven finger has what the model of the report leaves out; each is one switch of
``alpes-dyn identify --effects`` (default :data:`DEFAULT_EFFECTS`: compliance and tilt):

============== ======================================================================================
effect         what the fit does
============== ======================================================================================
``stiction``   (asked for; ``auto`` adds it where a fit's verdict names it, or flags it naming nothing) the friction's smooth sign tanh(qd / v_s) sharpened to v_s = :data:`STICTION_VELOCITY`
               (0.02 rad/s): a joint under a torque below F_s creeps at v_s atanh(tau / F_s) instead of
               sliding, the stick phases of dry friction; RK4 steps shortened to match
               (:func:`~alpes_dyn.simulation.integrate.stable_substeps`). The file written keeps this v_s.
``compliance`` the tendon's stretch seen by the encoder, y_k = S q_k + C tau_m,k-1 (``tendon_compliance``, the
               series-elastic tendon's quasi-static limit): fitted, written to the file; a motor whose torque
               did not move in the recording (:func:`still_motors`: the thumb's ab/adduction held relaxed) keeps
               the model's, named in the fit's ``not_identified`` (its stretch is not seen).
``tilt``       the palm's tilt: ``tilt_y`` on a planar finger (``tilt_x`` is seen only through its cosine), both on
               the thumb; on the file's gravity, or on the recording's ``gravity_*`` columns where ``identify``
               reads them (the rig's orientation as set up, palm up or hung: a real mount is degrees off it;
               :func:`fit_effects`' ``has_gravity`` True holds them as measured, the tilt not fitted).
``rotor``      (asked for, named, where the cable is seen stretching, or where a fit with the stick-slip law is still
               flagged) the motor's rotor on its tendon, J_m S^T S with the file's
               ``transmission.J_m`` (the motor's datasheet; held, not fitted: ``--parameters J_m`` fits it)
``offset``     the encoder's zero (``encoder_offset_<motor>``); off by default: a few counts are harmless
               (absorbed by the initial states), and beside the tilt it trades with the masses. ``auto`` adds it
               last to a fit still flagged naming nothing: the slack delta of a taut cable is a constant shift of
               the encoder (MuJoCo's 0.5 degree of play at the motor shaft: 5.7 counts, the joints unchanged),
               which on top of a zero's few counts colours a hung finger's residual.
``delay``      (asked for; ``auto`` adds it where a fit's verdict names "torque delay", the residual following
               the torque's own rate) the recorded torque lagging
               the motor's by whole samples (the current's filter and the bus): the fit made on the torque read
               1, 2, ... samples earlier (:func:`~alpes_dyn.estimation.observers.torque_reading.advanced`) while the residual
               falls and the verdict still names it, up to :data:`MAX_FIT_DELAY`; the delay kept in :attr:`EffectsFit.delay` (of the rig's
               sensors; written to the file, ``transmission.torque_delay``).
``lugre``      (asked for; ``auto`` adds it where a fit's verdict names a friction with a state) the LuGre law
               (:mod:`~alpes_dyn.model.friction`): the bristles in the fit's state, ``sigma0`` and ``sigma1``
               fitted with F_s and F_v (:func:`lugre_params`); the file written has ``friction.law = "lugre"``.
``creep``      (asked for; ``auto`` adds it where a fit drove a joint's F_s towards 0, a dry friction read as
               viscous: :func:`~alpes_dyn.estimation.identification.creep.collapsed`, or held one its steps ran there:
               :func:`~alpes_dyn.estimation.identification.creep.ran_down`) the creep law
               (:class:`~alpes_dyn.model.friction.Creep`, MuJoCo's soft ``frictionloss``: a band of viscous
               friction and added inertia up to F_s), its ``creep_kappa`` and ``creep_rate`` fitted with F_s and F_v
               from the file's (:func:`creep_params`); the file written has ``friction.law = "creep"``.
``capstan``    (asked for; ``auto`` adds it where a fit's verdict names "tendon-sheath friction", the residual
               following the tension times the sign of the motor velocity) each tendon's sheath friction
               ``capstan_<motor>`` (mu theta: the joints get tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c),
               :func:`~alpes_dyn.model.transmission.capstan_torque`): fitted from 0, written to the file; its
               round alone (not with the rotor of a compliance seen: the tension's friction looks like a stretch).
============== ======================================================================================

Which effects ``--effects auto`` tries, in which order, from which start and with which rule to keep a fit is
the table :data:`~alpes_dyn.estimation.identification.rounds.ROUNDS` (:mod:`~alpes_dyn.estimation.identification.rounds`),
walked by :func:`fit_effects`. A first fit that loses its basin is made again in stages (the rigid fit, then the
effects one by one, each from the last; where one breaks it, the last converged stage is kept and
:attr:`EffectsFit.notes` names the effect); the joint stop a lost fit's verdict may name is not believed. The fit
kept is then judged by the observer it feeds (:func:`~alpes_dyn.estimation.identification.observer_check.judge`):
where the EKF on its file predicts the encoder badly, the fit is not adequate, the reason naming the observer, and
``auto`` tries the effects not yet tried; where all were, the rounds as good a fit (residual within
:data:`OBSERVER_RESIDUAL_RATIO` of the kept one's) are judged too, and the first the observer passes is kept.

Why these defaults: compliance and tilt cost nothing where they are absent (the fit finds 0); stiction is asked
for, not a default, because the sharper sign is a different law from the smooth one of the library's own simulator
(``alpes-dyn experiment``), whose recordings it would call inadequate, and costs 15 RK4 steps per sample instead
of 4. What ``--effects auto`` achieves on MuJoCo's plants of finger3 with a real hand's effects (springs, masses,
the EKF on the file, each round's time) is ``benchmarks/realism.py``'s record, ``benchmarks/results/realism.json``
(the benchmarks page).
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ...errors import InputError
from ...model.extras import STICTION_VELOCITY
from ...model.params import HandParams, Param, with_values
from ...model.robot import Model
from ...model.friction import creep_of, lugre_of
from ...symbolic.parametric import parameter_catalogue, select_parameters, unseen_masses
from .creep import name_creep
from .law_spread import other_law, widen
from .rounds import FALLBACK, NAMED_BY, ROUNDS, Round, name_sticking, named_effects, rounds_of, sticking
from .shooting import FitDiverged
from ..experiments.recording import segment_starts

__all__ = ["EFFECTS", "DEFAULT_EFFECTS", "EFFECTS_INTERVAL", "LUGRE_INTERVAL", "MAX_FIT_DELAY", "OBSERVER_RESIDUAL_RATIO",
           "STICTION_VELOCITY", "MOVED_RATIO", "parse_effects", "effect_parameters", "still_motors", "stiction_params", "lugre_params", "lugre_start", "creep_params", "alpes_models", "fit_effects",
           "EffectsFit", "Kept", "RoundWalker", "unmatched_delay"]  # (NAMED_BY, named_effects: the rounds module's, imported here)

EFFECTS: tuple[str, ...] = ("stiction", "rotor", "compliance", "tilt", "offset", "delay", "capstan", "lugre", "creep")
DEFAULT_EFFECTS: tuple[str, ...] = ("compliance", "tilt")
MAX_FIT_DELAY = 3
"""The longest torque delay (samples) the ``delay`` effect tries: 1, 2, ... while the residual falls and the last
fit's verdict still names the delay."""
EFFECTS_INTERVAL = 0.05
"""s: the shooting interval of :func:`fit_effects`' fits unless the caller names one (``identify``'s own default is
100 ms): at 100 ms one of MuJoCo's finger3 plants with all the effects at once lost its basin from both starts,
where at 50 ms every round held (``benchmarks/realism.py``, ``benchmarks/results/realism.json``)."""


LUGRE_INTERVAL = 0.025
"""s: the longest shooting interval of a fit with the LuGre law: a joint that sticks in one interval's model and
slides in the data's is far from the linearisation; on a LuGre finger3 (2 s, +-20 %) at 50 ms the fit ended at
2.95 counts (5x the floor), at 25 ms at 0.71 with the springs and masses within 0.6 %."""


def parse_effects(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """The effects of a comma-separated list (``"none"``: the rigid, smooth-friction fit; None or ``"auto"``: the
    defaults plus ``"auto"``: the rounds of :func:`fit_effects`).

    Parameters
    ----------
    text : str or sequence of str or None
        The effects: a comma-separated string (``"compliance,tilt"``), a list of effect names (of
        :data:`EFFECTS`, or ``"auto"``), ``"none"`` alone, or None (as ``"auto"``).

    Returns
    -------
    tuple of str
        The effects named, in the order given (``"auto"`` kept among them); empty for ``"none"``.

    Raises
    ------
    InputError
        Naming an unknown or repeated effect, an empty list, ``"none"`` beside others, or a value neither a
        string nor a list of strings.
    """
    if text is None or text == "auto":
        return DEFAULT_EFFECTS + ("auto",)
    if not isinstance(text, (str, list, tuple)) or not all(isinstance(it, str) for it in text):
        raise InputError(f"effects: expected a comma-separated string or a list of effect names, got "
                         f"{type(text).__name__} {text!r:.60}")
    items = [s.strip() for s in text.split(",")] if isinstance(text, str) else list(text)
    if not items:
        raise InputError("effects: an empty list (give 'none' for the rigid, smooth-friction fit)")
    if items == ["none"]:
        return ()
    if "none" in items:
        raise InputError(f"effects: 'none' goes alone (the rigid, smooth-friction fit), got {text!r:.80}")
    for it in items:
        if it not in EFFECTS + ("auto",):
            raise InputError(f"effects: unknown effect {it!r} (expected some of {', '.join(EFFECTS)}, auto, or none)")
    if len(set(items)) != len(items):
        raise InputError(f"effects: an effect is named twice in {text!r}")
    return tuple(items)


def _planar(model: Model) -> bool:
    """Every joint axis parallel at q = 0 (a finger moving in one plane): then only tilt_y is seen."""
    import pinocchio as pin

    data = model.pin_model.createData()
    J = pin.computeJointJacobians(model.pin_model, data, np.zeros(model.pin_model.nq))
    axes = J[3:].T  # (n, 3): each revolute joint's axis in the base frame
    norms = np.linalg.norm(axes, axis=1)
    if np.any(norms < 1e-12):
        return False
    a = axes / norms[:, None]
    return bool(np.all(np.linalg.norm(np.cross(a[0], a), axis=1) < 1e-9))


MOVED_RATIO = 2.0
"""A motor's torque moved in a recording where its standard deviation exceeds this many times its sample-to-sample
noise (the standard deviation of its first differences over sqrt 2, which white noise alone gives): below, the
torque is its noise about a constant (a motor held relaxed, the thumb's ab/adduction during the flexion's
experiment), and its cable's stretch C tau_m is not seen (:func:`still_motors`)."""


def still_motors(recording: Any) -> dict[str, tuple[float, float]]:
    """The motors whose torque did not move in ``recording`` (:data:`MOVED_RATIO`), each with (its torque's standard
    deviation, its sample-to-sample noise), N m: the fit holds their tendon compliance (:func:`effect_parameters`).

    Parameters
    ----------
    recording : ~alpes_dyn.estimation.experiments.recording.Recording
        The recording (its ``torque`` (N, m) N m and ``motor_names``).

    Returns
    -------
    dict of str to tuple of float
        Motor name -> (spread, noise), in the recording's motor order; empty where every torque moved.
    """
    tau = np.asarray(recording.torque, dtype=float)
    if tau.shape[0] < 3:
        return {}
    spread, noise = tau.std(axis=0), np.diff(tau, axis=0).std(axis=0) / np.sqrt(2.0)
    return {m: (float(s), float(e)) for m, s, e in zip(recording.motor_names, spread, noise)
            if not s > MOVED_RATIO * e}


def effect_parameters(model: Model, effects: Sequence[str], has_gravity: bool,
                      base: str | None = None, still: Sequence[str] = ()) -> str | None:
    """The fit's selection for ``effects``: ``base`` (default K, m and friction: None) with ``tendon_compliance``
    (compliance: every motor's but those of ``still``, whose torque did not move, :func:`still_motors`),
    ``tilt_y`` or ``tilt`` (tilt, only where the recording has no gravity columns: else its
    orientation is known; :func:`fit_effects` fits it on a recording turned between orientations too: its
    columns the rig's nominal orientations, the mount's error on top of them unknown), ``encoder_offset`` (offset)
    and ``capstan`` (capstan: each tendon's sheath friction, from the model's value, 0 without one) added.

    Parameters
    ----------
    model : Model
        The model fitted (its parameter catalogue; whether its joint axes are parallel, a planar finger, decides
        ``tilt_y`` or ``tilt``).
    effects : sequence of str
        The fit's effects (:data:`EFFECTS`).
    has_gravity : bool
        The recording has gravity columns that are its orientation: the tilt is not fitted.
    base : str or None, optional
        The selection before the effects' parameters (default None: K, m and friction, or the default
        selection less the unseen masses where the model has some).
    still : sequence of str, optional
        The motors whose torque did not move (:func:`still_motors`): their tendon compliance held (default: none).

    Returns
    -------
    str or None
        The comma-separated selection; None (``base``) when nothing is added to the default.
    """
    extra = []
    if "compliance" in effects:
        extra += (["tendon_compliance"] if not still else
                  [pp.name for pp in parameter_catalogue(model) if pp.kind == "tendon_compliance"
                   and pp.motor not in still])
    if "capstan" in effects:
        extra.append("capstan")
    if "tilt" in effects and not has_gravity:
        extra.append("tilt_y" if _planar(model) else "tilt")
    if "offset" in effects:
        extra.append("encoder_offset")
    if not extra:
        return base
    if base is None:
        base = (",".join(pp.name for pp in select_parameters(model, None)) if unseen_masses(model)  # the default's
                else "K,m" + (",friction" if model.extras.has_friction else ""))  # (unseen masses held)
    return ",".join([base] + extra)


def stiction_params(params: HandParams) -> HandParams:
    """``params`` with the friction's smooth sign at v_s = :data:`STICTION_VELOCITY` (the stick-slip law).

    Parameters
    ----------
    params : HandParams
        The model's parameters (its ``friction.smooth_velocity`` replaced, marked ``assumed``).

    Returns
    -------
    HandParams
        A copy with ``friction.smooth_velocity`` = :data:`STICTION_VELOCITY` rad/s.
    """
    old = params.raw["friction.smooth_velocity"]
    new = dataclasses.replace(old, value=STICTION_VELOCITY, source="assumed",
                              reason="the stick-slip law of alpes_dyn.estimation.identification.effects: a joint creeps at "
                                     "v_s atanh(tau / F_s) under a torque below F_s", std=None)
    return with_values(params, {"friction.smooth_velocity": new})


def lugre_params(params: HandParams) -> HandParams:
    """``params`` with the LuGre law (``friction.law = "lugre"``; its sigma0 and sigma1 the file's, else the
    defaults of :mod:`~alpes_dyn.model.friction`: the fit's start).

    Parameters
    ----------
    params : HandParams
        The model's parameters.

    Returns
    -------
    HandParams
        ``params`` itself where its law is already ``"lugre"``, else a copy with ``friction.law = "lugre"``.
    """
    return _with_law(params, "lugre", "the friction law with a state")


def _with_law(params: HandParams, law: str, what: str) -> HandParams:
    """``params`` with ``friction.law = law`` (itself where it already has it), ``what`` the law in words for the
    value's source: ``--effects LAW``."""
    if params.friction_law == law:
        return params
    return with_values(params, {"friction.law": Param(law, "-", "assumed", f"{what} of --effects {law}",
                                                      "the joints' friction law")})


def creep_params(params: HandParams) -> HandParams:
    """``params`` with the creep law (``friction.law = "creep"``; its band constants the file's, else MuJoCo's
    default constraint's, :class:`~alpes_dyn.model.friction.Creep`: the fit's start).

    Parameters
    ----------
    params : HandParams
        The model's parameters.

    Returns
    -------
    HandParams
        ``params`` itself where its law is already ``"creep"``, else a copy with ``friction.law = "creep"``.
    """
    return _with_law(params, "creep", "the dry friction that creeps")


def lugre_start(result: Any) -> dict[str, float]:
    """The start of a fit with the LuGre law after ``result``, a fit with a memoryless law: its values by name but
    its friction's (F_s, F_v: the file's, as sigma0 and sigma1), without its trajectory. The smooth law's F_s takes
    up the sticking of a stateful friction (+69 % on F_s_2 of a LuGre finger3): from those values the LuGre fit lost
    its basin, from the file's friction with the smooth fit's springs and masses it met the sensor floor.

    Parameters
    ----------
    result : IdentificationResult
        The fit with a memoryless law (its ``names`` and ``values``).

    Returns
    -------
    dict of str to float
        Parameter name -> value, in the result's units, every fitted parameter but the ``F_s_*`` and ``F_v_*``.
    """
    return {n: float(v) for n, v in zip(result.names, result.values) if not n.startswith(("F_s_", "F_v_"))}


def alpes_models(model: str, params: HandParams, *, rotor_inertia: bool = False,
                 chain: str | None = None) -> Callable[[Sequence[str]], Model]:
    """``model_of`` for :func:`fit_effects` on an Alpes model: ``Model.alpes(model, friction=True, ...)`` from
    ``params``, with the stick-slip law's parameters where the effects hold ``stiction``, the LuGre law where they
    hold ``lugre``, the creep law where they hold ``creep`` (each made once, on first use) and the rotor on the
    tendon where they hold ``rotor`` (or ``rotor_inertia``).

    Parameters
    ----------
    model : str
        The Alpes model's name (``"finger2"``, ``"finger3"``, ``"hand"`` or ``"thumb"``:
        :meth:`~alpes_dyn.model.robot.Model.alpes`).
    params : HandParams
        The parameters the models are built from (the fit's start).
    rotor_inertia : bool, optional
        Every model with the motor's rotor on its tendon, J_m S^T S, whatever the effects (default False: only
        with ``rotor``).
    chain : str or None, optional
        A finger model built from that finger of the hand (a name of ``palm.finger_names``;
        :meth:`~alpes_dyn.model.robot.Model.alpes`' ``chain``); default None: the model as named.

    Returns
    -------
    callable
        ``model_of(effects) -> Model``.
    """
    made: dict[str, HandParams] = {}

    def model_of(effects: Sequence[str]) -> Model:
        law = next((e for e in ("lugre", "creep", "stiction") if e in effects), None)
        if law is not None and law not in made:
            made[law] = {"lugre": lugre_params, "creep": creep_params, "stiction": stiction_params}[law](params)
        return Model.alpes(model, friction=True, rotor_inertia=rotor_inertia or "rotor" in effects,
                           params=made[law] if law is not None else params, chain=chain)

    return model_of


def unmatched_delay(best: Any, rounds: Sequence[tuple[tuple[str, ...], Any]], delay: int) -> str | None:
    """Where the kept fit's verdict names a torque delay that the data do not hold: the kept fit has none
    (``delay`` 0) and every round made with the torque read a sample or more earlier (``rounds``, as
    :attr:`EffectsFit.rounds`) left a larger residual -- the best match at lag 0. Then the torque delay is taken
    off its likely missing effects and the note returned says why (None where nothing was changed). A residual
    that follows the torque's own rate is any lag of the plant behind the model, not only the sensor's: MuJoCo's
    default dry friction (``solreffriction`` 0.02 s), which creeps before it slides, lags the smooth law so, and a
    refusal had named a one-sample delay that a fit at that delay made worse.

    Parameters
    ----------
    best : IdentificationResult
        The kept fit (its ``adequacy.likely_missing`` edited in place where the delay is taken off).
    rounds : sequence of (tuple of str, IdentificationResult)
        Every fit made, as (effects, result) (:attr:`EffectsFit.rounds`).
    delay : int
        The kept fit's torque delay, samples (0: none).

    Returns
    -------
    str or None
        The note saying why the delay was taken off, or None where nothing was changed.
    """
    a = getattr(best, "adequacy", None)
    word = NAMED_BY["delay"]
    if delay or a is None or a.adequate or not any(word in m for m in a.likely_missing):
        return None
    late = [r.residual_rms for e, r in rounds if "delay" in e]
    if not late or min(late) < best.residual_rms:
        return None
    a.likely_missing = [m for m in a.likely_missing if word not in m]
    return (f"the residual follows the torque's rate, but a fit with the torque read a sample earlier left "
            f"{min(late):.3g} counts against {best.residual_rms:.3g} at lag 0: no torque delay (another lag of the "
            "plant behind the model, e.g. a dry friction that creeps before it slides)")


@dataclass
class EffectsFit:
    """What :func:`fit_effects` did: the result kept and the effects it was fitted with; ``tried``: the other fit
    where ``"auto"`` made two (with and without the stick-slip law; None otherwise) and its effects; ``rounds``:
    every fit made, in order, as (effects, result); ``seconds``: their time together, s."""

    result: Any
    effects: tuple[str, ...]
    tried: Any = None
    tried_effects: tuple[str, ...] | None = None
    rounds: tuple[tuple[tuple[str, ...], Any], ...] = ()
    delay: int = 0
    """Whole samples by which the kept fit found the recorded torque lagging the motor's (``delay``; 0 without it):
    of the rig's sensors, also the kept result's ``torque_delay``, written to its file (``transmission.torque_delay``,
    which the EKF on a recording reads: :func:`~alpes_dyn.estimation.observers.replay.estimate_recording`)."""
    observer: Any = None
    """The observer's check of the kept fit (:func:`~alpes_dyn.estimation.identification.observer_check.judge`), or None."""
    notes: list[str] = dataclasses.field(default_factory=list)
    """What a staged start did (which effect broke a fit that lost its basin)."""

    @classmethod
    def single(cls, result: Any, effects: tuple[str, ...]) -> "EffectsFit":
        """The record of one fit made with ``effects``.

        Parameters
        ----------
        result : IdentificationResult
            The fit.
        effects : tuple of str
            Its effects (:data:`EFFECTS`).

        Returns
        -------
        EffectsFit
            ``result`` kept, its only round.
        """
        return cls(result, effects, rounds=((effects, result),))

    @property
    def seconds(self) -> float:
        """The fits' time together, s (each round's ``seconds``; the kept one's alone where no round is recorded);
        the observer's check apart (``observer.seconds``)."""
        if not self.rounds:
            return float(self.result.seconds)
        return float(sum(r.seconds for _, r in self.rounds))


OBSERVER_RESIDUAL_RATIO = 1.05
"""A round whose residual is within this ratio of the kept fit's is as good a fit (:func:`_observer_choice`): two
rounds a hair apart in residual are the same fit to the encoder, and the observer tells them apart (a torque one
sample late: ``benchmarks/realism.py``'s records, ``benchmarks/results/realism.json``)."""


def _observer_choice(rounds: Sequence[tuple[tuple[str, ...], Any]], best: Any, recording: Any,
                     delays: dict[int, int]) -> tuple[tuple[tuple[str, ...], Any], Any] | None:
    """Where the observer fails the kept fit ``best``: the rounds as good a fit (converged, residual within
    :data:`OBSERVER_RESIDUAL_RATIO` of its), lowest residual first, judged by the observer too
    (:func:`~alpes_dyn.estimation.identification.observer_check.judge`, on ``recording``, each with its torque
    delay); the first that passes, ((effects, fit), its check), or None."""
    from .observer_check import judge

    for effs, res in sorted(rounds, key=lambda er: er[1].residual_rms):
        if res is best or not res.converged or res.residual_rms > OBSERVER_RESIDUAL_RATIO * best.residual_rms:
            continue
        check = judge(res, recording, delays[id(res)])
        if check is not None and check.passed:
            return (effs, res), check
    return None


@dataclass
class Kept:
    """The fit kept by the rounds so far: ``result`` with ``effects``; ``tried``, ``tried_effects``: the last fit
    not kept (a refused round's, or the one a round replaced)."""

    result: Any
    effects: tuple[str, ...]
    tried: Any = None
    tried_effects: tuple[str, ...] | None = None

    def take(self, result: Any, effects: tuple[str, ...]) -> None:
        """``result`` kept in place of the current fit, which becomes ``tried``.

        Parameters
        ----------
        result : IdentificationResult
            The round's fit, now kept.
        effects : tuple of str
            Its effects.
        """
        self.tried, self.tried_effects, self.result, self.effects = self.result, self.effects, result, effects

    def refuse(self, result: Any, effects: tuple[str, ...]) -> None:
        """``result`` not kept: it becomes ``tried``.

        Parameters
        ----------
        result : IdentificationResult
            The round's fit, refused.
        effects : tuple of str
            Its effects.
        """
        self.tried, self.tried_effects = result, effects


class RoundWalker:
    """The rounds of :func:`fit_effects` on one recording: each fit made (:attr:`rounds`), its torque delay, the
    effects attempted and the notes, shared by the stages that walk :data:`~.rounds.ROUNDS`.

    Parameters
    ----------
    model_of : callable
        ``model_of(effects) -> Model``: the model to fit with ``effects`` (:func:`alpes_models`).
    recording : Recording
        The recording every round fits (its torque advanced by a round's delay).
    has_gravity : bool
        The recording's gravity columns are its orientation (else the tilt is fitted, where asked).
    base : str or None
        The fit's selection before the effects' parameters (:func:`effect_parameters`).
    identify_kwargs : dict
        Passed to :func:`~alpes_dyn.estimation.identification.identification.identify` (``interval``:
        :data:`EFFECTS_INTERVAL` unless given; ``start``: the kept fit unless given).
    """

    def __init__(self, model_of: Callable[[tuple[str, ...]], Model], recording: Any, has_gravity: bool,
                 base: str | None, identify_kwargs: dict[str, Any]):
        self.model_of, self.recording, self.has_gravity, self.base = model_of, recording, has_gravity, base
        self.kwargs = identify_kwargs
        self.rounds: list[tuple[tuple[str, ...], Any]] = []
        self.delays: dict[int, int] = {}  # id(result) -> the torque delay (samples) it was fitted with
        self.attempted: set[str] = set()  # every effect a round was made with: none is tried twice
        self.notes: list[str] = []
        self.still = still_motors(recording)  # motor -> (spread, noise): their compliance held, named

    def one(self, effs: tuple[str, ...], warm: Any, delay: int) -> Any:
        """One fit with ``effs`` on the torque read ``delay`` samples earlier, from ``warm`` where it converged.

        Parameters
        ----------
        effs : tuple of str
            The fit's effects (:data:`EFFECTS`).
        warm : IdentificationResult or None
            The fit it starts from where converged (its values and trajectory); None: the model's values.
        delay : int
            The torque delay, samples: the fit made on the torque read this many samples earlier.

        Returns
        -------
        IdentificationResult
            The fit, recorded in :attr:`rounds` and its delay in :attr:`delays`.
        """
        from .adequacy import AdequacyWarning
        from .identification import identify
        from ..observers.torque_reading import advanced

        model = self.model_of(tuple(e for e in effs if e != "delay"))
        selection = effect_parameters(model, effs, self.has_gravity, self.base, tuple(self.still))
        kw = dict(self.kwargs)
        kw.setdefault("interval", EFFECTS_INTERVAL)
        if lugre_of(model) is not None:  # (LUGRE_INTERVAL)
            kw["interval"] = min(kw["interval"], LUGRE_INTERVAL)
        if warm is not None and warm.converged and "start" not in kw:
            kw["start"] = warm  # the next round from the last one's values and trajectory, in its basin
            if (lugre_of(model) is not None and lugre_of(warm.model) is None) or (
                    creep_of(model) is not None and creep_of(warm.model) is None):
                kw["start"] = lugre_start(warm)  # the friction from the file's: the memoryless law's is not its
        with warnings.catch_warnings():  # the caller reports the verdict of the fit it keeps
            warnings.simplefilter("ignore", AdequacyWarning)
            res = identify(model, advanced(self.recording, delay), selection, **kw)
        res.torque_delay = delay if "delay" in effs else None  # written to the file with the fit (fit_result)
        if "compliance" in effs and self.still:
            res.not_identified = {**self._held_compliances(model), **res.not_identified}
        self.rounds.append((effs, res))
        self.delays[id(res)] = delay
        return res

    def _held_compliances(self, model: Model) -> dict[str, str]:
        """``not_identified`` clauses of the tendon compliances held because their motor's torque did not move."""
        out = {}
        for pp in parameter_catalogue(model):
            if pp.kind == "tendon_compliance" and pp.motor in self.still:
                s, e = self.still[pp.motor]
                out[pp.name] = (f"held at {pp.nominal:g} rad/(N m), not fitted: its motor's torque did not move in the "
                                f"recording (spread {s:.2g} N m, within {MOVED_RATIO:g} times its noise {e:.2g} N m); "
                                "the data do not see an elastic tendon")
        return out

    def run(self, effs: tuple[str, ...], warm: Any = None) -> Any:
        """One fit with ``effs``; with ``delay`` among them, the torque read 1, 2, ... samples earlier (each from
        the last) while the residual falls and the last fit's verdict still names the delay, up to
        :data:`MAX_FIT_DELAY`: the lowest kept.

        Parameters
        ----------
        effs : tuple of str
            The fit's effects (:data:`EFFECTS`).
        warm : IdentificationResult or None, optional
            The fit it starts from (default None: the model's values).

        Returns
        -------
        IdentificationResult
            The fit (with ``delay``: the one of the lowest residual).
        """
        if "delay" not in effs:
            return self.one(effs, warm, 0)
        if warm is not None and "delay" in next((e for e, r in self.rounds if r is warm), ()):
            return self.one(effs, warm, self.delays[id(warm)])  # found by an earlier round
        res = self.one(effs, warm, 1)
        if warm is not None and res.residual_rms >= warm.residual_rms:
            return res  # a sample's delay does not help: none longer is tried
        for d in range(2, MAX_FIT_DELAY + 1):
            if "delay" not in named_effects(res):
                break
            nxt = self.attempt(f"delay of {d} samples", effs, res, d)
            if nxt is None or not (nxt.converged and nxt.residual_rms < res.residual_rms):
                break
            res = nxt
        return res

    def attempt(self, name: str, effs: tuple[str, ...], warm: Any = None, delay: int | None = None) -> Any:
        """:meth:`run` (or :meth:`one` at ``delay`` samples where given) for the round ``name``; None where its fit
        runs away (:class:`~alpes_dyn.estimation.identification.shooting.FitDiverged`): a failed round, named in
        :attr:`notes`, its overflow warnings dropped, the kept fit standing.

        Parameters
        ----------
        name : str
            The round's name, for the note.
        effs : tuple of str
            The effects of the round's fit (:data:`EFFECTS`).
        warm : IdentificationResult or None, optional
            The fit it starts from (None: the model's values).
        delay : int or None, optional
            The torque delay in samples to fit at (:meth:`one`); None: :meth:`run`'s own.

        Returns
        -------
        IdentificationResult or None
            The round's fit, or None where it diverged.
        """
        with warnings.catch_warnings(record=True) as seen:  # a diverged round's overflow warnings: its note instead
            warnings.simplefilter("always")
            try:
                res = self.run(effs, warm) if delay is None else self.one(effs, warm, delay)
            except FitDiverged as exc:
                self.notes.append(f"round {name} ({'+'.join(effs) or 'rigid'}): {exc}; the fit kept before it stands")
                return None
        for w in seen:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return res

    def first(self, chosen: tuple[str, ...]) -> Kept:
        """The ``first`` stage: the fit with ``chosen``; where it lost its basin, the ``staged`` round.

        Parameters
        ----------
        chosen : tuple of str
            The effects asked for (``"auto"`` left out).

        Returns
        -------
        Kept
            The fit kept (the staged one where the first lost its basin, the first then ``tried``).
        """
        first_round, staged = rounds_of("first")
        self.attempted.update(chosen)
        res = self.run(first_round.proposal(None, chosen))
        kept = Kept(res, chosen)
        target = staged.proposal(res, chosen)
        if target is not None:
            best, effs = self.staged(target, res)
            if best is not res:
                kept = Kept(best, effs, res, chosen)
        return kept

    def staged(self, target: tuple[str, ...], failed: Any) -> tuple[Any, tuple[str, ...]]:
        """The rigid fit, then the effects of ``target`` one by one, each round from the last; where a stage does
        not converge, the last converged one is kept and a note names the effect that broke it.

        Parameters
        ----------
        target : tuple of str
            The effects to add one by one.
        failed : IdentificationResult
            The fit that lost its basin (kept where the rigid fit itself does not converge).

        Returns
        -------
        tuple of (IdentificationResult, tuple of str)
            The last converged stage's fit and its effects (``failed`` and ``target`` where none converged).
        """
        accepts = dict((r.name, r) for r in ROUNDS)["staged"].accepts
        prev, stage = self.attempt("staged", ()), ()
        if prev is None or not accepts(prev, failed):
            if prev is not None:
                self.notes.append(f"staged start: the rigid fit itself did not converge ({prev.reason})")
            return failed, target
        for e in target:
            nxt = self.attempt("staged", stage + (e,), prev)
            if nxt is None or not accepts(nxt, prev):
                why = "it diverged" if nxt is None else nxt.reason
                self.notes.append(f"staged start: adding {e} to the converged {'+'.join(stage) or 'rigid'} fit "
                                  f"broke it ({why}); kept without it")
                self.attempted.add(e)
                return prev, stage
            prev, stage = nxt, stage + (e,)
        return prev, stage

    def play(self, rnd: Round, kept: Kept) -> bool:
        """One round from ``kept``: its fit made where :meth:`Round.proposal` proposes one (from the kept fit), kept
        where the round accepts it (``kept`` updated). True where a fit was made, or tried and ran away (a failed
        round: :meth:`attempt`, the kept fit standing).

        Parameters
        ----------
        rnd : Round
            The round (of :data:`~.rounds.ROUNDS`).
        kept : Kept
            The fit kept so far, updated in place.

        Returns
        -------
        bool
            Whether a fit was made or tried.
        """
        effs = rnd.proposal(kept.result, kept.effects, self.attempted)
        if effs is None:
            return False
        if rnd.stage == "auto":
            self.attempted.update(e for e in effs if e not in kept.effects)
        res = self.attempt(rnd.name, effs, kept.result)
        if res is None:  # a round that ran away: failed, the kept fit stands
            return True
        if rnd.accepts(res, kept.result):
            kept.take(res, effs)
        else:
            kept.refuse(res, effs)
        return True

    def auto(self, kept: Kept) -> None:
        """The ``auto`` stage: the first of its rounds that proposes a fit, again while one does; ends where none
        does, or where a round is refused while the kept fit is adequate.

        Parameters
        ----------
        kept : Kept
            The fit kept so far, updated in place.
        """
        while True:
            rnd = next((r for r in rounds_of("auto")
                        if r.proposal(kept.result, kept.effects, self.attempted) is not None), None)
            if rnd is None:
                return
            before = kept.result
            self.play(rnd, kept)
            if kept.result is before and before.trustworthy:
                return

    def cable(self, kept: Kept) -> None:
        """The ``cable`` stage: each of its rounds once.

        Parameters
        ----------
        kept : Kept
            The fit kept so far, updated in place.
        """
        for rnd in rounds_of("cable"):
            self.play(rnd, kept)

    def judged_on(self, validation: Any = None) -> Any:
        """The recording the observer check judges on: ``validation`` where it is a recording (``identify
        --validate``), else the fitted one.

        Parameters
        ----------
        validation : Recording or None, optional
            A held-out recording (default None, or anything not a recording: the fitted one).

        Returns
        -------
        Recording
            The recording to judge on.
        """
        return validation if isinstance(validation, type(self.recording)) else self.recording

    def observe(self, kept: Kept, auto: bool, validation: Any = None) -> Any:
        """The kept fit judged by the observer it feeds (on ``validation`` where it is a recording, else the fitted
        one); with ``auto``, while it fails, the ``auto`` stage again, then the rounds as good a fit
        (:func:`_observer_choice`).

        Parameters
        ----------
        kept : Kept
            The fit kept so far, updated in place (another round's fit taken where the observer passes it).
        auto : bool
            ``--effects auto``: while the observer fails the kept fit, try the rounds left.
        validation : Recording or None, optional
            The recording to judge on (default None, or anything not a recording: the fitted one).

        Returns
        -------
        ObserverCheck or None
            The last check (:func:`~alpes_dyn.estimation.identification.observer_check.judge`), or None.
        """
        from .observer_check import judge

        on = self.judged_on(validation)
        check = judge(kept.result, on, self.delays[id(kept.result)])
        while auto and check is not None and not check.passed and any(e not in self.attempted for e in FALLBACK):
            before = dataclasses.replace(kept)
            self.auto(kept)
            if kept.result is before.result:
                kept.tried, kept.tried_effects = before.tried, before.tried_effects  # nothing new kept
                break
            check = judge(kept.result, on, self.delays[id(kept.result)])
        if auto and check is not None and not check.passed:
            other = _observer_choice(self.rounds, kept.result, on, self.delays)
            if other is not None:
                (effs, res), check = other
                kept.take(res, effs)
        return check


def fit_effects(model_of: Callable[[tuple[str, ...]], Model], recording: Any, effects: Sequence[str],
                base: str | None = None, has_gravity: bool = False, observe: bool = True, spread: bool = False,
                **kwargs: Any) -> EffectsFit:
    """Identify with ``effects``, walking the rounds of :data:`~alpes_dyn.estimation.identification.rounds.ROUNDS`.

    Without ``"auto"`` among ``effects``: one fit (and the staged start where it lost its basin). With it: the
    ``auto`` rounds from the first fit (what its verdict names, the rotor for a cable seen stretching, or, while it
    is flagged asking for nothing, the stick-slip law, the rotor, the torque delay, the encoder's offset), each from
    the fit kept, kept where its residual is lower; then the rigid cable's round; then, where the observer the kept
    fit feeds fails it, the ``auto`` rounds not yet tried and the rounds as good a fit (:func:`_observer_choice`).

    Parameters
    ----------
    model_of : callable
        ``model_of(effects) -> Model``: the model to fit with ``effects`` (the stick-slip law where ``"stiction"``
        is among them, the rotor where ``"rotor"`` is; :func:`alpes_models`).
    recording : Recording or str or path
        The recording (read once with the first model where a path).
    effects : sequence of str
        The effects (:func:`parse_effects`), ``"auto"`` among them for the rounds.
    base : str or None, optional
        The selection before the effects' parameters (default: K, m and friction).
    has_gravity : bool, optional
        The recording's gravity columns are its orientation (a recording turned between orientations is not: its
        columns are the rig's nominal ones, the tilt is fitted).
    observe : bool, optional
        Judge the kept fit by the observer it feeds
        (:func:`~alpes_dyn.estimation.identification.observer_check.judge`, on ``kwargs["validation"]`` where it
        is a recording): where the EKF on its file fails, the fit is not adequate, the reason naming the observer.
    spread : bool, optional
        Add the model-form error to the kept fit's standard errors where it converged with friction
        (:mod:`~alpes_dyn.estimation.identification.law_spread`): the fit made again with the other friction law,
        from the kept one (a round that made it already is reused), each std widened by the difference and the
        memoryless laws' model-form term ((S2) there).
    **kwargs
        Passed to :func:`~alpes_dyn.estimation.identification.identification.identify` (``interval``:
        :data:`EFFECTS_INTERVAL` unless given).

    Returns
    -------
    EffectsFit
        The fit kept, its effects, the other rounds, its torque delay, the observer's check and the notes.
    """
    from ..experiments.held_out import split_held_out
    from ..experiments.recording import Recording, read_recording

    auto = "auto" in effects
    chosen = tuple(e for e in effects if e != "auto")
    if not isinstance(recording, Recording):  # read once: every round fits it, the delay's on its torque advanced
        recording = read_recording(recording, model_of(chosen))
    # the held-out samples (the stiction ramp): not fitted, the observer check and its law judged on them (not the
    # open-loop validation: a memoryless law's simulation does not follow a joint that sticks); --validate's first
    recording, judged = split_held_out(recording, kwargs.get("validation"))
    has_gravity = has_gravity and segment_starts(recording.gravity).size == 1
    walk = RoundWalker(model_of, recording, has_gravity, base, kwargs)
    kept = walk.first(chosen)
    if auto:
        walk.auto(kept)
        walk.cable(kept)
    check = walk.observe(kept, auto, judged) if observe else None
    if observe and sticking(kept.result, kept.effects, walk.attempted):  # judged with the stick law among the laws
        from .observer_check import judge

        on = walk.judged_on(judged)
        check = judge(kept.result, on, walk.delays[id(kept.result)], sticking=True) or check
    notes = [unmatched_delay(kept.result, walk.rounds, walk.delays[id(kept.result)]),
             name_sticking(kept.result, kept.effects, walk.attempted)]
    if not kept.result.trustworthy:  # a dry friction read as viscous (module creep): against the file's F_s
        notes.append(name_creep(kept.result, {p.name: p.nominal for p in parameter_catalogue(model_of(chosen))}))
    walk.notes += [n for n in notes if n]
    if spread and kept.result.converged and kept.result.model.extras.has_friction:
        other = other_law(kept.effects)
        made = [r for e, r in walk.rounds if e == other and r.converged]
        widen(kept.result, made[-1] if made else walk.run(other, kept.result))
    return EffectsFit(kept.result, kept.effects, kept.tried, kept.tried_effects, tuple(walk.rounds),
                      walk.delays[id(kept.result)], check, walk.notes)
