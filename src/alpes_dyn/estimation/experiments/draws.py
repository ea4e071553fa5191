"""Seeded draws of a hand within its tolerances: the "true" finger (or hand) of a simulated experiment, a
robustness study's draw (:mod:`alpes_dyn.studies.sweep`), the realism benchmark's plants."""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from ...errors import InputError
from ...model.params import HandParams, Param, load_params, with_values

__all__ = ["perturbed_params"]


def perturbed_params(params: HandParams | None = None, spread: float = 0.2, seed: int = 0,
                     kinds: Sequence[str] = ("K", "m", "friction"), chains: Sequence[str] | None = None) -> HandParams:
    """``params`` with the finger's springs K_i, masses m_i (inertias I_i with them) and per-joint
    friction F_s, F_v each multiplied by an independent factor uniform in [1 - spread, 1 + spread].

    Parameters
    ----------
    params : HandParams or None, optional
        The parameters drawn around (default: the shipped file).
    spread : float, optional
        The relative half-width of the draw, in [0, 1).
    seed : int, optional
        The generator's seed.
    kinds : sequence of str, optional
        Which kinds are drawn: ``"K"``, ``"m"``, ``"friction"``.
    chains : sequence of str or str or None, optional
        Which chains are drawn, each independently (one seeded generator, in the order given): None (default) the
        shared ``[finger]`` values; finger names (``palm.finger_names``) give each of those fingers values of its
        own (``[finger.<name>]``, drawn around its current ones); ``"thumb"`` draws the thumb's flexion springs,
        masses (its base's too) and friction, and its ab/adduction friction.

    Returns
    -------
    HandParams
        A valid parameter set (the changed entries marked ``assumed`` with the draw as reason), e.g. the "true"
        finger (or hand) of a simulated identification experiment.
    """
    if not (math.isfinite(spread) and 0 <= spread < 1):
        raise InputError(f"spread: expected a fraction in [0, 1), got {spread!r}")
    for k in kinds:
        if k not in ("K", "m", "friction"):
            raise InputError(f"kinds: unknown kind {k!r} (expected K, m, friction)")
    p = params if params is not None else load_params()
    if chains is None:
        chains = ("finger",)
    elif isinstance(chains, str):
        chains = (chains,)
    for c in chains:
        if c != "finger" and c not in p.chain_names:
            raise InputError(f"chains: unknown chain {c!r} (expected one of {', '.join(p.chain_names)})")
    rng = np.random.default_rng(seed)
    reason = f"drawn: nominal times a factor uniform in [{1 - spread:g}, {1 + spread:g}] per link, seed {seed}"
    upd: dict[str, Param] = {}
    units = {"K": "N m/rad", "m": "kg", "I": "kg m^2", "F_s": "N m", "F_v": "N m s/rad", "base_mass": "kg",
             "abduction_F_s": "N m", "abduction_F_v": "N m s/rad"}

    def put(name: str, value: np.ndarray | float) -> None:
        field_ = name.rsplit(".", 1)[1]
        old = p.raw.get(name) or p.raw.get(f"finger.{field_}")
        old = old if old is not None else Param(value, units[field_], "assumed", reason, f"per-joint {field_}")
        upd[name] = dataclasses.replace(old, value=value, unit=units[field_], source="assumed", reason=reason, std=None)

    def draw(size: int) -> np.ndarray | float:
        f = rng.uniform(1 - spread, 1 + spread, size)
        return f

    for c in chains:
        ch = p.chain(c)
        n = ch.n
        sec = "thumb" if c == "thumb" else ("finger" if c == "finger" else f"finger.{c}")
        if "K" in kinds:
            put(f"{sec}.K", ch.K * draw(n))
        if "m" in kinds:
            s = draw(n)
            put(f"{sec}.m", ch.m * s)
            put(f"{sec}.I", ch.I * s)
            if c == "thumb":
                put("thumb.base_mass", p.thumb_base_mass * float(draw(1)[0]))
        if "friction" in kinds:
            Fs = ch.F_s if ch.F_s is not None else np.full(n, p.F_s)
            Fv = ch.F_v if ch.F_v is not None else np.full(n, p.F_v)
            put(f"{sec}.F_s", Fs * draw(n))
            put(f"{sec}.F_v", Fv * draw(n))
            if c == "thumb":
                Fs_a = p.F_s if p.abduction_F_s is None else p.abduction_F_s
                Fv_a = p.F_v if p.abduction_F_v is None else p.abduction_F_v
                put("thumb.abduction_F_s", Fs_a * float(draw(1)[0]))
                put("thumb.abduction_F_v", Fv_a * float(draw(1)[0]))
    return with_values(p, upd)
