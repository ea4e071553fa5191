"""A long record simulated at its sample rate: compiled RK4 sub-steps, the states kept at the samples only.

:func:`~alpes_dyn.simulation.integrate.simulate` builds one CasADi ``mapaccum`` over every RK4 step of the run,
evaluates it in CasADi's virtual machine and returns the states and outputs of every sub-step: on a 600 s record at
1 kHz with 4 sub-steps, 2.4 million states of the finger (and a ``mapaccum`` whose construction alone grows with
the run), so that the identification experiment of a ten-minute record cost minutes and gigabytes per chain
(issue 39). :func:`sampled_rk4` runs the same RK4 step -- the model's numbers lifted into an input
(:func:`~alpes_dyn.symbolic.lifted.lift_constants`) and the step length too, so that one compiled library serves
every finger of that structure and every sub-step count -- in compiled C (:class:`~alpes_dyn.simulation.codegen.
CompiledStepLoop`, cached on disk: built once, in well under a second for a finger), a chunk of samples at a time,
keeping the states at the samples: time linear in the record, memory of the record's samples plus one chunk.

The same operations in the same order as :func:`simulate`'s ``"rk4"`` (a lifted constant is the same double as
the literal; the step's ``dt / 6`` computed from the same double): the states are :func:`simulate`'s to the bit
(tested). Without a C compiler, the lifted step runs in CasADi's virtual machine, chunk by chunk.
"""

from __future__ import annotations

import threading
from typing import Any

import casadi as cs
import numpy as np

from ..errors import InputError
from ..model.robot import Model
from ..symbolic.lifted import lift_constants
from .buildcache import CompilerError, expression_key
from .codegen import CasadiStepLoop, CompiledStepLoop
from .integrate import _check_dt, _rhs_function, as_statespace, rk4_expression

__all__ = ["CHUNK_STEPS", "sampled_rk4"]

CHUNK_STEPS = 1 << 16
"""RK4 sub-steps per chunk of :func:`sampled_rk4` (the sub-step states of one chunk are held at once: 3 MB for a
finger's six states)."""


def _lifted_step(ss: Any) -> tuple[cs.Function, np.ndarray]:
    """(step (x, w, [p; h]) -> x_next, p's values): one RK4 step of length h of the state space ``ss`` with its
    numbers lifted into p; cached on the state space."""
    cache = ss.__dict__
    if "_lifted_rk4" not in cache:
        f, values = lift_constants(_rhs_function(ss), "f_lifted")
        x = cs.SX.sym("x", ss.n_states)
        w = cs.SX.sym("w", f.size1_in(1))
        p = cs.SX.sym("p", values.size)
        h = cs.SX.sym("h")
        # the common subexpressions merged once in the right-hand side (as the observers do: a cse of the whole
        # step costs more for the same instructions); lifted first, since cse would merge equal values
        fc = cs.Function("f_cse", [x, w, p], [cs.cse(f(x, w, p))])
        step = cs.Function("rk4_lifted", [x, w, cs.vertcat(p, h)], [rk4_expression(lambda a, b: fc(a, b, p), x, w, h)])
        cache["_lifted_rk4"] = (step, values)
    return cache["_lifted_rk4"]


_LOOPS = threading.local()
"""This thread's compiled loops by the hash of their step's serialised expression (``loops``): an experiment
simulates many models of one structure (its gravity per orientation, its amplitudes trimmed run by run), each a new
state space whose lifted step is the same expression; its C is generated and loaded once, its p set per run."""


def _loop(ss: Any, step: cs.Function, parameters: np.ndarray, compiled: bool) -> CompiledStepLoop | CasadiStepLoop:
    """The loop of ``step`` with ``parameters``: compiled (one per step expression in this thread, :data:`_LOOPS`), or
    on CasADi's virtual machine where ``compiled`` is False or no C compiler can build it (both with
    :meth:`CompiledStepLoop.run`'s interface)."""
    if compiled:
        loops = _LOOPS.__dict__.setdefault("loops", {})
        key = expression_key(step)
        loop = loops.get(key)
        if loop is not None:
            np.copyto(loop.parameters, parameters)  # in place: the buffer the compiled loop reads
            return loop
        try:
            loop = loops[key] = CompiledStepLoop(step, f"sampled_{ss.model.name}", threads=1, vectorize=False,
                                                 parameters=parameters)
            return loop
        except CompilerError:
            pass
    x, w = cs.SX.sym("x", step.size1_in(0)), cs.SX.sym("w", step.size1_in(1))
    return CasadiStepLoop(cs.Function("rk4_fixed", [x, w], [step(x, w, parameters)]), threads=1)


def sampled_rk4(model: Model, x0: np.ndarray, u: np.ndarray, dt: float, substeps: int, input: str = "motor",
                compiled: bool = True) -> np.ndarray:
    """States (N+1, 2n), rad and rad/s, at the samples of a record: from ``x0`` (2n,), ``substeps`` RK4 steps of
    ``dt / substeps`` per sample period ``dt`` (s), the input ``u`` (N, m) (motor torques, N m, with ``input``
    ``"motor"``; joint torques with ``"joint"``) held over each period. :func:`~alpes_dyn.simulation.integrate.
    simulate`'s ``"rk4"`` on ``np.repeat(u, substeps, axis=0)`` with step ``dt / substeps``, its states taken every
    ``substeps`` steps, to the bit (module docstring). No joint-range check: the caller checks the samples
    (:func:`~alpes_dyn.model.stops.check_range`).

    Parameters
    ----------
    model : alpes_dyn.Model
        The model.
    x0 : numpy.ndarray, shape (2n,)
        The initial state [q; qd], rad and rad/s.
    u : numpy.ndarray, shape (N, m)
        The inputs, held over each period: motor torques (N m) with ``input="motor"``, joint torques (N m, (N, n))
        with ``"joint"``.
    dt : float
        The sample period, s.
    substeps : int
        RK4 steps per sample period (>= 1).
    input : str, optional
        ``"motor"`` (default) or ``"joint"``.
    compiled : bool, optional
        The generated C (default True); False: CasADi's virtual machine.

    Returns
    -------
    numpy.ndarray, shape (N+1, 2n)
        The states at the samples, rad and rad/s.

    Raises
    ------
    InputError
        States that become non-finite (naming the time), or shapes that do not fit.
    """
    ss = as_statespace(model, input, "encoder" if input == "motor" else "sum")
    dt = _check_dt(dt)
    if isinstance(substeps, bool) or not isinstance(substeps, (int, np.integer)) or substeps < 1:
        raise InputError(f"substeps: expected a positive integer, got {substeps!r:.40}")
    sub = int(substeps)
    u = np.ascontiguousarray(u, dtype=float)
    x0 = np.asarray(x0, dtype=float)
    if u.ndim != 2 or u.shape[1] != ss.n_inputs or u.shape[0] < 1:
        raise InputError(f"u: expected shape (N, {ss.n_inputs}), got {u.shape}")
    if x0.shape != (ss.n_states,):
        raise InputError(f"x0: expected shape ({ss.n_states},), got {x0.shape}")
    step, values = _lifted_step(ss)
    params = np.r_[values, dt / sub]
    loop = _loop(ss, step, params, compiled)
    N = u.shape[0]
    x = np.empty((N + 1, ss.n_states))
    x[0] = x0
    per = max(1, CHUNK_STEPS // sub)  # samples per chunk
    for k0 in range(0, N, per):  # a loop over chunks of samples (the steps themselves in C)
        k1 = min(N, k0 + per)
        X = loop.run(x[k0][None], np.repeat(u[k0:k1], sub, axis=0)[None])[0, sub::sub]
        x[k0 + 1: k1 + 1] = X
        if not np.isfinite(X[-1]).all():
            break
    if not np.isfinite(x).all():
        k = int(np.argmax(~np.isfinite(x).all(axis=1)))
        raise InputError(f"simulation diverged (non-finite state at t = {k * dt:g} s); reduce dt or the inputs")
    return x
