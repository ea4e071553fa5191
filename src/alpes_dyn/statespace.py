"""State-space form of the dynamics (report eq. 3.1-3.3, 3.11, 3.16).

x = [q; qd] (2n), xdot = f(x, u[, F]) = [qd; qdd(q, qd, B u, F)], y = h(x).

Inputs (``input=``):

* ``"joint"`` -- u = Gamma, the joint torques (n), the report's choice;
* ``"motor"`` -- u = tau_m, the motor torques (m), acting through the tendon transmission
  Gamma = S^T tau_m (:class:`~alpes_dyn.Transmission`).

The measured contact force F (eq. 2.9, 2.13: a 3-vector at the model's first tip, base frame) is an
optional known input (``force=True``).

Outputs (``output=``):

* ``"sum"`` -- y = q_1 + ... + q_k per tendon chain (the report's), plus the thumb's ab/adduction angle;
* ``"encoder"`` -- q_m = (r/r_m) sum q per motor (Section 3);
* a (p, n) array -- y = H q;
* a callable ``g(q, xp)`` returning y for q as a numpy array (``xp=numpy``) and as a CasADi SX column
  (``xp=casadi``).

f and h exist both numerically (Pinocchio ABA, :meth:`StateSpace.f`) and symbolically (CasADi SX,
:attr:`StateSpace.f_expr`), from the same URDF and the same extras.
"""

from __future__ import annotations

from typing import Any, Callable

import casadi as cs
import numpy as np

from .errors import InputError, ModelError
from .model import Model
from .symbolic import SymbolicDynamics

__all__ = ["StateSpace", "INPUTS", "OUTPUTS"]

INPUTS = ("joint", "motor")
OUTPUTS = ("sum", "encoder")


def _output_matrix(output: Any, n: int) -> np.ndarray:
    """An output matrix H (p, n) of finite numbers, else a ModelError saying what is wrong."""
    try:
        H = np.atleast_2d(np.asarray(output, dtype=float))
    except (TypeError, ValueError):
        raise ModelError(f"output matrix: expected a (p, {n}) array of numbers, got {output!r}") from None
    if H.ndim != 2 or H.shape[1] != n or H.shape[0] < 1:
        raise ModelError(f"output matrix: expected a finite (p, {n}) array, got shape {H.shape}")
    if not np.isfinite(H).all():
        raise ModelError("output matrix: contains NaN or inf")
    return H


def _output_expression(y: Any) -> cs.SX:
    """The column of what an output callable returned for a CasADi symbol (SX, numbers or a list of them)."""
    items = list(y) if isinstance(y, (list, tuple)) else [y]
    try:
        if not items or any(v is None or isinstance(v, (str, bytes)) for v in items):
            raise TypeError
        return cs.vec(cs.vertcat(*[cs.vec(cs.SX(v)) for v in items]))
    except (TypeError, NotImplementedError, RuntimeError, ValueError):
        raise ModelError(f"output function: returned {type(y).__name__} {y!r:.60}, expected CasADi expressions "
                         "or numbers") from None


class StateSpace:
    """x' = f(x, u[, F]), y = h(x) for a :class:`~alpes_dyn.Model`.

    Parameters
    ----------
    model: the dynamics.
    input: ``"joint"`` or ``"motor"``.
    output: ``"sum"``, ``"encoder"``, a (p, n) matrix or a callable ``g(q, xp)``.
    force: add the contact force F (3,) at ``tip`` as a known input.
    tip: tip frame of F (default: the model's first tip).
    smooth: use tanh for the Coulomb sign (default True: f is differentiable).
    backend: symbolic backend, see :class:`~alpes_dyn.symbolic.SymbolicDynamics`.

    Attributes
    ----------
    n_states, n_inputs, n_outputs: 2n, m, p.
    B: (n, m) input matrix, Gamma = B u.
    x, u, F: CasADi SX symbols; f_expr (2n,), h_expr (p,): SX expressions of them.
    f_function, h_function: ``casadi.Function`` f(x, u[, F]) and h(x).
    """

    def __init__(self, model: Model, input: str = "joint", output: str | np.ndarray | Callable[..., Any] = "sum",
                 force: bool = False, tip: str | None = None, smooth: bool = True, backend: str = "auto") -> None:
        self.model = model
        n = model.n
        self.n = n
        if input not in INPUTS:
            raise ModelError(f"unknown input {input!r} (expected one of {', '.join(INPUTS)})")
        tr = model.transmission
        if input == "motor":
            if tr is None:
                raise ModelError(f"input 'motor' needs a tendon transmission; model {model.name!r} has none")
            self.B = tr.actuation_matrix.copy()
            self.input_names = tuple(f"tau_m_{m}" for m in tr.motor_names)
        else:
            self.B = np.eye(n)
            self.input_names = tuple(f"tau_{j}" for j in model.joint_names)
        self.input = input
        self.output_name: str
        self._g: Callable[[Any, Any], Any] | None = None
        if isinstance(output, str):
            if output not in OUTPUTS:
                raise ModelError(f"unknown output {output!r} (expected one of {', '.join(OUTPUTS)}, a matrix or a callable)")
            if tr is None:
                raise ModelError(f"output {output!r} needs a tendon transmission; model {model.name!r} has none")
            self.H: np.ndarray | None = (tr.sum_matrix if output == "sum" else tr.S).copy()
            self.output_names = tuple(f"{'sum' if output == 'sum' else 'q_m'}_{m}" for m in tr.motor_names)
            self.output_name = output
        elif callable(output):
            self.H = None
            self._g = output
            self.output_name = getattr(output, "__name__", "custom")
        else:
            H = _output_matrix(output, n)
            self.H = H
            self.output_names = tuple(f"y{i}" for i in range(H.shape[0]))
            self.output_name = "matrix"
        self.force = bool(force)
        self.tip = tip if tip is not None else (model.tips[0] if model.tips else None)
        if self.force:
            model.frame_id(self.tip)
        self.smooth = smooth
        self.state_names = tuple(f"q_{j}" for j in model.joint_names) + tuple(f"qd_{j}" for j in model.joint_names)

        # symbolic f and h (eq. 3.3)
        self.sym = SymbolicDynamics(model, backend)
        self.x = cs.SX.sym("x", 2 * n)
        self.u = cs.SX.sym("u", self.B.shape[1])
        self.F = cs.SX.sym("F", 3) if self.force else None
        q, v = self.x[:n], self.x[n:]
        tau = cs.mtimes(cs.DM(self.B), self.u)
        qdd = self.sym.forward_dynamics(q, v, tau, self.F, self.tip, smooth)
        self.f_expr: cs.SX = cs.vertcat(v, qdd)
        self.h_expr: cs.SX = self._h_sym(q)
        if self._g is not None:
            self.output_names = tuple(f"y{i}" for i in range(self.h_expr.shape[0]))
        ins = [self.x, self.u] + ([self.F] if self.force else [])
        names = ["x", "u"] + (["F"] if self.force else [])
        self.f_function = cs.Function("f", ins, [self.f_expr], names, ["xdot"])
        self.h_function = cs.Function("h", [self.x], [self.h_expr], ["x"], ["y"])

    # ---------------------------------------------------------------- sizes
    @property
    def n_states(self) -> int:
        return 2 * self.n

    @property
    def n_inputs(self) -> int:
        return int(self.B.shape[1])

    @property
    def n_outputs(self) -> int:
        return int(self.h_expr.shape[0])

    def __repr__(self) -> str:
        return (f"StateSpace({self.model.name!r}, states={self.n_states}, input={self.input!r} ({self.n_inputs}), "
                f"output={self.output_name!r} ({self.n_outputs}), force={self.force})")

    # ---------------------------------------------------------------- output map
    def _h_sym(self, q: cs.SX) -> cs.SX:
        if self._g is None:
            return cs.mtimes(cs.DM(self.H), q)
        try:
            y = self._g(q, cs)
        except Exception as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise ModelError(f"output function failed on a CasADi symbol: {first}") from None
        return _output_expression(y)

    # ---------------------------------------------------------------- numeric f, h
    def _check_x(self, x: Any) -> np.ndarray:
        return self.model.vector(x, "x", 2 * self.n)

    def f(self, x: np.ndarray, u: np.ndarray, F: np.ndarray | None = None) -> np.ndarray:
        """xdot = f(x, u[, F]) (2n,), numerically with Pinocchio's ABA (eq. 3.3)."""
        x = self._check_x(x)
        u = self.model.vector(u, "u", self.n_inputs)
        if self.force and F is None:
            raise InputError("F: this state space has the contact force as an input; pass F (3,)")
        n = self.n
        qdd = self.model.forward_dynamics(x[:n], x[n:], self.B @ u, F if self.force else None, self.tip, self.smooth)
        return np.concatenate([x[n:], qdd])

    def h(self, x: np.ndarray) -> np.ndarray:
        """y = h(x) (p,), numerically."""
        x = self._check_x(x)
        q = x[: self.n]
        if self._g is None:
            return self.H @ q
        try:
            y = np.asarray(self._g(q, np), dtype=float).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ModelError(f"output function: expected numbers for a numeric q ({exc})") from None
        if y.shape != (self.n_outputs,):
            raise ModelError(f"output function: returned {y.size} values for a numeric q, {self.n_outputs} symbolically")
        return y
