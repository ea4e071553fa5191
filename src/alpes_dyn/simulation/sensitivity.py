"""Trajectories and their sensitivities to the initial state and the physical parameters, in compiled C.

For x' = f(x, Gamma; theta, g) (:class:`~alpes_dyn.symbolic.parametric.ParametricDynamics`, eq. 2.10, 3.3)
discretised by ``substeps`` classical RK4 steps per sample period (the input held over the period,
as the estimation scenario and the observers do), the augmented step

    x_{k+1} = F(x_k, w_k; theta),     X_{k+1} = F_x X_k + [0 | F_theta],     X_0 = [I | 0],

propagates X = dx/d(x_0, theta) (2n x (2n + p)) with the state: the variational equation integrated by the
same RK4 (:func:`variational_rk4_step`, which for an explicit Runge-Kutta method is the derivative of the
discrete step), so the Jacobians are exact for the discretised model. The
step is compiled once by :class:`~alpes_dyn.simulation.integrate.CompiledStepLoop` (cached on disk, keyed by
the model's structure and the parameter selection: the parameter *values* are inputs) and runs many
segments at once on threads: the multiple-shooting intervals of a fit, or the designs of a Fisher
information study.

Input corrections. With ``input_basis=b`` the input is u_k + C phi_k, where phi_k (b,) are known basis
values per sample (e.g. 1, sin 2 pi f t, cos 2 pi f t of a multisine's lines) and C (nu x b) constant
coefficients per segment, and X also holds dx/d vec(C) (column-major): the errors-in-variables fits of
:func:`~alpes_dyn.estimation.identification.identification.identify` fit the true torque as the measured one plus such a
correction. ``input_offset=True`` is ``input_basis=1`` with phi = 1: a constant correction per segment.
"""

from __future__ import annotations

from typing import Sequence

import casadi as cs
import numpy as np

from ..errors import InputError
from ..model.robot import Model
from ..symbolic.dynamics import block_solve
from ..symbolic.parametric import ParametricDynamics
from .lugre_sensitivity import lugre_steps
from .integrate import CompiledStepLoop, _check_dt
from .variational import CHAINED_BASIS, LOOPED_STATES, chain_sample_jacobians, looped_variational_rk4_step
from .variational import sample_jacobian_step
from .variational_c import VariationalStepLoop
from .variational import _rk4_calling, repeated_step, variational_rk4_step  # (re-exported: their home before)

__all__ = ["SensitivityModel", "variational_rk4_step", "repeated_step"]


def _check_kernel(kernel: str, lugre: bool) -> None:
    """An InputError naming ``kernel`` where it is not one of :class:`SensitivityModel`'s, or ``"c"`` on a LuGre law
    (``lugre``)."""
    if kernel not in ("auto", "c", "casadi"):
        raise InputError(f"kernel: expected 'auto', 'c' or 'casadi', got {kernel!r}")
    if kernel == "c" and lugre:
        raise InputError("kernel: 'c' is the smooth law's step; this model's friction law is LuGre")


class SensitivityModel:
    """Batched simulation with sensitivities of a model with symbolic parameters.

    Parameters
    ----------
    model : alpes_dyn.Model
        The model (motor input through its transmission if it has one, else joint torques).
    parameters : str or sequence of str or None, optional
        Selection for :func:`~alpes_dyn.symbolic.parametric.select_parameters` (default None: its default).
    dt : float, optional
        The sample period, s (default 1e-3).
    substeps : int, optional
        RK4 steps per sample, 1..1000 (default 4: the smooth friction is fast).
    threads : int or None, optional
        Worker threads of the compiled loop (default None: the CPUs this process may use).
    input_offset : bool, optional
        True is ``input_basis=1`` (a constant correction per segment; default False).
    input_basis : int, optional
        The number b of basis functions of an input correction, 0..64 (see the module docstring; default 0).
    kernel : str, optional
        How the compiled step computes the sensitivities of a smooth (not LuGre) law: ``"c"`` the stage's linear
        algebra written out in C (:class:`~alpes_dyn.simulation.variational_c.VariationalStepLoop`: the same
        numbers to rounding, 2-3 times faster on the whole Shadow hand), ``"casadi"`` CasADi's code of the
        step (the reference), ``"auto"`` (default) ``"c"`` from
        :data:`~alpes_dyn.simulation.variational.LOOPED_STATES` states (the fingers and the Alpes hand keep their
        cached libraries).

    Raises
    ------
    InputError
        A bad ``substeps``, ``input_basis``, ``input_offset`` with another basis, or ``kernel`` (``"c"`` on a LuGre
        law's model).

    Attributes
    ----------
    dynamics : ParametricDynamics
        The model's :class:`~alpes_dyn.symbolic.parametric.ParametricDynamics`; ``names``, ``nominal`` (p,): its
        parameters.
    nx, p, nu, nb, no, nd : int
        The states (2n; 3n with the LuGre law's bristles, module lugre_sensitivity), parameters, inputs (motors or
        joints), basis functions, correction coefficients (nu nb) and sensitivity directions (nx + p + no).
    compile_seconds : float
        Time spent compiling now, s (0 when the library came from the cache).
    kernel : str
        The kernel chosen: ``"c"`` or ``"casadi"``.
    chained : bool
        Whether the sensitivities come from each period's own Jacobian chained over the samples (a looped step
        with many basis functions, :data:`~alpes_dyn.simulation.variational.CHAINED_BASIS`; the compiled step then
        carries that Jacobian).
    """

    def __init__(self, model: Model, parameters: str | Sequence[str] | None = None, dt: float = 1e-3,
                 substeps: int = 4, threads: int | None = None, input_offset: bool = False,
                 input_basis: int = 0, kernel: str = "auto") -> None:
        self.model = model
        self.dt = _check_dt(dt)
        if isinstance(substeps, (bool, np.bool_)) or not isinstance(substeps, (int, np.integer)) or not 1 <= substeps <= 1000:
            raise InputError(f"substeps: expected an integer from 1 to 1000 (RK4 steps per sample), got {substeps!r}")
        self.substeps = int(substeps)
        pd = ParametricDynamics(model, parameters, gravity_input=True)
        self.dynamics = pd
        self.names, self.nominal, self.p = pd.names, pd.nominal, pd.p
        n = model.n
        self.lugre = pd.lugre  # the LuGre law: the bristles in the state (module lugre_sensitivity)
        self.n, self.nx = n, (3 if pd.lugre is not None else 2) * n
        tr = model.transmission
        Bm = tr.actuation_matrix if tr is not None else np.eye(n)
        self.B = np.asarray(Bm, dtype=float)
        self.nu = self.B.shape[1]
        if not isinstance(input_basis, (int, np.integer)) or isinstance(input_basis, bool) or not 0 <= input_basis <= 64:
            raise InputError(f"input_basis: expected an integer in [0, 64], got {input_basis!r}")
        if input_offset and input_basis not in (0, 1):
            raise InputError("input_offset: a constant offset is input_basis=1; pass one of them")
        _check_kernel(kernel, pd.lugre is not None)
        self.nb = 1 if input_offset else int(input_basis)
        self.input_offset = self.nb > 0
        self.no = self.nu * self.nb
        self.nd = self.nx + self.p + self.no
        x = cs.SX.sym("x", self.nx)
        u = cs.SX.sym("u", self.nu)
        phi = cs.SX.sym("phi", self.nb)
        off = cs.SX.sym("coef", self.no)
        w = cs.vertcat(u, pd.g, pd.theta, phi, off)
        u_eff = u + cs.mtimes(cs.reshape(off, self.nu, self.nb), phi) if self.nb else u
        tau = (pd.input_torque(x[:n], x[n:2 * n], u_eff, pd.theta) if tr is not None  # S^T u, rho(q)^T u, the capstan's
               else cs.mtimes(cs.DM(self.B), u_eff))
        h = self.dt / self.substeps
        if pd.lugre is not None:
            plain, sens_of = lugre_steps(pd, x, w, tau, h)
        else:
            M, r = pd.dynamics_terms(x[:n], x[n:], tau, pd.theta, pd.g)
            rhs = cs.vertcat(x[n:], block_solve(M, r))  # (pd.forward_dynamics)
            plain = _rk4_calling(cs.Function("rhs", [x, w], [cs.cse(rhs)]), h, "step")

            def sens_of(directions: cs.SX) -> cs.Function:
                if self.nx >= LOOPED_STATES:  # the implicit derivative: a large model's Jacobians stay small
                    return looped_variational_rk4_step(rhs, M, r, x, w, directions, h)
                return variational_rk4_step(rhs, x, w, directions, h)
        # one call per sample period: the substeps in the compiled step, the input held, the states at the samples
        self.plain_step = repeated_step(plain, self.substeps)
        # many coefficients (the Shadow hand's lines): each period's Jacobian to (x, p, u), chained in run
        self.chained = pd.lugre is None and self.nx >= LOOPED_STATES and self.nb >= CHAINED_BASIS
        self.kernel = "c" if kernel == "c" or (kernel == "auto" and pd.lugre is None and self.nx >= LOOPED_STATES) \
            else "casadi"
        label = f"sens_{model.name}{'_lugre' if pd.lugre is not None else ''}_{'-'.join(self.names)}{f'_b{self.nb}' if self.nb else ''}"[:90]
        self._label, self._threads = label, threads
        directions = cs.vertcat(pd.theta, u) if self.chained else cs.vertcat(pd.theta, off)
        if self.kernel == "c":  # the same steps, the linear algebra written out (module variational_c)
            self.step, args = None, (rhs, M, r, x, w, directions, h, self.substeps, self.chained,
                                     label.replace("sens_", "sensc_", 1), threads)
            self._state_step = lambda: VariationalStepLoop(*args, state=True)  # (the same library: one build)
            self._loop = VariationalStepLoop(*args)
        else:
            step = repeated_step(sens_of(directions), self.substeps)
            self.step = sample_jacobian_step(step, self.nx) if self.chained else step
            # the sensitivities to the initial state alone (dx/dx_0, nx x nx), built on first use
            self._state_step = lambda: CompiledStepLoop(repeated_step(sens_of(cs.SX(0, 1)), self.substeps),
                                                        label.replace("sens_", "xsens_", 1), threads)
            self._loop = CompiledStepLoop(self.step, label, threads)
        self._state_loop: CompiledStepLoop | None = None
        self._plain_loop: CompiledStepLoop | None = None  # the states alone, compiled on first use
        self.compile_seconds = self._loop.compile_seconds
        self.nw = self.nu + 3 + self.p + self.nb + self.no

    def run(self, x0: np.ndarray, U: np.ndarray, G: np.ndarray, theta: np.ndarray, offset: np.ndarray | None = None,
            progress: bool = False, basis: np.ndarray | None = None,
            sensitivities: bool | str = True) -> tuple[np.ndarray, np.ndarray | None]:
        """States and sensitivities at the samples of B segments of N samples.

        Parameters
        ----------
        x0 : numpy.ndarray, shape (B, nx)
            The initial states (nx = 2n, or 3n with the LuGre law's bristles).
        U : numpy.ndarray, shape (B, N, nu)
            The inputs, N m, U[:, k] held on sample period k.
        G : numpy.ndarray, shape (B, N, 3)
            Gravity, m/s^2, base frame, per sample period.
        theta : numpy.ndarray, shape (p,)
            The parameter values, in their units.
        offset : numpy.ndarray or None, optional
            The correction coefficients C, (B, nu, nb) per segment or (nu, nb) for all (with ``input_offset=True``
            also (B, nu)); default None: 0.
        progress : bool, optional
            A progress bar on stderr (default False).
        basis : numpy.ndarray, shape (B, N, nb), or None, optional
            phi per sample (default None: ones, which only makes sense for a constant offset).
        sensitivities : bool or str, optional
            True (default): all nd directions; False: the states alone (the same step without its derivatives,
            compiled on first use: what a line search's trial needs); ``"state"``: the derivatives with respect to
            x0 alone (X (B, N+1, nx, nx), the first nx columns of the full X by the same operations; compiled on
            first use: a shooting fit's node sweeps, theta fixed, at a fraction of the cost of all nd directions).

        Returns
        -------
        x : numpy.ndarray, shape (B, N+1, nx)
            The states at the samples.
        X : numpy.ndarray, shape (B, N+1, nx, nd), or None
            Their derivatives with respect to (x0, theta[, vec C]); None without ``sensitivities``.
        """
        x0 = np.asarray(x0, dtype=float)
        U = np.asarray(U, dtype=float)
        G = np.asarray(G, dtype=float)
        B, N = U.shape[0], U.shape[1]
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if theta.shape != (self.p,) or not np.isfinite(theta).all():
            raise InputError(f"theta: expected {self.p} finite values, got {theta!r}")
        W = np.empty((B, N, self.nw))  # per sample period: the compiled step makes the substeps
        W[:, :, : self.nu] = U
        W[:, :, self.nu: self.nu + 3] = G
        W[:, :, self.nu + 3: self.nu + 3 + self.p] = theta
        if self.nb:
            j = self.nu + 3 + self.p
            if basis is None:
                W[:, :, j: j + self.nb] = 1.0
            else:
                basis = np.asarray(basis, dtype=float)
                if basis.shape != (B, N, self.nb):
                    raise InputError(f"basis: expected shape {(B, N, self.nb)}, got {basis.shape}")
                W[:, :, j: j + self.nb] = basis
            if offset is None:
                W[:, :, j + self.nb:] = 0.0
            else:
                C = np.asarray(offset, dtype=float)
                if C.shape == (B, self.nu) and self.nb == 1:
                    C = C[:, :, None]
                C = np.broadcast_to(C, (B, self.nu, self.nb))
                W[:, :, j + self.nb:] = C.transpose(0, 2, 1).reshape(B, 1, self.no)  # vec, column-major
        if not sensitivities:
            if self._plain_loop is None:
                # a large model's states at -O1: the Shadow hand's (a source just under the -O3 size) builds in 3.2 s
                # of CPU instead of 7.6, once per fit's selection, and runs as fast, the same bits (CHANGELOG)
                level = {"level": "-O1"} if self.nx >= LOOPED_STATES else {}
                self._plain_loop = CompiledStepLoop(self.plain_step, self._label.replace("sens_", "states_", 1),
                                                    self._threads, **level)
                self.compile_seconds += self._plain_loop.compile_seconds
            x0 = np.ascontiguousarray(np.broadcast_to(x0, (B, self.nx)))
            return self._plain_loop.run(x0, W, progress, "states"), None
        state = sensitivities == "state"
        if state and self._state_loop is None:
            self._state_loop = self._state_step()
            self.compile_seconds += self._state_loop.compile_seconds
        nd = self.nx if state else self.nd
        if self.chained and not state:
            nj = self.nx + self.p + self.nu
            s0 = np.zeros((B, self.nx + self.nx * nj))
            s0[:, : self.nx] = x0
            S = self._loop.run(s0, W, progress, "sensitivities")
            J = S[:, 1:, self.nx:].reshape(B, N, nj, self.nx).transpose(0, 1, 3, 2)
            return S[:, :, : self.nx], chain_sample_jacobians(J, W[:, :, self.nu + 3 + self.p:][:, :, : self.nb], self.p)
        s0 = np.zeros((B, self.nx + self.nx * nd))
        s0[:, : self.nx] = x0
        s0[:, self.nx: self.nx + self.nx * self.nx] = np.eye(self.nx).ravel(order="F")
        S = (self._state_loop if state else self._loop).run(s0, W, progress, "sensitivities")
        x = S[:, :, : self.nx]
        X = S[:, :, self.nx:].reshape(B, N + 1, nd, self.nx).transpose(0, 1, 3, 2)
        return x, X
