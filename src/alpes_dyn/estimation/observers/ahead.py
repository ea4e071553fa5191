"""A Kalman filter's prediction ``horizon`` samples ahead from many starts at once, in compiled C.

From the filter's estimate z_k|k (and its covariance P_k|k) at each start k, the model is stepped open loop over the
known inputs w_k .. w_k+H-1 with no update:

    z_j+1 = F(z_j, w_j),    P_j+1 = A_j P_j A_j^T + G_j Sigma_w G_j^T + Q    (A = dF/dz, G = dF/dw at z_j, w_j)

and the measurement predicted, h(z_k+H), with its covariance H P_k+H|k H^T + R: what the consistency of the
predictions (:func:`~alpes_dyn.estimation.observers.innovation.nis`) and the observer's check of a fit
(:func:`~alpes_dyn.estimation.identification.observer_check.observer_statistics`) read. Its cost is B starts times
H steps (the check's 0.1 s horizon from every fifth sample of a 4 s record: 68,000 steps of the covariance); CasADi's
virtual machine took most of the observer check's time. Here the step (z, P) -> (z_next, P_next) is CasADi's code
compiled once and run by :class:`~alpes_dyn.simulation.codegen.CompiledStepLoop` over the starts: the same
operations as the virtual machine's expression, the same numbers to rounding. The library is keyed on the model's
structure: its numbers, Sigma_w and Q are the step's input p, so a model of other values or another noise setting
loads it from the cache. Without a C compiler the virtual machine's map over the starts is used.
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from .looped import step_jacobians

__all__ = ["AHEAD_BATCH", "AHEAD_COMPILE_MAX", "predicted_ahead", "linearised"]

AHEAD_BATCH = 256
"""Starts run per call of the compiled loop: its trajectory buffer (starts x (H + 1) x (nz + nz^2) doubles) stays a
few tens of MB for the LuGre model's states and a 0.1 s horizon."""


AHEAD_COMPILE_MAX = 100_000
"""CasADi instructions: a step above it is run by the virtual machine, not compiled. A finger's covariance step
(finger3 with friction, four substeps: 47k instructions) builds in seconds; the Allegro hand's (32 states: 212k) kept
gcc busy over 5 minutes and 4 GB, longer than the virtual machine's whole run of ``estimate``'s checks. A step whose
C is over the compiled loops' large-source size (the thumb's covariance, 1.5 MB) is built at ``-O0``
(:class:`~alpes_dyn.simulation.codegen.CompiledStepLoop`'s ``large_level``): seconds, where ``-O1`` took about 25 s
of gcc, longer than the check's runs of it."""


def _steps(filt: Any, covariance: bool | str) -> tuple[cs.Function, np.ndarray]:
    """The step (s, w, p) -> s_next, s = z (mean alone), [z; vec P] (with ``covariance``) or [z; vec X; vec Y]
    (``covariance="jacobians"``: X A and X G + Y, the step's Jacobians A = dF/dz, G = dF/dw from X = I, Y = 0), and
    its p: the model's numbers (``filt.model.values``), then vec Sigma_w and vec Q where the covariance is stepped."""
    mdl = filt.model
    nz, nw = mdl.nz, mdl.nw
    z, w, pm = cs.SX.sym("z", nz), cs.SX.sym("w", nw), cs.SX.sym("p", mdl.values.size)
    zn = mdl.step_p(z, w, pm)
    if not covariance:
        return cs.Function("ahead_mean", [z, w, pm], [zn]), np.asarray(mdl.values, dtype=float)
    if covariance == "jacobians":
        X, Y = cs.SX.sym("X", nz, nz), cs.SX.sym("Y", nz, nw)
        A, G = cs.jacobian(zn, z), cs.jacobian(zn, w)
        out = cs.vertcat(zn, cs.vec(cs.mtimes(A, X)), cs.vec(cs.mtimes(A, Y) + G))
        return (cs.Function("ahead_jac", [cs.vertcat(z, cs.vec(X), cs.vec(Y)), w, pm], [out]),
                np.asarray(mdl.values, dtype=float))
    P, Sw, Q = cs.SX.sym("P", nz, nz), cs.SX.sym("Sw", nw, nw), cs.SX.sym("Q", nz, nz)
    A, G = cs.jacobian(zn, z), cs.jacobian(zn, w)
    Pn = cs.mtimes([A, P, A.T]) + cs.mtimes([G, Sw, G.T]) + Q
    p = cs.vertcat(pm, cs.vec(Sw), cs.vec(Q))
    values = np.concatenate([mdl.values, np.asarray(filt.Sw, float).reshape(-1, order="F"),
                             np.asarray(filt.Q, float).reshape(-1, order="F")])
    step = cs.Function("ahead", [cs.vertcat(z, cs.vec(P)), w, p], [cs.vertcat(zn, cs.vec(Pn))])
    return step, values


def _loop(filt: Any, covariance: bool | str) -> Any:
    """The filter's compiled loop of the step (:func:`_steps`), built once per filter (kept on it) and loaded from
    the disk cache by any filter of the same structure; None without a C compiler or above
    :data:`AHEAD_COMPILE_MAX`."""
    from ...simulation.integrate import CompiledStepLoop, CompilerError

    cache = filt.__dict__.setdefault("_ahead_loops", {})
    if covariance not in cache:
        step, values = _steps(filt, covariance)
        if step.n_instructions() > AHEAD_COMPILE_MAX:
            cache[covariance] = None
            return None
        try:
            kind = {False: "", True: "_cov", "jacobians": "_jac"}[covariance]
            cache[covariance] = CompiledStepLoop(step, f"ahead{kind}_"
                                                       f"{filt.model.system.model.name}", threads=1,
                                                 vectorize=False, parameters=values, large_level="-O0")
        except CompilerError:
            cache[covariance] = None
    return cache[covariance]


def _vm(filt: Any, s0: np.ndarray, Wb: np.ndarray, covariance: bool | str) -> np.ndarray:
    """(B, ns) the state after the horizon by CasADi's virtual machine (the fallback without a compiler)."""
    step, values = _steps(filt, covariance)
    B, H, nw = Wb.shape
    acc = step.mapaccum("ahead", H).map(B)
    out = acc(s0.T, Wb.transpose(2, 1, 0).reshape(nw, -1, order="F"), values)
    return np.asarray(out).reshape(s0.shape[1], H, B, order="F")[:, -1, :].T


def _run(filt: Any, s0: np.ndarray, Wb: np.ndarray, covariance: bool | str) -> np.ndarray:
    """(B, ns) the state after the horizon from each row of s0 (B, ns) with the inputs Wb (B, H, nw): the compiled
    loop :data:`AHEAD_BATCH` starts at a time, or the virtual machine without a compiler."""
    loop = _loop(filt, covariance)
    if loop is None:
        return _vm(filt, s0, Wb, covariance)
    return np.concatenate([loop.run(s0[b: b + AHEAD_BATCH], np.ascontiguousarray(Wb[b: b + AHEAD_BATCH]))[:, -1]
                           for b in range(0, s0.shape[0], AHEAD_BATCH)])


def _looped(filt: Any, s0: np.ndarray, Wb: np.ndarray, covariance: bool) -> np.ndarray:
    """:func:`_run` for a looped filter (:mod:`~alpes_dyn.estimation.observers.looped`: a state too large for the
    unrolled step's Jacobian): the step and its Jacobians by its chain rule (``MX``), accumulated over the horizon by
    CasADi's ``mapaccum`` and mapped over the starts in its virtual machine. (B, ns) the end states."""
    mdl = filt.model
    nz, nw = mdl.nz, mdl.nw
    B, H = Wb.shape[0], Wb.shape[1]
    z, w = cs.MX.sym("z", nz), cs.MX.sym("w", nw)
    zn, A, G = step_jacobians(filt)(z, w)
    if covariance:
        P = cs.MX.sym("P", nz, nz)
        Pn = cs.mtimes([A, P, A.T]) + cs.mtimes([G, cs.DM(filt.Sw), G.T]) + cs.DM(filt.Q)
        step = cs.Function("pred", [cs.vertcat(z, cs.vec(P)), w], [cs.vertcat(zn, cs.vec(Pn))])
    else:
        step = cs.Function("pred", [z, w], [zn])
    out = step.mapaccum("ahead", H).map(B)(s0.T, Wb.transpose(2, 1, 0).reshape(nw, -1, order="F"))
    return np.asarray(out).reshape(s0.shape[1], H, B, order="F")[:, -1, :].T


def linearised(filt: Any, z: np.ndarray, W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The filter's step linearised along its run: A_k = dF/dz and G_k = dF/dw at (z_k, w_k), compiled.

    Parameters
    ----------
    filt : ~alpes_dyn.estimation.observers.observers.KalmanFilter
        The filter (its ``model``).
    z : ndarray
        (N, nz) the filter's estimates; the first N - 1 are used.
    W : ndarray
        (N - 1, nw) its known inputs, row k held from sample k to k + 1.

    Returns
    -------
    tuple of ndarray
        (A (N-1, nz, nz), G (N-1, nz, nw)).
    """
    nz, nw, K = filt.model.nz, filt.model.nw, W.shape[0]
    if getattr(filt, "looped", False):  # a large state: its chain rule, never the unrolled step's Jacobian
        A, G = step_jacobians(filt).map(K)(z[:K].T, W.T)[1:]
        return (np.asarray(A).reshape(nz, K, nz).transpose(1, 0, 2),  # the map stacks the samples side by side
                np.asarray(G).reshape(nz, K, nw).transpose(1, 0, 2))
    s0 = np.zeros((K, nz + nz * nz + nz * nw))
    s0[:, :nz] = z[:K]
    s0[:, nz: nz + nz * nz] = np.eye(nz).reshape(-1)
    end = _run(filt, s0, W[:, None, :], "jacobians")
    A = end[:, nz: nz + nz * nz].reshape(K, nz, nz).transpose(0, 2, 1)  # column-major vec
    return A, end[:, nz + nz * nz:].reshape(K, nw, nz).transpose(0, 2, 1)


def predicted_ahead(filt: Any, z: np.ndarray, W: np.ndarray, starts: np.ndarray, horizon: int,
                    P: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
    """The measurement the filter's model predicts ``horizon`` samples after each start, and its covariance.

    Parameters
    ----------
    filt : ~alpes_dyn.estimation.observers.observers.KalmanFilter
        The filter (its :class:`~alpes_dyn.estimation.observers.discrete.DiscreteModel` ``model``, its ``Q``,
        ``Sw`` and ``R``).
    z : ndarray
        (N, nz) the filter's estimates z_k|k.
    W : ndarray
        (N - 1, nw) its known inputs, row k held from sample k to k + 1.
    starts : ndarray
        (B,) int, the samples k predicted from (k + ``horizon`` <= N - 1).
    horizon : int
        H >= 1, samples ahead.
    P : ndarray or None, optional
        (N, nz, nz) the estimates' covariances P_k|k: where given, the prediction's covariance is propagated too.

    Returns
    -------
    tuple
        (y (B, ny) the predicted measurement, in the output's units; S (B, ny, ny) = H P_k+H|k H^T + R, or None
        without ``P``).
    """
    mdl = filt.model
    nz, covariance = mdl.nz, P is not None
    starts = np.asarray(starts, dtype=int)
    s0 = z[starts] if not covariance else np.concatenate(
        [z[starts], P[starts].transpose(0, 2, 1).reshape(len(starts), -1)], axis=1)
    Wb = np.lib.stride_tricks.sliding_window_view(W, horizon, axis=0)[starts].transpose(0, 2, 1)  # (B, H, nw)
    end = _looped(filt, s0, Wb, covariance) if getattr(filt, "looped", False) else _run(filt, s0, Wb, covariance)
    zs = cs.SX.sym("zs", nz)
    h = cs.Function("h", [zs], [mdl.output(zs), cs.densify(cs.jacobian(mdl.output(zs), zs))]).map(len(starts))
    y, Hs = h(end[:, :nz].T)
    y = np.asarray(y).T
    if not covariance:
        return y, None
    B, m = len(starts), mdl.ny
    Hs = np.asarray(Hs).reshape(m, B, nz).transpose(1, 0, 2)
    Pend = end[:, nz:].reshape(B, nz, nz).transpose(0, 2, 1)
    return y, Hs @ Pend @ Hs.transpose(0, 2, 1) + filt.R
