"""Identifiability of physical parameters, before any fit: structural (rank) and practical (Cramér-Rao).

Structural. The chosen physical parameters theta (p,) of :class:`~alpes_dyn.symbolic.parametric.ParametricDynamics`
(spring stiffness ``K_i``, mass ``m_i`` with its inertia, friction ``F_s_i``, ``F_v_i``, ``input_gain``)
are appended to the finger's state as constants, theta' = 0 (the approach of STRIKE-GOLDD):

    z = [q; qd; theta] (2n + p),     z' = [qd; qdd(q, qd, B u; theta); 0],     y = h(q) (default S q).

The observability matrix of that augmented system (:class:`~alpes_dyn.analysis.observability_matrix.ObservabilityMatrix`:
Lie derivatives with the input derivatives u', u'', ... as free symbols, i.e. a time-varying motor
torque; report eq. 3.6, 3.14) is evaluated at ``points`` seeded random points: q within the joint
limits, qd in [-2, 2] rad/s, u and its derivatives within the model's torque scale (as
:func:`~alpes_dyn.analysis.observability.check_observability` samples them), theta at its nominal value. The
parameter columns are taken in log coordinates, d/d(log theta_j) = theta_j d/d theta_j, so that they are
unit-free and a null vector reads as relative changes. Rank and conditioning follow the conventions of
:mod:`alpes_dyn.analysis.observability`: rows scaled to unit norm, rank = generic (largest over the points)
numerical rank, the *normalised smallest singular value* s_(2n+p) / s_1 is the median over the points.

Parameters whose column of O vanishes at every point "do not appear in y". The other unidentifiable
directions are the right null vectors of O (at the point of largest rank) over the parameters, in log
coordinates, made sparse by a reduced row-echelon basis and named:

* two terms of equal size and sign, d log K_2 = d log m_2: only the ratio is identifiable, ``"K_2/m_2 only"``;
* two terms of equal size and opposite sign: only the product, ``"K_2·m_2 only"``;
* several terms all equal: a common scale, ``"common scale of input_gain, K_1, ...: only their ratios"``;
* otherwise the unit vector, ``"0.71·K_2 + 0.71·m_2 (log)"``.

Practical. For an experiment (motor torques U (N, m) held per sample period dt, gravity per period,
encoder noise, optional joint angles measured a few times by a camera or a jig),
:func:`~alpes_dyn.analysis.fisher.fisher_information` (module :mod:`~alpes_dyn.analysis.fisher`, its names importable from
here too) computes the output-error Fisher information matrix from the exact forward
sensitivities of the RK4-discretised model (:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel`):

    FIM = sum_k (dy_k/dphi)^T R^-1 (dy_k/dphi),     phi = (theta, x0),

with y_k the encoder angles S q_k (rad) at the N + 1 samples, R = sigma_e^2 I, sigma_e^2 =
(noise_counts * step)^2 + step^2 / 12 (Gaussian noise plus the quantisation of a step of 2 pi /
counts_per_rev), and the camera's joint angles q_k at ``camera_times`` with noise ``camera_noise`` (rad).
The unknown initial state is a nuisance: its block is marginalised (the Schur complement
F_tt - F_tx F_xx^-1 F_xt). The Cramér-Rao bound of an unbiased estimate is cov >= FIM^-1: each
parameter's standard deviation (absolute, and relative to its value) and the correlation matrix.
The measured torque is taken as exact (its noise is not in this FIM; see the identification guide).

One call each::

    from alpes_dyn.analysis.identifiability import identifiability, fisher_information
    rep = identifiability("finger3", parameters="K")   # rank 9/9, smallest normalised sv ~3e-4
    print(rep.to_text())
    fim = fisher_information(model, "K,m", U=tau_m, dt=1e-3)
    fim.std, fim.relative_std, fim.correlation
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import casadi as cs
import numpy as np

from ..errors import InputError, ModelError
from ..limits import MAX_POINTS
from ..model.robot import Model
from .fisher import INITIAL_STATES, FisherReport, _theta, fisher_information  # noqa: F401 (re-exported)
from .observability import _input_scale
from .observability_matrix import MAX_INSTRUCTIONS, ObservabilityMatrix, normalised_singular_values, numerical_rank
from ..symbolic.parametric import ParametricDynamics
from ..symbolic.statespace import StateSpace

__all__ = ["IdentifiabilityReport", "FisherReport", "identifiability", "fisher_information", "name_direction"]

_EPS = float(np.finfo(float).eps)
_SPEED = 2.0  # rad/s, bound of the sampled joint velocities (as observability)


# ----------------------------------------------------------------------------- the augmented system
class _AugmentedStateSpace(StateSpace):
    """z = [x; theta], z' = [f(x, u; theta); 0], y = h(x): what :class:`ObservabilityMatrix` reads of a
    :class:`StateSpace` (x, u, f_expr, h_expr, names, sizes), built from a base state space and the
    parametric dynamics (not the base's own f: the parameters must be symbols)."""

    def __init__(self, base: StateSpace, pd: ParametricDynamics, gravity: np.ndarray) -> None:  # noqa: D401
        n = base.n
        self.model = base.model
        self.n = n
        self.B = base.B
        self.input = base.input
        self.input_names = base.input_names
        self.force = False
        self.F = None
        self.force_names = ()
        self.contacts = ()
        self.u = base.u
        self.x = cs.vertcat(base.x, pd.theta)
        q, v = base.x[:n], base.x[n:]
        tau = (pd.input_torque(q, v, base.u, pd.theta) if base.input == "motor"  # the capstan's share taken off
               else cs.mtimes(cs.DM(base.B), base.u))
        qdd = pd.forward_dynamics(q, v, tau, pd.theta, cs.DM(gravity))
        self.f_expr = cs.vertcat(v, qdd, cs.SX.zeros(pd.p))
        self.h_expr = base.h_expr
        self.output_names = base.output_names
        self.output_name = base.output_name
        self.state_names = base.state_names + pd.names
        self._nz = 2 * n + pd.p

    @property
    def n_states(self) -> int:
        return self._nz

    @property
    def n_outputs(self) -> int:
        return int(self.h_expr.shape[0])


# ----------------------------------------------------------------------------- naming null directions
def _fmt(c: float) -> str:
    return f"{c:.2f}"


def name_direction(v: Sequence[float], names: Sequence[str], tol: float = 1e-6) -> str:
    """Text for an unidentifiable direction ``v`` over parameter ``names`` in log coordinates (see the
    module doc): ``"K_2/m_2 only"``, ``"K_2·m_2 only"``, ``"common scale of ...: only their ratios"``
    or ``"0.71·K_2 + 0.71·m_2 (log)"``.

    Parameters
    ----------
    v : sequence of float
        The direction, one component per parameter, in log coordinates.
    names : sequence of str
        The parameters' names.
    tol : float, optional
        Components below ``tol`` times the largest are left out (default 1e-6).

    Returns
    -------
    str
        The text.

    Raises
    ------
    InputError
        ``v`` not one finite component per name, or zero.
    """
    v = np.asarray(v, dtype=float).reshape(-1)
    if v.size != len(names):
        raise InputError(f"v: expected {len(names)} components (one per name), got {v.size}")
    if not np.isfinite(v).all() or not np.any(v):
        raise InputError("v: expected a finite, non-zero direction")
    big = np.abs(v).max()
    idx = [i for i in range(v.size) if abs(v[i]) > tol * big]
    u = v / np.linalg.norm(v[idx])
    if u[idx[0]] < 0:
        u = -u
    same = all(abs(abs(u[i]) - abs(u[idx[0]])) < 1e-3 * abs(u[idx[0]]) for i in idx)
    if len(idx) == 1:
        return f"{names[idx[0]]} (log)"
    if len(idx) == 2 and same:
        a, b = names[idx[0]], names[idx[1]]
        return f"{a}/{b} only" if u[idx[1]] > 0 else f"{a}·{b} only"
    if same and all(u[i] > 0 for i in idx):
        return f"common scale of {', '.join(names[i] for i in idx)}: only their ratios"
    terms = []
    for k, i in enumerate(idx):
        c = u[i]
        sign = "-" if c < 0 else ("+" if k else "")
        terms.append(f"{sign}{' ' if k else ''}{_fmt(abs(c))}·{names[i]}")
    return " ".join(terms).replace("+ ", "+ ").strip() + " (log)"


def _rref(A: np.ndarray, tol: float = 1e-9) -> np.ndarray:
    """Reduced row-echelon form of A (k, p) with partial pivoting: a sparse basis of its row space."""
    A = np.array(A, dtype=float)
    r = 0
    rows, cols = A.shape
    for c in range(cols):
        if r >= rows:
            break
        piv = r + int(np.argmax(np.abs(A[r:, c])))
        if abs(A[piv, c]) <= tol * max(1.0, np.abs(A).max()):
            continue
        A[[r, piv]] = A[[piv, r]]
        A[r] /= A[r, c]
        for i in range(rows):
            if i != r:
                A[i] -= A[i, c] * A[r]
        r += 1
    A[np.abs(A) < tol] = 0.0
    return A[:r]


# ----------------------------------------------------------------------------- structural report
@dataclass
class IdentifiabilityReport:
    """Result of :func:`identifiability`.

    Attributes
    ----------
    model: model name. parameters: parameter names (p); nominal (p,): the values used (their units).
    n_states: 2n (the finger's states); dimension: 2n + p (the augmented state).
    rank: generic rank of the augmented observability matrix; ranks_by_order: rank of O_0, O_1, ...
    order: highest output derivative built.
    min_singular_value: normalised smallest singular value (median over the points; 0 if rank-deficient).
    singular_values: (points, dimension) normalised singular values at each point.
    absent: parameters whose column of O is zero: they do not appear in y.
    null_directions: (p, k) unidentifiable directions over the parameters (log coordinates, sparse basis),
        the absent parameters excluded (they are listed in ``absent``).
    combinations: one text per column of ``null_directions`` (see :func:`name_direction`).
    state_in_null: whether some unidentifiable direction also moves the initial state.
    truncated: the next derivative order would exceed ``max_operations``: ``rank`` is a lower bound
        (the null directions are those of the orders built).
    settings: input, output, points, seed, gravity.
    """

    model: str
    parameters: tuple[str, ...]
    nominal: np.ndarray
    n_states: int
    dimension: int
    rank: int
    ranks_by_order: tuple[int, ...]
    order: int
    min_singular_value: float
    singular_values: np.ndarray
    absent: tuple[str, ...] = ()
    null_directions: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    combinations: tuple[str, ...] = ()
    state_in_null: bool = False
    truncated: bool = False
    seconds: float = 0.0
    settings: dict[str, Any] = field(default_factory=dict)

    @property
    def identifiable(self) -> bool:
        """Every parameter (and the initial state) structurally identifiable: rank = 2n + p."""
        return self.rank == self.dimension

    @property
    def condition(self) -> float:
        return 1.0 / self.min_singular_value if self.min_singular_value > 0 else float("inf")

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict (lists for arrays, None for an infinite condition)."""
        return {
            "model": self.model, "parameters": list(self.parameters), "nominal": self.nominal.tolist(),
            "n_states": self.n_states, "dimension": self.dimension, "rank": self.rank,
            "identifiable": self.identifiable, "min_singular_value": self.min_singular_value,
            "condition": self.condition if math.isfinite(self.condition) else None,
            "ranks_by_order": list(self.ranks_by_order), "order": self.order, "absent": list(self.absent),
            "null_directions": self.null_directions.T.tolist(), "combinations": list(self.combinations),
            "state_in_null": self.state_in_null, "truncated": self.truncated, "seconds": self.seconds, **self.settings,
        }

    def to_text(self) -> str:
        st = self.settings
        lines = [f"Structural identifiability of {', '.join(self.parameters)} on {self.model}: parameters as "
                 f"constant states, input {st.get('input')} (time-varying), output {st.get('output')}",
                 f"  rank {self.rank}/{self.dimension} (2n + p = {self.n_states} + {len(self.parameters)}), "
                 f"{'identifiable' if self.identifiable else ('undecided' if self.truncated else 'NOT identifiable')}; smallest normalised singular "
                 f"value {self.min_singular_value:.2e} (median over {st.get('points')} points, seed {st.get('seed')})",
                 "  rank by derivative order: " + " ".join(str(r) for r in self.ranks_by_order)]
        for a in self.absent:
            lines.append(f"  {a}: does not appear in y")
        for c in self.combinations:
            lines.append(f"  unidentifiable: {c}")
        if self.state_in_null:
            lines.append("  (some unidentifiable direction also moves the initial state)")
        if self.truncated:
            lines.append(f"  rank is a lower bound: y^({self.order + 1}) would exceed max_operations "
                         f"({self.settings.get('max_operations')} CasADi operations)")
        lines.append(f"  {self.seconds:.2f} s")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()


def _check_int(value: Any, name: str, low: int, high: int | None = None) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < low \
            or (high is not None and value > high):
        want = f"an integer >= {low}" if high is None else f"an integer from {low} to {high}"
        raise InputError(f"{name}: expected {want}, got {value!r}")
    return int(value)


def identifiability(system: Model | str, parameters: str | Sequence[str] | None = None, output: Any = "encoder", *,
                    input: str | None = None, points: int = 8, seed: int = 0, theta: Any = None,
                    order: int | None = None, friction: bool | None = None,
                    max_operations: int = MAX_INSTRUCTIONS, coordinates: str = "log") -> IdentifiabilityReport:
    """Structural identifiability of physical parameters (see the module doc).

    Parameters
    ----------
    system : Model or str
        A :class:`~alpes_dyn.Model` or an Alpes model name (built with ``friction``).
    parameters : str, sequence of str or None, optional
        The selection for :func:`~alpes_dyn.symbolic.parametric.select_parameters` (``"K"``, ``"K,m"``,
        ``["K_1", "m_2"]``...; default K, m and friction where the model has it).
    output : str or array_like, optional
        The measured output, as for :class:`~alpes_dyn.StateSpace` (default ``"encoder"``: S q, the motor
        encoder; ``"sum"``, ``"joints"``, a matrix...).
    input : str or None, optional
        ``"motor"`` (default when the model has a transmission) or ``"joint"``.
    points : int, optional
        The random points of the generic rank, 1 to 10000 (default 8).
    seed : int, optional
        The points' seed (default 0).
    theta : array_like, shape (p,), optional
        The parameter values where O is evaluated (default the nominal ones; positive).
    order : int or None, optional
        The highest output derivative (default: up to 2n + p - 1, stopping at full rank or when the rank stops
        growing, as ``order="auto"`` of :func:`~alpes_dyn.analysis.observability.check_observability`).
    friction : bool or None, optional
        For a model name, build it with friction (default: when ``parameters`` names F_s, F_v or friction). The
        smooth Coulomb sign tanh(qd / v_s) makes the high output derivatives large and the normalised singular
        values small (finger3, K: ~5e-7 with friction, ~1e-3 without).
    max_operations : int, optional
        The size cap of one derivative order's function, CasADi operations.
    coordinates : str, optional
        ``"log"`` (default: parameter columns d/d log theta, unit-free) or ``"absolute"`` (d/d theta in the
        parameters' units; changes the singular values, not the rank).

    Returns
    -------
    IdentifiabilityReport
        The rank, the absent parameters and the unidentifiable directions named.

    Raises
    ------
    InputError
        ``points``, ``seed``, ``order`` or ``coordinates`` out of range.
    """
    t0 = time.perf_counter()
    points = _check_int(points, "points", 1, MAX_POINTS)
    seed = _check_int(seed, "seed", 0)
    if coordinates not in ("log", "absolute"):
        raise InputError(f"coordinates: expected 'log' or 'absolute', got {coordinates!r}")
    model = _model_of(system, parameters, friction)
    if input is None:
        input = "motor" if model.transmission is not None else "joint"
    base, pd, aug, th, additive = _augmented_system(model, parameters, input, output, theta)
    unit = np.where(additive, 1.0, th)  # d/d log theta = theta d/d theta; the additive ones as they are
    nz = aug.n_states
    n2 = base.n_states
    kmax = nz - 1 if order is None else _check_int(order, "order", 0)
    om = ObservabilityMatrix(aug, False, max_operations)
    colscale = np.concatenate([np.ones(n2), unit if coordinates == "log" else np.ones(pd.p)])
    blocks, ranks, truncated = _observability_blocks(om, model, base, th, colscale, points, seed, kmax, order)
    O = np.concatenate(blocks, axis=1)  # (points, rows, nz)
    rs = _row_scale(O)
    s = normalised_singular_values(O, rs)
    rank = ranks[-1]
    smin = float(np.median(s[:, nz - 1]))
    On, absent_idx = _absent_parameters(O, rs, n2, pd.p, truncated)
    null, combos, state_in_null = _null_directions(O, On, rs, absent_idx, n2, pd.names, unit, coordinates, truncated)
    return IdentifiabilityReport(
        model=model.name, parameters=pd.names, nominal=th, n_states=n2, dimension=nz, rank=rank,
        ranks_by_order=tuple(ranks), order=len(blocks) - 1, min_singular_value=smin if rank == nz else 0.0,
        singular_values=s, absent=tuple(pd.names[j] for j in absent_idx), null_directions=null,
        combinations=tuple(combos), state_in_null=state_in_null, truncated=truncated, seconds=time.perf_counter() - t0,
        settings={"input": input, "output": base.output_name, "points": points, "seed": seed,
                  "max_operations": om.max_operations, "coordinates": coordinates, "friction": bool(model.extras.has_friction),
                  "gravity": np.asarray(model.gravity, dtype=float).tolist()})


def _model_of(system: Model | str, parameters: Any, friction: bool | None) -> Model:
    """The model of :func:`identifiability`: ``system``, or the Alpes model of that name (with friction where asked,
    by default where ``parameters`` names it)."""
    if isinstance(system, str):
        if friction is None:
            spec = parameters if isinstance(parameters, str) else ",".join(map(str, parameters or ()))
            friction = any(k in spec for k in ("F_s", "F_v", "friction"))
        system = Model.alpes(system, friction=bool(friction))
    elif friction is not None:
        raise ModelError("friction: only with a model name; a Model has its friction already")
    if not isinstance(system, Model):
        raise ModelError(f"system: expected a Model or an Alpes model name, got {type(system).__name__}")
    return system


def _augmented_system(model: Model, parameters: Any, input: str, output: Any, theta: Any
                      ) -> tuple[StateSpace, ParametricDynamics, _AugmentedStateSpace, np.ndarray, np.ndarray]:
    """(base state space, parametric dynamics, the augmented system z = [x; theta], theta (p,), additive (p,) bool):
    the encoder offsets added to y = h(x); the tendon compliance (a feedthrough of the torque) refused."""
    base = StateSpace(model, input=input, output=output)
    pd = ParametricDynamics(model, parameters)
    additive = np.array([prm.additive for prm in pd.parameters], dtype=bool)
    th = _theta(theta, pd.nominal, pd.names, additive)
    aug = _AugmentedStateSpace(base, pd, np.asarray(model.gravity, dtype=float))
    if pd._sel["tendon_compliance"]:
        raise ModelError("parameters: tendon_compliance is a feedthrough of the torque to the encoder (y = S q + C "
                         "tau_m), outside this test's y = h(x); ask fisher_information on an experiment instead")
    if pd._sel["encoder_offset"]:  # y = S q + offset
        if base.output_name != "encoder":
            raise ModelError(f"parameters: encoder_offset applies to the encoder output, not {base.output_name!r}")
        aug.h_expr = aug.h_expr + pd.encoder_offset(pd.theta)
    return base, pd, aug, th, additive


def _observability_blocks(om: ObservabilityMatrix, model: Model, base: StateSpace, th: np.ndarray,
                          colscale: np.ndarray, points: int, seed: int, kmax: int, order: int | None
                          ) -> tuple[list[np.ndarray], list[int], bool]:
    """The blocks O_0, O_1, ... (each (points, rows, 2n + p), columns scaled by ``colscale``) at ``points`` seeded
    random states and inputs, up to order ``kmax`` or (``order`` None) full rank or a rank that stops growing; the
    rank after each; whether the next order was over ``max_operations`` (the rank a lower bound)."""
    nz = om.n_states
    rng = np.random.default_rng(seed)
    q, v = model.random_state(rng, _SPEED, size=points)
    scale = _input_scale(base, q)
    W = rng.uniform(-1.0, 1.0, size=(points, max(kmax, 1) * scale.size)) * np.tile(scale, max(kmax, 1))
    Z = np.hstack([q, v, np.tile(th, (points, 1))])
    blocks: list[np.ndarray] = []
    ranks: list[int] = []
    truncated = False
    for k in range(kmax + 1):
        try:
            om.block(k)
        except InputError:
            if order is not None or k == 0:
                raise
            truncated = True  # the next order is over max_operations: the rank found is a lower bound
            break
        b = om._eval_block(k, Z, W) * colscale
        if not np.isfinite(b).all():
            raise InputError(f"identifiability: O is not finite at derivative order {k} (model too stiff?)")
        blocks.append(b)
        O = np.concatenate(blocks, axis=1)
        ranks.append(int(np.max(numerical_rank(O, _row_scale(O)))))
        if ranks[-1] == nz:
            break
        if order is None and k > 0 and ranks[-1] == ranks[-2]:
            break
    return blocks, ranks, truncated


def _absent_parameters(O: np.ndarray, rs: np.ndarray, n2: int, p: int, truncated: bool
                       ) -> tuple[np.ndarray, list[int]]:
    """(O with its rows normalised (points, rows, nz), the indices of the parameters absent from y: a zero column
    of that O at every point; none when ``truncated``)."""
    nrm = np.linalg.norm(O, axis=2, keepdims=True)
    floor = max(O.shape[1:]) * _EPS * rs[None, :, None]
    On = np.divide(O, nrm, out=np.zeros_like(O), where=nrm > floor)
    colmax = np.linalg.norm(On, axis=1).max(axis=0)  # (nz,)
    tol = max(O.shape[1:]) * _EPS * 1e3
    absent_idx = [] if truncated else [j for j in range(p) if colmax[n2 + j] <= tol * max(colmax.max(), 1e-300)]
    return On, absent_idx


def _null_directions(O: np.ndarray, On: np.ndarray, rs: np.ndarray, absent_idx: list[int], n2: int,
                     names: Sequence[str], unit: np.ndarray, coordinates: str, truncated: bool
                     ) -> tuple[np.ndarray, list[str], bool]:
    """The unidentifiable directions over the parameters (p, k) (log coordinates, a sparse reduced row-echelon
    basis, unit columns; the absent parameters left out), their names, and whether one moves the initial state:
    the right null space of the row-normalised O at the point of largest rank."""
    p = len(names)
    nz = O.shape[2]
    keep = np.array([j for j in range(nz) if j < n2 or (j - n2) not in absent_idx], dtype=int)
    null = np.zeros((p, 0))
    combos: list[str] = []
    state_in_null = False
    best = int(np.argmax(numerical_rank(O, rs)))
    A = On[best][:, keep]
    r_keep = int(numerical_rank(A))
    if r_keep < keep.size and not truncated:  # (a truncated O's null space holds undecided directions too)
        _, _, Vt = np.linalg.svd(A)
        N = Vt[r_keep:].T  # (len(keep), k)
        state_in_null = bool(np.any(np.abs(N[: n2]) > 1e-6))
        Np = np.zeros((p, N.shape[1]))
        Np[[j - n2 for j in keep if j >= n2]] = N[n2:]
        if coordinates == "absolute":
            Np = Np / unit[:, None]  # d log theta = d theta / theta
        R = _rref(Np.T, 1e-6)
        null = (R / np.linalg.norm(R, axis=1, keepdims=True)).T if R.size else np.zeros((p, 0))
        combos = [name_direction(null[:, i], names) for i in range(null.shape[1])]
    return null, combos, state_in_null


def _row_scale(O: np.ndarray) -> np.ndarray:
    """Largest norm of each row over the points."""
    return np.linalg.norm(O, axis=-1).max(axis=0)

