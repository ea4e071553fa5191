"""One classical RK4 step with its sensitivities, and steps repeated within a sample period: the compiled steps of
:class:`~alpes_dyn.simulation.sensitivity.SensitivityModel` (the smooth law's) and of
:mod:`~alpes_dyn.simulation.lugre_sensitivity` (the LuGre law's split step)."""

from __future__ import annotations

import casadi as cs
import numpy as np

from .integrate import rk4_expression

__all__ = ["variational_rk4_step", "looped_variational_rk4_step", "sample_jacobian_step", "chain_sample_jacobians",
           "repeated_step", "LOOPED_STATES", "CHAINED_BASIS"]


def _rk4_calling(fn: cs.Function, h: float, name: str) -> cs.Function:
    """One classical RK4 step of z' = fn(z, w), w held, as an MX function calling the SX ``fn`` four times (its
    body once in the generated C, not four times inlined)."""
    z = cs.MX.sym("z", fn.size1_in(0))
    wm = cs.MX.sym("w", fn.size1_in(1))
    return cs.Function(name, [z, wm], [rk4_expression(fn, z, wm, h)])


def repeated_step(step: cs.Function, count: int) -> cs.Function:
    """``step`` (x, w) -> x_next applied ``count`` times with the same w (an MX function calling it ``count``
    times): the substeps of one sample period in one compiled call, so the caller's inputs and states are per
    sample (not repeated per substep: for a stick-slip fit's 15 substeps, 15x less memory in and out).

    Parameters
    ----------
    step : casadi.Function
        One substep ``(x, w) -> x_next``: the state (its first input's size) and the input held over the substep.
    count : int
        Substeps per sample period (>= 1); 1 returns ``step`` itself.

    Returns
    -------
    casadi.Function
        ``(x, w) -> x`` after ``count`` substeps with the same ``w``, named ``step``'s name + ``_x{count}``
        (``step`` itself when ``count`` is 1).
    """
    if count == 1:
        return step
    z = cs.MX.sym("z", step.size1_in(0))
    wm = cs.MX.sym("w", step.size1_in(1))
    zk = z
    for _ in range(count):
        zk = step(zk, wm)
    return cs.Function(step.name() + f"_x{count}", [z, wm], [zk])


def variational_rk4_step(rhs: cs.SX, x: cs.SX, w: cs.SX, p: cs.SX, h: float) -> cs.Function:
    """One RK4 step of x' = rhs(x, w) with its sensitivities: ``sens_step([x; vec X], w) -> [x+; vec X+]``.

    X = dx/d(x_0, p) (nx x (nx + np), column-major in the state vector) obeys the variational equation
    X' = f_x X + [0 | f_p]; the step applies the same classical RK4 (step h, s) to the augmented system. For an
    explicit Runge-Kutta method this *is* the derivative of the discrete step (differentiation and
    discretisation commute), so the Jacobians stay exact for the discretised model, and the states are
    computed by the same operations as :func:`~alpes_dyn.simulation.integrate.rk4_expression` (bit for bit).

    ``p`` (np,) is a subvector of ``w`` (the parameters, input corrections). The augmented right-hand side is
    one SX function called four times by an MX step, so the generated C holds it once, not the RK4 step's
    derivative inlined: a source many times smaller, which compiles much faster and runs faster (the SIMD lanes of
    :class:`~alpes_dyn.simulation.integrate.CompiledStepLoop` are not used by a step with calls).

    Parameters
    ----------
    rhs : casadi.SX
        (nx,) the states' right-hand side x' = rhs(x, w), in ``x`` and ``w``.
    x : casadi.SX
        (nx,) the state's symbols.
    w : casadi.SX
        The input held over the step (torques, parameters, input corrections), the symbols ``rhs`` depends on
        besides ``x``.
    p : casadi.SX
        (np,) the parameters the sensitivities are taken in: a subvector of ``w``.
    h : float
        The step, s.

    Returns
    -------
    casadi.Function
        ``sens_step([x; vec X], w) -> [x+; vec X+]``, X (nx, nx + np) column-major: an ``MX`` step calling one
        ``SX`` function (the augmented right-hand side) four times.
    """
    nx = x.numel()
    X = cs.SX.sym("X", nx, nx + p.numel())
    dX = cs.mtimes(cs.jacobian(rhs, x), X) + cs.horzcat(cs.SX.zeros(nx, nx), cs.jacobian(rhs, p))
    fa = cs.Function("sens_rhs", [cs.vertcat(x, cs.vec(X)), w], [cs.cse(cs.vertcat(rhs, cs.vec(dX)))])
    return _rk4_calling(fa, h, "sens_step")


LOOPED_STATES = 40
"""States from which :class:`~alpes_dyn.simulation.sensitivity.SensitivityModel` builds its step by
:func:`looped_variational_rk4_step`: above it the Jacobians of the forward dynamics, inlined, make C too large for the
compiler to finish; the fingers and the Alpes hand (30 states) keep :func:`variational_rk4_step` (their cached
libraries, bit for bit). The Shadow hand's commands with the looped step are recorded in
``benchmarks/results/foreign_hands.json`` (its commands part)."""


def looped_variational_rk4_step(rhs: cs.SX, M: cs.SX, r: cs.SX, x: cs.SX, w: cs.SX, p: cs.SX,
                                h: float) -> cs.Function:
    """:func:`variational_rk4_step` of x = [q; v], x' = rhs = [v; M^-1 r] (M qdd = r: eq. 2.10's terms,
    :meth:`~alpes_dyn.symbolic.parametric.ParametricDynamics.dynamics_terms`), its derivative by the implicit
    function instead of through the solve: with g(x, w, a) = r - M a, dqdd/d(x, p) = M^-1 dg/d(x, p) at a = qdd,
    so X' = [X_v; M^-1 (g_x X + [0 | g_p])] (X_v the rows of v).

    Parameters
    ----------
    rhs : casadi.SX
        (2n,) [v; qdd], the states' right-hand side (the plain step's expression: the same states, bit for bit).
    M, r : casadi.SX
        (n, n) and (n,): M qdd = r, in x and w.
    x, w, p : casadi.SX
        The state (2n,), the held input, the directions' parameters (a subvector of w).
    h : float
        The step, s.

    Returns
    -------
    casadi.Function
        ``sens_step([x; vec X], w) -> [x+; vec X+]``, ``MX``: two ``SX`` functions (rhs; M, g_x, g_p) called four
        times, the products by X and the solve by M (``qr``) as CasADi's dense loops; the written-out derivative's
        numbers to rounding (sums in another order).
    """
    nx, n = x.numel(), M.size1()
    nd = nx + p.numel()
    a = cs.SX.sym("a", n)
    g = r - cs.mtimes(M, a)
    f_rhs = cs.Function("sens_rhs", [x, w], [cs.cse(rhs)])
    terms = cs.Function("sens_terms", [x, w, a], cs.cse([M, cs.jacobian(g, x), cs.jacobian(g, p)]))
    z, wm = cs.MX.sym("z", nx + nx * nd), cs.MX.sym("w", w.numel())
    X = cs.reshape(z[nx:], nx, nd)
    f = f_rhs(z[:nx], wm)
    Mm, gx, gp = terms(z[:nx], wm, f[n:])
    dv = cs.solve(Mm, cs.mtimes(gx, X) + cs.horzcat(cs.MX(n, nx), cs.densify(gp)), "ldl")
    fa = cs.Function("sens_rhs_x", [z, wm], [cs.vertcat(f, cs.vec(cs.vertcat(X[n:, :], dv)))])
    return _rk4_calling(fa, h, "sens_step")


CHAINED_BASIS = 4
"""Basis functions of an input correction from which a looped step (:data:`LOOPED_STATES`) gives its sensitivities
by :func:`sample_jacobian_step` and :func:`chain_sample_jacobians`: each sample period's own Jacobian with respect
to (x, p, u) through the substeps (nx + p + nu directions), chained over the samples by products of matrices, not
the nx + p + nu nb directions through every substep (the whole Shadow hand's fit: 20 motors, 19 basis functions,
521 directions through the substeps -> 161)."""


def sample_jacobian_step(sample_step: cs.Function, nx: int) -> cs.Function:
    """One sample period's states and its own Jacobian: ``([x; vec J], w) -> [x+; vec J+]`` where J+ = d x+ / d(x,
    p, u) of this period alone (``sample_step`` seeded with [I | 0]; the J it is given is not read).

    Parameters
    ----------
    sample_step : casadi.Function
        ``([x; vec X], w) -> [x+; vec X+]``: the period's substeps with the sensitivities to (x, p, u), X (nx, nx +
        p + nu) column-major (:func:`repeated_step` of a variational step whose directions are the parameters, then
        the input: a subvector of ``w``).
    nx : int
        The states.

    Returns
    -------
    casadi.Function
        ``([x; vec J], w) -> [x+; vec J+]``, the states those of ``sample_step``, bit for bit.
    """
    nz = sample_step.size1_in(0)
    z, wm = cs.MX.sym("z", nz), cs.MX.sym("w", sample_step.size1_in(1))
    seed = cs.DM.zeros(nz - nx, 1)
    seed[[i * nx + i for i in range(nx)]] = 1.0  # vec [I | 0]
    return cs.Function(sample_step.name() + "_own", [z, wm], [sample_step(cs.vertcat(z[:nx], seed), wm)])


def chain_sample_jacobians(J: np.ndarray, phi: np.ndarray, p: int) -> np.ndarray:
    """The sensitivities X_k = d x_k / d(x_0, p, vec C) of segments whose input is u + C phi_k, from each sample
    period's own Jacobian [F_x | F_p | F_u] (:func:`sample_jacobian_step`): X_0 = [I | 0], X_{k+1} = F_x X_k + [0 |
    F_p | phi_k^T kron F_u] (the chain rule of the discrete step: the derivative the directions through the
    substeps give, to rounding).

    Parameters
    ----------
    J : numpy.ndarray, shape (B, N, nx, nx + p + nu)
        Each segment's periods' own Jacobians.
    phi : numpy.ndarray, shape (B, N, nb)
        The basis' values per period.
    p : int
        The parameters.

    Returns
    -------
    numpy.ndarray, shape (B, N + 1, nx, nx + p + nu nb)
        X at the samples (C's columns ``m + nu b``, as vec(C) column-major).
    """
    B, N, nx, nj = J.shape
    nu, nb = nj - nx - p, phi.shape[2]
    X = np.empty((B, N + 1, nx, nx + p + nu * nb))
    X[:, 0] = 0.0
    X[:, 0, :, :nx] = np.eye(nx)
    X[:, 1:, :, nx:nx + p] = J[..., nx:nx + p]
    X[:, 1:, :, nx + p:] = (phi[:, :, None, :, None] * J[:, :, :, None, nx + p:]).reshape(B, N, nx, nu * nb)
    X[:, 1:, :, :nx] = 0.0
    w = max(8, _ONE_THREAD_PRODUCT // (nx * nx))
    for k in range(N):  # (a loop over the samples, each a few products batched over the segments)
        for a in range(0, X.shape[3], w):  # (columns by blocks: products BLAS keeps on one thread)
            X[:, k + 1, :, a:a + w] += J[:, k, :, :nx] @ X[:, k, :, a:a + w]
    return X


_ONE_THREAD_PRODUCT = 300_000
"""Multiply-adds of one product of :func:`chain_sample_jacobians` (nx x nx by nx x columns): its columns go by
blocks below this, which OpenBLAS computes on one thread (the whole Shadow hand's 48 x 48 by 48 x 521 went to threads:
its threads' waits 1.0-1.4 s of CPU per 8 intervals of 50 samples, against 0.04 s by blocks of 128 on one)."""
