"""Sweeps: a function of a seeded draw run over many draws, on Dask (a local cluster by default).

:func:`sweep` runs ``fn(seed, **options)`` for each seed of a range, serially or on Dask workers --
a :class:`distributed.LocalCluster` of ``workers`` processes by default, or the scheduler at
``scheduler`` (``"tcp://host:8786"``) to scale out -- and gathers each draw's dictionary of results
into a :class:`SweepResult` (a table, CSV, JSON), each row with its seed. The models, state spaces,
observers and compiled roll-outs a draw builds travel to the workers by their description
(:mod:`alpes_dyn.rebuild`) and find their generated C in the on-disk cache, so a worker compiles
nothing that the machine has compiled before. The per-draw results do not depend on where the draw
ran: every draw is seeded by its own seed only (tested against the serial loop).

:func:`robustness_draw` is the study of ``alpes-dyn sweep``: a finger drawn within the tolerances,
its identification experiment, the fit, and the EKF on the recording with the nominal and with the
identified file (:mod:`alpes_dyn.estimation.observers.replay`); :func:`robot_robustness_draw` is the same study on any
URDF + spec robot (``alpes-dyn sweep --model ROBOT.urdf --spec FILE.toml``): what its spec holds drawn.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import logging
import math
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..fileio import atomic_path
from ..limits import MAX_SEED

__all__ = ["SweepResult", "sweep", "local_client", "robustness_draw", "robot_robustness_draw", "drawn_spec",
           "ROBOT_DRAWN", "ROBOT_HELD", "STUDIES"]


@dataclass
class SweepResult:
    """Rows of a sweep, one per draw in seed order (each a flat dict with its ``seed``), and how it ran."""

    rows: list[dict[str, Any]]
    seconds: float
    backend: str
    workers: int
    meta: dict[str, Any] = field(default_factory=dict)

    def columns(self) -> list[str]:
        cols: list[str] = []
        for r in self.rows:
            cols += [c for c in r if c not in cols]
        return cols

    def to_dict(self) -> dict[str, Any]:
        """JSON: the rows (non-finite numbers as null, at any depth of a nested value), the backend, workers and
        wall time."""
        return {"rows": [{k: _json_value(v) for k, v in r.items()} for r in self.rows], "seconds": self.seconds,
                "backend": self.backend, "workers": self.workers, **self.meta}

    def to_csv(self, path: str | Path) -> Path:
        """Write the table as CSV (one row per draw), atomically; a non-finite number is an empty cell (as
        :meth:`to_dict` writes it null: never ``nan`` or ``inf`` in a table); a nested value (a dict, or a list of a
        row that is not flat) is its JSON text, which ``json.loads`` reads back (non-finite numbers in it null).

        Parameters
        ----------
        path : str or pathlib.Path
            The CSV file written.

        Returns
        -------
        pathlib.Path
            ``path``.
        """
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=self.columns(), lineterminator="\n")
        w.writeheader()
        w.writerows({k: _csv_cell(v) for k, v in r.items()} for r in self.rows)
        with atomic_path(path, "--output") as tmp:
            tmp.write_text(buf.getvalue(), encoding="utf-8")
        return Path(path)

    def table(self, columns: Sequence[str] | None = None) -> str:
        """A plain-text table of ``columns`` (default: all; an unknown one is refused); a non-finite number is
        shown as ``-``.

        Parameters
        ----------
        columns : sequence of str or None, optional
            The columns shown (default: all).

        Returns
        -------
        str

        Raises
        ------
        InputError
            An unknown column.
        """
        cols = list(columns) if columns is not None else self.columns()
        unknown = [c for c in cols if c not in self.columns()]
        if unknown:
            raise InputError(f"columns: {unknown[0]!r} is not a column (columns: {', '.join(self.columns())})")

        def fmt(v: Any) -> str:
            return "-" if _non_finite(v) else f"{v:.4g}" if isinstance(v, float) else str(v)
        cells = [[fmt(r.get(c, "")) for c in cols] for r in self.rows]
        widths = [max(len(c), *(len(row[i]) for row in cells)) for i, c in enumerate(cols)]
        lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
        lines += ["  ".join(v.rjust(w) for v, w in zip(row, widths)) for row in cells]
        return "\n".join(lines)


def _non_finite(v: Any) -> bool:
    return isinstance(v, float) and not math.isfinite(v)


def _json_value(v: Any) -> Any:
    """``v`` as JSON can hold it: non-finite numbers None, NumPy scalars and arrays plain numbers and lists, at any
    depth of dicts, lists and tuples."""
    if isinstance(v, dict):
        return {str(k): _json_value(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json_value(x) for x in v]
    if isinstance(v, (np.ndarray, np.generic)):
        return _json_value(v.tolist())
    return None if _non_finite(v) else v


def _csv_cell(v: Any) -> Any:
    """A CSV cell: a non-finite number empty, a nested value its JSON text (other tools read it back), else ``v``."""
    if isinstance(v, (dict, list, tuple, np.ndarray)):
        return json.dumps(_json_value(v), allow_nan=False, default=str)
    return "" if _non_finite(v) else v


def _bool_array(v: Any) -> bool:
    try:
        return np.asarray(v).dtype.kind == "b"
    except (ValueError, TypeError):  # ragged: as_float_array names it
        return False


def _flat(seed: int, out: dict[str, Any]) -> dict[str, Any]:
    """A draw's result as one flat row: arrays and lists (of real numbers: anything else is refused naming the
    key) become name_0, name_1, ...; the keys are strings."""
    row: dict[str, Any] = {"seed": seed}
    for k, v in out.items():
        if not isinstance(k, str):
            raise InputError(f"fn: a draw's result has the key {k!r:.40}, expected a string (seed {seed})")
        if isinstance(v, (list, tuple, np.ndarray)) and _bool_array(v):
            row.update({f"{k}_{i}": bool(x) for i, x in enumerate(np.asarray(v).ravel())})  # flags stay flags
        elif isinstance(v, (list, tuple, np.ndarray)):
            for i, x in enumerate(as_float_array(v, f"fn: result {k!r} (seed {seed})", "numbers").ravel()):
                row[f"{k}_{i}"] = float(x)
        elif isinstance(v, (np.floating, np.integer, np.bool_)):
            row[k] = v.item()
        else:
            row[k] = v
    return row


def _draw(fn: Callable[..., dict[str, Any]], seed: int, options: dict[str, Any], flat: bool = True) -> dict[str, Any]:
    out = fn(seed, **options)
    if not isinstance(out, dict):
        raise InputError(f"fn: a draw must return a dict of results, got {type(out).__name__} (seed {seed})")
    return _flat(seed, out) if flat else {"seed": seed, **out}


def _check_options(fn: Callable[..., Any], options: dict[str, Any]) -> None:
    """InputError naming an option that ``fn`` has no keyword argument of (before any draw runs)."""
    import inspect

    try:
        params = inspect.signature(fn).parameters
    except (TypeError, ValueError):  # a builtin or a callable without a readable signature: fn says it
        return
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return
    names = {n for n, p in params.items() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}
    for k in options:
        if k not in names:
            raise InputError(f"options: {getattr(fn, '__name__', 'fn')} takes no argument {k!r} "
                             f"(its arguments: {', '.join(sorted(names)) or 'none'})")


def _check_int(x: Any, name: str, low: int, high: int) -> int:
    if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, np.integer)) or not low <= x <= high:
        raise InputError(f"{name}: expected an integer from {low} to {high}, got {x!r}")
    return int(x)


def local_client(workers: int) -> Any:
    """A ``distributed.Client`` on a new local cluster of ``workers`` processes, one thread each (each process's
    compiled loops then run on one thread: :func:`~alpes_dyn.simulation.codegen._default_threads` reads the
    OMP_NUM_THREADS Dask sets); close it with ``client.close(); client.cluster.close()``.

    On Linux the worker processes are forked from this one (Dask's ``multiprocessing-method: fork``) instead of
    started afresh (``spawn``, Dask's default): they begin with the modules this process has imported (numpy,
    CasADi, Pinocchio, alpes_dyn) instead of importing them again: the cluster starts and closes several times
    faster, and the draws run no slower (the forked workers keep the parent's BLAS threads). A script may then also
    start a sweep without an ``if __name__ == "__main__":`` guard, which spawned workers need. Elsewhere (macOS,
    Windows: fork is unsafe or absent) Dask's default.

    The workers' statistical profiler (``distributed.worker.profile.enabled``, the dashboard's profile) is off: it
    samples the worker thread's stack at a fixed interval, taking the GIL from a draw that calls compiled code in short
    steps, which slows the draws. The sweep's times with this client: ``benchmarks/results/sweep.json``
    (``median_dask_s``, ``median_speedup``). A user who wants it passes a client of their own. The workers get it in
    their whole Dask configuration (the Nanny's ``config``), so a worker the cluster restarts keeps it; a restarted
    worker is spawned, though (Dask reads the start method from the calling process's configuration at each start).

    Parameters
    ----------
    workers : int
        The number of worker processes.

    Returns
    -------
    distributed.Client
    """
    import copy

    import dask
    from distributed import Client, LocalCluster

    method = "fork" if sys.platform.startswith("linux") else dask.config.get("distributed.worker.multiprocessing-method")
    with dask.config.set({"distributed.worker.multiprocessing-method": method,
                          "distributed.worker.profile.enabled": False}):
        config = copy.deepcopy(dask.config.config)  # whole: the worker sets it subtree by subtree
        return Client(LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                                   silence_logs=logging.ERROR, config=config))


def sweep(fn: Callable[..., dict[str, Any]], draws: int | None = None, *, seed: int = 0,
          options: dict[str, Any] | None = None, workers: int | None = None, scheduler: str | None = None,
          client: Any = None, serial: bool = False, seeds: Sequence[int] | None = None,
          flat: bool = True) -> SweepResult:
    """Run ``fn(s, **options)`` for the seeds s = seed .. seed + draws - 1 (or for each of ``seeds``); gather the
    rows in that order.

    Parameters
    ----------
    fn : callable
        A module-level function (it travels to the workers by name) returning a dict of numbers, lists or strings.
    draws : int or None, optional
        The number of draws, 1..100000.
    seed : int, optional
        The first seed, >= 0 (default 0).
    options : dict or None, optional
        Keyword arguments of ``fn`` (not ``seed``), the same for every draw.
    workers : int or None, optional
        Processes of the local Dask cluster (one thread each), 1..256 (default 2).
    scheduler : str or None, optional
        The address of a running Dask scheduler instead of a local cluster.
    client : distributed.Client, optional
        A client to use as it is.
    serial : bool, optional
        Run in this process, one draw after another (the baseline; no Dask needed; default False).
    seeds : sequence of int or None, optional
        The seeds themselves instead of ``draws`` and ``seed`` (distinct integers >= 0, at most 100000).
    flat : bool, optional
        Each row flattened (lists and arrays as name_0, name_1, ...; default), or the draw's dict as it is (nested
        values kept) with its ``seed``.

    Returns
    -------
    SweepResult
        The rows in the seeds' order.

    Raises
    ------
    InputError
        Each of ``serial``, ``scheduler``, ``client`` and ``workers`` says where the draws run: given together
        they are refused (none is silently ignored); so is an option ``fn`` takes no argument of, a seed out of
        range or given twice, or Dask absent without ``serial``.
    """
    if not callable(fn):
        raise InputError(f"fn: expected a function of the seed, got {type(fn).__name__}")
    seeds = _sweep_seeds(draws, seed, seeds)
    options = _sweep_options(fn, flat, options)
    where = [n for n, given in (("serial", bool(serial)), ("scheduler", scheduler is not None),
                                ("client", client is not None), ("workers", workers is not None)) if given]
    if len(where) > 1:
        raise InputError(f"{where[1]}: {where[0]} already says where the draws run; give one of serial, scheduler, "
                         "client or workers")
    t0 = time.perf_counter()
    if serial:
        rows = [_draw(fn, s, options, bool(flat)) for s in seeds]
        return SweepResult(rows, time.perf_counter() - t0, "serial", 1)
    return _dask_sweep(fn, seeds, options, bool(flat), workers, scheduler, client, t0)


def _sweep_seeds(draws: int | None, seed: int, seeds: Sequence[int] | None) -> list[int]:
    """The seeds of :func:`sweep`: ``seeds`` checked (1 to 100000 distinct integers in 0..MAX_SEED), or
    seed .. seed + draws - 1 (draws in 1..100000, the last seed MAX_SEED at most)."""
    if seeds is not None:
        if draws is not None or seed != 0:
            raise InputError("seeds: give the seeds, or draws and seed, not both")
        if isinstance(seeds, (str, bytes)) or not hasattr(seeds, "__len__") or not 1 <= len(seeds) <= 100_000:
            raise InputError(f"seeds: expected 1 to 100000 integers, got {type(seeds).__name__}")
        seeds = [_check_int(s_, "seeds", 0, MAX_SEED) for s_ in seeds]
        if len(set(seeds)) != len(seeds):
            raise InputError("seeds: a seed is given twice (each draw is its seed's)")
        return seeds
    if draws is None:
        raise InputError("draws: expected the number of draws (or seeds=)")
    draws = _check_int(draws, "draws", 1, 100_000)
    seed = _check_int(seed, "seed", 0, MAX_SEED + 1 - draws)  # the last draw's seed MAX_SEED at most
    return list(range(seed, seed + draws))


def _sweep_options(fn: Callable[..., Any], flat: Any, options: dict[str, Any] | None) -> dict[str, Any]:
    """:func:`sweep`'s ``flat`` checked a bool and its ``options`` a dict of ``fn``'s keyword arguments (not the
    seed, each draw's own); a copy of them."""
    if not isinstance(flat, (bool, np.bool_)):
        raise InputError(f"flat: expected True or False, got {flat!r}")
    if options is not None and not (isinstance(options, dict) and all(isinstance(k, str) for k in options)):
        raise InputError(f"options: expected a dict of keyword arguments of fn, got {type(options).__name__}")
    options = dict(options or {})
    if "seed" in options:
        raise InputError("options: 'seed' is each draw's own (seed, seed + 1, ...); give it as sweep's seed")
    _check_options(fn, options)
    return options


def _dask_sweep(fn: Callable[..., dict[str, Any]], seeds: list[int], options: dict[str, Any], flat: bool,
                workers: int | None, scheduler: str | None, client: Any, t0: float) -> SweepResult:
    """The draws of :func:`sweep` on Dask: on ``client``, or on a client of its own (of the ``scheduler``, or of a
    local cluster of ``workers`` processes) closed at the end; the rows in the seeds' order."""
    if scheduler is not None and not (isinstance(scheduler, str) and "://" in scheduler):
        raise InputError(f"scheduler: expected an address such as tcp://host:8786, got {scheduler!r}")
    try:
        from distributed import Client
    except ImportError:
        raise InputError("sweep: Dask is not installed (pip install 'alpes_dyn[sweep]'), or pass serial=True "
                         "(the command line's --serial)") from None
    own = client is None
    cluster = None
    if own:
        if scheduler is not None:
            try:
                client = Client(scheduler, timeout="10s")
            except (OSError, ValueError, TypeError) as exc:  # no scheduler there, or not an address Dask reads
                raise InputError(f"scheduler: cannot connect to {scheduler!r} ({type(exc).__name__}: "
                                 f"{str(exc).splitlines()[0] if str(exc) else ''})") from None
        else:
            client = local_client(_check_int(2 if workers is None else workers, "workers", 1, 256))
            cluster = client.cluster
    try:
        n_workers = len(client.scheduler_info().get("workers", {}))
        run = uuid.uuid4().hex[:8]  # a sweep's own keys: two sweeps of the same seeds on one client stay apart
        futures = [client.submit(_draw, fn, s, options, flat, pure=False, key=f"draw-{s}-{run}") for s in seeds]
        rows = client.gather(futures)
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()
    return SweepResult(list(rows), time.perf_counter() - t0, "dask", n_workers)


def robustness_draw(seed: int, model: str = "finger3", spread: float = 0.2, duration: float = 4.0,
                    fit: bool = True) -> dict[str, Any]:
    """One draw of the robustness study: a finger drawn within +-``spread`` per link (K, m, friction; seed
    ``seed``), its identification experiment of ``duration`` s (our simulator), the fit (``fit``), and the EKF
    on the recording with the nominal file (``rmse_deg_before``, degrees per joint) and the identified one
    (``rmse_deg_after``); the worst parameter errors in %, the fit's time, convergence and residual (counts).

    Parameters
    ----------
    seed : int
        The draw's and the sensor noise's seed.
    model : str, optional
        The Alpes finger (default ``"finger3"``).
    spread : float, optional
        The draw's half-width, a fraction (default 0.2: +-20 %).
    duration : float, optional
        The experiment's duration, s (default 4).
    fit : bool, optional
        Run the fit (default True; False: the EKF with the nominal file only).

    Returns
    -------
    dict
    """
    from ..estimation.experiments.experiment import ExperimentDesign, experiment, perturbed_params
    from ..estimation.identification.identification import identified_params, identify
    from ..estimation.observers.replay import estimate_recording
    from ..model.robot import Model

    true = perturbed_params(spread=spread, seed=seed)
    design = ExperimentDesign(duration=duration)
    rec = experiment(model, true, design=design, seed=seed)
    nominal = Model.alpes(model, friction=True)
    out: dict[str, Any] = {"rmse_deg_before": np.degrees(estimate_recording(rec, nominal).rmse)}
    if fit:
        t0 = time.perf_counter()
        res = identify(nominal, rec, excitation=design.lines, progress=False)
        out["fit_seconds"] = time.perf_counter() - t0
        out["converged"] = bool(res.converged)
        out["residual_counts"] = float(res.residual_rms)
        ident = identified_params(res)
        truth = {"K": true.finger.K, "m": true.finger.m, "F_s": true.finger.F_s, "F_v": true.finger.F_v}
        got = {"K": ident.finger.K, "m": ident.finger.m, "F_s": ident.finger.F_s, "F_v": ident.finger.F_v}
        for k in truth:
            out[f"worst_{k}_pct"] = float(100 * np.max(np.abs(np.asarray(got[k]) / np.asarray(truth[k]) - 1)))
        out["rmse_deg_after"] = np.degrees(estimate_recording(rec, Model.alpes(model, friction=True, params=ident),
                                                                      force=True).rmse)  # a flagged fit judged too
    return out


def drawn_spec(spec: Any, spread: float, seed: int) -> Any:
    """A copy of the transmission spec ``spec`` whose stiffness, Coulomb and viscous friction values are each
    multiplied by U(1 - ``spread``, 1 + ``spread``) (seeded by ``seed``; in the spec's order: stiffness, coulomb,
    viscous, each table's joints as written); the rest (motors, ratios, rotor inertia, rest angles) as it is. What a
    spec holds of a robot's tolerances (its masses are the URDF's, not drawn).

    Parameters
    ----------
    spec : TransmissionSpec
        The robot's spec.
    spread : float
        The draw's half-width, a fraction in [0, 1).
    seed : int
        The draw's seed.

    Returns
    -------
    TransmissionSpec

    Raises
    ------
    InputError
        ``spread`` out of [0, 1).
    """
    import dataclasses

    if not (isinstance(spread, (int, float)) and not isinstance(spread, bool) and 0 <= spread < 1):
        raise InputError(f"spread: expected a fraction in [0, 1), got {spread!r}")
    rng = np.random.default_rng(seed)

    def drawn(table: Any) -> dict[str, float]:
        factors = rng.uniform(1 - spread, 1 + spread, len(table))
        return {j: float(v) * float(f) for (j, v), f in zip(table.items(), factors)}
    return dataclasses.replace(spec, stiffness=drawn(spec.stiffness), coulomb=drawn(spec.coulomb),
                               viscous=drawn(spec.viscous), identified=None)


WARM_UP_ITERATIONS = 12
"""Gauss-Newton iterations of the first stage of :func:`robot_robustness_draw`'s fit (the driven joints' values, the
passive ones held): a warm start, not a fit (its docstring: why two stages, and why short)."""
ROBOT_DRAWN: tuple[str, ...] = ("K", "F_s", "F_v")
"""What :func:`robot_robustness_draw` draws and fits on a URDF + spec robot: the spec's stiffness, Coulomb and viscous
friction of every joint that has them, passive joints included; the masses, inertias, rest angles, pulley ratios and
rotor inertia are held at the URDF's and the spec's values (not drawn, not fitted): :data:`ROBOT_HELD`."""
ROBOT_HELD: tuple[str, ...] = ("masses and inertias (the URDF's)", "rest angles", "pulley ratios", "rotor inertia")
"""What :func:`robot_robustness_draw` neither draws nor fits (held in the truth and in the fit alike)."""


def staged_fit(fit: Callable[..., Any], names: list[str], first: list[str]) -> tuple[Any, bool]:
    """(the fit kept, whether the one-stage restart was run) of :func:`robot_robustness_draw`: ``fit(names, **kw)``
    (``identify`` on the recording) of ``first`` (the driven joints' values) for at most :data:`WARM_UP_ITERATIONS`,
    then of every name from there; where that does not converge, one stage from the spec's values as well, the
    converged one kept (both converged or neither: the lower residual). Where ``first`` is every name (or none), one
    stage. Why the restart: neither order converges on every draw (robot_robustness_draw's docstring)."""
    if not first or len(first) == len(names):
        return fit(names), False
    held = fit(first, max_iterations=WARM_UP_ITERATIONS)
    res = fit(names, start=held)
    if res.converged:
        return res, False
    alt = fit(names)
    better = (alt.converged, -alt.residual_rms) > (res.converged, -res.residual_rms)
    return (alt if better else res), True


def robot_robustness_draw(seed: int, urdf: str = "", spec: str = "", spread: float = 0.2, duration: float = 4.0,
                          fit: bool = True) -> dict[str, Any]:
    """One draw of the robustness study on a URDF + spec robot (the files ``urdf`` and ``spec``: their paths travel
    to the workers, which read them): the true robot's spec drawn within +-``spread`` (:func:`drawn_spec`, seed ``seed``), the
    identification experiment of ``duration`` s designed on the nominal robot and simulated on the drawn one
    (:func:`~alpes_dyn.estimation.experiments.experiment.model_experiment`), the fit (``fit``) of what was drawn
    (:data:`ROBOT_DRAWN`: K, F_s, F_v of every joint that has them), and the EKF on the recording with the nominal spec
    (``rmse_deg_before``, degrees per joint) and the identified one (``rmse_deg_after``); the worst errors of the
    fitted K, F_s, F_v in %, the fit's time, convergence and residual (counts).

    Why the passive joints' values are fitted too: the draw perturbs them, and a fit that held them at the spec's
    values fitted a model that cannot reproduce the data (on finger_edu, whose ab/adduction has no motor, the fit of
    the driven joints then runs into the iteration cap, far above the sensor floor, its springs well off); freed,
    it converges at the sensor floor: the encoders do see a passive joint through its coupling to the driven ones.
    The masses are the URDF's in the draw and in the fit (a spec holds none), so nothing drawn is held.

    Why in two stages: freed from the nominal start at once, a draw with the passive values off can run into the
    iteration cap, the passive spring pulled away while the driven joints' values are still wrong. So the driven
    joints' values are fitted first, the passive ones held, for at most :data:`WARM_UP_ITERATIONS` (a warm-up:
    with wrong held values it cannot converge, and run longer it drifts away), then everything drawn from there.
    A robot whose motors drive every joint is fitted in one stage.

    Why the one-stage restart (:func:`staged_fit`): a draw with the passive spring far off fails the two stages
    (the warm-up, the passive values held that far off, pulls a driven spring away, and the second stage ends at
    the iteration cap) while one stage from the spec's values converges at the sensor floor, in less time; other
    draws are the other way round. So where the two stages do not converge, the fit is run in one stage too and
    the converged one kept (``one_stage_restart`` in the row).

    Parameters
    ----------
    seed : int
        The draw's and the sensor noise's seed.
    urdf : str
        The URDF file's path.
    spec : str
        The spec (TOML) file's path.
    spread : float, optional
        The draw's half-width, a fraction (default 0.2: +-20 %).
    duration : float, optional
        The experiment's duration, s (default 4).
    fit : bool, optional
        Run the fit (default True; False: the EKF with the nominal spec only).

    Returns
    -------
    dict
    """
    import warnings

    from ..estimation.identification.adequacy import AdequacyWarning
    from ..estimation.experiments.experiment import ExperimentDesign, model_experiment
    from ..estimation.identification.identification import identify
    from ..estimation.identification.identified_spec import identified_spec
    from ..estimation.observers.replay import estimate_recording
    from ..model.robot import Model
    from ..symbolic.parametric import select_parameters

    nominal = Model.from_urdf_file(urdf, spec)
    true_spec = drawn_spec(nominal.spec, spread, seed)
    truth = Model(nominal.urdf, true_spec)
    design = ExperimentDesign(duration=duration)
    rec = model_experiment(nominal, truth, design, seed=seed)
    out: dict[str, Any] = {"rmse_deg_before": np.degrees(estimate_recording(rec, nominal).rmse)}
    if fit:
        chosen = {p.name: p for p in select_parameters(nominal, ",".join(ROBOT_DRAWN))}  # every value drawn
        driven = {j for j, d in zip(nominal.joint_names, nominal.transmission.driven) if d}
        t0 = time.perf_counter()
        with warnings.catch_warnings():  # the verdict is the row's: converged, residual
            warnings.simplefilter("ignore", AdequacyWarning)
            first = [n for n, p in chosen.items() if p.joint in driven]
            fit_of = functools.partial(identify, nominal, rec, excitation=design.lines, progress=False)
            res, restarted = staged_fit(fit_of, list(chosen), first)
        out["fit_seconds"] = time.perf_counter() - t0
        out["one_stage_restart"] = restarted
        out["converged"] = bool(res.converged)
        out["residual_counts"] = float(res.residual_rms)
        truth_of = {"K": true_spec.stiffness, "F_s": true_spec.coulomb, "F_v": true_spec.viscous}
        for kind, table in truth_of.items():
            errs = [abs(v / table[chosen[n].joint] - 1) for n, v in zip(res.names, res.values)
                    if n.startswith(kind + "_") and chosen[n].joint in table]
            out[f"worst_{kind}_pct"] = float(100 * max(errs)) if errs else float("nan")
        ident = Model(nominal.urdf, identified_spec(res, nominal.spec))
        out["rmse_deg_after"] = np.degrees(estimate_recording(rec, ident).rmse)
    return out


STUDIES: dict[str, Callable[..., dict[str, Any]]] = {"robustness": robustness_draw}
"""The studies ``alpes-dyn sweep`` runs, by name."""
