"""A long recording's fit started from a window of it (issue 39).

The globalisation of the shooting fit (:class:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton`: stage 1, each
interval's start state alone; stage 2, the homotopy, four phases of Levenberg-Marquardt; two starts) costs some
twenty to thirty evaluations of the whole record with its sensitivities, each linear in its length: on a long
record the compiled sensitivities are most of the fit, the linear algebra little. Its only purpose is to find the
basin, and a few seconds of the record find it as well (a 4 s record's fit: ``benchmarks/results/fit_scaling.json``,
its first row). So a record longer than :data:`LONG_RECORD` is fitted in two steps: the whole fit (stages 1-3,
both starts) on its first :data:`WINDOW` seconds; then, on the whole record from the window's parameters, the
model's response under them (the nodes on the encoder,
:meth:`~alpes_dyn.estimation.identification.shooting.ShootingProblem.initial_nodes`) made continuous in the start
states alone (:meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.join_nodes`: their sensitivities
alone, a third of the whole's) and stage 3 from there. Stage 3 needs a continuous start: from stage 1's nodes (each
interval fitted alone, defects of its noise) it crawls into the iteration cap (the line search held to short steps
by the defects). From the joined nodes, though their residual is well above the floor (the window's parameters,
and the torque's line corrections at 0), it converges in a few iterations, as it did after the homotopy's last
phase, whose evaluations of the whole record with all its sensitivities, and stage 1's sweeps, the join replaces
(the fits by record length: ``benchmarks/results/fit_scaling.json``). Where the join leaves the start discontinuous
(:data:`JOIN_LIMIT`: a joint without spring, whose response from rest drifts over minutes, the thumb's
ab/adduction), stage 1's nodes and the homotopy's last phase start stage 3 instead, as before the join. Where stage
3 does not converge within the basin limit,
:meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.solve` falls back to the whole fit of the whole
record, as for any warm start: the answer is the same problem's, only its start differs.

A recording of several runs (issue 51: several runs fitted together took far longer than the runs fitted one by
one) starts from its runs fitted one by one (:func:`runs_start`): each run alone the whole fit (from its own
window where it is long), then the whole record from every run's own fitted trajectory and the runs' mean
parameters, stage 3 alone. The window of the first run's first seconds left the other runs' starts to the model's
response from rest, which on a springless finger drifts past :data:`JOIN_LIMIT` and sent the fit through the
homotopy on the whole record, then to the cold fit: its cost grew with the runs faster than their number.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...limits import check_bytes
from ...model.robot import Model
from ...symbolic.parametric import select_parameters
from ..experiments.recording import segment_starts
from .gauss_newton import BASIN_LIMIT, SOFT_PHASES, GaussNewton
from ..experiments.recording import Recording
from .shooting import Evaluation, ShootingProblem, torque_model
from .runs import split

__all__ = ["LONG_RECORD", "RUNS_START", "WINDOW", "JOIN_LIMIT", "MMAP_THRESHOLD", "window_start", "start_from",
           "runs_start", "fit_bytes", "check_fit_size"]

LONG_RECORD = 12.0
"""s: records longer than this start from a fit of their first :data:`WINDOW` seconds."""
WINDOW = 4.0
"""s: the window whose fit starts a long record's (the documented experiment's length)."""
JOIN_LIMIT = 0.1
"""The joined start is kept where its defects are at most this fraction of the nodes' scale (per state component);
else stage 1's nodes and the homotopy's last phase start stage 3. The model's response from rest under the window's
parameters drifts where a joint has no spring (the thumb's ab/adduction: after the join's steps the defects
stay a large share of the scale, and stage 3 from there crawls into its cap of
:data:`~alpes_dyn.estimation.identification.gauss_newton.WINDOW_ITERATIONS`); a finger's, on springs, joins to a
small fraction of it."""
RUNS_START = LONG_RECORD
"""s: a record of several runs longer than this (their durations summed) starts from its runs fitted one by one
(:func:`runs_start`); a shorter one, cheap to fit whole, is fitted from the model's own response as before. From the
runs' start stage 3 stops (its relative cost change) with the flat directions less polished: on noise-free runs
the dry friction comes further off the truth than fitted whole; on noisy runs within a small fraction of its
standard error of the whole fit (``tests/test_runs_start.py``)."""
WINDOW_RUN = 0.5
"""s: a recording of several runs: the window ends at the start of its last run where that run would have less
than this in it (a run of a few samples holds no line of the excitation)."""


def fit_bytes(samples: int, states: int, outputs: int, parameters: int, basis: int) -> float:
    """Bytes of the arrays a fit holds for every sample of its record, each counted twice (the solve's copy): the
    torque lines' basis, the Jacobian's rows (each output's sensitivity to its interval's start state, the
    parameters and the lines' coefficients) and the states. A lower bound of the fit's peak.

    Parameters
    ----------
    samples : int
        The record's samples N.
    states : int
        The model's states (2 n).
    outputs : int
        The encoders (and cameras) read at each sample.
    parameters : int
        The parameters fitted.
    basis : int
        The torque lines' basis width (2 lines + 1, times the record's orientations).

    Returns
    -------
    float
        Bytes.
    """
    return 16.0 * samples * (basis + outputs * (states + parameters + basis) + states)


def check_fit_size(rec: Recording, model: Model, parameters: object, excitation: object) -> None:
    """:class:`~alpes_dyn.InputError` naming ``recording`` where the fit of ``rec`` would hold more than
    :func:`~alpes_dyn.limits.max_bytes` of arrays (:func:`fit_bytes`), before any is made: the guard
    :func:`~alpes_dyn.estimation.observers.replay.estimate_recording` has for its observer.

    Parameters
    ----------
    rec : Recording
        The recording to fit.
    model : Model
        The model fitted.
    parameters : str or sequence of str or None
        The selection (:func:`~alpes_dyn.symbolic.parametric.select_parameters`).
    excitation : sequence of float or None
        The excitation's lines, Hz.
    """
    N = rec.t.shape[0]
    basis = (2 * int(np.size(excitation)) + 1) * segment_starts(rec.gravity).size if excitation is not None else 1
    p = len(select_parameters(model, parameters))
    check_bytes(fit_bytes(N, 2 * model.n, rec.encoder.shape[1], p, basis), "recording", f"{N} samples for the fit")


def window(rec: Recording, seconds: float) -> Recording:
    """The first ``seconds`` of ``rec`` (every per-sample column cut alike; of several runs, not a last run
    shorter than :data:`WINDOW_RUN`)."""
    k = min(int(round(seconds / rec.dt)) + 1, rec.n_samples)
    b = rec.run_starts()
    last = int(b[np.searchsorted(b, k, side="left") - 1])  # the start of the run sample k - 1 is in
    if 0 < last and (k - last) * rec.dt < WINDOW_RUN:
        k = last
    cut = {f.name: getattr(rec, f.name)[:k] for f in dataclasses.fields(rec)
           if isinstance(getattr(rec, f.name), np.ndarray) and getattr(rec, f.name).shape[:1] == (rec.n_samples,)}
    return dataclasses.replace(rec, **cut)


def window_start(pb: ShootingProblem, solver: GaussNewton, excitation, rest,
                 ) -> tuple[tuple[np.ndarray, np.ndarray, np.ndarray, Evaluation] | None, int]:
    """The start of ``pb``'s fit from its record's first :data:`WINDOW` seconds: the whole fit there (``solver``,
    stages 1-3; ``excitation`` the lines, Hz, or None, the torque noise the whole record's), then (nodes, offs,
    glob) of ``pb`` from the window's parameters: the model's response under them from the rest ``rest(pb)``
    (rad; ``rest`` a function of the problem) on the encoder, joined (:meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.join_nodes`; the module
    docstring). Returns (that start and the
    :class:`~alpes_dyn.estimation.identification.shooting.Evaluation` there with its Jacobians, or None where the record is not longer than :data:`LONG_RECORD` or the
    window's fit did not converge within :data:`~alpes_dyn.estimation.identification.gauss_newton.BASIN_LIMIT`; the window's
    iterations). A record of several runs longer than :data:`RUNS_START`: :func:`runs_start` first, the window
    where it gives no start.

    Parameters
    ----------
    pb : ShootingProblem
        The fit's problem (:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`).
    solver : GaussNewton
        The fit's solver (:class:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton`).
    excitation : Sequence[float] or None
        The excitation's lines, Hz, or None (the torque as recorded).
    rest : Callable[[ShootingProblem], numpy.ndarray]
        The rest q (n,), rad, a problem's model response starts from.

    Returns
    -------
    tuple
        (the start (nodes, offs, glob, evaluation) or None, the iterations spent).
    """
    its = 0
    if pb.rec.n_runs > 1 and pb.rec.duration > RUNS_START:
        start, its = runs_start(pb, solver, excitation, rest)
        if start is not None:
            return start, its
    if pb.rec.duration <= LONG_RECORD:
        return None, its
    q0 = rest(pb)
    sub = window(pb.rec, WINDOW)
    pw = ShootingProblem(pb.model, sub, pb.sens, pb.L, torque_model(sub, excitation, pb.torque.noise),
                         pb.camera_noise, dict(zip(pb.sens.names, pb.theta0)), dense=pb.dense,
                         structured=pb.structured, drift=pb.drift)
    out = solver.solve(pw, lambda: pw.initial_nodes(q0), np.zeros((pw.n_int, pw.no)), np.zeros(pw.ng))
    if not out.converged or pw.encoder_rms(out.at.r) > BASIN_LIMIT:
        return None, its + out.iterations
    return start_from(pb, solver, pw.values(out.glob), q0), its + out.iterations


def start_from(pb: ShootingProblem, solver: GaussNewton, theta: np.ndarray, q0: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, Evaluation]:
    """(nodes, offs, glob) of ``pb`` from the parameters ``theta`` (p,) of another fit (a window of its record, an
    earlier run): the model's response under them from the rest ``q0`` (rad) on the encoder, joined
    (:meth:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton.join_nodes`), else stage 1's nodes and
    the homotopy's last phase (the module docstring), and the
    :class:`~alpes_dyn.estimation.identification.shooting.Evaluation` there with its Jacobians.

    Parameters
    ----------
    pb : ShootingProblem
        The fit's problem (:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`).
    solver : GaussNewton
        The fit's solver (:class:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton`).
    theta : numpy.ndarray, shape (p,)
        The parameters of another fit, in the fit's units.
    q0 : numpy.ndarray, shape (n,)
        The rest the model's response starts from, rad.

    Returns
    -------
    tuple[numpy.ndarray, numpy.ndarray, numpy.ndarray, Evaluation]
        nodes (S, nx), offs (S, no), glob (ng,) and the evaluation there.
    """
    rho = (theta - pb.theta0) / pb.scale  # the additive parameters' (encoder offsets, tilt angles)
    mult = ~pb.additive
    rho[mult] = np.log(theta[mult] / pb.theta0[mult])
    glob = np.concatenate([rho, np.zeros(pb.ng - pb.p)])  # the line corrections and any drift from 0
    offs = np.zeros((pb.n_int, pb.no))
    if not pb.no:  # the model's response joined (without per-interval torque corrections, which the join leaves)
        nodes = solver.join_nodes(pb, pb.initial_nodes(q0, theta), offs, glob)
        c_scale = np.maximum(np.abs(nodes).max(axis=0), 1e-3)
        if float(np.max(np.abs(pb.evaluate(nodes, offs, glob, jac=False).c) / c_scale, initial=0.0)) <= JOIN_LIMIT:
            return nodes, offs, glob, pb.evaluate(nodes, offs, glob)
    # stage 1's nodes and the homotopy's last phase, as before the join
    nodes = solver.fit_nodes(pb, pb.initial_nodes(q0, theta), offs, glob, sweeps=4)
    return solver.homotopy(pb, nodes, offs, glob, freeze=False, first=SOFT_PHASES - 1)


def runs_start(pb: ShootingProblem, solver: GaussNewton, excitation, rest) -> tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, None] | None, int]:
    """The start of ``pb``'s fit where its record holds several runs: each run fitted alone (``solver``: the first
    as a record of its own, stages 1-3 from its window where it is longer than :data:`LONG_RECORD`; each next one
    from the runs before's mean parameters, :func:`start_from`, stage 3, stages 1-3 only where that fails; ``excitation`` the lines, Hz, or None;
    ``rest(problem)`` the rest its model's response starts from, rad), then (nodes, offs, glob) of ``pb``: every
    run's own fitted nodes, one after the other, and the runs' parameters averaged (log-mean of the multiplicative
    ones, mean of the additive ones), the lines' corrections and any drift from 0, and None for its evaluation
    (stage 3 from there is not held to a window start's
    :data:`~alpes_dyn.estimation.identification.gauss_newton.WINDOW_ITERATIONS`). Returns (that start, or None
    where ``pb`` has one run or a run's fit did not converge within
    :data:`~alpes_dyn.estimation.identification.gauss_newton.BASIN_LIMIT`; the iterations of the runs' fits).

    Parameters
    ----------
    pb : ShootingProblem
        The fit's problem (:class:`~alpes_dyn.estimation.identification.shooting.ShootingProblem`).
    solver : GaussNewton
        The fit's solver (:class:`~alpes_dyn.estimation.identification.gauss_newton.GaussNewton`).
    excitation : Sequence[float] or None
        The excitation's lines, Hz, or None (the torque as recorded).
    rest : Callable[[ShootingProblem], numpy.ndarray]
        The rest q (n,), rad, a problem's model response starts from.

    Returns
    -------
    tuple
        (the start (nodes, offs, glob, None) or None, the iterations of the runs' fits).
    """
    runs = split(pb.rec)
    if len(runs) < 2:
        return None, 0
    nodes, rhos, its = [], [], 0
    for r in runs:  # (a loop over the few runs: each a whole fit)
        pr = ShootingProblem(pb.model, r, pb.sens, pb.L, torque_model(r, excitation, pb.torque.noise),
                             pb.camera_noise, dict(zip(pb.sens.names, pb.theta0)), dense=pb.dense,
                             structured=pb.structured, drift=pb.drift)
        q0 = rest(pr)  # (the window start's own rest is the same: rest(pr))
        if rhos:  # from the runs before: their parameters, this run's own response under them
            start, it_w = start_from(pr, solver, pr.values(np.concatenate([np.mean(rhos, axis=0),
                                                                            np.zeros(pr.ng - pr.p)])), q0), 0
        else:  # the first run as a record of its own (from its window where it is long)
            start, it_w = window_start(pr, solver, excitation, rest)
        out = solver.solve(pr, lambda: pr.initial_nodes(q0), np.zeros((pr.n_int, pr.no)), np.zeros(pr.ng),
                           warm=None if start is None else start[:3], warm_at=[] if start is None else [start[3]])
        its += it_w + out.iterations
        start = None
        if not out.converged or pr.encoder_rms(out.at.r) > BASIN_LIMIT:
            return None, its
        nodes.append(out.nodes)
        rhos.append(out.glob[:pb.p])  # the same parametrisation as pb's (the same theta_0 and scale)
        out = pr = None
    if sum(len(x) for x in nodes) != pb.n_int:  # (runs start on nodes: runs.aligned; never seen otherwise)
        return None, its
    glob = np.concatenate([np.mean(rhos, axis=0), np.zeros(pb.ng - pb.p)])
    return (np.concatenate(nodes), np.zeros((pb.n_int, pb.no)), glob, None), its


MMAP_THRESHOLD = 2**20
"""Bytes: from a record longer than :data:`~alpes_dyn.estimation.identification.long_record.LONG_RECORD`, glibc's
allocator maps every block this large or larger on its own (``mallopt(M_MMAP_THRESHOLD)``) and gives it back to
the system when it is freed. By default the threshold follows the largest block freed, up to 32 MiB, so a long
fit's 8-30 MB arrays (a chunk's sensitivities, the states, the KKT system's blocks) came from the heap and stayed
resident once freed (``benchmarks/fit_scaling.py``'s peak memory, ``benchmarks/results/fit_scaling.json``)."""


def _map_large_blocks() -> None:
    """:data:`MMAP_THRESHOLD` set in glibc's allocator (process-wide; elsewhere nothing)."""
    import ctypes
    import ctypes.util

    try:
        ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallopt(-3, MMAP_THRESHOLD)  # M_MMAP_THRESHOLD
    except (OSError, AttributeError):  # not glibc
        pass
