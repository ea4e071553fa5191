"""The realism study (issue 16): identification and the EKF on MuJoCo plants with the effects of a real hand.

A plant we did not write -- the finger (or a chain of the hand) exported to MuJoCo
(:mod:`alpes_dyn.control.plants`), drawn +-20 % per link, with one effect of a real hand or all of them
(:func:`cases`: stick-slip, a series-elastic cable with its rotor, the rotor on the rigid tendon, the palm
tilted, the torque constant and the encoder's zero off, the cable's slack at the motor shaft, the torque read a
sample late) -- records the identification experiment; two fits of
it (the rigid smooth-friction model and ``alpes-dyn identify``'s default ``--effects auto``), and the EKF on the
extended fit's file and on the true file, on a fresh run of the plant: :func:`realism_case` gives one such row.
``benchmarks/realism.py`` prints them as a table; the gallery's "The hand on MuJoCo" runs the hand's five
chains. :func:`realism_row` is the same row as a function of the seed, for :func:`~alpes_dyn.studies.sweep.sweep`
(``benchmarks/realism.py --workers 2`` runs each case's seeds so), and :func:`realism_draw` flattens it to numbers;
:func:`summarise` gives a case's distribution over seeds (median, worst, silent misses, refusals).
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..bench.effects import (DELAY_SAMPLES, KT_ERROR, OFFSET_COUNTS, SLACK_DEG, TILT_DEG, ZETA,  # noqa: F401 (kept)
                             PlantEffects, cable_damping, cable_slack, real_hand_effects)
from ..control.plants import mujoco_recording, plant_model
from ..errors import InputError
from ..estimation.experiments.adapt import Adaptation, adaptation_of, candidate_designs, first_in_range
from ..estimation.experiments.design import ExperimentDesign
from ..estimation.experiments.turned import rig_design  # noqa: F401 (the documented design in a rig; moved down)
from ..estimation.experiments.draws import perturbed_params
from ..estimation.identification.effects import alpes_models, fit_effects, parse_effects
from ..estimation.experiments.experiment import experiment_torque, held_out_rows, orientation_segments
from ..estimation.identification.identification import THUMB_PARAMETERS, identify
from ..estimation.observers.replay import estimate_recording
from ..model.mjcf import HANGING_TILT, STICTION_TIMECONST
from ..model.params import load_params, write_params
from ..model.robot import Model
from ..symbolic.parametric import parameter_catalogue

__all__ = ["CASE_NAMES", "RIGS", "ADAPT", "Plant", "FINGER3", "hand_plant", "tendon_stiffness", "cases", "verdict",
           "plant_experiment", "realism_case", "fit_row", "on_rig", "rig_of", "ekf_run", "ekf_rmse", "torque_of", "realism_row", "realism_draw", "rig_design", "errors", "parse_seeds", "summarise",
           "EKF_GOAL_DEG", "MASS_GOAL_PCT", "SPRING_GOAL_PCT", "FIT_GOAL_S"]

KINDS = ("K", "m", "F_s", "F_v")
"""The kinds of parameter whose worst errors a row gives."""

MODEL = "finger3"
STRETCH = 0.03
"""The cable's stretch under the experiment's mean tension, as a fraction of the tendon's travel (:func:`tendon_stiffness`)."""
FRESH_FREQUENCIES = (0.4, 0.9, 1.7, 2.9, 4.3, 6.1, 8.9, 12.7)
"""Hz: the lines of the EKF's validation run (:func:`fresh_run`), none of the experiment's."""
FIT_EFFECTS = "auto"
"""The extended fit's effects: ``alpes-dyn identify``'s default ``--effects``."""


RIGS = {"level": 0.0, "hanging": HANGING_TILT}
"""The rig's orientation (rad about the joints' axes from the file's palm-up gravity, :func:`tilted_gravity`)."""

ADAPT = ("auto", "level", "hanging", "both", "none")
"""How :func:`plant_experiment` adapts the experiment to the plant (``auto``: as ``alpes-dyn experiment --rig auto``)."""

CASE_NAMES = ("none", "stiction", "tendon", "rotor", "tilt", "kt", "offset", "slack", "delay", "all")


def tendon_stiffness(design: ExperimentDesign) -> tuple[float, float, dict]:
    """k_t (N/m) and c_t (N s/m) for the tendon case, from the nominal finger's experiment on a rigid MuJoCo plant:
    under the experiment's mean tension mean(tau_m) / r_m the cable stretches by STRETCH times the tendon's travel
    from the springs' rest (q = 0) to the mean configuration, r mean(sum q). c_t gives the rotor-on-cable mode
    (J_m on r_m^2 k_t) the damping ratio ZETA.

    Parameters
    ----------
    design : ExperimentDesign
        The experiment's design.

    Returns
    -------
    k_t : float
        The cable's stiffness, N/m.
    c_t : float
        Its damping, N s/m.
    info : dict
        The tension, travel and rotor mode behind them (N, m, Hz).
    """
    p = load_params()
    t, u, x0 = experiment_torque(MODEL, p, design)
    rec = mujoco_recording(MODEL, p, u, design.dt, encoder_noise_counts=0.0, torque_noise=0.0)
    travel = p.r * float(np.mean(rec.true_q.sum(axis=1)))
    tension = float(np.mean(u)) / p.r_m
    k_t = tension / (STRETCH * travel)
    c_t = cable_damping(k_t)
    info = {"mean_tension_N": tension, "tension_swing_N": float(np.ptp(u)) / p.r_m, "tendon_travel_m": travel,
            "swing_travel_m": p.r * float(np.ptp(rec.true_q.sum(axis=1))), "k_t_N_per_m": k_t,
            "c_t_N_s_per_m": c_t, "rotor_mode_Hz": math.sqrt(k_t * p.r_m**2 / p.J_m) / (2 * math.pi)}
    return k_t, c_t, info


def cases(k_t: float, c_t: float, rig_tilt: float = 0.0) -> dict[str, PlantEffects]:
    """Each case's plant effects; ``rig_tilt`` (rad): the rig's orientation (:func:`tilted_gravity`), under every
    plant (the tilt cases' error on top of it). ``slack``: the elastic tendon with :data:`SLACK_DEG` of backlash at
    the motor shaft; ``delay``: the torque :data:`DELAY_SAMPLES` late; ``all``: every effect, these two included.

    Parameters
    ----------
    k_t : float
        The tendon case's cable stiffness, N/m.
    c_t : float
        Its damping, N s/m.
    rig_tilt : float, optional
        The rig's orientation, rad (default 0).

    Returns
    -------
    dict of str to PlantEffects
        Case (:data:`CASE_NAMES`) -> its effects.
    """
    slack = cable_slack()  # m of cable
    one = {
        "none": PlantEffects(),
        "stiction": PlantEffects(stiction=STICTION_TIMECONST),
        "tendon": PlantEffects(tendon_stiffness=k_t, tendon_damping=c_t),
        "rotor": PlantEffects(tendon_rotor=True),
        "tilt": PlantEffects(tilt=math.radians(TILT_DEG)),
        "kt": PlantEffects(torque_constant_error=KT_ERROR),
        "offset": PlantEffects(encoder_offset=OFFSET_COUNTS),
        "slack": PlantEffects(tendon_stiffness=k_t, tendon_damping=c_t, tendon_dead_band=slack),
        "delay": PlantEffects(torque_delay=DELAY_SAMPLES),
    }
    # all: every effect; the elastic tendon carries the rotor (tendon_rotor is its rigid limit)
    one["all"] = real_hand_effects(k_t, c_t)
    if rig_tilt:
        one = {c: dataclasses.replace(e, tilt=rig_tilt + e.tilt) for c, e in one.items()}
    return one


def verdict(res) -> str:
    """The fit's own word on itself (:mod:`alpes_dyn.estimation.identification.adequacy`): adequate, or why not (the stop reason,
    the failed checks, the likely missing effect).

    Parameters
    ----------
    res : IdentificationResult
        The fit.

    Returns
    -------
    str
        ``"adequate"`` or ``"FLAGGED: ..."``.
    """
    if res.trustworthy:
        return "adequate"
    why = [] if res.converged else [f"not converged ({res.reason})"]
    if res.adequacy is not None and not res.adequacy.adequate:
        obs = [r for r in res.adequacy.reasons if r.startswith("the EKF")]
        why.append("inadequate" + (" (the observer: " + obs[0][len("the EKF on the identified file "):] + ")"
                                   if obs else ""))
        if res.adequacy.likely_missing:
            why.append("likely " + ", ".join(res.adequacy.likely_missing[:2]))
    return "FLAGGED: " + "; ".join(why)


@dataclasses.dataclass(frozen=True)
class Plant:
    """What is identified: ``label`` (the table's), the Alpes ``model`` (finger3 or thumb) and the hand's ``chain``
    (None: the shared ``[finger]`` values of the default finger3 run), and the parameters the fits start from and
    select (``base``: None for a finger's default K, m and friction; :data:`~alpes_dyn.estimation.identification.identification.THUMB_PARAMETERS` for the
    thumb)."""

    label: str
    model: str = MODEL
    chain: str | None = None
    base: str | None = None

    def true_params(self, seed: int):
        """The plant's parameters: finger3 drawn +-20 % (default), or the whole hand, every chain drawn.

        Parameters
        ----------
        seed : int
            The draw's seed.

        Returns
        -------
        HandParams
        """
        if self.chain is None and self.model == MODEL:
            return perturbed_params(spread=0.2, seed=seed)
        nominal = load_params()
        return perturbed_params(nominal, spread=0.2, seed=seed, chains=nominal.chain_names)

    def alpes(self, **kwargs) -> Model:
        """The plant's library model, friction on.

        Parameters
        ----------
        **kwargs
            Passed to :meth:`Model.alpes <alpes_dyn.Model.alpes>` (``params``, ``rotor_inertia``...).

        Returns
        -------
        Model
        """
        return Model.alpes(self.model, friction=True, chain=self.chain, **kwargs)


FINGER3 = Plant("finger3")


def hand_plant(chain: str) -> Plant:
    """The :class:`Plant` of one of the hand's chains (``thumb`` or a finger's name), as ``identify`` fits it.

    Parameters
    ----------
    chain : str
        ``"thumb"`` or a finger's name.

    Returns
    -------
    Plant

    Raises
    ------
    InputError
        An unknown chain.
    """
    known = load_params().chain_names
    if chain not in known:
        raise InputError(f"chain: unknown chain {chain!r} (expected one of {', '.join(known)})")
    if chain == "thumb":
        return Plant("thumb", "thumb", None, THUMB_PARAMETERS)
    return Plant(chain, MODEL, chain)


def ekf_run(rec, params_path: str, fitted: dict | None, transient: float = 1.0, rotor: bool = False,
            plant: Plant = FINGER3, rig: np.ndarray | None = None, torque_delay: int = 0, stops: bool = False,
            friction_law: str | None = None):
    """The EKF on ``params_path`` run on a recording's encoder and torque
    (:func:`~alpes_dyn.estimation.observers.replay.estimate_recording`, as ``alpes-dyn estimate --data``: friction on,
    the tendon's stretch of the file taken off, and the rig's encoder offset and palm tilt as ``fitted``); its
    metrics after ``transient`` s.

    Parameters
    ----------
    rec : Recording
        The recording (its encoder and torque).
    params_path : str
        The parameter file the EKF runs on.
    fitted : dict or None
        The fit's values (the rig's encoder offset ``encoder_offset_<motor>``, rad, and palm tilt ``tilt_x``,
        ``tilt_y``, rad); None: the file's own rig side (its gravity, encoder zero and torque delay, as
        ``estimate --data`` reads them; ``rig`` and ``torque_delay`` unused), e.g. a plant's truth written by
        :func:`~alpes_dyn.bench.truth.write_truth`.
    transient : float, optional
        The metrics are taken after it, s (default 1).
    rotor : bool, optional
        The model with the file's rotor inertia J_m (default False).
    plant : Plant, optional
        The plant identified (default :data:`FINGER3`).
    rig : numpy.ndarray, shape (3,), or None, optional
        The gravity of the rig's orientation, m/s^2, if not the file's (the tilt on top of it).
    torque_delay : int, optional
        The torque's delay, samples, as fitted (default 0).
    stops : bool, optional
        The joints' end stops in the observer's model, as ``estimate --stops`` (default False).
    friction_law : str or None, optional
        The observer's friction law (default :func:`~alpes_dyn.estimation.observers.replay.estimate_recording`'s).

    Returns
    -------
    RecordingEstimate
        The :class:`~alpes_dyn.estimation.observers.replay.RecordingEstimate`.
    """
    if fitted is None:
        return estimate_recording(rec, plant.alpes(rotor_inertia=rotor, params=params_path), "ekf",
                                  transient=transient, force=True, stops=stops, friction_law=friction_law)
    # the rig's gravity, or the shipped file's: the fitted tilt is turned on below (the file's gravity holds it too)
    obs = on_rig(plant.alpes(rotor_inertia=rotor, params=params_path),
                 rig if rig is not None else load_params().gravity)
    off = [fitted.get(f"encoder_offset_{mo}", 0.0) for mo in obs.transmission.motor_names]
    tilt = (fitted.get("tilt_x", 0.0), fitted.get("tilt_y", 0.0))
    return estimate_recording(rec, obs, "ekf", encoder_offset=off, tilt=tilt, transient=transient,
                              torque_delay=torque_delay, force=True, stops=stops,  # a flagged fit judged too
                              friction_law=friction_law)


def ekf_rmse(rec, params_path: str, fitted: dict, transient: float = 1.0, rotor: bool = False,
             plant: Plant = FINGER3, rig: np.ndarray | None = None, torque_delay: int = 0) -> np.ndarray:
    """RMSE (rad, per joint) after ``transient`` s of :func:`ekf_run` (the same arguments).

    Parameters
    ----------
    rec : Recording
        The recording (its encoder and torque).
    params_path : str
        The parameter file the EKF runs on.
    fitted : dict or None
        The fit's values (the rig's encoder offset ``encoder_offset_<motor>``, rad, and palm tilt ``tilt_x``,
        ``tilt_y``, rad); None: the file's own rig side (its gravity, encoder zero and torque delay, as
        ``estimate --data`` reads them; ``rig`` and ``torque_delay`` unused), e.g. a plant's truth written by
        :func:`~alpes_dyn.bench.truth.write_truth`.
    transient : float, optional
        The metrics are taken after it, s (default 1).
    rotor : bool, optional
        The model with the file's rotor inertia J_m (default False).
    plant : Plant, optional
        The plant identified (default :data:`FINGER3`).
    rig : numpy.ndarray, shape (3,), or None, optional
        The gravity of the rig's orientation, m/s^2, if not the file's (the tilt on top of it).
    torque_delay : int, optional
        The torque's delay, samples, as fitted (default 0).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The RMSE per joint, rad.
    """
    return ekf_run(rec, params_path, fitted, transient, rotor, plant, rig, torque_delay).rmse


_TORQUES: dict = {}


def torque_of(seed: int, p, design: ExperimentDesign, gravity: np.ndarray, plant: Plant = FINGER3):
    """experiment_torque for a seed's finger (memoised: the cases of one seed share it, but for the tilt's trim).

    Parameters
    ----------
    seed : int
        The draw's seed.
    p : HandParams
        The true parameters.
    design : ExperimentDesign
        The experiment's design.
    gravity : numpy.ndarray, shape (3,) or (k, 3)
        The gravity the true finger feels, m/s^2.
    plant : Plant, optional
        The plant (default :data:`FINGER3`).

    Returns
    -------
    tuple
        (t, u, x0), :func:`~alpes_dyn.estimation.experiments.experiment.experiment_torque`'s.
    """
    key = (plant, seed, design, np.round(np.asarray(gravity, dtype=float), 12).tobytes())
    if key not in _TORQUES:
        _TORQUES[key] = experiment_torque(plant.model, p, design, chain=plant.chain, true_gravity=gravity)
    return _TORQUES[key]


def fresh_run(p, effects: PlantEffects, seed: int, design: ExperimentDesign, plant: Plant = FINGER3):
    """A validation run of the plant: the experiment's design on other lines (:data:`FRESH_FREQUENCIES`: a torque
    the fit never saw, in the joint range by the same design rule), from the plant's rest."""
    fresh = dataclasses.replace(design, frequencies=FRESH_FREQUENCIES, dither=0.0,  # in use: no dither, stick phases
                                orientations=design.orientations[:1],  # and palm up (the first orientation)
                                stick_seconds=0.0)  # no stiction ramp
    _, u, x0 = torque_of(seed, p, fresh, plant_model(plant.model, p, effects, plant.chain).gravity, plant)
    return mujoco_recording(plant.model, p, u, fresh.dt, effects=effects, q0=x0[: x0.size // 2], seed=seed + 1000,
                            chain=plant.chain)


def on_rig(model, rig: np.ndarray | None):
    """``model`` in the rig's orientation (gravity ``rig``, m/s^2), or as it is (None: the file's).

    Parameters
    ----------
    model : Model
        The model.
    rig : numpy.ndarray, shape (3,), or None
        The rig's gravity, m/s^2.

    Returns
    -------
    Model
    """
    return model if rig is None else model.copy(gravity=rig)


def rig_of(design: ExperimentDesign) -> np.ndarray | None:
    """The rig's gravity (the design's orientation) where it is not the parameter file's, else None.

    Parameters
    ----------
    design : ExperimentDesign
        The experiment's design.

    Returns
    -------
    numpy.ndarray, shape (3,), or None
        m/s^2.
    """
    g = np.asarray(design.orientations[0], dtype=float)
    return None if np.array_equal(g, load_params().gravity) else g


def errors(values: dict[str, float], truth: dict[str, float]) -> tuple[dict, dict, float]:
    """The worst error (%) of each of :data:`KINDS` over the fitted ``values`` whose ``truth`` is known and not 0,
    plain and up to the common scale c = exp(mean log(value / truth)) over K and m (the torque constant scales
    every parameter together: the encoder cannot see it); and c.

    Parameters
    ----------
    values : dict of str to float
        The fitted values.
    truth : dict of str to float
        The true values.

    Returns
    -------
    worst : dict
        Kind -> the worst error, %.
    worst_common : dict
        Kind -> the worst error up to the common scale, %.
    c : float
        The common scale.
    """
    kinds = {nm: kind for kind in KINDS for nm in values if nm.startswith(kind + "_") and truth.get(nm, 0.0) != 0.0}
    km = [values[nm] / truth[nm] for nm, kind in kinds.items() if kind in ("K", "m")]
    c = float(np.exp(np.mean(np.log(km))))
    worst = {kind: 0.0 for kind in KINDS}
    worst_c = dict(worst)
    for nm, kind in kinds.items():
        worst[kind] = max(worst[kind], abs(100 * (values[nm] / truth[nm] - 1)))
        worst_c[kind] = max(worst_c[kind], abs(100 * (values[nm] / (c * truth[nm]) - 1)))
    return worst, worst_c, c


def fit_row(fit: Any, truth: dict[str, float], effects: list[str]) -> dict[str, Any]:
    """A fit's part of a row: its worst errors (plain and up to the common scale), values, residual, verdict.

    Parameters
    ----------
    fit : IdentificationResult
        The fit.
    truth : dict of str to float
        The true values.
    effects : list of str
        The effects the fit modelled.

    Returns
    -------
    dict
    """
    values = dict(zip(fit.names, fit.values.tolist()))
    worst, worst_c, c = errors(values, truth)
    return {"worst_error_pct": worst, "worst_error_common_scale_pct": worst_c, "common_scale": c, "values": values,
            "residual_counts": fit.residual_rms, "converged": bool(fit.converged), "iterations": fit.iterations,
            "fit_seconds": fit.seconds, "compile_seconds": fit.compile_seconds, "verdict": verdict(fit),
            "flagged": not fit.trustworthy, "stop_reason": fit.reason, "effects": effects,
            "adequacy": fit.adequacy.to_dict() if fit.adequacy is not None else None}


def _rig_tilt(design: ExperimentDesign) -> float:
    """rad: the design's (first) orientation as a tilt (:func:`~alpes_dyn.model.mjcf.tilted_gravity`) of the file's
    gravity."""
    return _orientation_tilts(design)[0]


def _orientation_tilts(design: ExperimentDesign) -> list[float]:
    """rad: each of the design's orientations as a tilt (:func:`~alpes_dyn.model.mjcf.tilted_gravity`) of the file's
    gravity."""
    g0 = np.asarray(load_params().gravity, dtype=float)
    return [math.atan2(g0[2] * g[0] - g0[0] * g[2], g0[0] * g[0] + g0[2] * g[2])
            for g in np.asarray(design.orientations, dtype=float)]


def plant_experiment(effects: PlantEffects, seed: int, design: ExperimentDesign, true, plant: Plant = FINGER3,
                     adapt: str = "auto") -> tuple[Any, ExperimentDesign, PlantEffects, Adaptation]:
    """The identification experiment run on the MuJoCo plant (``effects``, the truth ``true``), adapted as
    ``alpes-dyn experiment`` adapts it (:func:`~alpes_dyn.estimation.experiments.adapt.first_in_range`: the whole record checked
    against the joints' range; ``adapt``: its ``--rig``, ``auto`` hanging the hand where palm up the finger leaves
    its range, then smaller amplitudes), but on the plant's own joint angles -- what the experimenter sees of
    the real finger on its stop.

    Parameters
    ----------
    effects : PlantEffects
        The plant's effects.
    seed : int
        The sensor noise's seed (and the memoised torque's key).
    design : ExperimentDesign
        The experiment's design.
    true : HandParams
        The plant's true parameters.
    plant : Plant, optional
        The plant (default :data:`FINGER3`).
    adapt : str, optional
        One of :data:`ADAPT`, as ``--rig`` (default ``"auto"``).

    Returns
    -------
    tuple
        (the recording, the design chosen, the plant's effects in its orientation (the tilt error on top of the
        rig's), the :class:`~alpes_dyn.estimation.experiments.adapt.Adaptation`).

    Raises
    ------
    InputError
        An unknown ``adapt``.
    """
    if adapt not in ADAPT:
        raise InputError(f"adapt: expected one of {', '.join(ADAPT)}, got {adapt!r}")
    own = _rig_tilt(design)
    limits = plant.alpes(params=true)

    def run(r: str, d: ExperimentDesign):
        e = effects if r == "level" else dataclasses.replace(effects, tilt=effects.tilt - own + _rig_tilt(d))
        felt = np.array([plant_model(plant.model, true, dataclasses.replace(e, tilt=e.tilt - _rig_tilt(d) + a),
                                     plant.chain).gravity for a in _orientation_tilts(d)])  # each orientation's
        _, u, x0 = torque_of(seed, true, d, felt, plant)
        seg = orientation_segments(d)
        turned = len(d.orientations) > 1
        rec = mujoco_recording(plant.model, true, u, d.dt, effects=e, q0=x0[: x0.size // 2], seed=seed,
                               chain=plant.chain, gravity=felt[seg] if turned else None)
        if turned:  # the rig's nominal orientations, as the experimenter writes them (the tilt fitted on top)
            rec.gravity = np.asarray(d.orientations, dtype=float)[seg]
        held = held_out_rows(d)
        rec.held_out = held if held.any() else None  # the stiction ramp: identify judges on it, does not fit it
        return (rec, d, e), rec.true_q

    if adapt == "none":
        candidates = [("level", 1.0, design)]  # the design as given, in its own orientation
    else:
        rig = adapt if adapt != "auto" or own == 0.0 else "hanging"  # a hung design stays hung
        candidates = candidate_designs(design, rig, np.asarray(load_params().gravity, dtype=float))
    (out, _, _, k), tried = first_in_range(run, candidates, limits.lower, limits.upper)
    return (*out, adaptation_of(tried, k, limits))


def realism_case(case: str, effects: PlantEffects, seed: int, design: ExperimentDesign, tmp: Path,
                 plant: Plant = FINGER3, rigid: bool = True, adapt: str = "auto") -> dict[str, Any]:
    """One row: the plant's recording, the two fits, the EKF runs (see the module docstring); the rig, the fits and
    the EKF on the orientation the adaptation chose.

    Parameters
    ----------
    case : str
        The case's name (:data:`CASE_NAMES`), written in the row.
    effects : PlantEffects
        The plant's effects.
    seed : int
        The draw's and the noise's seed.
    design : ExperimentDesign
        The experiment's design.
    tmp : pathlib.Path
        The directory the identified and true files are written in.
    plant : Plant, optional
        The plant (default :data:`FINGER3`).
    rigid : bool, optional
        Fit the rigid model too (default True).
    adapt : str, optional
        The experiment's adaptation (:func:`plant_experiment`): ``auto`` (as ``alpes-dyn experiment``), ``level``
        or ``hanging`` (that orientation only, the amplitudes adapting), ``none`` (``design`` as given).

    Returns
    -------
    dict
        Keys: case, seed, chain, rigid (absent without ``rigid``) and extended (each: worst errors in %, plain and
        up to the common scale, values, residual in counts, converged, verdict, adequacy), joint_range_deg,
        plant_seconds, ekf_seconds, ekf_rmse_deg and ekf_true_file_rmse_deg (per joint, deg), adaptation.
    """
    true = plant.true_params(seed)
    nominal = load_params()
    t0 = time.perf_counter()
    rec, design, effects, adaptation = plant_experiment(effects, seed, design, true, plant, adapt)
    rig = rig_of(design)
    plant_s = time.perf_counter() - t0
    row: dict[str, Any] = {"case": case, "seed": seed, "chain": plant.label, "adaptation": adaptation.to_dict()}
    truth = {pp.name: pp.nominal for pp in parameter_catalogue(plant.alpes(params=true))}
    if rigid:
        row["rigid"] = fit_row(identify(on_rig(plant.alpes(params=nominal), rig), rec, plant.base,
                                         excitation=design.lines, progress=False), truth, [])
    model_of = alpes_models(plant.model, nominal, chain=plant.chain)
    fit = fit_effects(lambda e: on_rig(model_of(e), rig), rec, parse_effects(FIT_EFFECTS), plant.base,
                      rec.gravity is not None, excitation=design.lines, progress=False)
    res = fit.result
    ident = res.write(tmp / f"ident_{plant.label}_{case}_{seed}.toml")  # marked NOT TRUSTWORTHY where the fit says so
    t1 = time.perf_counter()
    fresh = fresh_run(true, effects, seed, design, plant)
    fitted = dict(zip(res.names, res.values))
    rmse = ekf_rmse(fresh, str(ident), fitted, rotor="rotor" in fit.effects, plant=plant, rig=rig,
                    torque_delay=fit.delay)
    true_path = write_params(true, tmp / f"true_{plant.label}_{seed}.toml")
    rmse_true = ekf_rmse(fresh, str(true_path), {}, plant=plant, rig=rig)
    ekf_s = time.perf_counter() - t1
    row["extended"] = fit_row(res, truth, list(fit.effects))
    row["joint_range_deg"] = [np.degrees(rec.true_q.min(axis=0)).tolist(), np.degrees(rec.true_q.max(axis=0)).tolist()]
    row["extended"]["rounds"] = [{"effects": list(e), "residual_counts": r.residual_rms, "converged": bool(r.converged),
                                  "fit_seconds": r.seconds} for e, r in fit.rounds]
    observed = fit.observer.seconds if fit.observer is not None else 0.0
    row["extended"]["fit_seconds_total"] = fit.seconds + observed  # every round of auto, and the observer's check
    row["extended"]["observer_seconds"] = observed
    row["extended"]["torque_delay"] = fit.delay
    row["extended"]["notes"] = list(fit.notes)
    row["extended"]["observer"] = None if fit.observer is None else fit.observer.to_dict()
    row["extended"]["tried"] = None if fit.tried is None else {
        "effects": list(fit.tried_effects), "residual_counts": fit.tried.residual_rms, "flagged": not fit.tried.trustworthy,
        "fit_seconds": fit.tried.seconds}
    row.update({"plant_seconds": plant_s, "ekf_seconds": ekf_s, "ekf_rmse_deg": np.degrees(rmse).tolist(),
                "ekf_true_file_rmse_deg": np.degrees(rmse_true).tolist()})
    return row


def realism_row(seed: int, case: str = "all", rig: str = "level", chain: str | None = None,
                duration: float = 4.0, cable: tuple[float, float] | None = None, adapt: str = "auto") -> dict[str, Any]:
    """:func:`realism_case` as a function of the seed (for :func:`~alpes_dyn.studies.sweep.sweep`).

    Parameters
    ----------
    seed : int
        The draw's seed (finger3, or the whole hand with ``chain``).
    case : str, optional
        The plant's case, one of :data:`CASE_NAMES` (default ``"all"``).
    rig : str, optional
        The rig (:func:`rig_design`; default ``"level"``).
    chain : str or None, optional
        The hand's chain (None: finger3).
    duration : float, optional
        The experiment's duration, s (default 4).
    cable : tuple of (float, float) or None, optional
        The tendon case's (k_t N/m, c_t N s/m); None: sized by :func:`tendon_stiffness` on the level rig (a MuJoCo
        run of its own).
    adapt : str, optional
        :func:`realism_case`'s (default ``"auto"``).

    Returns
    -------
    dict
        :func:`realism_case`'s row.

    Raises
    ------
    InputError
        An unknown ``case`` or ``adapt``, or a ``cable`` out of range.
    """
    if case not in CASE_NAMES:
        raise InputError(f"case: expected one of {', '.join(CASE_NAMES)}, got {case!r}")
    if adapt not in ADAPT:
        raise InputError(f"adapt: expected one of {', '.join(ADAPT)}, got {adapt!r}")
    plant = FINGER3 if chain is None else hand_plant(chain)
    design = rig_design(rig, duration)
    if cable is None:
        cable = tendon_stiffness(rig_design("level", duration))[:2]  # sized on the level rig, used on every rig
    k_t, c_t = (float(x) for x in cable)
    if not (math.isfinite(k_t) and k_t > 0 and math.isfinite(c_t) and c_t >= 0):
        raise InputError(f"cable: expected (k_t > 0 N/m, c_t >= 0 N s/m), got {tuple(cable)!r}")
    effects = cases(k_t, c_t, RIGS[rig])[case]
    with tempfile.TemporaryDirectory() as d:
        return realism_case(case, effects, seed, design, Path(d), plant, adapt=adapt)


def realism_draw(seed: int, case: str = "all", rig: str = "level", chain: str | None = None,
                 duration: float = 4.0, cable: tuple[float, float] | None = None, adapt: str = "auto") -> dict[str, Any]:
    """:func:`realism_row` flattened to numbers: the worst errors up to the common scale (%), the residuals
    (counts), the verdicts (1: flagged), the extended fit's time (s, every round) and the EKF's RMSE per joint
    (deg).

    Parameters
    ----------
    seed : int
        The draw's seed (finger3, or the whole hand with ``chain``).
    case : str, optional
        The plant's case, one of :data:`CASE_NAMES` (default ``"all"``).
    rig : str, optional
        The rig (:func:`rig_design`; default ``"level"``).
    chain : str or None, optional
        The hand's chain (None: finger3).
    duration : float, optional
        The experiment's duration, s (default 4).
    cable : tuple of (float, float) or None, optional
        The tendon case's (k_t N/m, c_t N s/m); None: sized by :func:`tendon_stiffness` on the level rig (a MuJoCo
        run of its own).
    adapt : str, optional
        :func:`realism_case`'s (default ``"auto"``).

    Returns
    -------
    dict
    """
    row = realism_row(seed, case, rig, chain, duration, cable, adapt)
    a, b = row["rigid"], row["extended"]
    out: dict[str, Any] = {"rigid_flagged": int(a["flagged"]), "rigid_residual_counts": a["residual_counts"]}
    for kind in KINDS:
        out[f"{kind}_pct"] = b["worst_error_common_scale_pct"][kind]
    out.update({"residual_counts": b["residual_counts"], "converged": int(b["converged"]),
                "flagged": int(b["flagged"]), "fit_seconds": b["fit_seconds_total"],
                "effects": "+".join(b["effects"]) or "none", "ekf_deg": row["ekf_rmse_deg"],
                "ekf_true_file_deg": row["ekf_true_file_rmse_deg"]})
    return out


EKF_GOAL_DEG = 0.5
"""deg: the EKF's RMSE on every joint that an adequate file must give (issue 38)."""
MASS_GOAL_PCT = 5.0
"""%: the masses' worst error, up to the common scale, that an adequate file must keep."""
SPRING_GOAL_PCT = 3.0
"""%: the springs' worst error, up to the common scale, that an adequate file must keep."""
FIT_GOAL_S = 20.0
"""s: the median time of a fit, every round of ``--effects auto`` and the observer's check, cache warm (issue 38)."""


def parse_seeds(text: str) -> list[int]:
    """The seeds of ``text``: comma-separated non-negative integers or ranges ``a-b`` (both ends in), e.g.
    ``"301-320,5"``.

    Parameters
    ----------
    text : str
        The seeds' text.

    Returns
    -------
    list of int

    Raises
    ------
    InputError
        Naming ``seeds``, on anything else or a seed named twice.
    """
    seeds: list[int] = []
    for item in str(text).split(","):
        a, sep, b = item.strip().partition("-")
        try:
            lo, hi = int(a), int(b) if sep else int(a)
        except ValueError:
            raise InputError(f"seeds: expected non-negative integers or ranges a-b, comma-separated, got {text!r}") from None
        if lo < 0 or hi < lo:
            raise InputError(f"seeds: expected a range a-b with 0 <= a <= b, got {item.strip()!r}")
        seeds.extend(range(lo, hi + 1))
    if len(set(seeds)) != len(seeds):
        raise InputError(f"seeds: a seed is named twice in {text!r}")
    return seeds


def _stats(values: list[float]) -> dict[str, float | None]:
    return ({"median": float(np.median(values)), "worst": float(np.max(values))} if values
            else {"median": None, "worst": None})


def summarise(rows: list[dict[str, Any]], ekf_goal: float = EKF_GOAL_DEG,
              mass_goal: float = MASS_GOAL_PCT) -> dict[str, dict[str, Any]]:
    """Per case, the distribution of :func:`realism_case`'s rows (rows with ``error``: a run that raised, counted
    apart): ``n``, the median and worst of each kind's error up to the common scale (%), of the EKF's RMSE on the
    extended file (deg, the worst joint of each row) and of the fit's time (s, every round); ``adequate``;
    ``silent_misses``: the adequate rows whose EKF is above ``ekf_goal`` deg on a joint or whose masses are more
    than ``mass_goal`` % off (each as seed, EKF, m); ``refusals``: the flagged rows (each as seed and verdict);
    ``errors``: (seed, message); ``goal``: the goals (``ekf_deg``, ``K_pct``, ``m_pct``, ``fit_seconds``) and whether
    they are met: ``accuracy_met`` (no run raised, no silent miss, every adequate row's springs within ``K_pct``; a
    refusal names its cause in its verdict), ``time_met`` (the median fit within ``fit_seconds``).

    Parameters
    ----------
    rows : list of dict
        :func:`realism_case`'s rows.
    ekf_goal : float, optional
        The EKF's RMSE goal, deg (default :data:`EKF_GOAL_DEG`).
    mass_goal : float, optional
        The masses' error goal, % (default :data:`MASS_GOAL_PCT`).

    Returns
    -------
    dict of str to dict
        Case -> its summary.
    """
    out: dict[str, dict[str, Any]] = {}
    for case in dict.fromkeys(r["case"] for r in rows):
        mine = [r for r in rows if r["case"] == case]
        ok = [r for r in mine if "error" not in r]
        ext = [r["extended"] for r in ok]
        ekf = [max(r["ekf_rmse_deg"]) for r in ok]
        s: dict[str, Any] = {"n": len(mine), "errors": [(r["seed"], r["error"]) for r in mine if "error" in r]}
        for kind in KINDS:
            s[f"{kind}_pct"] = _stats([e["worst_error_common_scale_pct"][kind] for e in ext])
        s["ekf_deg"] = _stats(ekf)
        s["fit_seconds"] = _stats([e["fit_seconds_total"] for e in ext])
        s["adequate"] = sum(not e["flagged"] for e in ext)
        s["silent_misses"] = [{"seed": r["seed"], "ekf_deg": d, "m_pct": e["worst_error_common_scale_pct"]["m"]}
                              for r, e, d in zip(ok, ext, ekf)
                              if not e["flagged"] and (d > ekf_goal or e["worst_error_common_scale_pct"]["m"] > mass_goal)]
        s["refusals"] = [{"seed": r["seed"], "verdict": e["verdict"]} for r, e in zip(ok, ext) if e["flagged"]]
        good = [e for e in ext if not e["flagged"]]
        s["goal"] = {"ekf_deg": ekf_goal, "K_pct": SPRING_GOAL_PCT, "m_pct": mass_goal, "fit_seconds": FIT_GOAL_S,
                     "accuracy_met": not s["errors"] and not s["silent_misses"] and all(
                         e["worst_error_common_scale_pct"]["K"] <= SPRING_GOAL_PCT for e in good),
                     "time_met": s["fit_seconds"]["median"] is not None and s["fit_seconds"]["median"] <= FIT_GOAL_S}
        out[case] = s
    return out
