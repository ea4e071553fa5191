"""The looped variational RK4 step (:func:`~alpes_dyn.simulation.variational.looped_variational_rk4_step`) with its
linear algebra in hand-written C: the Shadow hand's sensitivities (issue 51).

CasADi's code of the looped step spends most of a stage in generic sparse loops and copies: the product g_x X by
``casadi_mtimes`` (indices read per multiply), the solve by M through ``casadi_ldl_solve`` one direction at a time,
and six transposes and copies of the (nx, nd) directions per stage to lay out [X_v; M^-1 (g_x X + [0 | g_p])] in
column-major order. Here the same stage is

    x' = rhs(x, w),     X' = [X_v; M^-1 (g_x X + [0 | g_p])],

with the directions held row by row (each state's nd derivatives contiguous, so that every product is an axpy over
the directions, which the compiler vectorises), M factorised as U D U' (U unit upper triangular: no fill on a
kinematic tree whose joints come after their parents, and the zeros of U and of g_x skipped where they fall), the
parameter directions whose g_p column is structurally zero (an output-only parameter: an encoder offset, a tendon
compliance) left out of the arithmetic and written as exact zeros. rhs, M, g_x and g_p
(:func:`~alpes_dyn.simulation.variational.looped_variational_rk4_step`'s expressions) are one CasADi function
generated into the same source (M and r computed once for rhs and the Jacobians); the states follow the same RK4
operations in the same order as :func:`~alpes_dyn.simulation.integrate.rk4_expression` (bit for bit with the plain
step), the sensitivities the same stage derivatives summed in another order (to rounding). One library holds two
steps: all the directions, and the start state's alone (a shooting fit's node sweeps). The loop over samples,
segments and threads is :class:`~alpes_dyn.simulation.codegen.CompiledStepLoop`'s (its driver, once per step).
"""

from __future__ import annotations

import ctypes

import casadi as cs
import numpy as np

from .codegen import _DRIVER, CompiledStepLoop, _build_library, _check_threads

__all__ = ["VariationalStepLoop"]


_STEP = r"""
/* ---- alpes_dyn: the looped variational RK4 step, its linear algebra written out (module variational_c) ---- */
#include <string.h>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC push_options
#pragma GCC optimize ("O3")
#endif
#define VN {n}
#define VNX {nx}
#define VND {nd}
#define VNDALL {nd_all}
#define VNP {np_all}
#define VSUB {substeps}
#define VSEED {seed}
#define VCB 32
static const int v_live{sfx}[VND] = {{{live}}};
static const double v_h{sfx} = {h}, v_h2{sfx} = {h2}, v_h6{sfx} = {h6};

/* M (n, n) column-major, symmetric positive definite -> U D U' (U unit upper, in Uf column-major; zeros skipped) */
static void v_udu{sfx}(const double* M, double* Uf, double* D) {{
  int i, j, k;
  for (j = VN - 1; j >= 0; --j) {{
    double d = M[j + VN * j];
    for (k = j + 1; k < VN; ++k) if (Uf[j + VN * k] != 0.0) d -= Uf[j + VN * k] * Uf[j + VN * k] * D[k];
    D[j] = d;
    Uf[j + VN * j] = 1.0;
    for (i = 0; i < j; ++i) {{
      double s = M[i + VN * j];
      for (k = j + 1; k < VN; ++k) if (Uf[j + VN * k] != 0.0) s -= Uf[i + VN * k] * Uf[j + VN * k] * D[k];
      Uf[i + VN * j] = s / d;
    }}
    for (i = j + 1; i < VN; ++i) Uf[i + VN * j] = 0.0;
  }}
}}

/* columns c0..c1-1 of T (n rows of VND) <- M^-1 T with M = U D U' */
static void v_solve{sfx}(const double* Uf, const double* D, double* T, int c0, int c1) {{
  int i, k, c;
  for (i = VN - 1; i >= 0; --i) {{
    double* ti = T + i * VND;
    for (k = i + 1; k < VN; ++k) {{
      double u = Uf[i + VN * k];
      const double* tk = T + k * VND;
      if (u != 0.0) for (c = c0; c < c1; ++c) ti[c] -= u * tk[c];
    }}
  }}
  for (i = 0; i < VN; ++i) {{
    double* ti = T + i * VND;
    for (c = c0; c < c1; ++c) ti[c] /= D[i];
  }}
  for (i = 0; i < VN; ++i) {{
    double* ti = T + i * VND;
    for (k = 0; k < i; ++k) {{
      double u = Uf[k + VN * i];
      const double* tk = T + k * VND;
      if (u != 0.0) for (c = c0; c < c1; ++c) ti[c] -= u * tk[c];
    }}
  }}
}}

/* one stage: kx = rhs(x, w), K = [Z_v; M^-1 (g_x Z + [0 | g_p])]; Z, K (nx rows of VND) */
static int v_stage{sfx}(const double* x, const double* Z, const double* wv, double* kx, double* K, double* Mb,
                   double* gx, double* gp, double* Uf, double* D, const casadi_real** arg, casadi_real** res,
                   casadi_int* iw, casadi_real* w) {{
  int r, i, c, c0;
  arg[0] = x; arg[1] = wv; res[0] = kx; res[1] = Mb; res[2] = gx; res[3] = gp;
  if (alpes_vterms(arg, res, iw, w, 0)) return 1;
  memcpy(K, Z + VN * VND, sizeof(double) * VN * VND);
  v_udu{sfx}(Mb, Uf, D);
  for (c0 = 0; c0 < VND; c0 += VCB) {{  /* the directions by blocks that stay in the first-level cache */
    int c1 = c0 + VCB < VND ? c0 + VCB : VND;
    for (r = 0; r < VN; ++r) {{
      double* t = K + (VN + r) * VND;
      for (c = c0; c < c1; ++c) t[c] = 0.0;
      for (i = 0; i < VNX; ++i) {{
        double g = gx[r + VN * i];
        const double* zi = Z + i * VND;
        if (g != 0.0) for (c = c0; c < c1; ++c) t[c] += g * zi[c];
      }}
      for (c = c0 > VNX ? c0 : VNX; c < c1; ++c) t[c] += gp[r + VN * (v_live{sfx}[c] - VNX)];
    }}
    v_solve{sfx}(Uf, D, K + VN * VND, c0, c1);
  }}
  return 0;
}}

static int alpes_step{sfx}(const casadi_real** arg0, casadi_real** res0, casadi_int* iw, casadi_real* w, int mem) {{
  const casadi_real* arg[VSZ_ARG];
  casadi_real* res[VSZ_RES];
  double* Z = w + VSZ_WF;
  double* Zs = Z + VNX * VND;
  double* K1 = Zs + VNX * VND;
  double* K2 = K1 + VNX * VND;
  double* K3 = K2 + VNX * VND;
  double* K4 = K3 + VNX * VND;
  double* xb = K4 + VNX * VND;
  double *xs = xb + VNX, *k1 = xs + VNX, *k2 = k1 + VNX, *k3 = k2 + VNX, *k4 = k3 + VNX;
  double *Mb = k4 + VNX, *gx = Mb + VN * VN, *gp = gx + VN * VNX, *Uf = gp + VN * (VNP > 0 ? VNP : 1);
  double* D = Uf + VN * VN;
  const double* z0 = arg0[0];
  const double* wv = arg0[1];
  double* out = res0[0];
  int i, c, s, m = VNX * VND;
  for (i = 0; i < VNX; ++i) xb[i] = z0[i];
  for (i = 0; i < VNX; ++i) for (c = 0; c < VND; ++c)
    Z[i * VND + c] = VSEED ? (double) (v_live{sfx}[c] == i) : z0[VNX + i + VNX * v_live{sfx}[c]];
  for (s = 0; s < VSUB; ++s) {{
    if (v_stage{sfx}(xb, Z, wv, k1, K1, Mb, gx, gp, Uf, D, arg, res, iw, w)) return 1;
    for (i = 0; i < VNX; ++i) xs[i] = xb[i] + v_h2{sfx} * k1[i];
    for (i = 0; i < m; ++i) Zs[i] = Z[i] + v_h2{sfx} * K1[i];
    if (v_stage{sfx}(xs, Zs, wv, k2, K2, Mb, gx, gp, Uf, D, arg, res, iw, w)) return 1;
    for (i = 0; i < VNX; ++i) xs[i] = xb[i] + v_h2{sfx} * k2[i];
    for (i = 0; i < m; ++i) Zs[i] = Z[i] + v_h2{sfx} * K2[i];
    if (v_stage{sfx}(xs, Zs, wv, k3, K3, Mb, gx, gp, Uf, D, arg, res, iw, w)) return 1;
    for (i = 0; i < VNX; ++i) xs[i] = xb[i] + v_h{sfx} * k3[i];
    for (i = 0; i < m; ++i) Zs[i] = Z[i] + v_h{sfx} * K3[i];
    if (v_stage{sfx}(xs, Zs, wv, k4, K4, Mb, gx, gp, Uf, D, arg, res, iw, w)) return 1;
    for (i = 0; i < VNX; ++i) xb[i] = xb[i] + v_h6{sfx} * (((k1[i] + 2.0 * k2[i]) + 2.0 * k3[i]) + k4[i]);
    for (i = 0; i < m; ++i) Z[i] = Z[i] + v_h6{sfx} * (((K1[i] + 2.0 * K2[i]) + 2.0 * K3[i]) + K4[i]);
  }}
  for (i = 0; i < VNX; ++i) out[i] = xb[i];
  memset(out + VNX, 0, sizeof(double) * VNX * VNDALL);
  for (i = 0; i < VNX; ++i) for (c = 0; c < VND; ++c) out[VNX + i + VNX * v_live{sfx}[c]] = Z[i * VND + c];
  return 0;
}}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC pop_options
#endif
#undef VNX
#undef VND
#undef VNDALL
#undef VSEED
"""

_SECOND = """
/* ---- the second step's driver: its own names ---- */
#undef NX
#undef NW
#undef SZ_ARG
#undef SZ_RES
#undef SZ_IW
#undef SZ_W
#undef LANES
#define alpes_job alpes_job_x
#define alpes_run alpes_run_x
#define alpes_worker alpes_worker_x
#define alpes_rollout alpes_rollout_x
"""


class VariationalStepLoop(CompiledStepLoop):
    """:class:`~alpes_dyn.simulation.codegen.CompiledStepLoop` of ``substeps`` RK4 steps of x = [q; v], x' = [v;
    M^-1 r] with the sensitivities X = dx/d(x_0, p) (nx, nd), the stage's linear algebra written out in C (module
    doc): the step ``([x; vec X], w) -> [x+; vec X+]`` of :func:`~alpes_dyn.simulation.variational.repeated_step`
    over :func:`~alpes_dyn.simulation.variational.looped_variational_rk4_step` (``seeded``: of
    :func:`~alpes_dyn.simulation.variational.sample_jacobian_step` over it), its numbers to rounding, its states bit
    for bit.

    Parameters
    ----------
    rhs : casadi.SX
        (2n,) [v; qdd] in ``x`` and ``w`` (the plain step's expression).
    M, r : casadi.SX
        (n, n) and (n,): M qdd = r, in ``x`` and ``w``.
    x, w : casadi.SX
        The state (2n,) and the input held over the step (a column of symbols).
    p : casadi.SX
        (np,) the directions' parameters, a subvector of ``w`` (0 x 1: the initial state's directions alone).
    h : float
        The RK4 step, s.
    substeps : int
        RK4 steps per call (the sample period's).
    seeded : bool
        True: the directions start from [I | 0] at every call, the input's X unread (each period's own Jacobian);
        False: from the input's X.
    label : str
        Stem of the cached library's file name.
    threads : int or None, optional
        Worker threads, 1 to 64 (default None: the CPUs this process may use).
    state : bool, optional
        True: the loop of the start state's directions alone (X (nx, nx), from the input's; the same library as
        the loop of all the directions of the same arguments: one build for both); default False.

    Attributes
    ----------
    live : numpy.ndarray
        The directions computed (the others' columns of g_p are structurally zero: written as zeros).
    """

    def __init__(self, rhs: cs.SX, M: cs.SX, r: cs.SX, x: cs.SX, w: cs.SX, p: cs.SX, h: float, substeps: int,
                 seeded: bool, label: str, threads: int | None = None, state: bool = False) -> None:
        nx, n, np_all = x.numel(), M.size1(), p.numel()
        a = cs.SX.sym("a", n)
        g = r - cs.mtimes(M, a)
        gp = cs.jacobian(g, p)
        gp_cols = np.diff(np.asarray(gp.sparsity().colind())) > 0 if np_all else np.zeros(0, dtype=bool)
        self.live = np.r_[np.arange(nx), nx + np.flatnonzero(gp_cols)].astype(int)
        # one function: rhs (the plain step's expression, its operations unchanged) and M, g_x, g_p at a = qdd,
        # sharing M and r with rhs (common subexpressions: the same operations once)
        terms = cs.substitute([cs.densify(M), cs.densify(cs.jacobian(g, x)), cs.densify(gp)], [a], [rhs[n:]])
        f = cs.Function("alpes_vterms", [x, w], cs.cse([rhs] + list(terms)))
        cg = cs.CodeGenerator("alpes_vstep.c", {"with_header": False})
        cg.add(f)
        nd_all, nd = nx + np_all, len(self.live)
        sz_w = f.sz_w() + 6 * nx * nd + 6 * nx + 2 * n * n + n * nx + n * max(np_all, 1) + n
        sizes = f"#define VSZ_ARG {f.sz_arg()}\n#define VSZ_RES {f.sz_res()}\n#define VSZ_WF {f.sz_w()}\n"
        common = dict(n=n, nx=nx, np_all=np_all, substeps=int(substeps), h=float(h).hex(), h2=(0.5 * h).hex(),
                      h6=(h / 6.0).hex())
        # two steps in one library: all the directions, and the start state's alone (the same terms, one build)
        steps = (_STEP.format(sfx="", nd=nd, nd_all=nd_all, seed=int(bool(seeded)),
                              live=", ".join(str(int(c)) for c in self.live), **common)
                 + _STEP.format(sfx="_x", nd=nx, nd_all=nx, seed=0, live=", ".join(map(str, range(nx))), **common))
        fmt = dict(nw=int(w.numel()), sz_arg=2, sz_res=1, sz_iw=f.sz_iw(), sz_w=sz_w, parg="", lanes=1,
                   vector_code="")
        source = ("#define _GNU_SOURCE\n" + cg.dump() + sizes + steps
                  + _DRIVER.format(nx=nx + nx * nd_all, step="alpes_step", **fmt) + _SECOND
                  + _DRIVER.format(nx=nx + nx * nx, step="alpes_step_x", **fmt))
        self.state = bool(state)
        self.nx, self.nw = nx + nx * (nx if self.state else nd_all), int(w.numel())
        self.threads = _check_threads(threads)
        self.parameters, self.lanes = np.zeros(0), 1
        self.library, self.compiled, self.compile_seconds, self._lib = _build_library(source, label)
        fn = self._lib.alpes_rollout_x if self.state else self._lib.alpes_rollout
        dp = ctypes.POINTER(ctypes.c_double)
        fn.argtypes = [dp, dp, dp, ctypes.c_long, ctypes.c_long, ctypes.c_long, ctypes.c_long, ctypes.c_int]
        fn.restype = ctypes.c_int
        self._fn, self._dp = fn, dp
        self._pp = self.parameters.ctypes.data_as(dp)
        self._one = None
