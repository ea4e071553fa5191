"""The identification experiment: what to do with the hand so that its parameters can be fitted.

The documented experiment on one finger (``finger2``, ``finger3``):

* the palm held still in one or more orientations (``orientations``, gravity vectors in the base frame;
  default palm up, gravity along -z as in the report); with several, the record is split among them and the
  hand turned between runs of the excitation, each run designed and trimmed in its own orientation
  (:func:`_orientation_torques`; palm up then hung fingers down, ``alpes-dyn experiment --rig both``: gravity
  across the finger, then along it, pins the split of the masses that one orientation leaves to the friction);
* the motor driven by a multisine torque, tau_m(t) = tau_b + a sum_i sin(2 pi f_i t + phi_i) / sqrt(n_f /
  2) over ``frequencies`` (default 0.3 to 11.3 Hz, Schroeder phases), so that the springs, gravity,
  inertias and friction all leave their mark on the encoder. The bias tau_b puts the nominal finger's
  mean joint angle mid-range (on a robot whose springs already rest there, the middle of the range its tendon
  reaches pulling: :func:`_pulled_target`), the amplitude a is the largest that keeps the nominal finger's static
  equilibria within its joint limits (a ``margin`` inside), both from the model the user starts with;
* a dither on top (``dither``, default 20 times the breakaway torque of the motor's joints, at
  ``dither_frequency``, 20 Hz; 0 turns it off): it keeps every joint sliding through its dry friction, whose
  stick phases no memoryless friction law fits (:func:`dither_amplitude`); none on a motor of springless
  joints (the thumb's ab/adduction), which it would let drift away from where they are placed. The experiment's lines, the
  multisine's and the dither's, are :attr:`ExperimentDesign.lines`: what ``identify(excitation=)`` takes;
* the bias trimmed on the hand (``trim_bias``, default on; :mod:`alpes_dyn.estimation.experiments.trim`): before
  recording, a slow loop on the measured encoder moves the bias until the finger rests where the nominal one would (the
  real finger, not the model, must sit mid-range: with springs softer than nominal the untrimmed bias drives
  q_1 past its upper stop), or, for a finger soft enough to snap through before it gets there (a fold of its
  static equilibria), as high as the excitation keeps clear of the fold. Palm up a finger within +-20 % of the
  nominal values is up to several times as compliant mid-range as the nominal, and the excitation then swings it past
  its stops: :data:`alpes_dyn.estimation.experiments.trim.MATCH_COMPLIANCE` (off by default: its cost in the fits'
  precision) holds such a finger no higher than where it is as compliant as the nominal at its design point, its
  multisine and dither shrunk with the room its joints have left below;
* optionally, at ``camera_times``, the joint angles measured once by a camera or a jig with noise
  ``camera_noise`` (rad);
* the sensors of the estimation scenario (:mod:`alpes_dyn.estimation.observers.scenario`): encoder quantised to
  ``counts_per_rev`` with 0.5 count of Gaussian noise, motor torque with white noise of 5e-4 N m,
  sampled at 1 kHz.

The hand is identified one chain at a time (:data:`EXPERIMENT_MODELS`): a finger model built from one
finger of the hand (``chain=``), or the ``thumb`` model, whose two motors are excited at once, each with
the multisine (phases shifted between them): the flexion tendon as a finger's, the ab/adduction (no
spring; its joint placed mid-range) about the torque that balances gravity there (trimmed on the hand:
the gravity it feels, not the design's), its amplitude searched down from four times its joint's breakaway
(Coulomb) torque until a nominal run stays in range, and no dither on it (nothing but its friction holds it).

Why this design (measured with :func:`~alpes_dyn.analysis.identifiability.fisher_information`, the Cramér-Rao
bounds of K, m, F_s, F_v on finger3 from 4 s of encoder data, 0.5 count of noise plus quantisation):
the estimation scenario's small torque wiggle leaves the distal viscous friction and the masses poorly bounded;
the multisine across the joint range bounds every parameter several times tighter.

:func:`experiment` simulates it on a finger with given true parameters (friction included) and returns
(and writes) a :class:`~alpes_dyn.estimation.experiments.recording.Recording` with the true joint angles in
``true_q_*``.
:func:`model_experiment` does the same on any tendon-driven robot (a URDF + spec :class:`~alpes_dyn.Model`),
its searches scaled by the robot's own static torques. Both warn
(:class:`~alpes_dyn.estimation.experiments.excursion.SmallExcursionWarning`, one per motor) where the recording moved a
motor's encoder by fewer counts than a fit can use
(:mod:`alpes_dyn.estimation.experiments.excursion`).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ...errors import InputError
from ...fileio import check_outputs
from ...limits import MAX_SEED
from ...model.robot import Model
from ...model.params import HandParams, load_params
from ...model.transmission import acceleration_before, torque_before
from .stick_ramp import held_out_rows, stick_ramp, with_ramp  # noqa: F401 (held_out_rows re-exported)
from .multisine import _motor_groups, _profile, _profiles, dither_amplitude  # noqa: F401 (re-exported)
from .design import ExperimentDesign, _checked_design  # noqa: F401 (re-exported)
from .draws import perturbed_params  # noqa: F401 (re-exported)
from .excursion import warn_small_excursions
from . import trim as _trim
from .trim import (_fmt, _holding_bias, _mean_equilibrium, _oriented, _rest_torque, _torque_ceiling, _trimmed_bias,
                   _with)
from .recording import Recording, write_recording
from ...simulation.integrate import stable_substeps
from ...simulation.sampled import sampled_rk4
from ...simulation.lugre import ACCURATE, lugre_substeps, simulate_lugre
from ...model.friction import lugre_of
from ...model.stops import JointRangeWarning, check_range

__all__ = ["EXPERIMENT_MODELS", "ExperimentDesign", "experiment", "experiment_torque", "orientation_segments",
           "held_out_rows", "excitation", "model_experiment",
           "model_experiment_torque",
           "perturbed_params", "dither_amplitude"]  # dither_amplitude: from .multisine

EXPERIMENT_MODELS: tuple[str, ...] = ("finger2", "finger3", "thumb")
"""The models the identification experiment is defined for: one finger, or the thumb (one chain at a time)."""


def excitation(model: Model, design: ExperimentDesign) -> tuple[float, float] | tuple[np.ndarray, np.ndarray]:
    """(tau_b, a): the multisine's bias and amplitude for ``model`` (see the module docstring), N m; numbers
    for a one-motor model, arrays (m,) per motor otherwise (the thumb: flexion and ab/adduction).

    Parameters
    ----------
    model : Model
        The finger (nominal).
    design : ExperimentDesign
        The design.

    Returns
    -------
    tau_b : float or numpy.ndarray, shape (m,)
        The bias, N m.
    a : float or numpy.ndarray, shape (m,)
        The amplitude, N m.
    """
    bias, amp = _excitation(model, design)
    if model.transmission.n_motors == 1:
        return float(bias[0]), float(amp[0])
    return bias, amp


def _unheld_joints(model: Model) -> list[str]:
    """The joints that no motor's tendon moves and no spring holds (a robot arm's joints under a tendon gripper):
    no static equilibrium to design the experiment about, and a simulation of them falls through their range."""
    k = np.asarray(model.extras.stiffness, dtype=float)
    return [j for j, d, k_j in zip(model.joint_names, model.transmission.driven, k) if not d and not k_j > 0]


MARGIN_FRACTION = 0.1
"""The most of a joint's range the design's ``margin`` takes at each end: a short range keeps its middle."""


def _joint_margins(model: Model, margin: float) -> np.ndarray:
    """(n,) rad or m: the design's ``margin`` inside each joint limit, at most :data:`MARGIN_FRACTION` of the joint's
    range (the 0.05 rad default is 0.05 m on a prismatic joint: more than the whole 0.04 m travel of Panda's
    fingers, whose design range was then empty). Where a range is wider than 10 margins (the Alpes joints' 1.57 rad)
    it is the margin itself."""
    span = np.where(np.isfinite(model.upper - model.lower), model.upper - model.lower, np.inf)
    return np.minimum(margin, MARGIN_FRACTION * span)


def _excitation(model: Model, design: ExperimentDesign) -> tuple[np.ndarray, np.ndarray]:
    """Bias and amplitude per motor (m,), N m. A motor against springs: bias putting the mean of its joints
    mid-range, amplitude the largest keeping the static equilibria in range; a motor on springless joints
    (the thumb's ab/adduction): bias balancing gravity there, amplitude from the motor's limit down.
    Then every amplitude whose joints a nominal run takes out of range shrinks by 15 % until none does."""
    unheld = _unheld_joints(model)
    if unheld:
        raise InputError(f"model: {', '.join(unheld)} {'has' if len(unheld) == 1 else 'have'} neither a motor nor a "
                         "spring, so nothing holds {} still for the experiment to start from; weld {} in the URDF "
                         "(type=\"fixed\") or give {} a spring ([stiffness]) or a motor".format(
                             *(["it"] * 3 if len(unheld) == 1 else ["them"] * 3)))
    margin = _joint_margins(model, design.margin)
    lo, hi = model.lower + margin, model.upper - margin
    g0 = np.asarray(design.orientations[0], dtype=float)
    n_m = model.transmission.n_motors
    joints, sprung, free = _motor_groups(model)

    def within(tau: np.ndarray) -> bool:
        try:
            return all(np.all((q >= lo) & (q <= hi)) for q in
                       (_mean_equilibrium(model, tau, np.asarray(g, dtype=float)) for g in design.orientations))
        except InputError:
            return False

    bias = np.zeros(n_m)
    for k in sprung:
        if design.torque_bias is not None:
            bias[k] = design.torque_bias
        else:  # mean joint angle of the motor's joints mid-range (or mid pulled range: _pulled_target)
            js = joints[k]
            bias[k] = _rest_torque(model, lambda q, js=js: float(np.mean(q[js])),
                                   _pulled_target(model, bias, k, js, g0), g0, _torque_ceiling(model, k),
                                   lambda c, k=k: _with(bias, k, c))
    bias = _holding_bias(model, bias, free, joints, g0)
    if design.torque_amplitude is not None:
        return bias, np.full(n_m, float(design.torque_amplitude))
    if not within(bias) and design.torque_bias is None:
        bias = _bias_in_range(model, bias, sprung, within)
    if not within(bias):
        raise InputError(f"torque_bias: the nominal finger's equilibrium at {_fmt(bias)} N m leaves its joint range")
    amp = np.zeros(n_m)
    for k in sprung:
        a, b = 0.0, _amplitude_ceiling(model, k, bias[k])
        for _ in range(40):
            c = 0.5 * (a + b)
            a, b = (c, b) if within(_with(bias, k, bias[k] + c)) and within(_with(bias, k, bias[k] - c)) else (a, c)
        amp[k] = a
    cap = float(model.params.tau_max) if model.params is not None else None
    S = model.transmission.S
    for k in free:  # from 4 x the breakaway torque (Coulomb friction) of its joints: a larger one runs away
        js = joints[k]
        breakaway = float(np.max(model.extras.coulomb[js] / np.abs(S[k, js])))
        cap_k = cap if cap is not None else _torque_ceiling(model, k)
        amp[k] = min(cap_k, 4.0 * breakaway) if breakaway > 0 else cap_k
    # resonances swing the finger further than its static equilibria: shrink until a nominal run stays in range.
    # First the springless joints' motors alone (a wild swing there also throws the other joints out of range),
    # then every motor whose joints leave the range.
    t, seg, G = _schedule(design)
    dither = dither_amplitude(model, design)  # the range is checked with it (it is part of the torque)
    for shrinking in ((free,) if free else ()) + (tuple(range(n_m)),):
        for _ in range(60):
            with warnings.catch_warnings():  # a trial amplitude may leave the range: that is what is tested
                warnings.simplefilter("ignore", JointRangeWarning)
                q = _simulate(model, design, _profiles(design, t, bias, amp, dither), G, seg)[:, : model.n]
            out = np.any((q < lo) | (q > hi), axis=0)
            hit = [k for k in shrinking if out[joints[k]].any()]
            if not hit:
                break
            for k in hit:
                amp[k] *= 0.85
    return bias, amp * design.amplitude_fraction


def _pulled_target(model: Model, bias: np.ndarray, k: int, js: np.ndarray, gravity: np.ndarray) -> float:
    """The mean joint angle (rad) that motor ``k``'s bias puts its joints ``js`` at: mid-range; but on a motor that
    pulls only (:func:`_amplitude_ceiling` = its bias) whose joints' springs already hold them mid-range or beyond
    with the motor off, the middle of the range the tendon reaches pulling, between that unloaded rest and the
    joints' upper limits. Without it a spring resting mid-range asks for no bias, hence no multisine (amplitude <=
    bias): on finger_edu (springs resting at 0 in ranges symmetric about 0) the excitation was the dither alone,
    0.012 N m, the joints moved by 0.2 deg, and the fit lost its basin even from the true values."""
    target = float(np.mean(0.5 * (model.lower + model.upper)[js]))
    if _amplitude_ceiling(model, k, 0.0) > 0:  # a motor that pushes too: mid-range about no bias is fine
        return target
    try:
        unloaded = float(np.mean(_mean_equilibrium(model, _with(bias, k, 0.0), gravity)[js]))
    except InputError:
        return target
    return target if target > unloaded else 0.5 * (unloaded + float(np.mean(model.upper[js])))


def _bias_in_range(model: Model, bias: np.ndarray, sprung: list[int], within: Callable[[np.ndarray], bool],
                   points: int = 81) -> np.ndarray:
    """``bias`` with each sprung motor's entry moved to the nearest torque (on a grid of ``points`` over
    [-ceiling, ceiling]) whose equilibrium keeps every joint in range: springs of unequal stiffness spread the
    joints so that the bias putting their mean mid-range can leave one of them out (a finger drawn by
    ``perturbed_params``); the middle of the feasible torques nearest the first choice then. Unchanged where no
    grid torque is feasible (the caller refuses it)."""
    out = bias.copy()
    for k in sprung:
        c = _torque_ceiling(model, k)
        grid = np.linspace(-c, c, points)
        ok = np.array([within(_with(out, k, float(tau))) for tau in grid])
        if not ok.any():
            continue
        runs = np.split(np.arange(points), np.flatnonzero(np.diff(ok.astype(int))) + 1)  # feasible and not runs
        feasible = [r for r in runs if ok[r[0]]]
        best = min(feasible, key=lambda r: float(np.min(np.abs(grid[r] - out[k]))))
        out[k] = float(0.5 * (grid[best[0]] + grid[best[-1]]))
    return out


def _amplitude_ceiling(model: Model, k: int, bias: float) -> float:
    """The largest multisine amplitude searched on motor ``k``: its bias (a tendon pulls only: the torque stays
    >= 0), but on a robot other than an Alpes model a motor that drives one joint alone (a direct drive or a
    gear, both ways) may swing through zero, up to :func:`_torque_ceiling`."""
    if model.params is not None or np.count_nonzero(model.transmission.S[k]) != 1:
        return bias
    return max(bias, _torque_ceiling(model, k))


def _trim_on_hand(truth: Model, nominal: Model, design: ExperimentDesign, t: np.ndarray, bias: np.ndarray,
                  amp: np.ndarray, dither: np.ndarray, gravity: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(bias, amp, dither), N m per motor, as the experimenter's slow loop on the encoder leaves them on ``truth``
    under ``gravity`` (3,) (:func:`~alpes_dyn.estimation.experiments.trim._trimmed_bias`: the nominal finger's encoder
    readings at the design's first orientation as the target, found on the finger as it is; the multisine's and the
    dither's amplitudes scaled with it, 1 but on a finger held lower); unchanged where the design gives its own
    ``torque_bias`` or no ``trim_bias``. The fold check's peak is the multisine's and the dither's, the multisine's
    alone under :data:`~alpes_dyn.estimation.experiments.trim.MATCH_COMPLIANCE`."""
    if not design.trim_bias or design.torque_bias is not None:
        return bias, amp, dither
    extra = None if _trim.MATCH_COMPLIANCE else dither
    peak = np.max(np.abs(_profiles(design, t, np.zeros_like(bias), amp, extra)), axis=0)
    g_design = np.asarray(design.orientations[0], dtype=float)
    bias, scale = _trimmed_bias(truth, nominal, bias, gravity, peak, design_gravity=g_design)
    return bias, amp * scale, dither * scale


def _schedule(design: ExperimentDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample times (N+1,), orientation segment of each sample and gravity (N+1, 3)."""
    N = design.n_samples - 1
    t = design.dt * np.arange(N + 1)
    n_or = len(design.orientations)
    seg = np.minimum((np.arange(N + 1) * n_or) // (N + 1), n_or - 1)
    return t, seg, np.asarray(design.orientations, dtype=float)[seg]


def _recorded(design: ExperimentDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_schedule` with the stiction ramp after it (:func:`~alpes_dyn.estimation.experiments.stick_ramp.
    with_ramp`): times, segments, gravity, and which samples are the ramp's."""
    return with_ramp(design, *_schedule(design)[:2])


def orientation_segments(design: ExperimentDesign) -> np.ndarray:
    """(N+1 + ``design.stick_samples``,) int: the index of the orientation (``design.orientations``) each sample of
    the record is taken in (the excitation split evenly among them, in turn; the stiction ramp in the last).

    Parameters
    ----------
    design : ExperimentDesign
        The design.

    Returns
    -------
    numpy.ndarray of int, shape (N+1,)
    """
    return _recorded(design)[1]


def _simulate(truth: Model, design: ExperimentDesign, u: np.ndarray, G: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """States (N+1, 2n) from the static equilibrium at u[0], RK4 with the design's substeps (more where the truth's
    friction asks for them, :func:`~alpes_dyn.simulation.integrate.stable_substeps`; the truth's LuGre law, where its
    file has it, by :func:`~alpes_dyn.simulation.lugre.simulate_lugre` from unloaded bristles, at
    :data:`~alpes_dyn.simulation.lugre.ACCURATE` times its stable steps), the torques u (N+1, m) held
    per sample, segment by segment of constant gravity: compiled, the states kept at the samples
    (:func:`~alpes_dyn.simulation.sampled.sampled_rk4`, :func:`~alpes_dyn.simulation.integrate.simulate`'s RK4 to
    the bit, linear in the record); a :class:`~alpes_dyn.model.stops.JointRangeWarning` where a sample leaves the
    joint range."""
    N = u.shape[0] - 1
    # a sharper friction sign asks for more, and so does a sheath's friction under the torque's tension
    sub = max(design.substeps, stable_substeps(truth, design.dt, tension=np.abs(u).max(axis=0)))
    x = np.zeros((N + 1, 2 * truth.n))
    x[0, : truth.n] = _mean_equilibrium(truth, u[0], G[0])
    law, z = lugre_of(truth), np.zeros(truth.n)  # the LuGre law: its bristles carried from segment to segment
    start = 0
    while start < N:
        stop = start + 1
        while stop < N and seg[stop] == seg[start]:
            stop += 1
        m = _oriented(truth, G[start])
        if law is not None:
            res = simulate_lugre(m, x[start], u[start:stop], design.dt, law, z0=z, input="motor",
                                 substeps=max(sub, ACCURATE * lugre_substeps(m, law, design.dt)))
            x[start + 1: stop + 1], z = np.hstack([res.q, res.qd])[1:], res.z[-1]
        else:
            x[start + 1: stop + 1] = sampled_rk4(m, x[start], u[start:stop], design.dt, sub)[1:]
        start = stop
    check_range(design.dt * np.arange(N + 1), x[:, : truth.n], truth.lower, truth.upper, truth.joint_names, "warn",
                rest=np.where(truth.extras.stiffness != 0, truth.extras.rest, np.nan))
    return x


def experiment(model: str, true_params: HandParams | str | Path | None = None,
               design: ExperimentDesign | None = None, seed: int = 0, path: str | Path | None = None,
               nominal_params: HandParams | str | Path | None = None, chain: str | None = None,
               rotor_inertia: bool = False) -> Recording:
    """Simulate the identification experiment on a finger (or the thumb) with ``true_params`` (friction included).

    Parameters
    ----------
    model : str
        ``"finger2"``, ``"finger3"`` or ``"thumb"`` (:data:`EXPERIMENT_MODELS`). On the thumb both motors are
        excited at once, each with the multisine (phases shifted between them): the flexion tendon about a bias that
        holds the flexion joints mid-range (trimmed on the hand), the ab/adduction about the torque that balances
        gravity there (trimmed on the hand too), its joint starting mid-range, its amplitude the largest that keeps
        the nominal thumb in range (x ``amplitude_fraction``), without dither.
    true_params : HandParams or str or Path or None, optional
        The true parameters, or their file (default: the shipped one).
    design : ExperimentDesign or None, optional
        The design (default: the documented one).
    seed : int, optional
        The sensor noise's seed (0 to :data:`~alpes_dyn.limits.MAX_SEED`).
    path : str or Path or None, optional
        Where to write the recording as CSV too.
    nominal_params : HandParams or str or Path or None, optional
        The parameters the experimenter knows, from which the excitation is designed (default: the shipped file).
    chain : str or None, optional
        For a finger model, the hand's finger it is (its own ``[finger.<name>]`` values, in the true and the
        nominal file; see :meth:`Model.alpes <alpes_dyn.Model.alpes>`).
    rotor_inertia : bool, optional
        The true finger (and the nominal one the excitation is designed on) with each file's rotor inertia J_m on
        its tendon (eq. 2.8; default off, the rigid finger of the documented experiment).

    Returns
    -------
    Recording
        Encoder counts, measured torque, the camera's joint angles (if any), gravity (when not the model's
        constant) and the true joint angles.
    """
    if model not in EXPERIMENT_MODELS:
        raise InputError(f"model: the identification experiment is defined for one chain "
                         f"({', '.join(EXPERIMENT_MODELS)}), got {model!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or not 0 <= seed <= MAX_SEED:
        raise InputError(f"seed: expected an integer from 0 to {MAX_SEED}, got {seed!r:.60}")
    design = _checked_design(design)
    if path is not None:  # the output policy before any work: not over the parameter files read, nor a link...
        check_outputs([("path", path)], [(name, f) for name, f in (("true_params", true_params),
                                                                   ("nominal_params", nominal_params))
                                         if isinstance(f, (str, Path))])
    p_true = true_params if isinstance(true_params, HandParams) else load_params(true_params)
    p_nom = nominal_params if isinstance(nominal_params, HandParams) else load_params(nominal_params)
    nominal = Model.alpes(model, friction=True, rotor_inertia=rotor_inertia, params=p_nom, chain=chain)
    truth = Model.alpes(model, friction=True, rotor_inertia=rotor_inertia, params=p_true, chain=chain)
    return _run(truth, nominal, design, seed, path)


def model_experiment(nominal: Model, truth: Model | None = None, design: ExperimentDesign | None = None,
                     seed: int = 0, path: str | Path | None = None) -> Recording:
    """The identification experiment of :func:`experiment` on any tendon-driven robot (a URDF + spec
    :class:`~alpes_dyn.Model`): the multisine designed on ``nominal`` (the bias that puts each motor's joints
    mid-range, the amplitude the largest that keeps the static equilibria and a nominal run in the joint range,
    both searched up to the robot's own static torque scale), the bias trimmed on ``truth`` (default: the
    nominal itself), simulated on ``truth`` with the sensors of the design.

    Parameters
    ----------
    nominal : Model
        The robot the experimenter knows (a URDF + spec model).
    truth : Model or None, optional
        The robot as it is, with the nominal's joints and motors (e.g. the same URDF with a perturbed spec);
        default: the nominal itself.
    design : ExperimentDesign or None, optional
        The design (default: the documented one).
    seed : int, optional
        The sensor noise's seed.
    path : str or Path or None, optional
        Where to write the recording as CSV too.

    Returns
    -------
    Recording
        Readable by :func:`~alpes_dyn.estimation.experiments.recording.read_recording` with either model.
    """
    truth = _checked_robots(nominal, truth)
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or not 0 <= seed <= MAX_SEED:
        raise InputError(f"seed: expected an integer from 0 to {MAX_SEED}, got {seed!r:.60}")
    design = _checked_design(design)
    if path is not None:
        check_outputs([("path", path)])
    return _run(truth, nominal, design, seed, path)


def _checked_robots(nominal: Any, truth: Any) -> Model:
    """The true robot (``nominal`` where ``truth`` is None); InputError naming the argument unless both are
    alpes_dyn Models, the nominal with motors, the truth with the nominal's joints and motors."""
    if not isinstance(nominal, Model):
        raise InputError(f"nominal: expected an alpes_dyn Model, got {type(nominal).__name__}")
    truth = nominal if truth is None else truth
    if not isinstance(truth, Model):
        raise InputError(f"truth: expected an alpes_dyn Model, got {type(truth).__name__}")
    if nominal.transmission is None:
        raise InputError(f"nominal: model {nominal.name!r} has no motors (give its spec's [[motor]] tables)")
    if truth.joint_names != nominal.joint_names or truth.motor_names != nominal.motor_names:
        raise InputError(f"truth: expected the nominal's joints {', '.join(nominal.joint_names)} and motors "
                         f"{', '.join(nominal.motor_names)}, got {', '.join(truth.joint_names)} and "
                         f"{', '.join(truth.motor_names)}")
    return truth


def model_experiment_torque(nominal: Model, truth: Model | None = None, design: ExperimentDesign | None = None
                            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The motor torque of the experiment that :func:`model_experiment` runs on ``truth`` (default: the nominal),
    without sensors: the input to replay on another plant (the robot's MJCF stepped by MuJoCo,
    :func:`~alpes_dyn.control.plants.mjcf_recording`), as :func:`experiment_torque` gives it for the named fingers.

    Replay this, not the recording's measured torque: the measured one carries the torque sensor's noise
    (``design.torque_noise``), which a plant driven by it feels. On a springless finger that noise walks the joints
    (on the Shadow hand's first finger), a motion no model driven by the excitation explains: the fit's masses
    come out several times further off on MuJoCo than replaying this torque.

    Parameters
    ----------
    nominal : Model
        The robot the experimenter knows, on which the excitation is designed.
    truth : Model or None, optional
        The robot run (default: ``nominal``).
    design : ExperimentDesign or None, optional
        The design (default: the documented one).

    Returns
    -------
    t : numpy.ndarray, shape (N+1,)
        The sample times, s.
    u : numpy.ndarray, shape (N+1, m)
        The true motor torque, N m, u[k] held on [t_k, t_k+1).
    x0 : numpy.ndarray, shape (2n,)
        The initial state (the true robot at rest under u[0], first orientation), rad and rad/s: the recording's
        first true state.
    """
    return _command(_checked_robots(nominal, truth), nominal, _checked_design(design))


def _command(truth: Model, nominal: Model, design: ExperimentDesign, felt: np.ndarray | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t, u, x0) of :func:`experiment_torque` and :func:`model_experiment_torque`: the excitation designed on
    ``nominal``, trimmed on ``truth`` under ``felt`` (k, 3), m/s^2, the gravity it feels in each orientation (default
    the design's own), and the truth at rest under u[0] in the first."""
    felt = np.asarray(design.orientations if felt is None else felt, dtype=float)
    t, seg, _, _ = _recorded(design)
    u = _orientation_torques(truth, nominal, design, t, seg, felt)
    x0 = np.zeros(2 * truth.n)
    x0[: truth.n] = _mean_equilibrium(truth, u[0], felt[0])
    return t, u, x0


def _orientation_torques(truth: Model, nominal: Model, design: ExperimentDesign, t: np.ndarray, seg: np.ndarray,
                         felt: np.ndarray) -> np.ndarray:
    """u (N+1, m), N m: the excitation of each orientation's segment (``seg`` (N+1,) its index per sample) designed
    on ``nominal`` in that orientation alone and trimmed on ``truth`` under ``felt`` (k, 3), m/s^2, the gravity the
    finger feels there, the multisine restarting at the segment's first sample: the hand turned between two runs
    of the experiment (palm up, then hung fingers down), each run with the bias and amplitudes its orientation asks
    for -- hung, gravity pulls along the finger and the palm-up bias would be the wrong one. The fit takes each
    segment on its own lines (:func:`~alpes_dyn.estimation.identification.torque_lines.line_basis`). One orientation: the
    documented experiment as it was."""
    u = np.empty((t.shape[0], nominal.transmission.n_motors))
    n_ex = t.shape[0] - design.stick_samples
    for i, g in enumerate(design.orientations):  # a loop over the orientations (one or two)
        one = dataclasses.replace(design, orientations=(tuple(g),))
        rows = np.flatnonzero(seg[:n_ex] == i)
        ti = t[rows] - t[rows[0]]
        bias, amp = _excitation(nominal, one)
        dither = dither_amplitude(nominal, one)
        bias, amp, dither = _trim_on_hand(truth, nominal, one, ti, bias, amp, dither, np.asarray(felt[i], dtype=float))
        u[rows] = _profiles(one, ti, bias, amp, dither)
    u[n_ex:] = stick_ramp(nominal, design, bias, _ramp_in_range(nominal, design, felt[-1]))  # about the last bias
    return u


def _ramp_in_range(nominal: Model, design: ExperimentDesign, g: np.ndarray) -> Callable[[np.ndarray], bool]:
    """Whether a stiction ramp's torque (n, m) run on ``nominal`` from rest under gravity ``g`` keeps its joints
    ``design.margin`` inside their ranges (as :func:`_excitation` checks the multisine)."""
    margin = _joint_margins(nominal, design.margin)
    lo, hi = nominal.lower + margin, nominal.upper - margin

    def in_range(u: np.ndarray) -> bool:
        with warnings.catch_warnings():  # a trial swing may leave the range: that is what is tested
            warnings.simplefilter("ignore", JointRangeWarning)
            q = _simulate(nominal, design, u, np.repeat(np.asarray(g, dtype=float)[None], len(u), 0),
                          np.zeros(len(u), int))[:, : nominal.n]
        return bool(np.all((q >= lo) & (q <= hi)))
    return in_range


def _run(truth: Model, nominal: Model, design: ExperimentDesign, seed: int, path: str | Path | None) -> Recording:
    """The experiment designed on ``nominal``, trimmed on and simulated with ``truth``, with the sensors."""
    t, seg, G, held = _recorded(design)
    u = _orientation_torques(truth, nominal, design, t, seg, np.asarray(design.orientations, dtype=float))
    rng = np.random.default_rng(seed)
    N = t.shape[0] - 1
    n_or = len(design.orientations)
    x = _simulate(truth, design, u, G, seg)
    tr = truth.transmission
    step = 2 * np.pi / tr.counts_per_rev
    # S q, plus the stretch C (u_k-1 - J_m qdd_m) where elastic (the fit's ShootingProblem.tension_torque)
    qm = tr.encoder_angles(x[:, : truth.n], torque_before(u),
                           acceleration_before(tr.motor_velocities(x[:, : truth.n], x[:, truth.n: 2 * truth.n]),
                                               design.dt))
    counts = np.round((qm + design.encoder_noise_counts * step * rng.standard_normal(qm.shape)) / step)
    torque = u + design.torque_noise * rng.standard_normal(u.shape)
    q_meas = None
    if design.camera_times:
        q_meas = np.full((N + 1, truth.n), np.nan)
        for tc in design.camera_times:
            k = int(round(tc / design.dt))
            q_meas[k] = x[k, : truth.n] + design.camera_noise * rng.standard_normal(truth.n)
    same_g = n_or == 1 and np.array_equal(G[0], truth.gravity)
    rec = Recording(t=t, encoder=counts, torque=torque, motor_names=tr.motor_names, joint_names=truth.joint_names,
                    q=q_meas, gravity=None if same_g else G, true_q=x[:, : truth.n].copy(),
                    held_out=held if held.any() else None)
    if path is not None:
        write_recording(rec, path)
    warn_small_excursions(rec)  # one SmallExcursionWarning per motor whose encoder barely moved
    return rec


def experiment_torque(model: str, true_params: HandParams | str | Path | None = None,
                      design: ExperimentDesign | None = None, nominal_params: HandParams | str | Path | None = None,
                      chain: str | None = None,
                      true_gravity: Sequence[float] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The motor torque of the experiment that :func:`experiment` runs on ``true_params``, without sensors: the
    input to replay on another plant (a MuJoCo finger, :func:`alpes_dyn.control.plants.mujoco_recording`).

    The bias is trimmed on the true finger as in :func:`experiment` (what the experimenter's slow loop on the
    encoder finds with the library's model of that finger). Several orientations: one run of the excitation each,
    in turn (:func:`_orientation_torques`); the plant turned at the segments' first samples
    (:func:`~alpes_dyn.control.plants.mujoco_recording`'s ``gravity``).

    Parameters
    ----------
    model : str
        ``"finger2"``, ``"finger3"`` or ``"thumb"`` (:data:`EXPERIMENT_MODELS`), as :func:`experiment`'s.
    true_params : HandParams or str or Path or None, optional
        The true parameters, or their file (default: the shipped one).
    design : ExperimentDesign or None, optional
        The design (default: the documented one).
    nominal_params : HandParams or str or Path or None, optional
        The parameters the experimenter knows, from which the excitation is designed (default: the shipped file).
    chain : str or None, optional
        For a finger model, the hand's finger it is, as :func:`experiment`'s.
    true_gravity : sequence of float, shape (3,) or (k, 3), or None, optional
        The gravity the true finger feels in each of the design's k orientations, m/s^2, if not the design's own
        (a palm tilted unknown to the experimenter: the excitation is designed for the orientation the design
        names, the bias trimmed and the rest found on the finger as it is).

    Returns
    -------
    t : numpy.ndarray, shape (N+1,)
        The sample times, s.
    u : numpy.ndarray, shape (N+1, m)
        The true motor torque, N m, u[k] held on [t_k, t_k+1).
    x0 : numpy.ndarray, shape (2n,)
        The initial state (the true finger at rest under u[0], first orientation), rad and rad/s.

    Raises
    ------
    InputError
        An unknown ``model`` or a malformed ``true_gravity``.
    """
    if model not in EXPERIMENT_MODELS:
        raise InputError(f"model: the identification experiment is defined for one chain "
                         f"({', '.join(EXPERIMENT_MODELS)}), got {model!r}")
    design = _checked_design(design)
    n_or = len(design.orientations)
    g_true = np.asarray(design.orientations if true_gravity is None else true_gravity, dtype=float)
    g_true = g_true[None] if g_true.shape == (3,) else g_true
    if g_true.shape != (n_or, 3) or not np.isfinite(g_true).all():
        raise InputError(f"true_gravity: expected 3 finite numbers (m/s^2) per orientation ({n_or}), got "
                         f"{np.asarray(true_gravity).tolist()!r:.80}")
    p_true = true_params if isinstance(true_params, HandParams) else load_params(true_params)
    p_nom = nominal_params if isinstance(nominal_params, HandParams) else load_params(nominal_params)
    nominal = Model.alpes(model, friction=True, params=p_nom, chain=chain)
    truth = Model.alpes(model, friction=True, params=p_true, chain=chain)
    return _command(truth, nominal, design, g_true)
