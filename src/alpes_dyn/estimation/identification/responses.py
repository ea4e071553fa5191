"""The encoder's responses to the missing effects a verdict reads, and to the torque's noise, through a fitted model.

Split from :mod:`~alpes_dyn.estimation.identification.adequacy` (its 600-line bound), which re-exports both: the
responses are the regressors of :func:`~alpes_dyn.estimation.identification.adequacy.signatures` (each then projected
off the fit's tangent space by :func:`~alpes_dyn.estimation.identification.identification.identify`), each missing
effect's signature through the fitted model, each interval from its fitted node (:func:`effect_responses`), and what
the recorded torque's white noise makes of the encoder, a part of the sensor floor (:func:`torque_explained`).
States-only runs of the compiled step, in chunks of intervals.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...model.ratio_curve import encoder_angles, encoder_rates
from ...model.transmission import capstan_velocity

__all__ = ["effect_responses", "torque_explained"]


def effect_responses(sens: Any, nodes: np.ndarray, Ub: np.ndarray, Gb: np.ndarray, theta: np.ndarray,
               corr: np.ndarray | None, Psib: np.ndarray | None, valid: np.ndarray, x_fit: np.ndarray, S: np.ndarray,
               step: float, dt: float, chunk_doubles: int = 2**20, ramp: np.ndarray | None = None
               ) -> dict[str, np.ndarray]:
    """The encoder's responses (S, L+1, m), counts per N m, through the fitted model (each interval from its
    fitted node) to a motor torque following the sign of the motor velocity, the tension |tau_m| times that sign,
    the velocity, the acceleration (dry friction, the tendon's sheath friction growing with the tension, viscous
    friction, a rotor's inertia on the tendon), the torque times ``ramp`` (N+1,) where given (a drifting torque
    constant) and the torque's own forward
    difference u_k+1 - u_k (a torque read d samples late is the applied one less d times it, to first order: a
    torque delay): the signatures of :func:`~alpes_dyn.estimation.identification.adequacy.signatures`; finite
    differences of batched runs, states only, in chunks of intervals of ``chunk_doubles`` per-sample inputs.

    Parameters
    ----------
    sens : SensitivityModel
        The fit's sensitivity model (:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`).
    nodes : numpy.ndarray, shape (B, nx)
        The fitted nodes: each interval's start state.
    Ub : numpy.ndarray, shape (B, L, nu)
        The torque held over each period of each interval, N m, as the fit takes it.
    Gb : numpy.ndarray, shape (B, L, 3)
        Gravity, m/s^2, base frame, per period.
    theta : numpy.ndarray, shape (p,)
        The fitted parameters, in their units.
    corr : numpy.ndarray or None
        The fitted torque corrections (the run's ``offset`` coefficients), per interval (B, nu, nb) or for all;
        None: none.
    Psib : numpy.ndarray, shape (B, L, nb), or None
        The corrections' basis per sample (None: ones).
    valid : numpy.ndarray of bool, shape (B, L+1)
        True on the samples scored (within the record; an interval's end counted once, as the next one's start).
    S : numpy.ndarray
        The transmission: its matrix (m, n), or its ratio curve (:func:`~alpes_dyn.model.ratio_curve.encoder_angles`).
    x_fit : numpy.ndarray, shape (N+1, nx)
        The fitted states at the record's samples.
    step : float
        The encoder's step, rad per count.
    dt : float
        The sample period, s.
    chunk_doubles : int, optional
        The per-sample inputs of a chunk of intervals run at once (default 2**20).
    ramp : numpy.ndarray, shape (N+1,), optional
        The recorded time's ramp a drifting torque constant multiplies the torque by (default None: no
        ``gain_drift`` response).

    Returns
    -------
    dict[str, numpy.ndarray]
        Effect name -> the encoder's response (B, L+1, m), counts per N m (0 off the samples ``valid`` scores).
    """
    n, (B, L) = sens.n, Ub.shape[:2]
    N1 = x_fit.shape[0]
    vm = encoder_rates(S, x_fit[:, :n], x_fit[:, n:2 * n])  # (N+1, m) motor velocity, rad/s
    held = Ub.reshape(B * L, -1)[: N1 - 1]  # (N, nu) the torque held over each period, as the fit takes it
    rate = np.diff(held, axis=0, append=held[-1:])
    sign = np.tanh(vm / max(0.05 * float(np.std(vm)), 1e-12))
    # the sheath friction's share that the tension's changes make (|tau_m| less its mean, times the sign): its mean's
    # share is the dry friction's, which the first regressor holds (with a biased torque the two were one direction)
    # (its sign smoothed as the model's capstan law smooths it, capstan_torque: the response of a missing capstan)
    tension = np.abs(np.concatenate([held, held[-1:]]))  # (N+1, m): the motors' torques, as the sheaths see them
    tension = tension - tension.mean(axis=0)
    tr = getattr(sens.model, "transmission", None)
    sheath = (tension * np.tanh(vm / capstan_velocity(tr.S, sens.model.extras.smooth_velocity))
              if tr is not None and tension.shape == vm.shape else None)
    sigs = {"sign_velocity": sign, "tension_sign_velocity": sheath,
            "velocity": vm, "acceleration": np.gradient(vm, dt, axis=0),
            "torque_rate": np.concatenate([rate, rate[-1:]])}
    sigs = {k: g for k, g in sigs.items() if g is not None}  # joint torques (no motors): no tension to weigh
    if ramp is not None:  # the torque times a ramp of the recorded time (N+1,): a drifting torque constant
        sigs["gain_drift"] = np.concatenate([held, held[-1:]]) * ramp[:, None]
    eps = 1e-6  # N m RMS of each perturbation: the response stays linear (about 0.1 count)
    pert = []
    for g in sigs.values():  # a loop over the effects (four to six)
        g = g / max(float(np.sqrt(np.mean(g**2))), 1e-300) * eps
        gp = np.concatenate([g[:-1], np.repeat(g[-2:-1], B * L - (N1 - 1), axis=0)])
        pert.append(gp.reshape(B, L, -1))
    per_int = corr is not None and (Psib is None or np.ndim(corr) == 3)  # per interval (a run's own lines too)
    y, k = [], max(1, chunk_doubles // (L * sens.nw))  # (600 s: 264 MB)
    for d in [0.0] + pert:  # the fitted run, then one per effect (one at a time: a 60 s record's are 30 MB each)
        U, C = Ub + d, (lambda a: corr[a:a + k]) if per_int else (lambda a: corr)
        xs = np.concatenate([sens.run(nodes[a:a + k], U[a:a + k], Gb[a:a + k], theta, C(a), sensitivities=False,
                                      basis=None if Psib is None else Psib[a:a + k])[0] for a in range(0, B, k)])
        y.append(encoder_angles(S, xs[:, :, :n]) / step)
    return {name: (y[i + 1] - y[0]) * valid[:, :, None] / eps for i, name in enumerate(sigs)}


def torque_explained(sens: Any, nodes: np.ndarray, Ub: np.ndarray, Gb: np.ndarray, theta: np.ndarray,
                      offs: np.ndarray, valid: np.ndarray, S: np.ndarray, step: float, sigma: float, L: int) -> float:
    """RMS encoder difference (counts) the recorded torque's white noise ``sigma`` (N m) makes through the
    fitted model, each interval from its fitted node, the noise's per-interval mean removed (the fit's
    per-interval corrections take it): a Monte Carlo of two draws (a fixed generator: the same number each call),
    states only.

    Parameters
    ----------
    sens : SensitivityModel
        The fit's sensitivity model (:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`).
    nodes : numpy.ndarray, shape (B, nx)
        The fitted nodes: each interval's start state.
    Ub : numpy.ndarray, shape (B, L, nu)
        The torque held over each period of each interval, N m, as the fit takes it.
    Gb : numpy.ndarray, shape (B, L, 3)
        Gravity, m/s^2, base frame, per period.
    theta : numpy.ndarray, shape (p,)
        The fitted parameters, in their units.
    offs : numpy.ndarray
        The fitted per-interval torque corrections (the run's ``offset`` coefficients).
    valid : numpy.ndarray of bool, shape (B, L+1)
        True on the samples scored (within the record; an interval's end counted once, as the next one's start).
    S : numpy.ndarray
        The transmission: its matrix (m, n), or its ratio curve (:func:`~alpes_dyn.model.ratio_curve.encoder_angles`).
    step : float
        The encoder's step, rad per count.
    sigma : float
        The torque's white noise, N m.
    L : int
        The samples per interval.

    Returns
    -------
    float
        The RMS encoder difference, counts.
    """
    rng = np.random.default_rng(0)
    R = 2
    w = sigma * rng.standard_normal((R,) + Ub.shape)
    w -= w.mean(axis=2, keepdims=True)
    B = Ub.shape[0]
    U = np.concatenate([Ub[None], Ub[None] + w]).reshape((R + 1) * B, L, -1)
    x0 = np.tile(nodes, (R + 1, 1))
    G = np.tile(Gb, (R + 1, 1, 1))
    off = np.tile(offs, (R + 1, 1))
    xs, _ = sens.run(x0, U, G, theta, off, sensitivities=False)
    y = encoder_angles(S, xs[:, :, : S.shape[1]]).reshape(R + 1, B, L + 1, -1) / step
    d = (y[1:] - y[:1]) * valid[None, :, :, None]
    return float(np.sqrt(np.sum(d**2) / (R * max(int(valid.sum()), 1) * S.shape[0])))
