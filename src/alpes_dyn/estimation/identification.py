"""Identification of a finger's physical parameters from a recording (output-error, multiple shooting).

Problem. With the recording's measured motor torques as the known input, find the parameters theta
(:mod:`alpes_dyn.symbolic.parametric`: K_i, m_i with I_i, F_s_i, F_v_i, ...) and the initial states that make the
model's encoder reading q_m = S q (Section 3, eq. 3.13) -- and, where the recording has them, the
camera's joint angles -- match the recording in the least-squares sense:

    min  sum_k |S q_k - y_k|^2 / sigma_y^2 + sum_(k, i measured) (q_k,i - q^meas_k,i)^2 / sigma_q^2.

Method: direct multiple shooting (Bock): the record is cut into intervals of ``interval`` seconds,
each starting from its own state s_j; continuity s_j+1 = x(end of interval j) is an equality
constraint. A lightly damped, stiff-ish system makes single shooting's cost landscape rugged; multiple
shooting keeps every interval short, so the problem stays close to linear and converges from the
nominal parameters. Each iteration is a constrained Gauss-Newton step (Levenberg-Marquardt damped,
l1-merit line search) on the exact Jacobians of the RK4-discretised model, all intervals simulated
with their sensitivities at once in compiled C (:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`).
Parameters are fitted as log theta: every iterate is physical (masses, springs and friction
positive, inertias scaled with their masses); the encoder offsets and the tilt angles (nominal 0, either
sign) as they are. An encoder offset enters the output only, y = S q + offset; the tilt turns gravity
(:func:`~alpes_dyn.symbolic.parametric.tilted_gravity`).

Globalisation. From parameters 20 % off, 100 ms of the finger (tiny inertias, a soft balance of springs
and gravity) drifts by degrees and rad/s, and imposing continuity at once let Gauss-Newton trade the
fit for the defects and stop in another basin (m_1 -> 0). So the fit goes in three stages: (1) each
interval's start state alone on its encoder samples; (2) a homotopy, continuity as a quadratic penalty
tightened tenfold per phase (four phases of Levenberg-Marquardt), friction held; (3) the constrained
problem. In the homotopy a step whose parameter part the trust region shortens has its nodes solved
again for the shortened step. If the encoder residual then stays above three times the quantisation floor (a wrong basin:
4-8 counts against the noise's 0.58), or stage 3 asks three times in a row for a change of log theta
above 30 (the linearisation has lost the basin), stages 2-3 run again with friction free in the homotopy.
If both starts miss, the whole fit runs again at half the interval (from 100 ms: 50 ms drifts less; one of
three MuJoCo fingers with the effects of a real hand needed it).

Speed. A line search's trial needs the states, not their sensitivities: it runs the step without its
derivatives (a tenth of the time), and the sensitivities are computed once a step is accepted. Near the
solution a full Gauss-Newton step can raise the defects while the cost falls (the curvature of the
shooting map at the smooth Coulomb friction's knee); a second-order correction (Nocedal & Wright,
Section 18.3) removes them with the same matrix before the step is shortened. The fit stops at the
data's resolution: once continuous, when no parameter would move by a tenth of its standard error.

Torque noise. The recorded torque is not the true one. With a multisine excitation the true torque
lies on its lines; the fit adds to the projected torque a correction on the lines with the
projection error's own prior (errors in variables), see ``excitation``. The standard errors are those of the Gauss-Newton
covariance at the solution scaled by the residual variance (a posteriori), by the delta method on
theta = theta_0 exp(rho).
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import scipy.sparse as sp

from ..errors import InputError, ModelError, RecordingError
from ..model.robot import Model
from ..symbolic.parametric import common_scale, select_parameters
from .adequacy import (AdequacyWarning, Validation, assess, compare, effect_responses, sensor_floor,
                       torque_explained)
from .recording import Recording, check_recording
from .scenario import static_equilibrium
from ..simulation.integrate import stable_substeps
from ..simulation.sensitivity import SensitivityModel
from .kkt import Shape, continuity_jacobian, factorize, kkt_matrix, normal_matrix
from .fit_result import IdentificationResult, identified_params
from ..progress import _Progress

__all__ = ["IdentificationResult", "identify", "identified_params", "project_torque", "check_selection"]

VALIDATION_PREFIX = 0.1
"""s: the held-out recording's prefix that fixes its initial state (at least one shooting interval)."""
RETRY_INTERVAL = 0.1
"""s: from shooting intervals this long or longer, a fit whose two starts both end above :data:`RETRY_FLOOR_RATIO`
times the recording's sensor floor runs again at half the interval (once: 100 ms, the default, retries at 50 ms),
kept where it converges to a lower residual."""
RETRY_FLOOR_RATIO = 3.0
"""The retry's threshold, times the recording's own sensor floor (quantisation and white noise, estimated from
its encoder: :func:`~alpes_dyn.estimation.adequacy.sensor_floor`); wrong basins leave 4-8 times it."""


def check_selection(model: Model, parameters: str | Sequence[str] | None) -> None:
    """:class:`~alpes_dyn.ModelError` for a selection :func:`identify` cannot fit: an unknown or repeated
    name (:func:`~alpes_dyn.symbolic.parametric.select_parameters`), or the torque constant's common scale
    (``input_gain`` with every mass, spring and friction, :func:`~alpes_dyn.symbolic.parametric.common_scale`)."""
    if common_scale(model, select_parameters(model, parameters)):
        raise ModelError("parameters: input_gain with every mass, spring and friction: the encoder sees only their "
                         "ratios (theta -> c theta leaves the motion unchanged); hold the masses (known from the "
                         "maker) and fit input_gain with the springs and friction, or leave input_gain out")


def _line_basis(t: np.ndarray, frequencies: Sequence[float]) -> np.ndarray:
    """(N, 2 n_f + 1): 1, sin(2 pi f t), cos(2 pi f t) for f in ``frequencies`` (Hz), t from t[0]."""
    f = np.asarray(frequencies, dtype=float).reshape(-1)
    if f.size == 0 or not np.all(np.isfinite(f)) or np.any(f <= 0):
        raise InputError(f"excitation: expected positive frequencies in Hz, got {frequencies!r}")
    t = np.asarray(t, dtype=float)
    fs = 1.0 / ((t[-1] - t[0]) / (t.shape[0] - 1))
    if np.any(f >= 0.5 * fs):
        raise InputError(f"excitation: frequencies must be below the Nyquist frequency {0.5 * fs:g} Hz")
    if 2 * f.size + 1 >= t.shape[0] // 4:
        raise InputError(f"excitation: {f.size} frequencies are too many for {t.shape[0]} samples")
    w = 2 * np.pi * f[None, :] * (t - t[0])[:, None]
    return np.hstack([np.ones((t.shape[0], 1)), np.sin(w), np.cos(w)])


def _project(Q: np.ndarray, torque: np.ndarray) -> np.ndarray:
    """The least-squares fit of each column of ``torque`` on the orthonormal basis Q."""
    return Q @ (Q.T @ torque)


def project_torque(t: np.ndarray, torque: np.ndarray, frequencies: Sequence[float]) -> np.ndarray:
    """The least-squares fit of each torque column (N, m) on 1, sin(2 pi f t), cos(2 pi f t) for f in
    ``frequencies`` (Hz): the excitation without the measurement noise off its lines."""
    return _project(np.linalg.qr(_line_basis(t, frequencies))[0], np.asarray(torque, dtype=float))


def _as_recording(recording: Recording | str | Path, model: Model) -> tuple[Recording, str]:
    if isinstance(recording, Recording):
        return check_recording(recording), ""
    from .recording import read_recording

    return read_recording(recording, model), str(recording)


def identify(model: Model, recording: Recording | str | Path, parameters: str | Sequence[str] | None = None, *,
             excitation: Sequence[float] | None = None, interval: float = 0.1, substeps: int | None = None,
             torque_noise: float | None = None, camera_noise: float = math.radians(0.1),
             max_iterations: int = 50, tol: float = 1e-6, threads: int | None = None,
             progress: bool | None = None, validation: Recording | str | Path | None = None,
             encoder_noise: float | None = None, start: Mapping[str, float] | None = None,
             kkt: str = "sparse") -> IdentificationResult:
    """Fit ``parameters`` of ``model`` (and the initial states) to a recording.

    Parameters
    ----------
    model: the finger with the values to start from (e.g. ``Model.alpes("finger3", friction=True)``);
        parameters not fitted keep its values.
    recording: a :class:`~alpes_dyn.estimation.recording.Recording` or a CSV path (:func:`~alpes_dyn.estimation.recording.read_recording`).
    parameters: selection (:func:`~alpes_dyn.symbolic.parametric.select_parameters`), default K, m and friction;
        by name also ``J_m`` (a model with rotors), ``encoder_offset``, ``tilt`` (``tilt_y`` on a planar finger:
        ``tilt_x`` is seen only through its cosine) and ``input_gain`` (with the masses held:
        :func:`check_selection`).
    excitation: the frequencies (Hz) of a multisine excitation (e.g. ``ExperimentDesign().lines``):
        the true torque is taken to lie on a constant and these sines and cosines (periodic-excitation
        identification). The measured torque is projected on them, and the projection's error (what
        the noise leaves on the lines) is fitted with the parameters: u = P u_meas + sigma_u Q c with Q
        the lines' orthonormal basis and c ~ N(0, I) a priori (errors in variables, maximum likelihood).
        None: the measured torque as it is.
    interval: multiple-shooting interval, s (default 100 ms; where both starts miss the basin, the fit runs again
        at half of it, :data:`RETRY_INTERVAL`: on MuJoCo's +-20 % fingers with the effects of a real hand one
        seed of three lost its basin from both starts at 100 ms and fitted to the sensor floor at 50 ms, while
        on a 1 s recording of the model's own structure 50 ms crawled into the 50-iteration cap where 100 ms
        converged in 13). substeps: RK4 steps per sample (default
        :func:`~alpes_dyn.simulation.integrate.stable_substeps`: 4 for the smooth friction law at 1 kHz, 15 for the
        stick-slip law of :data:`~alpes_dyn.model.extras.STICTION_VELOCITY` on finger3).
    torque_noise: standard deviation sigma_u of the recorded torque's white noise, N m. Default: with
        ``excitation``, estimated from what the measured torque has off the lines; without, 0 (the torque
        taken as exact). Without ``excitation`` a positive value gives each interval a constant torque
        correction with prior sigma_u / sqrt(samples per interval). Why it matters: near its gravity
        balance a finger turns 3e-5 N m of in-band torque error into 13 counts of encoder misfit.
    camera_noise: standard deviation of the recording's joint-angle measurements, rad (weights them
        against the encoder, whose noise is its quantisation step / sqrt(12) plus the fit's residual).
    max_iterations, tol: Gauss-Newton stopping rule: continuous to 1e-6 and either the next step moving
        no parameter by more than a tenth of its standard error, or a predicted or realised (whole step)
        change of the cost below max(tol * cost, 0.05) (chi^2 by 0.1), or chi^2 down by less than 1 over
        five iterations.
    progress: a progress line on stderr (default: when stderr is a terminal).
    validation: a held-out recording of the same finger (another run of the experiment): the fitted
        model is simulated open-loop on its torque (:func:`~alpes_dyn.estimation.adequacy.compare`, fit %).
    encoder_noise: the encoder's white noise beyond its quantisation, counts, for the adequacy's sensor
        floor (default: estimated from the recording, :func:`~alpes_dyn.estimation.adequacy.white_noise_level`).
    start: values to start the fit from, by the fit's parameter names (e.g. an earlier fit's
        ``dict(zip(result.names, result.values))``, as :func:`~alpes_dyn.estimation.effects.fit_effects` does from
        one round to the next); the parameters not named start from the model's values. A name that is not
        fitted here, or a value that is not finite (positive where the parameter is fitted as log theta), is an
        :class:`~alpes_dyn.InputError`.
    kkt: ``"sparse"`` (default): the shooting problem's normal and KKT matrices held sparse and factorised once per
        iteration (:mod:`alpes_dyn.estimation.kkt`), time and memory linear in the record; ``"dense"``: as arrays
        (the reference; quadratic memory, cubic time).

    The result carries the fit's ``reason`` (why it stopped: converged, iteration cap, lost basin, step
    failure), the encoder ``residual`` (N, m) counts and its ``adequacy``
    (:func:`~alpes_dyn.estimation.adequacy.assess`: whiteness, independence of the torque, RMS against the
    sensor floor, the validation).

    Returns
    -------
    :class:`IdentificationResult`. Raises :class:`~alpes_dyn.errors.RecordingError` for a recording
    that does not fit the model, :class:`~alpes_dyn.InputError` for bad settings.
    """
    t_start = time.perf_counter()
    if not isinstance(model, Model):
        raise InputError(f"model: expected an alpes_dyn Model, got {type(model).__name__}")
    if model.transmission is None:
        raise ModelError(f"model {model.name!r} has no tendon transmission: nothing to read the encoder with")
    rec, rec_path = _as_recording(recording, model)
    if tuple(rec.motor_names) != tuple(model.transmission.motor_names) or tuple(rec.joint_names) != model.joint_names:
        raise RecordingError(f"recording: motors {rec.motor_names} / joints {rec.joint_names} do not match model "
                             f"{model.name!r}")
    val_rec = None
    if validation is not None:  # read and checked before the fit: a bad file fails at once
        val_rec = _as_recording(validation, model)
        if (tuple(val_rec[0].motor_names) != tuple(model.transmission.motor_names)
                or tuple(val_rec[0].joint_names) != model.joint_names):
            raise RecordingError(f"validation: motors {val_rec[0].motor_names} / joints {val_rec[0].joint_names} do "
                                 f"not match model {model.name!r}")
    if encoder_noise is not None and not (isinstance(encoder_noise, (int, float)) and not isinstance(encoder_noise, bool)
                                          and math.isfinite(encoder_noise) and encoder_noise >= 0):
        raise InputError(f"encoder_noise: expected a non-negative number of counts, got {encoder_noise!r}")
    for name, v in (("interval", interval), ("camera_noise", camera_noise), ("tol", tol)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise InputError(f"{name}: expected a positive number, got {v!r}")
    if val_rec is not None:
        if abs(val_rec[0].dt - rec.dt) > 1e-9 * rec.dt:
            raise RecordingError(f"validation: sample period {val_rec[0].dt:g} s differs from the recording's {rec.dt:g} s")
        pre = max(2, int(round(max(interval, VALIDATION_PREFIX) / rec.dt)))  # the prefix that fixes the start
        if val_rec[0].n_samples <= 4 * pre:
            raise RecordingError(f"validation: {val_rec[0].n_samples} samples are too few (the first {pre} fix the "
                                 f"start; give more than {4 * pre})")
    if not isinstance(kkt, str) or kkt not in ("sparse", "dense"):
        raise InputError(f"kkt: expected 'sparse' or 'dense', got {kkt!r}")
    if not isinstance(max_iterations, int) or max_iterations < 1:
        raise InputError(f"max_iterations: expected a positive integer, got {max_iterations!r}")
    dt = rec.dt
    L = int(round(interval / dt))
    N = rec.n_samples - 1
    if L < 2 or L > N:
        raise InputError(f"interval: {interval:g} s must hold 2 to {N} samples of {dt:g} s")
    if torque_noise is not None and not (isinstance(torque_noise, (int, float)) and not isinstance(torque_noise, bool)
                                         and math.isfinite(torque_noise) and torque_noise >= 0):
        raise InputError(f"torque_noise: expected a non-negative number of N m, got {torque_noise!r}")
    if excitation is not None:
        Phi_all = _line_basis(rec.t, excitation)
        Phi = Phi_all[:-1]  # (N, nphi): 1, sin, cos of each line, at the held samples
        Q, R_q = np.linalg.qr(Phi)
        U = _project(Q, rec.torque[:-1])  # the measured torque projected on the lines
        Q_last = np.linalg.solve(R_q.T, Phi_all[-1])  # the basis at the last sample (Q = Phi R^-1)
        U_last = (Q_last @ (Q.T @ rec.torque[:-1]))[None]
        if torque_noise is None:  # what is off the lines is the noise: its standard deviation
            off_lines = rec.torque[:-1] - U
            torque_noise = float(np.sqrt(np.sum(off_lines**2) / (off_lines.size - Q.shape[1] * U.shape[1])))
    else:
        U = rec.torque[:-1]
        U_last = rec.torque[-1:]
        torque_noise = 0.0 if torque_noise is None else torque_noise
    # errors in variables. With the lines: the true torque is U + sigma_u Q c, c ~ N(0, I) a priori (exactly the
    # projection's error, whitened), c fitted with the parameters. Without them: a constant per interval.
    eiv = torque_noise > 0
    lines = eiv and excitation is not None
    nphi = Q.shape[1] if lines else 0
    check_selection(model, parameters)  # before anything is compiled
    if substeps is None:
        substeps = stable_substeps(model, dt)
    sens = SensitivityModel(model, parameters, dt=dt, substeps=substeps, threads=threads,
                            input_offset=eiv and not lines, input_basis=nphi)
    nx, p, nu, n = sens.nx, sens.p, sens.nu, sens.n
    no = sens.no if (eiv and not lines) else 0  # local torque corrections per interval
    ncg = sens.no if lines else 0  # global line-coefficient corrections
    ng = p + ncg
    nb = nx + no  # local variables of an interval: its start state and its torque correction
    tr = model.transmission
    S_enc = np.asarray(tr.S, dtype=float)
    ny = S_enc.shape[0]
    step = 2 * np.pi / tr.counts_per_rev
    y = rec.encoder * step  # motor angle, rad
    sig_y = step / math.sqrt(12.0)
    sig_off = torque_noise / math.sqrt(L) if eiv else 1.0  # the mean of L white samples
    G = rec.gravity[:-1] if rec.gravity is not None else np.broadcast_to(model.gravity, (N, 3))
    n_int = -(-N // L)
    pad = n_int * L - N
    Ub = np.concatenate([U, np.repeat(U[-1:], pad, axis=0)]).reshape(n_int, L, nu)
    Gb = np.concatenate([G, np.repeat(G[-1:], pad, axis=0)]).reshape(n_int, L, 3)
    Psib = None
    if lines:
        Psi = torque_noise * Q
        Psib = np.concatenate([Psi, np.repeat(Psi[-1:], pad, axis=0)]).reshape(n_int, L, nphi)
    # residual layout per interval: samples j = 0..L-1 (the last interval also its final sample)
    k_idx = np.arange(n_int)[:, None] * L + np.arange(L + 1)[None, :]
    valid = k_idx <= N
    valid[:-1, L] = False  # an interval's end is the next one's start
    kk = np.minimum(k_idx, N)
    Yb = y[kk]  # (S, L+1, m)
    Qm = rec.q[kk] if rec.q is not None else None  # (S, L+1, n) with NaN
    q_mask = np.isfinite(Qm) & valid[:, :, None] if Qm is not None else None

    theta0 = sens.nominal.copy()
    # additive parameters (encoder offsets, tilt angles: nominal 0, either sign) are fitted as they are, the
    # others as log theta / theta_0; the encoder offsets enter the output only (their state sensitivities are 0)
    additive = np.array([pp.additive for pp in sens.dynamics.parameters], dtype=bool)
    if start is not None:
        theta0 = _start_values(theta0, sens.names, additive, start)
    off_cols = [(k, model.motor_index(pp.motor)) for k, pp in enumerate(sens.dynamics.parameters)
                if pp.kind == "encoder_offset"]
    # tendon compliances (y = S q + offset + C u, u the modelled torque at the sample): fitted in units of
    # the recording's own encoder-to-torque scale std(y) / std(u), so that a unit step is of the data's order
    comp_cols = [(k, model.motor_index(pp.motor)) for k, pp in enumerate(sens.dynamics.parameters)
                 if pp.kind == "tendon_compliance"]
    scale = np.ones(p)
    for k, mo in comp_cols:
        su, sy = float(np.std(rec.torque[:, mo])), float(np.std(y[:, mo]))
        scale[k] = sy / su if su > 0 and sy > 0 else 1.0
    Ufull = np.concatenate([U, U_last])  # the modelled torque at every sample, the last one's too
    Uk = Ufull[kk]  # (S, L+1, nu)
    Psik = (np.concatenate([Psi, torque_noise * Q_last[None]])[kk] if lines else None)  # (S, L+1, nphi)
    if np.any((theta0 <= 0) & ~additive):
        bad = sens.names[int(np.argmax((theta0 <= 0) & ~additive))]
        raise ModelError(f"parameters: {bad} has the starting value {theta0[sens.names.index(bad)]:g}; a fitted "
                         "parameter needs a positive starting value (use a model with that term switched on)")

    # initial guess: the model's own response from its static equilibrium, cut at the nodes
    q0 = _rest_guess(model, tr.joint_torque(U[0]), y[0]) if rec.gravity is None else np.zeros(n)
    x_nom, _ = sens.run(np.concatenate([q0, np.zeros(n)])[None], U[None], G[None], theta0,
                        np.zeros((1, nu, sens.nb)) if sens.nb else None, basis=Psi[None] if lines else None)
    nodes = x_nom[0, np.arange(n_int) * L].copy()
    if not np.isfinite(nodes).all():
        nodes[:] = np.concatenate([q0, np.zeros(n)])
    offs = np.zeros((n_int, no))
    glob = np.zeros(ng)  # log theta / theta_0, then the whitened line-coefficient corrections
    iv, ip = slice(0, nx), slice(nx, nx + p)
    io = slice(nx + p, nx + p + sens.no)

    def values(glob: np.ndarray) -> np.ndarray:
        """theta from the fitted variables: theta_0 exp(rho), or theta_0 + scale rho for the additive ones."""
        return np.where(additive, theta0 + scale * glob[:p], theta0 * np.exp(np.where(additive, 0.0, glob[:p])))

    def per_motor(theta: np.ndarray, cols: list[tuple[int, int]]) -> np.ndarray:
        """(m,) the entries ``cols`` (index in theta, motor) of theta on their motors, 0 elsewhere."""
        out = np.zeros(ny)
        for k, mo in cols:
            out[mo] += theta[k]
        return out

    def offset(theta: np.ndarray) -> np.ndarray:
        """(m,) the encoder offsets, rad."""
        return per_motor(theta, off_cols)

    def torque_at(glob: np.ndarray, offs: np.ndarray) -> np.ndarray:
        """(S, L+1, nu) the modelled torque at each residual's sample (N m): the measured or projected one plus
        the fitted correction."""
        if lines:
            return Uk + np.einsum("skl,il->ski", Psik, glob[p:].reshape(nphi, nu).T)
        if eiv:
            return Uk + offs[:, None, :]
        return Uk

    def stretch(theta: np.ndarray, u_k: np.ndarray | None) -> np.ndarray | float:
        """(S, L+1, m) the tendons' stretch C u seen by the encoders, rad, for the modelled torque u_k
        (:func:`torque_at`; None without compliance: 0)."""
        return 0.0 if u_k is None else u_k * per_motor(theta, comp_cols)

    def correction(glob: np.ndarray, offs: np.ndarray) -> np.ndarray | None:
        if lines:
            return glob[p:].reshape(nphi, nu).T  # C (nu, nphi) from its column-major vec
        return offs if eiv else None

    def evaluate(nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray, jac: bool = True):
        """Residuals r (S, R), their Jacobians J (S, R, nb + ng) with respect to the interval's local
        variables and the global ones (log theta, line corrections), continuity c (S-1, nx) and its
        Jacobians Cv (S-1, nx, nb), Cr (S-1, nx, ng); the global residuals rg (ng,) (the line
        corrections' prior; zeros for theta) and the states. ``jac=False``: r, c, rg and the states
        alone (J, Cv, Cr None), from the step without its sensitivities (a tenth of the time)."""
        theta = values(glob)
        if not (np.isfinite(theta).all() and np.isfinite(nodes).all()):  # not sens.run's "theta: expected finite"
            raise InputError("identify: the fit diverged (its parameters or states overflowed to NaN or inf): are "
                             "the recording's encoders this model's, in counts, and its torques in N m?")
        xs, X = sens.run(nodes, Ub, Gb, theta, correction(glob, offs), basis=Psib, sensitivities=jac)
        q = xs[:, :, :n]
        u_k = torque_at(glob, offs) if comp_cols else None
        r_enc = ((np.einsum("ij,skj->ski", S_enc, q) + offset(theta) + stretch(theta, u_k) - Yb) / sig_y
                 * valid[:, :, None])
        c = xs[:-1, L] - nodes[1:]
        rg = np.concatenate([np.zeros(p), glob[p:]])
        if not jac:
            res = [r_enc.reshape(n_int, -1)]
            if Qm is not None:
                res.append((np.where(q_mask, q - np.nan_to_num(Qm), 0.0) / camera_noise).reshape(n_int, -1))
            if no:
                res.append(offs / sig_off)
            return np.concatenate(res, axis=1), None, c, None, None, rg, xs
        Xv = np.concatenate([X[..., iv], X[..., io]], axis=-1) if no else X[..., iv]  # (S, L+1, nx, nb)
        Xr = X[..., ip] * np.where(additive, scale, theta)  # d/d log theta (d/d (theta / scale) if additive)
        if lines:
            Xr = np.concatenate([Xr, X[..., io]], axis=-1)
        w = valid[:, :, None, None] / sig_y
        res = [r_enc.reshape(n_int, -1)]
        J_enc = np.concatenate([np.einsum("ij,skjd->skid", S_enc, Xv[:, :, :n]),
                                np.einsum("ij,skjd->skid", S_enc, Xr[:, :, :n])], axis=-1)
        for k, mo in off_cols:  # y = S q + offset: d r / d offset_m = e_m
            J_enc[:, :, mo, nb + k] += 1.0
        if comp_cols:  # y += C u: d/d C (in its scale) = u scale; d/d the torque's correction = C
            for k, mo in comp_cols:
                J_enc[:, :, mo, nb + k] += u_k[:, :, mo] * scale[k]
                if lines:  # vec(C_lines) is column-major: coefficient (motor mo, line l) at l * nu + mo
                    J_enc[:, :, mo, nb + p + mo::nu] += theta[k] * Psik
                elif eiv:
                    J_enc[:, :, mo, nx + mo] += theta[k]
        J_enc = J_enc * w
        jac = [J_enc.reshape(n_int, -1, nb + ng)]
        if Qm is not None:
            rq = np.where(q_mask, q - np.nan_to_num(Qm), 0.0) / camera_noise
            Jq = np.concatenate([Xv[:, :, :n], Xr[:, :, :n]], axis=-1) / camera_noise * q_mask[:, :, :, None]
            res.append(rq.reshape(n_int, -1))
            jac.append(Jq.reshape(n_int, -1, nb + ng))
        if no:  # the per-interval torque corrections' prior: zero mean, sigma_u / sqrt(L)
            res.append(offs / sig_off)
            Jo = np.zeros((n_int, no, nb + ng))
            Jo[:, :, nx:nb] = np.eye(no) / sig_off
            jac.append(Jo)
        r = np.concatenate(res, axis=1)
        J = np.concatenate(jac, axis=1)
        return r, J, c, Xv[:-1, L], Xr[:-1, L], rg, xs

    nv = n_int * nb
    nz = nv + ng
    nc = (n_int - 1) * nx

    shape = Shape(n_int, nb, nx, ng)
    prior = np.r_[np.zeros(p), np.ones(ncg)]  # d rg / d glob, squared
    dense = kkt == "dense"

    def normal(J: np.ndarray, mu: float):
        """Gauss-Newton normal matrix of the interval-structured residuals, LM-damped by mu (:mod:`.kkt`)."""
        return normal_matrix(J, shape, mu, prior, dense)

    def continuity(Cv: np.ndarray, Cr: np.ndarray):
        """(nc, nz) Jacobian of the continuity defects."""
        return continuity_jacobian(Cv, Cr, shape, dense)

    def kkt_system(J: np.ndarray, Cv: np.ndarray, Cr: np.ndarray, mu: float):
        """Normal equations of the interval-structured least squares, with the continuity constraints."""
        return kkt_matrix(normal(J, mu), continuity(Cv, Cr))

    def grad(r: np.ndarray, J: np.ndarray, rg: np.ndarray) -> np.ndarray:
        gs = np.einsum("sk,skd->sd", r, J)
        return np.concatenate([gs[:, :nb].reshape(-1), gs[:, nb:].sum(axis=0) + rg])

    # stage 1: the nodes alone (theta fixed, intervals decoupled), from the nominal states shifted onto the
    # measured encoder: a start close to the data, where Gauss-Newton on the whole problem converges
    k_nodes = np.arange(n_int) * L
    Sp = np.linalg.pinv(S_enc)
    y_rigid = y - Ufull * np.asarray(tr.tendon_compliance) if comp_cols else y  # the start's stretch off
    nodes[:, :n] += (y_rigid[k_nodes] - nodes[:, :n] @ S_enc.T) @ Sp.T
    nodes[:, n:] += (np.gradient(y, dt, axis=0)[k_nodes] - nodes[:, n:] @ S_enc.T) @ Sp.T
    mu_n = 1e-2 * np.ones(n_int)
    for _ in range(8):
        r, J, *_ = evaluate(nodes, offs, glob)
        A = J[:, :, :nx]
        Hn = np.einsum("ski,skj->sij", A, A)
        gn = np.einsum("sk,ski->si", r, A)
        Dn = np.einsum("sii->si", Hn)
        dn = -np.linalg.solve(Hn + mu_n[:, None, None] * np.einsum("si,ij->sij", Dn + 1e-12, np.eye(nx)), gn[:, :, None])
        r2, *_ = evaluate(nodes + dn[:, :, 0], offs, glob, jac=False)
        better = np.sum(r2**2, axis=1) < np.sum(r**2, axis=1)
        nodes[better] += dn[better, :, 0]
        mu_n = np.where(better, mu_n / 10, mu_n * 10)

    max_log_step = 0.3  # at most a 35 % change of any parameter per iteration
    soft_phases = 4
    max_coef_step = 1.0  # and of a line-coefficient correction, in standard deviations of its prior
    c_scale = np.maximum(np.abs(nodes).max(axis=0), 1e-3)  # per state component
    show = sys.stderr.isatty() if progress is None else bool(progress)
    bar = _Progress(max_iterations, "identify", show)

    def encoder_rms(r: np.ndarray) -> float:
        """RMS of the encoder residuals in r, counts."""
        enc = r[:, : (L + 1) * ny] * sig_y / step
        return float(np.sqrt(np.sum(enc**2) / max(int(valid.sum()) * ny, 1)))

    def limited(d: np.ndarray) -> tuple[np.ndarray, np.ndarray, bool]:
        """A trust region (no jump into a far basin): log theta by at most max_log_step, the line
        corrections by at most max_coef_step prior standard deviations, the whole step scaled down.
        In stage 3 the local variables are scaled with the global ones: there, re-solving the nodes
        for a shortened parameter step (continuity a hard constraint), or damping the whole step, sent
        three of six +-20 % fingers to residuals of 50-1700 counts. Returns the local and global steps
        and whether the step is whole."""
        dv, dg = d[:nv].reshape(n_int, nb), d[nv:nz]
        big = max(float(np.max(np.abs(dg[:p]), initial=0.0)) / max_log_step,
                  float(np.max(np.abs(dg[p:]), initial=0.0)) / max_coef_step)
        return (dv / big, dg / big, False) if big > 1.0 else (dv, dg, True)

    n_res = int(valid.sum()) * ny + (int(q_mask.sum()) if q_mask is not None else 0) + n_int * no + ncg
    dof = max(n_res - (nz - nc), 1)
    unit_p = np.zeros((nz + nc, p))
    unit_p[nv + np.arange(p), np.arange(p)] = 1.0

    def solve(nodes: np.ndarray, offs: np.ndarray, glob: np.ndarray, freeze: bool):
        """Stages 2 and 3 from the stage-1 nodes; ``freeze``: friction held during the homotopy."""
        # stage 2: continuity as a soft penalty, tightened tenfold per phase (a homotopy from the decoupled
        # intervals to the shooting problem). With the starting parameters wrong, a 100 ms interval of the
        # finger (tiny inertias, a soft balance of springs and gravity) drifts by degrees and rad/s; imposing
        # continuity at once lets Gauss-Newton trade the fit for the defects and stall far from the truth.
        r, J, c, Cv, Cr, rg, xs = evaluate(nodes, offs, glob)
        defect0 = np.maximum(np.abs(c).max(axis=0), 1e-9)  # per state component
        # the softly-coupled problem lets friction absorb the defects (F_v_1 went to 8x, F_s_1 to 0.4x and the
        # fit to another basin): during the homotopy only the springs, masses, gains and torque lines move
        frozen = nv + np.array([i for i, nm in enumerate(sens.names) if freeze and nm.startswith("F_")], dtype=int)
        for level in range(soft_phases):
            wdef = np.tile(10.0**level / defect0, n_int - 1)  # 1 / sigma of each defect
            mu_s = 1e-3
            for _ in range(6):
                soft_cost = 0.5 * float(np.sum(r**2) + np.sum(rg**2) + np.sum((c.reshape(-1) * wdef) ** 2))
                C = continuity(Cv, Cr)
                C = C * wdef[:, None] if dense else sp.diags(wdef) @ C
                H = normal(J, mu_s) + C.T @ C
                hold = np.zeros(nz)  # friction waits for the hard phase
                hold[frozen] = 1e12 * np.maximum(H.diagonal()[frozen], 1.0)
                H = H + (np.diag(hold) if dense else sp.diags(hold, format="csc"))
                g = grad(r, J, rg) + C.T @ (c.reshape(-1) * wdef)
                d = -factorize(H)(g)  # the least-squares solution where H is singular
                dv, dg, whole = limited(d)
                if not whole:
                    # the global step shortened, the local variables solved again for it: with continuity a
                    # penalty the data hold the nodes, and they follow the parameters (scaled with them, the
                    # nodes crawled: the homotopy left the defects at 30-60 % and stage 3 needed 20-40
                    # iterations at 1/10-1/60 of the Gauss-Newton step)
                    try:
                        dv = factorize(H[:nv, :nv])(-g[:nv] - H[:nv, nv:] @ dg).reshape(n_int, nb)
                    except np.linalg.LinAlgError:
                        pass
                trial = evaluate(nodes + dv[:, :nx], offs + dv[:, nx:], glob + dg, jac=False)
                new_cost = 0.5 * float(np.sum(trial[0] ** 2) + np.sum(trial[5] ** 2)
                                       + np.sum((trial[2].reshape(-1) * wdef) ** 2))
                if np.isfinite(new_cost) and new_cost < soft_cost:
                    nodes, offs, glob = nodes + dv[:, :nx], offs + dv[:, nx:], glob + dg
                    r, J, c, Cv, Cr, rg, xs = evaluate(nodes, offs, glob)
                    mu_s = max(mu_s / 10.0, 1e-9)
                    if soft_cost - new_cost < 1e-3 * soft_cost:
                        break
                else:
                    mu_s *= 10.0
                    if mu_s > 1e6:
                        break

        # stage 3: the shooting problem, continuity as constraints (constrained Gauss-Newton, l1 merit)
        nu_merit = 1.0
        mu = 1e-3
        converged = False
        history: list[float] = []
        lost = 0  # consecutive steps that asked log theta for more than 30
        it = 0
        reason = f"iteration cap: {max_iterations} Gauss-Newton iterations without meeting the stopping rule"
        for it in range(1, max_iterations + 1):
            cost = 0.5 * float(np.sum(r**2) + np.sum(rg**2))
            rhs = np.concatenate([-grad(r, J, rg), -c.reshape(-1)])
            # the step, and the parameters' block of the inverse (their covariance up to the scale)
            solve_K = factorize(kkt_system(J, Cv, Cr, mu))  # once per iteration: the step and the correction
            sol = solve_K(np.column_stack([rhs, unit_p]))
            sol, P_rho = sol[:, 0], sol[nv:nv + p, 1:]
            d, lam = sol[:nz], sol[nz:]
            viol = float(np.max(np.abs(c) / c_scale, initial=0.0))
            sd_rho = np.sqrt(np.maximum(np.diag(P_rho), 1e-300) * max(2.0 * cost / dof, 1e-300))
            step_sigma = float(np.max(np.abs(d[nv:nv + p]) / sd_rho, initial=0.0))
            if viol < 1e-6 and (abs(float(rhs[:nz] @ d)) <= max(tol * cost, 0.05) or step_sigma < 0.1):
                # continuous, and Gauss-Newton predicts a decrease of chi^2 below 0.1 or no parameter moving by
                # a tenth of its standard error: the statistical resolution of the data
                converged = True
                reason = "converged: continuous, and the next step within the data's resolution"
                break
            nu_merit = max(nu_merit, 1.5 * float(np.max(np.abs(lam), initial=0.0)))
            merit = cost + nu_merit * float(np.sum(np.abs(c)))
            dv, dg, full = limited(d)
            accepted, soc_done = False, False
            candidates = [(1.0, dv, dg), (0.5, dv, dg), (0.25, dv, dg), (0.1, dv, dg), (0.03, dv, dg)]
            k_try = 0
            while k_try < len(candidates):
                alpha, sv, sg = candidates[k_try]
                k_try += 1
                trial = evaluate(nodes + alpha * sv[:, :nx], offs + alpha * sv[:, nx:], glob + alpha * sg, jac=False)
                if not (np.isfinite(trial[0]).all() and np.isfinite(trial[2]).all()):
                    continue
                cost_new = 0.5 * float(np.sum(trial[0] ** 2) + np.sum(trial[5] ** 2))
                m_new = cost_new + nu_merit * float(np.sum(np.abs(trial[2])))
                # the l1 merit, or (a filter's second chance, against the Maratos effect near the solution) a
                # step that halves the defects while the cost stays put
                if m_new < merit or (np.sum(np.abs(trial[2])) < 0.5 * np.sum(np.abs(c))
                                     and cost_new <= cost * (1.0 + 1e-6)):
                    accepted = True
                    break
                if alpha == 1.0 and full and not soc_done:
                    # second-order correction (Nocedal & Wright, 18.3): the full step's own defects removed by a
                    # minimum-norm correction from the same system; near the solution the curvature of the
                    # shooting map makes a full Gauss-Newton step raise the defects though the cost falls (the
                    # Maratos effect), and without the correction the line search crawls
                    soc_done = True
                    try:
                        d2 = solve_K(np.concatenate([np.zeros(nz), -trial[2].reshape(-1)]))[:nz]
                    except np.linalg.LinAlgError:
                        continue
                    candidates.insert(k_try, (1.0, sv + d2[:nv].reshape(n_int, nb), sg + d2[nv:]))
            bar.update(1)
            if not accepted:
                mu *= 10.0
                if mu > 1e8:
                    reason = (f"step failure: no step lowered the merit function (Levenberg-Marquardt damping "
                              f"above 1e8, iteration {it})")
                    break
                continue
            dv, dg = sv, sg
            step_g = float(np.max(np.abs(alpha * dg), initial=0.0))
            nodes, offs, glob = nodes + alpha * dv[:, :nx], offs + alpha * dv[:, nx:], glob + alpha * dg
            r, J, c, Cv, Cr, rg, xs = evaluate(nodes, offs, glob)
            mu = max(mu / 10.0, 1e-9) if alpha == 1.0 else min(mu * 3.0, 1e6)
            viol = float(np.max(np.abs(c) / c_scale, initial=0.0))
            small_change = alpha == 1.0 and abs(cost - cost_new) <= max(tol * cost, 0.05)  # chi^2 by less than 0.1
            history.append(cost_new)
            far = not full and float(np.max(np.abs(d[nv:nv + p]), initial=0.0)) > 100.0 * max_log_step
            lost = lost + 1 if far else 0
            if lost >= 3 and viol > 1e-3:
                # three Gauss-Newton steps in a row asking log theta to move by more than 30: the linearisation
                # has lost the basin (on one +-20 % finger a mass headed for 0, the step for 1e6): this start fails
                reason = (f"lost basin: three Gauss-Newton steps in a row asked log theta to move by more than "
                          f"{100.0 * max_log_step:g} (iteration {it})")
                break
            stalled = len(history) > 5 and history[-6] - history[-1] <= max(tol * cost, 0.5)  # chi^2 by 1 in 5
            if viol < 1e-6 and (small_change or stalled or step_g < tol):
                converged = True
                reason = "converged: continuous, and the cost no longer falls"
                break
        return nodes, offs, glob, (r, J, c, Cv, Cr, rg, xs), it, converged, reason

    # Two starts of stages 2-3, friction held during the homotopy or not: each alone missed the
    # right basin on one of five +-20 % fingers; the wrong basins leave a residual of 4-8 counts,
    # the right one the encoder noise (0.58 counts), so a residual above three times the quantisation
    # floor (1/sqrt(12) count) asks for the second start.
    basin_limit = 3.0 / math.sqrt(12.0)
    first = (nodes.copy(), offs.copy(), glob.copy())  # both starts from the stage-1 nodes
    total_its = 0
    for freeze in (True, False):
        if not freeze:  # the second start has its own progress line (each start takes up to max_iterations)
            bar.close()
            bar = _Progress(max_iterations, "identify (second start)", show)
        nodes, offs, glob, state, it, converged, reason = solve(*[a.copy() for a in first], freeze)
        total_its += it
        r, J, c, Cv, Cr, rg, xs = state
        if encoder_rms(r) <= basin_limit:
            break
    it = total_its
    bar.close()
    # a third chance where both starts ended far above the floor (not merely at the iteration cap)
    missed = encoder_rms(r) > RETRY_FLOOR_RATIO * sensor_floor(rec.encoder, 0.0, encoder_noise).total \
        and not reason.startswith("iteration")
    if missed and interval >= RETRY_INTERVAL * (1 - 1e-9) and int(round(0.5 * interval / dt)) >= 2:
        # both starts ended above the basin limit (not merely at the iteration cap): shorter intervals drift less
        # from a wrong start (on MuJoCo's +-20 % fingers with a real hand's effects, one of three lost its basin from both
        # starts at 100 ms, and fitted to the sensor floor at 50 ms); kept if it converged to a lower residual (on
        # a plant with a rotor the model lacks, the retry's lost basin fitted lower and named the wrong effect)
        with warnings.catch_warnings():  # the verdict is reported on the fit kept
            warnings.simplefilter("ignore", AdequacyWarning)
            again = identify(model, recording, parameters, excitation=excitation, interval=0.5 * interval,
                             substeps=substeps, torque_noise=torque_noise, camera_noise=camera_noise,
                             max_iterations=max_iterations, tol=tol, threads=threads, progress=progress,
                             validation=validation, encoder_noise=encoder_noise, start=start, kkt=kkt)
        if again.converged and again.residual_rms < encoder_rms(r):  # a lost basin again: the first kept
            again.iterations += it
            again.seconds = time.perf_counter() - t_start
            again.reason += (f" (at {500 * interval:g} ms intervals; at {1000 * interval:g} ms both starts missed:"
                             f" {encoder_rms(r):.3g} counts, {reason})")
            if not again.trustworthy:
                warnings.warn(AdequacyWarning(f"identify: {again.status()}"), stacklevel=2)
            return again
        it += again.iterations
        reason += f" (a fit at {500 * interval:g} ms intervals did no better: {again.residual_rms:.3g} counts)"

    # covariance: the parameters' block of the undamped Gauss-Newton KKT inverse at the solution, scaled by
    # the residual variance
    s2 = float(np.sum(r**2) + np.sum(rg**2)) / dof
    solve_Kz = factorize(kkt_system(J, Cv, Cr, 0.0))  # undamped: the covariance and the effects' regressors
    P_rho = solve_Kz(unit_p)[nv:nv + p] * s2
    theta = values(glob)
    sd_rho = np.sqrt(np.maximum(np.diag(P_rho), 0.0))
    # a parameter the data do not see at the solution (its columns zero: tilt_x on a planar finger at a level
    # palm, seen only through cos tilt_x): the least-squares step left it at its start, its std is unbounded
    info = np.einsum("skd,skd->d", J[:, :, nb:nb + p], J[:, :, nb:nb + p]) + np.einsum("sid,sid->d", Cr[:, :, :p],
                                                                                       Cr[:, :, :p])
    blind = info <= 1e-20 * max(float(info.max(initial=0.0)), 1e-300)
    if blind.any():
        sd_rho = np.where(blind, np.inf, sd_rho)
        warnings.warn(f"identify: {', '.join(n_ for n_, b in zip(sens.names, blind) if b)}: no information in "
                      "this recording (the encoder does not see it here); left at its start, std inf", stacklevel=2)
    with np.errstate(invalid="ignore", over="ignore"):
        sd_c = np.where(np.isfinite(sd_rho), np.maximum(sd_rho, 1e-300), np.nan)
        corr = P_rho / np.outer(sd_c, sd_c)
    rms = encoder_rms(r)
    # the adequacy of the fitted model (module adequacy): its trajectory at the samples, the intervals cut
    # at their valid samples (sample order), the residual y - yhat in counts
    x_fit = xs[valid]
    u_fit = stretch(theta, torque_at(glob, offs))[valid] if comp_cols else 0.0
    yhat = (x_fit[:, :n] @ S_enc.T + offset(theta) + u_fit) / step  # y = S q + offset + C u (the fitted ones)
    e = rec.encoder - yhat
    explained = 0.0
    if eiv and not lines:  # what the torque noise explains through the model (with the lines: fitted away)
        explained = torque_explained(sens, nodes, Ub, Gb, theta, offs, valid, S_enc, step, torque_noise, L)
    floor = sensor_floor(rec.encoder, explained, encoder_noise)
    resp = effect_responses(sens, nodes, Ub, Gb, theta, correction(glob, offs), Psib, valid, x_fit, S_enc, step, dt)
    resp["torque"] = (rec.torque - rec.torque.mean(axis=0))[kk] * valid[:, :, None]  # tendon stretch ~ tension
    # each response less what the fit itself would absorb of it (its projection on the fit's tangent space:
    # the nodes and parameters, continuity kept): the residual of a missing effect is that remainder
    regressors = {}
    for name, R in resp.items():  # a loop over the four effects
        Rr = np.zeros_like(r)
        Rr[:, : (L + 1) * ny] = (R * step / sig_y).reshape(n_int, -1)
        z = solve_Kz(np.concatenate([grad(Rr, J, np.zeros(ng)), np.zeros(nc)]))[:nz]
        Jz = np.einsum("skd,sd->sk", J[:, :, :nb], z[:nv].reshape(n_int, nb)) + J[:, :, nb:] @ z[nv:nz]
        regressors[name] = ((Rr - Jz)[:, : (L + 1) * ny].reshape(n_int, L + 1, ny) * sig_y / step)[valid]
    val = None
    if val_rec is not None:
        val = _validate(model, sens, theta, val_rec, excitation, max(interval, VALIDATION_PREFIX), offset(theta),
                        per_motor(theta, comp_cols))
    verdict = assess(e, rec.torque, floor, regressors, val, velocity=x_fit[:, n:] @ S_enc.T)
    result = IdentificationResult(
        names=sens.names, values=theta, std=np.where(additive, scale, theta) * sd_rho, initial=theta0,
        units=tuple(pp.unit for pp in sens.dynamics.parameters), correlation=corr, residual_rms=rms, iterations=it,
        converged=converged, seconds=time.perf_counter() - t_start, compile_seconds=sens.compile_seconds,
        states=nodes, node_times=rec.t[np.arange(n_int) * L], model=model, recording_path=rec_path,
        reason=reason, residual=e, adequacy=verdict)
    if not result.trustworthy:  # one line (the CLI reports it itself)
        warnings.warn(AdequacyWarning(f"identify: {result.status()}"), stacklevel=2)
    return result


def _start_values(theta0: np.ndarray, names: Sequence[str], additive: np.ndarray,
                  start: Mapping[str, float]) -> np.ndarray:
    """``theta0`` with the values of ``start`` (by parameter name) put in; :class:`~alpes_dyn.InputError` naming
    a parameter that is not fitted, or a value that is not a finite number (positive unless additive)."""
    if not isinstance(start, Mapping):
        raise InputError(f"start: expected a mapping of parameter names to values, got {type(start).__name__}")
    theta = theta0.copy()
    for name, v in start.items():
        if name not in names:
            raise InputError(f"start: {name!r} is not a parameter of this fit (fitted: {', '.join(names)})")
        k = list(names).index(name)
        ok = isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, (bool, np.bool_))
        if not ok or not math.isfinite(float(v)) or (not additive[k] and float(v) <= 0):
            need = "a finite number" if additive[k] else "a finite number > 0"
            raise InputError(f"start: {name} = {v!r}: expected {need}")
        theta[k] = float(v)
    return theta


def _validate(model: Model, sens: SensitivityModel, theta: np.ndarray, recording: tuple[Recording, str],
              excitation: Sequence[float] | None, prefix_s: float, offset: np.ndarray | None = None,
              compliance: np.ndarray | None = None) -> Validation:
    """:func:`~alpes_dyn.estimation.adequacy.compare` of the fitted model on a held-out recording, its
    torque projected on the excitation's lines as in the fit, the initial state estimated on the first
    ``prefix_s`` seconds (one shooting interval); ``offset`` (m,) rad: the fitted encoder offsets, the same
    sensors' (taken off the held-out encoder), and ``compliance`` (m,) rad/(N m): the fitted tendon stretch
    C u, u the held-out torque as the fit takes it (taken off too)."""
    rec, path = recording
    U = rec.torque[:-1] if excitation is None else project_torque(rec.t[:-1], rec.torque[:-1], excitation)
    G = rec.gravity[:-1] if rec.gravity is not None else np.broadcast_to(model.gravity, (rec.n_samples - 1, 3))
    tr = model.transmission
    step = 2 * np.pi / tr.counts_per_rev
    prefix = max(2, int(round(prefix_s / rec.dt)))  # checked against the length in identify
    enc = rec.encoder if offset is None else rec.encoder - np.asarray(offset) / step
    if compliance is not None and np.any(compliance != 0):
        enc = enc - np.concatenate([U, U[-1:]]) * np.asarray(compliance) / step
    q0 = _rest_guess(model, tr.joint_torque(U[0]), enc[0] * step) if rec.gravity is None else np.zeros(model.n)
    val = compare(sens, theta, np.concatenate([q0, np.zeros(model.n)]), U, G, enc,
                  np.asarray(tr.S, dtype=float), step, prefix, path)
    val.prefix_s = prefix * rec.dt
    return val


def _rest_guess(model: Model, tau: np.ndarray, y0: np.ndarray) -> np.ndarray:
    """The static equilibrium under the joint torques ``tau``, the joints without spring (the thumb's
    ab/adduction, which its own motor holds) held where the first encoder reading ``y0`` puts them."""
    held = model.springless_joints
    if not held:
        return static_equilibrium(model, tau)
    q = np.zeros(model.n)
    idx = [model.joint_index(j) for j in held]
    q[idx] = (np.linalg.pinv(model.transmission.S) @ y0)[idx]
    return model.static_equilibrium(tau, q, fixed=held)
