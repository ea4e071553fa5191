"""A Kalman filter's prediction ``horizon`` samples ahead from many starts at once, in compiled C.

From the filter's estimate z_k|k (and its covariance P_k|k) at each start k, the model is stepped open loop over the
known inputs w_k .. w_k+H-1 with no update:

    z_j+1 = F(z_j, w_j),    P_j+1 = A_j P_j A_j^T + G_j Sigma_w G_j^T + Q    (A = dF/dz, G = dF/dw at z_j, w_j)

and the measurement predicted, h(z_k+H), with its covariance H P_k+H|k H^T + R: what the consistency of the
predictions (:func:`~alpes_dyn.estimation.observers.innovation.nis`) and the observer's check of a fit
(:func:`~alpes_dyn.estimation.identification.observer_check.observer_statistics`) read. Its cost is B starts times
H steps (the check's 0.1 s horizon from every fifth sample of a 4 s record: 68,000 steps of the covariance); in
CasADi's virtual machine they are most of the observer check's time. Here the step (z, P) -> (z_next, P_next) is CasADi's code
compiled once and run by :class:`~alpes_dyn.simulation.codegen.CompiledStepLoop` over the starts: the same
operations as the virtual machine's expression, the same numbers to rounding. The library is keyed on the model's
structure: its numbers, Sigma_w and Q are the step's input p, so a model of other values or another noise setting
loads it from the cache. Without a C compiler the virtual machine's map over the starts is used. A looped
filter's step (:mod:`~alpes_dyn.estimation.observers.looped`: the Shadow hand's 48 states) is its chain rule's graph
with the covariance and the Jacobians in one state, compiled the same way (:func:`predicted_step`: the NEES's and the
NIS's one-step prediction computed once for both).
"""

from __future__ import annotations

import threading
import uuid
from typing import Any

import casadi as cs
import numpy as np

from ...simulation.buildcache import expression_key

__all__ = ["AHEAD_BATCH", "AHEAD_COMPILE_MAX", "predicted_ahead", "predicted_step", "keep_predicted", "linearised",
           "kept_run", "MAX_KEPT_BYTES"]

AHEAD_BATCH = 256
"""Starts run per call of the compiled loop: its trajectory buffer (starts x (H + 1) x (nz + nz^2) doubles) stays a
few tens of MB for the LuGre model's states and a 0.1 s horizon."""


AHEAD_COMPILE_MAX = 100_000
"""CasADi instructions: a step above it is run by the virtual machine, not compiled. A finger's covariance step
(finger3 with friction, four substeps) builds in seconds; a large hand's (the Allegro hand's 32 states) keeps the
compiler busy for minutes and gigabytes, longer than the virtual machine's whole run of ``estimate``'s checks. A step
whose C is over the compiled loops' large-source size (the thumb's covariance) is built at ``-O0``
(:class:`~alpes_dyn.simulation.codegen.CompiledStepLoop`'s ``large_level``): faster to build than at ``-O1``, whose
build would outlast the check's runs of it; a smaller one (a finger's) at ``-O0`` too (``level``): a quarter of
``-O3``'s build, for runs of a fraction of a second (CHANGELOG)."""


def _steps(filt: Any, covariance: bool | str) -> tuple[cs.Function, np.ndarray]:
    """The step (s, w, p) -> s_next, s = z (mean alone), [z; vec P] (with ``covariance``), [z; vec X; vec Y]
    (``covariance="jacobians"``: X A and X G + Y, the step's Jacobians A = dF/dz, G = dF/dw from X = I, Y = 0) or
    [z; vec P; vec X; vec Y] (``covariance="looped"``: both, by a looped filter's chain rule, :func:`_looped_step`),
    and its p: the model's numbers (``filt.model.values``), then vec Sigma_w and vec Q where the covariance is
    stepped."""
    if covariance == "looped":
        return _looped_step(filt)
    mdl = filt.model
    nz, nw = mdl.nz, mdl.nw
    z, w, pm = cs.SX.sym("z", nz), cs.SX.sym("w", nw), cs.SX.sym("p", mdl.values.size)
    zn = mdl.step_p(z, w, pm)
    if not covariance:
        return cs.Function("ahead_mean", [z, w, pm], [zn]), _values(filt, covariance)
    if covariance == "jacobians":
        X, Y = cs.SX.sym("X", nz, nz), cs.SX.sym("Y", nz, nw)
        A, G = cs.jacobian(zn, z), cs.jacobian(zn, w)
        out = cs.vertcat(zn, cs.vec(cs.mtimes(A, X)), cs.vec(cs.mtimes(A, Y) + G))
        return cs.Function("ahead_jac", [cs.vertcat(z, cs.vec(X), cs.vec(Y)), w, pm], [out]), _values(filt, covariance)
    P, Sw, Q = cs.SX.sym("P", nz, nz), cs.SX.sym("Sw", nw, nw), cs.SX.sym("Q", nz, nz)
    A, G = cs.jacobian(zn, z), cs.jacobian(zn, w)
    Pn = cs.mtimes([A, P, A.T]) + cs.mtimes([G, Sw, G.T]) + Q
    p = cs.vertcat(pm, cs.vec(Sw), cs.vec(Q))
    step = cs.Function("ahead", [cs.vertcat(z, cs.vec(P)), w, p], [cs.vertcat(zn, cs.vec(Pn))])
    return step, _values(filt, True)


def _values(filt: Any, covariance: bool | str) -> np.ndarray:
    """(np,) the step's p of ``filt`` (:func:`_steps`): the model's numbers, then vec Sigma_w and vec Q where the
    covariance is stepped (column-major, as the step reads them)."""
    values = np.asarray(filt.model.values, dtype=float)
    if covariance not in (True, "looped"):
        return values
    return np.concatenate([values, np.asarray(filt.Sw, float).reshape(-1, order="F"),
                           np.asarray(filt.Q, float).reshape(-1, order="F")])


def _structure(filt: Any) -> str:
    """The key of ``filt``'s step structure: a hash of its model's step (z, w, p) -> z_next serialised (the
    expression, its numbers an input p); two filters of one key share their compiled loops (:func:`_loop`), whatever
    their numbers or noise; a looped filter's (a large state, whose unrolled step is never built) is its own. Kept on
    the filter."""
    key = filt.__dict__.get("_ahead_key")
    if key is None and getattr(filt, "looped", False):  # never the unrolled step of a large state: its own loops
        key = filt.__dict__["_ahead_key"] = uuid.uuid4().hex
    if key is None:
        mdl = filt.model
        z, w, pm = cs.SX.sym("z", mdl.nz), cs.SX.sym("w", mdl.nw), cs.SX.sym("p", mdl.values.size)
        key = filt.__dict__["_ahead_key"] = expression_key(cs.Function("ahead_mean", [z, w, pm],
                                                                        [mdl.step_p(z, w, pm)]))
    return key


_LOOPS = threading.local()
"""This thread's compiled loops (``loops``), by (:func:`_structure`, kind): the observer's filters of one structure
(the model error's calibration builds one per trial noise, :mod:`~alpes_dyn.estimation.identification.
noise_calibration`) generate and load the C once (about 0.8 s each on finger3), not once per filter; per thread, as
:mod:`~alpes_dyn.simulation.sampled`'s, since each run writes its filter's numbers into the loop's parameters."""


def _looped_step(filt: Any) -> tuple[cs.Function, np.ndarray]:
    """A looped filter's step (:mod:`~alpes_dyn.estimation.observers.looped`) with its covariance and Jacobians,
    ``MX``: (s = [z; vec P; vec X; vec Y], w, p) -> [F(z, w); vec(A P A^T + G Sigma_w G^T + Q); vec(A X);
    vec(A Y + G)], A and G by :func:`~alpes_dyn.estimation.observers.looped.linearization` (the chain rule over the
    substeps, never the unrolled step's Jacobian); p = [the model's numbers; vec Sigma_w; vec Q], with its values."""
    from .looped import linearization

    mdl = filt.model
    nz, nw, npar = mdl.nz, mdl.nw, mdl.values.size
    z, w, p = cs.MX.sym("z", nz), cs.MX.sym("w", nw), cs.MX.sym("p", npar + nw * nw + nz * nz)
    P, X, Y = cs.MX.sym("P", nz, nz), cs.MX.sym("X", nz, nz), cs.MX.sym("Y", nz, nw)
    zn, A, G = linearization(mdl)(z, w, p[:npar])
    Sw, Q = cs.reshape(p[npar: npar + nw * nw], nw, nw), cs.reshape(p[npar + nw * nw:], nz, nz)
    Pn = cs.mtimes([A, P, A.T]) + cs.mtimes([G, Sw, G.T]) + Q
    out = cs.vertcat(zn, cs.vec(Pn), cs.vec(cs.mtimes(A, X)), cs.vec(cs.mtimes(A, Y) + G))
    return cs.Function("ahead_looped", [cs.vertcat(z, cs.vec(P), cs.vec(X), cs.vec(Y)), w, p], [out]), \
        _values(filt, "looped")


def _loop(filt: Any, covariance: bool | str) -> Any:
    """The compiled loop of ``filt``'s step (:func:`_steps`), built once per step structure in this thread
    (:data:`_LOOPS`, :func:`_structure`) and loaded from the disk cache by any other process, its parameters set to
    ``filt``'s numbers and noise (:func:`_values`); None without a C compiler or above :data:`AHEAD_COMPILE_MAX`."""
    from ...simulation.integrate import CompiledStepLoop, CompilerError

    loops = _LOOPS.__dict__.setdefault("loops", {})
    key = (_structure(filt), covariance)
    if key not in loops:
        step, values = _steps(filt, covariance)
        if step.n_instructions() > AHEAD_COMPILE_MAX:
            loops[key] = None
            return None
        try:
            kind = {False: "", True: "_cov", "jacobians": "_jac", "looped": "_looped"}[covariance]
            # a looped filter's runs are long: optimised above the size; the others' -O0 whatever their size
            level = {"large_level": "-O1"} if covariance == "looped" else {"level": "-O0"}
            loops[key] = CompiledStepLoop(step, f"ahead{kind}_{filt.model.system.model.name}", threads=1,
                                          vectorize=False, parameters=values, **level)
        except CompilerError:
            loops[key] = None
    loop = loops[key]
    if loop is not None:
        np.copyto(loop.parameters, _values(filt, covariance))  # in place: the buffer the compiled loop reads
    return loop


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


def _looped(filt: Any, z0: np.ndarray, P0: np.ndarray | None, Wb: np.ndarray) -> tuple[np.ndarray, ...]:
    """:func:`_run` for a looped filter (:mod:`~alpes_dyn.estimation.observers.looped`: a state too large for the
    unrolled step's Jacobian): its step with covariance and Jacobians (:func:`_looped_step`, compiled once and
    cached; the virtual machine's map without a compiler) from each start z0 (B, nz), P0 (B, nz, nz) (None: zero)
    over the inputs Wb (B, H, nw), :data:`AHEAD_BATCH` starts at a time. Returns (z (B, nz), P (B, nz, nz), A (B,
    nz, nz), G (B, nz, nw)) after the horizon: A and G the Jacobians of the horizon's map (one step's at H = 1)."""
    nz, nw = filt.model.nz, filt.model.nw
    B, n2 = z0.shape[0], nz * nz
    loop = _loop(filt, "looped")
    out = (np.empty((B, nz)), np.empty((B, nz, nz)), np.empty((B, nz, nz)), np.empty((B, nz, nw)))
    for b in range(0, B, AHEAD_BATCH):
        sl = slice(b, min(b + AHEAD_BATCH, B))
        s0 = np.zeros((sl.stop - b, nz + 2 * n2 + nz * nw))
        s0[:, :nz] = z0[sl]
        if P0 is not None:
            s0[:, nz: nz + n2] = P0[sl].transpose(0, 2, 1).reshape(-1, n2)  # column-major vec
        s0[:, nz + n2: nz + 2 * n2] = np.eye(nz).reshape(-1)
        W = np.ascontiguousarray(Wb[sl])
        end = loop.run(s0, W)[:, -1] if loop is not None else _vm(filt, s0, W, "looped")
        out[0][sl] = end[:, :nz]
        for k, (a, e, cols) in enumerate(((nz, nz + n2, nz), (nz + n2, nz + 2 * n2, nz), (nz + 2 * n2, None, nw))):
            out[k + 1][sl] = end[:, a:e].reshape(-1, cols, nz).transpose(0, 2, 1)
    return out


def predicted_step(filt: Any, z: np.ndarray, W: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, ...]:
    """A looped filter's one-step prediction from each sample of its run, compiled: what the NEES's error model
    (:func:`~alpes_dyn.estimation.observers.consistency.predicted_covariance`) and the NIS of the innovations
    (:func:`predicted_ahead` at ``horizon`` 1) both read, computed once for both (the last run's kept on the filter,
    keyed on its inputs' bytes; a filter's own run keeps its prediction there, :func:`~alpes_dyn.estimation.
    observers.ahead.kept_run`: then nothing is stepped again).

    Parameters
    ----------
    filt : ~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter
        A looped filter (``filt.looped``).
    z : ndarray
        (N, nz) its estimates z_k|k; the first K = N - 1 are used.
    W : ndarray
        (K, nw) its known inputs, row k held from sample k to k + 1.
    P : ndarray
        (N, nz, nz) the estimates' covariances P_k|k.

    Returns
    -------
    tuple of ndarray
        (z_k+1|k (K, nz), P_k+1|k = A_k P_k A_k^T + G_k Sigma_w G_k^T + Q (K, nz, nz), A_k = dF/dz (K, nz, nz),
        G_k = dF/dw (K, nz, nw)).
    """
    K = W.shape[0]
    key = _step_key(z[:K], P[:K], W)
    kept = filt.__dict__.get("_predicted_step")
    if kept is None or kept[0] != key:
        z, P, W = (np.ascontiguousarray(a, dtype=float) for a in (z[:K], P[:K], W))
        kept = filt.__dict__["_predicted_step"] = (key, _looped(filt, z, P, W[:, None, :]))
    return kept[1]


def _step_key(z: np.ndarray, P: np.ndarray, W: np.ndarray) -> bytes:
    """The key of :func:`predicted_step`'s kept prediction: a hash of its inputs' bytes and shapes."""
    import hashlib

    h = hashlib.blake2b(digest_size=16)
    for a in (z, P, W):  # the bytes of each array made contiguous, a block of rows at a time (no copy of the whole)
        for b in range(0, max(len(a), 1), 256):
            h.update(np.ascontiguousarray(a[b: b + 256], dtype=float).tobytes())
    h.update(repr((np.shape(z), np.shape(P), np.shape(W))).encode())
    return h.digest()


def keep_predicted(filt: Any, z: np.ndarray, P: np.ndarray, W: np.ndarray, predicted: tuple[np.ndarray, ...]
                   ) -> None:
    """Keep on ``filt`` the one-step prediction its run computed (:func:`~alpes_dyn.estimation.observers.looped.
    kept_run`), for :func:`predicted_step` of the same estimates and inputs to return instead of stepping again.

    Parameters
    ----------
    filt : ~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter
        A looped filter.
    z : ndarray
        (K, nz) its estimates z_k|k, k = 0 .. K - 1.
    P : ndarray
        (K, nz, nz) their covariances.
    W : ndarray
        (K, nw) the known inputs.
    predicted : tuple of ndarray
        (z_k+1|k (K, nz), P_k+1|k (K, nz, nz), A_k (K, nz, nz), G_k (K, nz, nw)): :func:`predicted_step`'s.
    """
    filt.__dict__["_predicted_step"] = (_step_key(z, P, W), predicted)


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
        return _looped(filt, z[:K], None, W[:, None, :])[2:]
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
    Wb = np.lib.stride_tricks.sliding_window_view(W, horizon, axis=0)[starts].transpose(0, 2, 1)  # (B, H, nw)
    if getattr(filt, "looped", False) and covariance and horizon == 1:
        zend, Pend = (a[starts] for a in predicted_step(filt, z, W, P)[:2])  # (shared with the NEES)
    elif getattr(filt, "looped", False):
        zend, Pend = _looped(filt, z[starts], P[starts] if covariance else None, Wb)[:2]
    else:
        s0 = z[starts] if not covariance else np.concatenate(
            [z[starts], P[starts].transpose(0, 2, 1).reshape(len(starts), -1)], axis=1)
        end = _run(filt, s0, Wb, covariance)
        zend = end[:, :nz]
        Pend = end[:, nz:].reshape(len(starts), nz, nz).transpose(0, 2, 1) if covariance else None
    zs = cs.SX.sym("zs", nz)
    h = cs.Function("h", [zs], [mdl.output(zs), cs.densify(cs.jacobian(mdl.output(zs), zs))]).map(len(starts))
    y, Hs = h(zend.T)
    y = np.asarray(y).T
    if not covariance:
        return y, None
    B, m = len(starts), mdl.ny
    Hs = np.asarray(Hs).reshape(m, B, nz).transpose(1, 0, 2)
    return y, Hs @ Pend @ Hs.transpose(0, 2, 1) + filt.R


MAX_KEPT_BYTES = 512 * 2**20
"""Largest kept prediction of :func:`kept_run`, bytes: [z_pred; vec P_pred; vec A; vec G] per sample is about 3.4
times the run's own [z; vec P] (64 kB per sample on the Shadow hand, so 512 MiB at about 8,000 samples). A longer
record runs the filter's plain step instead (:func:`kept_run` returns None), its prediction recomputed where the
consistency checks ask for it: one more pass along the run, not a run's memory grown past what
:func:`~alpes_dyn.limits.check_bytes` admitted."""


def kept_run(filt: Any, s0: np.ndarray, WY: np.ndarray, W: np.ndarray) -> np.ndarray | None:
    """A looped filter's run that keeps each step's prediction and Jacobians for its consistency checks: the NEES's
    error model and the NIS's one-step prediction (:func:`~alpes_dyn.estimation.observers.ahead.predicted_step`)
    read them from this run instead of stepping the model again along it (on the Shadow hand the same cost as the
    filter's run). The filter's step compiled with its prediction z_k+1|k, P_k+1|k = A_k P_k|k A_k^T + G_k
    Sigma_w G_k^T + Q and A_k = dF/dz, G_k = dF/dw as more outputs (``filt._kept_step_p`` of :func:`~.looped.looped_functions`), run once.

    Parameters
    ----------
    filt : ExtendedKalmanFilter
        A looped filter (``filt.looped``; :func:`looped_functions`'s ``_kept_step_p`` set).
    s0 : numpy.ndarray
        (nz + nz^2,) the state after the first measurement's update: [z_0|0; vec P_0|0] (column-major).
    WY : numpy.ndarray
        (N, nw + ny) the known inputs w_k and the measurements y_k+1.
    W : numpy.ndarray
        (N, nw) the known inputs alone (the key the prediction is kept under, with the run's estimates).

    Returns
    -------
    numpy.ndarray or None
        (N + 1, nz + nz^2) [z_k|k; vec P_k|k] (a view of the run's states) as the filter's step gives them (the
        same numbers to the bit), or None without a C compiler or where the kept prediction would be over
        :data:`MAX_KEPT_BYTES` (the caller's run then, its prediction recomputed where asked).
    """
    from ...simulation.integrate import CompiledStepLoop, CompilerError
    from .looped import kept_size

    if 8.0 * (WY.shape[0] + 1) * kept_size(filt.model) > MAX_KEPT_BYTES:
        return None
    loop = filt.__dict__.get("_kept_loop")
    if loop is None:
        try:
            loop = filt.__dict__["_kept_loop"] = CompiledStepLoop(
                filt._kept_step_p, f"{filt.kind}_kept_{filt.model.system.model.name}", threads=1, vectorize=False,
                parameters=filt.model.values)
        except CompilerError:
            return None
    mdl = filt.model
    nz, nw, n2 = mdl.nz, mdl.nw, mdl.nz * mdl.nz
    x0 = np.zeros(kept_size(mdl))
    x0[: nz + n2] = s0
    S = loop.run(x0[None], np.ascontiguousarray(WY)[None])[0]
    N = WY.shape[0]
    out = S[:, : nz + n2]  # (a view: the estimates and the kept prediction share the run's one array)
    T = S[1:, nz + n2:]  # step k's prediction and Jacobians, k = 0 .. N - 1
    pred = (T[:, :nz], T[:, nz: nz + n2].reshape(N, nz, nz).transpose(0, 2, 1),
            T[:, nz + n2: nz + 2 * n2].reshape(N, nz, nz).transpose(0, 2, 1),
            T[:, nz + 2 * n2:].reshape(N, nw, nz).transpose(0, 2, 1))
    keep_predicted(filt, out[:N, :nz], out[:N, nz:].reshape(N, nz, nz).transpose(0, 2, 1), W, pred)
    return out
