"""One loop for every scenario: blocks with named signals, composed, stepped at the sample rate.

In the style of python-control's ``nlsys`` / ``interconnect`` / ``input_output_response``: a scenario is a list
of :class:`Block` objects -- a plant, its sensors, observers, controllers, sources of known signals -- each reading
and writing *named signals*; :func:`run_loop` connects them by name, steps them at the sample period ``dt`` and
logs every signal (:class:`LoopLog`). The plants and sensors are in :mod:`alpes_dyn.simulation.plants` and
:mod:`alpes_dyn.simulation.sensors`, the observer and the recording played back in
:mod:`alpes_dyn.estimation.observers.blocks`, the force controllers in :mod:`alpes_dyn.control.blocks`.

Time. Samples k = 0 .. N-1 (and k = N with ``final=True``) at t_k = k dt; periods k = 0 .. N-1 are [t_k, t_k+1).
A signal is either

* a *sample* signal, the value at t_k, written by a block's :meth:`Block.output` (a sensor's reading, an
  estimate, a command), or
* a *period* signal, the value over [t_k, t_k+1), written by a block's :meth:`Block.update` once the period is
  over (the torque a motor applied over it, its current sensor's reading).

Each sample k the loop (1) calls every block's ``output(k, inputs)`` in an order where a sample signal is written
before it is read (a block's ``inputs``: direct feedthrough; a cycle of them is an algebraic loop and an error),
then, unless k = N, (2) every block's ``update(k, inputs)`` (its ``update_inputs``: sample signals at t_k, period
signals of period k, written earlier in the same pass). A period signal read by ``output`` is the previous
period's (the producer's ``initial`` value at k = 0); a sample signal from t_k-1 is read through a
:class:`Delay`. Blocks are started (:meth:`Block.start`: a sensor draws its noise there) in the order given, so that
the random draws of a composition come in the order of its list.

Open loops (no signal path from a block back to itself) whose blocks all have :meth:`Block.response` -- a block's
signals over the whole record at once -- are evaluated block by block over the record (``mode="auto"``, the
default, or ``"batch"``): a simulator's whole trajectory in one integrator call, an observer's whole record in one
compiled loop. ``mode="step"`` steps them sample by sample instead (the same numbers, up to the last bits of
CasADi's map against its single calls: tested).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from ..errors import InputError

__all__ = ["Block", "Source", "Function", "Delay", "LoopLog", "run_loop", "MODES"]

MODES: tuple[str, ...] = ("auto", "step", "batch")
"""The ways :func:`run_loop` evaluates a composition (see the module docstring)."""


class Block:
    """A discrete-time block at the loop's sample rate (see the module docstring for the timing).

    Class or instance attributes, tuples of signal names:

    * ``inputs``: read by :meth:`output` (sample signals at t_k; period signals of the previous period);
    * ``update_inputs``: read by :meth:`update` (sample signals at t_k; period signals of period k);
    * ``outputs``: the sample signals :meth:`output` returns; ``period_outputs``: those :meth:`update` returns;
    * ``initial``: {period signal: value} read at k = 0, before the first period (default 0.0).

    ``output`` may advance the block's own state (it is called once per sample, in the loop's order).
    ``has_response``: the block implements :meth:`response` (its signals over the whole record at once).
    """

    name: str = "block"
    inputs: tuple[str, ...] = ()
    update_inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    period_outputs: tuple[str, ...] = ()
    initial: Mapping[str, Any] = MappingProxyType({})

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        """Before the run.

        Parameters
        ----------
        n_periods : int
            N periods.
        dt : float
            Of ``dt`` s.
        final : bool
            The outputs at t_N are evaluated too.
        """

    def output(self, k: int, u: Mapping[str, Any]) -> dict[str, Any]:
        """The sample signals at t_k from the inputs: ``u[name]`` for each name of ``inputs`` (``u`` is a read-only
        mapping of the loop's current values; read the declared inputs only).

        Parameters
        ----------
        k : int
            The sample.
        u : mapping
            The inputs by name.

        Returns
        -------
        dict
            The outputs by name.
        """
        return {}

    def update(self, k: int, u: Mapping[str, Any]) -> dict[str, Any] | None:
        """Advance over [t_k, t_k+1) with ``u[name]`` for each name of ``update_inputs``.

        Parameters
        ----------
        k : int
            The period.
        u : mapping
            The inputs by name.

        Returns
        -------
        dict or None
            The period signals of that period (or None).
        """
        return None

    has_response = False  # True where response() is implemented

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The whole record at once: ``u`` maps every signal the block reads to its array (sample signals one
        row per sample, period signals one row per period).

        Parameters
        ----------
        u : dict
            The signals' arrays by name.

        Returns
        -------
        dict
            The arrays of its outputs.
        """
        raise NotImplementedError


def _names(x: Any, what: str) -> tuple[str, ...]:
    names = (x,) if isinstance(x, str) else tuple(x)
    for s in names:
        if not isinstance(s, str) or not s:
            raise InputError(f"{what}: expected signal names (non-empty strings), got {s!r}")
    return names


class Source(Block):
    """Known signals from arrays: ``signals`` maps a name to an array with one row per sample (a sample signal;
    the row of t_k at sample k) -- a reference, a torque profile. ``period=True``: one row per period, written by
    :meth:`update` (a period signal).

    Parameters
    ----------
    name : str, optional
        The block's name (default ``"source"``).
    period : bool, optional
        One row per period, written by :meth:`update` (default False: one row per sample).
    **signals
        Name -> array, one row per sample (or per period), any units.

    Raises
    ------
    InputError
        No signal, or a name that is not a non-empty string.
    """

    has_response = True

    def __init__(self, name: str = "source", period: bool = False, **signals: Any) -> None:
        if not signals:
            raise InputError("Source: expected at least one signal (name=array)")
        self.name = name
        self.signals = {k: np.asarray(v) for k, v in signals.items()}
        self.period = bool(period)
        names = _names(tuple(signals), "Source")
        self.outputs, self.period_outputs = ((), names) if period else (names, ())

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        need = n_periods if self.period else n_periods + int(final)
        for k, v in self.signals.items():
            if v.ndim < 1 or v.shape[0] < need:
                raise InputError(f"{k}: expected at least {need} rows (one per {'period' if self.period else 'sample'}),"
                                 f" got shape {v.shape}")
        self._need = need

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        return {} if self.period else {s: v[k] for s, v in self.signals.items()}

    def update(self, k: int, u: dict[str, Any]) -> dict[str, Any] | None:
        return {s: v[k] for s, v in self.signals.items()} if self.period else None

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        return {s: v[: self._need] for s, v in self.signals.items()}


class Function(Block):
    """A static block (no state): ``outputs = fn(**inputs)`` at every sample, e.g. a known-input vector assembled
    from a torque reading and a force. ``fn`` returns one value or a tuple (one per output). ``vectorized``: ``fn``
    also takes the whole record (arrays, one row per sample) and the block has :meth:`response`.

    Parameters
    ----------
    fn : callable
        ``fn(**inputs)`` -> one value or a tuple, one per output.
    inputs : sequence of str
        The signals read, passed to ``fn`` by name.
    outputs : sequence of str or str
        The signals written.
    name : str, optional
        The block's name (default ``"function"``).
    vectorized : bool, optional
        ``fn`` also takes the whole record (default False).

    Raises
    ------
    InputError
        ``fn`` not callable, or a signal name that is not a non-empty string.
    """

    def __init__(self, fn: Callable[..., Any], inputs: Sequence[str], outputs: Sequence[str] | str, *,
                 name: str = "function", vectorized: bool = False) -> None:
        if not callable(fn):
            raise InputError(f"fn: expected a callable, got {type(fn).__name__}")
        self.fn, self.name = fn, name
        self.inputs = _names(inputs, "inputs")
        self.outputs = _names(outputs, "outputs")
        self.has_response = bool(vectorized)

    def output(self, k: int, u: Mapping[str, Any]) -> dict[str, Any]:
        out = self.fn(**{s: u[s] for s in self.inputs})
        return {self.outputs[0]: out} if len(self.outputs) == 1 else dict(zip(self.outputs, out))

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        return self.output(-1, u)


class Delay(Block):
    """A unit delay: ``output`` at t_k is ``signal`` at t_k-1 (``initial`` at t_0).

    Parameters
    ----------
    signal : str
        The period signal read at each update.
    output : str
        The sample signal written.
    initial : object, optional
        The output at t_0 (default 0.0).
    name : str, optional
        The block's name (default ``"delay"``).
    """

    def __init__(self, signal: str, output: str, initial: Any = 0.0, name: str = "delay") -> None:
        self.name = name
        self.update_inputs = _names(signal, "signal")
        self.outputs = _names(output, "output")
        self._x0 = initial

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self._x = self._x0

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        return {self.outputs[0]: self._x}

    def update(self, k: int, u: dict[str, Any]) -> None:
        self._x = u[self.update_inputs[0]]


@dataclass
class LoopLog:
    """Every named signal of a run.

    Attributes
    ----------
    t: (S,) sample times, s (S = N, or N + 1 with ``final``). signals: name -> array, one row per sample
    (sample signals, (S, ...)) or per period (period signals, (N, ...)). period: the names of the period signals.
    mode: ``"step"`` or ``"batch"``. wall_s: wall time of the run (the blocks' start excluded), s.
    """

    t: np.ndarray
    signals: dict[str, np.ndarray]
    period: frozenset[str] = field(default_factory=frozenset)
    mode: str = "step"
    wall_s: float = 0.0

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError:
            raise InputError(f"signal: no signal {name!r} in the log (signals: {', '.join(self.signals)})") from None


def _producers(blocks: Sequence[Block]) -> tuple[dict[str, int], dict[str, int]]:
    """signal -> index of the block writing it, for the sample and the period signals (one writer each)."""
    sample: dict[str, int] = {}
    period: dict[str, int] = {}
    for i, b in enumerate(blocks):
        if not isinstance(b, Block):
            raise InputError(f"blocks: expected Block objects, got {type(b).__name__} at position {i}")
        for s in (*b.outputs, *b.period_outputs):
            if s in sample or s in period:
                j = sample.get(s, period.get(s))
                raise InputError(f"signal {s!r}: written by two blocks ({blocks[j].name!r} and {b.name!r})")
            (sample if s in b.outputs else period)[s] = i
    for b in blocks:
        for s in (*b.inputs, *b.update_inputs):
            if s not in sample and s not in period:
                raise InputError(f"signal {s!r}: read by block {b.name!r} but written by no block")
    return sample, period


def _order(n: int, edges: dict[int, set[int]], what: str, blocks: Sequence[Block]) -> list[int]:
    """A topological order of blocks 0..n-1 (``edges[i]``: the blocks that must come before i), stable in the
    list's order; a cycle is an algebraic loop (:class:`~alpes_dyn.InputError` naming its blocks). Depth-first:
    a chain of more blocks than Python's recursion limit (1000) is refused by Python."""
    order: list[int] = []
    state = [0] * n

    def visit(i: int, path: list[int]) -> None:
        if state[i] == 2:
            return
        if state[i] == 1:
            names = " -> ".join(blocks[j].name for j in path[path.index(i):] + [i])
            raise InputError(f"blocks: algebraic loop through the {what} ({names}); put a Delay in it")
        state[i] = 1
        for j in sorted(edges.get(i, ())):
            visit(j, path + [i])
        state[i] = 2
        order.append(i)

    for i in range(n):
        visit(i, [])
    return order


def _has_cycle(n: int, edges: dict[int, set[int]], blocks: Sequence[Block]) -> bool:
    """Whether the signal graph has a cycle (a feedback loop: the runner then steps the blocks)."""
    try:
        _order(n, edges, "signals", blocks)
    except InputError:
        return True
    return False


def run_loop(blocks: Sequence[Block], n_periods: int, dt: float, *, final: bool = False,
             mode: str = "auto") -> LoopLog:
    """Run a composition of blocks over ``n_periods`` periods of ``dt`` s and log every named signal.

    Parameters
    ----------
    blocks : sequence of Block
        The :class:`Block` objects, connected by their signal names (each signal written by one block); started
        in this order.
    n_periods : int
        N >= 1.
    dt : float
        The sample period, s.
    final : bool, optional
        Evaluate the outputs at t_N too (sample signals then have N + 1 rows; default False).
    mode : str, optional
        ``"auto"`` (default; batch for an open loop of blocks that all have :meth:`Block.response`, else step),
        ``"step"`` or ``"batch"`` (:data:`MODES`).

    Returns
    -------
    LoopLog
        Every named signal of the run.

    Raises
    ------
    InputError
        A signal read but not written or written twice, an algebraic loop (a cycle of direct feedthroughs: put a
        :class:`Delay` in it), ``batch`` on a closed loop, a block writing a signal at some samples only; and what
        the blocks raise (a source too short, an observer diverging...).
    """
    if mode not in MODES:
        raise InputError(f"mode: expected one of {', '.join(MODES)}, got {mode!r}")
    if isinstance(n_periods, bool) or not isinstance(n_periods, (int, np.integer)) or n_periods < 1:
        raise InputError(f"n_periods: expected an integer >= 1, got {n_periods!r}")
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating)) or not (np.isfinite(dt) and dt > 0):
        raise InputError(f"dt: expected a positive number of seconds, got {dt!r}")
    blocks = list(blocks)
    sample, period = _producers(blocks)
    nb = len(blocks)
    feed = {i: {sample[s] for s in b.inputs if s in sample} for i, b in enumerate(blocks)}
    upd = {i: {period[s] for s in b.update_inputs if s in period} for i, b in enumerate(blocks)}
    out_order = _order(nb, feed, "outputs", blocks)
    upd_order = _order(nb, upd, "updates", blocks)
    flow = {i: {sample.get(s, period.get(s)) for s in (*b.inputs, *b.update_inputs)} for i, b in enumerate(blocks)}
    open_loop = not _has_cycle(nb, flow, blocks)
    batch = all(b.has_response for b in blocks) and open_loop
    if mode == "batch" and not batch:
        raise InputError("mode: 'batch' needs an open loop of blocks that all have response(); use 'step'")
    use_batch = batch and mode != "step"
    N = int(n_periods)
    for b in blocks:
        b.start(N, float(dt), bool(final))
    S = N + 1 if final else N
    t = dt * np.arange(S)
    t0 = time.perf_counter()
    if use_batch:
        signals = _run_batch(blocks, _order(nb, flow, "signals", blocks))
    else:
        signals = _run_step(blocks, out_order, upd_order, N, final, set(period))
    return LoopLog(t=t, signals=signals, period=frozenset(period), mode="batch" if use_batch else "step",
                   wall_s=time.perf_counter() - t0)


def _run_batch(blocks: Sequence[Block], order: list[int]) -> dict[str, np.ndarray]:
    signals: dict[str, np.ndarray] = {}
    for i in order:
        b = blocks[i]
        out = b.response({s: signals[s] for s in dict.fromkeys((*b.inputs, *b.update_inputs))})
        signals.update({s: np.asarray(out[s]) for s in (*b.outputs, *b.period_outputs)})
    return signals


def _updates(b: Block) -> bool:
    """Whether the block takes part in the update pass: it reads or writes there, or has an update of its own."""
    return bool(b.update_inputs or b.period_outputs) or "update" in vars(b) or type(b).update is not Block.update


def _run_step(blocks: Sequence[Block], out_order: list[int], upd_order: list[int], N: int, final: bool,
              period: set[str]) -> dict[str, np.ndarray]:
    """The sample-by-sample loop: outputs in ``out_order``, updates in ``upd_order``; every value logged (a numpy
    array copied: a block may reuse its buffers), the logs stacked at the end."""
    now: dict[str, Any] = {}
    for b in blocks:
        for s in b.period_outputs:
            now[s] = b.initial.get(s, 0.0)
    lists: dict[str, list[Any]] = {s: [] for b in blocks for s in (*b.outputs, *b.period_outputs)}
    S = N + 1 if final else N
    ndarray = np.ndarray
    outs = [(blocks[i].output, blocks[i].outputs) for i in out_order if blocks[i].outputs]
    upds = [(blocks[i].update, blocks[i].period_outputs) for i in upd_order if _updates(blocks[i])]
    view = MappingProxyType(now)  # every block reads the current values through one read-only view
    logs = [(call, [(s, lists[s].append) for s in names]) for call, names in outs]
    ulogs = [(call, [(s, lists[s].append) for s in names]) for call, names in upds]

    def run(stage: list, k: int) -> None:
        for call, appends in stage:
            values = call(k, view)
            if values:
                now.update(values)
                for s, append in appends:
                    try:
                        v = values[s]
                    except KeyError:
                        raise InputError(f"signal {s!r}: not written by its block at step {k} (a block writes all its "
                                         f"signals every time)") from None
                    append(v.copy() if type(v) is ndarray else v)

    for k in range(N):
        run(logs, k)
        run(ulogs, k)
    if final:
        run(logs, N)
    log: dict[str, np.ndarray] = {}
    for s, values in lists.items():
        rows = N if s in period else S
        if len(values) != rows:
            raise InputError(f"signal {s!r}: written {len(values)} times in {rows} "
                             f"{'periods' if s in period else 'samples'} (a block must write its signals every time)")
        a = np.array(values)
        log[s] = a.astype(np.float64) if a.dtype.kind in "iub" else a
    return log
