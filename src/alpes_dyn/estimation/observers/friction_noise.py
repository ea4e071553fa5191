"""The smooth friction law's model error as process noise: what makes the observer's reported sigma cover its
error where the torque sensor's noise shakes the filter's joint velocities across the law's band.

The observer of a recording reads the measured motor torque as its known input; its white noise (sigma_tau, N m)
enters the filter's prediction as an input noise G Sigma_w G^T (:class:`~alpes_dyn.estimation.observers.observers.
KalmanFilter`). Each sample it kicks the filter's joint velocities by about dt |M^-1 B| sigma_tau (rad/s; M the
inertia matrix at rest, B the actuation matrix; the root sum of squares over the motors): on finger3 with 5e-4 N m,
0.02, 0.23 and 0.77 rad/s, against the smooth law's F_s tanh(v / v_s) band of v_s = 0.1 rad/s. The filter then
evaluates the friction at a velocity that is off by more than the law's band, where its linearisation (a slope F_s /
v_s within it, none outside) no longer describes the friction's error: the error F_s (tanh(v / v_s) - tanh(v_hat /
v_s)) is up to 2 F_s and changes sign from sample to sample, and nothing in P carries it. On MuJoCo's
finger3 with the library's own smooth law (the model exact but for the torque noise) the joints' NEES stays several
times above its band, and a process noise on the joints' velocities scaled uniformly does not bring it down (the
error lies in the split the encoder does not see, and the friction's error is per joint); the unscented filter is
no better.

Here the friction's error is a white torque on each joint i of standard deviation ``fraction`` sqrt(rho_i) F_s,i,
rho_i = kick_i^2 / (kick_i^2 + v_s^2) the share of the law's band the kicks cover (0 without torque noise: the
filter unchanged, as consistent as it was), mapped on the velocities by dt M^-1:

    Q_v = dt^2 M^-1 diag(fraction^2 rho F_s^2) M^-1.

``fraction`` (:data:`FRICTION_MODEL_ERROR`) was chosen by measurement on the same plant (seeds of the draws listed
in the observers guide): 1 (the whole F_s) and 0.5 made the filter cautious (NEES 1.2-1.9 below its band), 0.25
put it in its band on every draw tried; the estimate's error grows with the noise the filter admits (the worst
joint's 0.088-0.095 degree without it, 0.070-0.111 at 0.25, 0.102-0.141 at 1).

A creep file's observer (``friction.law = "creep"``, :class:`~alpes_dyn.model.friction.Creep`: a friction
a_j (qdd_j + b qd_j) up to F_s) takes a torque kick with the band's added inertia a_j: its kicks are
dt |(M + A)^-1 B| sigma_tau (A = diag(a_j)) against the band's edge F_s,j / (a_j b) in rho_i. On MuJoCo's
soft plants (finger3, a_j nine times the joint's own inertia) the smooth law's kicks (the joint's inertia alone
against v_s: rho 0.84 and 0.98 on the two distal joints, 0.0002 and 0.02 with the band's inertia) made the filter
cautious there (NEES 0.5-0.6 at 1x F_s, 0.07 at 3x) and let the split wander: the true file's EKF at 3x F_s went
from 0.11-0.15 degree to 0.01-0.04 on three draws.

The LuGre law's bristles (``friction_law="lugre"``) carry no such term: their deflection z is a state, and it walks
by :data:`BRISTLE_WALK` of the presliding displacement F_s / sigma0 per step. Where the parameter file holds a calibrated model error (``friction.model_error`` = e, in units of F_s, written
by ``identify``: :mod:`~alpes_dyn.estimation.observers.noise_calibration`), it replaces the smooth law's term above
on every law (smooth, stick, LuGre): a white torque e F_s,i on each joint,

    Q_v = dt^2 M^-1 diag(e^2 F_s^2) M^-1                                               (:func:`model_error_noise`).

All are added in one place,
:func:`with_friction_noise`, which :func:`~alpes_dyn.estimation.observers.observers.make_observer` applies to the
process noise it is given: every observer built from a parameter file (a recording's, the estimation scenario's, the
force loop's, the exported C's) carries them.
"""

from __future__ import annotations

import numpy as np

from typing import Any

from ...checks import as_float_array
from ...model.friction import LuGre, creep_of, lugre_of
from ...model.params import HandParams, Param, with_values
from ...model.robot import Model

__all__ = ["FRICTION_MODEL_ERROR", "BRISTLE_WALK", "friction_process_noise", "model_error_noise", "model_error_of",
           "with_model_error", "with_friction_noise"]

FRICTION_MODEL_ERROR = 0.25
"""The smooth law's model error as a fraction of each joint's F_s where the torque noise covers its band (module
docstring)."""

BRISTLE_WALK = 1e-3
"""The LuGre observer's random walk of each bristle per step, as a fraction of the presliding displacement
F_s / sigma0 (the bristle's prior standard deviation is the whole of it: a joint at rest holds an unknown
friction). On MuJoCo's stick-slip finger2, held: a small walk keeps the estimate as close as a smaller one, a
larger walk lets the bristle free and the filter lets the split between the joints move."""


def model_error_of(model: Model) -> float | None:
    """The calibrated model error e of ``model``'s parameter file.

    Parameters
    ----------
    model : Model
        The observer's model (its ``params``, the parameter file it was built from, if any).

    Returns
    -------
    float or None
        ``friction.model_error``, in units of each joint's F_s, or None (no file, or none written).
    """
    p = getattr(model, "params", None)
    e = getattr(p, "model_error", None)
    return None if e is None else float(e)


def with_model_error(params: HandParams, error: float, reason: str = "calibrated on the record") -> HandParams:
    """``params`` with ``friction.model_error`` = ``error``: both the field and what
    :func:`~alpes_dyn.model.params.write_params` writes (source ``identified``).

    Parameters
    ----------
    params : HandParams
        The parameter file's values.
    error : float
        The observer's model error, in units of each joint's F_s, >= 0 (:func:`model_error_noise`).
    reason : str, optional
        How it was calibrated, written beside it (default "calibrated on the record").

    Returns
    -------
    HandParams
        A copy of ``params`` with the model error.

    Raises
    ------
    ModelError
        ``error`` not a finite number >= 0.
    """
    prm = Param(float(error), "F_s", "identified", reason, "the observer's model error: a white torque per sample of "
                "this times each joint's F_s (calibrated on the identification record)")
    return with_values(params, {"friction.model_error": prm})


def model_error_noise(model: Model, dt: float, error: float) -> np.ndarray:
    """Q_v = dt^2 M^-1 diag(``error``^2 F_s^2) M^-1: a white torque of ``error`` F_s,i (N m) on each joint i, mapped
    on the joint velocities.

    Parameters
    ----------
    model : Model
        The observer's model: its Coulomb F_s (N m) per joint and its inertia matrix M at q = 0.
    dt : float
        The sample period, s.
    error : float
        The model error, in units of each joint's F_s.

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Q_v, (rad/s)^2 per sample (symmetric).
    """
    n = model.n
    Fs = np.asarray(model.extras.coulomb, dtype=float)
    Minv = np.linalg.inv(model.inertia_matrix(np.zeros(n)))
    Qv = dt**2 * Minv @ np.diag((float(error) * Fs) ** 2) @ Minv.T
    return 0.5 * (Qv + Qv.T)


def friction_process_noise(model: Model, B: np.ndarray, dt: float, torque_noise: float,
                           fraction: float = FRICTION_MODEL_ERROR) -> np.ndarray:
    """The covariance Q_v added to the observer's process noise on the joint velocities (module docstring).

    Parameters
    ----------
    model : Model
        The observer's model: its Coulomb F_s (N m) and smooth band v_s (rad/s) per joint, its inertia matrix M at
        q = 0.
    B : numpy.ndarray, shape (n, m)
        The actuation matrix (joint torque per motor torque).
    dt : float
        The sample period, s.
    torque_noise : float
        The recorded torque's white noise, N m (standard deviation).
    fraction : float, optional
        The model error as a fraction of each joint's F_s where the kicks cover the law's band (default
        :data:`FRICTION_MODEL_ERROR`).

    Returns
    -------
    numpy.ndarray, shape (n, n)
        Q_v, (rad/s)^2 per sample (symmetric); zero without friction or torque noise.
    """
    n = model.n
    Fs = np.asarray(model.extras.coulomb, dtype=float)
    vs = float(model.extras.smooth_velocity)
    if not (np.any(Fs > 0) and torque_noise > 0 and vs > 0):
        return np.zeros((n, n))
    Minv = np.linalg.inv(model.inertia_matrix(np.zeros(n)))
    kicked, band = _kicked_inertia(model, Minv, Fs, vs)
    kick = dt * np.sqrt(np.sum((kicked @ np.asarray(B, dtype=float)) ** 2, axis=1)) * torque_noise
    rho = kick**2 / (kick**2 + band**2)
    Qv = dt**2 * Minv @ np.diag(fraction**2 * rho * Fs**2) @ Minv.T
    return 0.5 * (Qv + Qv.T)


def _kicked_inertia(model: Model, Minv: np.ndarray, Fs: np.ndarray, vs: float) -> tuple[np.ndarray, np.ndarray]:
    """The inverse inertia the torque noise kicks the joint velocities through, and the law's band (rad/s, (n,)):
    M^-1 and v_s for the smooth law; for the creep law (:class:`~alpes_dyn.model.friction.Creep`) (M + A)^-1, the
    band's added inertia A = diag(a_j) taking the kick with the joint while it creeps, and its edge
    F_s / (a_j b) (module docstring)."""
    creep = creep_of(model)
    if creep is None:
        return Minv, np.full(Fs.shape, vs)
    a, edge = creep.band(Minv, np.maximum(Fs, 1e-300))
    return np.linalg.inv(np.linalg.inv(Minv) + np.diag(a)), edge


def with_friction_noise(system: Any, dt: float, process_noise: Any, input_noise: Any = None,
                        friction_law: str = "smooth", n_parameters: int = 0) -> Any:
    """The process noise of an observer on ``system`` with the friction's terms added (module docstring).

    Parameters
    ----------
    system : StateSpace
        The observer's state space: its model's F_s, v_s, inertia and LuGre law, its actuation matrix B (n, m).
    dt : float
        The sample period, s.
    process_noise : array_like
        The process noise per step without the friction's: variances or a covariance over [q; qd; parameters]
        (2n + ``n_parameters``), or, with the LuGre law, over the bristles too (2n + ``n_parameters`` + n: then
        taken as given).
    input_noise : array_like or None, optional
        The known input's covariance (variances or a matrix); its first m diagonal entries are the motor torques'
        (N^2 m^2), whose largest standard deviation is the torque noise of :func:`friction_process_noise`.
    friction_law : {"smooth", "stick", "lugre"}, optional
        The observer's law: ``"smooth"`` adds :func:`friction_process_noise` on qd, ``"lugre"`` appends the
        bristles' walk (:data:`BRISTLE_WALK` F_s / sigma0 per step, rad), ``"stick"`` adds nothing; where the
        model's file holds a calibrated ``friction.model_error`` (:func:`model_error_of`), every law adds
        :func:`model_error_noise` on qd instead of :func:`friction_process_noise`.
    n_parameters : int, optional
        The gains and disturbances estimated with the state.

    Returns
    -------
    ndarray or object
        The (nz, nz) covariance; ``process_noise`` itself where the model has no friction or its shape is not one
        of the above (the filter then names the field).
    """
    model = system.model
    n, Fs = model.n, np.asarray(model.extras.coulomb, dtype=float)
    base = 2 * n + n_parameters
    error = model_error_of(model)
    if not np.any(Fs > 0) or (friction_law == "stick" and error is None):
        return process_noise
    Q = as_float_array(process_noise, "process_noise", f"{base} variances or a ({base}, {base}) covariance")
    Q = np.diag(np.broadcast_to(Q, (base,))) if Q.ndim == 0 or Q.shape == (base,) else Q.copy()
    if Q.shape == (base, base) and error is not None:
        Q[n:2 * n, n:2 * n] += model_error_noise(model, dt, error)
    if friction_law == "lugre":
        span = Fs / (lugre_of(model) or LuGre()).sigma0
        return (np.block([[Q, np.zeros((base, n))], [np.zeros((n, base)), np.diag((BRISTLE_WALK * span) ** 2)]])
                if Q.shape == (base, base) else process_noise)
    if Q.shape != (base, base) or error is not None:
        return Q if Q.shape == (base, base) else process_noise
    m = system.B.shape[1]
    Sw = np.zeros(m) if input_noise is None else as_float_array(input_noise, "input_noise", "variances")
    Sw = np.diag(Sw) if Sw.ndim == 2 else np.broadcast_to(Sw, (max(Sw.size, m),))
    torque_noise = float(np.sqrt(np.max(Sw[:m], initial=0.0)))
    Q[n:2 * n, n:2 * n] += friction_process_noise(model, system.B, dt, torque_noise)
    return Q
