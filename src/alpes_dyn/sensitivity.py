"""Trajectories and their sensitivities to the initial state and the physical parameters, in compiled C.

For x' = f(x, Gamma; theta, g) (:class:`~alpes_dyn.parametric.ParametricDynamics`, eq. 2.10, 3.3)
discretised by ``substeps`` classical RK4 steps per sample period (the input held over the period,
as the estimation scenario and the observers do), the augmented step

    x_{k+1} = F(x_k, w_k; theta),     X_{k+1} = F_x X_k + [0 | F_theta],     X_0 = [I | 0],

propagates X = dx/d(x_0, theta) (2n x (2n + p)) with the state (with ``input_offset=True`` also the
derivative with respect to a constant correction of the input over the segment): forward sensitivities by CasADi's
automatic differentiation of the step, so the Jacobians are exact for the discretised model. The
step is compiled once by :class:`~alpes_dyn.simulation.CompiledStepLoop` (cached on disk, keyed by
the model's structure and the parameter selection: the parameter *values* are inputs) and runs many
segments at once on threads: the multiple-shooting intervals of a fit, or the designs of a Fisher
information study.
"""

from __future__ import annotations

from typing import Sequence

import casadi as cs
import numpy as np

from .errors import InputError
from .model import Model
from .parametric import ParametricDynamics
from .simulation import CompiledStepLoop, _check_dt, rk4_expression

__all__ = ["SensitivityModel"]


class SensitivityModel:
    """Batched simulation with sensitivities of a model with symbolic parameters.

    Parameters
    ----------
    model: the model (motor input through its transmission if it has one, else joint torques).
    parameters: selection for :func:`~alpes_dyn.parametric.select_parameters`.
    dt: sample period, s. substeps: RK4 steps per sample (default 4: the smooth friction is fast).
    threads: worker threads of the compiled loop.

    Attributes
    ----------
    dynamics: the :class:`~alpes_dyn.parametric.ParametricDynamics`; names, nominal (p,): parameters.
    nx = 2n, p, nu (inputs: motors or joints), nd = nx + p (sensitivity directions).
    compile_seconds: time spent compiling now (0 when the library came from the cache).
    """

    def __init__(self, model: Model, parameters: str | Sequence[str] | None = None, dt: float = 1e-3,
                 substeps: int = 4, threads: int | None = None, input_offset: bool = False) -> None:
        self.model = model
        self.dt = _check_dt(dt)
        if not isinstance(substeps, (int, np.integer)) or substeps < 1:
            raise InputError(f"substeps: expected a positive integer, got {substeps!r}")
        self.substeps = int(substeps)
        pd = ParametricDynamics(model, parameters, gravity_input=True)
        self.dynamics = pd
        self.names, self.nominal, self.p = pd.names, pd.nominal, pd.p
        n = model.n
        self.n, self.nx = n, 2 * n
        tr = model.transmission
        Bm = tr.actuation_matrix if tr is not None else np.eye(n)
        self.B = np.asarray(Bm, dtype=float)
        self.nu = self.B.shape[1]
        self.input_offset = bool(input_offset)
        self.no = self.nu if self.input_offset else 0
        self.nd = self.nx + self.p + self.no
        x = cs.SX.sym("x", self.nx)
        u = cs.SX.sym("u", self.nu)
        off = cs.SX.sym("offset", self.no)
        w = cs.vertcat(u, pd.g, pd.theta, off)
        u_eff = u + off if self.input_offset else u
        qdd = pd.forward_dynamics(x[:n], x[n:], cs.mtimes(cs.DM(self.B), u_eff), pd.theta, pd.g)
        f = cs.Function("f", [x, w], [cs.vertcat(x[n:], qdd)])
        xn = rk4_expression(f, x, w, self.dt / self.substeps)
        X = cs.SX.sym("X", self.nx, self.nd)
        Xn = cs.mtimes(cs.jacobian(xn, x), X) + cs.horzcat(cs.SX.zeros(self.nx, self.nx), cs.jacobian(xn, pd.theta),
                                                           cs.jacobian(xn, off))
        self.step = cs.Function("sens_step", [cs.vertcat(x, cs.vec(X)), w], [cs.cse(cs.vertcat(xn, cs.vec(Xn)))])
        self.plain_step = cs.Function("step", [x, w], [xn])
        label = f"sens_{model.name}_{'-'.join(self.names)}{'_off' if self.input_offset else ''}"[:90]
        self._loop = CompiledStepLoop(self.step, label, threads)
        self.compile_seconds = self._loop.compile_seconds
        self.nw = self.nu + 3 + self.p + self.no

    def run(self, x0: np.ndarray, U: np.ndarray, G: np.ndarray, theta: np.ndarray, offset: np.ndarray | None = None,
            progress: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """States and sensitivities at the samples of B segments of N samples.

        Parameters
        ----------
        x0: (B, 2n) initial states. U: (B, N, nu) inputs (N m), U[:, k] held on sample period k.
        G: (B, N, 3) gravity (m/s^2, base frame) per sample period. theta: (p,) parameter values.
        offset: (B, nu) constant input corrections per segment (with ``input_offset=True``; default 0).

        Returns
        -------
        x: (B, N+1, 2n) states at the samples; X: (B, N+1, 2n, 2n + p) their derivatives with respect
        to (x0, theta[, offset]).
        """
        x0 = np.asarray(x0, dtype=float)
        U = np.asarray(U, dtype=float)
        G = np.asarray(G, dtype=float)
        B, N = U.shape[0], U.shape[1]
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.shape != (self.p,) or not np.isfinite(theta).all():
            raise InputError(f"theta: expected {self.p} finite values, got {theta!r}")
        s = self.substeps
        W = np.empty((B, N * s, self.nw))
        W[:, :, : self.nu] = np.repeat(U, s, axis=1)
        W[:, :, self.nu: self.nu + 3] = np.repeat(G, s, axis=1)
        W[:, :, self.nu + 3: self.nu + 3 + self.p] = theta
        if self.input_offset:
            W[:, :, self.nu + 3 + self.p:] = 0.0 if offset is None else np.asarray(offset, dtype=float)[:, None, :]
        s0 = np.zeros((B, self.nx + self.nx * self.nd))
        s0[:, : self.nx] = x0
        s0[:, self.nx: self.nx + self.nx * self.nx] = np.eye(self.nx).ravel(order="F")
        S = self._loop.run(s0, W, progress, "sensitivities")[:, ::s]
        x = S[:, :, : self.nx]
        X = S[:, :, self.nx:].reshape(B, N + 1, self.nd, self.nx).transpose(0, 1, 3, 2)
        return x, X
