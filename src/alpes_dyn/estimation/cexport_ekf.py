"""The EKF's step as C with its covariance arithmetic written out as loops (issue 20, item 3).

:func:`~alpes_dyn.estimation.cexport.c_sources` exports the EKF this way (``code="sparse"``). CasADi generates
the code of the model alone -- the RK4 step z_next = F(z, w), its Jacobian A = dF/dz (sparse, CSC) and the
noise's share N = G Sigma_w G^T + Q (its lower triangle, G = dF/dw), the filter's
:attr:`~alpes_dyn.estimation.observers.ExtendedKalmanFilter.linearized`; the measurement h(z) and H = dh/dz,
its :attr:`~alpes_dyn.estimation.observers.KalmanFilter.measurement`. The covariance arithmetic is C loops over
the nonzeros of A and H in the order of operations of :mod:`alpes_dyn.estimation.covariance`, the order in
which the filter's own step (``filter_step``, what ``run``, ``online`` and the compiled loop evaluate) is built:
the same operations, the same numbers, to the last bit. The loops skip the products by an exact zero of P, of
P H^T or of K (they add a zero: the sign of a zero aside, nothing changes): a hand whose prior is block-diagonal
by chain keeps a block-diagonal P, and most of the products are such zeros.

Why: CasADi's expression of the whole step is straight-line code of every scalar operation of the dense
nz x nz covariance algebra (the hand: 134,000 operations, a 2.3 MB program, 44 us per step); the model's code
is 41,000 operations and the loops a few kilobytes. ``benchmarks/observer_step.py`` measures both.

Bit for bit needs the C compiler's IEEE arithmetic as written: no ``-ffast-math``, and no contraction of a
multiply and an add into one (``-std=c99``, or ``-ffp-contract=off`` on targets with a fused multiply-add).
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from .observers import ExtendedKalmanFilter

__all__ = ["ekf_c_source"]

_ARITHMETIC = r"""
/* ---- alpes_dyn: the EKF's covariance arithmetic (P column-major, P[i + NZ*j]), in the order of
   alpes_dyn.estimation.covariance: the filter's own step, operation for operation ---- */
#include <math.h>
#include <string.h>
#include "{prefix}.h"

#define NZ {P}_NZ
#define NW {P}_NW
#define NY {P}_NY

/* the sparsity (CSC) of A = dF/dz (NZ x NZ), of N, the lower triangle of G Sigma_w G^T + Q (NZ x NZ), and of
   H = dh/dz (NY x NZ) */
static const int A_colind[NZ + 1] = {{{A_colind}}};
static const int A_row[{A_nnz}] = {{{A_row}}};
static const int N_colind[NZ + 1] = {{{N_colind}}};
static const int N_row[{N_nnz}] = {{{N_row}}};
static const int H_colind[NZ + 1] = {{{H_colind}}};
static const int H_row[{H_nnz}] = {{{H_row}}};
/* the measurement noise R (NY x NY, column-major) */
static const double R[NY * NY] = {{{R}}};

/* Pp (lower triangle) = A P A^T + N: T = A P (T[i,j] += A[i,k] P[k,j], k ascending), then Pp[i,j] += T[i,k]
   A[j,k], k ascending, then + N[i,j] */
static void predict_covariance(const double* A, const double* P, const double* N, double* T, double* Pp) {{
  int i, j, k, a;
  memset(T, 0, sizeof(double) * NZ * NZ);
  memset(Pp, 0, sizeof(double) * NZ * NZ);
  for (j = 0; j < NZ; ++j)
    for (k = 0; k < NZ; ++k) {{
      const double m = P[k + NZ * j];
      if (m == 0.0) continue; /* adds zeros (the sign of a zero aside): P's blocks, e.g. a hand's chains */
      for (a = A_colind[k]; a < A_colind[k + 1]; ++a) T[A_row[a] + NZ * j] += A[a] * m;
    }}
  for (k = 0; k < NZ; ++k)
    for (a = A_colind[k]; a < A_colind[k + 1]; ++a) {{
      const double v = A[a];
      const double* t = T + NZ * k;
      double* o = Pp + NZ * A_row[a];
      for (i = A_row[a]; i < NZ; ++i) o[i] += t[i] * v;
    }}
  for (j = 0; j < NZ; ++j)
    for (a = N_colind[j]; a < N_colind[j + 1]; ++a) Pp[N_row[a] + NZ * j] += N[a];
}}

static void mirror_lower(double* P) {{
  int i, j;
  for (j = 0; j < NZ; ++j)
    for (i = j + 1; i < NZ; ++i) P[j + NZ * i] = P[i + NZ * j];
}}

/* C = B H^T (NZ x NY), B (NZ x NZ): C[i,r] += B[i,k] H[r,k], k ascending */
static void times_Ht(const double* B, const double* H, double* C) {{
  int i, k, a;
  memset(C, 0, sizeof(double) * NZ * NY);
  for (k = 0; k < NZ; ++k)
    for (a = H_colind[k]; a < H_colind[k + 1]; ++a) {{
      double* c = C + NZ * H_row[a];
      const double* b = B + NZ * k;
      const double v = H[a];
      for (i = 0; i < NZ; ++i) c[i] += b[i] * v;
    }}
}}

/* K = PHt S^-1 (NZ x NY): a division when NY = 1, else S = L L^T (in place, lower) and two substitutions per
   row of K; 1 if S is not positive definite */
static int gain(const double* PHt, double* S, double* K) {{
  int i, j, k, r;
  if (NY == 1) {{
    for (i = 0; i < NZ; ++i) K[i] = PHt[i] / S[0];
    return !(S[0] > 0.0);
  }}
  for (j = 0; j < NY; ++j) {{
    double d = S[j + NY * j];
    for (k = 0; k < j; ++k) d = d - S[j + NY * k] * S[j + NY * k];
    if (!(d > 0.0)) return 1;
    S[j + NY * j] = sqrt(d);
    for (i = j + 1; i < NY; ++i) {{
      double s = S[i + NY * j];
      for (k = 0; k < j; ++k) s = s - S[i + NY * k] * S[j + NY * k];
      S[i + NY * j] = s / S[j + NY * j];
    }}
  }}
  for (i = 0; i < NZ; ++i) {{
    for (r = 0; r < NY; ++r) {{
      double s = PHt[i + NZ * r];
      for (k = 0; k < r; ++k) s = s - S[r + NY * k] * K[i + NZ * k];
      K[i + NZ * r] = s / S[r + NY * r];
    }}
    for (r = NY - 1; r >= 0; --r) {{
      double s = K[i + NZ * r];
      for (k = r + 1; k < NY; ++k) s = s - S[k + NY * r] * K[i + NZ * k];
      K[i + NZ * r] = s / S[r + NY * r];
    }}
  }}
  return 0;
}}

#define UPD_W (NY + {H_nnz} + 3 * NZ * NY + NY * NY + NZ * NZ)

/* the measurement update of (z, P) with y into (z_out, P_out) (they may be z and P); w: UPD_W doubles then
   the generated code's work */
static int update_into(const double* z, const double* P, const double* y, double* z_out, double* P_out,
                       double* w) {{
  const casadi_real* arg[{meas_arg}];
  casadi_real* res[{meas_res}];
  casadi_int iw[{meas_iw} + 1];
  double* h = w;
  double* H = h + NY;
  double* PHt = H + {H_nnz}; /* NZ x NY */
  double* K = PHt + NZ * NY; /* NZ x NY */
  double* D = K + NZ * NY;   /* NZ x NY: K R - M H^T */
  double* S = D + NZ * NY;   /* NY x NY */
  double* M = S + NY * NY;   /* NZ x NZ */
  int i, j, k, r, a;
  arg[0] = z;
  res[0] = h;
  res[1] = H;
  if ({prefix}_cs_meas(arg, res, iw, M + NZ * NZ, 0)) return 1;
  times_Ht(P, H, PHt);
  memcpy(S, R, sizeof(double) * NY * NY); /* S = R + H (P H^T) */
  for (k = 0; k < NZ; ++k)
    for (a = H_colind[k]; a < H_colind[k + 1]; ++a)
      for (j = 0; j < NY; ++j) S[H_row[a] + NY * j] += H[a] * PHt[k + NZ * j];
  if (gain(PHt, S, K)) return 1; /* S not positive definite: the filter diverged */
  for (r = 0; r < NY; ++r) {{ /* z + K (y - h) */
    const double e = y[r] - h[r];
    for (i = 0; i < NZ; ++i) z_out[i] = (r ? z_out[i] : z[i]) + K[i + NZ * r] * e;
  }}
  for (j = 0; j < NZ; ++j) {{ /* M = (I - K H) P = P - K (P H^T)^T: its lower triangle and H's columns (the rest
                                  is not used) */
    const int i0 = H_colind[j + 1] > H_colind[j] ? 0 : j;
    memcpy(M + NZ * j + i0, P + NZ * j + i0, sizeof(double) * (NZ - i0));
    for (r = 0; r < NY; ++r) {{
      const double c = PHt[j + NZ * r];
      if (c == 0.0) continue; /* zeros: measurements of other chains */
      for (i = i0; i < NZ; ++i) M[i + NZ * j] = M[i + NZ * j] - K[i + NZ * r] * c;
    }}
  }}
  times_Ht(M, H, D); /* D = K R - M H^T */
  for (r = 0; r < NY; ++r)
    for (i = 0; i < NZ; ++i) {{
      double s = 0.0;
      for (k = 0; k < NY; ++k)
        if (R[k + NY * r] != 0.0) s = s + K[i + NZ * k] * R[k + NY * r];
      D[i + NZ * r] = s - D[i + NZ * r];
    }}
  for (j = 0; j < NZ; ++j) {{ /* P_out = M (I - K H)^T + K R K^T = M + (K R - M H^T) K^T, lower triangle */
    memcpy(P_out + NZ * j + j, M + NZ * j + j, sizeof(double) * (NZ - j));
    for (r = 0; r < NY; ++r) {{
      const double c = K[j + NZ * r];
      if (c == 0.0) continue;
      for (i = j; i < NZ; ++i) P_out[i + NZ * j] += D[i + NZ * r] * c;
    }}
  }}
  mirror_lower(P_out);
  return 0;
}}

int {prefix}_update(const double z[NZ], const double P[NZ * NZ], const double y[NY], double z_out[NZ],
                    double P_out[NZ * NZ], double work[{P}_NWORK]) {{
  return update_into(z, P, y, z_out, P_out, work);
}}

/* predict with w over the period, then update with y */
int {prefix}_step(const double z[NZ], const double P[NZ * NZ], const double w[NW], const double y[NY],
                  double z_out[NZ], double P_out[NZ * NZ], double work[{P}_NWORK]) {{
  const casadi_real* arg[{model_arg}];
  casadi_real* res[{model_res}];
  casadi_int iw[{model_iw} + 1];
  double* zp = work;
  double* Pp = zp + NZ;
  double* A = Pp + NZ * NZ;
  double* N = A + {A_nnz};
  double* T = N + {N_nnz}; /* scratch: NZ x NZ, the generated code's work, the update's */
  arg[0] = z;
  arg[1] = w;
  res[0] = zp;
  res[1] = A;
  res[2] = N;
  if ({prefix}_cs_model(arg, res, iw, T, 0)) return 1;
  predict_covariance(A, P, N, T, Pp);
  mirror_lower(Pp);
  return update_into(zp, Pp, y, z_out, P_out, T);
}}
"""


def _ints(a: Any) -> str:
    return ", ".join(str(int(x)) for x in a) or "0"


def _doubles(a: np.ndarray) -> str:
    return ", ".join(repr(float(x)) for x in np.asarray(a, float).reshape(-1, order="F"))


def ekf_c_source(filt: ExtendedKalmanFilter, prefix: str) -> tuple[str, int]:
    """The C source of ``filt``'s step and update (the API of :mod:`~alpes_dyn.estimation.cexport`) and the
    doubles of its work array: (source, nwork)."""
    nz, ny = filt.nz, filt.ny
    lin, meas = filt.linearized, filt.measurement  # the functions the filter's step calls
    fmodel = cs.Function(f"{prefix}_cs_model", lin.sx_in(), cs.cse(lin.call(lin.sx_in())))
    fmeas = cs.Function(f"{prefix}_cs_meas", meas.sx_in(), cs.cse(meas.call(meas.sx_in())))
    sA, sN, sH = fmodel.sparsity_out(1), fmodel.sparsity_out(2), fmeas.sparsity_out(1)
    cg = cs.CodeGenerator(f"{prefix}.c", {"with_header": False, "casadi_real": "double"})
    cg.add(fmodel)
    cg.add(fmeas)
    upd_w = ny + max(sH.nnz(), 1) + 3 * nz * ny + ny * ny + nz * nz + fmeas.sz_w()
    nwork = nz + nz * nz + max(sA.nnz(), 1) + max(sN.nnz(), 1) + max(nz * nz, fmodel.sz_w(), upd_w)
    text = _ARITHMETIC.format(
        prefix=prefix, P=prefix.upper(),
        A_colind=_ints(sA.colind()), A_row=_ints(sA.row()), A_nnz=max(sA.nnz(), 1),
        N_colind=_ints(sN.colind()), N_row=_ints(sN.row()), N_nnz=max(sN.nnz(), 1),
        H_colind=_ints(sH.colind()), H_row=_ints(sH.row()), H_nnz=max(sH.nnz(), 1),
        R=_doubles(filt.R),
        model_arg=fmodel.sz_arg(), model_res=fmodel.sz_res(), model_iw=fmodel.sz_iw(),
        meas_arg=fmeas.sz_arg(), meas_res=fmeas.sz_res(), meas_iw=fmeas.sz_iw())
    return cg.dump() + text, nwork
