"""Fingertip force controllers, one motor each: the static balance and the loops that track F_z.

Static balance (eq. 2.11 at rest): G(q) = S^T tau_m + J(q)^T F with the contact force on the finger
F = -F_z n, n the unit normal of the object's surface (base frame, pointing from the fingertip into
the object: the direction it presses in; F_z >= 0 the pressing force). With one motor for several joints the
balance is solved in the least-squares sense over the joints:

* :func:`static_motor_torque` -- the tendon torque that holds F_z against springs and gravity,
  tau_m = S (G(q) + F_z J^T n) / (S S^T);
* :func:`static_contact_force` -- the contact force that balances a motor torque,
  F_z = -(J^T n) . (G(q) - S^T tau_m) / |J^T n|^2.

Controllers (:data:`CONTROLLERS`), one motor each, at 1 kHz:

* ``"sensor"`` -- feedforward :func:`static_motor_torque` at q_hat for the reference, plus a PI on
  the measured F_z, in a two-degree-of-freedom structure: the feedforward and the integral follow the
  reference through a first-order prefilter (``prefilter_s``, 25 ms; ``release_s``, 50 ms, while the
  reference falls), the proportional term acts on the
  raw reference (set-point weight ``setpoint_weight`` = 1). A torque step at the static balance would make
  the fingertip roll on the object (the passive joints redistribute through a lightly damped mode, about
  5 Hz, and the force overshoots); the prefilter brings the model's torque in at the pace of that motion,
  while the proportional term reacts at once as the baseline does and the integral, fed the prefiltered
  error, can be 3 times the baseline's (the overshoot under 10 %). The EKF gets the measured contact force as a
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

The closed loops that run them: :mod:`alpes_dyn.control.finger_loop` (a finger on a block) and
:mod:`alpes_dyn.control.hand_loop` (the hand on a cylinder).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..errors import InputError
from ..model.robot import Model


CONTROLLERS: tuple[str, ...] = ("sensor", "sensorless", "pi")
REFERENCES: tuple[str, ...] = ("step", "ramp", "sine")
DEFAULT_LEVELS: tuple[float, float, float] = (0.2, 0.6, 0.2)
"""N: the default step reference, 0.2 -> 0.6 -> 0.2 N (steps of 0.4 N up and down): the finger pressing the block
keeps its contact there on the drawn fingers of ``benchmarks/bench_loop.py``'s record; at 1.0 N the fingertip rolls
off the block on some draws of finger3 +-20 %, whatever the parameter file (the changelog gives the count)."""


#: Default settings of :class:`ForceController` per controller. The ``pi`` baseline was tuned on the block scene of
#: finger3 by one rule: on the grid kp in {0.002, 0.004, 0.006, 0.008, 0.012} N m/N x ki in {0.8, 1.2, 1.6, 2.0,
#: 2.4} N m/(N s), the lowest force RMSE on the step reference (0.2 -> 1.0 -> 0.5 N) with an overshoot below 10 % on
#: four noise draws (kp = 0.012 loses the contact); the sensor loop's kp comes from the same grid. The sensor loop's
#: 2-DOF structure is fixed before its gains: a first-order prefilter on the reference of the feedforward and the
#: integral, the proportional term on the raw reference; its time constant, 25 ms, is the shortest of {15, 20, 25}
#: ms with which the loop keeps the contact on the five plants drawn 10 % off (a shorter one is a little faster on the
#: nominal plant but loses the FlexiForce's reading on some drawn plants as the fingertip rolls). Its ki: the
#: smallest of {1.6, 2.0, 2.2, 2.4, 2.8, 3.2} whose worst 10-90 % rise on the +-20 % draws of finger3 and of the
#: hand's finger chains (the loop alone on the MuJoCo stand-in with a real hand's effects, the CLI's default step)
#: stays under 90 ms, a tenth below the goal of ``benchmarks/bench_loop.py``: the rise is the fingertip rolling
#: to its new pose (its joints move 10-20 degrees over 100 ms while the force crawls over the step's last fifth),
#: which the integral's catch-up sets, not the prefilter alone (its 25 ms are 55 ms of rise); each larger ki rises
#: faster and overshoots more, by the integral's excess once the roll ends (ki 1.6: rise up to 101 ms, overshoot
#: 7.4 %; 2.4: 89 ms, 9.1 %; 2.8: 85 ms, 9.7 %; 3.2: above 10 %). kp up to 0.010, a 2nd-order prefilter, a setpoint
#: weight below 1 or a 15-20 ms prefilter traded rise for overshoot no better. The loops with these gains:
#: ``benchmarks/results/control.json``, ``benchmarks/results/bench_loop.json``. The sensorless loop feeds back a
#: noisier, model-dependent estimate and is made slower; it declares contact once its estimate stays above 0.1 N for
#: 20 ms (the FlexiForce's loops: above 0.03 N). The sensor loop releases slower than it presses (``release_s``
#: 50 ms, the prefilter while the reference falls): unloading, the fingertip rolls back across the block, and with
#: the rise's time constant the force undershoots the lower level by a sizeable share of the step on drawn fingers
#: (the fingertip can bounce off the block); with the slower release a few percent, the rise and the up step as they
#: were.
DEFAULT_GAINS: dict[str, dict[str, float]] = {
    "sensor": {"kp": 0.008, "ki": 2.4, "prefilter_s": 0.025, "prefilter_order": 1, "setpoint_weight": 1.0,
               "release_s": 0.05},
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

    Least squares over the motor's joints of S^T tau_m = G(q) + F_z J(q)^T n (rho(q)^T where the ratios change with
    q).

    Parameters
    ----------
    model : Model
        The finger.
    q : ndarray
        (n,) joint angles, rad.
    F_z : float
        The normal force, N.
    normal : sequence of float
        n (3,), the object's surface normal (base frame) along which the fingertip presses.
    motor : int, optional
        The motor's index.
    tip : str or None, optional
        The contact frame (default: the model's first tip).

    Returns
    -------
    float
        tau_m, N m.
    """
    S = model.transmission.ratio(q)[motor]
    b = model.gravity_torque(q) + float(F_z) * (model.fingertip_jacobian(q, tip).T @ _normal(normal))
    return float(S @ b / (S @ S))


def static_contact_force(model: Model, q: np.ndarray, tau_m: np.ndarray, normal: Sequence[float],
                         tip: str | None = None) -> float:
    """Normal contact force F_z (N) that balances the motor torques tau_m (N m) at q (rad) (eq. 2.11 at rest).

    Least squares over the joints of G(q) - S^T tau_m = -F_z J(q)^T n.

    Parameters
    ----------
    model : Model
        The finger.
    q : ndarray
        (n,) joint angles, rad.
    tau_m : ndarray
        (m,) motor torques, N m.
    normal : sequence of float
        n (3,), the object's surface normal (base frame).
    tip : str or None, optional
        The contact frame (default: the model's first tip).

    Returns
    -------
    float
        F_z, N.
    """
    jn = model.fingertip_jacobian(q, tip).T @ _normal(normal)
    r = model.gravity_torque(q) - model.transmission.joint_torque(np.atleast_1d(tau_m), q)
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
    release_s: the prefilter's time constant while the reference falls below it (the finger unloading), s (None:
        ``prefilter_s``).
    setpoint_weight: weight b in [0, 1] of the raw reference in the proportional term's error
        (b F_ref + (1 - b) F_ref_filtered - F_fb; the model-based controllers only).
    loss_s: contact is lost when the force stays below the threshold this long, s.
    motor: the motor's row of S (the feedforward's torque is this motor's). tip: the contact frame (None: the
        model's default tip).
    notch_hz: the command through a notch (s^2 + w^2) / (s^2 + 2 zeta w s + w^2) at this frequency, Hz (None: no
        notch), damping ratio ``notch_zeta``: the series-elastic cable's mode on its rotor, which the proportional
        path excites (:mod:`alpes_dyn.control.realism_loop`).

    The field defaults are generic starting values, **not** the gains tuned on the block scene: build the tuned
    controller with :meth:`tuned` (:data:`DEFAULT_GAINS` of its kind), or use
    :class:`~alpes_dyn.control.step.ForceStep`, which holds it with the observer and the compensation.
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
    release_s: float | None = None
    motor: int = 0
    tip: str | None = None
    notch_hz: float | None = None
    notch_zeta: float = 0.5
    _notch: tuple | None = None
    _above: int = 0
    integral: float = 0.0
    in_contact: bool = False
    tau_prev: float = 0.0
    F_ref_f: float | None = None
    F_ref_f2: float | None = None
    _below: int = 0

    @classmethod
    def tuned(cls, kind: str, model: Model, normal: Sequence[float], dt: float, tau_max: float,
              **overrides: float) -> "ForceController":
        """The controller with the tuned settings of ``kind`` (:data:`DEFAULT_GAINS`), ``overrides`` (any field)
        replacing them: ``ForceController.tuned("sensor", model, n, 1e-3, 0.05)``.

        Parameters
        ----------
        kind : str
            One of :data:`DEFAULT_GAINS`' keys.
        model : Model
            The controller's model.
        normal : sequence of float
            (3,) the contact normal (base frame).
        dt : float
            The control period, s.
        tau_max : float
            The largest motor torque, N m.
        **overrides
            Any field, replacing its tuned value.

        Returns
        -------
        ForceController
            The controller.

        Raises
        ------
        InputError
            An unknown kind."""
        if kind not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {kind!r} (expected one of {', '.join(CONTROLLERS)})")
        return cls(kind, model, normal, dt, tau_max, **{**DEFAULT_GAINS[kind], **overrides})

    def __post_init__(self) -> None:
        if self.kind not in CONTROLLERS:
            raise InputError(f"controller: unknown controller {self.kind!r} (expected one of {', '.join(CONTROLLERS)})")
        self.normal = _normal(self.normal)
        if self.prefilter_order not in (1, 2):
            raise InputError(f"prefilter_order: expected 1 or 2, got {self.prefilter_order!r}")
        if not 0.0 <= self.setpoint_weight <= 1.0:
            raise InputError(f"setpoint_weight: expected a number in [0, 1], got {self.setpoint_weight!r}")
        r = self.release_s
        number = not isinstance(r, (bool, np.bool_)) and isinstance(r, (int, float, np.integer, np.floating))
        if r is not None and not (number and math.isfinite(r) and r >= 0):
            raise InputError(f"release_s: expected a non-negative number of seconds or None, got {r!r}")

    def feedforward(self, q_hat: np.ndarray, F_ref: float) -> float:
        """Static-balance torque at q_hat for F_ref (0 for the ``"pi"`` baseline).

        Parameters
        ----------
        q_hat : ndarray
            (n,) the estimated joint angles, rad.
        F_ref : float
            The force reference, N.

        Returns
        -------
        float
            N m.
        """
        if self.kind == "pi":
            return 0.0
        return static_motor_torque(self.model, q_hat, F_ref, self.normal, self.motor, self.tip)

    def update(self, F_ref: float, F_fb: float, q_hat: np.ndarray | None,
               normal: Sequence[float] | None = None) -> float:
        """The motor torque command (N m): :meth:`command`, through the notch at ``notch_hz`` (if any) and clipped
        to [0, tau_max] again.

        Parameters
        ----------
        F_ref : float
            The force reference, N.
        F_fb : float
            The force fed back, N.
        q_hat : ndarray or None
            (n,) the estimated joint angles, rad (None for the ``"pi"`` baseline).
        normal : sequence of float or None, optional
            (3,), from this step on, in place of :attr:`normal`.

        Returns
        -------
        float
            N m."""
        tau = self.command(F_ref, F_fb, q_hat, normal)
        if self.notch_hz is None:
            return tau
        if self._notch is None:
            self._notch = (_notch_coefficients(self.notch_hz, self.notch_zeta, self.dt), [tau, tau], [tau, tau])
        (b0, b1, b2, a1, a2), x, y = self._notch
        out = b0 * tau + b1 * x[0] + b2 * x[1] - a1 * y[0] - a2 * y[1]
        x[1], x[0], y[1], y[0] = x[0], tau, y[0], out
        return min(max(out, 0.0), self.tau_max)

    def command(self, F_ref: float, F_fb: float, q_hat: np.ndarray | None,
                normal: Sequence[float] | None = None) -> float:  # noqa: C901
        """The motor torque command (N m) before the notch for the reference F_ref and the force fed back F_fb (N).

        ``normal`` (3,), if given, replaces :attr:`normal` from this step on (a curved object: the
        surface normal at the fingertip moves with q_hat, see :func:`.cylinder_normal`).

        The model-based controllers follow the reference through a prefilter of ``prefilter_order``
        first-order stages of time constant ``prefilter_s`` (a torque step would make the fingertip roll
        on the object) for the feedforward and the integral; the proportional term acts on
        ``setpoint_weight`` x the raw reference + (1 - ``setpoint_weight``) x the prefiltered one; contact
        is lost when F_fb stays below the threshold for ``loss_s``, and the approach starts again.

        Parameters
        ----------
        F_ref : float
            The force reference, N.
        F_fb : float
            The force fed back, N.
        q_hat : ndarray or None
            (n,) the estimated joint angles, rad (None for the ``"pi"`` baseline).
        normal : sequence of float or None, optional
            (3,), from this step on, in place of :attr:`normal`.

        Returns
        -------
        float
            N m.
        """
        if normal is not None:
            self.normal = _normal(normal)
        F_raw = F_ref
        if self.kind != "pi":
            if self.F_ref_f is None:
                self.F_ref_f = self.F_ref_f2 = F_ref
            tau_f = self.release_s if self.release_s is not None and F_ref < self.F_ref_f else self.prefilter_s
            a = self.dt / (tau_f + self.dt)
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


def _notch_coefficients(f_hz: float, zeta: float, dt: float) -> tuple[float, float, float, float, float]:
    """(b0, b1, b2, a1, a2) of the notch (s^2 + w^2) / (s^2 + 2 zeta w s + w^2) at f_hz (Hz), bilinear with the
    frequency prewarped, sample period dt (s): y_k = b0 x_k + b1 x_k-1 + b2 x_k-2 - a1 y_k-1 - a2 y_k-2 (unit DC gain)."""
    w = 2.0 * math.pi * f_hz
    K = w / math.tan(w * dt / 2.0)  # prewarp: the notch exactly at f_hz
    a0 = K * K + 2 * zeta * w * K + w * w
    b0 = (K * K + w * w) / a0
    b1 = 2 * (w * w - K * K) / a0
    a2 = (K * K - 2 * zeta * w * K + w * w) / a0
    return b0, b1, b0, b1, a2


def reference_profile(kind: str, t: np.ndarray, levels: Sequence[float] = DEFAULT_LEVELS,
                      sine: Sequence[float] = (0.3, 0.8, 1.0), step_times: Sequence[float] = (1.0, 2.0)) -> np.ndarray:
    """F_z reference (N) at times t (s).

    ``"step"``: levels[0] until step_times[0], levels[1] until step_times[1], then levels[2];
    ``"ramp"``: levels[0] until step_times[0], a linear ramp to levels[1] over 1 s, then held;
    ``"sine"``: levels[0] until step_times[0], then a sine between sine[0] and sine[1] at sine[2] Hz
    starting at its mean value.

    Parameters
    ----------
    kind : {"step", "ramp", "sine"}
        The profile.
    t : ndarray
        Times, s.
    levels : sequence of float, optional
        Three levels, N.
    sine : sequence of float, optional
        The sine's low and high levels (N) and its frequency (Hz).
    step_times : sequence of float, optional
        Two times, s.

    Returns
    -------
    ndarray
        F_z reference, N, the shape of t.
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
