"""The truth of a MuJoCo plant as a parameter file: the drawn :class:`~alpes_dyn.model.params.HandParams` with
the plant's effects (:class:`~alpes_dyn.bench.effects.PlantEffects`) written into the fields that ``identify``
writes (:func:`~alpes_dyn.estimation.identification.fit_result.identified_params`), so that an observer run on
it is judged against the whole truth, not the drawn parameters alone.

Each effect and where it goes (:func:`truth_params`):

=========================== ==================================================================================
effect                      field of the file
=========================== ==================================================================================
``tilt``                    ``environment.gravity``: the file's gravity turned as the plant's is
                            (:func:`~alpes_dyn.bench.mujoco_plant.plant_model`); not the thumb's (its gravity
                            is in its own base frame: named)
``encoder_offset`` (counts) ``encoder_offset`` of the chain's section, rad of the motor (counts times
                            2 pi / counts_per_rev, the encoder reading y = S q + offset)
``torque_delay``            ``transmission.torque_delay`` (samples)
``stiction`` (stiff)        ``friction.smooth_velocity`` = :data:`~alpes_dyn.model.extras.STICTION_VELOCITY`, the
                            stick-slip law as ``identify --effects stiction`` writes it (the file's mark of a
                            friction that sticks; the observer's ``stick`` law is asked for by name,
                            :func:`~alpes_dyn.simulation.stick.observer_friction_law`)
``tendon_stiffness`` k_t    ``transmission.tendon_compliance`` C = 1 / (k_t r_m^2), the cable's quasi-static
                            stretch; the observer takes the rotor's J_m on the tendons (:attr:`TruthFile.rotor`)
``tendon_rotor``            the rotor's J_m on the rigid tendons (:attr:`TruthFile.rotor`)
``torque_constant_error`` e the torque read is (1 + e) times the plant's: every torque-like field (units N m,
                            N m/rad, N m s/rad, kg, kg m^2: springs, masses, inertias, friction, the rotor, the
                            LuGre law's sigma0/sigma1, tau_max) times (1 + e) and the compliance divided by it
                            -- the plant's dynamics in the reading's units, exactly the plant seen through the
                            sensor (the common scale a fit cannot resolve either)
``soft_stiction``           ``friction.law = "creep"`` with ``creep_kappa`` and ``creep_rate`` of MuJoCo's
                            default constraint (:func:`~alpes_dyn.model.friction.creep_of_constraint`: the
                            inverse of the MJCF writers' map), the law as ``identify --effects creep`` writes it
=========================== ==================================================================================

What a file cannot hold is named (:attr:`TruthFile.not_held`), never dropped in silence: the cable's damping and
slack and its rotor's own dynamics (the file's tendon is the quasi-static limit), MuJoCo's stiff dry-friction
constraint itself (``stiction``'s time constant, held as the stick-slip law). MuJoCo's soft constraint is, per
joint, a viscous law saturated at F_s whose slope depends on the joint's inverse inertia (creeping at
v = (1 - d) A_ii t_c tau / 2 under a torque tau below F_s, d = 0.9 the impedance, t_c = 0.02 s, A = M^-1): no one
v_s of the smooth law is the plant's (with it the EKF on the true file of a soft plant was worse than on a file
identified with the creep law), and the creep law with MuJoCo's default parameters is.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..model.extras import STICTION_VELOCITY
from ..model.friction import creep_of_constraint
from ..model.params import HandParams, Param, load_params, with_values, write_params
from .effects import PlantEffects
from .mujoco_plant import PLANT_MODELS, plant_model

__all__ = ["TruthFile", "TORQUE_UNITS", "truth_params", "write_truth"]

TORQUE_UNITS: tuple[str, ...] = ("N m", "N m/rad", "N m s/rad", "kg", "kg m^2")
"""The units of the file's fields that scale with the torque reading's gain (module docstring)."""


@dataclasses.dataclass(frozen=True)
class TruthFile:
    """The truth of a plant as a parameter file (:func:`write_truth`).

    Attributes
    ----------
    params : HandParams
        The truth's parameters (what the file holds).
    rotor : bool
        The plant has a rotor on its tendons (the series-elastic cable's or ``tendon_rotor``): the observer's model
        takes the file's J_m (``Model.alpes(rotor_inertia=True)``, ``estimate --rotor-inertia``).
    not_held : tuple of str
        The plant's effects that the file cannot hold, each ``"<effect>: <why>"``.
    path : Path or None
        The file written (None from :func:`truth_params`).
    """

    params: HandParams
    rotor: bool
    not_held: tuple[str, ...]
    path: Path | None = None


def _scaled(p: HandParams, gain: float) -> dict[str, Param]:
    """Every torque-like entry of ``p`` (:data:`TORQUE_UNITS`) times ``gain``, the compliance divided by it."""
    out = {}
    for name, prm in p.raw.items():
        if prm.unit in TORQUE_UNITS or name == "transmission.tendon_compliance":
            f = gain if prm.unit in TORQUE_UNITS else 1.0 / gain
            std = None if prm.std is None else np.abs(f) * np.asarray(prm.std, dtype=float)
            value = f * np.asarray(prm.value, dtype=float)
            out[name] = dataclasses.replace(prm, value=float(value) if value.ndim == 0 else value, std=std)
    return out


def _held(p: HandParams, e: PlantEffects, model: str, chain: str | None) -> tuple[dict[str, Param], list[str]]:
    """The entries of the rig's side (tilt, encoder zero, delay, compliance) and the effects not held."""
    why = "the plant's truth (bench.truth)"
    upd: dict[str, Param] = {}
    named = []
    thumb = model == "thumb"
    if e.tilt:
        if thumb:
            named.append(f"tilt ({e.tilt:.6g} rad): the thumb's gravity is in its own base frame, not the file's")
        else:
            upd["environment.gravity"] = Param(plant_model(model, p, e, chain).gravity, "m/s^2", "assumed", why,
                                               "gravity in the hand's base frame, turned by the palm's tilt")
    if e.encoder_offset:
        cpr = float(plant_model(model, p, None, chain).transmission.counts_per_rev)
        sec = "thumb" if thumb else ("finger" if chain is None else f"finger.{chain}")
        for name in (f"{sec}.encoder_offset",) + (("thumb.abduction_encoder_offset",) if thumb else ()):
            upd[name] = Param(e.encoder_offset * 2 * math.pi / cpr, "rad", "assumed", why,
                              "the zero of a motor's encoder, rad of the motor: y = S q + offset")
    if e.torque_delay:
        upd["transmission.torque_delay"] = Param(int(e.torque_delay), "samples", "assumed", why,
                                                 "the recorded motor torque's lag behind the motor's, whole samples")
    if e.tendon_stiffness is not None:
        upd["transmission.tendon_compliance"] = Param(1.0 / (e.tendon_stiffness * p.r_m ** 2), "rad/(N m)",
                                                      "assumed", why, "the cable's stretch 1 / (k_t r_m^2)")
        named.append(f"tendon_stiffness ({e.tendon_stiffness:.6g} N/m): the rotor on the cable's own mode; the file "
                     "holds its quasi-static stretch")
        if e.tendon_damping:
            named.append(f"tendon_damping ({e.tendon_damping:.6g} N s/m): the file's tendon is quasi-static")
        if e.tendon_dead_band:
            named.append(f"tendon_dead_band ({e.tendon_dead_band:.6g} m): the cable's slack")
    if e.stiction is not None:  # as identify writes its stick-slip law (--effects stiction)
        upd["friction.smooth_velocity"] = Param(STICTION_VELOCITY, "rad/s", "assumed", why,
                                                "the smooth sign's velocity scale of the stick-slip law")
        named.append(f"stiction ({e.stiction:.6g} s): MuJoCo's stiff dry-friction constraint, held as the stick-slip "
                     f"law's v_s = {STICTION_VELOCITY:g} rad/s")
    if e.soft_stiction:  # MuJoCo's default constraint, as identify writes its creep law (--effects creep)
        law = creep_of_constraint()
        upd["friction.law"] = Param("creep", "-", "assumed", why, "the joints' friction law: MuJoCo's soft dry friction")
        upd["friction.creep_kappa"] = Param(law.kappa, "-", "assumed", why, "the creep band's added inertia, in "
                                            "units of the joint's own: MuJoCo's default solimpfriction d / (1 - d)")
        upd["friction.creep_rate"] = Param(law.rate, "1/s", "assumed", why, "the creep band's rate: MuJoCo's default "
                                           "solreffriction and solimpfriction, 2 / (d_max t_c)")
    return upd, named


def truth_params(true: HandParams | str | Path | None, effects: PlantEffects | None = None,
                 model: str = "finger3", chain: str | None = None) -> TruthFile:
    """The truth of a MuJoCo plant as parameters (module docstring): ``true`` with the plant's ``effects`` in the
    file's fields.

    Parameters
    ----------
    true : HandParams or str or Path or None
        The plant's parameters (what :func:`~alpes_dyn.control.plants.mujoco_recording` was given; a path, or None
        for the shipped file).
    effects : PlantEffects or None, optional
        The plant's effects (default none).
    model : str, optional
        The plant's model, one of :data:`~alpes_dyn.bench.mujoco_plant.PLANT_MODELS`.
    chain : str or None, optional
        The hand's chain the plant is (a finger's name), or None.

    Returns
    -------
    TruthFile
        The parameters, whether the observer takes the rotor, the effects not held (``path`` None).

    Raises
    ------
    InputError
        An unknown ``model``, or ``effects`` out of range (:meth:`PlantEffects.check`).
    """
    if model not in PLANT_MODELS:
        raise InputError(f"model: expected one of {', '.join(PLANT_MODELS)}, got {model!r:.40}")
    e = (effects or PlantEffects()).check()
    p = true if isinstance(true, HandParams) else load_params(true)
    upd, named = _held(p, e, model, chain)
    p = with_values(p, upd) if upd else p
    if e.torque_constant_error:
        p = with_values(p, _scaled(p, 1.0 + e.torque_constant_error))
    return TruthFile(p, e.tendon_stiffness is not None or bool(e.tendon_rotor), tuple(named))


def write_truth(true: HandParams | str | Path | None, effects: PlantEffects | None, path: str | Path,
                model: str = "finger3", chain: str | None = None) -> TruthFile:
    """Write the truth of a MuJoCo plant as a parameter file (:func:`truth_params`, the same arguments; ``path``
    the TOML file, written atomically).

    Parameters
    ----------
    true : HandParams or str or Path or None
        The plant's parameters.
    effects : PlantEffects or None
        The plant's effects.
    path : str or Path
        The file to write.
    model : str, optional
        The plant's model.
    chain : str or None, optional
        The hand's chain the plant is, or None.

    Returns
    -------
    TruthFile
        With ``path`` the file written.
    """
    t = truth_params(true, effects, model, chain)
    header = "The truth of a MuJoCo plant (alpes_dyn.bench.truth)" + "".join(
        f"\nnot held: {n}" for n in t.not_held)
    return dataclasses.replace(t, path=write_params(t.params, path, header=header))
