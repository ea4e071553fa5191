"""The realism study's friction cases (issue 50): identification and the EKF on MuJoCo plants whose dry friction is
MuJoCo's own, soft or stiff, at 1 and 3 times the draw's F_s, alone or with every other effect of a real hand.

The cases are data (:data:`FRICTION_CASES`, each a :class:`FrictionCase`), walked by
:func:`friction_row` and checked by ``tests/test_realism_friction.py``:

=============== ==========================================================================================
case            the plant (finger3 drawn +-20 %, :func:`~alpes_dyn.studies.realism.FINGER3`)
=============== ==========================================================================================
soft            MuJoCo's ``frictionloss`` F_s with MuJoCo's default constraint (``solreffriction`` 0.02 s,
                ``solimpfriction`` 0.9 0.95): a dry friction that creeps
soft_3x         the same, F_s three times the draw's
stiff           the stiff constraint of :data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST` (0.5 ms, impedance
                0.999): a joint that sticks
stiff_3x        the same, F_s three times the draw's
all_soft ...    each of the four with every other effect of :func:`~alpes_dyn.bench.effects.real_hand_effects`
                (the cable with its rotor and slack, the palm's tilt, the torque constant, the encoder's zero,
                the torque a sample late)
=============== ==========================================================================================

Per case and seed (:func:`friction_row`): the identification experiment on the plant as ``alpes-dyn experiment
--rig auto`` adapts and records it (:func:`~alpes_dyn.studies.realism.plant_experiment`; its stiction ramp after the
excitation, :data:`~alpes_dyn.estimation.experiments.stick_ramp.STICK_SECONDS`, held out of the fit and judged on by
its observer check), fitted as ``alpes-dyn identify`` fits it (``--effects auto``), the file written; then a
validation run that the fit never saw, a different motion
(:func:`validation_torque`: the ``estimate`` scenario's torque, then a slow ramp through the stick band), the EKF
on it with the identified file and with the true one (:func:`~alpes_dyn.studies.realism.ekf_run`, the joints' end
stops in its model as ``estimate --stops``: the scenario's torque takes a drawn finger onto its stops; the true file
is the plant's whole truth, :func:`~alpes_dyn.bench.truth.write_truth`: the finger's true K, m and friction with the
tilt, the encoder's zero, the delay, the cable's compliance and rotor, the torque constant and a soft plant's
creep law (MuJoCo's default band) in the fields ``identify`` writes, its EKF reading them from the file; what a file cannot hold is named in the row,
``true_file_not_held``). A row holds
what :func:`~alpes_dyn.studies.realism.summarise` reads (the verdict, the errors up to the torque constant's
common scale, the EKF's RMSE per joint) and, for each file, the joints' NEES against their 95 % band
(:func:`~alpes_dyn.estimation.observers.consistency.nees`) and each fitted parameter's error in units of its
reported standard error (:func:`standard_scores`). :func:`friction_summary` gives each case's worst values.
"""

from __future__ import annotations

import dataclasses
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..bench.effects import PlantEffects, real_hand_effects
from ..bench.truth import write_truth
from ..control.plants import mujoco_recording
from ..errors import InputError
from ..estimation.experiments.design import ExperimentDesign
from ..estimation.experiments.stick_ramp import STICK_SECONDS
from ..estimation.identification.effects import alpes_models, fit_effects, parse_effects
from ..estimation.observers.band_sigma import band_fraction, band_sigma
from ..estimation.observers.consistency import chi2_band, nees
from ..estimation.observers.law_sigma import law_sigma
from ..estimation.observers.scenario import EstimationScenario, scenario_torque
from ..model.mjcf import STICTION_TIMECONST
from ..model.params import HandParams, load_params, with_values
from ..simulation.stick import FRICTION_LAWS, library_law
from ..symbolic.parametric import parameter_catalogue
from .realism import (EKF_GOAL_DEG, FINGER3, FIT_EFFECTS, KINDS, MASS_GOAL_PCT, SPRING_GOAL_PCT, ekf_run, fit_row,
                      on_rig, plant_experiment, rig_design, rig_of, summarise)

__all__ = ["FrictionCase", "FRICTION_CASES", "FRICTION_CASE_NAMES", "CONSTRAINTS", "STUCK_SPEED", "STOP_MARGIN_DEG",
           "RAMP_TORQUE", "RAMP_SECONDS",
           "validation_torque", "held_out_ramp", "standard_scores", "true_file_row", "friction_row", "friction_summary", "complete_seeds"]

CONSTRAINTS: dict[str, tuple[float, float]] = {"soft": (0.02, 1.0), "stiff": (STICTION_TIMECONST, 1.0)}
"""The dry-friction constraint of each kind: MuJoCo's ``solreffriction`` (time constant s, damping ratio) the plant
holds -- MuJoCo's default (nothing written) for ``soft``, :data:`~alpes_dyn.model.mjcf.STICTION_TIMECONST` for
``stiff``."""


@dataclasses.dataclass(frozen=True)
class FrictionCase:
    """One friction case of the study (module docstring).

    Attributes
    ----------
    name : str
        The table's name.
    constraint : str
        ``"soft"`` (MuJoCo's default constraint) or ``"stiff"`` (:data:`CONSTRAINTS`).
    scale : float
        The plant's F_s, times the draw's (1 or 3).
    others : bool
        With every other effect of :func:`~alpes_dyn.bench.effects.real_hand_effects`.
    """

    name: str
    constraint: str
    scale: float
    others: bool

    def effects(self) -> PlantEffects:
        """The plant's :class:`~alpes_dyn.bench.effects.PlantEffects` (its F_s is in :meth:`true_params`)."""
        base = real_hand_effects() if self.others else PlantEffects()
        if self.constraint == "soft":
            return dataclasses.replace(base, stiction=None, soft_stiction=True).check()
        return dataclasses.replace(base, stiction=CONSTRAINTS["stiff"][0]).check()

    def true_params(self, seed: int) -> HandParams:
        """The plant's parameters: finger3 drawn +-20 % with ``seed`` (:meth:`FINGER3.true_params
        <alpes_dyn.studies.realism.Plant.true_params>`), its joints' F_s times :attr:`scale`.

        Parameters
        ----------
        seed : int
            The draw's seed.

        Returns
        -------
        HandParams
            The plant's true parameters.
        """
        p = FINGER3.true_params(seed)
        if self.scale == 1.0:
            return p
        prm = p.raw["finger.F_s"]  # through the file's entries: what write_params writes holds it too
        return with_values(p, {"finger.F_s": dataclasses.replace(prm, value=self.scale * np.asarray(prm.value),
                                                                 reason=f"{prm.reason}; times {self.scale:g}")})


FRICTION_CASES: tuple[FrictionCase, ...] = tuple(
    FrictionCase(("all_" if others else "") + constraint + ("_3x" if scale == 3.0 else ""), constraint, scale, others)
    for others in (False, True) for constraint in ("soft", "stiff") for scale in (1.0, 3.0))
"""The eight cases: each constraint at 1 and 3 times F_s, alone and with every other effect."""
FRICTION_CASE_NAMES: tuple[str, ...] = tuple(c.name for c in FRICTION_CASES)

STUCK_SPEED = 0.01
"""rad/s: a plant's joint slower than this is said to be stuck in the rows' phases of the NEES (``per_joint_stuck``;
the stiff constraint holds a stuck joint to well below it, a sliding one on the validation ramp moves at 0.05 rad/s
and more)."""
STOP_MARGIN_DEG = 0.5
"""deg: a validation run's joint within this of an end of its range is said to reach its stop
(``validation_at_stops``; the EKF runs with the stops in its model, as ``estimate --stops``)."""
RAMP_TORQUE = 0.002
"""N m: the validation ramp's swing about the scenario's bias (the scenario's sines' sum, 2.2 mN m, about 8 times
the draw's F_s seen at the motor, r_m F_s / r)."""
RAMP_SECONDS = 6.0
"""s: the validation ramp's length: up by :data:`RAMP_TORQUE` in a quarter, down by twice it in a half, back in a
quarter (1.3 mN m/s: the joints stick and slip in turn)."""


def validation_torque(dt: float, m: int = 1) -> np.ndarray:
    """The validation run's motor torque: the ``estimate`` scenario's
    (:func:`~alpes_dyn.estimation.observers.scenario.scenario_torque`, its 5 s: the bias and its sines, which end at
    the bias), then a slow triangle about the bias (:data:`RAMP_TORQUE`, :data:`RAMP_SECONDS`).

    Parameters
    ----------
    dt : float
        The sample period, s.
    m : int, optional
        The number of motors (default 1), each given the same torque.

    Returns
    -------
    numpy.ndarray, shape (N+1, m)
        The motor torque, N m, N = round(5 s / dt) + round(:data:`RAMP_SECONDS` / dt).
    """
    sc = EstimationScenario()
    n1, n2 = int(round(sc.duration / dt)), int(round(RAMP_SECONDS / dt))
    t = dt * np.arange(n1 + n2 + 1)
    u = scenario_torque(sc, t[: n1 + 1], m)
    s = (t[n1 + 1:] - t[n1]) / RAMP_SECONDS  # 0..1 over the ramp
    tri = RAMP_TORQUE * np.interp(s, [0.0, 0.25, 0.75, 1.0], [0.0, 1.0, -1.0, 0.0])
    return np.vstack([u, sc.torque_bias + np.repeat(tri[:, None], m, axis=1)])


def standard_scores(values: dict[str, float], std: dict[str, float], truth: dict[str, float],
                    scale: float) -> dict[str, float]:
    """Each fitted K, m, F_s, F_v (:data:`~alpes_dyn.studies.realism.KINDS`) whose truth is known and not 0: its
    error up to the common ``scale`` (:func:`~alpes_dyn.studies.realism.errors`) in units of its reported standard
    error, (value / scale - truth) / (std / scale); |z| <= 3 where the reported uncertainty tells the truth.

    Parameters
    ----------
    values : dict of str to float
        The fitted values by parameter name, in their units.
    std : dict of str to float
        Their reported standard errors, same units (a parameter without one, or 0, left out).
    truth : dict of str to float
        The plant's true values by name, same units.
    scale : float
        The common scale of the fit (the torque constant's, :func:`~alpes_dyn.studies.realism.errors`), -.

    Returns
    -------
    dict of str to float
        Parameter name -> its standard score z, -.
    """
    out = {}
    for nm, v in values.items():
        if any(nm.startswith(k + "_") for k in KINDS) and truth.get(nm, 0.0) != 0.0 and std.get(nm, 0.0) > 0:
            out[nm] = (v / scale - truth[nm]) / (std[nm] / scale)
    return out


def _consistency(est, true_q: np.ndarray, transient: float) -> dict[str, Any]:
    """The EKF's NEES after ``transient`` s (the filter's own model of its error's correlation) and each joint's
    against its band (:meth:`~alpes_dyn.estimation.observers.consistency.Nees.joint_band`); where the filter's count
    of independent samples is checked, each joint's counted from its own series and the band at that count
    (``joint_measured_effective``, ``joint_band_measured``); and where the error lies, each joint's NEES while the
    plant's joint is stuck (speed below :data:`STUCK_SPEED`) and while it slides (``per_joint_stuck``,
    ``per_joint_sliding``, None where a phase has no sample; every sample after the transient)."""
    r = nees(est.estimate, true_q, est.filter, est.inputs, start=transient)
    lo, hi = r.joint_band()
    k0 = int(round(transient / (est.t[1] - est.t[0])))
    n = true_q.shape[1]
    r2 = (est.q_hat[k0:] - true_q[k0:]) ** 2 / np.diagonal(est.estimate.P[k0:, :n, :n], axis1=1, axis2=2)
    stuck = np.abs(np.gradient(true_q, est.t, axis=0)[k0:]) < STUCK_SPEED

    def phase(mask):
        return [float(np.mean(r2[mask[:, i], i])) if mask[:, i].any() else None for i in range(n)]

    return {"value": r.value, "band": [r.low, r.high], "verdict": r.verdict, "effective_samples": r.effective,
            "per_joint": r.per_joint.tolist(), "joint_band": [lo, hi],
            "joints_consistent": [bool(lo <= x <= hi) for x in r.per_joint],
            "joint_measured_effective": r.joint_measured.tolist(),
            "joint_band_measured": [list(chi2_band(1, m, r.level)) for m in r.joint_measured],
            "stuck_fraction": stuck.mean(axis=0).tolist(), "per_joint_stuck": phase(stuck),
            "per_joint_sliding": phase(~stuck)}


def _law_consistency(run, est, true_q: np.ndarray, transient: float) -> dict[str, Any]:
    """The NEES with each joint's variance widened by the spread between the observer's friction laws
    (:func:`~alpes_dyn.estimation.observers.law_sigma.law_sigma` over
    :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`, each on the file as it is; ``run(law)`` the EKF with that
    observer's law, ``est`` the kept one): its per-joint values against their band, the samples taken as independent
    (the filter's error model is its own P's, not the widened one's), and the spread's RMS per joint."""
    spread = law_sigma(run, est, laws=FRICTION_LAWS)  # the observer's laws on the file as it is (no creep run)
    r = nees(spread.widened(est.estimate), true_q, start=transient)
    lo, hi = r.joint_band()
    return {"per_joint": r.per_joint.tolist(), "joint_band": [lo, hi],
            "joints_consistent": [bool(lo <= x <= hi) for x in r.per_joint],
            **spread.to_dict(int(round(transient / (est.t[1] - est.t[0]))))}


def _band_consistency(est, true_q: np.ndarray, transient: float) -> dict[str, Any]:
    """The NEES with each joint's variance widened by the dry-friction band
    (:func:`~alpes_dyn.estimation.observers.band_sigma.band_sigma` on the observer's model, estimate and torque, as
    ``estimate --data`` by default, c of the observer's law,
    :func:`~alpes_dyn.estimation.observers.band_sigma.band_fraction`): its per-joint values against their band, the
    samples taken as independent (as :func:`_law_consistency`), and the band's RMS per joint."""
    model = est.filter.model.system.model
    law = library_law(model, est.settings["friction_law"])
    band = band_sigma(model, est.estimate.z, est.inputs, fraction=band_fraction(law), law=law)
    r = nees(band.widened(est.estimate), true_q, start=transient)
    lo, hi = r.joint_band()
    return {"per_joint": r.per_joint.tolist(), "joint_band": [lo, hi],
            "joints_consistent": [bool(lo <= x <= hi) for x in r.per_joint],
            **band.to_dict(int(round(transient / (est.t[1] - est.t[0]))))}


def _case(case: FrictionCase | str) -> FrictionCase:
    """``case``, or the case of that name (:class:`~alpes_dyn.InputError` naming ``case`` on an unknown one)."""
    if isinstance(case, str):
        if case not in FRICTION_CASE_NAMES:
            raise InputError(f"case: expected one of {', '.join(FRICTION_CASE_NAMES)}, got {case!r}")
        case = FRICTION_CASES[FRICTION_CASE_NAMES.index(case)]
    return case


def true_file_row(case: FrictionCase | str, seed: int, laws: tuple[str, ...] = ("smooth",), tmp: Path | None = None,
                  transient: float = 1.0, dt: float = 1e-3) -> dict[str, Any]:
    """The EKF with the plant's true file alone (no fit): ``case`` drawn with ``seed``, its validation run
    (:func:`validation_torque`, sample period ``dt`` s, the sensors' noise ``seed + 1000`` as in
    :func:`friction_row`), the truth written in ``tmp`` (:func:`~alpes_dyn.bench.truth.write_truth`; default a
    temporary directory) and the EKF on it with each observer friction law of ``laws``
    (:data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`). Keys: ``case``, ``seed``, ``not_held``, ``rotor``, and per
    law in ``laws`` (a dict by law): ``rmse_deg`` (per joint, after ``transient`` s), ``nees``
    (:func:`_consistency`), ``seconds``.

    Parameters
    ----------
    case : FrictionCase or str
        The case, or its name (:data:`FRICTION_CASE_NAMES`).
    seed : int
        The draw's seed (the validation run's sensor noise ``seed + 1000``).
    laws : tuple of str, optional
        The observer friction laws to run the EKF with (default ``("smooth",)``).
    tmp : pathlib.Path or None, optional
        The directory the true file is written in (default None: a temporary directory).
    transient : float, optional
        The EKF's transient left out of the RMSE and NEES, s (default 1).
    dt : float, optional
        The validation run's sample period, s (default 1 ms).

    Returns
    -------
    dict
        The row (keys above).

    Raises
    ------
    InputError
        An unknown case name.
    """
    case = _case(case)
    if tmp is None:
        with tempfile.TemporaryDirectory() as d:
            return true_file_row(case, seed, laws, Path(d), transient, dt)
    true, effects = case.true_params(seed), case.effects()
    u = validation_torque(dt, FINGER3.alpes(params=true).transmission.n_motors)
    val = mujoco_recording(FINGER3.model, true, u, dt, effects=effects, seed=seed + 1000, chain=FINGER3.chain)
    truth = write_truth(true, effects, tmp / f"true_{case.name}_{seed}.toml", FINGER3.model, FINGER3.chain)
    row: dict[str, Any] = {"case": case.name, "seed": seed, "not_held": list(truth.not_held), "rotor": truth.rotor,
                           "laws": {}}
    for law in laws:  # a few observers on one run
        t0 = time.perf_counter()
        est = ekf_run(val, str(truth.path), None, transient, rotor=truth.rotor, stops=True, friction_law=law)
        row["laws"][law] = {"rmse_deg": np.degrees(est.rmse).tolist(), "nees": _consistency(est, val.true_q, transient),
                            "seconds": time.perf_counter() - t0}
    return row


def held_out_ramp(case: FrictionCase | str, seed: int, effects: PlantEffects, dt: float = 1e-3) -> Any:
    """A held-out slow record for ``identify --validate`` (the observer check judged on it,
    :func:`~alpes_dyn.estimation.identification.effects.fit_effects` ``validation``): the validation run's ramp
    alone (:func:`validation_torque` after the scenario's 5 s, :data:`RAMP_SECONDS`: the joints stick and slip in
    turn) on the plant of ``case`` drawn with ``seed`` in its orientation (``effects``), its sensors' noise
    ``seed + 2000`` (neither the fit's nor the validation run's).

    Parameters
    ----------
    case : FrictionCase or str
        The case, or its name (:data:`FRICTION_CASE_NAMES`).
    seed : int
        The draw's seed.
    effects : PlantEffects
        The plant's effects in the experiment's orientation (:func:`~alpes_dyn.studies.realism.plant_experiment`).
    dt : float, optional
        The sample period, s (default 1 ms).

    Returns
    -------
    Recording
        The MuJoCo recording (encoder counts, torque N m, true joints rad).

    Raises
    ------
    InputError
        An unknown case name.
    """
    case = _case(case)
    true = case.true_params(seed)
    u = validation_torque(dt, FINGER3.alpes(params=true).transmission.n_motors)
    ramp = u[int(round(EstimationScenario().duration / dt)):]
    return mujoco_recording(FINGER3.model, true, ramp, dt, effects=effects, seed=seed + 2000, chain=FINGER3.chain)


def friction_row(case: FrictionCase | str, seed: int, design: ExperimentDesign | None = None,
                 tmp: Path | None = None, adapt: str = "auto", transient: float = 1.0,
                 check_ramp: bool = False) -> dict[str, Any]:
    """One row of the friction study (module docstring): ``case`` (a :class:`FrictionCase` or its name) on finger3
    drawn with ``seed`` (also the sensors' noise; the validation run's is ``seed + 1000``), the experiment ``design``
    (default the documented one on the level rig) adapted as ``adapt`` (:func:`~alpes_dyn.studies.realism.
    plant_experiment`), the files written in ``tmp`` (default a temporary directory). Keys: those of
    :func:`~alpes_dyn.studies.realism.realism_case` that :func:`~alpes_dyn.studies.realism.summarise` reads
    (``extended`` the fit, ``ekf_rmse_deg``, ``ekf_true_file_rmse_deg``), ``nees`` and ``nees_true_file``
    (:func:`_consistency`), ``nees_band`` and ``nees_true_file_band`` (:func:`_band_consistency`), ``z``
    (:func:`standard_scores`: the fit's standard errors with the model-form error of
    :mod:`~alpes_dyn.estimation.identification.law_spread` where the fit converged), ``z_noise`` (with the noise's
    alone), ``law_spread`` (it was added), ``validation_s``, ``validation_range_deg`` (the true
    joints' min and max), ``validation_at_stops`` (per joint, within :data:`STOP_MARGIN_DEG` of its range's ends),
    ``true_file_not_held`` (the plant's effects the true file cannot hold, :attr:`~alpes_dyn.bench.truth.TruthFile.
    not_held`), ``extended.observer_law`` and ``extended.law_choice`` (the law the file's observer runs, chosen by
    identify's check, :mod:`~alpes_dyn.estimation.identification.law_choice`), ``ekf_law_rmse_deg`` and ``ekf_true_file_law_rmse_deg`` (each file's EKF with each observer law the
    law spread runs, :data:`~alpes_dyn.simulation.stick.FRICTION_LAWS`, and ``file`` the file's own: RMSE per joint,
    deg, by law).

    Parameters
    ----------
    case : FrictionCase or str
        The case, or its name (:data:`FRICTION_CASE_NAMES`).
    seed : int
        The draw's seed, also the identification run's sensor noise (the validation run's is ``seed + 1000``).
    design : ExperimentDesign or None, optional
        The identification experiment (default None: the documented one on the level rig,
        :func:`~alpes_dyn.studies.realism.rig_design`).
    tmp : pathlib.Path or None, optional
        The directory the identified and true files are written in (default None: a temporary directory).
    adapt : str, optional
        How the experiment is adapted, as ``--rig`` (default ``"auto"``;
        :func:`~alpes_dyn.studies.realism.plant_experiment`).
    transient : float, optional
        The EKF's transient left out of the RMSE and NEES, s (default 1).
    check_ramp : bool, optional
        Give the fit a held-out slow record (:func:`held_out_ramp`) as ``identify --validate`` does: the observer
        check, and its choice of the friction law, judged on it (default False: on the fitted record). The row's
        ``check_ramp`` says which.

    Returns
    -------
    dict
        The row (keys above).

    Raises
    ------
    InputError
        An unknown case name or ``adapt``.
    """
    case = _case(case)
    if tmp is None:
        with tempfile.TemporaryDirectory() as d:
            return friction_row(case, seed, design, Path(d), adapt, transient, check_ramp)
    design = dataclasses.replace(rig_design("level"), stick_seconds=STICK_SECONDS) if design is None else design
    true, nominal = case.true_params(seed), load_params()
    t0 = time.perf_counter()
    rec, design, effects, adaptation = plant_experiment(case.effects(), seed, design, true, FINGER3, adapt)
    rig = rig_of(design)
    truth = {pp.name: pp.nominal for pp in parameter_catalogue(FINGER3.alpes(params=true))}
    model_of = alpes_models(FINGER3.model, nominal, chain=FINGER3.chain)
    held = {"validation": held_out_ramp(case, seed, effects, design.dt)} if check_ramp else {}
    fit = fit_effects(lambda e: on_rig(model_of(e), rig), rec, parse_effects(FIT_EFFECTS), FINGER3.base,
                      rec.gravity is not None, excitation=design.lines, progress=False, spread=True, **held)
    res = fit.result
    ident = res.write(tmp / f"ident_{case.name}_{seed}.toml")  # marked NOT TRUSTWORTHY where the fit says so
    plant_s = time.perf_counter() - t0
    u = validation_torque(design.dt, FINGER3.alpes(params=true).transmission.n_motors)
    val = mujoco_recording(FINGER3.model, true, u, design.dt, effects=effects, seed=seed + 1000, chain=FINGER3.chain)
    fitted = dict(zip(res.names, res.values.tolist()))
    laws: dict[str, dict[str, list]] = {"ekf_law_rmse_deg": {}, "ekf_true_file_law_rmse_deg": {}}

    def kept(key, law, est):  # each observer law's RMSE per joint, deg, as the law spread runs it
        laws[key][law or "file"] = np.degrees(est.rmse).tolist()
        return est

    def run(law=None):  # the EKF on the identified file, with the file's law or another
        return kept("ekf_law_rmse_deg", law, ekf_run(val, str(ident), fitted, transient, rotor="rotor" in fit.effects,
                                                     rig=rig, torque_delay=fit.delay, stops=True, friction_law=law))

    truth_file = write_truth(true, effects, tmp / f"true_{case.name}_{seed}.toml", FINGER3.model, FINGER3.chain)

    def run_true(law=None):
        return kept("ekf_true_file_law_rmse_deg", law, ekf_run(val, str(truth_file.path), None, transient,
                                                               rotor=truth_file.rotor, stops=True, friction_law=law))

    est, est_true = run(), run_true()
    lo, hi = np.degrees(val.true_q.min(axis=0)), np.degrees(val.true_q.max(axis=0))
    limits = FINGER3.alpes(params=true)
    row = {"case": case.name, "seed": seed, "chain": FINGER3.label, "adaptation": adaptation.to_dict(),
           "check_ramp": bool(check_ramp),
           "extended": fit_row(res, truth, list(fit.effects))}
    ext = row["extended"]
    choice = getattr(fit.observer, "law_choice", None)
    ext.update({"fit_seconds_total": fit.seconds + (fit.observer.seconds if fit.observer is not None else 0.0),
                "torque_delay": fit.delay, "notes": list(fit.notes), "observer_law": res.observer_law,
                "law_choice": None if choice is None else choice.to_dict()})
    z = standard_scores(fitted, dict(zip(res.names, res.std.tolist())), truth, ext["common_scale"])
    se = res.standard_errors  # the noise's alone (the larger of the classical and the HAC sandwich's): measured too
    noise = {} if se is None else dict(zip(res.names, np.maximum(se.classical, se.robust).tolist()))
    row["z_noise"] = standard_scores(fitted, noise, truth, ext["common_scale"])
    row["law_spread"] = se is not None and se.law_spread is not None
    row.update({"plant_seconds": plant_s, "validation_s": val.duration,
                "validation_range_deg": [lo.tolist(), hi.tolist()],
                "validation_at_stops": ((lo <= np.degrees(limits.lower) + STOP_MARGIN_DEG)
                                        | (hi >= np.degrees(limits.upper) - STOP_MARGIN_DEG)).tolist(),
                "ekf_rmse_deg": np.degrees(est.rmse).tolist(),
                "ekf_true_file_rmse_deg": np.degrees(est_true.rmse).tolist(),
                "nees": _consistency(est, val.true_q, transient),
                "nees_true_file": _consistency(est_true, val.true_q, transient), "z": z,
                "nees_law": _law_consistency(run, est, val.true_q, transient),
                "nees_true_file_law": _law_consistency(run_true, est_true, val.true_q, transient),
                "nees_band": _band_consistency(est, val.true_q, transient),
                "nees_true_file_band": _band_consistency(est_true, val.true_q, transient),
                "true_file_not_held": list(truth_file.not_held),
                "ekf_seconds": time.perf_counter() - t0 - plant_s, **laws})
    return row


def complete_seeds(rows: list[dict[str, Any]], names: tuple[str, ...] | list[str]) -> list[int]:
    """The seeds whose rows hold every case of ``names`` (a run stopped part-way: the same draws for each case).

    Parameters
    ----------
    rows : list of dict
        The study's rows (:func:`friction_row`; their ``seed`` and ``case``).
    names : tuple or list of str
        The case names a seed must hold.

    Returns
    -------
    list of int
        The seeds, in the order of their first row.
    """
    have: dict[int, set] = {}
    for r in rows:
        have.setdefault(r["seed"], set()).add(r["case"])
    return [s for s, c in have.items() if set(names) <= c]


def _worst(values: list[float]) -> float | None:
    return float(np.max(values)) if values else None


def friction_summary(rows: list[dict[str, Any]], ekf_goal: float = EKF_GOAL_DEG) -> dict[str, dict[str, Any]]:
    """Per case, :func:`~alpes_dyn.studies.realism.summarise` (its silent misses: adequate yet the EKF above
    ``ekf_goal`` deg on a joint, or the masses above its goal) and the worst of the rest over the case's rows:
    ``ekf_true_file_deg`` (the EKF with the true file, worst joint), ``nees_inconsistent`` and
    ``nees_true_file_inconsistent`` (the rows with a joint's NEES outside its 95 % band), ``nees_law_inconsistent``
    and ``nees_true_file_law_inconsistent`` (the same with the variance widened by the laws' spread, the rows that
    hold it), ``nees_band_inconsistent`` and ``nees_true_file_band_inconsistent`` (widened by the dry-friction
    band, ``estimate --data``'s default), ``nees_worst`` (the largest joint NEES, identified file), ``z_worst`` (the
    largest |error / standard error| over the parameters), ``z_within_3`` (the fraction of parameters within 3;
    ``z_noise_within_3`` with the noise's standard errors alone), ``verdicts`` (each row's, by seed);
    ``issue_goal_met`` (issue 50's goal on every row: the EKF within ``ekf_goal`` on every joint with both
    files, every joint's NEES in its band with both, every |z| within 3, springs and masses within their goals, no
    run that raised).

    Parameters
    ----------
    rows : list of dict
        The study's rows (:func:`friction_row`; a row with ``error``: a run that raised).
    ekf_goal : float, optional
        The EKF's RMSE goal on every joint, deg (default :data:`~alpes_dyn.studies.realism.EKF_GOAL_DEG`).

    Returns
    -------
    dict of str to dict
        Case name -> its summary (keys above).
    """
    out = summarise(rows, ekf_goal)
    for case, s in out.items():
        ok = [r for r in rows if r["case"] == case and "error" not in r]
        zs = [abs(v) for r in ok for v in r["z"].values()]
        zn = [abs(v) for r in ok for v in r.get("z_noise", {}).values()]
        s.update({
            "ekf_true_file_deg": {"median": float(np.median([max(r["ekf_true_file_rmse_deg"]) for r in ok]))
                                  if ok else None, "worst": _worst([max(r["ekf_true_file_rmse_deg"]) for r in ok])},
            "nees_inconsistent": sum(not all(r["nees"]["joints_consistent"]) for r in ok),
            "nees_true_file_inconsistent": sum(not all(r["nees_true_file"]["joints_consistent"]) for r in ok),
            "nees_worst": _worst([max(r["nees"]["per_joint"]) for r in ok]),
            "nees_true_file_worst": _worst([max(r["nees_true_file"]["per_joint"]) for r in ok]),
            **{f"{key}_inconsistent": sum(not all(r[key]["joints_consistent"]) for r in ok if key in r)
               for key in ("nees_law", "nees_true_file_law", "nees_band", "nees_true_file_band")},  # older rows: out
            "z_worst": _worst(zs), "z_within_3": float(np.mean([z <= 3 for z in zs])) if zs else None,
            "z_noise_within_3": float(np.mean([z <= 3 for z in zn])) if zn else None,
            "verdicts": {str(r["seed"]): r["extended"]["verdict"] for r in ok}})
        s["issue_goal_met"] = bool(ok) and not s["errors"] and all(
            max(r["ekf_rmse_deg"] + r["ekf_true_file_rmse_deg"]) <= ekf_goal
            and all(r["nees"]["joints_consistent"]) and all(r["nees_true_file"]["joints_consistent"])
            and all(abs(v) <= 3 for v in r["z"].values())
            and r["extended"]["worst_error_common_scale_pct"]["K"] <= SPRING_GOAL_PCT
            and r["extended"]["worst_error_common_scale_pct"]["m"] <= MASS_GOAL_PCT for r in ok)
    return out
