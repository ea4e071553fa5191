"""The rounds of ``alpes-dyn identify --effects auto`` as data: which effects each round adds to the fit kept, from
which start, and the rule that keeps its fit (issue 52).
:func:`~alpes_dyn.estimation.identification.effects.fit_effects` walks :data:`ROUNDS`; each row is one round,
testable alone (:meth:`Round.proposal`, :meth:`Round.accepts`).

=============== ====== =========================================================== ============== ===============
round           stage  made when (adds)                                            starts from    kept when
=============== ====== =========================================================== ============== ===============
``first``       first  always (the effects asked for)                              the model's    always
                                                                                   values
``staged``      first  the first fit lost its basin with an effect beyond          the rigid fit, each stage
                       stiction and the rotor (the rigid fit, then those effects   then the last  converged
                       one by one)                                                 stage
``creep``       auto   the kept fit, not to be trusted, drove a joint's F_s below  the kept fit's lower residual
                       a tenth of the file's (:func:`~.creep.collapsed`: a dry     values, its
                       friction read as viscous) or holds one the steps ran        friction the
                       towards 0 (:func:`~.creep.ran_down`: the lost basin's       file's
                       hold hides the collapse) or its verdict names
                       :data:`~.creep.CREEP`, viscous friction or a friction with
                       a state (:data:`BAND_WORDS`, from :data:`BAND_FLOOR_RATIO`
                       sensor floors): the creep law, its band fitted with
                       F_s (:class:`~alpes_dyn.model.friction.Creep`)
``asked``       auto   the kept fit's verdict names effects not yet tried          the kept fit   lower residual
                       (:func:`named_effects`), or it sees the cable stretching
                       (the rotor, in place of a kept tendon-sheath friction);
                       the tendon-sheath friction alone
``lugre``       auto   the kept fit's verdict names a friction with a state        the kept fit's lower residual
                       (its residual at the velocity reversals or the harmonics:   values, its
                       :data:`~.adequacy.STATEFUL_FRICTION`): the LuGre law,       friction the
                       sigma0 and sigma1 fitted with F_s                           file's
                                                                                   (effects.
                                                                                   lugre_start)
``stiction``    auto   the kept fit is flagged and asks for nothing                the kept fit   lower residual
``rotor``       auto   likewise, the stick-slip law tried                          the kept fit   lower residual
``delay``       auto   likewise, the rotor tried                                   the kept fit   lower residual
``offset``      auto   likewise, the delay tried, its verdict naming no            the kept fit   lower residual
                       nonlinearity
``rigid cable`` cable  the kept fit's compliance is below minus three standard     the kept fit   converged
                       errors (removes the compliance)
=============== ====== =========================================================== ============== ===============

"Lower residual" keeps a fit that did not converge only over a kept fit that did not either.

A fit the walk leaves refused with the stick-slip law, its verdict naming a friction with a state within
:data:`BAND_FLOOR_RATIO` sensor floors after the LuGre law's fit was not kept (:func:`sticking`: a dry friction
that sticks), has that verdict name :data:`STUCK_FRICTION` instead of the LuGre law (:func:`name_sticking`, a note
of the walk): it stays refused, unless the observer check, made on it with the stick law among its laws, chooses
that law and passes it (:func:`~alpes_dyn.estimation.identification.observer_check.judge` with ``sticking``:
adequate, the file's ``friction.observer_law = "stick"``).

Every round with the compliance fits it on the motors whose torque moved in the recording only
(:func:`~alpes_dyn.estimation.identification.effects.still_motors`); the others' is held at the model's value and
named in the fit's ``not_identified``.

The ``auto`` stage is walked again while the kept fit's check by the observer it feeds fails
(:func:`~alpes_dyn.estimation.identification.observer_check.judge`, which marks the fit flagged); each effect is tried
in one round at most. A refused round's fit is
:attr:`~alpes_dyn.estimation.identification.effects.EffectsFit.tried`; a round whose fit diverges
(:class:`~alpes_dyn.estimation.identification.shooting.FitDiverged`) is refused, a note naming it. The measurements behind each rule are
``benchmarks/realism.py``'s records (``benchmarks/results/realism.json``) and the user guide's identification page.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Collection

import numpy as np

from ...symbolic.parametric import parameter_catalogue
from .adequacy import SIGNATURES
from .creep import CREEP, collapsed, ran_down
from .harmonics import NONLINEARITY

STATEFUL_WORD = "a friction with a state"
"""The words of the adequacy verdict's likely missing effect that make the ``lugre`` round
(:data:`~alpes_dyn.estimation.identification.adequacy.STATEFUL_FRICTION` begins with them)."""

BAND_WORDS: tuple[str, ...] = (SIGNATURES["velocity"], STATEFUL_WORD)
"""The likely missing effects of a verdict on a fit not to be trusted that make the ``creep`` round too: a viscous
friction (the band's velocity-proportional force, beyond the fit's F_v) or a friction with a state (the band's
lag at the reversals)."""
BAND_FLOOR_RATIO = 2.0
"""The residual, in sensor floors (:attr:`~.adequacy.Adequacy.floor_ratio`), from which :data:`BAND_WORDS` make the
``creep`` round: the soft plants' smooth fits the band misled sat at 4-5 floors, while a stick-slip plant's at 1.2
names a friction with a state too (there the round costs minutes and the ``lugre`` and ``stiction`` rounds are the
ones to try)."""

__all__ = ["Round", "ROUNDS", "STATEFUL_WORD", "BAND_WORDS", "BAND_FLOOR_RATIO", "STUCK_FRICTION", "NAMED_BY", "FALLBACK",
           "named_effects", "rounds_of", "sticking", "name_sticking"]

STUCK_FRICTION = (STATEFUL_WORD + " that holds the joints at rest: dry friction that sticks, the switched "
                  "stick-slip law (the fit's stick-slip law kept, its residual within two sensor floors, the LuGre "
                  "law's fit not kept); no memoryless law of the fit holds a stuck joint, nor does a smooth "
                  "observer where the joints stick, and the observer check did not choose the stick law on this "
                  "record (friction.observer_law: judge on a record where the joints stick: alpes-dyn experiment "
                  "--stick-seconds 6, or identify --validate REC2.csv with a slow motion)")
"""The likely missing effect a refused fit's verdict names, in place of the LuGre law's presliding, where
:func:`sticking` holds (:func:`name_sticking`)."""

NAMED_BY: dict[str, str] = {"stiction": "stick-slip", "rotor": "rotor inertia", "delay": "torque delay",
                            "capstan": "tendon-sheath friction"}
"""The effects ``auto`` adds where a fit's adequacy check names them (a word of the likely missing effect)."""

Proposal = Callable[[Any, tuple[str, ...], Collection[str]], "tuple[str, ...] | None"]


def named_effects(result: Any) -> tuple[str, ...]:
    """The effects of :data:`NAMED_BY` that a flagged fit's adequacy check names among the likely missing ones.

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        A fit (anything with an ``adequacy`` verdict: ``adequate`` and ``likely_missing``).

    Returns
    -------
    tuple of str
        The named effects, in :data:`NAMED_BY`'s order; empty where the fit is adequate or has no verdict.
    """
    a = getattr(result, "adequacy", None)
    if a is None or a.adequate:
        return ()
    return tuple(e for e, word in NAMED_BY.items() if any(word in m for m in a.likely_missing))


def _compliances(result: Any) -> list[tuple[float, float]]:
    """(value, standard error) of each tendon compliance a fit found with a finite standard error."""
    return [(value, sd) for name, value, sd in zip(result.names, result.values, result.std)
            if name.startswith("tendon_compliance") and np.isfinite(sd)]


def elastic(result: Any) -> bool:
    """True when a fit found a tendon compliance above three of its standard errors (the cable seen stretching)."""
    return any(value > 3.0 * sd for value, sd in _compliances(result))


def contracting(result: Any) -> bool:
    """True when a fit found a tendon compliance below minus three of its standard errors (a cable read as
    shortening under tension: no cable does, the compliance absorbed another effect)."""
    return any(value < -3.0 * sd for value, sd in _compliances(result))


def nonlinear(result: Any) -> bool:
    """A flagged fit whose verdict names a nonlinearity (the residual's power at the excitation's harmonics): a
    constant in the output (the encoder's offset) makes no harmonics, so the offset's round is not made for it."""
    a = getattr(result, "adequacy", None)
    return a is not None and not a.adequate and any(NONLINEARITY in m for m in a.likely_missing)


def _lower_residual(new: Any, kept: Any) -> bool:
    """The new fit's residual below the kept one's, the new fit converged where the kept one did (a fit stopped by
    its iteration cap or a lost basin never replaces a converged one)."""
    return bool(new.residual_rms < kept.residual_rms and (new.converged or not kept.converged))


def _converged(new: Any, kept: Any) -> bool:
    """The new fit converged."""
    return bool(new.converged)


def _always(new: Any, kept: Any) -> bool:
    """Kept whatever it is (the first fit)."""
    return True


def _first(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...]:
    """The effects asked for (``effects``: the caller's, without ``auto``)."""
    return effects


def _staged(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
    """The effects to reach in stages where the first fit lost its basin with an effect beyond stiction and the
    rotor (the two change the model, not the parameters: the rigid fit would not be a stage towards them)."""
    lost = not result.converged and "lost basin" in str(getattr(result, "reason", ""))
    return effects if lost and any(e not in ("stiction", "rotor") for e in effects) else None


def _asked(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
    """The effects the kept fit asks for: those its verdict names, the rotor where it sees the cable stretching (the
    quasi-static cable carries the rotor's J_m S^T S to the joints, which the verdict does not tell from a wrong
    inertia); the tendon-sheath friction alone (a friction growing with the tension is also a cable stretching with
    it: with the rotor its fit was worse). The rotor replaces a kept tendon-sheath friction for the same reason:
    the two read the same tension-following motion, and carried beside the rotor the sheath friction is fitted
    towards 0 and its bound, where the later rounds' fits stop at their iteration cap (on the MuJoCo thumb the
    torque delay's round, which its observer needed, was refused so); kept only on a lower residual."""
    more = tuple(e for e in named_effects(result) if e not in attempted)
    if "rotor" not in attempted and "rotor" not in more and elastic(result):
        more += ("rotor",)
    if "capstan" in more:
        more = ("capstan",)
    if not more:
        return None
    return tuple(e for e in effects if not ("rotor" in more and e == "capstan")) + more


def _stateful(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
    """The kept effects with the LuGre law where the kept fit's verdict names a friction with a state and the law
    was not tried (the stick-slip law's sharper sign, a law without memory, taken off: the two are exclusive)."""
    a = getattr(result, "adequacy", None)
    if getattr(getattr(result, "model", None), "params", None) is None:
        return None  # a model without a parameter file (a URDF's) has no place for the law
    if "lugre" in attempted or a is None or a.adequate or not any(STATEFUL_WORD in m for m in a.likely_missing):
        return None
    return tuple(e for e in effects if e != "stiction") + ("lugre",)


def _creeps(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
    """The kept effects with the creep law where the kept fit is not to be trusted and drove a joint's F_s below
    :data:`~.creep.CREEP_FRACTION` of the file's (:func:`~.creep.collapsed`: a dry friction read as viscous), or
    holds one at the file's value after its steps ran it towards 0 (:func:`~.creep.ran_down`: the same collapse,
    hidden by the hold), or its verdict names :data:`~.creep.CREEP`, viscous friction or a friction with a state
    (:data:`BAND_WORDS`, at a residual of :data:`BAND_FLOOR_RATIO` sensor floors or more: what the creep band looks
    like where its F_s shrank less than that, on soft MuJoCo plants
    the fit kept F_s at 0.13-0.3 of the file's), and the law was not tried (the other friction laws taken off; the
    round is kept only where it lowers the residual, so a wrong trigger costs a fit's time, not the result)."""
    model = getattr(result, "model", None)
    if "creep" in attempted or result.trustworthy or getattr(model, "params", None) is None:
        return None
    a = getattr(result, "adequacy", None)
    words = (CREEP,) + (BAND_WORDS if a is not None and a.floor_ratio >= BAND_FLOOR_RATIO else ())
    named = a is not None and any(w in m for m in a.likely_missing for w in words)
    start = {p.name: p.nominal for p in parameter_catalogue(model)}
    if not (named or collapsed(result.names, result.values, start) or ran_down(result)):
        return None
    return tuple(e for e in effects if e not in ("stiction", "lugre")) + ("creep",)


def _flagged(effect: str) -> Proposal:
    """The proposal of a round made on a flagged fit that asks for nothing: ``effect`` added, once."""
    def proposal(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
        if result.trustworthy or effect in attempted or (effect == "offset" and nonlinear(result)):
            return None
        return effects + (effect,)

    proposal.__doc__ = f"``{effect}`` added to a flagged fit asking for nothing, where not yet tried."
    return proposal


def _rigid_cable(result: Any, effects: tuple[str, ...], attempted: Collection[str]) -> tuple[str, ...] | None:
    """The kept effects without the compliance, where the kept fit's is below minus three standard errors."""
    if "compliance" not in effects or not contracting(result):
        return None
    return tuple(e for e in effects if e != "compliance")


@dataclass(frozen=True)
class Round:
    """One round of ``--effects auto``: one fit, the effects it is made with, its start and the rule that keeps it.

    Attributes
    ----------
    name : str
        The round's name (the table's first column).
    stage : str
        When it is walked: ``"first"`` (the first fit, and the staged start after a lost basin), ``"auto"`` (while
        the kept fit asks for an effect or is flagged; the first ``auto`` row proposing a fit makes it), ``"cable"``
        (once, after the ``auto`` rounds).
    adds : tuple of str
        The effects the round may add (``"rigid cable"``: the one it removes).
    when : str
        When the round is made, in words.
    propose : callable
        ``propose(kept, kept_effects, attempted)``: the round's effects (a tuple of str), or None where the round
        is not made; ``kept`` the fit kept so far, ``kept_effects`` its effects, ``attempted`` the effects some
        round was made with.
    start_from : str
        Where the round's fit starts, in words (``"kept"``: the kept fit's values and trajectory).
    accept : callable
        ``accept(new, kept) -> bool``: the new fit replaces the kept one.
    """

    name: str
    stage: str
    adds: tuple[str, ...]
    when: str
    propose: Proposal
    start_from: str
    accept: Callable[[Any, Any], bool]

    def proposal(self, kept: Any, kept_effects: tuple[str, ...],
                 attempted: Collection[str] = ()) -> tuple[str, ...] | None:
        """The round's effects from the fit kept, or None where it is not made.

        Parameters
        ----------
        kept : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
            The fit kept so far.
        kept_effects : tuple of str
            Its effects.
        attempted : collection of str
            The effects some round was already made with (none is tried twice).

        Returns
        -------
        tuple of str or None
            The effects of the round's fit.
        """
        return self.propose(kept, tuple(kept_effects), attempted)

    def accepts(self, new: Any, kept: Any) -> bool:
        """Whether the round's fit ``new`` replaces ``kept``.

        Parameters
        ----------
        new : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
            The round's fit.
        kept : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
            The fit kept before it.

        Returns
        -------
        bool
            True where ``new`` is kept.
        """
        return bool(self.accept(new, kept))


_FLAGGED = "the kept fit flagged, asking for nothing"

ROUNDS: tuple[Round, ...] = (
    Round("first", "first", (), "always", _first, "the model's values", _always),
    Round("staged", "first", (), "the first fit lost its basin", _staged, "the rigid fit, then the last stage",
          _converged),
    Round("creep", "auto", ("creep",), "it drove a joint's F_s towards 0, or held one its steps ran there, or "
          "its verdict names viscous friction or a friction with a state (a dry friction read as viscous)", _creeps,
          "kept, its friction the file's", _lower_residual),
    Round("asked", "auto", tuple(NAMED_BY), "its verdict names effects, or it sees the cable stretching", _asked,
          "kept", _lower_residual),
    Round("lugre", "auto", ("lugre",), "its verdict names a friction with a state", _stateful,
          "kept, its friction the file's", _lower_residual),
    Round("stiction", "auto", ("stiction",), _FLAGGED, _flagged("stiction"), "kept", _lower_residual),
    Round("rotor", "auto", ("rotor",), _FLAGGED, _flagged("rotor"), "kept", _lower_residual),
    Round("delay", "auto", ("delay",), _FLAGGED, _flagged("delay"), "kept", _lower_residual),
    Round("offset", "auto", ("offset",), _FLAGGED + ", naming no nonlinearity", _flagged("offset"), "kept",
          _lower_residual),
    Round("rigid cable", "cable", ("compliance",), "the compliance below minus three standard errors",
          _rigid_cable, "kept", _converged),
)
"""The rounds of ``--effects auto``, in the order they are walked (the module's table)."""

FALLBACK: tuple[str, ...] = tuple(r.adds[0] for r in ROUNDS if r.when.startswith(_FLAGGED))
"""The effects tried, in order, on a flagged fit that asks for none (stick-slip, the rotor, the torque delay, the
encoder's offset); the observer's failure walks them again."""


def sticking(result: Any, effects: Collection[str], attempted: Collection[str]) -> bool:
    """Whether the walk's refused fit is a dry friction that sticks: kept with the stick-slip law (``stiction`` among
    ``effects``), its verdict naming a friction with a state (:data:`STATEFUL_WORD`) at a residual below
    :data:`BAND_FLOOR_RATIO` sensor floors (not the creep band's), and the LuGre law tried (in ``attempted``) but
    not kept. MuJoCo's stiff ``frictionloss`` at three times F_s is such a plant: the LuGre fit lost its basin, the
    stick-slip law's kept one at 1.1 floors with its residual coloured at the low intermodulation lines, not at the
    reversals (the experiment's dither keeps the joints sliding), while the joints stick on a slow validation motion
    where the file's smooth observer is off by more than the EKF's goal and the switched law's holds them
    (``benchmarks/results/realism.friction.json``, the case ``stiff_3x``).

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit kept (its ``adequacy``).
    effects : collection of str
        Its effects.
    attempted : collection of str
        The effects some round was made with (:attr:`~.effects.RoundWalker.attempted`).

    Returns
    -------
    bool
        True where all of the above hold.
    """
    a = getattr(result, "adequacy", None)
    if a is None or a.adequate or "stiction" not in effects or "lugre" in effects or "lugre" not in attempted:
        return False
    return bool(a.floor_ratio < BAND_FLOOR_RATIO and any(STATEFUL_WORD in m for m in a.likely_missing))


def name_sticking(result: Any, effects: Collection[str], attempted: Collection[str]) -> str | None:
    """Where :func:`sticking` holds: :data:`STUCK_FRICTION` in place of the verdict's friction with a state (first
    among its likely missing effects), and the note returned; None (nothing changed) otherwise. The verdict stays a
    refusal: called after the observer check was made with the stick law among its laws
    (:func:`~alpes_dyn.estimation.identification.observer_check.judge` with ``sticking``), which did not choose it
    and pass it (where it did, the fit is adequate and :func:`sticking` no longer holds).

    Parameters
    ----------
    result : ~alpes_dyn.estimation.identification.fit_result.IdentificationResult
        The fit kept (its ``adequacy`` updated in place).
    effects : collection of str
        Its effects.
    attempted : collection of str
        The effects some round was made with.

    Returns
    -------
    str or None
        One line naming the cause.
    """
    if not sticking(result, effects, attempted):
        return None
    a = result.adequacy
    a.likely_missing = [STUCK_FRICTION] + [m for m in a.likely_missing if STATEFUL_WORD not in m]
    return (f"the residual ({a.floor_ratio:.2f}x the sensor floor, coloured) is a dry friction that sticks: "
            f"{STUCK_FRICTION}")


def rounds_of(stage: str) -> tuple[Round, ...]:
    """The rows of :data:`ROUNDS` walked at ``stage`` (``"first"``, ``"auto"`` or ``"cable"``), in order.

    Parameters
    ----------
    stage : str
        The stage.

    Returns
    -------
    tuple of Round
        Its rounds.
    """
    return tuple(r for r in ROUNDS if r.stage == stage)
