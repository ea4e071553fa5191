"""The EKF's model over a period of several substeps as C loops (a friction model), for
:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`: :func:`substep_model_source`.

A friction model is predicted with :func:`~alpes_dyn.simulation.integrate.stable_substeps` RK4 steps per period (4 on
the fingers). CasADi's code of the filter's model writes each substep, and its forward-mode Jacobian, out in one
straight-line function (finger3's friction EKF: megabytes of C, minutes of the compiler: its time grows faster
than a function's size). Here the substeps are a loop, each RK4 step a loop over its four stages: the chain rule
composes A = dF/dz and G = dF/dw over CasADi's code of the right-hand side and its Jacobians (a source many times
smaller, built in about a second). The numbers are the filter's to rounding, not bit for bit: the sums run in another
order than CasADi's expression of the whole step.
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from ..observers.looped import stage_jacobians
from ..observers.observers import ExtendedKalmanFilter

__all__ = ["substep_model_source"]


def _ints(a: Any) -> str:
    """A C initializer list of integers ("0" for none)."""
    return ", ".join(str(int(x)) for x in a) or "0"


def _doubles(a: Any) -> str:
    """A C initializer list of an array's doubles, column-major (``repr``: read back exactly)."""
    return ", ".join(repr(float(x)) for x in np.asarray(a, float).reshape(-1, order="F"))


_SUBSTEPS = r"""
/* ---- alpes_dyn: the model over the period as {S} calls of one RK4 step and its Jacobians (the chain rule):
   z_s+1 = F(z_s, w), A = A_S ... A_1, B = sum over s of A_S ... A_s+1 B_s (A_s = dF/dz, B_s = dF/dw at z_s);
   N = the lower triangle of B Sigma_w B^T + Q. The code of one step (of its right-hand side for RK4), not of
   {S} unrolled: the build takes
   seconds, not minutes; the numbers are the filter's to rounding, not bit for bit. ---- */
#include <string.h>
static const double SUB_SW[{nw} * {nw}] = {{{Sw}}};
static const double SUB_Q[{nz} * {nz}] = {{{Q}}};
static const int SUB_A_colind[{nz} + 1] = {{{A_colind}}};
static const int SUB_A_row[{A_nnz}] = {{{A_row}}};
static const int SUB_N_colind[{nz} + 1] = {{{N_colind}}};
static const int SUB_N_row[{N_nnz}] = {{{N_row}}};

int {name}(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  const casadi_real* a[{g_arg}];
  casadi_real* r[{g_res}];
  double* zc = w;                       /* z_s */
  double* z1 = zc + {nz};                 /* z_s+1 */
  double* A1 = z1 + {nz};                 /* A_s, column-major */
  double* B1 = A1 + {nz} * {nz};          /* B_s */
  double* A = B1 + {nz} * {nw};           /* the product so far */
  double* B = A + {nz} * {nz};
  double* T = B + {nz} * {nw};            /* scratch: nz x max(nz, nw) */
  double* gw = T + {nz} * {nm};
  int s, i, j, k, l;
  (void) mem;
  memcpy(zc, arg[0], sizeof(double) * {nz});
  a[0] = zc;
  a[1] = arg[1];
  a[2] = arg[2];
  r[0] = z1;
  r[1] = A1;
  r[2] = B1;
  for (s = 0; s < {S}; ++s) {{
    if ({g}(a, r, iw, gw, 0)) return 1;
    memcpy(zc, z1, sizeof(double) * {nz});
    if (s == 0) {{
      memcpy(A, A1, sizeof(double) * {nz} * {nz});
      memcpy(B, B1, sizeof(double) * {nz} * {nw});
      continue;
    }}
    for (j = 0; j < {nz}; ++j) /* A = A_s A */
      for (i = 0; i < {nz}; ++i) {{
        double t = 0.0;
        for (k = 0; k < {nz}; ++k) t += A1[i + {nz} * k] * A[k + {nz} * j];
        T[i + {nz} * j] = t;
      }}
    memcpy(A, T, sizeof(double) * {nz} * {nz});
    for (j = 0; j < {nw}; ++j) /* B = A_s B + B_s */
      for (i = 0; i < {nz}; ++i) {{
        double t = B1[i + {nz} * j];
        for (k = 0; k < {nz}; ++k) t += A1[i + {nz} * k] * B[k + {nz} * j];
        T[i + {nz} * j] = t;
      }}
    memcpy(B, T, sizeof(double) * {nz} * {nw});
  }}
  if (res[0]) memcpy(res[0], zc, sizeof(double) * {nz});
  if (res[1])
    for (j = 0; j < {nz}; ++j)
      for (k = SUB_A_colind[j]; k < SUB_A_colind[j + 1]; ++k) res[1][k] = A[SUB_A_row[k] + {nz} * j];
  if (res[2]) {{
    for (l = 0; l < {nw}; ++l) /* T = B Sigma_w */
      for (i = 0; i < {nz}; ++i) {{
        double t = 0.0;
        for (k = 0; k < {nw}; ++k) t += B[i + {nz} * k] * SUB_SW[k + {nw} * l];
        T[i + {nz} * l] = t;
      }}
    for (j = 0; j < {nz}; ++j)
      for (k = SUB_N_colind[j]; k < SUB_N_colind[j + 1]; ++k) {{
        double t = SUB_Q[SUB_N_row[k] + {nz} * j];
        for (l = 0; l < {nw}; ++l) t += T[SUB_N_row[k] + {nz} * l] * B[j + {nz} * l];
        res[2][k] = t;
      }}
  }}
  return 0;
}}
"""


_RK4 = r"""
/* ---- alpes_dyn: one RK4 step x + h/6 (k1 + 2 k2 + 2 k3 + k4) of z' = f(z, w) and its Jacobians, by the chain rule
   through its four stages, each a call of CasADi's code of f and its Jacobians (dense, column-major) ---- */
#include <string.h>
static int {name}(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem) {{
  static const double C_NEXT[3] = {{{h2!r}, {h2!r}, {h!r}}};  /* x_s+1 = z + C_NEXT[s] k_s */
  static const double WEIGHT[4] = {{1.0, 2.0, 2.0, 1.0}};
  const double* z = arg[0];
  double* x = w;
  double* k = x + {nz};
  double* J = k + {nz};
  double* W = J + {nz} * {nz};
  double* dX = W + {nz} * {nw};   /* dx_s/dz */
  double* dXw = dX + {nz} * {nz}; /* dx_s/dw */
  double* dK = dXw + {nz} * {nw}; /* dk_s/dz */
  double* dKw = dK + {nz} * {nz}; /* dk_s/dw */
  double* S = dKw + {nz} * {nw};  /* the weighted sums of k, dk/dz, dk/dw */
  double* SA = S + {nz};
  double* SB = SA + {nz} * {nz};
  double* fw = SB + {nz} * {nw};
  const casadi_real* fa[{f_arg}];
  casadi_real* fr[{f_res}];
  int s, i, j, l;
  (void) mem;
  memcpy(x, z, sizeof(double) * {nz});
  fa[0] = x;
  fa[1] = arg[1];
  fa[2] = arg[2];
  fr[0] = k;
  fr[1] = J;
  fr[2] = W;
  for (s = 0; s < 4; ++s) {{
    if ({f}(fa, fr, iw, fw, 0)) return 1;
    for (j = 0; j < {nz}; ++j) /* dK = J dX */
      for (i = 0; i < {nz}; ++i) {{
        double t = 0.0;
        if (s == 0) t = J[i + {nz} * j];
        else for (l = 0; l < {nz}; ++l) t += J[i + {nz} * l] * dX[l + {nz} * j];
        dK[i + {nz} * j] = t;
      }}
    for (j = 0; j < {nw}; ++j) /* dKw = J dXw + W */
      for (i = 0; i < {nz}; ++i) {{
        double t = 0.0;
        if (s > 0) for (l = 0; l < {nz}; ++l) t += J[i + {nz} * l] * dXw[l + {nz} * j];
        dKw[i + {nz} * j] = s > 0 ? t + W[i + {nz} * j] : W[i + {nz} * j];
      }}
    for (i = 0; i < {nz}; ++i) S[i] = s == 0 ? k[i] : S[i] + WEIGHT[s] * k[i];
    for (i = 0; i < {nz} * {nz}; ++i) SA[i] = s == 0 ? dK[i] : SA[i] + WEIGHT[s] * dK[i];
    for (i = 0; i < {nz} * {nw}; ++i) SB[i] = s == 0 ? dKw[i] : SB[i] + WEIGHT[s] * dKw[i];
    if (s == 3) break;
    for (i = 0; i < {nz}; ++i) x[i] = z[i] + C_NEXT[s] * k[i];
    for (j = 0; j < {nz}; ++j)
      for (i = 0; i < {nz}; ++i) dX[i + {nz} * j] = (i == j ? 1.0 : 0.0) + C_NEXT[s] * dK[i + {nz} * j];
    for (i = 0; i < {nz} * {nw}; ++i) dXw[i] = C_NEXT[s] * dKw[i];
  }}
  for (i = 0; i < {nz}; ++i) res[0][i] = z[i] + {h6!r} * S[i];
  for (j = 0; j < {nz}; ++j)
    for (i = 0; i < {nz}; ++i) res[1][i + {nz} * j] = (i == j ? 1.0 : 0.0) + {h6!r} * SA[i + {nz} * j];
  for (i = 0; i < {nz} * {nw}; ++i) res[2][i] = {h6!r} * SB[i];
  return 0;
}}
"""


def _rk4_substep(dm: Any, nz: int, nw: int, name: str) -> tuple[str, int, int, int, cs.Function]:
    """One RK4 substep of ``dm`` with its Jacobians as C over CasADi's code of the right-hand side and its
    Jacobians: (source, its sz_arg, sz_res, doubles of work, the right-hand side's function)."""
    f = stage_jacobians(dm, f"{name}_rhs")
    h = dm.dt / dm.substeps
    text = _RK4.format(name=name, f=f.name(), nz=nz, nw=nw, h2=0.5 * h, h=h, h6=h / 6.0, f_arg=f.sz_arg(),
                       f_res=f.sz_res())
    return text, 3, 3, 3 * nz + 4 * nz * nz + 4 * nz * nw + f.sz_w(), f


def substep_model_source(filt: ExtendedKalmanFilter, name: str) -> tuple[str, int, cs.Function] | None:
    """C source of ``name(arg, res, iw, w, mem)``, the filter's ``linearized_p`` (z_next, A, N) as a loop over its
    model's RK4 substeps (the chain rule through CasADi's code of one substep and its Jacobians), the doubles of
    work it needs and that one substep's function (to add to the code generator); None with one substep.

    Parameters
    ----------
    filt : ExtendedKalmanFilter
        The filter (its model's substeps and their functions).
    name : str
        The C function's name.

    Returns
    -------
    tuple or None
        (source, doubles of work, the substep's casadi.Function), or None.
    """
    dm = filt.model
    if dm.substeps < 2 or getattr(dm, "substep_p", None) is None:
        return None
    nz, nw = filt.nz, filt.nw
    if getattr(dm, "rhs_p", None) is not None:  # RK4: its four stages over the code of the right-hand side
        rk4, g_arg, g_res, g_w, g = _rk4_substep(dm, nz, nw, f"{name}_sub")
        g_name = f"{name}_sub"
    else:  # CasADi's code of one substep (the stick law's) and its Jacobians
        g = stage_jacobians(dm, f"{name}_sub")
        rk4, g_arg, g_res, g_w, g_name = "", g.sz_arg(), g.sz_res(), g.sz_w(), g.name()
    sA, sN = filt.linearized_p.sparsity_out(1), filt.linearized_p.sparsity_out(2)
    nm = max(nz, nw)
    text = rk4 + _SUBSTEPS.format(
        name=name, g=g_name, S=dm.substeps, nz=nz, nw=nw, nm=nm, g_arg=g_arg, g_res=g_res,
        Sw=_doubles(filt.Sw), Q=_doubles(filt.Q), A_colind=_ints(sA.colind()), A_row=_ints(sA.row()),
        A_nnz=max(sA.nnz(), 1), N_colind=_ints(sN.colind()), N_row=_ints(sN.row()), N_nnz=max(sN.nnz(), 1))
    return text, 2 * nz + 2 * nz * nz + 2 * nz * nw + nz * nm + g_w, g
