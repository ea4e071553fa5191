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
               series-elastic tendon's quasi-static limit): fitted, written to the file.
``tilt``       the palm's orientation when the recording has no ``gravity_*`` columns: ``tilt_y`` on a
               planar finger (``tilt_x`` is seen only through its cosine), both on the thumb. Of the rig,
               kept in the result, not in the file.
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
               1, 2, ... samples earlier (:func:`~alpes_dyn.estimation.observers.replay.advanced`) while the residual
               falls and the verdict still names it, up to :data:`MAX_FIT_DELAY`; the delay kept in :attr:`EffectsFit.delay` (of the rig's
               sensors; written to the file, ``transmission.torque_delay``).
``capstan``    (asked for; ``auto`` adds it where a fit's verdict names "tendon-sheath friction", the residual
               following the tension times the sign of the motor velocity) each tendon's sheath friction
               ``capstan_<motor>`` (mu theta: the joints get tau_m - (1 - exp(-mu theta)) |tau_m| tanh(v_m / v_c),
               :func:`~alpes_dyn.model.transmission.capstan_torque`): fitted from 0, written to the file; its
               round alone (not with the rotor of a compliance seen: the tension's friction looks like a stretch).
============== ======================================================================================

A first fit that loses its basin (its stop reason "lost basin"; the joint stop its verdict may name is not believed of a lost fit) is made again in stages: the rigid fit, then the effects one by
one, each from the last; where one breaks it, the last converged stage is kept and :attr:`EffectsFit.notes` names
the effect. The fit kept is then judged by the observer it feeds
(:func:`~alpes_dyn.estimation.identification.observer_check.judge`): where the EKF on its file predicts the encoder badly, the fit
is not adequate, the reason naming the observer, and ``auto`` tries the effects not yet tried; where all were, the
rounds as good a fit (residual within :data:`OBSERVER_RESIDUAL_RATIO` of the kept one's) are judged too, and the first
the observer passes is kept.

Why these defaults: compliance and tilt cost nothing where they are absent (the fit finds 0) and stiction is
asked for, because the sharper sign is a different law from the smooth one of the library's own simulator
(``alpes-dyn experiment``), whose recordings it would call inadequate, and costs 15 RK4 steps per sample instead
of 4. Measured with today's documented experiment (``benchmarks/realism.py``, MuJoCo plants of finger3 drawn +-20 %,
all effects at once, seeds 40-43, 45 and 31, not tuned on, 2026-12-03, load 1.8-2.6, cache warm): the rigid fit
flagged on all six; ``--effects auto`` stops after the rotor's round (compliance and tilt, then the rotor for the
stretching cable), adequate, springs within 0.88 %, masses within 3.6 %, the EKF within 0.43 degree, all rounds
6.8-8.6 s. Measured with the experiment before it (dither 12, multisine at 0.6 of its ceiling; seeds 12-14,
2026-12-02, load about 1.5, cache warm): the rigid fit of every plant with an effect is
flagged but the torque constant's (only seed 13's, whose rigid fit loses its basin: the encoder cannot see the
scale) and the encoder offset's (never: the excitation's constant line absorbs it, harmlessly), and none of the
model's own structure is; with
``--effects auto`` every effect alone lands the springs within 0.47 %, the masses within 3.6 % and the EKF within
0.28 degree. All of them at once: springs within 0.64 %, masses within 4.0 % (1.50 / 2.33 / 4.02), the EKF within
0.27 degree on every joint, all rounds 7.4-9.7 s. Two things made the masses: the tendon's stretch under the torque
held *before* each reading (:func:`~alpes_dyn.model.transmission.torque_before`; under the same sample's torque the
masses were 4.5-11.3 % off, the elastic tendon alone's 12.8 %), and, while a fit is flagged, the rotor tried after
the stick-slip law (the rotor on a rigid tendon of seed 13, which the verdict does not name: K 4.2 -> 0.17 %, EKF 1.8
-> 0.09 degree). Without the dither the stick phases biased the springs by 1-2 % and the EKF was 0.74-1.30 degrees
off.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

from ...errors import InputError
from ...model.extras import STICTION_VELOCITY
from ...model.params import HandParams, with_values
from ...model.robot import Model
from ...symbolic.parametric import select_parameters, unseen_masses
from .harmonics import NONLINEARITY
from ..experiments.recording import segment_starts

__all__ = ["unmatched_delay", "EFFECTS", "DEFAULT_EFFECTS", "EFFECTS_INTERVAL", "MAX_FIT_DELAY", "OBSERVER_RESIDUAL_RATIO", "STICTION_VELOCITY", "parse_effects", "effect_parameters",
           "stiction_params", "alpes_models", "named_effects", "fit_effects", "EffectsFit", "NAMED_BY"]

EFFECTS: tuple[str, ...] = ("stiction", "rotor", "compliance", "tilt", "offset", "delay", "capstan")
NAMED_BY: dict[str, str] = {"stiction": "stick-slip", "rotor": "rotor inertia", "delay": "torque delay",
                            "capstan": "tendon-sheath friction"}
"""The effects ``auto`` adds where the first fit's adequacy check names them (a word of the likely missing effect)."""
DEFAULT_EFFECTS: tuple[str, ...] = ("compliance", "tilt")
MAX_FIT_DELAY = 3
"""The longest torque delay (samples) the ``delay`` effect tries: 1, 2, ... while the residual falls and the last
fit's verdict still names the delay."""
EFFECTS_INTERVAL = 0.05
"""s: the shooting interval of :func:`fit_effects`' fits unless the caller names one (``identify``'s own default is
100 ms). On MuJoCo's finger3 plants with all the effects at once (seeds 12-14), 100 ms lost the basin of seed 13
from both starts (2.53 counts, EKF 4.95 degrees), and its fit at 50 ms could not be rejoined by the later rounds;
at 50 ms every round held (0.69-0.99 counts, K within 2.4 %, masses within 4.6 %)."""


def parse_effects(text: str | Sequence[str] | None) -> tuple[str, ...]:
    """The effects of a comma-separated list (``"none"``: the rigid, smooth-friction fit; None or ``"auto"``: the
    defaults plus ``"auto"``: the rounds of :func:`fit_effects`).
    :class:`~alpes_dyn.InputError` naming an unknown or repeated one."""
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


def effect_parameters(model: Model, effects: Sequence[str], has_gravity: bool,
                      base: str | None = None) -> str | None:
    """The fit's selection for ``effects``: ``base`` (default K, m and friction: None) with ``tendon_compliance``
    (compliance), ``tilt_y`` or ``tilt`` (tilt, only where the recording has no gravity columns: else its
    orientation is known; :func:`fit_effects` fits it on a recording turned between orientations too: its
    columns the rig's nominal orientations, the mount's error on top of them unknown), ``encoder_offset`` (offset)
    and ``capstan`` (capstan: each tendon's sheath friction, from the model's value, 0 without one) added. None
    when nothing is added to the default."""
    extra = []
    if "compliance" in effects:
        extra.append("tendon_compliance")
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
    """``params`` with the friction's smooth sign at v_s = :data:`STICTION_VELOCITY` (the stick-slip law)."""
    old = params.raw["friction.smooth_velocity"]
    new = dataclasses.replace(old, value=STICTION_VELOCITY, source="assumed",
                              reason="the stick-slip law of alpes_dyn.estimation.identification.effects: a joint creeps at "
                                     "v_s atanh(tau / F_s) under a torque below F_s", std=None)
    return with_values(params, {"friction.smooth_velocity": new})


def alpes_models(model: str, params: HandParams, *, rotor_inertia: bool = False,
                 chain: str | None = None) -> Callable[[Sequence[str]], Model]:
    """``model_of`` for :func:`fit_effects` on an Alpes model: ``Model.alpes(model, friction=True, ...)`` from
    ``params``, with the stick-slip law's parameters where the effects hold ``stiction`` (made once, on first
    use) and the rotor on the tendon where they hold ``rotor`` (or ``rotor_inertia``)."""
    stick: list[HandParams] = []

    def model_of(effects: Sequence[str]) -> Model:
        if "stiction" in effects and not stick:
            stick.append(stiction_params(params))
        return Model.alpes(model, friction=True, rotor_inertia=rotor_inertia or "rotor" in effects,
                           params=stick[0] if "stiction" in effects else params, chain=chain)

    return model_of


def _nonlinear(result: Any) -> bool:
    """A flagged fit whose verdict names a nonlinearity (the residual's power at the excitation's harmonics): not
    for the encoder's offset, which adds a constant to the output. Tried anyway, it only nudged a borderline
    verdict: on MuJoCo's all-effects finger3 turned halfway (``experiment --rig both``, seeds 588, 606 and 616 of
    ``benchmarks/realism.py``) the offset's round lowered the residual by 0.16-0.34 %, was called adequate, and
    its offset came out -0.023 to -0.029 rad against the plant's +0.015 (its 4 counts and the cable's 0.5 degree of
    slack), the palm's tilt traded against it: the EKF on its file 0.50-0.57 degree off on j1, against 0.11-0.32
    without it."""
    a = getattr(result, "adequacy", None)
    return a is not None and not a.adequate and any(NONLINEARITY in m for m in a.likely_missing)


def unmatched_delay(best: Any, rounds: Sequence[tuple[tuple[str, ...], Any]], delay: int) -> str | None:
    """Where the kept fit's verdict names a torque delay that the data do not hold: the kept fit has none
    (``delay`` 0) and every round made with the torque read a sample or more earlier (``rounds``, as
    :attr:`EffectsFit.rounds`) left a larger residual -- the best match at lag 0. Then the torque delay is taken
    off its likely missing effects and the note returned says why (None where nothing was changed). A residual
    that follows the torque's own rate is any lag of the plant behind the model, not only the sensor's: MuJoCo's
    default dry friction (``solreffriction`` 0.02 s), which creeps before it slides, lags the smooth law so, and a
    refusal had named a one-sample delay that a fit at that delay made worse."""
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


def named_effects(result: Any) -> tuple[str, ...]:
    """The effects of :data:`NAMED_BY` that a flagged fit's adequacy check names among the likely missing ones."""
    a = getattr(result, "adequacy", None)
    if a is None or a.adequate:
        return ()
    return tuple(e for e, word in NAMED_BY.items() if any(word in m for m in a.likely_missing))


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
        """The record of one fit made with ``effects``."""
        return cls(result, effects, rounds=((effects, result),))

    @property
    def seconds(self) -> float:
        """The fits' time together, s (each round's ``seconds``; the kept one's alone where no round is recorded);
        the observer's check apart (``observer.seconds``)."""
        if not self.rounds:
            return float(self.result.seconds)
        return float(sum(r.seconds for _, r in self.rounds))


def _compliances(result: Any) -> list[tuple[float, float]]:
    """(value, standard error) of each tendon compliance a fit found with a finite standard error."""
    return [(value, sd) for name, value, sd in zip(result.names, result.values, result.std)
            if name.startswith("tendon_compliance") and np.isfinite(sd)]


def _elastic(result: Any) -> bool:
    """True when a fit found a tendon compliance above three of its standard errors (the cable is seen stretching)."""
    return any(value > 3.0 * sd for value, sd in _compliances(result))


def _contracting(result: Any) -> bool:
    """True when a fit found a tendon compliance below minus three of its standard errors (a cable read as
    shortening under tension: no cable does)."""
    return any(value < -3.0 * sd for value, sd in _compliances(result))


OBSERVER_RESIDUAL_RATIO = 1.05
"""A round whose residual is within this ratio of the kept fit's is as good a fit (:func:`_observer_choice`)."""


def _observer_choice(rounds: Sequence[tuple[tuple[str, ...], Any]], best: Any, recording: Any,
                     delays: dict[int, int]) -> tuple[tuple[tuple[str, ...], Any], Any] | None:
    """Where the observer fails the kept fit ``best``: the rounds as good a fit (converged, residual within
    :data:`OBSERVER_RESIDUAL_RATIO` of its), lowest residual first, judged by the observer too
    (:func:`~alpes_dyn.estimation.identification.observer_check.judge`, on ``recording``, each with its torque
    delay); the first that passes, ((effects, fit), its check), or None. Why: two rounds a hair apart in residual
    are the same fit to the encoder, and the observer tells them apart (MuJoCo's all-effects finger3 of seed 541,
    the torque 1 sample late, 2026-12-05: the delay's round 0.603 counts against 0.594 without it, not kept on its
    residual; the EKF without the delay predicted the encoder 20 ms ahead at 33x the floor, refused)."""
    from .observer_check import judge

    for effs, res in sorted(rounds, key=lambda er: er[1].residual_rms):
        if res is best or not res.converged or res.residual_rms > OBSERVER_RESIDUAL_RATIO * best.residual_rms:
            continue
        check = judge(res, recording, delays[id(res)])
        if check is not None and check.passed:
            return (effs, res), check
    return None


def fit_effects(model_of: Callable[[tuple[str, ...]], Model], recording: Any, effects: Sequence[str],
                base: str | None = None, has_gravity: bool = False, observe: bool = True,
                **kwargs: Any) -> EffectsFit:
    """Identify with ``effects`` (:func:`parse_effects`). ``model_of(effects)`` builds the model to fit from (the
    stick-slip law where ``"stiction"`` is in them, the rotor where ``"rotor"`` is). With ``"auto"`` among the
    effects: the fit without those first; then a fit with what it asks for: the effects its adequacy check names
    (:func:`named_effects`: stick-slip, the rotor), the rotor where it sees the tendon stretching (a compliance
    above three standard errors: the quasi-static cable carries the rotor's J_m S^T S to the joints, which the
    verdict does not tell from a wrong inertia), or, where it is flagged and asks for none of these (a lost
    basin, or several effects mixed), the stick-slip law, the rotor, the torque delay, then the encoder's offset
    (a taut cable's slack); kept if its residual is lower, and so on
    while the kept fit asks for more or is flagged (each effect in one round at most; ``tried`` is the last fit not
    kept, or the one before the kept one). Where the kept fit's compliance is below minus three standard errors
    (a cable shortening under tension: another effect absorbed), a last round without it, kept where it
    converges. Each round starts from the last converged one's values
    (:func:`~alpes_dyn.estimation.identification.identification.identify`'s ``start``), at :data:`EFFECTS_INTERVAL` unless
    ``kwargs`` (which go to ``identify``) name an ``interval``. With ``delay``: the torque read 1, 2, ... samples
    earlier while the residual falls and the last fit's verdict names the delay (``EffectsFit.delay``). ``observe``: the kept fit judged by the observer it
    feeds (:func:`~alpes_dyn.estimation.identification.observer_check.judge`, on the ``validation`` recording where one is given,
    else the fitted one): where the EKF on its file fails, the fit is not adequate, the reason naming the
    observer.

    Long because its stages (the delay search, the staged start, auto's rounds, the observer's judgement) share the
    rounds made, each fit's delay, the effects attempted and the notes through closures; the next step is a class
    holding that state, one method per stage (issue 36's split of estimation/)."""
    from .adequacy import AdequacyWarning
    from .identification import identify
    from .observer_check import judge
    from ..experiments.recording import Recording, read_recording
    from ..observers.replay import advanced

    auto = "auto" in effects
    chosen = tuple(e for e in effects if e != "auto")
    if not isinstance(recording, Recording):  # read once: every round fits it, the delay's on its torque advanced
        recording = read_recording(recording, model_of(chosen))
    # a hand turned between orientations: the gravity columns are the rig's nominal ones, its mount's tilt unknown
    has_gravity = has_gravity and segment_starts(recording.gravity).size == 1
    rounds: list[tuple[tuple[str, ...], Any]] = []
    delays: dict[int, int] = {}  # id(result) -> the torque delay (samples) it was fitted with

    def one(effs: tuple[str, ...], warm: Any, delay: int):
        model = model_of(tuple(e for e in effs if e != "delay"))
        selection = effect_parameters(model, effs, has_gravity, base)
        kw = dict(kwargs)
        kw.setdefault("interval", EFFECTS_INTERVAL)
        if warm is not None and warm.converged and "start" not in kw:
            # the next round from the last one's values and trajectory, in its basin (all-effects seed 12: the
            # rotor's round took 6 iterations from the stick-slip round's values; seeds 40-41: the rotor's and the
            # stick-slip law's rounds 3.2-8.2 s from the trajectory instead of 5.0-16.5 s after a homotopy)
            kw["start"] = warm
        with warnings.catch_warnings():  # the caller reports the verdict of the fit it keeps
            warnings.simplefilter("ignore", AdequacyWarning)
            res = identify(model, advanced(recording, delay), selection, **kw)
        res.torque_delay = delay if "delay" in effs else None  # written to the file with the fit (fit_result)
        rounds.append((effs, res))
        delays[id(res)] = delay
        return res

    def run(effs: tuple[str, ...], warm: Any = None):
        """One fit with ``effs``; with ``delay`` among them, the torque read 1, 2, ... samples earlier (each from
        the last, warm) while the residual falls, up to :data:`MAX_FIT_DELAY`: the lowest kept."""
        if "delay" not in effs:
            return one(effs, warm, 0)
        if warm is not None and "delay" in _effects_of(warm):
            return one(effs, warm, delays[id(warm)])  # found by an earlier round
        res = one(effs, warm, 1)
        if warm is not None and res.residual_rms >= warm.residual_rms:
            return res  # a sample's delay does not help: none longer is tried
        for d in range(2, MAX_FIT_DELAY + 1):
            # one sample more only while the last fit's verdict still names the delay (its residual following the
            # torque's rate): MuJoCo's all-effects finger3 of seed 417, one sample late, adequate at 1 sample, took
            # 20 iterations, 10 s, at 2 to end above it
            if "delay" not in named_effects(res):
                break
            nxt = one(effs, res, d)
            if not (nxt.converged and nxt.residual_rms < res.residual_rms):
                break
            res = nxt
        return res

    def _effects_of(res: Any) -> tuple[str, ...]:
        return next((e for e, r in rounds if r is res), ())

    def staged(target: tuple[str, ...], failed: Any) -> tuple[Any, tuple[str, ...]]:
        """A first fit that lost its basin, made again in stages: the rigid fit from the start, then the effects of
        ``target`` one by one, each round from the last (its values and trajectory); where a stage does not
        converge, the last converged one is kept and the note names the effect that broke it."""
        prev, stage = run(()), ()
        if not prev.converged:
            notes.append(f"staged start: the rigid fit itself did not converge ({prev.reason})")
            return failed, target
        for e in target:
            nxt = run(stage + (e,), prev)
            if not nxt.converged:
                notes.append(f"staged start: adding {e} to the converged {'+'.join(stage) or 'rigid'} fit broke it "
                             f"({nxt.reason}); kept without it")
                attempted.add(e)
                return prev, stage
            prev, stage = nxt, stage + (e,)
        return prev, stage

    def extend(best: Any, best_effects: tuple[str, ...], tried: Any, tried_effects: Any, fallback: tuple[str, ...]):
        """auto's rounds from the kept fit: what it asks for, or while flagged the effects of ``fallback``."""
        while True:
            more = tuple(e for e in named_effects(best) if e not in attempted)
            if "rotor" not in attempted and "rotor" not in more and _elastic(best):
                more += ("rotor",)  # a cable seen stretching carries the motor's rotor: J_m S^T S below its mode
            if "capstan" in more:
                # alone: a friction growing with the tension is also a cable "stretching" with it. Our finger2 with
                # mu theta 0.02, `experiment --rig both` then `identify` (2026-12-05): the sheath named after the
                # stick-slip round, with the rotor for the compliance seen: 1.53 counts, worse, flagged; alone 0.588,
                # adequate, mu theta 0.0195, K and m within 0.05 %
                more = ("capstan",)
            if not more and not best.trustworthy:
                # a flagged fit whose signature names nothing (a lost basin, or several effects mixed): stick-slip,
                # the effect every tendon-driven hand has (on MuJoCo's all-effects plants the verdict named it on
                # two seeds of three); only then, as added to a fit it does not explain it made the rotor's round
                # worse (a stretching cable's fit, K 2 % and EKF 1.1 degrees off where the rotor alone gave 0.6 %);
                # and where the stick-slip law did not help or the fit is still flagged with it, the rotor (on
                # MuJoCo's rotor on a rigid tendon, seed 13, the verdict named neither)
                more = next(((e,) for e in fallback if e not in attempted and not (e == "offset" and _nonlinear(best))),
                            ())
            if not more:
                break
            attempted.update(more)
            effs = best_effects + more
            res = run(effs, best)
            if res.residual_rms >= best.residual_rms:
                tried, tried_effects = res, effs
                if best.trustworthy:
                    break
                continue  # still flagged: the next effect not yet tried, on the fit kept
            tried, tried_effects = best, best_effects
            best, best_effects = res, effs
        return best, best_effects, tried, tried_effects

    notes: list[str] = []
    attempted = set(chosen)  # every effect a round was made with (the kept fit's among them): none is tried twice
    best, best_effects, tried, tried_effects = run(chosen), chosen, None, None
    if (not best.converged and "lost basin" in str(getattr(best, "reason", ""))
            and any(e != "stiction" and e != "rotor" for e in chosen)):
        # a lost basin from the start (MuJoCo's all-effects finger3 of seed 306: 45.8 counts, j1 at -52 deg). Its
        # verdict's joint stop is not believed: a lost fit's trajectory wanders out of range by itself (seed 536, in
        # range on the plant, 2026-12-05: the first round lost at 14.4 counts named a stop; ending there refused it
        # for the wrong cause, while auto's rounds, the rotor then the delay, fitted it: adequate, masses within
        # 1.8 %, 135 s). A plant truly on its stop (seeds 306 and 311 before the experiment adapted to the plant)
        # costs the rounds (150 s) before the refusal, which names the stop.
        first = best
        best, best_effects = staged(chosen, first)
        if best is not first:
            tried, tried_effects = first, chosen
    # a flagged fit naming nothing: stick-slip, the rotor, the torque delay (named by the verdict only where the
    # residual follows the torque's rate), then the encoder's offset, which a taut cable's slack is (MuJoCo's
    # all-effects finger3 hung fingers down, seed 413: flagged after the first three, residual 1.09 times the floor,
    # lag 1 at 0.15; the slack's 5.7 counts on the plant's 4: adequate with the offset, masses within 1.2 %)
    fallback = ("stiction", "rotor", "delay", "offset")
    if auto:
        best, best_effects, tried, tried_effects = extend(best, best_effects, tried, tried_effects, fallback)
    if auto and "compliance" in best_effects and _contracting(best):
        # a cable does not shorten under tension: the compliance absorbed another effect (MuJoCo's stick-slip
        # plant of seed 31, a rigid tendon: -0.42 +- 0.10 with the masses 5.2 % off; held at 0, within 2.6 %)
        effs = tuple(e for e in best_effects if e != "compliance")
        res = run(effs, best)
        if res.converged:
            tried, tried_effects, best, best_effects = best, best_effects, res, effs
    check = None
    if observe:
        val = kwargs.get("validation")
        on = val if isinstance(val, type(recording)) else recording
        check = judge(best, on, delays[id(best)])
        while auto and check is not None and not check.passed and any(e not in attempted for e in fallback):
            # the EKF on the kept file fails where the fit's own verdict passed: the effects not yet tried, from it,
            # the torque delay among them (MuJoCo's all-effects finger3, seeds 405-409: the fit adequate without
            # it, its EKF predicting the encoder 20 ms ahead within 28-43 times the floor; 9-13 with it); each new
            # fit kept judged again
            again = extend(best, best_effects, tried, tried_effects, fallback)
            if again[0] is best:
                break
            best, best_effects, tried, tried_effects = again
            check = judge(best, on, delays[id(best)])
        if auto and check is not None and not check.passed:
            other = _observer_choice(rounds, best, on, delays)
            if other is not None:
                tried, tried_effects = best, best_effects
                (best_effects, best), check = other
    note = unmatched_delay(best, rounds, delays[id(best)])
    if note:
        notes.append(note)
    return EffectsFit(best, best_effects, tried, tried_effects, tuple(rounds), delays[id(best)], check, notes)
