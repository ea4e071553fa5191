"""The smooth friction law's model error as process noise: what makes the observer's reported sigma cover its
error where the torque sensor's noise shakes the filter's joint velocities across the law's band.

The observer of a recording reads the measured motor torque as its known input; its white noise (sigma_tau, N m)
enters the filter's prediction as an input noise G Sigma_w G^T (:class:`~alpes_dyn.estimation.observers.observers.
KalmanFilter`). Each sample it kicks the filter's joint velocities by about dt |M^-1 B| sigma_tau (rad/s; M the
inertia matrix at rest, B the actuation matrix; the root sum of squares over the motors): on finger3 with 5e-4 N m,
0.02, 0.23 and 0.77 rad/s, against the smooth law's F_s tanh(v / v_s) band of v_s = 0.1 rad/s. The filter then
evaluates the friction at a velocity that is off by more than the law's band, where its linearisation (a slope F_s /
v_s within it, none outside) no longer describes the friction's error: the error F_s (tanh(v / v_s) - tanh(v_hat /
v_s)) is up to 2 F_s and changes sign from sample to sample, and nothing in P carries it. Measured on MuJoCo's
finger3 with the library's own smooth law (the model exact but for the noise; 2 s of the estimation scenario's
torque, 5e-4 N m): the NEES of the joints 15 to 22 against a 95 % band of 1.8-4.5 (errors of 0.06-0.10 degree, sigma
0.02-0.04); with a process noise on the joints' velocities scaled uniformly by 3 to 30 it stayed at 12 to 20 (the
error lies in the split the encoder does not see, and the friction's error is per joint); the unscented filter was
at 30.

Here the friction's error is a white torque on each joint i of standard deviation ``fraction`` sqrt(rho_i) F_s,i,
rho_i = kick_i^2 / (kick_i^2 + v_s^2) the share of the law's band the kicks cover (0 without torque noise: the
filter unchanged, as consistent as it was), mapped on the velocities by dt M^-1:

    Q_v = dt^2 M^-1 diag(fraction^2 rho F_s^2) M^-1.

``fraction`` (:data:`FRICTION_MODEL_ERROR`) was chosen by measurement on the same plant (seeds of the draws listed
in the observers guide): 1 (the whole F_s) and 0.5 made the filter cautious (NEES 1.2-1.9 below its band), 0.25
put it in its band on every draw tried; the estimate's error grows with the noise the filter admits (the worst
joint's 0.088-0.095 degree without it, 0.070-0.111 at 0.25, 0.102-0.141 at 1).
"""

from __future__ import annotations

import numpy as np

from ...model.robot import Model

__all__ = ["FRICTION_MODEL_ERROR", "friction_process_noise"]

FRICTION_MODEL_ERROR = 0.25
"""The smooth law's model error as a fraction of each joint's F_s where the torque noise covers its band (module
docstring)."""


def friction_process_noise(model: Model, B: np.ndarray, dt: float, torque_noise: float,
                           fraction: float = FRICTION_MODEL_ERROR) -> np.ndarray:
    """(n, n) the covariance Q_v added to the observer's process noise on the joint velocities, (rad/s)^2 per sample
    (module docstring): ``model``'s Coulomb F_s (N m) and smooth band v_s (rad/s), its inertia matrix at q = 0,
    ``B`` (n, m) the actuation matrix (joint torque per motor torque), ``dt`` the sample period (s),
    ``torque_noise`` the recorded torque's white noise (N m). Zero without friction or torque noise."""
    n = model.n
    Fs = np.asarray(model.extras.coulomb, dtype=float)
    vs = float(model.extras.smooth_velocity)
    if not (np.any(Fs > 0) and torque_noise > 0 and vs > 0):
        return np.zeros((n, n))
    Minv = np.linalg.inv(model.inertia_matrix(np.zeros(n)))
    kick = dt * np.sqrt(np.sum((Minv @ np.asarray(B, dtype=float)) ** 2, axis=1)) * torque_noise
    rho = kick**2 / (kick**2 + vs**2)
    Qv = dt**2 * Minv @ np.diag(fraction**2 * rho * Fs**2) @ Minv.T
    return 0.5 * (Qv + Qv.T)
