"""The physical range of every fitted parameter, and what a fit reports where the data do not support one (issue 35).

A fit's value is only a result where it is physical and the data determine it. The ranges:

==================== ============== ===================================================================
kind                 range          how the fit keeps it
==================== ============== ===================================================================
K, m (with I), F_s,  (0, inf)       fitted as log theta (:mod:`~alpes_dyn.estimation.identification.identification`):
F_v, J_m, input_gain                every iterate is positive; a value that ran off by more than
                                    :data:`RUNAWAY` times its start is at the bound (0 or inf) in effect
tendon_compliance    [0, inf)       fitted as it is (nominal 0): a cable does not shorten under tension,
                                    so a value below 0 has the bound active -- the bounded fit's optimum
                                    is the fit with the compliance held at 0 (the active set)
capstan              [0, inf)       fitted as it is (nominal 0): a sheath's friction does not push the cable
                                    (mu theta >= 0); below 0 not identified, held at the model's value
sigma0 (LuGre)       (0, inf),      fitted as log theta; the bristles' stiffness physical within
                     within         :data:`SIGMA0_RANGE` times the file's (its start): presliding
                     SIGMA0_RANGE   displacements F_s / sigma0 of 0.1 to 10 mrad around the default 1 mrad
                                    (:data:`~alpes_dyn.model.friction.PRESLIDING`); outside, not identified
sigma1 (LuGre)       [0, inf)       fitted as log theta (every iterate > 0); 0 in effect where it runs off
creep_kappa,         (0, inf),      fitted as log theta; the creep law's band (its added inertia, its rate)
creep_rate           within         physical within :data:`CREEP_RANGE` times the file's (its start, by
                     CREEP_RANGE    default MuJoCo's constraint); outside, not identified
encoder_offset, tilt (-inf, inf)    of the rig and its sensors, either sign: never bounded
==================== ============== ===================================================================

A parameter is **not identified** (:func:`unsupported`) where its value is outside that range or pinned at a bound,
or where its 95 % interval (value +- :data:`Z_INTERVAL` standard errors) reaches past 0 (the data cannot tell it from
no such effect). :func:`~alpes_dyn.estimation.identification.identification.identify` then fits again with it held (at
its bound 0 where it crossed it, else at the model's value: the file's prior), warm-started from the first fit, so that
the values written are those of a fit whose every parameter is identified; the result names each one not identified
and the effect the data do not support
(:attr:`~alpes_dyn.estimation.identification.fit_result.IdentificationResult.not_identified`), and the parameter file
never receives its value. A parameter the recording does not see at all (its standard error
infinite: ``tilt_x`` at a level palm) is left as :func:`identify` leaves it (at its start, never written).
"""

from __future__ import annotations

import math
from typing import Sequence

__all__ = ["Z_INTERVAL", "RUNAWAY", "SIGMA0_RANGE", "CREEP_RANGE", "RANGES", "LOWER_BOUND", "EFFECT_OF", "physical_range", "unsupported", "held_value",
           "describe"]

Z_INTERVAL = 1.96
"""Standard errors on each side of a value: its 95 % interval (normal errors)."""
RUNAWAY = 1e3
"""A log-fitted parameter that moved by more than this factor from its start (either way) is at its bound in effect
(a mass run off to 0 in a wrong basin: 1e-6 times its start; the +-20 % draws stay within 1.5 times)."""
SIGMA0_RANGE = (0.1, 10.0)
"""The LuGre bristles' stiffness sigma0 a fit may find, as factors of its start (the file's): a joint's presliding
displacement F_s / sigma0 within 0.1 to 10 times the file's (0.1 to 10 mrad from the default 1 mrad: a bearing's or a
bush's micrometres to a tendon's slack); the fit's RK4 substeps are set for the upper end's presliding mode."""
CREEP_RANGE = (0.1, 10.0)
"""The creep law's band inertia and rate a fit may find, as factors of its start (the file's; MuJoCo's default
constraint unless the file says otherwise): a band edge v_c = F_s / (a b) within 0.01 to 100 times the start's."""
RANGES: dict[str, tuple[float, float]] = {"sigma0": SIGMA0_RANGE, "creep_kappa": CREEP_RANGE,
                                          "creep_rate": CREEP_RANGE}
"""The kinds fitted within a range of factors of their start."""
LOWER_BOUND: dict[str, float] = {"K": 0.0, "m": 0.0, "F_s": 0.0, "F_v": 0.0, "J_m": 0.0, "input_gain": 0.0,
                                 "tendon_compliance": 0.0, "capstan": 0.0, "sigma0": 0.0, "sigma1": 0.0,
                                 "creep_kappa": 0.0, "creep_rate": 0.0}
"""The physical lower bound of each bounded kind (the unbounded ones, encoder offsets and tilts, are not listed)."""
EFFECT_OF: dict[str, str] = {"K": "a return spring", "m": "a link's mass", "F_s": "dry friction",
                             "F_v": "viscous friction", "J_m": "the rotor inertia", "input_gain": "a torque-constant error",
                             "tendon_compliance": "an elastic tendon", "capstan": "tendon-sheath friction",
                             "sigma0": "the friction's presliding stiffness (the LuGre bristles)",
                             "sigma1": "the friction's presliding damping (the LuGre bristles)",
                             "creep_kappa": "the dry friction's band inertia (the creep law)",
                             "creep_rate": "the dry friction's band rate (the creep law)"}
"""The effect a parameter of each kind stands for, as the verdict names it when the data do not support it."""


ADDITIVE_BOUNDED: tuple[str, ...] = ("tendon_compliance", "capstan")
"""The bounded kinds fitted as they are (nominal 0), their bound 0 closed: no runaway rule (a log-fit's)."""


def physical_range(kind: str) -> tuple[float, float, bool]:
    """(lower, upper, lower bound closed) of a parameter kind (:data:`~alpes_dyn.symbolic.parametric.KINDS`): open
    (0, inf) for the log-fitted kinds, [0, inf) for the tendon compliance, the whole line for the rig's own.

    Parameters
    ----------
    kind : str
        The parameter's kind, one of :data:`~alpes_dyn.symbolic.parametric.KINDS`.

    Returns
    -------
    tuple[float, float, bool]
        The lower and upper bounds, in the fit's units, and whether the lower one is closed.
    """
    if kind not in LOWER_BOUND:
        return -math.inf, math.inf, False
    return LOWER_BOUND[kind], math.inf, kind in ADDITIVE_BOUNDED


def unsupported(names: Sequence[str], kinds: Sequence[str], values: Sequence[float], std: Sequence[float],
                initial: Sequence[float], units: Sequence[str], held: bool = True) -> dict[str, str]:
    """The fitted parameters the data do not support, name -> why (one clause with the value +- its standard error
    and the effect, e.g. ``"-0.054 +- 0.032 rad/(N m): below its physical bound 0 (held there); the data do not
    support an elastic tendon"``). The rules: the module docstring.

    Parameters
    ----------
    names : Sequence[str]
        The p parameters' names.
    kinds : Sequence[str]
        Their kinds (:data:`~alpes_dyn.symbolic.parametric.KINDS`).
    values : Sequence[float]
        The fitted values (p,), in the fit's units.
    std : Sequence[float]
        Their standard errors (p,), in the fit's units (not finite: not seen, skipped).
    initial : Sequence[float]
        The fit's starts (p,), in the fit's units.
    units : Sequence[str]
        Each parameter's unit, as the clause prints it.
    held : bool, optional
        The parameters are held in a fit again (default True; the clause says where); False: no fit again is made
        (a fit not to be trusted), and the clause says so.

    Returns
    -------
    dict[str, str]
        Name -> why, for the parameters not supported (empty where every one is).
    """
    out: dict[str, str] = {}
    for name, kind, v, sd, v0, unit in zip(names, kinds, values, std, initial, units):
        if kind not in LOWER_BOUND or not math.isfinite(sd):
            continue  # the rig's own (either sign), or not seen at all (left at its start by identify)
        lo = LOWER_BOUND[kind]
        what = f"{v:.3g} +- {sd:.2g} {unit}"
        effect = f"the data do not support {EFFECT_OF[kind]}"
        there, start = ("held there", "held at the start") if held else ("not fitted again", "not fitted again")
        if v < lo:
            out[name] = f"{what}: below its physical bound {lo:g} ({there}); {effect}"
        elif kind not in ADDITIVE_BOUNDED and v0 > 0 and not (1.0 / RUNAWAY <= v / v0 <= RUNAWAY):
            out[name] = f"{what}: ran off to its bound ({v / v0:.2g} times its start; {start}); {effect}"
        elif kind in RANGES and v0 > 0 and not (RANGES[kind][0] <= v / v0 <= RANGES[kind][1]):
            lo_f, hi_f = RANGES[kind]
            out[name] = (f"{what}: {v / v0:.2g} times its start, outside its physical range {lo_f:g}-"
                         f"{hi_f:g} times ({start}); {effect}")
        elif v - Z_INTERVAL * sd <= lo:
            out[name] = f"{what}: its 95 % interval reaches past {lo:g} ({start}); {effect}"
    return out


def held_value(kind: str, value: float, start: float) -> float:
    """The value a parameter not identified is held at in the fit again: its bound where the fit crossed it, else
    its start (the model's value, the file's prior).

    Parameters
    ----------
    kind : str
        The parameter's kind (:data:`~alpes_dyn.symbolic.parametric.KINDS`).
    value : float
        Its fitted value, in the fit's units.
    start : float
        Its start, in the fit's units.

    Returns
    -------
    float
        The value it is held at.
    """
    lo = LOWER_BOUND.get(kind, -math.inf)
    return lo if value < lo else start


def describe(not_identified: dict[str, str]) -> str:
    """One clause for a verdict: ``"not identified: NAME (WHY); ..."`` (empty where every parameter is).

    Parameters
    ----------
    not_identified : dict[str, str]
        Name -> why (:func:`unsupported`).

    Returns
    -------
    str
        The clause.
    """
    if not not_identified:
        return ""
    return "not identified: " + "; ".join(f"{n} ({why})" for n, why in not_identified.items())
