"""The EKF's step as C with its covariance arithmetic written out as loops (issue 20, item 3).

:func:`~alpes_dyn.estimation.cexport.cexport.c_sources` exports the EKF this way (``code="sparse"``). The model -- the
RK4 step z_next = F(z, w), its Jacobian A = dF/dz (sparse, CSC) and the noise's share N = G Sigma_w G^T + Q (its
lower triangle, G = dF/dw), the
filter's :attr:`~alpes_dyn.estimation.observers.observers.ExtendedKalmanFilter.linearized` -- is CasADi's instructions
written out by block (:mod:`~alpes_dyn.estimation.cexport.cexport_chains`: the hand's four fingers side by side in
vector lanes, its thumb alone) or, where the model has one block (a finger) or ``chains=False``, CasADi's generated code
of it; the measurement h(z) and H = dh/dz, its
:attr:`~alpes_dyn.estimation.observers.observers.KalmanFilter.measurement`, is CasADi's code. The covariance arithmetic
is C loops over the nonzeros of A and H in the order of operations of :mod:`alpes_dyn.estimation.observers.covariance`,
the order in which the filter's own step (``filter_step_p``, what ``run``, ``online`` and the compiled loop evaluate) is
built: the same operations, the same numbers, to the last bit. Each sum accumulates in a register and is stored
once. The blocks: the states that A, N, H and R couple (the hand: its five chains); when P's entries between two
blocks are exact zeros (a prior diagonal or block-diagonal by chain; A P A^T + N and the update keep them so) the
loops run over each column's block only and write the rest as zeros -- sums of products by an exact zero, so the
sign of a zero aside nothing changes --, else over all rows. The products by an exact zero of P H^T or of K are
skipped likewise.

A model of several substeps per period (a friction model: :func:`~alpes_dyn.simulation.integrate.stable_substeps`)
is not written out substep by substep: :func:`~alpes_dyn.estimation.cexport.cexport_substeps.substep_model_source` loops over them and over each RK4 step's four
stages, composing A and G = dF/dw by the chain rule over CasADi's code of the right-hand side and its Jacobians
(a source many times smaller than the straight-line code of every substep, which takes the compiler minutes to
build); its numbers are the filter's to rounding, not bit for bit.

A looped filter (a large state, :mod:`~alpes_dyn.estimation.observers.looped`: the Shadow hand's 48) is exported
from CasADi's code of its looped model -- the right-hand side and its Jacobians once, the RK4 stages, substeps and
chain rule as loops -- never expanded into one expression; its numbers are the filter's to rounding.

Why: CasADi's expression of the whole step is straight-line code of every scalar operation of the dense
nz x nz covariance algebra (on the hand a program of megabytes); the model's code is one function of tens of
thousands of operations, and the loops a few kilobytes. ``benchmarks/observer_step.py`` measures the three codes:
the default, the loops on CasADi's code of the whole model (``chains=False``) and CasADi's code of the whole
step (``benchmarks/results/observer_step.json``).

Bit for bit needs the C compiler's IEEE arithmetic as written: no ``-ffast-math``, and no contraction of a
multiply and an add into one (``-std=c99``, or ``-ffp-contract=off`` on targets with a fused multiply-add); with
those, any optimisation level and ``-march`` give the same numbers (the hand's export at -O1, -O2, -O3 and
``-O1 -march=native`` printed the same estimates).
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from .cexport_chains import chain_model_source, components, model_blocks
from .cexport_substeps import _doubles, _ints, substep_model_source
from ..observers.observers import ExtendedKalmanFilter

__all__ = ["ekf_c_source"]

_ARITHMETIC = r"""
/* ---- alpes_dyn: the EKF's covariance arithmetic (P column-major, P[i + NZ*j]), in the order of
   alpes_dyn.estimation.observers.covariance: the filter's own step, operation for operation ---- */
#include <math.h>
#include <string.h>
#include "{prefix}.h"

#define NZ {P}_NZ
#define NW {P}_NW
#define NY {P}_NY

/* the sparsity (CSC) of A = dF/dz (NZ x NZ), of N, the lower triangle of G Sigma_w G^T + Q (NZ x NZ), and of
   H = dh/dz (NY x NZ); A's and H's rows (CSR: each row's columns ascending, and their entries' places in the CSC
   values) */
static const int A_rowptr[NZ + 1] = {{{A_rowptr}}};
static const int A_col[{A_nnz}] = {{{A_col}}};
static const int A_nz[{A_nnz}] = {{{A_nzs}}};
static const int N_colind[NZ + 1] = {{{N_colind}}};
static const int N_row[{N_nnz}] = {{{N_row}}};
static const int H_colind[NZ + 1] = {{{H_colind}}};
static const int H_row[{H_nnz}] = {{{H_row}}};
static const int H_rowptr[NY + 1] = {{{H_rowptr}}};
static const int H_col[{H_nnz}] = {{{H_col}}};
static const int H_nz[{H_nnz}] = {{{H_nzs}}};
/* the measurement noise R (NY x NY): its nonzeros by column (CSC) */
static const int R_colind[NY + 1] = {{{R_colind}}};
static const int R_row[{R_nnz}] = {{{R_row}}};
static const double R_val[{R_nnz}] = {{{R_val}}};
static const double R[NY * NY] = {{{R}}};

/* The blocks: the states that A, N, H and R couple (a hand: its chains); a P whose entries between two blocks
   are exact zeros keeps them (A P A^T + N and the update stay within the blocks), and its loops then run over
   the rows of each column's block only; any other P over all rows. */
#define NB {nb}
#define NOFF {noff}
static const int B_of[NZ] = {{{B_of}}};        /* each state's block */
static const int B_ptr[NB + 1] = {{{B_ptr}}};
static const int B_idx[NZ] = {{{B_idx}}};       /* the states of each block, ascending */
static const int ALL[NZ] = {{{ALL}}};
static const int Y_blk[NY] = {{{Y_blk}}};      /* each measurement's block (-1: it measures no state) */
static const int Y_ptr[NB + 1] = {{{Y_ptr}}};
static const int Y_idx[{ny1}] = {{{Y_idx}}};       /* the measurements of each block, ascending */
static const int ALL_Y[NY] = {{{ALL_Y}}};
static const int OFF[NOFF] = {{{OFF}}};         /* P's entries between two blocks (column-major places) */

/* 1 when every entry of P between two blocks is an exact zero (0 for a NaN) */
static int blocked(const double* P) {{
  int t, any = 0;
  if (NB < 2) return 0;
  for (t = 0; t < NOFF; ++t) any |= P[OFF[t]] != 0.0;
  return !any;
}}

/* the rows of a column j that may hold a nonzero: j's block if blk, else all; returns their number */
static inline int rows_of(int j, int blk, const int** rows) {{
  if (!blk) {{
    *rows = ALL;
    return NZ;
  }}
  *rows = B_idx + B_ptr[B_of[j]];
  return B_ptr[B_of[j] + 1] - B_ptr[B_of[j]];
}}

/* Every sum below runs in the order of alpes_dyn.estimation.observers.covariance (k ascending), accumulated in a register
   and stored once; with blk, the entries between two blocks, sums of exact zeros, are written as zeros (the
   sign of a zero aside, the same numbers). */

/* Pp (lower triangle) = A P A^T + N: T = A P (T[i,j] = sum over k of A[i,k] P[k,j], k ascending), then
   Pp[i,j] = sum over k of T[i,k] A[j,k], k ascending, then + N[i,j] */
static void predict_covariance(const double* A, const double* P, const double* N, double* T, double* Pp,
                               int blk) {{
  int i, j, t, n, a, b;
  const int* rows;
  if (blk) memset(Pp, 0, sizeof(double) * NZ * NZ);
  for (j = 0; j < NZ; ++j) {{
    const double* p = P + NZ * j;
    n = rows_of(j, blk, &rows);
    for (t = 0; t < n; ++t) {{
      double s = 0.0;
      i = rows[t];
      for (b = A_rowptr[i]; b < A_rowptr[i + 1]; ++b) s += A[A_nz[b]] * p[A_col[b]];
      T[i + NZ * j] = s;
    }}
  }}
  for (j = 0; j < NZ; ++j) {{
    double* o = Pp + NZ * j;
    n = rows_of(j, blk, &rows);
    for (t = 0; t < n; ++t) {{
      double s = 0.0;
      i = rows[t];
      if (i < j) continue;
      for (b = A_rowptr[j]; b < A_rowptr[j + 1]; ++b) s += T[i + NZ * A_col[b]] * A[A_nz[b]];
      o[i] = s;
    }}
    for (a = N_colind[j]; a < N_colind[j + 1]; ++a) o[N_row[a]] += N[a];
  }}
}}

/* the upper triangle of P from its lower one (with blk, within the blocks: the rest stays zero) */
static void mirror_lower(double* P, int blk) {{
  int i, j, t, n;
  const int* rows;
  for (j = 0; j < NZ; ++j) {{
    n = rows_of(j, blk, &rows);
    for (t = 0; t < n; ++t)
      if ((i = rows[t]) > j) P[j + NZ * i] = P[i + NZ * j];
  }}
}}

/* C = B H^T (NZ x NY), B (NZ x NZ): C[i,r] = sum over k of B[i,k] H[r,k], k ascending (with blk, the rows of
   r's block: the others are zeros) */
static void times_Ht(const double* B, const double* H, double* C, int blk) {{
  int i, r, b, t, n;
  const int* rows;
  if (blk) memset(C, 0, sizeof(double) * NZ * NY);
  for (r = 0; r < NY; ++r) {{
    if (!blk) {{
      rows = ALL;
      n = NZ;
    }} else if (Y_blk[r] < 0) {{
      continue;
    }} else {{
      rows = B_idx + B_ptr[Y_blk[r]];
      n = B_ptr[Y_blk[r] + 1] - B_ptr[Y_blk[r]];
    }}
    for (t = 0; t < n; ++t) {{
      double s = 0.0;
      i = rows[t];
      for (b = H_rowptr[r]; b < H_rowptr[r + 1]; ++b) s += B[i + NZ * H_col[b]] * H[H_nz[b]];
      C[i + NZ * r] = s;
    }}
  }}
}}

/* K = PHt S^-1 (NZ x NY): a division when NY = 1, else S = L L^T (in place, lower) and two substitutions per
   row of K (with blk, over the measurements of the row's block: K's other entries are zeros); 1 if S is not
   positive definite */
static int gain(const double* PHt, double* S, double* K, int blk) {{
  int i, j, k, r, t, u, n;
  const int* rr;
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
  if (blk) memset(K, 0, sizeof(double) * NZ * NY);
  for (i = 0; i < NZ; ++i) {{
    if (blk) {{
      rr = Y_idx + Y_ptr[B_of[i]];
      n = Y_ptr[B_of[i] + 1] - Y_ptr[B_of[i]];
    }} else {{
      rr = ALL_Y;
      n = NY;
    }}
    for (t = 0; t < n; ++t) {{
      double s = PHt[i + NZ * (r = rr[t])];
      for (u = 0; u < t; ++u) s = s - S[r + NY * rr[u]] * K[i + NZ * rr[u]];
      K[i + NZ * r] = s / S[r + NY * r];
    }}
    for (t = n - 1; t >= 0; --t) {{
      double s = K[i + NZ * (r = rr[t])];
      for (u = t + 1; u < n; ++u) s = s - S[rr[u] + NY * r] * K[i + NZ * rr[u]];
      K[i + NZ * r] = s / S[r + NY * r];
    }}
  }}
  return 0;
}}

#define UPD_W (NY + {H_nnz} + 3 * NZ * NY + NY * NY + NZ * NZ)

/* the measurement update of (z, P) with y into (z_out, P_out) (they may be z and P); w: UPD_W doubles then
   the generated code's work */
static int update_into(const double* z, const double* P, const double* y, double* z_out, double* P_out,
                       double* w, int blk) {{
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
  int i, j, k, r, a, t, n;
  const int* rows;
  arg[0] = z;
  res[0] = h;
  res[1] = H;
  if ({prefix}_cs_meas(arg, res, iw, M + NZ * NZ, 0)) return 1;
  times_Ht(P, H, PHt, blk);
  memcpy(S, R, sizeof(double) * NY * NY); /* S = R + H (P H^T) */
  for (k = 0; k < NZ; ++k)
    for (a = H_colind[k]; a < H_colind[k + 1]; ++a)
      for (j = 0; j < NY; ++j) S[H_row[a] + NY * j] += H[a] * PHt[k + NZ * j];
  if (gain(PHt, S, K, blk)) return 1; /* S not positive definite: the filter diverged */
  for (r = 0; r < NY; ++r) {{ /* z + K (y - h) */
    const double e = y[r] - h[r];
    for (i = 0; i < NZ; ++i) z_out[i] = (r ? z_out[i] : z[i]) + K[i + NZ * r] * e;
  }}
  if (blk) memset(M, 0, sizeof(double) * NZ * NZ);
  for (j = 0; j < NZ; ++j) {{ /* M = (I - K H) P = P - K (P H^T)^T: its lower triangle and H's columns (the rest
                                  is not used); M[i,j] = P[i,j] - K[i,r] PHt[j,r], r ascending, PHt's zeros skipped
                                  (measurements of other chains) */
    const int i0 = H_colind[j + 1] > H_colind[j] ? 0 : j;
    int rr[NY], nr = 0;
    double cr[NY];
    for (r = 0; r < NY; ++r)
      if (PHt[j + NZ * r] != 0.0) {{ rr[nr] = r; cr[nr++] = PHt[j + NZ * r]; }}
    n = rows_of(j, blk, &rows);
    for (t = 0; t < n; ++t) {{
      double s;
      i = rows[t];
      if (i < i0) continue;
      s = P[i + NZ * j];
      for (k = 0; k < nr; ++k) s = s - K[i + NZ * rr[k]] * cr[k];
      M[i + NZ * j] = s;
    }}
  }}
  times_Ht(M, H, D, blk); /* D = K R - M H^T (R's zeros skipped) */
  for (r = 0; r < NY; ++r)
    for (i = 0; i < NZ; ++i) {{
      double s = 0.0;
      for (a = R_colind[r]; a < R_colind[r + 1]; ++a) s = s + K[i + NZ * R_row[a]] * R_val[a];
      D[i + NZ * r] = s - D[i + NZ * r];
    }}
  if (blk) memset(P_out, 0, sizeof(double) * NZ * NZ); /* P is not read any more (P_out may be P) */
  for (j = 0; j < NZ; ++j) {{ /* P_out = M (I - K H)^T + K R K^T = M + (K R - M H^T) K^T, lower triangle:
                                  P_out[i,j] = M[i,j] + D[i,r] K[j,r], r ascending, K's zeros skipped */
    int rr[NY], nr = 0;
    double cr[NY];
    for (r = 0; r < NY; ++r)
      if (K[j + NZ * r] != 0.0) {{ rr[nr] = r; cr[nr++] = K[j + NZ * r]; }}
    n = rows_of(j, blk, &rows);
    for (t = 0; t < n; ++t) {{
      double s;
      i = rows[t];
      if (i < j) continue;
      s = M[i + NZ * j];
      for (k = 0; k < nr; ++k) s += D[i + NZ * rr[k]] * cr[k];
      P_out[i + NZ * j] = s;
    }}
  }}
  mirror_lower(P_out, blk);
  return 0;
}}

int {prefix}_update(const double z[NZ], const double P[NZ * NZ], const double y[NY], double z_out[NZ],
                    double P_out[NZ * NZ], double work[{P}_NWORK]) {{
  return update_into(z, P, y, z_out, P_out, work, blocked(P));
}}

/* predict with w over the period, then update with y */
int {prefix}_step_p(const double z[NZ], const double P[NZ * NZ], const double w[NW], const double y[NY],
                    const double p[{P}_NP], double z_out[NZ], double P_out[NZ * NZ], double work[{P}_NWORK]) {{
  const casadi_real* arg[{model_arg}];
  casadi_real* res[{model_res}];
  casadi_int iw[{model_iw} + 1];
  const int blk = blocked(P); /* then Pp is too */
  double* zp = work;
  double* Pp = zp + NZ;
  double* A = Pp + NZ * NZ;
  double* N = A + {A_nnz};
  double* T = N + {N_nnz}; /* scratch: NZ x NZ, the generated code's work, the update's */
  arg[0] = z;
  arg[1] = w;
  arg[2] = p;
  res[0] = zp;
  res[1] = A;
  res[2] = N;
  if ({prefix}_cs_model(arg, res, iw, T, 0)) return 1;
  predict_covariance(A, P, N, T, Pp, blk);
  mirror_lower(Pp, blk);
  return update_into(zp, Pp, y, z_out, P_out, T, blk);
}}
"""


def _rows(sp: cs.Sparsity) -> tuple[list[int], list[int], list[int]]:
    """A CSC sparsity by rows: (row pointers, each row's columns ascending, their places in the CSC values)."""
    colind, row = sp.colind(), sp.row()
    rows: list[list[tuple[int, int]]] = [[] for _ in range(sp.size1())]
    for k in range(sp.size2()):
        for a in range(colind[k], colind[k + 1]):
            rows[row[a]].append((k, a))
    ptr = [0]
    for r in rows:
        ptr.append(ptr[-1] + len(r))
    return ptr, [k for r in rows for k, _ in r], [a for r in rows for _, a in r]


def _blocks(sA: cs.Sparsity, sN: cs.Sparsity, sH: cs.Sparsity, R: np.ndarray) -> list[int]:
    """Each state's block: the connected components of the states that A, N, H (one measurement's states) and R
    (two measurements' states) couple, numbered by their first state."""
    nz = sA.size1()
    pairs = []
    for sp in (sA, sN):
        colind, row = sp.colind(), sp.row()
        pairs += [(row[a], k) for k in range(nz) for a in range(colind[k], colind[k + 1])]
    H_ptr, H_col, _ = _rows(sH)
    states = [H_col[H_ptr[r]:H_ptr[r + 1]] for r in range(sH.size1())]
    pairs += [(cols[0], k) for cols in states for k in cols[1:]]
    pairs += [(states[r1][0], states[r2][0]) for r1, r2 in zip(*np.nonzero(R)) if states[r1] and states[r2]]
    return components(nz, pairs)


def ekf_c_source(filt: ExtendedKalmanFilter, prefix: str, by_chain: bool = True) -> tuple[str, int]:
    """The C source of ``filt``'s step and update (the API of :mod:`~alpes_dyn.estimation.cexport.cexport`) and the
    doubles of its work array: (source, nwork). ``by_chain``: the model's code by block
    (:mod:`~alpes_dyn.estimation.cexport.cexport_chains`) where it has several, else CasADi's.

    Parameters
    ----------
    filt : ExtendedKalmanFilter
        The filter.
    prefix : str
        Starts every external symbol.
    by_chain : bool, optional
        The model's code by block where it has several (default True).

    Returns
    -------
    source : str
        The C source.
    nwork : int
        The doubles of its work array.
    """
    nz, ny = filt.nz, filt.ny
    lin, meas = filt.linearized_p, filt.measurement  # the functions the filter's step calls (p: the model's numbers)
    if filt.looped:  # a large state: CasADi's code of the looped model (estimation.observers.looped), never expanded
        fmodel = cs.Function(f"{prefix}_cs_model", lin.mx_in(), lin.call(lin.mx_in()))
        by_chain = False
    else:
        fmodel = cs.Function(f"{prefix}_cs_model", lin.sx_in(), cs.cse(lin.call(lin.sx_in())))
    fmeas = cs.Function(f"{prefix}_cs_meas", meas.sx_in(), cs.cse(meas.call(meas.sx_in())))
    sA, sN, sH = fmodel.sparsity_out(1), fmodel.sparsity_out(2), fmeas.sparsity_out(1)
    cg = cs.CodeGenerator(f"{prefix}.c", {"with_header": False, "casadi_real": "double"})
    chains = chain_model_source(fmodel, model_blocks(fmodel, nz), f"{prefix}_cs_model") if by_chain else None
    looped = substep_model_source(filt, f"{prefix}_cs_model") if chains is None else None
    if looped is not None:  # the model's substeps as a loop over one's code
        cg.add(looped[2])
        chains = looped[:2]
    if chains is None:
        cg.add(fmodel)
    cg.add(fmeas)
    model_w = fmodel.sz_w() if chains is None else chains[1]
    upd_w = ny + max(sH.nnz(), 1) + 3 * nz * ny + ny * ny + nz * nz + fmeas.sz_w()
    nwork = nz + nz * nz + max(sA.nnz(), 1) + max(sN.nnz(), 1) + max(nz * nz, model_w, upd_w)
    (A_ptr, A_col, A_nzs), (H_ptr, H_col, H_nzs) = _rows(sA), _rows(sH)
    R_cols = [[i for i in range(ny) if filt.R[i, j] != 0.0] for j in range(ny)]  # R's nonzeros by column
    R_row = [i for col in R_cols for i in col]
    R_vals = [float(filt.R[i, j]) for j, col in enumerate(R_cols) for i in col]
    block = _blocks(sA, sN, sH, np.asarray(filt.R))
    nb = max(block) + 1
    members = [[i for i in range(nz) if block[i] == b] for b in range(nb)]
    off = [i + nz * j for j in range(nz) for i in range(nz) if block[i] != block[j]]
    y_blk = [block[H_col[H_ptr[r]]] if H_ptr[r + 1] > H_ptr[r] else -1 for r in range(ny)]
    y_members = [[r for r in range(ny) if y_blk[r] == b] for b in range(nb)]
    text = _ARITHMETIC.format(
        prefix=prefix, P=prefix.upper(), nb=nb, noff=max(len(off), 1), B_of=_ints(block),
        B_ptr=_ints(np.cumsum([0] + [len(m) for m in members])), B_idx=_ints([i for m in members for i in m]),
        ALL=_ints(range(nz)), OFF=_ints(off), ALL_Y=_ints(range(ny)), ny1=max(ny, 1), Y_blk=_ints(y_blk),
        Y_ptr=_ints(np.cumsum([0] + [len(m) for m in y_members])), Y_idx=_ints([r for m in y_members for r in m]),
        A_nnz=max(sA.nnz(), 1),
        A_rowptr=_ints(A_ptr), A_col=_ints(A_col), A_nzs=_ints(A_nzs),
        H_rowptr=_ints(H_ptr), H_col=_ints(H_col), H_nzs=_ints(H_nzs),
        R_colind=_ints(np.cumsum([0] + [len(c) for c in R_cols])), R_row=_ints(R_row), R_nnz=max(len(R_row), 1),
        R_val=", ".join(repr(v) for v in R_vals) or "0.0",
        N_colind=_ints(sN.colind()), N_row=_ints(sN.row()), N_nnz=max(sN.nnz(), 1),
        H_colind=_ints(sH.colind()), H_row=_ints(sH.row()), H_nnz=max(sH.nnz(), 1),
        R=_doubles(filt.R),
        model_arg=fmodel.sz_arg(), model_res=fmodel.sz_res(), model_iw=fmodel.sz_iw(),
        meas_arg=fmeas.sz_arg(), meas_res=fmeas.sz_res(), meas_iw=fmeas.sz_iw())
    return cg.dump() + (chains[0] if chains is not None else "") + text, nwork

