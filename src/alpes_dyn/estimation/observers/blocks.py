"""Estimation blocks of :func:`alpes_dyn.simulation.loop.run_loop`: an observer, and a recording played back.

* :class:`Observer`: a Kalman filter of :mod:`alpes_dyn.estimation.observers.observers` at the sample rate: at t_0 its
  prior (updated with the first measurement, or not), then each sample one predict-update step
  (``filter_step_p``) with the known inputs of the previous period and the measurement at t_k. Its whole-record
  response is the filter's :meth:`~alpes_dyn.estimation.observers.observers.KalmanFilter.run` (one compiled loop).
* :class:`ObserverBank`: observers of the same model advanced together, one compiled call per sample;
* :func:`step_caller` / :func:`batch_step_caller`: the filter step of one filter, or of B filters of the same model
  in one call of compiled C (CasADi's virtual machine without a compiler).
* :class:`RecordingPlayback`: a :class:`~alpes_dyn.estimation.experiments.recording.Recording` as the plant: its encoder
  counts, its motor torques (sample and period signals) and, where recorded, the true joint angles.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

import numpy as np

from ...errors import InputError
from ...model.transmission import torque_before
from ...simulation.loop import Block
from .observers import KalmanFilter
from ..experiments.recording import Recording

__all__ = ["Observer", "ObserverBank", "RecordingPlayback", "step_caller", "batch_step_caller"]


def _compiled_loop(step: Any, label: str, parameters: Any) -> Any:
    """The step's :class:`~alpes_dyn.simulation.codegen.CompiledStepLoop` (built, or loaded from the cache), or None
    without a C compiler."""
    from ...simulation.integrate import CompiledStepLoop, CompilerError

    try:
        return CompiledStepLoop(step, label, threads=1, vectorize=False, parameters=parameters)
    except CompilerError:
        return None


def _vm_step(step: Any, parameters: Any) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """(s, wy) -> s_next of the step in CasADi's virtual machine (its model's numbers ``parameters``, if any)."""
    if parameters is None:
        return lambda s, wy: np.asarray(step(s, wy)).reshape(-1)
    from ...simulation.codegen import _step_parameters

    p = _step_parameters(step, parameters)  # checked against the step's input p (InputError naming it)
    return lambda s, wy: np.asarray(step(s, wy, p)).reshape(-1)


def batch_step_caller(step: Any, label: str, compiled: bool,
                      parameters: Any = None) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """S (B, ns), WY (B, nw) -> S_next (B, ns): one filter step of B filters of the same model, in one call
    of compiled C (cached, :class:`~alpes_dyn.simulation.integrate.CompiledStepLoop`) when ``compiled`` and a C
    compiler is there, else CasADi's virtual machine (one call per filter).

    Parameters
    ----------
    step : casadi.Function
        A filter's ``filter_step`` (s, wy) -> s_next, or its ``filter_step_p`` (s, wy, p) -> s_next; s = [z; vec P]
        (ns,), wy = [w; y] (nw,).
    label : str
        The name of the compiled library (its cache key with the step's structure).
    compiled : bool
        Compile the step to C (when a C compiler is there); False: CasADi's virtual machine.
    parameters : numpy.ndarray or None, optional
        The model's numbers p of a ``filter_step_p`` (``filt.model.values``: the compiled library then keyed on
        the model's structure, shared by models of other values); None (default) for a ``filter_step``.

    Returns
    -------
    Callable[[numpy.ndarray, numpy.ndarray], numpy.ndarray]
        S (B, ns), WY (B, nw) -> S_next (B, ns).
    """
    vm = _vm_step(step, parameters)
    loop = _compiled_loop(step, label, parameters) if compiled else None
    if loop is not None:
        run = loop.run

        def call(S: np.ndarray, WY: np.ndarray) -> np.ndarray:
            return run(S, WY[:, None, :])[:, 1]

        return call

    def call_vm(S: np.ndarray, WY: np.ndarray) -> np.ndarray:
        return np.stack([vm(s, wy) for s, wy in zip(S, WY)])

    return call_vm


def step_caller(step: Any, label: str, compiled: bool,
                parameters: Any = None) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """s (ns,), wy (nw,) -> s_next (ns,): one filter step (:func:`batch_step_caller` with B = 1; compiled, one
    call of :meth:`CompiledStepLoop.step <alpes_dyn.simulation.codegen.CompiledStepLoop.step>` on buffers it
    keeps: a control loop's call at each sample).

    Parameters
    ----------
    step : casadi.Function
        A filter's ``filter_step`` (s, wy) -> s_next, or its ``filter_step_p`` (s, wy, p) -> s_next.
    label : str
        The name of the compiled library.
    compiled : bool
        Compile the step to C (when a C compiler is there); False: CasADi's virtual machine.
    parameters : numpy.ndarray or None, optional
        The model's numbers p of a ``filter_step_p``; None (default) for a ``filter_step``.

    Returns
    -------
    Callable[[numpy.ndarray, numpy.ndarray], numpy.ndarray]
        s (ns,), wy (nw,) -> s_next (ns,), with s = [z; vec P].
    """
    vm = _vm_step(step, parameters)
    loop = _compiled_loop(step, label, parameters) if compiled else None
    return loop.step if loop is not None else vm


class Observer(Block):
    """A Kalman filter as a block.

    Parameters
    ----------
    filt : KalmanFilter
        A :class:`~alpes_dyn.estimation.observers.observers.KalmanFilter` (EKF, UKF).
    z0 : array_like, shape (nz,)
        The prior mean.
    P0 : array_like, shape (nz,) or (nz, nz)
        The prior's variances or covariance.
    known : Sequence[str], optional
        The signals whose values, flattened and concatenated, are the known input w (nw,) of the predict over
        [t_k-1, t_k]: period signals (the previous period's: a torque held over it) or sample signals read at t_k
        (default ``("u",)``).
    measurement : str, optional
        The measurement's signal (ny,) at t_k (default ``"y"``).
    estimate : str, optional
        The signal written with the estimate z (nz,) at t_k (default ``"z"``).
    covariance : str or None, optional
        The signal written with the covariance P (nz, nz) at t_k (default ``"P"``; None: not written).
    first_update : bool, optional
        Update the prior with the measurement at t_0 (as :meth:`KalmanFilter.run`; the default); else the
        estimate at t_0 is the prior.
    step : Callable[[numpy.ndarray, numpy.ndarray], numpy.ndarray] or None, optional
        The step s, wy -> s_next (:func:`step_caller`; default None: the filter's ``filter_step_p`` with its
        model's numbers in CasADi's VM, :meth:`~alpes_dyn.estimation.observers.observers.KalmanFilter.run`'s step).
    label : str or None, optional
        The name of its compiled step in an :class:`ObserverBank` (default None: ``<kind>_<model name>``).
    name : str, optional
        The block's name in the loop (default ``"observer"``).

    Raises
    ------
    InputError
        ``filt`` not a KalmanFilter, or ``z0`` / ``P0`` of the wrong shape.
    """

    def __init__(self, filt: KalmanFilter, z0: Any, P0: Any, *, known: Sequence[str] = ("u",),
                 measurement: str = "y", estimate: str = "z", covariance: str | None = "P",
                 first_update: bool = True, step: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None,
                 label: str | None = None, name: str = "observer") -> None:
        if not isinstance(filt, KalmanFilter):
            raise InputError(f"filt: expected a KalmanFilter of alpes_dyn.estimation.observers.observers, got {type(filt).__name__}")
        self.filt, self.name = filt, name
        self.z0, self.P0 = filt._z(z0, "z0"), filt._P(P0, "P0")
        self.known = tuple(known)
        self.measurement, self.estimate, self.covariance = measurement, estimate, covariance
        self.first_update = bool(first_update)
        self._step = step
        self.label = label or f"{filt.kind}_{filt.model.system.model.name}"
        self.inputs = (*self.known, measurement)
        self.outputs = (estimate,) if covariance is None else (estimate, covariance)
        self.has_response = self.first_update and step is None

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        self.n_periods, self._slots = n_periods, None
        if self._step is None:
            fs, p = self.filt.filter_step_p, self.filt.model.values
            self._call = lambda s, wy: np.asarray(fs(s, wy, p)).reshape(-1)
        else:
            self._call = self._step

    def _out(self) -> dict[str, Any]:
        nz = self.filt.nz
        out: dict[str, Any] = {self.estimate: self._s[:nz]}
        if self.covariance is not None:
            out[self.covariance] = self._s[nz:].reshape(nz, nz, order="F")
        return out

    def first(self, u: dict[str, Any]) -> np.ndarray:
        """The state s = [z; vec P] at t_0: the prior, updated with the first measurement or not.

        Parameters
        ----------
        u : dict[str, Any]
            The input signals at t_0 by name (the measurement's read).

        Returns
        -------
        numpy.ndarray, shape (nz + nz * nz,)
            s = [z; vec P] (P flattened column-major).
        """
        z, P = self.z0, self.P0
        if self.first_update:
            z, P = self.filt._update(z, P, np.ravel(u[self.measurement]))
        self._s = np.concatenate([np.array(z).reshape(-1), np.array(P).reshape(-1, order="F")])
        return self._s

    def wy(self, u: dict[str, Any]) -> np.ndarray:
        """[w; y] (nw + ny,) from the input signals (a buffer reused at each sample).

        Parameters
        ----------
        u : dict[str, Any]
            The input signals at t_k by name: the ``known`` ones and the measurement.

        Returns
        -------
        numpy.ndarray, shape (nw + ny,)
            The known input w and the measurement y, concatenated.
        """
        if self._slots is None:  # where each signal goes
            sizes = np.cumsum([0] + [np.size(u[s]) for s in self.inputs])
            self._slots = [(s, slice(int(a), int(b))) for s, a, b in zip(self.inputs, sizes[:-1], sizes[1:])]
            self._wy = np.empty(int(sizes[-1]))
        wy = self._wy
        for s, sl in self._slots:
            wy[sl] = u[s]
        return wy

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        if k == 0:
            self.first(u)
        else:
            self._s = self._call(self._s, self.wy(u))
        return self._out()

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The filter's :meth:`~alpes_dyn.estimation.observers.observers.KalmanFilter.run` on the record.

        Parameters
        ----------
        u : dict[str, numpy.ndarray]
            The whole record of the input signals by name, each (N + 1, ...) or (N, ...) (period signals).

        Returns
        -------
        dict[str, numpy.ndarray]
            The estimates z (N + 1, nz) and, where written, the covariances P (N + 1, nz, nz) by signal name.
        """
        N = self.n_periods
        W = np.hstack([np.asarray(u[s], dtype=float).reshape(np.shape(u[s])[0], -1)[:N] for s in self.known])
        Y = np.asarray(u[self.measurement], dtype=float)
        est = self.filt.run(self.z0, self.P0, W, Y.reshape(Y.shape[0], -1))
        out = {self.estimate: est.z}
        if self.covariance is not None:
            out[self.covariance] = est.P
        return out


class ObserverBank(Block):
    """Several :class:`Observer` blocks as one: those whose filters share a step function and its numbers (the
    same model and noise settings: the hand's four fingers) advance together, in one call of compiled C per sample
    (:func:`batch_step_caller`; ``compiled=False``: CasADi's virtual machine); those of one structure but other
    numbers load the same library. Each observer keeps its own signals.

    Parameters
    ----------
    observers : Sequence[Observer]
        The observers (a non-empty list).
    compiled : bool, optional
        Their steps as compiled C (default True; False: CasADi's virtual machine).
    name : str, optional
        The block's name in the loop (default ``"observers"``).

    Raises
    ------
    InputError
        ``observers`` empty or not all :class:`Observer` blocks.
    """

    def __init__(self, observers: Sequence[Observer], *, compiled: bool = True, name: str = "observers") -> None:
        observers = list(observers)
        if not observers or not all(isinstance(o, Observer) for o in observers):
            raise InputError("observers: expected a non-empty list of Observer blocks")
        self.observers, self.name = observers, name
        groups: dict[str, list[int]] = {}
        self._callers: dict[str, Callable[[np.ndarray, np.ndarray], np.ndarray]] = {}
        for i, o in enumerate(observers):
            key = o.filt.filter_step_p.serialize() + o.filt.model.values.tobytes().hex()
            if key not in self._callers:
                self._callers[key] = batch_step_caller(o.filt.filter_step_p, o.label, compiled, o.filt.model.values)
            groups.setdefault(key, []).append(i)
        self._groups = list(groups.items())
        self.inputs = tuple(dict.fromkeys(s for o in observers for s in o.inputs))
        self.outputs = tuple(s for o in observers for s in o.outputs)

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        for o in self.observers:
            o.start(n_periods, dt, final)

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        obs = self.observers
        if k == 0:
            for o in obs:
                o.first(u)
        else:
            for key, idx in self._groups:
                S = self._callers[key](np.stack([obs[i]._s for i in idx]), np.stack([obs[i].wy(u) for i in idx]))
                for j, i in enumerate(idx):
                    obs[i]._s = S[j]
        out: dict[str, Any] = {}
        for o in obs:
            out.update(o._out())
        return out


class RecordingPlayback(Block):
    """A :class:`~alpes_dyn.estimation.experiments.recording.Recording` as the plant (run the loop with ``final=True``
    over its N = n_samples - 1 periods).

    Writes ``encoder`` (m,) counts and ``torque`` (m,) N m at t_k (sample signals), ``before`` the torque held over
    the period before t_k (the first sample's own at t_0: what the tendons' tension balances at the reading,
    :func:`~alpes_dyn.model.transmission.torque_before`), ``held`` the torque over [t_k, t_k+1) (a period signal:
    what a known input reads), and ``true_q`` (n,) rad where the recording has it.

    Parameters
    ----------
    recording : Recording
        The recording played back.
    encoder : str, optional
        The signal of the encoder counts (m,) at t_k (default ``"counts"``).
    torque : str, optional
        The signal of the motor torques (m,), N m, at t_k (default ``"tau"``).
    held : str, optional
        The period signal of the torque (m,), N m, held over [t_k, t_k+1) (default ``"tau_held"``).
    true_q : str or None, optional
        The signal of the true joint angles (n,), rad, where the recording has them (default ``"true_q"``; None:
        not written).
    before : str or None, optional
        The signal of the torque (m,), N m, held over the period before t_k (default None: not written).
    name : str, optional
        The block's name in the loop (default ``"recording"``).

    Raises
    ------
    InputError
        ``recording`` not a Recording.
    """

    has_response = True

    def __init__(self, recording: Recording, *, encoder: str = "counts", torque: str = "tau",
                 held: str = "tau_held", true_q: str | None = "true_q", before: str | None = None,
                 name: str = "recording") -> None:
        if not isinstance(recording, Recording):
            raise InputError(f"recording: expected a Recording, got {type(recording).__name__}")
        self.rec, self.name = recording, name
        self._sample = {encoder: recording.encoder, torque: recording.torque}
        if before is not None:
            self._sample[before] = torque_before(recording.torque)
        if true_q is not None and recording.true_q is not None:
            self._sample[true_q] = recording.true_q
        self.outputs = tuple(self._sample)
        self.held = held
        self.period_outputs = (held,)

    def start(self, n_periods: int, dt: float, final: bool) -> None:
        rows = self.rec.encoder.shape[0]
        if n_periods + int(final) > rows:
            raise InputError(f"n_periods: the recording has {rows} samples, not {n_periods + int(final)}")
        self._rows = n_periods + int(final)
        self._N = n_periods

    def output(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        return {s: v[k] for s, v in self._sample.items()}

    def update(self, k: int, u: dict[str, Any]) -> dict[str, Any]:
        return {self.held: self.rec.torque[k]}

    def response(self, u: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        out = {s: v[: self._rows] for s, v in self._sample.items()}
        out[self.held] = self.rec.torque[: self._N]
        return out
