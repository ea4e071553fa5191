"""A standalone C export of an observer's step (issue 20): C source, header and a test program, no Python.

:func:`c_sources` turns a :class:`~alpes_dyn.estimation.observers.observers.KalmanFilter` (the EKF, the UKF, with or
without their parameter states) into three texts:

* ``alpes_<kind>.h`` -- the documented, fixed-size API (sizes as macros, the model, dt and noise settings in
  its comment);
* ``alpes_<kind>.c`` -- the filter's own step
  (:attr:`~alpes_dyn.estimation.observers.observers.KalmanFilter.filter_step_p`, the expression that ``run``, ``online``
  and the compiled loop evaluate: the same numbers, to the last bit) and its measurement update, with the two
  functions below: for the EKF, the code of the model and its Jacobian (on the hand by chain, the fingers side by
  side in vector lanes: :mod:`~alpes_dyn.estimation.cexport.cexport_chains`; else CasADi's generated code) and the
  covariance arithmetic as loops over their nonzeros (:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`,
  ``code="sparse"``); for the UKF (or ``code="casadi"``), CasADi's generated code of the whole step. It needs
  only ``<math.h>`` and ``<string.h>`` (link with ``-lm``): no CasADi runtime, no heap, no global state;
* ``main.c`` -- a test program: reads a prior, a first measurement and lines of inputs and measurements,
  prints the estimate and its covariance after each sample (``%.17g``: they read back exactly), or times the
  step (``-t REPEAT``).

The API (``alpes_ekf`` for the EKF)::

    int alpes_ekf_update(const double z[NZ], const double P[NZ*NZ], const double y[NY],
                         double z_out[NZ], double P_out[NZ*NZ], double work[ALPES_EKF_NWORK]);
    int alpes_ekf_step(const double z[NZ], const double P[NZ*NZ], const double w[NW], const double y[NY],
                       double z_out[NZ], double P_out[NZ*NZ], double work[ALPES_EKF_NWORK]);
    int alpes_ekf_step_p(const double z[NZ], const double P[NZ*NZ], const double w[NW], const double y[NY],
                         const double p[ALPES_EKF_NP], double z_out[NZ], double P_out[NZ*NZ],
                         double work[ALPES_EKF_NWORK]);
    extern const double alpes_ekf_model_p[ALPES_EKF_NP];

``alpes_ekf_step`` is ``alpes_ekf_step_p`` with the exported model's numbers ``alpes_ekf_model_p`` (its masses,
inertias, lengths, springs, friction, ratios: one entry per use in its code, :mod:`alpes_dyn.symbolic.lifted`): the
code of a model of the same structure -- joints, transmission, effects, noise settings -- is the same but for
that array, so one build runs any of them given its array (``alpes_ekf_model_p`` of the file exported for it).

P column-major (it is symmetric); outputs may be the inputs (in place); 0 on success.

:func:`write_c_observer` writes them into a new directory, atomically (a temporary directory renamed).
:func:`scenario_filter` builds the observer of ``alpes-dyn estimate``'s scenario (its noise settings and
prior) for ``alpes-dyn codegen``. Build::

    cc -O2 -std=c99 -o alpes_ekf_main main.c alpes_ekf.c -lm

The lanes use GCC's and Clang's vector extensions, 2 doubles wide by default (SSE2 on any x86-64, NEON), 4 with
AVX (``-mavx``, ``-march=native`` on a machine that has it); ``-DALPES_NO_LANES`` (and any other compiler) runs
the fingers one after the other. All give the same numbers.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import casadi as cs
import numpy as np

from ...errors import InputError
from ...simulation.buildcache import expression_key
from ...fileio import check_output_directory, write_directory as write_sources  # their home: fileio
from .cexport_ekf import ekf_c_source
from ..observers.observers import ExtendedKalmanFilter, KalmanFilter

__all__ = ["c_sources", "write_c_observer", "write_sources", "check_output_directory", "scenario_filter",
           "read_main_output", "main_input", "compiled_c_step"]

_WRAPPERS = r"""
/* ---- alpes_dyn wrappers: the fixed-size API of {prefix}.h ---- */
#include <string.h>
#include "{prefix}.h"

#define NS ({P}_NZ + {P}_NZ * {P}_NZ)

/* the inputs are copied into work first: the outputs may be the inputs */
int {prefix}_step_p(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double w[{P}_NW],
                    const double y[{P}_NY], const double p[{P}_NP], double z_out[{P}_NZ],
                    double P_out[{P}_NZ * {P}_NZ], double work[{P}_NWORK]) {{
  const casadi_real* arg[{step_arg}];
  casadi_real* res[{step_res}];
  casadi_int iw[{step_iw} + 1];
  double* s = work;
  double* wy = s + NS;
  double* sn = wy + {P}_NW + {P}_NY;
  memcpy(s, z, sizeof(double) * {P}_NZ);
  memcpy(s + {P}_NZ, P, sizeof(double) * {P}_NZ * {P}_NZ);
  memcpy(wy, w, sizeof(double) * {P}_NW);
  memcpy(wy + {P}_NW, y, sizeof(double) * {P}_NY);
  arg[0] = s;
  arg[1] = wy;
  arg[2] = p;
  res[0] = sn;
  if ({prefix}_cs_step(arg, res, iw, sn + NS, 0)) return 1;
  memcpy(z_out, sn, sizeof(double) * {P}_NZ);
  memcpy(P_out, sn + {P}_NZ, sizeof(double) * {P}_NZ * {P}_NZ);
  return 0;
}}

int {prefix}_update(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double y[{P}_NY],
                    double z_out[{P}_NZ], double P_out[{P}_NZ * {P}_NZ], double work[{P}_NWORK]) {{
  const casadi_real* arg[{upd_arg}];
  casadi_real* res[{upd_res}];
  casadi_int iw[{upd_iw} + 1];
  double* zi = work;
  double* Pi = zi + {P}_NZ;
  double* yi = Pi + {P}_NZ * {P}_NZ;
  double* zo = yi + {P}_NY;
  double* Po = zo + {P}_NZ;
  memcpy(zi, z, sizeof(double) * {P}_NZ);
  memcpy(Pi, P, sizeof(double) * {P}_NZ * {P}_NZ);
  memcpy(yi, y, sizeof(double) * {P}_NY);
  arg[0] = zi;
  arg[1] = Pi;
  arg[2] = yi;
  res[0] = zo;
  res[1] = Po;
  if ({prefix}_cs_update(arg, res, iw, Po + {P}_NZ * {P}_NZ, 0)) return 1;
  memcpy(z_out, zo, sizeof(double) * {P}_NZ);
  memcpy(P_out, Po, sizeof(double) * {P}_NZ * {P}_NZ);
  return 0;
}}
"""

_HEADER = r"""/* {prefix}.h -- {title}, exported by alpes_dyn {version} (alpes-dyn codegen).

   {about}

   State z ({nz}): {names}
     (rad, rad/s{gain_units}). Known input w ({nw}): {inputs} (N m{force_units}), held over the sample
   period. Measurement y ({ny}): {outputs} (rad), at the end of the period.
   Sample period dt = {dt!r} s, {substeps} RK4 step(s) per period. The model's numbers (masses, inertias,
   lengths, springs, friction, ratios: {np} values, one per use in the model's code) are the array
   {prefix}_model_p, an input of {prefix}_step_p: the same code runs another model of the same structure (its
   joints, transmission and effects) given that model's array, from the {prefix}.c exported for it. The noise
   settings are compiled in:
     process noise Q (per step), diagonal: {Q}
     measurement noise R, diagonal: {R}
     input noise Sigma_w, diagonal: {Sw}
   Suggested prior (the estimation scenario's): z0 = {z0}, P0 = diag({P0}).

   Arrays are double; P is NZ x NZ, column-major (P[i + NZ*j] = P_ij; it is symmetric, so row-major reads
   the same). The outputs may be the inputs (in place). No heap, no global state, no CasADi runtime: the
   caller owns every buffer, work included; the functions are reentrant. Return 0 on success, 1 if the
   generated code failed (it does not: a non-finite estimate shows in z_out, check it) or, in the EKF's
   loops, if H P H^T + R is not positive definite (the filter diverged).

   A filter loop at the sample rate:
     double z[NZ] = z0, P[NZ*NZ] = P0, work[{P}_NWORK];
     {prefix}_update(z, P, y0, z, P, work);            y0: the first measurement, at t_0
     each sample k: {prefix}_step(z, P, w_k, y_k1, z, P, work);   w_k on [t_k, t_k+1), y_k1 at t_k+1
   Build: cc -O2 -c {prefix}.c (link with -lm); the test program: cc -O2 -o {prefix}_main main.c {prefix}.c -lm
*/
#ifndef {P}_H
#define {P}_H

#ifdef __cplusplus
extern "C" {{
#endif

#define {P}_NZ {nz}      /* states: joint angles, velocities{gain_word} */
#define {P}_NW {nw}      /* known inputs: motor torques{force_word} */
#define {P}_NY {ny}      /* measurements: motor encoder angles */
#define {P}_NWORK {nwork}  /* doubles of the work array */
#define {P}_DT {dt!r}  /* sample period, s */
#define {P}_NP {np}  /* the model's numbers, an input of the step */

/* The numbers of the model this file was exported for. */
extern const double {prefix}_model_p[{P}_NP];

/* Predict with w held over the period, then update with y measured at its end: one filter sample. */
int {prefix}_step(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double w[{P}_NW],
                  const double y[{P}_NY], double z_out[{P}_NZ], double P_out[{P}_NZ * {P}_NZ],
                  double work[{P}_NWORK]);

/* The same with the model's numbers p ({prefix}_step is {prefix}_step_p with p = {prefix}_model_p). */
int {prefix}_step_p(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double w[{P}_NW],
                    const double y[{P}_NY], const double p[{P}_NP], double z_out[{P}_NZ],
                    double P_out[{P}_NZ * {P}_NZ], double work[{P}_NWORK]);

/* The measurement update alone (for the first measurement y0, before any step). */
int {prefix}_update(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double y[{P}_NY],
                    double z_out[{P}_NZ], double P_out[{P}_NZ * {P}_NZ], double work[{P}_NWORK]);

#ifdef __cplusplus
}}
#endif
#endif
"""

_MAIN = r"""/* main.c -- test program of {prefix}.c (alpes-dyn codegen).

   {prefix}_main FILE|-              print z and P after each sample, one line each (z then P column-major)
   {prefix}_main -t REPEAT FILE|-    time the steps: run the record REPEAT times, print us per step (wall clock,
                                    and the process's processor time: what a loaded machine leaves to it)

   FILE: whitespace-separated numbers: z0 ({nz}), P0 ({nz}x{nz}, column-major), y0 ({ny}), then one sample per
   group: w ({nw}) y ({ny}) -- w held on [t_k, t_k+1), y measured at t_k+1. The first line printed is the prior
   updated with y0, then one line per sample (%.17g: the numbers read back exactly).
   Build: cc -O2 -o {prefix}_main main.c {prefix}.c -lm
*/
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "{prefix}.h"

#define NZ {P}_NZ
#define NW {P}_NW
#define NY {P}_NY

static int read_n(FILE* f, double* x, int n) {{
  int i;
  for (i = 0; i < n; ++i) if (fscanf(f, "%lf", &x[i]) != 1) return i;
  return n;
}}

static void print_state(const double* z, const double* P) {{
  int i;
  for (i = 0; i < NZ; ++i) printf(i ? " %.17g" : "%.17g", z[i]);
  for (i = 0; i < NZ * NZ; ++i) printf(" %.17g", P[i]);
  printf("\n");
}}

int main(int argc, char** argv) {{
  double z0[NZ], P0[NZ * NZ], y0[NY], z[NZ], P[NZ * NZ], work[{P}_NWORK];
  double* wy = 0;
  long n = 0, cap = 0, k, r, repeat = 0;
  int a = 1, got;
  FILE* f;
  if (argc > 2 && strcmp(argv[1], "-t") == 0) {{ repeat = atol(argv[2]); a = 3; }}
  if (argc != a + 1 || (a == 3 && repeat < 1)) {{
    fprintf(stderr, "usage: %s [-t REPEAT] FILE|-\n", argv[0]);
    return 2;
  }}
  f = strcmp(argv[a], "-") == 0 ? stdin : fopen(argv[a], "r");
  if (!f) {{ fprintf(stderr, "%s: cannot open %s\n", argv[0], argv[a]); return 2; }}
  if (read_n(f, z0, NZ) != NZ || read_n(f, P0, NZ * NZ) != NZ * NZ || read_n(f, y0, NY) != NY) {{
    fprintf(stderr, "%s: expected z0 (%d), P0 (%d) and y0 (%d) numbers\n", argv[0], NZ, NZ * NZ, NY);
    return 2;
  }}
  for (;;) {{ /* the samples, kept to time them without input and output */
    if (n == cap) {{
      double* more = realloc(wy, sizeof(double) * (NW + NY) * (cap = cap ? 2 * cap : 1024));
      if (!more) {{ fprintf(stderr, "%s: out of memory\n", argv[0]); return 2; }}
      wy = more;
    }}
    got = read_n(f, wy + n * (NW + NY), NW + NY);
    if (got == 0) break;
    if (got != NW + NY) {{
      fprintf(stderr, "%s: sample %ld: expected %d numbers\n", argv[0], n + 1, NW + NY);
      return 2;
    }}
    ++n;
  }}
  if (repeat == 0) {{
    if ({prefix}_update(z0, P0, y0, z, P, work)) return 1;
    print_state(z, P);
    for (k = 0; k < n; ++k) {{
      if ({prefix}_step(z, P, wy + k * (NW + NY), wy + k * (NW + NY) + NW, z, P, work)) return 1;
      print_state(z, P);
    }}
  }} else {{
    struct timespec t0, t1;
    double s;
    clock_t c0 = clock(), c1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeat; ++r) {{
      {prefix}_update(z0, P0, y0, z, P, work);
      for (k = 0; k < n; ++k) {prefix}_step(z, P, wy + k * (NW + NY), wy + k * (NW + NY) + NW, z, P, work);
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    c1 = clock();
    s = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
    printf("%ld steps x %ld: %.4f us per step, %.4f us of processor time (z[0] = %.17g)\n", n, repeat,
           1e6 * s / (n * repeat > 0 ? n * repeat : 1),
           1e6 * (double)(c1 - c0) / CLOCKS_PER_SEC / (n * repeat > 0 ? n * repeat : 1), z[0]);
  }}
  free(wy);
  return 0;
}}
"""


def _vec(a: np.ndarray) -> str:
    return "[" + ", ".join(f"{float(x):.6g}" for x in np.asarray(a).reshape(-1)) + "]"


def _diag_or_full(M: np.ndarray) -> str:
    if np.array_equal(M, np.diag(np.diag(M))):
        return _vec(np.diag(M))
    return "full matrix " + _vec(M) + " (column-major)"


def c_sources(filt: KalmanFilter, *, prefix: str | None = None, about: str = "",
              z0: Any = None, P0: Any = None, code: str | None = None, chains: bool | None = None) -> dict[str, str]:
    """The C export of ``filt``'s step: ``{"<prefix>.h": ..., "<prefix>.c": ..., "main.c": ...}``.

    See the module docstring for the API.

    Parameters
    ----------
    filt : KalmanFilter
        The filter exported.
    prefix : str or None, optional
        Starts every external symbol, a C identifier of at most 40 characters (default ``alpes_<kind>``:
        ``alpes_ekf``, ``alpes_ukf``).
    about : str, optional
        A line for the header's comment (the model, its parameter file).
    z0 : array_like, shape (nz,), optional
        The prior state it suggests (documentation only).
    P0 : array_like, shape (nz,) or (nz, nz), optional
        The prior covariance it suggests (documentation only).
    code : str or None, optional
        ``"sparse"`` -- CasADi's code of the model and its Jacobian, the covariance arithmetic as C loops over the
        nonzeros in the filter's own order of operations (:mod:`~alpes_dyn.estimation.cexport.cexport_ekf`; the
        EKF only, where CasADi folded no constant in that arithmetic, ``filt.exact_loops``); ``"casadi"`` --
        CasADi's code of the filter's whole step. Both give the filter's numbers to the last bit (but
        ``"sparse"`` on a model of several RK4 substeps per period, a friction model: its code loops over one
        substep, :func:`~alpes_dyn.estimation.cexport.cexport_substeps.substep_model_source`, the filter's
        numbers to rounding). Default (None): ``"sparse"`` for an EKF whose covariance arithmetic is large (over
        :data:`_LOOPS_FROM` operations: the hand) or whose model takes substeps (a friction model: CasADi's code
        of the whole step writes each substep out, a source that takes minutes to build), else ``"casadi"`` (a finger, the UKF).
    chains : bool or None, optional
        (``"sparse"`` only) the model's code by block, the blocks of one structure side by side
        (:mod:`~alpes_dyn.estimation.cexport.cexport_chains`: the hand's four fingers; the default, None, is True
        there); False: CasADi's code of the whole model.

    Returns
    -------
    dict of str to str
        File name -> its text.

    Raises
    ------
    InputError
        ``filt`` not a KalmanFilter, ``prefix`` not a C identifier, or ``code`` unknown or not applicable.
    """
    if not isinstance(filt, KalmanFilter):
        raise InputError(f"filt: expected a KalmanFilter, got {type(filt).__name__}")
    prefix = prefix or f"alpes_{filt.kind}"
    if not (prefix.isidentifier() and prefix.isascii() and len(prefix) <= 40):
        raise InputError(f"prefix: expected a C identifier of at most 40 characters, got {prefix!r}")
    ekf = isinstance(filt, ExtendedKalmanFilter)
    looped = ekf and filt.looped  # a large state: its model and covariance arithmetic as loops in either code
    code = ("sparse" if ekf and (looped or filt.exact_loops and (_covariance_operations(filt) > _LOOPS_FROM
                                                                 or filt.model.substeps > 1)) else "casadi") \
        if code is None else code
    if code not in ("sparse", "casadi"):
        raise InputError(f"code: expected 'sparse' or 'casadi', got {code!r}")
    if code == "sparse" and not ekf:
        raise InputError(f"code: 'sparse' is the EKF's; the {filt.kind} is exported as 'casadi'")
    if code == "sparse" and not filt.exact_loops and not looped:
        raise InputError("code: 'sparse' would round differently from the filter's step on this model (CasADi "
                         "folds constant products in it); use 'casadi'")
    if chains is not None and not isinstance(chains, bool):
        raise InputError(f"chains: expected True or False, got {chains!r}")
    if chains and code != "sparse":
        raise InputError("chains: the model's code by block is the 'sparse' code's; "
                         f"code {code!r} is CasADi's code of the whole step")
    body, nwork = (ekf_c_source(filt, prefix, by_chain=chains is not False) if code == "sparse"
                   else _whole_step_source(filt, prefix))
    P = prefix.upper()
    values = filt.model.values
    source = (f"/* {prefix}.c -- generated by alpes_dyn (alpes-dyn codegen); the API is in {prefix}.h */\n" + body
              + _MODEL_P.format(prefix=prefix, P=P, values=", ".join(repr(float(v)) for v in values) or "0.0"))
    header = _HEADER.format(prefix=prefix, P=P, **_header_fields(filt, about, nwork, z0, P0))
    main = _MAIN.format(prefix=prefix, P=P, nz=filt.nz, nw=filt.nw, ny=filt.ny)
    return {f"{prefix}.h": header, f"{prefix}.c": source, "main.c": main}


_MODEL_P = r"""
/* the numbers of the model exported (one per use in its code: what differs between models of one structure) */
const double {prefix}_model_p[{P}_NP] = {{{values}}};

int {prefix}_step(const double z[{P}_NZ], const double P[{P}_NZ * {P}_NZ], const double w[{P}_NW],
                  const double y[{P}_NY], double z_out[{P}_NZ], double P_out[{P}_NZ * {P}_NZ],
                  double work[{P}_NWORK]) {{
  return {prefix}_step_p(z, P, w, y, {prefix}_model_p, z_out, P_out, work);
}}
"""

_LOOPS_FROM = 5000
"""The EKF's default code is ``"sparse"`` when its covariance arithmetic takes more operations than this in the
filter's step (the hand: 30,000; finger3: 700, where CasADi's straight-line code of the whole step runs a little
faster than the loops). The default code's time per step: ``benchmarks/results/observer_step.json`` (its rows'
``c_us``)."""


def _covariance_operations(filt: ExtendedKalmanFilter) -> int:
    """The operations of the filter's step beyond its model's (the RK4 step, its Jacobian, the measurement)."""
    return filt.filter_step.n_instructions() - filt.linearized.n_instructions() - filt.measurement.n_instructions()


def _whole_step_source(filt: KalmanFilter, prefix: str) -> tuple[str, int]:
    """CasADi's code of the filter's own step and update with the API's wrappers: (source, nwork)."""
    step = filt.filter_step_p  # the model's numbers an input (run's and the compiled loop's step)
    upd = filt._update
    sym = (lambda f: f.mx_in()) if step.is_a("MXFunction") else (lambda f: f.sx_in())  # a looped step: its loops
    fstep = cs.Function(f"{prefix}_cs_step", sym(step), step.call(sym(step)))
    fupd = cs.Function(f"{prefix}_cs_update", sym(upd), upd.call(sym(upd)))
    cg = cs.CodeGenerator(f"{prefix}.c", {"with_header": False, "casadi_real": "double"})
    cg.add(fstep)
    cg.add(fupd)
    ns = filt.nz + filt.nz * filt.nz
    nwork = max(2 * ns + filt.nw + filt.ny + fstep.sz_w(), 2 * ns + filt.ny + fupd.sz_w())
    fmt = dict(prefix=prefix, P=prefix.upper(), step_arg=fstep.sz_arg(), step_res=fstep.sz_res(),
               step_iw=fstep.sz_iw(), upd_arg=fupd.sz_arg(), upd_res=fupd.sz_res(), upd_iw=fupd.sz_iw())
    return cg.dump() + _WRAPPERS.format(**fmt), nwork


def _header_fields(filt: KalmanFilter, about: str, nwork: int, z0: Any, P0: Any) -> dict[str, Any]:
    from ..._version import __version__

    ss = filt.model.system
    tr = ss.model.transmission
    motors = tuple(tr.motor_names) if tr is not None else ()
    params = filt.model.parameters
    inputs = ", ".join(f"tau_{m}" for m in motors) if ss.input == "motor" else f"{ss.n_inputs} joint torques"
    force = " and F_x, F_y, F_z (N)" if ss.force else ""
    outputs = ", ".join(f"encoder_{m}" for m in motors) if motors else f"{filt.ny} outputs"
    kind = {"ekf": "extended Kalman filter", "ukf": "unscented Kalman filter"}.get(filt.kind, filt.kind)
    return dict(
        title=f"{kind} of {ss.model.name} ({filt.kind} step in C)", version=__version__,
        about=(about or f"Model {ss.model.name}.").replace("*/", "* /"),
        nz=filt.nz, nw=filt.nw, ny=filt.ny, nwork=nwork, np=max(int(filt.model.values.size), 1), dt=float(filt.dt), substeps=filt.model.substeps,
        names=", ".join(filt.names), inputs=inputs + force, outputs=outputs,
        gain_units=", and the gains / disturbances " + ", ".join(params) if params else "",
        gain_word=f", then {len(params)} estimated parameter(s)" if params else "",
        force_units=", N" if ss.force else "", force_word=" then the contact force" if ss.force else "",
        Q=_diag_or_full(filt.Q), R=_diag_or_full(filt.R), Sw=_diag_or_full(filt.Sw),
        z0=_vec(z0) if z0 is not None else "(none given)", P0=_vec(P0) if P0 is not None else "(none given)")


def write_c_observer(filt: KalmanFilter, directory: str | os.PathLike[str], *, what: str = "-o",
                     **kwargs: Any) -> dict[str, Path]:
    """Write :func:`c_sources` into ``directory``, a new (or empty) directory (:func:`write_sources`).

    Parameters
    ----------
    filt : KalmanFilter
        The filter exported.
    directory : str or PathLike
        The folder.
    what : str, optional
        The option named in errors (the CLI's ``-o``).
    **kwargs
        Passed to :func:`c_sources`.

    Returns
    -------
    dict of str to Path
        {file name: path}."""
    check_output_directory(directory, what)
    return write_sources(c_sources(filt, **kwargs), directory, what)


def main_input(z0: Any, P0: Any, y0: Any, W: Any, Y: Any) -> str:
    """The text ``main.c`` reads: z0, P0 (variances (nz,) or (nz, nz), written column-major), y0, then w_k y_k+1 per
    sample (``repr``: read back exactly).

    Parameters
    ----------
    z0 : array_like, shape (nz,)
        The prior state.
    P0 : array_like, shape (nz,) or (nz, nz)
        The prior covariance (or its variances).
    y0 : array_like, shape (ny,)
        The first measurement.
    W : array_like, shape (N, nw)
        The known inputs w_k.
    Y : array_like, shape (N, ny)
        The measurements y_k+1.

    Returns
    -------
    str
    """
    P0 = np.asarray(P0, float)
    P0 = np.diag(P0) if P0.ndim == 1 else P0
    W, Y = np.asarray(W, float), np.asarray(Y, float)
    W = W.reshape(len(W), -1)
    Y = Y.reshape(len(Y), -1)
    lines = [" ".join(repr(float(x)) for x in np.asarray(z0, float).reshape(-1)),
             " ".join(repr(float(x)) for x in np.asarray(P0, float).reshape(-1, order="F")),
             " ".join(repr(float(x)) for x in np.asarray(y0, float).reshape(-1))]
    lines += [" ".join(repr(float(x)) for x in np.r_[w, y]) for w, y in zip(W, Y)]
    return "\n".join(lines) + "\n"


def read_main_output(text: str, nz: int) -> tuple[np.ndarray, np.ndarray]:
    """``main.c``'s printout as (Z (N+1, nz), P (N+1, nz, nz)).

    Parameters
    ----------
    text : str
        ``main.c``'s standard output.
    nz : int
        The state's length.

    Returns
    -------
    Z : numpy.ndarray, shape (N+1, nz)
        The estimates.
    P : numpy.ndarray, shape (N+1, nz, nz)
        Their covariances.

    Raises
    ------
    InputError
        A line is not nz + nz^2 numbers.
    """
    S = np.array([[float(x) for x in line.split()] for line in text.splitlines() if line.strip()])
    if S.ndim != 2 or S.shape[1] != nz + nz * nz:
        raise InputError(f"main.c output: expected lines of {nz + nz * nz} numbers, got shape {S.shape}")
    return S[:, :nz], S[:, nz:].reshape(len(S), nz, nz).transpose(0, 2, 1)


def scenario_filter(observer: str = "ekf", model: str = "finger3", *, params: Any = None, chain: str | None = None,
                    friction: bool = False, force: bool = False) -> tuple[KalmanFilter, np.ndarray, np.ndarray]:
    """The observer of the estimation scenario (:func:`~alpes_dyn.estimation.observers.scenario.run_estimation`, no
    mismatch) on ``model`` with the parameter file ``params``: (filter, z0, P0), its noise settings, substeps and
    prior those of the scenario (the same filter: tested against its estimate). A file marked not trustworthy:
    :class:`~alpes_dyn.ModelError` naming it unless ``force`` (:func:`~alpes_dyn.model.trust.check_trusted`).

    Parameters
    ----------
    observer : str, optional
        One of :data:`~alpes_dyn.estimation.observers.observers.OBSERVERS` (default ``"ekf"``).
    model : str, optional
        The scenario's model (default ``"finger3"``).
    params : HandParams, str, path or None, optional
        The parameter file (None: the shipped one).
    chain : str or None, optional
        The hand's chain (None: the model's own).
    friction : bool, optional
        The model with the file's friction (default False), in the file's law as ``estimate --data`` runs it
        (:func:`~alpes_dyn.simulation.stick.observer_friction_law`: ``lugre`` with the joints' bristles as the
        state's last entries, prior 0 and standard deviation F_s / sigma0, rad, and its split steps; ``creep`` solved
        in the dynamics of each RK4 substep).
    force : bool, optional
        Accept a file marked not trustworthy (default False).

    Returns
    -------
    filt : KalmanFilter
        The filter.
    z0 : numpy.ndarray, shape (nz,)
        The prior state.
    P0 : numpy.ndarray, shape (nz,)
        The prior variances.

    Raises
    ------
    InputError
        An unknown ``observer`` or a scenario that fails its check.
    """
    from ...model.params import load_params
    from ...model.trust import check_trusted
    from ...model.robot import Model
    from ...simulation.integrate import stable_substeps
    from ...symbolic.statespace import StateSpace
    from ..observers.observers import OBSERVERS, PARAMETERS, make_observer
    from ..observers.scenario import EstimationScenario, default_noise
    from ...model.friction import LuGre, lugre_of
    from ...simulation.lugre import lugre_substeps
    from ...simulation.stick import observer_friction_law

    if observer not in OBSERVERS:
        raise InputError(f"unknown observer {observer!r} (expected one of {', '.join(OBSERVERS)})")
    sc = EstimationScenario(model=model, friction=bool(friction), chain=chain)
    sc.check()
    p = load_params(params)
    check_trusted(p, force)
    m = Model.alpes(sc.model, spring=sc.spring, friction=sc.friction, params=p, chain=sc.chain)
    n, nm = m.n, m.transmission.n_motors
    step = 2 * np.pi / m.transmission.counts_per_rev
    meas_var = step**2 / 12 + (sc.encoder_noise_counts * step) ** 2
    pars = tuple(PARAMETERS) if observer.endswith("-params") else ()
    noise = default_noise(sc, n, nm, len(pars), meas_var)
    ss = StateSpace(m, input="motor", output="encoder")
    law = observer_friction_law(m) if sc.friction else "smooth"  # the file's law, as estimate's (lugre: bristles)
    substeps = lugre_substeps(m, lugre_of(m), sc.dt) if law == "lugre" else (
        max(sc.substeps, stable_substeps(m, sc.dt)) if sc.friction else 1)
    filt = make_observer(observer, ss, sc.dt, parameters=pars, substeps=substeps, friction_law=law, **noise)
    span = m.extras.coulomb[:filt.model.nb] / (lugre_of(m) or LuGre()).sigma0  # F_s / sigma0 (rad), as estimate's
    z0 = np.concatenate([np.zeros(2 * n), np.ones(len(pars)), np.zeros(span.size)])
    P0 = np.concatenate([[0.5**2] * n + [1.0**2] * n + [0.2**2] * len(pars), span**2])
    return filt, z0, P0


_LIBRARY_STEP = r"""
/* ---- alpes_dyn: the filter's step on its state s = [z; P (column-major)] and wy = [w; y], for ctypes ---- */
int alpes_library_step(const double* s, const double* wy, const double* p, double* out, double* work) {{
  return {prefix}_step_p(s, s + {P}_NZ, wy, wy + {P}_NW, p, out, out + {P}_NZ, work);
}}
"""


def compiled_c_step(filt: KalmanFilter, label: str, parameters: Any = None) -> Any:
    """(s, wy) -> s_next: ``filt``'s step from its C export (:func:`c_sources`, its default code), compiled once into
    a shared library in the cache (:func:`~alpes_dyn.simulation.buildcache.build_library`, ``-O2``) and called through
    ctypes; s = [z; P column-major] (nz + nz^2,), wy = [w; y]. The numbers of the exported C to the last bit; with
    substeps (a friction model) the C loops over one substep (seconds to build, where CasADi's code of the whole
    step, each substep written out, takes minutes).

    Parameters
    ----------
    filt : KalmanFilter
        The filter.
    label : str
        The cache entry's label.
    parameters : array_like, optional
        The model's numbers (default the filter's).

    Returns
    -------
    callable or None
        ``step(s, wy)`` -> s_next; None without a C compiler
        (:class:`~alpes_dyn.simulation.buildcache.CompilerError`).
    """
    import ctypes

    from ...simulation.codegen import _CFLAGS, _compiler, cache_dir
    from ...simulation.buildcache import CompilerError, build_library

    source, nwork = _library_source(filt)
    try:
        _, _, _, lib = build_library(source, label, _compiler(), ("-O2",) + _CFLAGS[1:], cache_dir())
    except CompilerError:
        return None
    fn = lib.alpes_library_step
    dp = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [dp, dp, dp, dp, dp]
    fn.restype = ctypes.c_int
    p = np.ascontiguousarray(filt.model.values if parameters is None else parameters, dtype=float)
    ns = filt.nz + filt.nz * filt.nz
    s_in, wy_in, out, work = np.empty(ns), np.empty(filt.nw + filt.ny), np.empty(ns), np.empty(max(nwork, 1))
    p = p if p.size else np.zeros(1)
    ptrs = [a.ctypes.data_as(dp) for a in (s_in, wy_in, p, out, work)]
    keep = (p, s_in, wy_in, out, work)  # the buffers live as long as the step

    def step(s: np.ndarray, wy: np.ndarray) -> np.ndarray:
        s_in[:] = s
        wy_in[:] = wy
        if fn(*ptrs) != 0 and keep:
            raise InputError("step: the compiled filter step failed (H P H^T + R not positive definite: the filter "
                             "diverged)")
        return out.copy()

    return step


_LIBRARY_SOURCES: dict[str, tuple[str, int]] = {}
""":func:`_library_source`'s sources by the filter's step serialised: filters of one structure (the hand's four
fingers, every step of a finger built in a process) generate the C once (about 0.5 s of CPU on finger3)."""


def _library_source(filt: KalmanFilter) -> tuple[str, int]:
    """(the C of :func:`compiled_c_step`'s library, its work size): ``filt``'s :func:`c_sources` with the model's
    numbers zeroed (an input: the library is its structure's, shared by every file of that structure). Kept by the
    key of its step ``filter_step_p`` (the model's numbers an input p; the noises, the substeps and the law are
    constants in it), serialised, as the observer blocks key their steps.

    Parameters
    ----------
    filt : KalmanFilter
        The filter.

    Returns
    -------
    tuple of (str, int)
        The library's C source and its work array's size (doubles).
    """
    key = type(filt).__name__ + expression_key(filt.filter_step_p)
    made = _LIBRARY_SOURCES.get(key)
    if made is None:
        prefix = "alpes_libstep"
        files = c_sources(filt, prefix=prefix)
        header, body = files[f"{prefix}.h"], files[f"{prefix}.c"]
        body = re.sub(rf"(const double {prefix}_model_p\[{prefix.upper()}_NP\] = {{)[^}}]*(}};)", r"\g<1>0.0\g<2>",
                      body)
        source = header + body.replace(f'#include "{prefix}.h"', "") + _LIBRARY_STEP.format(prefix=prefix,
                                                                                            P=prefix.upper())
        nwork = int(header.split(f"#define {prefix.upper()}_NWORK ")[1].split()[0])
        made = _LIBRARY_SOURCES[key] = (source, nwork)
    return made
