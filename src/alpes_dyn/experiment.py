"""The identification experiment: what to do with the hand so that its parameters can be fitted.

The documented experiment on one finger (``finger2``, ``finger3``):

* the palm held still in one or more orientations (``orientations``, gravity vectors in the base frame;
  default palm up, gravity along -z as in the report);
* the motor driven by a multisine torque, tau_m(t) = tau_b + a sum_i sin(2 pi f_i t + phi_i) / sqrt(n_f /
  2) over ``frequencies`` (default 0.3 to 11.3 Hz, Schroeder phases), so that the springs, gravity,
  inertias and friction all leave their mark on the encoder. The bias tau_b puts the nominal finger's
  mean joint angle mid-range, the amplitude a is the largest that keeps the nominal finger's static
  equilibria within its joint limits (a ``margin`` inside), both from the model the user starts with;
* the bias trimmed on the hand (``trim_bias``, default on): before recording, a slow loop on the
  measured encoder moves the bias until the finger rests where the nominal one would (the real finger,
  not the model, must sit mid-range: with springs 17 % softer than nominal the untrimmed bias drove
  q_1 past its 90 degree stop);
* optionally, at ``camera_times``, the joint angles measured once by a camera or a jig with noise
  ``camera_noise`` (rad);
* the sensors of the estimation scenario (:mod:`alpes_dyn.scenario`): encoder quantised to
  ``counts_per_rev`` with 0.5 count of Gaussian noise, motor torque with white noise of 5e-4 N m,
  sampled at 1 kHz.

Why this design (measured with :func:`~alpes_dyn.identifiability.fisher_information`, the Cramér-Rao
bounds of K, m, F_s, F_v on finger3 from 4 s of encoder data, 0.5 count of noise plus quantisation):
the estimation scenario's small torque wiggle leaves F_v_3 at 10 % and the masses at up to 0.64 %; the
multisine across the joint range brings every parameter below 0.8 % (masses 0.08-0.26 %). See the
identification user guide for the full comparison.

:func:`experiment` simulates it on a finger with given true parameters (friction included) and returns
(and writes) a :class:`~alpes_dyn.recording.Recording` with the true joint angles in ``true_q_*``.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .errors import InputError
from .model import Model
from .params import HandParams, Param, load_params, with_values
from .recording import Recording, write_recording
from .scenario import SCENARIO_MODELS, static_equilibrium
from .simulation import simulate
from .stops import JointRangeWarning

__all__ = ["ExperimentDesign", "experiment", "excitation", "perturbed_params"]


@dataclass(frozen=True)
class ExperimentDesign:
    """Settings of the identification experiment (see the module docstring); SI units."""

    duration: float = 4.0
    dt: float = 1e-3
    substeps: int = 4
    frequencies: tuple[float, ...] = (0.3, 0.7, 1.3, 2.1, 3.7, 5.3, 7.9, 11.3)
    torque_bias: float | None = None
    torque_amplitude: float | None = None
    margin: float = 0.05
    orientations: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, -9.81),)
    camera_times: tuple[float, ...] = ()
    camera_noise: float = math.radians(0.1)
    encoder_noise_counts: float = 0.5
    torque_noise: float = 5e-4
    trim_bias: bool = True
    amplitude_fraction: float = 0.6

    @property
    def n_samples(self) -> int:
        return int(round(self.duration / self.dt)) + 1

    def check(self) -> "ExperimentDesign":
        if not (math.isfinite(self.dt) and 0 < self.dt <= 0.1):
            raise InputError(f"dt: expected a sample period in (0, 0.1] s, got {self.dt!r}")
        N = round(self.duration / self.dt) if math.isfinite(self.duration) else -1
        if N < 100 or abs(N * self.dt - self.duration) > 1e-9 * self.duration:
            raise InputError(f"duration: expected a whole number of at least 100 samples of {self.dt:g} s, "
                             f"got {self.duration!r}")
        if N > 2_000_000:
            raise InputError(f"duration: {self.duration:g} s is more than 2e6 samples")
        if not isinstance(self.substeps, int) or not 1 <= self.substeps <= 64:
            raise InputError(f"substeps: expected an integer in [1, 64], got {self.substeps!r}")
        f = np.asarray(self.frequencies, dtype=float)
        if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0) or np.any(f >= 0.5 / self.dt):
            raise InputError(f"frequencies: expected positive frequencies below Nyquist, got {self.frequencies!r}")
        g = np.asarray(self.orientations, dtype=float)
        if g.ndim != 2 or g.shape[1] != 3 or g.shape[0] < 1 or not np.isfinite(g).all():
            raise InputError(f"orientations: expected gravity vectors (3 numbers each), got {self.orientations!r}")
        if not (math.isfinite(self.amplitude_fraction) and 0 < self.amplitude_fraction <= 1):
            raise InputError(f"amplitude_fraction: expected a number in (0, 1], got {self.amplitude_fraction!r}")
        for name in ("encoder_noise_counts", "torque_noise", "camera_noise", "margin"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise InputError(f"{name}: expected a non-negative number, got {v!r}")
        for t in self.camera_times:
            if not (math.isfinite(t) and 0 <= t <= self.duration):
                raise InputError(f"camera_times: {t!r} is outside [0, {self.duration:g}] s")
        return self


def _oriented(model: Model, gravity: np.ndarray) -> Model:
    """``model`` itself, or a copy of it with another gravity vector (the hand turned)."""
    return model if np.array_equal(model.gravity, gravity) else model.copy(gravity=gravity)


def _mean_equilibrium(model: Model, tau_m: float, gravity: np.ndarray) -> np.ndarray:
    m = _oriented(model, gravity)
    return static_equilibrium(m, m.transmission.joint_torque(np.array([tau_m])))


def excitation(model: Model, design: ExperimentDesign) -> tuple[float, float]:
    """(tau_b, a): the multisine's bias and amplitude for ``model`` (see the module docstring), N m."""
    lo, hi = model.lower + design.margin, model.upper - design.margin
    g0 = np.asarray(design.orientations[0], dtype=float)

    def within(tau: float) -> bool:
        try:
            return all(np.all((q >= lo) & (q <= hi)) for q in
                       (_mean_equilibrium(model, tau, np.asarray(g, dtype=float)) for g in design.orientations))
        except InputError:
            return False

    bias = design.torque_bias
    if bias is None:  # mean joint angle mid-range
        bias = _rest_torque(model, lambda q: float(np.mean(q)), float(np.mean(0.5 * (model.lower + model.upper))),
                            g0, 0.2)
    amp = design.torque_amplitude
    if amp is None:
        if not within(bias):
            raise InputError(f"torque_bias: the nominal finger's equilibrium at {bias:g} N m leaves its joint range")
        a, b = 0.0, bias
        for _ in range(40):
            c = 0.5 * (a + b)
            a, b = (c, b) if within(bias + c) and within(bias - c) else (a, c)
        amp = a
        # resonances swing the finger further than its static equilibria: shrink until a nominal run stays in range
        t, seg, G = _schedule(design)
        for _ in range(30):
            with warnings.catch_warnings():  # a trial amplitude may leave the range: that is what is tested
                warnings.simplefilter("ignore", JointRangeWarning)
                q = _simulate(model, design, _profile(design, t, bias, amp), G, seg)[:, : model.n]
            if np.all((q >= lo) & (q <= hi)):
                break
            amp *= 0.85
        amp *= design.amplitude_fraction
    return float(bias), float(amp)


def _rest_torque(model: Model, reading: Callable[[np.ndarray], float], target: float, gravity: np.ndarray,
                 upper: float) -> float:
    """The motor torque in [0, upper] N m at which ``reading`` of the finger's static equilibrium (a
    quantity that grows with the torque) equals ``target``: bisection, a torque that leaves the
    equilibrium undefined counting as too much."""
    a, b = 0.0, upper
    for _ in range(60):
        c = 0.5 * (a + b)
        try:
            above = reading(_mean_equilibrium(model, c, gravity)) > target
        except InputError:
            above = True
        a, b = (a, c) if above else (c, b)
    return 0.5 * (a + b)


def _trimmed_bias(truth: Model, nominal: Model, bias: float, gravity: np.ndarray) -> float:
    """The motor torque at which the finger ``truth`` rests with the encoder reading that ``nominal``
    has at ``bias`` (N m): what an experimenter gets by trimming the bias with a slow loop on the
    measured encoder before recording (the encoder is all it uses)."""
    S = nominal.transmission.S

    def encoder(q: np.ndarray) -> float:
        return float(np.sum(S @ q))

    return _rest_torque(truth, encoder, encoder(_mean_equilibrium(nominal, bias, gravity)), gravity,
                        max(4.0 * bias, 0.2))


def _schedule(design: ExperimentDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sample times (N+1,), orientation segment of each sample and gravity (N+1, 3)."""
    N = design.n_samples - 1
    t = design.dt * np.arange(N + 1)
    n_or = len(design.orientations)
    seg = np.minimum((np.arange(N + 1) * n_or) // (N + 1), n_or - 1)
    return t, seg, np.asarray(design.orientations, dtype=float)[seg]


def _simulate(truth: Model, design: ExperimentDesign, u: np.ndarray, G: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """States (N+1, 2n) from the static equilibrium at u[0], RK4 with substeps, the torque held per sample,
    segment by segment of constant gravity."""
    N = u.shape[0] - 1
    x = np.zeros((N + 1, 2 * truth.n))
    x[0, : truth.n] = _mean_equilibrium(truth, u[0], G[0])
    start = 0
    while start < N:
        stop = start + 1
        while stop < N and seg[stop] == seg[start]:
            stop += 1
        m = _oriented(truth, G[start])
        k = stop - start
        sim = simulate(m, x[start], np.repeat(u[start:stop, None], design.substeps, axis=0), k * design.dt,
                       design.dt / design.substeps, "rk4", input="motor", output="encoder")
        x[start + 1: stop + 1] = sim.x[design.substeps:: design.substeps]
        start = stop
    return x


def _profile(design: ExperimentDesign, t: np.ndarray, bias: float, amp: float) -> np.ndarray:
    f = np.asarray(design.frequencies, dtype=float)
    k = np.arange(1, f.size + 1)
    phases = -np.pi * k * (k - 1) / f.size  # Schroeder: a low crest factor
    s = np.sin(2 * np.pi * f[None, :] * t[:, None] + phases[None, :]).sum(axis=1)
    return bias + amp * s / math.sqrt(f.size / 2)


def experiment(model: str, true_params: HandParams | str | Path | None = None,
               design: ExperimentDesign | None = None, seed: int = 0, path: str | Path | None = None,
               nominal_params: HandParams | str | Path | None = None) -> Recording:
    """Simulate the identification experiment on a finger with ``true_params`` (friction included).

    Parameters
    ----------
    model: ``"finger2"`` or ``"finger3"``.
    true_params: the finger's true parameters (a :class:`~alpes_dyn.params.HandParams` or a file).
    design: the :class:`ExperimentDesign` (default: the documented one).
    seed: seed of the sensor noise. path: write the recording there as CSV too.
    nominal_params: the parameters the experimenter knows, from which the excitation is designed
        (default: the shipped file).

    Returns
    -------
    :class:`~alpes_dyn.recording.Recording` with encoder counts, measured torque, the camera's joint
    angles (if any), gravity (when not the model's constant) and the true joint angles.
    """
    if model not in SCENARIO_MODELS:
        raise InputError(f"model: the identification experiment is defined for one finger "
                         f"({', '.join(SCENARIO_MODELS)}), got {model!r}")
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool) or seed < 0:
        raise InputError(f"seed: expected a non-negative integer, got {seed!r}")
    design = (design or ExperimentDesign()).check()
    p_true = true_params if isinstance(true_params, HandParams) else load_params(true_params)
    p_nom = nominal_params if isinstance(nominal_params, HandParams) else load_params(nominal_params)
    nominal = Model.alpes(model, friction=True, params=p_nom)
    bias, amp = excitation(nominal, design)
    truth = Model.alpes(model, friction=True, params=p_true)
    if design.trim_bias and design.torque_bias is None:
        bias = _trimmed_bias(truth, nominal, bias, np.asarray(design.orientations[0], dtype=float))
    rng = np.random.default_rng(seed)
    t, seg, G = _schedule(design)
    N = t.shape[0] - 1
    n_or = len(design.orientations)
    u = _profile(design, t, bias, amp)
    x = _simulate(truth, design, u, G, seg)
    tr = truth.transmission
    step = 2 * np.pi / tr.counts_per_rev
    qm = x[:, : truth.n] @ tr.S.T
    counts = np.round((qm + design.encoder_noise_counts * step * rng.standard_normal(qm.shape)) / step)
    torque = u[:, None] + design.torque_noise * rng.standard_normal((N + 1, 1))
    q_meas = None
    if design.camera_times:
        q_meas = np.full((N + 1, truth.n), np.nan)
        for tc in design.camera_times:
            k = int(round(tc / design.dt))
            q_meas[k] = x[k, : truth.n] + design.camera_noise * rng.standard_normal(truth.n)
    same_g = n_or == 1 and np.array_equal(G[0], truth.gravity)
    rec = Recording(t=t, encoder=counts, torque=torque, motor_names=tr.motor_names, joint_names=truth.joint_names,
                    q=q_meas, gravity=None if same_g else G, true_q=x[:, : truth.n].copy())
    if path is not None:
        write_recording(rec, path)
    return rec


def perturbed_params(params: HandParams | None = None, spread: float = 0.2, seed: int = 0,
                     kinds: Sequence[str] = ("K", "m", "friction")) -> HandParams:
    """``params`` with the finger's springs K_i, masses m_i (inertias I_i with them) and per-joint
    friction F_s, F_v each multiplied by an independent factor uniform in [1 - spread, 1 + spread].

    The result is a valid parameter set (the changed entries marked ``assumed`` with the draw as reason),
    e.g. the "true" finger of a simulated identification experiment.
    """
    if not (math.isfinite(spread) and 0 <= spread < 1):
        raise InputError(f"spread: expected a fraction in [0, 1), got {spread!r}")
    for k in kinds:
        if k not in ("K", "m", "friction"):
            raise InputError(f"kinds: unknown kind {k!r} (expected K, m, friction)")
    p = params if params is not None else load_params()
    rng = np.random.default_rng(seed)
    f = p.finger
    reason = f"drawn: nominal times a factor uniform in [{1 - spread:g}, {1 + spread:g}] per link, seed {seed}"
    upd: dict[str, Param] = {}

    def put(name: str, value: np.ndarray) -> None:
        old = p.raw[name] if name in p.raw else Param(value, "N m" if name.endswith("F_s") else "N m s/rad",
                                                         "assumed", reason, "per-joint friction")
        upd[name] = dataclasses.replace(old, value=value, source="assumed", reason=reason, std=None)

    if "K" in kinds:
        put("finger.K", f.K * rng.uniform(1 - spread, 1 + spread, 3))
    if "m" in kinds:
        s = rng.uniform(1 - spread, 1 + spread, 3)
        put("finger.m", f.m * s)
        put("finger.I", f.I * s)
    if "friction" in kinds:
        Fs = f.F_s if f.F_s is not None else np.full(3, p.F_s)
        Fv = f.F_v if f.F_v is not None else np.full(3, p.F_v)
        put("finger.F_s", Fs * rng.uniform(1 - spread, 1 + spread, 3))
        put("finger.F_v", Fv * rng.uniform(1 - spread, 1 + spread, 3))
    return with_values(p, upd)
