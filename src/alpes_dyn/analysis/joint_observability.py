"""Which joints a recorded motion observes: a practical, noise-aware observability of each joint along the motion.

The rank test of :mod:`alpes_dyn.analysis.observability` says whether the joints can be told apart at all; this
module says how well the encoders tell them apart on the motion at hand, at their noise. For a window of L samples
starting at sample k of the (estimated) trajectory, the Fisher information of phi = (x_k, b) from the window's
encoder readings y_k+j = h(x_k+j) + noise (covariance R, rad^2), linearised along the trajectory (the empirical
observability Gramian of a window, as in Cellini et al.'s pybounds), is

    F_k = sum_j S_j^T R^-1 S_j + Lambda,     S_j = H_k+j [dx_k+j/dx_k, dx_k+j/db],

the sensitivities carried by the sample's Jacobians: X_j+1 = A_k+j X_j + [0, E_k+j], with [A, E] the zero-order
hold exp([[df/dx, df/db], [0, 0]] dt) of the continuous dynamics' Jacobians (CasADi's automatic differentiation;
exact for the linearisation however stiff the smooth friction makes it). b is a constant torque on each joint with
dry friction, N m, of prior standard deviation its Coulomb level F_c: below breakaway the friction's torque is any
value within +-F_s (a constraint, not the smooth law's number there), so the measure does not let the model's
friction pin a joint it holds. Lambda is the prior information, diag(1 / 0.5^2 rad^-2 on q, 1 / 1^2 on qd, 1 / F_c^2 on b): the observers' own prior
(:func:`~alpes_dyn.estimation.observers.replay.recording_filter`), so that a direction the window does not see
keeps the prior's 0.5 rad (the regularisation lambda I of pybounds, in the state's units). Each joint's error
standard deviation from the window is sqrt((F_k^-1)_ii); its smallest over the windows is what the recording can
tell of that joint at best. A joint whose best is above ``limit`` (default :data:`UNOBSERVED_LIMIT`, 1 degree) is
not observed: ``alpes-dyn estimate`` flags it instead of giving its estimate as a confident number.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import casadi as cs
import numpy as np

from ..checks import as_float_array
from ..errors import InputError
from ..model.robot import Model
from ..symbolic.statespace import StateSpace
from ..symbolic.tree_sparsity import block_solve

__all__ = ["JointObservability", "joint_observability", "UNOBSERVED_LIMIT", "WINDOW", "STRIDE"]

UNOBSERVED_LIMIT = math.radians(1.0)
"""A joint whose best window's standard deviation is above this (rad, 1 degree) is not observed: the issue's bar
for a foreign finger (within 1 degree or flagged), twice the observers' 0.5-degree goal."""
WINDOW = 0.5
"""The window, s: a few periods of a finger's motion at the estimation scenario's 3.1 Hz, short enough that its
linearisation along the estimated trajectory holds."""
STRIDE = 0.1
"""The step between windows' starts, s."""
PRIOR_STD = (0.5, 1.0)
"""The prior's standard deviations on q (rad) and qd (rad/s): the observers' initial covariance."""


@dataclass
class JointObservability:
    """Each joint's observability along a motion (see the module docstring).

    Attributes
    ----------
    joints: (n,) names. t: (W,) the windows' starts, s from the first sample. std: (W, n) each joint's error
    standard deviation from each window, rad. best: (n,) its smallest over the windows, rad. limit: rad.
    window, stride: s. friction: the joints whose dry friction's torque is taken unknown (within F_c).
    """

    joints: tuple[str, ...]
    t: np.ndarray
    std: np.ndarray
    best: np.ndarray
    limit: float
    window: float
    stride: float
    friction: tuple[str, ...]

    @property
    def unobserved(self) -> tuple[str, ...]:
        """The joints whose best window leaves them above ``limit``."""
        return tuple(j for j, s in zip(self.joints, self.best) if not s <= self.limit)

    def to_dict(self) -> dict[str, Any]:
        """The JSON of ``alpes-dyn estimate --json`` (its ``observability`` object), degrees."""
        return {"best_std_deg": np.degrees(self.best).tolist(), "limit_deg": math.degrees(self.limit),
                "unobserved": list(self.unobserved), "window_s": self.window, "stride_s": self.stride,
                "windows": int(self.t.size), "friction_unknown": list(self.friction)}


def _linearised(model: Model) -> tuple[cs.Function, int, np.ndarray]:
    """(x, u) -> (M, g_x, H): the terms of the continuous dynamics x' = f(x, u, b) = [v; qdd], M qdd = r (eq. 3.3)
    driven by the motor torques u (N m) plus a torque b on each joint with Coulomb friction (at b = 0), as
    :func:`_jacobians` differentiates them (the implicit derivative: g = r - M a at a = qdd, so dqdd/dx = M^-1 g_x
    and dqdd/db = M^-1 S_b, instead of the Jacobian through the solve: for the Shadow hand with its wrist free a
    fifth of the instructions); the encoders' Jacobian H; the number of those joints and S_b (n, nb)."""
    ss = StateSpace(model, input="motor", output="encoder")
    n = model.n
    fr = np.flatnonzero(np.asarray(model.extras.coulomb) > 0)
    x, u = cs.SX.sym("x", 2 * n), cs.SX.sym("u", ss.n_inputs)
    q, v = x[:n], x[n:]
    tau = ss.input_torque(q, u, v)
    Sb = np.zeros((n, fr.size))
    Sb[fr, np.arange(fr.size)] = 1.0
    sym = ss.sym  # joint_accelerations' forward dynamics, its two terms apart
    r = sym.net_torque(q, v, tau, sym.extras.passive_torque(q, v, ss.smooth, cs), None, ss.tip)
    M = sym.inertia_matrix(q)
    qdd = block_solve(M, r)
    a = cs.SX.sym("a", n)
    gx = cs.substitute(cs.jacobian(r - cs.mtimes(M, a), x), a, qdd)
    H = cs.jacobian(ss.h_function(x), x)
    return cs.Function("lin", [x, u], cs.cse([cs.densify(M), cs.densify(gx), cs.densify(H)])), int(fr.size), Sb


def _jacobians(M: np.ndarray, gx: np.ndarray, Sb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(A_c (N, 2n, 2n), E_c (N, 2n, nb)) of x' = [v; qdd] from :func:`_linearised`'s M (N, n, n) and g_x (N, n, 2n):
    [[0, I], [M^-1 g_x]] and [[0], [M^-1 S_b]], every sample at once."""
    N, n = M.shape[0], M.shape[1]
    sol = np.linalg.solve(M, np.concatenate([gx, np.broadcast_to(Sb, (N,) + Sb.shape)], axis=2))
    Ac = np.zeros((N, 2 * n, 2 * n))
    Ac[:, :n, n:] = np.eye(n)
    Ac[:, n:] = sol[:, :, :2 * n]
    Ec = np.zeros((N, 2 * n, Sb.shape[1]))
    Ec[:, n:] = sol[:, :, 2 * n:]
    return Ac, Ec


HELD_CHUNK = 512
"""Samples per batch of :func:`_held` (its products' memory: the whole hand's samples at once would hold gigabytes)."""


def _held(Ac: np.ndarray, Ec: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, E) of one sample with the input held (zero-order hold): exp([[A_c, E_c], [0, 0]] dt) = [[A, E], [0, I]],
    every sample at once, by scaling and squaring (each sample's matrix scaled by 2^-s to a 1-norm below 1/2, the
    Taylor series to its 12th term, 2^-12 / 13! relative: below rounding, then squared s times; not scipy's expm, a
    Python loop over the samples); exact for the linearised dynamics however stiff the smooth friction
    makes them. The zero rows kept out of the products: with C = [A_c, E_c] dt 2^-s, each term is [T, U] with
    [T_k, U_k] = T_k-1 C / k, and a squaring [P, Q] -> P [P, Q] + [0, Q]."""
    N, nx, nb = Ec.shape
    A, E = np.empty((N, nx, nx)), np.empty((N, nx, nb))
    for a in range(0, N, HELD_CHUNK):  # (a loop over chunks of samples)
        sl = slice(a, min(a + HELD_CHUNK, N))
        C = np.concatenate([Ac[sl], Ec[sl]], axis=2) * dt
        norm = np.abs(C).sum(axis=1).max(axis=1)  # each sample's 1-norm (the zero rows add nothing)
        s = np.where(norm > 0.5, np.ceil(np.log2(np.maximum(norm, 0.5) / 0.5)), 0.0).astype(int)
        C /= (2.0 ** s)[:, None, None]
        Phi = np.zeros(C.shape)
        Phi[:, :, :nx] = np.eye(nx)
        term = Phi.copy()
        for k in range(1, 13):  # the Taylor series, the chunk's samples at once
            term = term[:, :, :nx] @ C / k
            Phi += term
        for r in range(int(s.max(initial=0))):  # each sample squared its own s times
            m = s > r
            P = Phi[m]
            sq = P[:, :, :nx] @ P
            sq[:, :, nx:] += P[:, :, nx:]
            Phi[m] = sq
        A[sl], E[sl] = Phi[:, :, :nx], Phi[:, :, nx:]
    return A, E


def _window_std(A: np.ndarray, E: np.ndarray, H: np.ndarray, Rinv: np.ndarray, starts: np.ndarray, L: int,
                prior: np.ndarray, n: int) -> np.ndarray:
    """(W, n) sqrt of the q block's diagonal of F^-1 for the windows of L samples at ``starts``."""
    nx, nb = A.shape[1], E.shape[2]
    X = np.zeros((starts.size, nx, nx + nb))
    X[:, :, :nx] = np.eye(nx)
    F = np.broadcast_to(np.diag(prior), (starts.size, nx + nb, nx + nb)).copy()
    for j in range(L):  # a loop over the window's samples, every window at once
        S = H[starts + j] @ X
        F += S.transpose(0, 2, 1) @ Rinv @ S
        if j + 1 < L:
            X = A[starts + j] @ X
            X[:, :, nx:] += E[starts + j]
    cov = np.linalg.inv(F)
    return np.sqrt(np.maximum(np.diagonal(cov, axis1=1, axis2=2)[:, :n], 0.0))


def joint_observability(model: Model, states: Any, inputs: Any, dt: float, measurement_noise: Any, *,
                        window: float = WINDOW, stride: float = STRIDE,
                        limit: float = UNOBSERVED_LIMIT) -> JointObservability:
    """Each joint's practical observability along a motion (module docstring).

    Parameters
    ----------
    model : Model
        The observer's :class:`~alpes_dyn.Model` (with motors and encoders).
    states : array_like, shape (N, >= 2n)
        The trajectory [q; qd; ...] along which to linearise, rad and rad/s: the observer's estimate (its extra
        states ignored).
    inputs : array_like, shape (N-1, m)
        The motor torques held from each sample to the next, N m.
    dt : float
        The sample period, s.
    measurement_noise : array_like, shape (m,) or (m, m)
        The encoders' covariance: variances or a positive definite matrix, rad^2.
    window : float, optional
        The window's length, s (default :data:`WINDOW`; a record shorter than it is one window).
    stride : float, optional
        The step between windows' starts, s (default :data:`STRIDE`).
    limit : float, optional
        The flag's threshold on a joint's best standard deviation, rad (default :data:`UNOBSERVED_LIMIT`).

    Returns
    -------
    JointObservability
        Each joint's error standard deviation from each window (W, n), rad, its best over the windows and the
        joints not observed (``unobserved``).

    Raises
    ------
    InputError
        Naming the argument: a model without motors and encoders, states or inputs of the wrong shape or not
        finite, a covariance not positive definite, or ``dt``, ``window``, ``stride`` or ``limit`` not a positive
        number.
    """
    if not isinstance(model, Model) or model.transmission is None:
        raise InputError("model: expected an alpes_dyn Model with motors and encoders")
    n, m = model.n, model.transmission.n_motors
    X = as_float_array(states, "states", f"(N, {2 * n}) states")
    if X.ndim != 2 or X.shape[0] < 2 or X.shape[1] < 2 * n or not np.isfinite(X).all():
        raise InputError(f"states: expected (N >= 2, {2 * n}) finite states, got shape {X.shape}")
    N = X.shape[0]
    U = as_float_array(inputs, "inputs", f"({N - 1}, {m}) motor torques")
    if U.shape != (N - 1, m) or not np.isfinite(U).all():
        raise InputError(f"inputs: expected ({N - 1}, {m}) finite motor torques, got shape {U.shape}")
    R = as_float_array(measurement_noise, "measurement_noise", f"{m} variances")
    R = np.diag(R) if R.ndim == 1 else R
    if R.shape != (m, m) or not np.isfinite(R).all() or np.linalg.eigvalsh(R).min() <= 0:
        raise InputError(f"measurement_noise: expected {m} positive variances or an ({m}, {m}) covariance")
    for x, name in ((dt, "dt"), (window, "window"), (stride, "stride"), (limit, "limit")):
        if isinstance(x, (bool, np.bool_)) or not isinstance(x, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(x) and x > 0):
            raise InputError(f"{name}: expected a positive number, got {x!r:.40}")
    L = min(N, max(1, int(round(window / dt))))
    starts = np.arange(0, N - L + 1, max(1, int(round(stride / dt))))
    lin, nb, Sb = _linearised(model)
    # the Jacobians at every sample (the last one's input: the last held)
    Mk, gx, H = (np.asarray(a) for a in lin.map(N)(X[:, : 2 * n].T, np.vstack([U, U[-1:]]).T))
    Mk = Mk.reshape(n, N, n).transpose(1, 0, 2)  # the map stacks the samples side by side
    gx = gx.reshape(n, N, 2 * n).transpose(1, 0, 2)
    H = H.reshape(m, N, 2 * n).transpose(1, 0, 2)
    A, E = _held(*_jacobians(Mk, gx, Sb), float(dt))
    Mk = gx = None
    coulomb = np.asarray(model.extras.coulomb, dtype=float)
    fr = np.flatnonzero(coulomb > 0)
    prior = np.concatenate([np.full(n, PRIOR_STD[0] ** -2), np.full(n, PRIOR_STD[1] ** -2), coulomb[fr] ** -2.0])
    std = _window_std(A, E, H, np.linalg.inv(R), starts, L, prior, n)
    return JointObservability(joints=tuple(model.joint_names), t=starts * float(dt), std=std, best=std.min(axis=0),
                              limit=float(limit), window=L * float(dt), stride=float(stride),
                              friction=tuple(model.joint_names[i] for i in fr))
