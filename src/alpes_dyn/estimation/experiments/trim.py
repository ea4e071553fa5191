"""The experiment's bias trimmed on the hand (:mod:`alpes_dyn.estimation.experiments.experiment` designs it on the
nominal model): the static equilibria it is designed and trimmed on, the torque searches, and what the experimenter's
slow loop on the encoder settles to on the real finger (:func:`_trimmed_bias`).

Why the trim is more than the nominal's encoder reading: palm up, the Alpes finger at mid-range is close to a fold of
its static equilibria (gravity's torque nearly outgrows its springs: the nominal finger3's compliance there,
d(S q)/d tau, is several times its compliance unloaded), so a finger within +-20 % per link of the nominal values
(``perturbed_params(spread=0.2)``) is from about half to several times as compliant at the nominal's reading, or
has no rest there at all (it folds below it). The nominal design's room (its multisine at 0.5 of the amplitude
that keeps a nominal run in range) covers about a factor of 2: on the softer fingers the multisine and the dither
together swing q_1 past its upper stop, and the folding ones, held below their fold, rest q_1 on its lower stop.
No one bias serves the whole +-20 % box palm up: over its 64 corners (K_i, m_i each 0.8 or 1.2 times nominal) the
encoder readings at which a corner rests with every joint 0.05 rad inside its range do not overlap.
The trim therefore measures the finger it holds: where it is more compliant than the nominal finger at its design
point, it stops lower, where the compliances match (:func:`_matched_compliance`), and the multisine and the dither
shrink with the room the joints have left below that rest (:func:`_room_below`), so that drawn fingers stay inside
their range. The box's extreme corners remain at the edge (every spring 20 % soft and every mass 20 % heavy: the
fold lies just above the lower stop, and the dither swings q_1 past it, a range warning); such a finger is for the
hanging rig (``ExperimentDesign(orientations=(hanging_gravity(g),))``), where drawn fingers stay well inside their
range.
"""

from __future__ import annotations

import math
import warnings
from typing import Callable

import numpy as np

from ...errors import InputError
from ...model.robot import Model
from ...model.stops import JointRangeWarning
from .multisine import _motor_groups


def _oriented(model: Model, gravity: np.ndarray) -> Model:
    """``model`` itself, or a copy of it with another gravity vector (the hand turned)."""
    return model if np.array_equal(model.gravity, gravity) else model.copy(gravity=gravity)


def _mean_equilibrium(model: Model, tau_m: float | np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """The static equilibrium under the motor torques ``tau_m`` (m,) (a number for one motor), the joints
    without spring held mid-range."""
    m = _oriented(model, gravity)
    held = m.springless_joints
    q0 = np.zeros(m.n)
    for j in held:
        i = m.joint_index(j)
        q0[i] = 0.5 * (m.lower[i] + m.upper[i])
    return m.static_equilibrium(None, q0, fixed=held, tau_m=np.atleast_1d(np.asarray(tau_m, dtype=float)))


def _holding_bias(model: Model, bias: np.ndarray, free: list[int], joints: list[np.ndarray],
                  gravity: np.ndarray) -> np.ndarray:
    """``bias`` with each motor of ``free`` set to the torque that balances gravity on its (held) joints."""
    out = bias.copy()
    if not free:
        return out
    q = _mean_equilibrium(model, out, gravity)
    m = _oriented(model, gravity)
    G = m.gravity_torque(q) - m.transmission.joint_torque(out, q)  # what the held joints still need
    S = m.transmission.S
    for k in free:
        js = joints[k]
        out[k] += float(S[k, js] @ G[js] / (S[k, js] @ S[k, js]))
    return out


def _torque_ceiling(model: Model, k: int) -> float:
    """The largest motor torque the design's searches try on motor ``k``, N m: 0.2 on an Alpes model (what the
    documented experiment was measured with); on any other robot its own static scale, twice the largest torque
    that one of the motor's joints needs to hold its far limit against its spring and the largest gravity torque
    met over its range (through the motor's ratio): max_i 2 (k_i max(|lo_i - r_i|, |hi_i - r_i|) + G_i) / |S_ki|, r_i
    the spring's rest angle (0.05 N m for joints with neither)."""
    if model.params is not None:
        return 0.2
    S = model.transmission.S
    k_j, rest = model.extras.stiffness, model.extras.rest
    grav = np.zeros(model.n)
    for q in (model.lower, 0.5 * (model.lower + model.upper), model.upper):  # gravity alone (springs taken off)
        grav = np.maximum(grav, np.abs(model.gravity_torque(q) - model.spring_torque(q)))
    js = np.flatnonzero(S[k])
    reach = np.maximum(np.abs(model.lower[js] - rest[js]), np.abs(model.upper[js] - rest[js]))  # from the rest angle
    need = (k_j[js] * reach + grav[js]) / np.abs(S[k, js])
    top = float(2.0 * need.max())
    return top if top > 0 else 0.05


def _with(x: np.ndarray, k: int, value: float) -> np.ndarray:
    out = x.copy()
    out[k] = value
    return out


def _fmt(x: np.ndarray) -> str:
    return f"{x[0]:g}" if x.size == 1 else "[" + ", ".join(f"{v:g}" for v in x) + "]"


def _rest_torque(model: Model, reading: Callable[[np.ndarray], float], target: float, gravity: np.ndarray,
                 upper: float, torques: Callable[[float], np.ndarray] | None = None) -> float:
    """The motor torque c in [0, upper] N m at which ``reading`` of the finger's static equilibrium (a
    quantity that grows with the torque) equals ``target``: bisection, a torque that leaves the
    equilibrium undefined counting as too much. ``torques(c)``: the motor torques with c on the motor
    searched (default: the one motor)."""
    torques = torques or (lambda c: np.array([c]))
    a, b = 0.0, upper
    for _ in range(60):
        c = 0.5 * (a + b)
        try:
            above = reading(_mean_equilibrium(model, torques(c), gravity)) > target
        except InputError:
            above = True
        a, b = (a, c) if above else (c, b)
    return 0.5 * (a + b)


MATCH_COMPLIANCE = False
"""Whether :func:`_trimmed_bias` holds a finger more compliant than the nominal lower, its excitation shrunk (the
module docstring). Off by default: it keeps every drawn finger in its range, but the fits of the fingers
it holds lower lose precision (their masses several times further off, on the library's simulator and on MuJoCo's
all-effects plants; the tests of fits on drawn fingers then fail), a trade-off to weigh.
``trim.MATCH_COMPLIANCE = True`` turns it on."""


def _trimmed_bias(truth: Model, nominal: Model, bias: np.ndarray, gravity: np.ndarray,
                  peak: np.ndarray | None = None, design_gravity: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(bias, scale): the motor torques (m,), N m, at which ``truth`` rests with the encoder readings that ``nominal``
    has at ``bias``, motor by motor for the motors against springs, and the factor (m,) by which each motor's
    multisine and dither shrink on ``truth`` (1 but where the rest was lowered, below). What an experimenter gets by
    trimming each bias with a slow loop on its measured encoder before recording (the encoders are all it uses). The
    motors of springless joints (the thumb's ab/adduction) get the torque that holds their joints where the
    nominal design places them (mid-range) on ``truth`` under ``gravity``: what the same loop settles to on
    that motor's encoder. Their bias from the nominal model, which balances the gravity the design names,
    leaves an unknown tilt's torque unbalanced: with the palm 3 degrees off, the thumb's ab/adduction
    (no spring) drifts from mid-range onto its stop within the experiment (MuJoCo plants of the hand), which
    no fit without the stop explains (a residual far above the floor, springs well off).

    A finger more compliant there than the nominal one at its design point (:func:`_compliance`, the encoder's
    slope against the bias, which the same loop reads by stepping the bias) is held lower, where the compliances
    match (:func:`_matched_compliance`), and its multisine and dither shrink by the room its joints have left below
    (:func:`_room_below`): the module docstring says why. A finger that folds (its static equilibria end: gravity's
    torque outgrows the springs' and it snaps to full flexion) is infinitely compliant at the fold, so its matched
    rest lies below it; should the fold still lie within 1.25 times the shrunk multisine's ``peak`` torque (m, the
    multisine alone: the 20 Hz dither is too fast to carry the finger over) above the rest, the loop stops there
    instead. ``design_gravity`` (3,): the orientation the nominal design is made for (default ``gravity``), where
    the nominal's encoder readings at ``bias`` are the loop's target."""
    joints, sprung, free = _motor_groups(nominal)
    g_design = gravity if design_gravity is None else design_gravity
    q_design = _mean_equilibrium(nominal, bias, g_design)
    target = _reading(nominal, q_design)
    truth = _oriented(truth, gravity)  # once: each search below solves hundreds of equilibria under this gravity
    out = np.asarray(bias, dtype=float).copy()
    scale = np.ones(out.size)
    for k in sprung:
        upper = max(4.0 * out[k], _torque_ceiling(nominal, k))
        out[k] = _rest_torque(truth, lambda q, k=k: float(_reading(nominal, q, k)), float(target[k]), gravity, upper,
                              lambda c, k=k: _with(out, k, c))
        if MATCH_COMPLIANCE:  # the nominal's compliance at its design point: the most the finger may have
            allowed = _compliance(nominal, k, bias, g_design)
            if _compliance(truth, k, out, gravity) > allowed * (1 + 1e-6):
                out[k] = _matched_compliance(truth, k, out, gravity, allowed)
                reading = float(_reading(nominal, _mean_equilibrium(truth, out, gravity), k))
                scale[k] = _room_below(nominal, k, bias, reading, g_design, q_design)
        if peak is not None:
            fold = _fold_torque(truth, lambda c, k=k: _with(out, k, c), gravity, upper)
            if fold is not None and fold - 1.25 * scale[k] * float(peak[k]) < out[k]:
                out[k] = fold - 1.25 * scale[k] * float(peak[k])
                _warn_folded(truth, out, gravity, fold)
    return _holding_bias(truth, out, free, joints, gravity), scale


def _reading(model: Model, q: np.ndarray, k: int | None = None) -> np.ndarray | float:
    """The encoder reading (rad) at the joint angles q (n,): S q (or S_k q of motor ``k``), s(q) where the ratios
    change with q (:meth:`~alpes_dyn.model.transmission.Transmission.motor_positions`)."""
    tr = model.transmission
    if tr.curved:
        y = tr.motor_positions(q)
        return y if k is None else y[k]
    return tr.S @ q if k is None else tr.S[k] @ q


def _compliance(model: Model, k: int, tau: np.ndarray, gravity: np.ndarray) -> float:
    """d(S_k q)/d tau_k at the static equilibrium under the motor torques ``tau`` (m,), rad of motor ``k``'s encoder
    reading per N m: a central difference over +-1e-3 of the motor's torque scale (:func:`_torque_ceiling`; 2e-4 N m
    on an Alpes finger), what a slow loop on the encoder reads by stepping the bias; infinite where either step has
    no equilibrium near q = 0 (past a fold)."""
    h = 1e-3 * _torque_ceiling(model, k)
    try:
        hi = float(_reading(model, _mean_equilibrium(model, _with(tau, k, float(tau[k]) + h), gravity), k))
        lo = float(_reading(model, _mean_equilibrium(model, _with(tau, k, float(tau[k]) - h), gravity), k))
    except InputError:
        return math.inf
    return (hi - lo) / (2 * h)


def _matched_compliance(model: Model, k: int, tau: np.ndarray, gravity: np.ndarray, allowed: float) -> float:
    """Motor ``k``'s torque in [0, tau_k] N m at which ``model``'s :func:`_compliance` is ``allowed`` (rad/(N m)):
    bisection (the compliance grows with the pull on a finger whose springs gravity softens, to infinity at a
    fold); the torques of the other motors as in ``tau``."""
    a, b = 0.0, float(tau[k])
    for _ in range(40):
        c = 0.5 * (a + b)
        a, b = (c, b) if _compliance(model, k, _with(tau, k, c), gravity) <= allowed else (a, c)
    return a


def _room_below(nominal: Model, k: int, bias: np.ndarray, reading: float, gravity: np.ndarray,
                q_design: np.ndarray) -> float:
    """The factor in [0, 1] by which motor ``k``'s multisine and dither shrink on a finger held at the encoder ``reading``
    (rad) below the design's: of the room each of the motor's joints has between its rest and the limit that a
    slackening tendon moves it towards (the lower limit where S_kj > 0), the smallest share the nominal finger
    keeps at that reading, against its rest at the design point ``q_design`` (n,). The nominal model, not the
    finger, gives the joints' split (the encoder reads their sum only). Why both shrink: with the multisine
    unshrunk, the matched rest leaves some drawn fingers' q_1 close enough to its stop that the excitation swings it
    past; the multisine alone shrunk, a distal joint that the dither swings as far as the multisine can still dip
    past its stop; both shrunk, the joints stay inside their range."""
    S = nominal.transmission.S[k]
    upper = max(4.0 * float(bias[k]), _torque_ceiling(nominal, k))
    tau = _rest_torque(nominal, lambda q: float(_reading(nominal, q, k)), reading, gravity, upper,
                       lambda c: _with(bias, k, c))
    q = _mean_equilibrium(nominal, _with(bias, k, tau), gravity)
    js = np.flatnonzero(S)
    limit = np.where(S[js] > 0, nominal.lower[js], nominal.upper[js])
    share = (q[js] - limit) / (q_design[js] - limit)
    return float(np.clip(np.min(share), 0.0, 1.0))


def _warn_folded(truth: Model, bias: np.ndarray, gravity: np.ndarray, fold: float) -> None:
    """A :class:`JointRangeWarning` where the bias held below a fold rests a joint of ``truth`` outside its range:
    in this orientation the finger cannot be excited mid-range (it would be excited on its stop)."""
    q = _mean_equilibrium(truth, bias, gravity)
    out = np.flatnonzero((q < truth.lower) | (q > truth.upper))
    if out.size:
        j = int(out[np.argmax(np.maximum(truth.lower[out] - q[out], q[out] - truth.upper[out]))])
        warnings.warn(JointRangeWarning(
            f"the finger's static equilibria fold at {fold:.4g} N m (gravity outgrows its springs in this orientation): "
            f"held below it, at {_fmt(bias)} N m, joint {truth.joint_names[j]!r} rests at "
            f"{math.degrees(q[j]):.1f} deg, outside its range [{math.degrees(truth.lower[j]):g}, "
            f"{math.degrees(truth.upper[j]):g}] deg: the experiment would excite it on its stop. Hang the hand fingers "
            "down (alpes-dyn experiment --rig hanging, or --rig auto, the default, which does it by itself; from "
            "Python ExperimentDesign(orientations=(hanging_gravity(g),)), alpes_dyn.model.mjcf): gravity then "
            "pulls along the finger and its equilibria do not fold"), stacklevel=3)


def _fold_torque(model: Model, torques: Callable[[float], np.ndarray], gravity: np.ndarray,
                 upper: float) -> float | None:
    """The torque (N m) up to which the branch of stable static equilibria starting at zero torque goes on
    (a fold, where dG/dq turns singular), or None if it reaches ``upper``: a scan in steps of upper/400,
    then bisection; each equilibrium's Newton starts from the last stable one found below it (a continuation along
    the branch: a few iterations each, where from zero torque's start each took about twelve)."""
    m = _oriented(model, gravity)
    held = m.springless_joints
    free = [i for i, j in enumerate(m.joint_names) if j not in held]

    def stable(c: float, start: np.ndarray) -> np.ndarray | None:
        """The stable equilibrium under torque ``c`` from ``start`` (the held joints' angles in it), or None."""
        try:
            q = m.static_equilibrium(None, start, fixed=held, tau_m=np.atleast_1d(np.asarray(torques(c), dtype=float)))
        except InputError:
            return None
        dG = m.gravity_jacobian(q)[np.ix_(free, free)]
        return q if np.linalg.eigvalsh(0.5 * (dG + dG.T)).min() > 0 else None

    last = _mean_equilibrium(model, torques(0.0), gravity)  # zero torque's, from _mean_equilibrium's start
    steps = np.linspace(0.0, upper, 401)
    for a, b in zip(steps[:-1], steps[1:]):
        q = stable(b, last)
        if q is None:
            for _ in range(40):
                c = 0.5 * (a + b)
                q = stable(c, last)
                a, b, last = (c, b, q) if q is not None else (a, c, last)
            return a
        last = q
    return None
