"""The observability matrix O_k = d(y, y', ..., y^(k))/dx of a state space, and its numerical rank (report
Chapter 3, eq. 3.6, 3.14).

:class:`ObservabilityMatrix` builds O_k order by order by automatic differentiation on CasADi SX: the output
derivatives are Lie derivatives along the extended vector field of z = (x, u, u', u'', ...),

    d/dt phi(x, u, ..., u^(j-1)) = dphi/dx f(x, u) + sum_i dphi/du^(i) u^(i+1),

with the input derivatives free symbols (time-varying inputs; ``constant_input=True``: zero), and evaluates them
at many points at once (one compiled ``casadi.Function`` per derivative order, ``.map`` over the points). An
order whose function would exceed ``max_operations`` CasADi operations (default :data:`MAX_INSTRUCTIONS`) raises
:class:`~alpes_dyn.InputError` naming the order.

:func:`normalised_singular_values` and :func:`numerical_rank` are the rank at one point: each row scaled to unit
norm, singular values above max(rows, cols) * eps times the largest.

The rank test that uses them (random points, the stop rule, the report, the parts of a tree) is
:mod:`alpes_dyn.analysis.observability`, which re-exports these names; so is the structural identifiability
test (:mod:`alpes_dyn.analysis.identifiability`).
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from ..errors import InputError, ModelError
from ..limits import MAX_OPERATIONS, MAX_ORDER
from ..symbolic.statespace import StateSpace

__all__ = ["ObservabilityMatrix", "MAX_INSTRUCTIONS", "normalised_singular_values", "numerical_rank"]

_EPS = float(np.finfo(float).eps)
MAX_INSTRUCTIONS = 2_000_000
"""Default size cap (CasADi operations) of one derivative order's function; each order costs ~3x the last."""


# ----------------------------------------------------------------------------- numerical rank
def normalised_singular_values(O: np.ndarray, row_scale: np.ndarray | None = None) -> np.ndarray:
    """Singular values of the row-normalised O divided by the largest, zero-padded to the column count.

    Each row is scaled to unit norm; zero rows stay zero, and so do rows whose norm is at most
    max(r, c) * eps * ``row_scale``.

    Parameters
    ----------
    O : numpy.ndarray, shape (..., r, c)
        The matrix (or a stack of them).
    row_scale : numpy.ndarray, shape (r,), or None, optional
        Each row's scale, e.g. the row's largest norm over generic points, so that rounding noise in a row that
        vanishes at a special point is not blown up to a unit row (default None: only zero rows stay zero).

    Returns
    -------
    numpy.ndarray, shape (..., c)
        Decreasing, the first entry 1 (0 if O is zero). The last entry is the normalised smallest singular value
        s_c / s_1 (0 when r < c).

    Raises
    ------
    InputError
        ``O`` not a matrix, or not finite.
    """
    O = np.asarray(O, dtype=float)
    if O.ndim < 2:
        raise InputError(f"O: expected a matrix (..., rows, cols), got shape {O.shape}")
    if not np.isfinite(O).all():
        raise InputError("O: contains NaN or inf (state or inputs too large?)")
    r, c = O.shape[-2:]
    norms = np.linalg.norm(O, axis=-1, keepdims=True)
    floor = 0.0 if row_scale is None else max(r, c) * _EPS * np.asarray(row_scale, dtype=float)[:, None]
    On = np.divide(O, norms, out=np.zeros_like(O), where=norms > floor)
    s = np.linalg.svd(On, compute_uv=False) if min(r, c) > 0 else np.zeros(O.shape[:-2] + (0,))
    smax = s[..., :1] if s.shape[-1] else np.zeros(O.shape[:-2] + (1,))
    s = np.divide(s, smax, out=np.zeros_like(s), where=smax > 0)
    if s.shape[-1] < c:
        s = np.concatenate([s, np.zeros(s.shape[:-1] + (c - s.shape[-1],))], axis=-1)
    return s


def numerical_rank(O: np.ndarray, row_scale: np.ndarray | None = None) -> np.ndarray | int:
    """Rank of O (..., r, c): singular values of the row-normalised O above max(r, c) * eps * s_1
    (``row_scale``: see :func:`normalised_singular_values`).

    Parameters
    ----------
    O : numpy.ndarray, shape (..., r, c)
        The matrix (or a stack of them).
    row_scale : numpy.ndarray, shape (r,), or None, optional
        Each row's scale (see :func:`normalised_singular_values`; default None).

    Returns
    -------
    int or numpy.ndarray of int, shape (...)
        The rank.
    """
    O = np.asarray(O, dtype=float)
    s = normalised_singular_values(O, row_scale)
    tol = max(O.shape[-2:]) * _EPS
    rank = np.sum(s > tol, axis=-1)
    return int(rank) if rank.ndim == 0 else rank


# ----------------------------------------------------------------------------- the matrix
class ObservabilityMatrix:
    """O_k = d(y, y', ..., y^(k))/dx of a :class:`StateSpace`, built order by order (eq. 3.6, 3.14).

    Parameters
    ----------
    ss : StateSpace
        The state space x' = f(x, u[, F]), y = h(x). With ``force=True`` the contact force F is a known input
        like u (w below holds [u; F] and its derivatives).
    constant_input : bool, optional
        u' = u'' = ... = 0 (default False: the input derivatives are free symbols).
    max_operations : int, optional
        The size cap of one derivative order's function (CasADi operations, default :data:`MAX_INSTRUCTIONS`);
        an order estimated above it raises :class:`~alpes_dyn.InputError`.

    Raises
    ------
    ModelError
        ``ss`` is not a StateSpace.

    Notes
    -----
    Every function of order k takes ``(x, w)``: x (n_states,) and w = [v; v'; ...; v^(K-1)] with
    v = [u; F], K = max(k, 1) (time-varying input) or w = v (constant input); see :meth:`w_size`.
    Rows are ordered by derivative order: the p outputs' y, then their y', ... (eq. 3.14).
    """

    def __init__(self, ss: StateSpace, constant_input: bool = False, max_operations: int = MAX_INSTRUCTIONS) -> None:
        if not isinstance(ss, StateSpace):
            raise ModelError(f"ObservabilityMatrix: expected a StateSpace, got {type(ss).__name__}")
        self.max_operations = _max_operations(max_operations)
        self.ss = ss
        self.constant_input = bool(constant_input)
        self.x: cs.SX = ss.x
        v = cs.vertcat(ss.u, ss.F) if ss.force else ss.u
        self.n_states = ss.n_states
        self.n_outputs = ss.n_outputs
        self.m = int(v.shape[0])  # known inputs (u and, with force=True, F)
        self.input_names = tuple(ss.input_names) + tuple(ss.force_names)
        self._V: list[cs.SX] = [v]  # v, v', v'', ... symbols
        self._phi: list[cs.SX] = [ss.h_expr]  # y, y', ... as SX
        self._blocks: list[cs.Function] = []
        self._maps: dict[tuple[int, int], cs.Function] = {}

    # -------------------------------------------------------------- symbols
    def w_size(self, order: int) -> int:
        """Length of the input vector w of a function of this order (see the class doc).

        Parameters
        ----------
        order : int
            The highest output derivative k, >= 0.

        Returns
        -------
        int
        """
        return self.m if self.constant_input else self.m * max(int(order), 1)

    def _v(self, j: int) -> cs.SX:
        while len(self._V) <= j:
            self._V.append(cs.SX.sym(f"v{len(self._V)}", self.m))
        return self._V[j]

    def _w(self, order: int) -> cs.SX:
        if self.constant_input:
            return self._V[0]
        return cs.vertcat(*(self._v(j) for j in range(max(order, 1))))

    def lie_derivative(self, k: int) -> cs.SX:
        """y^(k) (p,) as an SX expression of x and w (k >= 0).

        Parameters
        ----------
        k : int
            The derivative's order, >= 0.

        Returns
        -------
        casadi.SX, shape (p,)
        """
        k = _order(k)
        f = self.ss.f_expr
        while len(self._phi) <= k:
            j = len(self._phi) - 1  # phi_j = y^(j) depends on x and v..v^(j-1)
            phi = self._phi[j]
            if self.constant_input or j == 0:
                nxt = cs.jtimes(phi, self.x, f)
            else:
                z = cs.vertcat(self.x, *(self._v(i) for i in range(j)))
                zd = cs.vertcat(f, *(self._v(i + 1) for i in range(j)))
                nxt = cs.jtimes(phi, z, zd)
            self._phi.append(nxt)
        return self._phi[k]

    def expression(self, order: int) -> cs.SX:
        """O_order (p (order + 1), n_states) as SX of x and w.

        Parameters
        ----------
        order : int
            The highest output derivative k, >= 0.

        Returns
        -------
        casadi.SX, shape (p (order + 1), n_states)
        """
        order = _order(order)
        return cs.jacobian(cs.vertcat(*(self.lie_derivative(k) for k in range(order + 1))), self.x)

    def function(self, order: int) -> cs.Function:
        """``casadi.Function`` O(x, w) -> O_order, (p (order + 1), n_states).

        Parameters
        ----------
        order : int
            The highest output derivative k, >= 0.

        Returns
        -------
        casadi.Function
        """
        order = _order(order)
        return cs.Function(f"O{order}", [self.x, self._w(order)], [self.expression(order)], ["x", "w"], ["O"])

    def block(self, k: int) -> cs.Function:
        """``casadi.Function`` (x, w) -> d y^(k) / dx, (p, n_states), w of :meth:`w_size` (k).

        Parameters
        ----------
        k : int
            The derivative's order, >= 0.

        Returns
        -------
        casadi.Function

        Raises
        ------
        InputError
            The order's function would exceed ``max_operations``.
        """
        k = _order(k)
        while len(self._blocks) <= k:
            j = len(self._blocks)
            need = 3 * self._blocks[-1].n_instructions() if j >= 3 else 0  # ~3x per order
            if need > self.max_operations:
                raise InputError(f"max_operations: d y^({j})/dx would need about {need} operations, more than "
                                 f"max_operations={self.max_operations} (raise it, or --max-operations on the "
                                 f"command line; time and memory grow with it)")
            J = cs.jacobian(self.lie_derivative(j), self.x)
            self._blocks.append(cs.Function(f"dy{j}", [self.x, self._w(j)], [J], ["x", "w"], ["dy"]))
        return self._blocks[k]

    # -------------------------------------------------------------- numbers
    def _points(self, X: Any, W: Any, order: int) -> tuple[np.ndarray, np.ndarray]:
        X = np.asarray(X, dtype=float)
        W = np.asarray(W, dtype=float)
        single = X.ndim == 1
        X2, W2 = np.atleast_2d(X), np.atleast_2d(W)
        if X2.ndim != 2 or X2.shape[1] != self.n_states:
            raise InputError(f"x: expected shape ({self.n_states},) or (N, {self.n_states}), got {X.shape}")
        need = self.w_size(order)
        if W2.ndim != 2 or W2.shape[1] < need or W2.shape[0] != X2.shape[0] or (single and W.ndim != 1):
            raise InputError(f"w: expected shape ({need},) or (N, {need}) with N = {X2.shape[0]} "
                             f"(inputs and their derivatives), got {W.shape}")
        for a, name in ((X2, "x"), (W2, "w")):
            if not np.isfinite(a).all():
                raise InputError(f"{name}: contains NaN or inf")
        return X2, W2

    def _eval_block(self, k: int, X: np.ndarray, W: np.ndarray) -> np.ndarray:
        N = X.shape[0]
        key = (k, N)
        if key not in self._maps:
            self._maps[key] = self.block(k).map(N)
        out = np.asarray(self._maps[key](X.T, W[:, : self.w_size(k)].T))
        p, n = self.n_outputs, self.n_states
        return out.reshape(p, N, n).transpose(1, 0, 2)

    def evaluate(self, order: int, x: Any, w: Any) -> np.ndarray:
        """O_order at one point (x (n_states,), w (w_size,)) -> (rows, n_states), or at N points
        (x (N, n_states), w (N, >= w_size)) -> (N, rows, n_states).

        Parameters
        ----------
        order : int
            The highest output derivative k, >= 0.
        x : array_like, shape (n_states,) or (N, n_states)
            The state(s) [q; qd], rad and rad/s.
        w : array_like, shape (w_size,) or (N, >= w_size)
            The known inputs and their derivatives (:meth:`w_size`).

        Returns
        -------
        numpy.ndarray, shape (rows, n_states) or (N, rows, n_states)

        Raises
        ------
        InputError
            ``x`` or ``w`` of the wrong shape, or not finite.
        """
        order = _order(order)
        single = np.asarray(x).ndim == 1
        X, W = self._points(x, w, order)
        O = np.concatenate([self._eval_block(k, X, W) for k in range(order + 1)], axis=1)
        return O[0] if single else O

    def rank_at(self, order: int, x: Any, w: Any | None = None) -> int:
        """Numerical rank of O_order at one point (w default zeros: u and its derivatives 0).

        Parameters
        ----------
        order : int
            The highest output derivative k, >= 0.
        x : array_like, shape (n_states,)
            The state [q; qd], rad and rad/s.
        w : array_like, shape (w_size,), or None, optional
            The known inputs and their derivatives (default zeros).

        Returns
        -------
        int
        """
        w = np.zeros(self.w_size(order)) if w is None else w
        return int(numerical_rank(self.evaluate(order, x, w)))


def _max_operations(cap: Any) -> int:
    if isinstance(cap, (bool, np.bool_)) or not isinstance(cap, (int, np.integer)) or cap < 1:
        raise InputError(f"max_operations: expected a positive integer, got {cap!r}")
    if cap > MAX_OPERATIONS:
        raise InputError(f"max_operations: {cap} is over the limit of {MAX_OPERATIONS} CasADi operations")
    return int(cap)


def _order(k: Any) -> int:
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, (int, np.integer)) or k < 0:
        raise InputError(f"order: expected a non-negative integer, got {k!r}")
    if k > MAX_ORDER:
        raise InputError(f"order: {int(k)} is over the limit of {MAX_ORDER}")
    return int(k)
