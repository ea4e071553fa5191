"""Nonlinear observability rank test of a state space (report Chapter 3, eq. 3.4-3.8, 3.14).

For x' = f(x, u), y = h(x) (:class:`~alpes_dyn.symbolic.statespace.StateSpace`, eq. 3.1-3.3) the observability
matrix of order k is

    O_k = d(y, y', ..., y^(k)) / dx,        shape (p (k + 1), n),

(eq. 3.6, 3.14), built here by automatic differentiation on CasADi SX. The output derivatives are
Lie derivatives along the extended vector field of z = (x, u, u', u'', ...):

    d/dt phi(x, u, ..., u^(j-1)) = dphi/dx f(x, u) + sum_i dphi/du^(i) u^(i+1),

so the input derivatives u', u'', ... are independent symbols (time-varying inputs, as STRIKE-GOLDD
does); with ``constant_input=True`` they are zero. The system is observable iff rank O_{n-1} = n
(eq. 3.8; n = number of states).

Numerical rank (at one point). Each row of O is scaled to unit Euclidean norm (rows are derivatives of
different orders and units; zero rows stay zero), then the singular values s_1 >= ... of the scaled
matrix are computed and ``rank = #{s_i > tol}`` with numpy's rule ``tol = max(rows, cols) * eps * s_1``.
In the analysis below, a row whose norm is below max(rows, cols) * eps times that row's largest norm over
the random points counts as zero, so that rounding noise at a special point (the rest state) is not
blown up into a unit row.
``s_n / s_1`` (n = number of states; 0 if rows < n) is the *normalised smallest singular value*, its
inverse the *condition*: how well, not only whether, the state is observable there.

Generic rank. O is evaluated at ``points`` seeded random points (one compiled ``casadi.Function`` per
derivative order, ``.map`` over all points, no Python loop over points): q uniform within the joint
limits, q' uniform in [-2, 2] rad/s, each input u_j and its derivatives u_j^(i) uniform in
[-s_j, s_j] (units N m / s^i, i.e. a 1 s^-1 time scale), with s_j the largest joint torque of gravity
and springs over the sampled q that input j acts on (the model's torque scale). The generic rank is the
maximum over the points; the points where the rank is lower are reported, and so is the rank at the
rest state x = 0, u = u' = ... = 0.

Observability index and stop rule. rank O_k grows with k (the filtration O_0 c O_1 c ..., eq. 3.4).
If rank O_{k+1} = rank O_k (generic rank), the rows of y^(k+1) are, locally, functions of
(y, ..., y^(k)) and of the inputs and their derivatives; differentiating once more keeps them so, hence
rank O_j = rank O_k for every j > k: the filtration is stationary and rank O_k = dim O_inf (eq. 3.5-3.6).
``order="auto"`` (default) therefore stops at the first stall, at full rank n, or at n - 1 (the
theorem's bound), whichever comes first; the *index* is the smallest k with rank O_k = dim O_inf.
This keeps the 30-state hand cheap (each finger needs y..y^(5), not y..y^(29)).
``order="report"`` builds the report's O = d(y, ..., y^(n-1))/dx (eq. 3.6, 3.8, 3.14), stopping early
only once the rank is n (more rows cannot change it); an integer builds exactly that order. Each order
costs about 3 times the previous one (finger3: 2e4 operations at y^(5), 1.7e6 at y^(9)); an order whose
function would exceed ``max_operations`` operations (default
:data:`~alpes_dyn.analysis.observability_matrix.MAX_INSTRUCTIONS`) raises
:class:`~alpes_dyn.InputError` naming the order, the estimate and how to raise the cap.

The matrix. :class:`~alpes_dyn.analysis.observability_matrix.ObservabilityMatrix` (O_k built and evaluated) and
the rank at one point (:func:`~alpes_dyn.analysis.observability_matrix.numerical_rank`,
:func:`~alpes_dyn.analysis.observability_matrix.normalised_singular_values`) are the module
:mod:`alpes_dyn.analysis.observability_matrix`; their names stay importable from here.

Parts. A tree whose chains move independently (the hand: four fingers and the thumb; the mass matrix is
block diagonal per chain) is also analysed part by part: the rows of the part's outputs and the
columns of its states. ``coupled`` tells whether those rows also depend on other states (then the
part's figures assume those states known).

One call::

    import alpes_dyn as ad
    rep = ad.check_observability("finger3")   # Model.alpes("finger3"), u = joint torques, y = q1 + q2 + q3
    rep.rank, rep.observable, rep.index       # 6, True, 5
    print(rep.to_text()); rep.to_dict()

Names. The function is :func:`check_observability`; the module is ``alpes_dyn.analysis.observability``. The
function used to be exported by the package as ``alpes_dyn.analysis.observability``, which hid this module
(``import alpes_dyn.analysis.observability`` then gave the function). The function was renamed rather than the
module because the module name is the one the documentation, the command (``alpes-dyn observability``)
and the other modules' imports use. The old spellings keep working: ``observability`` is an alias of
:func:`check_observability` in this module, and the module itself is callable
(``alpes_dyn.analysis.observability("finger3")`` forwards to :func:`check_observability`).
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..errors import InputError, ModelError
from ..limits import MAX_OPERATIONS, MAX_ORDER, MAX_POINTS  # noqa: F401 (importable from here as before)
from ..model.robot import Model
from ..symbolic.statespace import StateSpace
from .observability_matrix import (_EPS, MAX_INSTRUCTIONS, ObservabilityMatrix, _max_operations,  # noqa: F401
                                   _order, normalised_singular_values, numerical_rank)  # (re-exported: the matrix)

__all__ = [
    "ObservabilityMatrix", "ObservabilityReport", "check_observability", "observability", "MAX_INSTRUCTIONS",
    "normalised_singular_values",
    "numerical_rank", "sample_points",
]

_SPEED = 2.0  # rad/s, bound of the sampled joint velocities (as Model.random_state)


# ----------------------------------------------------------------------------- sampling
def sample_points(ss: StateSpace, points: int, rng: np.random.Generator, order: int,
                  constant_input: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Random points (X (N, n_states), W (N, w_size)) for the generic rank, see the module doc.

    Parameters
    ----------
    ss : StateSpace
        The system.
    points : int
        The number of points N.
    rng : numpy.random.Generator
        The random source.
    order : int
        The highest output derivative (the inputs' derivatives up to it are drawn).
    constant_input : bool, optional
        One input per point, its derivatives zero (default False).

    Returns
    -------
    X : numpy.ndarray, shape (N, n_states)
        The states [q; qd], joint velocities within 2 rad/s.
    W : numpy.ndarray, shape (N, w_size)
        The inputs and their derivatives, each input scaled by the largest gravity + spring torque of the joints it
        drives.
    """
    q, v = ss.model.random_state(rng, _SPEED, size=points)
    scale = _input_scale(ss, q)
    reps = 1 if constant_input else max(order, 1)
    W = rng.uniform(-1.0, 1.0, size=(points, reps * scale.size)) * np.tile(scale, reps)
    return np.hstack([q, v]), W


def _input_scale(ss: StateSpace, q: np.ndarray) -> np.ndarray:
    """Per known input: the largest gravity + spring torque (N m) of the joints it drives, over q (N, n)."""
    # Pinocchio, a few microseconds per sampled point (this is set-up, not a hot path)
    g = np.max(np.abs([ss.model.gravity_torque(qi) for qi in q]), axis=0)  # (n,)
    gmax = float(g.max()) if g.size and g.max() > 0 else 1.0
    B = np.abs(ss.B)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(B > 0, g[:, None] / B, 0.0).max(axis=0)
        fallback = gmax / np.where(B.max(axis=0) > 0, B.max(axis=0), 1.0)
    s = np.where(s > 0, s, fallback)
    if ss.force:
        s = np.concatenate([s, np.ones(ss.n_force)])  # contact forces, N (wrench torques N m)
    return s


# ----------------------------------------------------------------------------- the report
@dataclass
class ObservabilityReport:
    """Result of :func:`observability` for a system or one of its parts.

    Attributes
    ----------
    model: name of the model (or of the part).
    n_states, n_outputs: sizes (of the part).
    rank: generic rank of O (max over the random points) = dim O_inf (eq. 3.6).
    rank_at_rest: rank of O at x = 0, u = u' = ... = 0.
    min_singular_value: median over the random points of s_n / s_1 of the row-normalised O.
    condition: 1 / min_singular_value (inf when not observable).
    index: smallest derivative order k with rank O_k = rank.
    ranks_by_order: generic rank of O_0, O_1, ... O_order.
    order: highest derivative order built (O = d(y..y^(order))/dx).
    seconds: wall time (for a part: its rank analysis on the shared O).
    rank_drops: sampled points (x, u, rank) where the rank is below ``rank``.
    unobservable_directions: (n_states, n_states - rank) right null vectors of O at a generic point.
    coupled: whether the part's output derivatives depend on states outside the part.
    parts: per-part reports (the hand: four fingers and the thumb).
    """

    model: str
    n_states: int
    n_outputs: int
    rank: int
    rank_at_rest: int
    min_singular_value: float
    condition: float
    index: int
    ranks_by_order: tuple[int, ...]
    order: int
    seconds: float
    state_names: tuple[str, ...] = ()
    output_names: tuple[str, ...] = ()
    rank_drops: list[dict[str, Any]] = field(default_factory=list)
    unobservable_directions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    singular_values: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    coupled: bool = False
    parts: tuple["ObservabilityReport", ...] = ()
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def observable(self) -> bool:
        """rank O = n_states (eq. 3.8)."""
        return self.rank == self.n_states

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: model, n_states, n_outputs, rank, observable, rank_at_rest, min_singular_value,
        condition (None if infinite), index, seconds, parts, and the details."""
        d: dict[str, Any] = {
            "model": self.model, "n_states": self.n_states, "n_outputs": self.n_outputs, "rank": self.rank,
            "observable": self.observable, "rank_at_rest": self.rank_at_rest,
            "min_singular_value": self.min_singular_value,
            "condition": self.condition if np.isfinite(self.condition) else None,
            "index": self.index, "seconds": self.seconds, "parts": [p.to_dict() for p in self.parts],
            "order": self.order, "ranks_by_order": list(self.ranks_by_order),
            "state_names": list(self.state_names), "output_names": list(self.output_names),
            "rank_drops": self.rank_drops,
            "unobservable_directions": self.unobservable_directions.T.tolist(),
        }
        if self.settings:
            d.update(self.settings)
        else:
            d["coupled"] = self.coupled
        return d

    def _row(self, name: str) -> str:
        cond = f"{self.condition:9.2e}" if np.isfinite(self.condition) else "      inf"
        return (f"  {name:12s} {self.n_states:6d} {self.n_outputs:7d} {f'{self.rank}/{self.n_states}':>7s}  "
                f"{'yes' if self.observable else 'NO ':10s} {self.index:5d}  {self.min_singular_value:9.2e} {cond}"
                f" {f'{self.rank_at_rest}/{self.n_states}':>8s}")

    def to_text(self) -> str:
        """A short readable report: one line per part and one for the whole."""
        st = self.settings
        lines = [
            f"Observability of {self.model}: input {st.get('input')} ({st.get('n_inputs')}), output "
            f"{st.get('output')} ({self.n_outputs}), spring {st.get('spring')}, "
            f"{'contact force known, ' if st.get('force') else ''}"
            f"{'constant' if st.get('constant_input') else 'time-varying'} input",
            f"  O = d(y, y', ..., y^({self.order}))/dx (eq. 3.6, 3.14, order {st.get('definition')}), generic rank "
            f"over {st.get('points')} random points (seed {st.get('seed')})",
            "  part         states outputs    rank  observable index  min sv    condition  at rest",
        ]
        for p in self.parts:
            lines.append(p._row(p.model) + ("  (coupled)" if p.coupled else ""))
        lines.append(self._row(self.model + (" (tree)" if self.parts else "")))
        lines.append("  rank by derivative order: " + " ".join(str(r) for r in self.ranks_by_order))
        if not self.observable and self.unobservable_directions.size:
            v = self.unobservable_directions[:, 0]
            big = np.argsort(-np.abs(v))[:3]
            lines.append("  unobservable direction (largest components): "
                         + ", ".join(f"{self.state_names[i]} {v[i]:+.3f}" for i in big if abs(v[i]) > 1e-3))
        drops = [p for p in self.parts if p.rank_drops] + ([self] if self.rank_drops else [])
        for p in drops:
            lines.append(f"  {p.model}: rank drops at {len(p.rank_drops)} of the sampled points")
        lines.append(f"  {self.seconds:.2f} s")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()


def _row_scale(O: np.ndarray) -> np.ndarray:
    """Largest norm of each row over the random points (all but the last, the rest state)."""
    return np.linalg.norm(O[:-1], axis=-1).max(axis=0)


def _analyse(name: str, blocks: list[np.ndarray], rows: np.ndarray, cols: np.ndarray, X: np.ndarray, W: np.ndarray,
             m: int, state_names: Sequence[str], output_names: Sequence[str]) -> ObservabilityReport:
    """Ranks and conditioning of O restricted to output ``rows`` and state ``cols``.

    ``blocks[k]``: (N + 1, p, n) values of d y^(k)/dx at N random points and, last, the rest state.
    """
    t0 = time.perf_counter()
    n = cols.size
    ranks: list[int] = []
    for k in range(len(blocks)):
        Ok = np.concatenate([b[:, rows][:, :, cols] for b in blocks[: k + 1]], axis=1)
        ranks.append(int(np.max(numerical_rank(Ok[:-1], _row_scale(Ok)))))
    O = np.concatenate([b[:, rows] for b in blocks], axis=1)  # (N + 1, rows, all states)
    Oc = O[:, :, cols]
    tol = max(Oc.shape[1:]) * _EPS
    s = normalised_singular_values(Oc, _row_scale(Oc))
    pr = np.sum(s > tol, axis=-1)
    rank = ranks[-1]
    index = next(k for k, r in enumerate(ranks) if r == rank)
    smin = float(np.median(s[:-1, n - 1])) if n else 0.0
    cond = 1.0 / smin if (rank == n and smin > 0) else float("inf")
    drops = [{"x": X[i].tolist(), "u": W[i, :m].tolist(), "rank": int(pr[i])}
             for i in np.flatnonzero(pr[:-1] < rank)]
    null = np.zeros((n, 0))
    if rank < n:
        best = int(np.argmax(pr[:-1]))
        A = Oc[best]
        nrm = np.linalg.norm(A, axis=1, keepdims=True)
        A = np.divide(A, nrm, out=np.zeros_like(A), where=nrm > 0)
        _, _, Vt = np.linalg.svd(A)
        null = Vt[rank:].T if Vt.shape[0] >= n else np.zeros((n, 0))
    coupled = False
    if cols.size < O.shape[2]:
        other = np.setdiff1d(np.arange(O.shape[2]), cols)
        nrm = np.linalg.norm(O[:-1], axis=2)
        out = np.linalg.norm(O[:-1][:, :, other], axis=2)
        coupled = bool(np.any(out > 1e-12 * np.maximum(nrm, 1e-300)))
    return ObservabilityReport(
        model=name, n_states=n, n_outputs=rows.size, rank=rank, rank_at_rest=int(pr[-1]),
        min_singular_value=smin, condition=cond, index=index, ranks_by_order=tuple(ranks), order=len(blocks) - 1,
        seconds=time.perf_counter() - t0, state_names=tuple(state_names[i] for i in cols),
        output_names=tuple(output_names[i] for i in rows), rank_drops=drops, unobservable_directions=null,
        singular_values=s[:-1], coupled=coupled)


def tree_parts(model: Model) -> dict[str, tuple[str, ...]]:
    """The subtrees hanging from the root body, {name: joint names}: the parts that move independently
    (the mass matrix of a fixed-base tree is block diagonal over them). A part is named after the first
    motor driving one of its joints (parts in motor order: the Alpes hand's index, middle, ring, little,
    thumb), else after its first joint."""
    pm = model.pin_model
    root_of = {}
    for j in range(1, pm.njoints):
        if pm.names[j] not in model.joint_names:
            continue  # a mimic joint (model.mimic): no coordinate of its own
        k = j
        while pm.parents[k] != 0:
            k = pm.parents[k]
        root_of.setdefault(k, []).append(pm.names[j])
    S = model.transmission.S if model.transmission is not None else np.zeros((0, model.n))
    named = []
    for joints in root_of.values():
        cols = [model.joint_index(j) for j in joints]
        motors = np.flatnonzero(np.any(S[:, cols] != 0, axis=1))
        key = (0, int(motors[0])) if motors.size else (1, cols[0])
        named.append((key, model.motor_names[motors[0]] if motors.size else joints[0], tuple(joints)))
    return {name: joints for _, name, joints in sorted(named)}


def _parts(ss: StateSpace, parts: Any) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(name, output rows, state columns) of each part; [] for a single chain."""
    n = ss.n
    if parts is None or parts is False:
        return []
    if parts == "auto":
        spec = tree_parts(ss.model)
        if len(spec) < 2:
            return []
    elif isinstance(parts, dict):
        spec = {str(k): tuple(v) for k, v in parts.items()}
    else:
        raise ModelError(f"parts: expected 'auto', None or a dict name -> joint names, got {parts!r}")
    support = np.array(cs.DM(cs.jacobian(ss.h_expr, ss.x).sparsity(), 1)) != 0  # (p, 2n): y_i depends on x_j
    idx = {j: i for i, j in enumerate(ss.model.joint_names)}
    out = []
    for name, joints in spec.items():
        bad = [j for j in joints if j not in idx]
        if bad:
            raise ModelError(f"parts: unknown joint {bad[0]!r} in part {name!r} (joints: {', '.join(idx)})")
        jj = np.array(sorted(idx[j] for j in joints), dtype=int)
        mask = np.zeros(2 * n, bool)
        mask[jj] = mask[jj + n] = True
        rows = np.flatnonzero(support.any(axis=1) & ~(support & ~mask).any(axis=1))
        out.append((name, rows, np.concatenate([jj, jj + n])))
    return out


def check_observability(system: Model | StateSpace | str, input: str | None = None, output: Any = None, *,
                        spring: str | None = None, points: int = 8, seed: int = 0, constant_input: bool = False,
                        order: str | int = "auto", parts: Any = "auto",
                        max_operations: int = MAX_INSTRUCTIONS) -> ObservabilityReport:
    """Nonlinear observability of a model's state space, in one call (eq. 3.4-3.8, 3.14).

    Parameters
    ----------
    system : StateSpace or Model or str
        A :class:`StateSpace`, a :class:`Model`, or an Alpes model name (``finger2``, ``finger3``, ``hand``; built
        with :meth:`Model.alpes` and ``spring``).
    input, output : str or None, optional
        The input and output of the :class:`StateSpace` built for a model (default ``"joint"``, ``"sum"``: the
        report's u = Gamma, y = sum q); not allowed with a StateSpace (it has its own).
    spring : str or None, optional
        The spring model for a model name (default ``"torsional"``).
    points : int, optional
        Random points for the generic rank (1 to :data:`alpes_dyn.limits.MAX_POINTS` = 10000).
    seed : int, optional
        Their seed (an integer >= 0).
    constant_input : bool, optional
        u' = u'' = ... = 0 instead of free input derivatives.
    order : {"auto", "report"} or int, optional
        ``"auto"`` (stop at full rank or when the filtration stops growing, see the module doc), ``"report"``
        (y .. y^(n-1), eq. 3.8, stopping early only at full rank) or the highest derivative order.
    parts : "auto" or None or dict, optional
        ``"auto"`` (the subtrees from the root, :func:`tree_parts`: the Alpes hand's fingers and thumb), None, or
        {name: joint names}.
    max_operations : int, optional
        The size cap of one derivative order's CasADi function (default
        :data:`~alpes_dyn.analysis.observability_matrix.MAX_INSTRUCTIONS`); above it :class:`~alpes_dyn.InputError`
        says so. Raise it for large trees whose outputs need high orders.

    Returns
    -------
    ObservabilityReport
        The rank at each order, the unobservable directions named, the verdict.

    Also available as ``observability`` (the former name, kept as an alias).
    """
    t0 = time.perf_counter()
    if isinstance(points, (bool, np.bool_)) or not isinstance(points, (int, np.integer)) or points < 1:
        raise InputError(f"points: expected a positive integer, got {points!r}")
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed: expected an integer >= 0, got {seed!r}")
    if points > MAX_POINTS:
        raise InputError(f"points: at most {MAX_POINTS} random points (alpes_dyn.limits.MAX_POINTS), got {points}")
    if isinstance(system, str):
        system = Model.alpes(system, spring=spring or "torsional")
    elif spring is not None:
        raise ModelError("spring: only with a model name; a Model or StateSpace has its springs already")
    if isinstance(system, StateSpace):
        if input is not None or output is not None:
            raise ModelError("input/output: a StateSpace has its own; pass a Model to choose them")
        ss = system
    elif isinstance(system, Model):
        ss = StateSpace(system, input=input or "joint", output="sum" if output is None else output)
    else:
        raise ModelError(f"system: expected a StateSpace, a Model or a model name, got {type(system).__name__}")
    n = ss.n_states
    if order == "auto" or order == "report":
        kmax = n - 1
    else:
        kmax = _order(order) if not isinstance(order, str) else -1
        if kmax < 0:
            raise InputError(f"order: expected 'auto', 'report' or a non-negative integer, got {order!r}")
    om = ObservabilityMatrix(ss, constant_input, max_operations)
    rng = np.random.default_rng(int(seed))
    X, W = sample_points(ss, int(points), rng, kmax, constant_input)
    Xa = np.vstack([X, np.zeros((1, n))])
    Wa = np.vstack([W, np.zeros((1, W.shape[1]))])
    part_spec = _parts(ss, parts)
    blocks: list[np.ndarray] = []
    ranks: list[int] = []
    for k in range(kmax + 1):
        blocks.append(om._eval_block(k, Xa, Wa))
        if not np.isfinite(blocks[-1]).all():
            raise InputError(f"observability matrix is not finite at derivative order {k} (model too stiff?)")
        Ok = np.concatenate(blocks, axis=1)
        ranks.append(int(np.max(numerical_rank(Ok[:-1], _row_scale(Ok)))))
        if order in ("auto", "report") and ranks[-1] == n:
            break  # more rows cannot change a rank that is already full
        if order == "auto" and k > 0 and ranks[-1] == ranks[-2]:
            break  # the filtration is stationary
    names_s, names_y = ss.state_names, ss.output_names
    whole = _analyse(ss.model.name, blocks, np.arange(ss.n_outputs), np.arange(n), X, W, om.m, names_s, names_y)
    whole.parts = tuple(_analyse(nm, blocks, r, c, X, W, om.m, names_s, names_y) for nm, r, c in part_spec)
    whole.seconds = time.perf_counter() - t0
    whole.settings = {
        "input": ss.input, "n_inputs": ss.n_inputs, "output": ss.output_name, "spring": ss.model.spring,
        "constant_input": bool(constant_input), "definition": order if isinstance(order, str) else int(order),
        "points": int(points), "seed": int(seed), "force": ss.force,
    }
    return whole


observability = check_observability  # the former name (``from alpes_dyn.analysis.observability import observability``)


class _CallableModule(type(sys.modules[__name__])):  # type: ignore[misc]
    """``alpes_dyn.analysis.observability(...)`` (the package used to export the function under the module's name)."""

    def __call__(self, *args: Any, **kwargs: Any) -> ObservabilityReport:
        return check_observability(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
