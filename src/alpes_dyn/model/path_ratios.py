"""The q-dependent ratios of a transmission whose motors include spatial tendons given as paths.

The rows of motors with a ``path`` (:mod:`alpes_dyn.model.spatial_path`) come from the tendon's length,
s_k(q) = g (L(q) - L(0)): rho_k = ds_k/dq and the rate product ((drho/dt) qd)_k = qd^T (d^2 s_k/dq^2) qd by AD of
one CasADi function (built once); the other rows are a :class:`~alpes_dyn.model.ratio_curve.RatioCurve`'s (constant
or polynomial). :class:`PathRatios` has the RatioCurve's interface (``ratio``, ``angle``, ``rate_product``,
``torque_jacobian``, ``S``, ``C``), numpy or CasADi (``xp``), so the numeric model, the symbolic one, the fit and
the C export take it where they take a RatioCurve.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import ModelError
from .ratio_curve import RatioCurve

__all__ = ["PathRatios"]


class PathRatios:
    """Ratios rho(q) (m, n) with the rows of ``paths`` {motor row: SpatialPath} from the tendon's length (module
    doc), the others ``base``'s.

    Parameters
    ----------
    base : RatioCurve
        The ratios of every row (constant or polynomial); its path rows are replaced.
    paths : mapping of int to SpatialPath
        {motor row: the tendon's path} (:class:`~alpes_dyn.model.spatial_path.SpatialPath`).
    names : sequence of str
        The motors' names (m), as errors name them.
    joint_names : sequence of str
        The model's joints (n), in order.

    Raises
    ------
    ModelError
        A path's joint that is not the model's, or a path whose ratio at q = 0 is not the spec's.
    """

    def __init__(self, base: RatioCurve, paths: Mapping[int, Any], names: Sequence[str],
                 joint_names: Sequence[str]) -> None:
        import casadi as cs

        self.base, self.S, self.C = base, base.S, base.C
        m, n = base.S.shape
        self.rows = sorted(paths)
        idx = {j: i for i, j in enumerate(joint_names)}
        q, v = cs.SX.sym("q", n), cs.SX.sym("v", n)
        s = []
        for k in self.rows:
            missing = [j for j in paths[k].joint_names if j not in idx]
            if missing:
                raise ModelError(f"motor {names[k]!r}.path: joint {missing[0]!r} is not a joint of the model")
            angle = {j: q[i] for j, i in idx.items()}
            L = paths[k].length(angle)
            s.append(paths[k].gear * (L - cs.substitute(L, q, cs.DM.zeros(n))))
        s = cs.vertcat(*s)
        rho = cs.jacobian(s, q)
        rate = cs.mtimes(cs.jacobian(cs.mtimes(rho, v), q), v)
        tau = cs.SX.sym("tau", len(self.rows))
        tj = cs.jacobian(cs.mtimes(rho.T, tau), q)
        self._f = {"angle": cs.Function("path_angle", [q], [s]), "ratio": cs.Function("path_ratio", [q], [rho]),
                   "rate": cs.Function("path_rate", [q, v], [rate]),
                   "torque": cs.Function("path_torque_jacobian", [q, tau], [tj])}
        self._maps: dict = {}
        at0 = np.asarray(self._f["ratio"](np.zeros(n)))
        for r, k in enumerate(self.rows):  # the spec's joints: the path's ratios at q = 0
            i = int(np.argmax(np.abs(at0[r] - base.S[k])))
            if abs(at0[r, i] - base.S[k, i]) > 1e-9 * max(np.max(np.abs(at0[r])), 1e-300):
                raise ModelError(f"motor {names[k]!r}.joints.{joint_names[i]}: the path's ratio at q = 0 is "
                                 f"{at0[r, i]:.10g}, not {base.S[k, i]:g} (a path motor's joints are its ratios there)")
        E = np.zeros((m, len(self.rows)))
        E[self.rows, np.arange(len(self.rows))] = 1.0
        self._E, self._keep = E, np.ones(m)
        self._keep[self.rows] = 0.0
        self.P = base.P

    @property
    def shape(self) -> tuple[int, int]:
        """(m, n)."""
        return self.S.shape

    def _batch(self, name: str, q: np.ndarray, *more: np.ndarray) -> np.ndarray:
        """The path function ``name`` at numpy q (..., n) (and ``more`` of the same leading shape): (..., rows, k)."""
        q = np.asarray(q, dtype=float)
        lead = q.shape[:-1]
        flat = [np.reshape(x, (-1, x.shape[-1])) for x in (q,) + tuple(np.asarray(a, dtype=float) for a in more)]
        N = flat[0].shape[0]
        if N > 1 and (name, N) not in self._maps:  # one map per batch size, built once
            self._maps[(name, N)] = self._f[name].map(N)
        f = self._f[name] if N == 1 else self._maps[(name, N)]
        out = np.asarray(f(*[x.T for x in flat]))
        r = out.shape[0]
        return out.reshape(r, N, -1).transpose(1, 0, 2).reshape(lead + (r, -1))

    def ratio(self, q: Any, xp: Any = np) -> Any:
        """rho(q) (m, n) for q (n,); (..., m, n) for numpy q (..., n); CasADi for a CasADi q.

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,) or (..., n)
            Joint angles, rad.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        if xp is np:
            out = np.array(self.base.ratio(q), dtype=float)
            out[..., self.rows, :] = self._batch("ratio", q)
            return out
        return xp.mtimes(xp.diag(xp.DM(self._keep)), self.base.ratio(q, xp)) + xp.mtimes(
            xp.DM(self._E), self._f["ratio"](q))

    def angle(self, q: Any, xp: Any = np) -> Any:
        """s(q), rad of motor shaft: (..., m) for numpy q (..., n), an (m,) column for CasADi q.

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,) or (..., n)
            Joint angles, rad.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        if xp is np:
            out = np.array(self.base.angle(q), dtype=float)
            out[..., self.rows] = self._batch("angle", q)[..., 0]
            return out
        return xp.DM(self._keep) * self.base.angle(q, xp) + xp.mtimes(xp.DM(self._E), self._f["angle"](q))

    def rate_product(self, q: Any, v: Any, xp: Any = np) -> Any:
        """(drho/dt) qd (m,), rad/s^2, for q, v (n,) numpy or CasADi.

        Parameters
        ----------
        q : numpy.ndarray or casadi.SX, shape (n,)
            Joint angles, rad.
        v : numpy.ndarray or casadi.SX, shape (n,)
            Joint velocities qd, rad/s.
        xp : module, optional
            ``numpy`` (default) or ``casadi``.
        """
        if xp is np:
            out = np.array(self.base.rate_product(q, v), dtype=float)
            out[self.rows] = np.asarray(self._f["rate"](q, v)).ravel()
            return out
        return xp.DM(self._keep) * self.base.rate_product(q, v, xp) + xp.mtimes(xp.DM(self._E), self._f["rate"](q, v))

    def torque_jacobian(self, q: np.ndarray, tau_m: np.ndarray) -> np.ndarray:
        """d(rho(q)^T tau_m)/dq (n, n), N m/rad (numpy).

        Parameters
        ----------
        q : numpy.ndarray, shape (n,)
            Joint angles, rad.
        tau_m : numpy.ndarray, shape (m,)
            Motor torques, N m.
        """
        tau_m = np.asarray(tau_m, dtype=float)
        keep = tau_m * self._keep
        out = self.base.torque_jacobian(q, keep)
        return out + np.asarray(self._f["torque"](q, tau_m[self.rows]))
