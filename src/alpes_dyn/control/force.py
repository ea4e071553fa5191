"""Effort control: the fingertip's normal force F_z tracked from what the hand measures.

The report is titled *Control in effort of a robotic hand*: its model carries the contact torque
J^T F (eq. 2.9-2.13), F measured by the fingertip's FlexiForce sensor. This module closes the loop.
The controller sees only the hand's sensors -- the motor encoder q_m (quantised, noisy), the motor
torque tau_m (from the current, noisy) and, if it uses it, the FlexiForce reading F_z (noisy,
quantised) -- and the joints q_hat estimated by the library's EKF (:mod:`alpes_dyn.estimation.observers`).

Static balance (eq. 2.11 at rest): G(q) = S^T tau_m + J(q)^T F with the contact force on the finger
F = -F_z n, n the unit normal of the object's surface (base frame, pointing from the fingertip into
the object: the direction it presses in; F_z >= 0 the pressing force). With one motor for several joints the balance is solved
in the least-squares sense over the joints:

* :func:`static_motor_torque` -- the tendon torque that holds F_z against springs and gravity,
  tau_m = S (G(q) + F_z J^T n) / (S S^T);
* :func:`static_contact_force` -- the contact force that balances a motor torque,
  F_z = -(J^T n) . (G(q) - S^T tau_m) / |J^T n|^2.

Controllers (:data:`CONTROLLERS`), one motor each, at 1 kHz:

* ``"sensor"`` -- feedforward :func:`static_motor_torque` at q_hat for the reference, plus a PI on
  the measured F_z, in a two-degree-of-freedom structure: the feedforward and the integral follow the
  reference through a first-order prefilter (``prefilter_s``, 25 ms), the proportional term acts on the
  raw reference (set-point weight ``setpoint_weight`` = 1). A torque step at the static balance would make
  the fingertip roll on the object (the passive joints redistribute through a lightly damped mode, about
  5 Hz, and the force overshoots); the prefilter brings the model's torque in at the pace of that motion,
  while the proportional term reacts at once as the baseline does and the integral, fed the prefiltered
  error, can be 2 times the baseline's without overshoot. The EKF gets the measured contact force as a
  known input;
* ``"sensorless"`` -- no FlexiForce: F_z estimated by :func:`static_contact_force` from the measured
  motor torque and q_hat (low-passed), used in the same loop; the EKF gets this estimate as its
  contact force;
* ``"pi"`` -- the baseline a user writes first: a PI on the measured F_z alone (no model, no observer).

All three share the contact-onset logic: before contact (F_z below ``contact_threshold``) the motor
torque rises at a bounded rate (``approach_rate``) so that the fingertip reaches the object slowly;
at contact the PI's integrator is set so that the torque is continuous (bumpless transfer). The
command is saturated to [0, tau_max] (a cable only pulls; ``transmission.tau_max`` of the parameter
file), with a conditional integration anti-windup.

:func:`run_control` runs the closed loop with MuJoCo as the plant (the MJCF of :mod:`alpes_dyn.model.mjcf`,
contact on, the block scene, joint friction on: ``pip install 'alpes_dyn[mujoco]'``); see
:class:`ControlScenario` for every setting and :class:`ControlResult` for the metrics.

:func:`run_hand_control` runs the same loops on the whole hand grasping the cylinder of the MJCF's
``"cylinder"`` scene: one controller, one EKF and one set of sensors per flexion motor (the four fingers
and the thumb, :func:`chain_model`), the contact normal the cylinder's at the estimated fingertip
(:func:`cylinder_normal`), the thumb's ab/adduction held by a PD on its encoder
(:class:`HandControlScenario`, :class:`HandControlResult`).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from ..errors import InputError, ModelError
from ..fileio import atomic_path
from ..limits import check_bytes, check_duration
from ..model.mjcf import BLOCK_CONTACT_Q, block_normal, joint_permutation, load_mujoco, mjcf_string, palm_down_params
from ..model.robot import Model
from ..estimation.observers import make_observer
from ..model.params import HandParams, load_params
from ..estimation.scenario import default_noise, static_equilibrium, EstimationScenario
from ..symbolic.statespace import StateSpace

__all__ = [
    "CONTROLLERS", "REFERENCES", "CONTROL_MODELS", "DEFAULT_GAINS", "static_motor_torque", "static_contact_force", "ForceController",
    "ControlScenario", "ControlResult", "run_control", "plot_control", "reference_profile",
    "HAND_LEVELS", "HAND_GAINS", "hand_chains", "chain_frame", "chain_model", "cylinder_normal", "HandControlScenario",
    "HandControlResult", "run_hand_control", "plot_hand_control",
]

CONTROLLERS: tuple[str, ...] = ("sensor", "sensorless", "pi")
REFERENCES: tuple[str, ...] = ("step", "ramp", "sine")
CONTROL_MODELS: tuple[str, ...] = ("finger2", "finger3")
#: Default settings of :class:`ForceController` per controller, tuned on the block scene of finger3 by one
#: rule for the ``sensor`` loop and the ``pi`` baseline: on the grid kp in {0.002, 0.004, 0.006, 0.008,
#: 0.012} N m/N x ki in {0.8, 1.2, 1.6, 2.0, 2.4} N m/(N s), the lowest force RMSE on the step reference
#: (0.2 -> 1.0 -> 0.5 N) with an overshoot below 10 % for the noise seeds 0-3 (kp = 0.012 loses the contact
#: for both). The sensor loop's 2-DOF structure is fixed before the grid: a first-order prefilter on the
#: reference of the feedforward and the integral, the proportional term on the raw reference; its time
#: constant, 25 ms, is the shortest of {15, 20, 25} ms with which the loop keeps the contact on the five
#: plants drawn 10 % off (``benchmarks/control.py``; with 20 ms it is a little faster on the nominal plant
#: but the FlexiForce reading drops to 0 on two of them as the fingertip rolls). The sensorless loop feeds
#: back a noisier, model-dependent estimate and is made slower; it declares contact once its estimate
#: stays above 0.1 N for 20 ms (the FlexiForce's loops: above 0.03 N).
DEFAULT_GAINS: dict[str, dict[str, float]] = {
    "sensor": {"kp": 0.008, "ki": 1.6, "prefilter_s": 0.025, "prefilter_order": 1, "setpoint_weight": 1.0},
    "sensorless": {"kp": 0.002, "ki": 0.4, "prefilter_s": 0.04, "contact_threshold": 0.1, "onset_s": 0.02},
    "pi": {"kp": 0.008, "ki": 0.8},
}


def _normal(normal: Sequence[float]) -> np.ndarray:
    n = np.asarray(normal, dtype=float)
    if n.shape == (3,):
        x, y, z = n.tolist()
        s = x * x + y * y + z * z  # Python floats: inf on overflow, NaN stays NaN, no warning
        if 0.0 < s < math.inf:  # the common case, called at every control step
            return n / math.sqrt(s)
    if n.shape != (3,) or not np.isfinite(n).all() or not n.any():
        raise InputError(f"normal: expected a non-zero 3-vector, got {np.asarray(normal).tolist()!r}")
    n = n / np.max(np.abs(n))  # huge entries: scale first so that the norm does not overflow
    return n / math.sqrt(float(n @ n))


def static_motor_torque(model: Model, q: np.ndarray, F_z: float, normal: Sequence[float], motor: int = 0,
                        tip: str | None = None) -> float:
    """Motor torque tau_m (N m) that holds the normal force F_z (N) at joint angles q (rad) (eq. 2.11 at rest).

    Least squares over the motor's joints of S^T tau_m = G(q) + F_z J(q)^T n; ``normal`` n (3,) is the
    object's surface normal (base frame) along which the fingertip presses.
    """
    S = model.transmission.S[motor]
    b = model.gravity_torque(q) + float(F_z) * (model.fingertip_jacobian(q, tip).T @ _normal(normal))
    return float(S @ b / (S @ S))


def static_contact_force(model: Model, q: np.ndarray, tau_m: np.ndarray, normal: Sequence[float],
                         tip: str | None = None) -> float:
    """Normal contact force F_z (N) that balances the motor torques tau_m (N m) at q (rad) (eq. 2.11 at rest).

    Least squares over the joints of G(q) - S^T tau_m = -F_z J(q)^T n.
    """
    jn = model.fingertip_jacobian(q, tip).T @ _normal(normal)
    r = model.gravity_torque(q) - model.transmission.joint_torque(np.atleast_1d(tau_m))
    return float(-(jn @ r) / (jn @ jn))


@dataclass
class ForceController:
    """One motor's force loop: feedforward (optional) + PI on the force error, contact onset, saturation.

    Parameters
    ----------
    kind: ``"sensor"``, ``"sensorless"`` or ``"pi"`` (the feedforward is used by the first two).
    model: the controller's model (for the feedforward).
    normal: the object's surface normal n (3,), base frame.
    dt: control period, s. tau_max: motor torque limit, N m (command in [0, tau_max]).
    kp: proportional gain, N m / N. ki: integral gain, N m / (N s).
    contact_threshold: F_z (N) above which the fingertip is in contact, for ``onset_s`` s.
    approach_rate: largest rise of the torque before contact, N m/s.
    prefilter_s: time constant of the reference's prefilter, s. prefilter_order: its first-order stages (1, 2).
    setpoint_weight: weight b in [0, 1] of the raw reference in the proportional term's error
        (b F_ref + (1 - b) F_ref_filtered - F_fb; the model-based controllers only).
    loss_s: contact is lost when the force stays below the threshold this long, s.
    """

    kind: str
    model: Model
    normal: np.ndarray
    dt: float
    tau_max: float
    kp: float = 0.004
    ki: float = 0.8
    contact_threshold: float = 0.03
    approach_rate: float = 0.03
    prefilter_s: float = 0.015
    loss_s: float = 0.02
    onset_s: float = 0.0
    prefilter_order: int = 2
    setpoint_weight: float = 0.0
    _above: int = 0
    integral: float = 0.0
    in_contact: bool = False
    tau_prev: float = 0.0
    F_ref_f: float | None = None
    F_ref_f2: float | None = None
    _below: int = 0

    def __post_init__(self) -> None:
        if self.kind not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.kind!r} (expected one of {', '.join(CONTROLLERS)})")
        self.normal = _normal(self.normal)
        if self.prefilter_order not in (1, 2):
            raise InputError(f"prefilter_order: expected 1 or 2, got {self.prefilter_order!r}")
        if not 0.0 <= self.setpoint_weight <= 1.0:
            raise InputError(f"setpoint_weight: expected a number in [0, 1], got {self.setpoint_weight!r}")

    def feedforward(self, q_hat: np.ndarray, F_ref: float) -> float:
        """Static-balance torque at q_hat for F_ref (0 for the ``"pi"`` baseline), N m."""
        if self.kind == "pi":
            return 0.0
        return static_motor_torque(self.model, q_hat, F_ref, self.normal)

    def update(self, F_ref: float, F_fb: float, q_hat: np.ndarray | None,
               normal: Sequence[float] | None = None) -> float:  # noqa: C901
        """The motor torque command (N m) for the reference F_ref and the force fed back F_fb (N).

        ``normal`` (3,), if given, replaces :attr:`normal` from this step on (a curved object: the
        surface normal at the fingertip moves with q_hat, see :func:`cylinder_normal`).

        The model-based controllers follow the reference through a prefilter of ``prefilter_order``
        first-order stages of time constant ``prefilter_s`` (a torque step would make the fingertip roll
        on the object) for the feedforward and the integral; the proportional term acts on
        ``setpoint_weight`` x the raw reference + (1 - ``setpoint_weight``) x the prefiltered one; contact
        is lost when F_fb stays below the threshold for ``loss_s``, and the approach starts again.
        """
        if normal is not None:
            self.normal = _normal(normal)
        F_raw = F_ref
        if self.kind != "pi":
            a = self.dt / (self.prefilter_s + self.dt)
            if self.F_ref_f is None:
                self.F_ref_f = self.F_ref_f2 = F_ref
            self.F_ref_f += a * (F_ref - self.F_ref_f)
            self.F_ref_f2 += a * (self.F_ref_f - self.F_ref_f2)
            F_ref = self.F_ref_f2 if self.prefilter_order == 2 else self.F_ref_f
        ff = self.feedforward(q_hat, F_ref) if self.kind != "pi" else 0.0
        e = F_ref - F_fb
        e_p = e + self.setpoint_weight * (F_raw - F_ref)  # the proportional term's error (set-point weighting)
        if self.in_contact:
            self._below = self._below + 1 if F_fb < self.contact_threshold else 0
            if self._below * self.dt >= self.loss_s:
                self.in_contact, self._below = False, 0
                self.tau_prev = min(self.tau_prev, max(ff, 0.0)) if self.kind != "pi" else 0.5 * self.tau_prev
        if not self.in_contact:
            self._above = self._above + 1 if F_fb >= self.contact_threshold else 0
            if self._above == 0 or self._above * self.dt < self.onset_s:  # approach: bounded torque rate
                tau = min(self.tau_prev + self.approach_rate * self.dt, self.tau_max)
                if self.kind != "pi":
                    tau = min(tau, max(ff, self.tau_prev))
                self.tau_prev = tau
                return tau
            self.in_contact = True
            self.integral = self.tau_prev - ff - self.kp * e_p  # bumpless transfer
        tau_u = ff + self.kp * e_p + self.integral
        tau = min(max(tau_u, 0.0), self.tau_max)
        if tau == tau_u or (tau_u > self.tau_max and e < 0) or (tau_u < 0 and e > 0):  # anti-windup
            self.integral += self.ki * e * self.dt
        self.tau_prev = tau
        return tau


def reference_profile(kind: str, t: np.ndarray, levels: Sequence[float] = (0.2, 1.0, 0.5),
                      sine: Sequence[float] = (0.3, 0.8, 1.0), step_times: Sequence[float] = (1.0, 2.0)) -> np.ndarray:
    """F_z reference (N) at times t (s).

    ``"step"``: levels[0] until step_times[0], levels[1] until step_times[1], then levels[2];
    ``"ramp"``: levels[0] until step_times[0], a linear ramp to levels[1] over 1 s, then held;
    ``"sine"``: levels[0] until step_times[0], then a sine between sine[0] and sine[1] at sine[2] Hz
    starting at its mean value.
    """
    t = np.asarray(t, dtype=float)
    a, b, c = levels
    t1, t2 = step_times
    if kind == "step":
        return np.where(t < t1, a, np.where(t < t2, b, c))
    if kind == "ramp":
        return np.where(t < t1, a, np.minimum(a + (b - a) * (t - t1), b))
    if kind == "sine":
        lo, hi, f = sine
        mean, amp = 0.5 * (lo + hi), 0.5 * (hi - lo)
        return np.where(t < t1, a, mean + amp * np.sin(2 * np.pi * f * (t - t1)))
    raise InputError(f"reference: unknown reference {kind!r} (expected one of {', '.join(REFERENCES)})")


@dataclass(frozen=True)
class ControlScenario:
    """Settings of the closed loop of :func:`run_control` (all SI units).

    The plant: MuJoCo stepping the MJCF of ``model`` with the ``"block"`` scene (a fixed, frictionless
    block met by the fingertip at ``contact_q``, :func:`~alpes_dyn.model.mjcf.block_normal`), contact and joint
    stops on, joint friction on
    (damping F_v, frictionloss F_s of the parameter file), the hand palm down (gravity reversed: the
    finger flexes with gravity toward the block under it), at ``dt / substeps``; its parameters are
    ``plant_params`` (default: the controller's). The controller's model is
    ``Model.alpes(model, params)`` palm down, no friction (the report's eq. 2.11).

    Sensors, sampled every ``dt`` (1 kHz): the encoder as in the estimation scenario
    (``transmission.encoder_counts`` counts per motor revolution, plus ``encoder_noise_counts`` counts
    of Gaussian noise, then quantised); the motor torque plus ``torque_noise`` N m of white noise; the
    FlexiForce: MuJoCo's touch sensor plus ``force_noise`` N of noise, quantised to ``force_resolution``
    (a 10-bit reading of a 4.4 N -- 1 lb -- FlexiForce A201: 4.3 mN).

    The reference (:func:`reference_profile`): ``levels`` (N) and a 1 Hz sine between ``sine[0]`` and
    ``sine[1]``; metrics over the levels after ``settle`` s (see :class:`ControlResult`). The sensorless
    loop low-passes its force estimate with ``force_filter_s``. ``gains`` override
    :data:`DEFAULT_GAINS` (any :class:`ForceController` field). ``compiled``: the EKF step in compiled C
    (cached; CasADi's virtual machine if no C compiler), the same numbers.

    Initial state: the finger at rest on its springs (static equilibrium, motor off); the EKF starts
    there too, with standard deviations 0.05 rad and 0.1 rad/s.
    """

    model: str = "finger3"
    controller: str = "sensor"
    reference: str = "step"
    duration: float = 3.0
    dt: float = 1e-3
    substeps: int = 4
    seed: int = 0
    levels: tuple[float, float, float] = (0.2, 1.0, 0.5)
    sine: tuple[float, float, float] = (0.3, 0.8, 1.0)
    step_times: tuple[float, float] = (1.0, 2.0)
    settle: float = 0.5
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    force_noise: float = 0.005
    force_resolution: float = 4.4 / 1024
    contact_q: tuple[float, ...] = BLOCK_CONTACT_Q
    force_filter_s: float = 0.01
    compiled: bool = True
    gains: dict = field(default_factory=dict, compare=False)  # overrides of DEFAULT_GAINS[controller]
    params: Any = field(default=None, compare=False)
    plant_params: Any = field(default=None, compare=False)

    def check(self) -> None:
        if self.model not in CONTROL_MODELS:
            raise InputError(f"model: the control scenario is defined for one finger ({', '.join(CONTROL_MODELS)}), "
                             f"got {self.model!r}")
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.controller!r} "
                             f"(expected one of {', '.join(CONTROLLERS)})")
        if self.reference not in REFERENCES:
            raise InputError(f"reference: unknown reference {self.reference!r} (expected one of {', '.join(REFERENCES)})")
        if not (isinstance(self.duration, (int, float)) and math.isfinite(self.duration) and self.duration > 0):
            raise InputError(f"duration: expected a positive number of seconds, got {self.duration!r}")
        check_duration(self.duration, "duration")
        if not self.settle + _METRIC_WINDOW_S <= self.duration:
            raise InputError(f"duration: {self.duration:g} s leaves less than {_METRIC_WINDOW_S:g} s after the settling "
                             f"time {self.settle:g} s (the metrics' window)")
        if not (isinstance(self.dt, (int, float)) and math.isfinite(self.dt) and self.dt > 0):
            raise InputError(f"dt: expected a positive number of seconds, got {self.dt!r}")
        check_bytes(8.0 * self.duration / self.dt * _SAMPLE_ARRAYS, "duration",
                    f"{self.duration:g} s at dt = {self.dt:g} s")
        if self.substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {self.substeps!r}")


_METRIC_WINDOW_S = 0.05
"""Shortest run after the settling time, s: the force RMSE needs samples (50 at 1 kHz)."""
_SAMPLE_ARRAYS = 64
"""Float64 values a closed-loop run keeps per sample (an upper bound: traces of forces, torques, q, q-hat)."""


@dataclass
class ControlResult:
    """One closed-loop run.

    Attributes
    ----------
    t: (N,) times, s. F_ref: (N,) reference, N. F_true: (N,) MuJoCo's touch sensor (noise-free), N.
    F_meas: (N,) the FlexiForce reading (noisy, quantised), N. F_hat: (N,) the force the controller fed
    back (F_meas, or the sensorless estimate), N. q_true, q_hat: (N, n) joints, rad (q_hat NaN for ``pi``).
    tau_cmd, tau_meas: (N,) motor torque command and its noisy measurement, N m.
    force_rmse: RMSE of F_true - F_ref after ``settle``, N. steady_state_error: worst over the constant
    levels (after ``settle``; for the ramp, the levels before and after it) of |mean(F_true) - F_ref| / F_ref
    over each level's last 200 ms (None for the sine). overshoot: worst over the steps of the excursion
    beyond the new level / step size (None unless step). rise_time_s: 10-90 % rise time of the up-step, s
    (None unless step). q_rmse_deg: (n,) RMSE of
    q_hat - q during contact (F_true > 0.05 N), deg (None for ``pi``). wall_s: wall time of the loop, s.
    saturated: fraction of samples with the command at 0 or tau_max.
    """

    scenario: ControlScenario
    t: np.ndarray
    F_ref: np.ndarray
    F_true: np.ndarray
    F_meas: np.ndarray
    F_hat: np.ndarray
    q_true: np.ndarray
    q_hat: np.ndarray
    tau_cmd: np.ndarray
    tau_meas: np.ndarray
    joint_names: tuple[str, ...]
    tau_max: float
    wall_s: float
    force_rmse: float = float("nan")
    steady_state_error: float | None = None
    overshoot: float | None = None
    rise_time_s: float | None = None
    q_rmse_deg: list[float] | None = None
    saturated: float = 0.0

    @property
    def realtime_ratio(self) -> float:
        """Simulated time / wall time of the loop (> 1: faster than real time)."""
        return float(self.scenario.duration / self.wall_s)

    def to_dict(self) -> dict[str, Any]:
        """The JSON summary of ``alpes-dyn control --json``."""
        sc = self.scenario
        return {
            "controller": sc.controller, "plant": "mujoco", "model": sc.model, "reference": sc.reference,
            "force_rmse": self.force_rmse, "steady_state_error": self.steady_state_error, "overshoot": self.overshoot,
            "rise_time_s": self.rise_time_s, "q_rmse_deg": self.q_rmse_deg, "joints": list(self.joint_names),
            "duration_s": sc.duration, "dt_s": sc.dt, "seed": sc.seed, "tau_max_Nm": self.tau_max,
            "saturated_fraction": self.saturated, "realtime_ratio": self.realtime_ratio,
        }

    def to_csv(self, path: str) -> None:
        """Write t, F_ref, F_z measured by MuJoCo's sensor, the FlexiForce reading, the force fed back, true
        and estimated q, motor torque command and measurement, one row per sample."""
        n = len(self.joint_names)
        head = (["t_s", "F_ref_N", "F_mujoco_N", "F_flexiforce_N", "F_feedback_N"]
                + [f"q_true_{j}_rad" for j in self.joint_names] + [f"q_hat_{j}_rad" for j in self.joint_names]
                + ["tau_cmd_Nm", "tau_meas_Nm"])
        rows = np.column_stack([self.t, self.F_ref, self.F_true, self.F_meas, self.F_hat, self.q_true[:, :n],
                                self.q_hat[:, :n], self.tau_cmd, self.tau_meas])
        with atomic_path(path, "--log") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            w.writerows([[f"{x:.9g}" for x in r] for r in rows])


def _metrics(res: ControlResult) -> None:
    sc = res.scenario
    t, F, R = res.t, res.F_true, res.F_ref
    k0 = t >= sc.settle
    res.force_rmse = float(np.sqrt(np.mean((F[k0] - R[k0]) ** 2)))
    res.saturated = float(np.mean((res.tau_cmd <= 0.0) | (res.tau_cmd >= res.tau_max)))
    contact = F > 0.05
    if sc.controller != "pi" and contact.any():
        err = np.degrees(res.q_hat[contact] - res.q_true[contact])
        res.q_rmse_deg = np.sqrt(np.mean(err**2, axis=0)).tolist()
    if sc.reference == "sine":
        return
    a, b, c = sc.levels
    t1, t2 = sc.step_times
    T = sc.duration
    segs = [(sc.settle, t1, a), (t1, t2, b), (t2, T, c)] if sc.reference == "step" else [(sc.settle, t1, a),
                                                                                           (t1 + 1.0, T, b)]
    segs = [(lo, min(hi, T), v) for lo, hi, v in segs if min(hi, T) - lo > 0.25]
    sse = []
    for lo, hi, v in segs:
        win = (t >= hi - 0.2) & (t < hi)
        sse.append(abs(float(np.mean(F[win])) - v) / v)
    res.steady_state_error = max(sse) if sse else None
    if sc.reference != "step" or T - t1 < 0.25:
        return
    over = []
    for lo, hi, prev, new in ((t1, min(t2, T), a, b), (t2, T, b, c)):
        k = (t >= lo) & (t < hi)
        if hi - lo < 0.25:
            continue
        seg = F[k]
        ex = float(seg.max()) - new if new > prev else new - float(seg.min())
        over.append(max(0.0, ex) / abs(new - prev))
    res.overshoot = max(over)
    k = (t >= t1) & (t < min(t2, T))
    F_up, t_up = F[k], t[k]
    lo, hi = a + 0.1 * (b - a), a + 0.9 * (b - a)
    if (F_up >= hi).any():
        res.rise_time_s = float(t_up[np.argmax(F_up >= hi)] - t_up[np.argmax(F_up >= lo)])


def _batch_step_caller(step, label: str, compiled: bool):
    """S (B, ns), WY (B, nw) -> S_next (B, ns): one filter step of B filters of the same model, in one call
    of compiled C (cached, :class:`~alpes_dyn.simulation.integrate.CompiledStepLoop`) when possible, else CasADi's
    virtual machine (one call per filter)."""
    if compiled:
        from ..simulation.integrate import CompiledStepLoop, CompilerError

        try:
            loop = CompiledStepLoop(step, label, threads=1, vectorize=False)
        except CompilerError:
            loop = None
        if loop is not None:
            run = loop.run

            def call(S: np.ndarray, WY: np.ndarray) -> np.ndarray:
                return run(S, WY[:, None, :])[:, 1]

            return call

    def call_vm(S: np.ndarray, WY: np.ndarray) -> np.ndarray:
        return np.stack([np.asarray(step(s, wy)).reshape(-1) for s, wy in zip(S, WY)])

    return call_vm


def _step_caller(step, label: str, compiled: bool):
    """s, wy -> s_next for one filter step (:func:`_batch_step_caller` with B = 1)."""
    batch = _batch_step_caller(step, label, compiled)

    def call(s: np.ndarray, wy: np.ndarray) -> np.ndarray:
        return batch(s[None], wy[None])[0]

    return call


def _plant_and_params(sc: Any) -> tuple[Any, HandParams, HandParams]:
    """MuJoCo (one line naming the extra if it is missing), the controller's and the plant's parameters
    (the plant's default: the controller's), both turned palm down."""
    try:
        import mujoco
    except ImportError:
        raise ModelError("the control loop's plant needs mujoco (pip install 'alpes_dyn[mujoco]')") from None
    p = sc.params if isinstance(sc.params, HandParams) else load_params(sc.params)
    pp = sc.plant_params if isinstance(sc.plant_params, HandParams) else (
        load_params(sc.plant_params) if sc.plant_params is not None else p)
    return mujoco, palm_down_params(p), palm_down_params(pp)


def run_control(controller: str = "sensor", scenario: ControlScenario | None = None, **overrides: Any) -> ControlResult:
    """Run the closed loop: MuJoCo plant, the hand's sensors, the EKF and a force controller.

    Parameters
    ----------
    controller: one of :data:`CONTROLLERS`.
    scenario: the settings (default :class:`ControlScenario`); ``overrides`` replace fields, e.g.
        ``run_control("sensor", reference="sine", duration=4.0, plant_params="plant.toml")``.

    Returns
    -------
    :class:`ControlResult` with the traces and the metrics.

    Raises
    ------
    InputError: bad settings. ModelError: MuJoCo missing (one line naming the ``[mujoco]`` extra) or
    an unreadable parameter file.
    """
    sc = dataclasses.replace(scenario or ControlScenario(), controller=controller, **overrides)
    sc.check()
    mujoco, p, pp = _plant_and_params(sc)
    n = 2 if sc.model == "finger2" else 3
    cq = tuple(sc.contact_q[:n])
    model = Model.alpes(sc.model, params=p)
    plant_model = Model.alpes(sc.model, params=pp)
    mj = load_mujoco(mjcf_string(sc.model, pp, friction=True, scene="block", contact_q=cq,
                                 timestep=sc.dt / sc.substeps))
    d = mujoco.MjData(mj)
    perm = joint_permutation(mj, model.joint_names)
    normal = block_normal(cq)  # the block's face normal: the fingertip presses along it
    tr = model.transmission
    rng = np.random.default_rng(sc.seed)
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    F_ref = reference_profile(sc.reference, t, sc.levels, sc.sine, sc.step_times)

    # the plant starts at rest: the finger hanging on its springs, motor off
    q0 = static_equilibrium(plant_model, np.zeros(plant_model.n))
    d.qpos[perm] = q0
    mujoco.mj_forward(mj, d)
    s_enc = mj.sensor("encoder_finger").adr[0]
    s_frc = mj.sensor("torque_finger").adr[0]
    s_touch = mj.sensor("flexiforce_finger").adr[0]

    # observer: the library's EKF, motor torque and contact force as known inputs, encoder measured
    use_obs = sc.controller != "pi"
    step = 2 * np.pi / tr.counts_per_rev
    if use_obs:
        ss = StateSpace(model, input="motor", output="encoder", force=True)
        est_sc = EstimationScenario(torque_noise=sc.torque_noise, encoder_noise_counts=sc.encoder_noise_counts)
        meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
        noise = default_noise(est_sc, n, 1, 0, meas_var)
        f_var = (sc.force_noise**2 + sc.force_resolution**2 / 12) if sc.controller == "sensor" else 0.05**2
        noise["input_noise"] = [sc.torque_noise**2] + [f_var] * 3
        ekf = make_observer("ekf", ss, sc.dt, **noise)
        z0 = np.concatenate([static_equilibrium(model, np.zeros(n)), np.zeros(n)])
        P0 = np.array([0.05**2] * n + [0.1**2] * n)
        s = np.concatenate([z0, np.diag(P0).reshape(-1, order="F")])
        fstep = _step_caller(ekf.filter_step, f"ekf_force_{sc.model}", sc.compiled)
    ctl = ForceController(sc.controller, model, normal, sc.dt, p.tau_max, **{**DEFAULT_GAINS[sc.controller], **sc.gains})

    out_F_true = np.empty(N)
    out_F_meas = np.empty(N)
    out_F_hat = np.empty(N)
    out_q = np.empty((N, n))
    out_qh = np.full((N, n), np.nan)
    out_tau = np.empty(N)
    out_tau_meas = np.empty(N)
    enc_noise = sc.encoder_noise_counts * step * rng.standard_normal(N + 1)
    trq_noise = sc.torque_noise * rng.standard_normal(N)
    frc_noise = sc.force_noise * rng.standard_normal(N)
    alpha = sc.dt / (sc.force_filter_s + sc.dt)
    F_filt = 0.0
    tau_meas_prev = 0.0
    sd = d.sensordata
    t_wall = time.perf_counter()
    for k in range(N):
        # sensors at t_k
        out_q[k] = d.qpos[perm]
        F_true = float(sd[s_touch])
        F_meas = max(0.0, round((F_true + frc_noise[k]) / sc.force_resolution) * sc.force_resolution)  # reads >= 0
        y = round((float(sd[s_enc]) + enc_noise[k]) / step) * step
        # observer update with the previous period's inputs and this encoder reading
        if use_obs:
            F_in = F_meas if sc.controller == "sensor" else F_filt
            if k > 0:
                s = fstep(s, np.concatenate([[tau_meas_prev], -F_in * normal, [y]]))
            q_hat = s[:n]
            if sc.controller == "sensorless":
                F_est = static_contact_force(model, q_hat, np.array([tau_meas_prev]), normal)
                F_filt += alpha * (max(F_est, 0.0) - F_filt)
                F_fb = F_filt
            else:
                F_fb = F_meas
            out_qh[k] = q_hat
        else:
            q_hat, F_fb = None, F_meas
        tau = ctl.update(float(F_ref[k]), F_fb, q_hat)
        d.ctrl[0] = tau
        for _ in range(sc.substeps):
            mujoco.mj_step(mj, d)
        tau_meas_prev = float(sd[s_frc]) + trq_noise[k]  # the current sensor over the period
        out_F_true[k], out_F_meas[k], out_F_hat[k] = F_true, F_meas, F_fb
        out_tau[k], out_tau_meas[k] = tau, tau_meas_prev
    wall = time.perf_counter() - t_wall
    res = ControlResult(scenario=sc, t=t, F_ref=F_ref, F_true=out_F_true, F_meas=out_F_meas, F_hat=out_F_hat,
                        q_true=out_q, q_hat=out_qh, tau_cmd=out_tau, tau_meas=out_tau_meas,
                        joint_names=model.joint_names, tau_max=p.tau_max, wall_s=wall)
    _metrics(res)
    return res


# ----------------------------------------------------------------------------- the whole hand
#: Default references of :func:`run_hand_control` per chain, N: (before, after) the step at ``step_time``.
#: Within what each fingertip holds on the :data:`~alpes_dyn.model.mjcf.CYLINDER` (the five motor torques ramped from 0
#: to 0.05 N m over 4 s, palm down: the fingers' pads slide around the cylinder beyond 0.47-0.65 N, the thumb's
#: beyond 1.48 N).
HAND_LEVELS: dict[str, tuple[float, float]] = {
    "index": (0.25, 0.4), "middle": (0.2, 0.35), "ring": (0.3, 0.4), "little": (0.25, 0.35), "thumb": (0.4, 0.7),
}
#: :class:`ForceController` settings of the hand's loops over :data:`DEFAULT_GAINS` (then the scenario's
#: ``gains``): a slower approach (15 mN m/s; at 30 mN m/s the fingertips reach the cylinder faster and bounce on
#: it for 0.3 s) and, for the model-based loops, a 40 ms prefilter, the shortest of {25, 30, 40, 50} ms with the
#: fingers' overshoots near 10 % on :data:`HAND_LEVELS` (seed 0): with 25 ms (the block's) the middle finger's pad
#: slips on the curved surface at the up-step and its force falls to 0 (overshoot 175 %), with 30 ms 18 %; with
#: 40 ms 7-10.5 %, 10-90 % rise 77-97 ms.
HAND_GAINS: dict[str, float] = {"approach_rate": 0.015, "prefilter_s": 0.04}


def _rotation(axis: Sequence[float], angle: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * K @ K


def hand_chains(params: HandParams) -> tuple[str, ...]:
    """The hand's flexion chains, one motor each: the fingers of the parameter file, then ``"thumb"``."""
    return (*params.finger_names, "thumb")


def chain_frame(params: HandParams, chain: str, abduction: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), p (3,)): orientation and position (m) of a chain's base frame -- its first flexion joint's
    frame at q = 0, the frame of a standalone finger model -- in the palm frame, the thumb at the
    ab/adduction angle ``abduction`` (rad). A finger's frame is the palm's, translated; the thumb's is
    turned by ``palm.thumb_yaw`` about z, then by ``abduction`` about ``thumb.abduction_axis``."""
    if chain in params.finger_names:
        x, y = params.finger_xy[list(params.finger_names).index(chain)]
        return np.eye(3), np.array([x, y, 0.0])
    if chain == "thumb":
        R = _rotation((0.0, 0.0, 1.0), params.thumb_yaw) @ _rotation(params.abduction_axis, float(abduction))
        return R, np.asarray(params.thumb_xyz, dtype=float).copy()
    raise InputError(f"chain: unknown chain {chain!r} (expected one of {', '.join(hand_chains(params))})")


def chain_model(params: HandParams, chain: str, abduction: float = 0.0) -> Model:
    """The controller's model of one chain of the hand: ``finger3`` for a finger; for the thumb's flexion
    chain (the ab/adduction held at ``abduction``, rad) a two-phalanx finger with the ``[thumb]`` table's
    values. Gravity is the parameter file's, expressed in the chain's base frame (R^T g,
    :func:`chain_frame`), so that the chain's G(q), J(q) and encoder are the hand's on its joints."""
    R, _ = chain_frame(params, chain, abduction)
    g = R.T @ np.asarray(params.gravity, dtype=float)
    if chain == "thumb":
        return Model.alpes("finger2", params=dataclasses.replace(params, finger=params.thumb, gravity=g))
    return Model.alpes("finger3", params=dataclasses.replace(params, gravity=g), chain=chain)  # the finger's own values


def cylinder_normal(model: Model, q: np.ndarray, center: Sequence[float], axis: Sequence[float] = (0.0, 1.0, 0.0),
                    tip: str | None = None) -> np.ndarray:
    """Unit normal n (3,) of a cylinder's surface at the fingertip, the model's base frame: from the tip frame
    (the centre of the fingertip's rounded end) toward the cylinder's axis, the direction the fingertip
    presses in. ``center``: a point of the axis, ``axis``: its direction (base frame, m)."""
    a = _normal(axis)
    d = np.asarray(center, dtype=float) - model.fingertip_position(q, tip)
    d = d - a * (d @ a)
    nd = float(np.linalg.norm(d))
    if not nd > 0:
        raise InputError("q: the fingertip is on the cylinder's axis; the normal is undefined")
    return d / nd


@dataclass(frozen=True)
class HandControlScenario:
    """Settings of :func:`run_hand_control` (SI units): the hand grasping the cylinder, one force loop per motor.

    The plant: MuJoCo stepping the hand's MJCF with the ``"cylinder"`` scene (:data:`~alpes_dyn.model.mjcf.CYLINDER`,
    fixed and frictionless), contact and joint stops on, joint friction on, palm down (the fingers flex with
    gravity toward the cylinder under the palm), at ``dt / substeps``; its parameters ``plant_params``
    (default: the controller's). Each chain (:func:`hand_chains`) has its own loop of :class:`ForceController`
    (``controller``, :data:`DEFAULT_GAINS` overridden by :data:`HAND_GAINS`, then by ``gains``), its own EKF on its own encoder (the
    model of :func:`chain_model`) and its own FlexiForce, with the sensors of :class:`ControlScenario`
    (``encoder_noise_counts``, ``torque_noise``, ``force_noise``, ``force_resolution``), at 1 kHz; the
    contact normal of the feedforward and of the EKF's force input is the cylinder's at the estimated
    fingertip (:func:`cylinder_normal`).

    The thumb's ab/adduction starts at 0 (beside the palm); a PD on its encoder (``abduction_kp`` N m/rad,
    ``abduction_kd`` N m s/rad on the encoder's difference low-passed over ``abduction_filter_s`` s) brings it to
    ``thumb_abduction`` rad, where the thumb's pad faces the cylinder.

    References: ``levels[chain]`` = (before, after) the step at ``step_time`` s (default :data:`HAND_LEVELS`);
    metrics (per chain, as :class:`ControlResult`) after ``settle`` s.
    """

    controller: str = "sensor"
    duration: float = 3.5
    step_time: float = 2.5
    settle: float = 1.7
    levels: Any = field(default=None, compare=False)
    dt: float = 1e-3
    substeps: int = 4
    seed: int = 0
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    force_noise: float = 0.005
    force_resolution: float = 4.4 / 1024
    force_filter_s: float = 0.01
    thumb_abduction: float = math.radians(35.0)
    abduction_kp: float = 0.5
    abduction_kd: float = 0.01
    abduction_filter_s: float = 0.01
    compiled: bool = True
    gains: dict = field(default_factory=dict, compare=False)
    params: Any = field(default=None, compare=False)
    plant_params: Any = field(default=None, compare=False)

    def check(self, chains: Sequence[str] | None = None) -> None:
        if self.controller not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.controller!r} "
                             f"(expected one of {', '.join(CONTROLLERS)})")
        for name in ("duration", "step_time", "settle", "dt", "thumb_abduction", "abduction_kp", "abduction_kd",
                     "abduction_filter_s"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"{name}: expected a finite number, got {v!r}")
        for name in ("abduction_kp", "abduction_kd", "abduction_filter_s"):
            if getattr(self, name) < 0:
                raise InputError(f"{name}: expected a number >= 0, got {getattr(self, name)!r}")
        if self.dt <= 0 or self.duration <= 0:
            raise InputError(f"{'dt' if self.dt <= 0 else 'duration'}: expected a positive number of seconds")
        check_duration(self.duration, "duration")
        check_bytes(8.0 * self.duration / self.dt * _SAMPLE_ARRAYS * 5, "duration",
                    f"{self.duration:g} s at dt = {self.dt:g} s")
        if not (0.0 <= self.settle and self.settle + 0.25 <= self.step_time and self.step_time + 0.25 <= self.duration):
            raise InputError(f"step_time: expected settle + 0.25 s <= step_time <= duration - 0.25 s (the metrics' "
                             f"windows), got settle {self.settle:g}, step_time {self.step_time:g}, duration "
                             f"{self.duration:g}")
        if not isinstance(self.substeps, int) or isinstance(self.substeps, bool) or self.substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {self.substeps!r}")
        if chains is not None:
            lv = HAND_LEVELS if self.levels is None else self.levels
            if not isinstance(lv, dict):
                raise InputError(f"levels: expected a dict chain -> (before, after) in N, got {type(lv).__name__}")
            unknown = sorted(set(lv) - set(chains))
            if unknown:
                raise InputError(f"levels: unknown chain {unknown[0]!r} (expected {', '.join(chains)})")
            for c in chains:
                if c not in lv:
                    raise InputError(f"levels: no reference for chain {c!r}")
                v = np.asarray(lv[c], dtype=float) if np.ndim(lv[c]) == 1 else np.array([np.nan])
                if v.shape != (2,) or not np.isfinite(v).all() or (v <= 0).any():
                    raise InputError(f"levels: {c!r} expects two positive forces (before, after) in N, got {lv[c]!r}")


@dataclass
class HandControlResult:
    """One run of :func:`run_hand_control`.

    Attributes
    ----------
    t: (N,) times, s.
    chains: chain name -> the :class:`ControlResult` of its loop, traces and metrics. Its ``scenario`` is a
        :class:`ControlScenario` with the chain's levels (a, b, b), step times (step_time, duration) and
        ``model`` ``"finger3"`` for a finger, ``"finger2"`` for the thumb's chain model.
    q_abduction: (N,) the thumb's ab/adduction angle, rad.
    wall_s: wall time of the loop, s.
    """

    scenario: HandControlScenario
    t: np.ndarray
    chains: dict[str, ControlResult]
    q_abduction: np.ndarray
    wall_s: float

    @property
    def realtime_ratio(self) -> float:
        """Simulated time / wall time of the loop (> 1: faster than real time)."""
        return float(self.scenario.duration / self.wall_s)

    def table(self) -> list[dict[str, Any]]:
        """One row per chain: ``chain``, ``F_ref`` (the last level, N), ``F_held`` (mean MuJoCo force over the
        last 200 ms, N), ``steady_state_error``, ``overshoot`` (fractions), ``rise_time_s``, ``force_rmse`` (N),
        ``q_rmse_deg`` (the observer's worst joint during contact, deg; None for ``pi``), ``saturated``."""
        rows = []
        for c, r in self.chains.items():
            late = r.t >= r.t[-1] - 0.2 + 0.5 * (r.t[1] - r.t[0])
            rows.append({"chain": c, "F_ref": float(r.F_ref[-1]), "F_held": float(np.mean(r.F_true[late])),
                         "steady_state_error": r.steady_state_error, "overshoot": r.overshoot,
                         "rise_time_s": r.rise_time_s, "force_rmse": r.force_rmse,
                         "q_rmse_deg": None if r.q_rmse_deg is None else max(r.q_rmse_deg), "saturated": r.saturated})
        return rows

    def to_csv(self, path: str) -> None:
        """Write one row per sample: t, then per chain F_ref, F_z measured by MuJoCo's sensor, the FlexiForce
        reading, the force fed back, true and estimated q, motor torque command and measurement (columns
        prefixed by the chain's name), then the thumb's ab/adduction angle."""
        head, cols = ["t_s"], [self.t]
        for c, r in self.chains.items():
            head += [f"{c}_F_ref_N", f"{c}_F_mujoco_N", f"{c}_F_flexiforce_N", f"{c}_F_feedback_N"]
            head += [f"q_true_{j}_rad" for j in r.joint_names] + [f"q_hat_{j}_rad" for j in r.joint_names]
            head += [f"{c}_tau_cmd_Nm", f"{c}_tau_meas_Nm"]
            cols += [r.F_ref, r.F_true, r.F_meas, r.F_hat, r.q_true, r.q_hat, r.tau_cmd, r.tau_meas]
        head.append("q_thumb_abd_rad")
        cols.append(self.q_abduction)
        rows = np.column_stack(cols)
        with atomic_path(path, "--log") as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            w.writerows([[f"{x:.9g}" for x in r] for r in rows])

    def to_dict(self) -> dict[str, Any]:
        """A JSON summary: the controller, the plant, per-chain metrics (:meth:`table`), the wall time."""
        sc = self.scenario
        return {"controller": sc.controller, "plant": "mujoco", "model": "hand", "scene": "cylinder",
                "duration_s": sc.duration, "dt_s": sc.dt, "seed": sc.seed, "chains": self.table(),
                "thumb_abduction_rad": sc.thumb_abduction, "realtime_ratio": self.realtime_ratio}


def run_hand_control(controller: str = "sensor", scenario: HandControlScenario | None = None,
                     **overrides: Any) -> HandControlResult:
    """The whole hand grasping the cylinder in MuJoCo: one force loop, one EKF per motor (issue 9, item 5).

    Each chain (the four fingers and the thumb's flexion) runs the loop of :func:`run_control` on its own
    sensors -- encoder, motor torque, FlexiForce -- with its own :class:`ForceController` and, for the
    model-based controllers, its own EKF on :func:`chain_model`; the contact normal is the cylinder's at the
    estimated fingertip (:func:`cylinder_normal`). The EKFs of chains with the same model (the four fingers)
    advance in one call of compiled code. See :class:`HandControlScenario` for the settings.

    Returns
    -------
    :class:`HandControlResult`.

    Raises
    ------
    InputError: bad settings. ModelError: MuJoCo missing (one line naming the ``[mujoco]`` extra) or an
    unreadable parameter file.
    """
    sc = dataclasses.replace(scenario or HandControlScenario(), controller=controller, **overrides)
    sc.check()
    mujoco, p, pp = _plant_and_params(sc)
    from ..model.mjcf import CYLINDER

    chains = hand_chains(p)
    sc.check(chains)
    if not p.abduction_lower <= sc.thumb_abduction <= p.abduction_upper:
        raise InputError(f"thumb_abduction: {sc.thumb_abduction:g} rad is outside the ab/adduction range "
                         f"[{p.abduction_lower:g}, {p.abduction_upper:g}] rad")
    levels = HAND_LEVELS if sc.levels is None else sc.levels
    mj = load_mujoco(mjcf_string("hand", pp, friction=True, scene="cylinder", timestep=sc.dt / sc.substeps))
    d = mujoco.MjData(mj)
    sd = d.sensordata
    N = int(round(sc.duration / sc.dt))
    t = sc.dt * np.arange(N)
    rng = np.random.default_rng(sc.seed)
    use_obs = sc.controller != "pi"
    gains = {**DEFAULT_GAINS[sc.controller], **HAND_GAINS, **sc.gains}
    center = np.asarray(CYLINDER["center"], dtype=float)

    # per chain: the controller's model, the plant's initial state, sensors, the cylinder in the chain's frame
    C = []
    for c in chains:
        m = chain_model(p, c, sc.thumb_abduction)
        R, pos = chain_frame(p, c, sc.thumb_abduction)
        names = [f"{c}_{j}" for j in m.joint_names]
        perm = joint_permutation(mj, names)
        q0 = static_equilibrium(chain_model(pp, c, sc.thumb_abduction), np.zeros(m.n))
        d.qpos[perm] = q0
        a, b = (float(x) for x in levels[c])
        C.append(dict(name=c, model=m, n=m.n, perm=perm, names=tuple(names), center=R.T @ (center - pos),
                      axis=R.T @ np.array([0.0, 1.0, 0.0]), F_ref=np.where(t < sc.step_time, a, b), levels=(a, b),
                      enc=mj.sensor(f"encoder_{c}").adr[0], frc=mj.sensor(f"torque_{c}").adr[0],
                      touch=mj.sensor(f"flexiforce_{c}").adr[0], act=mj.actuator(c).id, z0=q0))
    abd_q = mj.joint("thumb_abd").qposadr[0]
    abd_act = mj.actuator("thumb_abduction").id
    abd_enc = mj.sensor("encoder_thumb_abduction").adr[0]
    d.qpos[abd_q] = 0.0
    mujoco.mj_forward(mj, d)
    step = 2 * np.pi / C[0]["model"].transmission.counts_per_rev

    # observers: one EKF per chain, those of the same model advanced together
    groups: dict[str, list[int]] = {}
    callers = {}
    S: list[np.ndarray] = []
    if use_obs:
        est_sc = EstimationScenario(torque_noise=sc.torque_noise, encoder_noise_counts=sc.encoder_noise_counts)
        meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
        f_var = (sc.force_noise**2 + sc.force_resolution**2 / 12) if sc.controller == "sensor" else 0.05**2
        for i, ch in enumerate(C):
            n = ch["n"]
            ss = StateSpace(ch["model"], input="motor", output="encoder", force=True)
            noise = default_noise(est_sc, n, 1, 0, meas_var)
            noise["input_noise"] = [sc.torque_noise**2] + [f_var] * 3
            fstep = make_observer("ekf", ss, sc.dt, **noise).filter_step
            key = fstep.serialize()
            if key not in callers:
                callers[key] = _batch_step_caller(fstep, f"ekf_force_hand_{ch['model'].name}", sc.compiled)
            groups.setdefault(key, []).append(i)
            z0 = np.concatenate([static_equilibrium(ch["model"], np.zeros(n)), np.zeros(n)])
            P0 = np.diag([0.05**2] * n + [0.1**2] * n)
            S.append(np.concatenate([z0, P0.reshape(-1, order="F")]))
    ctls = [ForceController(sc.controller, ch["model"], cylinder_normal(ch["model"], ch["z0"], ch["center"], ch["axis"]),
                            sc.dt, p.tau_max, **gains) for ch in C]

    nc = len(C)
    out = {k: np.empty((nc, N)) for k in ("F_true", "F_meas", "F_hat", "tau", "tau_meas")}
    out_q = [np.empty((N, ch["n"])) for ch in C]
    out_qh = [np.full((N, ch["n"]), np.nan) for ch in C]
    q_abd = np.empty(N)
    enc_noise = sc.encoder_noise_counts * step * rng.standard_normal((nc + 1, N))
    trq_noise = sc.torque_noise * rng.standard_normal((nc, N))
    frc_noise = sc.force_noise * rng.standard_normal((nc, N))
    alpha = sc.dt / (sc.force_filter_s + sc.dt)
    a_v = sc.dt / (sc.abduction_filter_s + sc.dt)
    F_filt = np.zeros(nc)
    tau_meas_prev = np.zeros(nc)
    F_in_prev = np.zeros(nc)
    normals = [ctl.normal.copy() for ctl in ctls]
    y_abd_prev, v_abd = None, 0.0
    res = sc.force_resolution
    t_wall = time.perf_counter()
    for k in range(N):
        y = np.empty(nc)
        F_meas = np.empty(nc)
        for i, ch in enumerate(C):
            out_q[i][k] = d.qpos[ch["perm"]]
            F_true = float(sd[ch["touch"]])
            out["F_true"][i, k] = F_true
            F_meas[i] = max(0.0, round((F_true + frc_noise[i, k]) / res) * res)
            y[i] = round((float(sd[ch["enc"]]) + enc_noise[i, k]) / step) * step
        if use_obs and k > 0:
            for key, idx in groups.items():
                WY = np.stack([np.concatenate([[tau_meas_prev[i]], -F_in_prev[i] * normals[i], [y[i]]]) for i in idx])
                S_next = callers[key](np.stack([S[i] for i in idx]), WY)
                for j, i in enumerate(idx):
                    S[i] = S_next[j]
        for i, ch in enumerate(C):
            if use_obs:
                q_hat = S[i][: ch["n"]]
                out_qh[i][k] = q_hat
                normals[i] = cylinder_normal(ch["model"], q_hat, ch["center"], ch["axis"])
                if sc.controller == "sensorless":
                    F_est = static_contact_force(ch["model"], q_hat, np.array([tau_meas_prev[i]]), normals[i])
                    F_filt[i] += alpha * (max(F_est, 0.0) - F_filt[i])
                    F_fb = F_filt[i]
                else:
                    F_fb = F_meas[i]
                F_in_prev[i] = F_fb
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, q_hat, normal=normals[i])
            else:
                F_fb = F_meas[i]
                tau = ctls[i].update(float(ch["F_ref"][k]), F_fb, None)
            d.ctrl[ch["act"]] = tau
            out["F_meas"][i, k], out["F_hat"][i, k], out["tau"][i, k] = F_meas[i], F_fb, tau
        # the thumb's ab/adduction: PD on its encoder
        y_abd = round((float(sd[abd_enc]) + enc_noise[nc, k]) / step) * step / p.abduction_ratio
        if y_abd_prev is not None:
            v_abd += a_v * ((y_abd - y_abd_prev) / sc.dt - v_abd)
        y_abd_prev = y_abd
        q_abd[k] = d.qpos[abd_q]
        u = sc.abduction_kp * (sc.thumb_abduction - y_abd) - sc.abduction_kd * v_abd
        d.ctrl[abd_act] = min(max(u, -p.tau_max), p.tau_max)
        for _ in range(sc.substeps):
            mujoco.mj_step(mj, d)
        for i, ch in enumerate(C):
            tau_meas_prev[i] = float(sd[ch["frc"]]) + trq_noise[i, k]
        out["tau_meas"][:, k] = tau_meas_prev
    wall = time.perf_counter() - t_wall

    results = {}
    for i, ch in enumerate(C):
        a, b = ch["levels"]
        csc = ControlScenario(model="finger2" if ch["n"] == 2 else "finger3", controller=sc.controller,
                              reference="step", duration=sc.duration, dt=sc.dt, substeps=sc.substeps, seed=sc.seed,
                              levels=(a, b, b), step_times=(sc.step_time, sc.duration), settle=sc.settle,
                              encoder_noise_counts=sc.encoder_noise_counts, torque_noise=sc.torque_noise,
                              force_noise=sc.force_noise, force_resolution=sc.force_resolution,
                              force_filter_s=sc.force_filter_s, compiled=sc.compiled, gains=sc.gains,
                              params=sc.params, plant_params=sc.plant_params)
        r = ControlResult(scenario=csc, t=t, F_ref=ch["F_ref"], F_true=out["F_true"][i], F_meas=out["F_meas"][i],
                          F_hat=out["F_hat"][i], q_true=out_q[i], q_hat=out_qh[i], tau_cmd=out["tau"][i],
                          tau_meas=out["tau_meas"][i], joint_names=ch["names"], tau_max=p.tau_max, wall_s=wall)
        _metrics(r)
        results[ch["name"]] = r
    return HandControlResult(scenario=sc, t=t, chains=results, q_abduction=q_abd, wall_s=wall)


def _save_figure(fig: Any, plt: Any, path: str) -> None:
    """Lay ``fig`` out and write it to ``path`` (PNG, whole or not at all); close it."""
    fig.tight_layout()
    try:
        with atomic_path(path, "--plot") as tmp:
            fig.savefig(tmp, dpi=110)
    finally:
        plt.close(fig)


def plot_hand_control(result: HandControlResult, path: str) -> None:
    """Write a figure (PNG): per chain, the F_z reference and MuJoCo's force; the motor torques. Needs matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("--plot: matplotlib is not installed (pip install matplotlib)") from None
    n = len(result.chains)
    fig, axes = plt.subplots(n + 1, 1, figsize=(9, 1.6 * (n + 1) + 0.8), sharex=True)
    for i, (ax, (c, r)) in enumerate(zip(axes, result.chains.items())):
        ax.plot(r.t, r.F_ref, "k--", lw=1.0)
        ax.plot(r.t, r.F_true, color=f"C{i}", lw=1.0)
        ax.set_ylim(0.0, 1.5 * float(np.max(r.F_ref)))
        ax.set_ylabel(f"{c}\nF_z [N]")
        axes[-1].plot(r.t, r.tau_cmd, color=f"C{i}", lw=0.8, label=c)
    axes[0].set_title(f"the hand on the cylinder, {result.scenario.controller} loops (dashed: references)", fontsize=9)
    axes[-1].axhline(next(iter(result.chains.values())).tau_max, color="gray", ls=":", lw=0.8)
    axes[-1].set_ylabel("tau_m [N m]")
    axes[-1].set_xlabel("time [s]")
    axes[-1].legend(loc="upper left", fontsize=7, ncol=n)
    _save_figure(fig, plt, path)


def plot_control(result: ControlResult, path: str) -> None:
    """Write a figure (PNG): F_z reference, MuJoCo's and the fed-back force; motor torque; joints true and
    estimated (degrees). Needs matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise InputError("--plot: matplotlib is not installed (pip install matplotlib)") from None
    r = result
    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax = axes[0]
    ax.plot(r.t, r.F_ref, "k--", lw=1.2, label="reference")
    ax.plot(r.t, r.F_hat, color="C1", lw=0.6, alpha=0.7, label="fed back")
    ax.plot(r.t, r.F_true, color="C0", lw=1.2, label="MuJoCo touch sensor")
    ax.set_ylabel("F_z [N]")
    ax.legend(loc="upper right", fontsize=8, ncol=3)
    ax.set_title(f"{r.scenario.model}, {r.scenario.controller} controller: force RMSE {r.force_rmse:.3f} N", fontsize=9)
    ax = axes[1]
    ax.plot(r.t, r.tau_cmd, color="C2", lw=1.0, label="command")
    ax.axhline(r.tau_max, color="gray", ls=":", lw=0.8, label="tau_max")
    ax.set_ylabel("tau_m [N m]")
    ax.legend(loc="upper right", fontsize=8)
    ax = axes[2]
    for i, j in enumerate(r.joint_names):
        ax.plot(r.t, np.degrees(r.q_true[:, i]), color=f"C{i}", lw=1.2, label=f"{j} true")
        if np.isfinite(r.q_hat[:, i]).any():
            ax.plot(r.t, np.degrees(r.q_hat[:, i]), "--", color=f"C{i}", lw=1.0, label=f"{j} EKF")
    ax.set_ylabel("q [deg]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right", fontsize=8, ncol=2)
    _save_figure(fig, plt, path)
