"""The whole force step in C: :meth:`ForceStep.step <alpes_dyn.control.step.ForceStep.step>` as standalone C, the
contact's surface normal an input of each call.

:func:`step_c_sources` writes, for a :class:`~alpes_dyn.control.step.ForceStep` (its model, parameter file,
controller, gains, compensation and noise settings compiled in):

* ``alpes_step.h`` / ``alpes_step.c`` -- the step: the encoder counts in rad, the compensation of the identified
  effects (the encoder's zero and the tendon's stretch C tau_m,k-1 off the reading, the command held as the
  observer's motor torque), the EKF's predict with the known input [tau_m, -F n] and its update
  (``alpes_step_ekf``), the sensorless estimate (``"sensorless"``), the controller with its tuned gains and the
  notch (``alpes_step_force``), in the order of the step's module docstring (:mod:`alpes_dyn.control.step`);
* ``alpes_step_ekf.h`` / ``alpes_step_ekf.c`` -- the observer's step,
  :func:`~alpes_dyn.estimation.cexport.cexport.c_sources` of the step's EKF (with the file's friction when the
  step's observer has it; none for ``"pi"``);
* ``alpes_step_force.h`` / ``alpes_step_force.c`` -- the controller,
  :func:`~alpes_dyn.control.cexport.controller_c_sources` of the step's controller;
* ``main.c`` -- a test program: reads one line of readings per tick (counts (NM), torque (NM), force, reference,
  normal (3)), prints per tick the command (NM), the EKF's estimate [q_hat; qd_hat] (NZ) and the force fed back
  (``%.17g``), or times the step (``-t REPEAT``).

The API (``alpes_step.h``)::

    void alpes_step_init(alpes_step_state* s);          /* the first sample: the finger at rest */
    int alpes_step(alpes_step_state* s, const double counts[ALPES_STEP_NM], const double torque[ALPES_STEP_NM],
                   double force, double reference, const double normal[3], double command[ALPES_STEP_NM],
                   double work[ALPES_STEP_NWORK]);

No heap, no global state, ``-lm`` only; the state (the estimate, its covariance, the controller's memory) is the
caller's. Build::

    cc -O2 -std=c99 -o alpes_step_main main.c alpes_step.c alpes_step_ekf.c alpes_step_force.c -lm

:func:`write_c_step` writes them into a new directory, atomically (a temporary directory renamed).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..estimation.cexport.cexport import c_sources, check_output_directory, write_sources
from ..estimation.cexport.cexport_substeps import _doubles  # a C initializer list, read back exactly
from .cexport import READ_ROWS_C, controller_c_sources
from .step import ForceStep
from .step_parts import StepParts

__all__ = ["step_c_sources", "write_c_step", "step_main_input", "step_state_row", "read_step_output", "C_STEP_BUILD",
           "STEP_ERRORS", "LOAD_STATE_C", "TIME_STEPS_C"]

C_STEP_BUILD = "cc -O2 -std=c99 -o alpes_step_main main.c alpes_step.c alpes_step_ekf.c alpes_step_force.c -lm"
"""The build of the test program (``alpes_step_ekf.c`` absent for ``"pi"``)."""

STEP_ERRORS: dict[int, str] = {
    1: "the generated code failed",
    2: "a reading is not finite (counts, torque, the force of the sensor and pi controllers, the reference) or the "
       "normal is zero or not finite",
    3: "the EKF diverged on the readings (joint estimate beyond 1e6 rad or rad/s, or not finite): check their units",
}
"""What ``alpes_step`` returns besides 0; the state is left as it was."""

_HEADER = r"""/* alpes_step.h -- the force step of {model} (alpes_dyn.control.step.ForceStep.step in C), exported by
   alpes_dyn {version} (alpes-dyn codegen --step).

   {about}

   One tick at dt = {dt!r} s, called once per tick with that tick's readings; its command is held over
   [t_k, t_k+1) -- the timing of ForceStep.step:
     counts (NM)      the motor encoders' counts at t_k ({cpr} per revolution);
     torque (NM)      the motor torque the current sensor reports at t_k, N m{torque_note};
     force            the fingertip sensor's normal force at t_k, N{force_note};
     reference        the force reference F_ref at t_k, N;
     normal (3)       the object's surface normal at the contact, base frame, pointing from the fingertip into
                      the object (any length: normalised at each call); the step presses along it.
   Out: command (NM), the motor torques to write, N m (motor {motor_name} in [0, {tau_max!r}], the others 0).
   {observer_note}
   {gains}

   Start: alpes_step_state s; alpes_step_init(&s); double work[ALPES_STEP_NWORK];
   each tick: if (alpes_step(&s, counts, torque, force, F_ref, normal, command, work)) stop the motor.
   Returns 0, or 1 (the generated code failed), 2 (a reading not finite: counts, torque{force_read}, the
   reference; or a zero or non-finite normal), 3 (the EKF diverged: a joint estimate beyond 1e6 rad or
   rad/s: check the readings' units); on an error the state is left as it was. After a call, s.z holds
   [q_hat (rad); qd_hat (rad/s)]{bristles} ({nz}), s.P its covariance (column-major), s.F_fb the force fed back (N).
   No heap, no global state; reentrant. Build: cc -O2 -std=c99 -c alpes_step.c{ekf_c} alpes_step_force.c
   (link with -lm); the test program:
     {build}
*/
#ifndef ALPES_STEP_H
#define ALPES_STEP_H

#include "alpes_step_force.h"

#ifdef __cplusplus
extern "C" {{
#endif

#define ALPES_STEP_NM {nm}        /* motors */
#define ALPES_STEP_NQ {n}        /* joints */
#define ALPES_STEP_NZ {nz}        /* the EKF's states [q; qd]{bristles} */
#define ALPES_STEP_NWORK {nwork}  /* doubles of the work array */
#define ALPES_STEP_DT {dt!r}  /* the period, s */
#define ALPES_STEP_TAU_MAX {tau_max!r}  /* the motor limit, N m */

typedef struct {{
  double z[ALPES_STEP_NZ];                   /* [q_hat; qd_hat] (rad, rad/s){bristles}{z_note} */
  double P[ALPES_STEP_NZ * ALPES_STEP_NZ];   /* its covariance, column-major */
  double command[ALPES_STEP_NM];             /* the last command, N m */
  double F_fb;                               /* the force fed back at the last tick, N */
  long k;                                    /* ticks done */
  alpes_step_force_state controller;         /* the controller's memory */
}} alpes_step_state;

/* The first tick's state: the finger at rest (the EKF's prior), the controller cleared, the command 0. */
void alpes_step_init(alpes_step_state* s);

/* One tick: the readings in, the command out (see above). */
int alpes_step(alpes_step_state* s, const double counts[ALPES_STEP_NM], const double torque[ALPES_STEP_NM],
               double force, double reference, const double normal[3], double command[ALPES_STEP_NM],
               double work[ALPES_STEP_NWORK]);

#ifdef __cplusplus
}}
#endif
#endif
"""

_STEP = r"""/* alpes_step.c -- generated by alpes_dyn (alpes-dyn codegen --step); the API is in alpes_step.h */
#include <math.h>
#include <string.h>
#include "alpes_step.h"
{ekf_include}
#define NM ALPES_STEP_NM
#define NQ ALPES_STEP_NQ
#define NZ ALPES_STEP_NZ
#define FILTER {filter}
#define SENSORLESS {sensorless}
#define NEEDS_FORCE {needs_force}
#define COMMAND_INPUT {command_input}
#define UNSTRETCH {unstretch}
#define MOTOR {motor}
#define RAD_PER_COUNT {rad_per_count!r}
#define OFFSET {offset!r}  /* the encoder's zero, rad of the motor */
#define ALPHA {alpha!r}    /* the sensorless estimate's low-pass weight */
#define SCALE {scale!r}    /* force_scale: the sensor's N into the file's torque units (the estimate divided by it) */
#define DIVERGED 1e6

#if FILTER
static const double C_TENDON[NM] = {{{compliance}}};  /* rad/(N m): the tendons' stretch */
#endif
static const double Z0[NZ] = {{{z0}}};
static const double P0[NZ * NZ] = {{{P0}}};

void alpes_step_init(alpes_step_state* s) {{
  memset(s, 0, sizeof(*s));
  memcpy(s->z, Z0, sizeof(Z0));
  memcpy(s->P, P0, sizeof(P0));
  alpes_step_force_init(&s->controller);
}}

int alpes_step(alpes_step_state* s, const double counts[NM], const double torque[NM], double force,
               double reference, const double normal[3], double command[NM], double work[ALPES_STEP_NWORK]) {{
  double n[3], y[NM], tau[NM], F_fb = force, u;
  const double* q_hat = s->z;
  alpes_step_force_state ctl = s->controller;
  int i;
  for (i = 0; i < NM; ++i) {{
    if (!isfinite(counts[i]) || !isfinite(torque[i])) return 2;
    y[i] = counts[i] * RAD_PER_COUNT;
    tau[i] = COMMAND_INPUT ? s->command[i] : torque[i]; /* the motor torque over [t_k-1, t_k) */
  }}
  if ((NEEDS_FORCE && !isfinite(force)) || !isfinite(reference)) return 2;
  if (alpes_step_force_unit_normal(normal, n)) return 2;
  (void) y; /* unused without the observer; */
  (void) tau; /* ... with neither the observer nor the sensorless estimate */
#if FILTER
  if (s->k > 0) {{ /* the EKF's predict over [t_k-1, t_k] and its update with the encoder at t_k */
    double* zn = work;
    double* Pn = zn + NZ;
    double* w = Pn + NZ * NZ;
    double* yy = w + NM + 3;
    const double F_in = (SENSORLESS ? s->F_fb : force) * SCALE; /* the force in the file's torque units */
    for (i = 0; i < NM; ++i) {{
      w[i] = tau[i];
      yy[i] = UNSTRETCH ? (y[i] - OFFSET) - tau[i] * C_TENDON[i] : y[i];
    }}
    for (i = 0; i < 3; ++i) w[NM + i] = -F_in * n[i];
    if (alpes_step_ekf_step(s->z, s->P, w, yy, zn, Pn, yy + NM)) return 1;
    for (i = 0; i < NZ; ++i) if (!(fabs(zn[i]) < DIVERGED)) return 3;
    memcpy(s->z, zn, sizeof(double) * NZ);
    memcpy(s->P, Pn, sizeof(double) * NZ * NZ);
  }}
#endif
#if SENSORLESS
  {{
    double F_est;
    if (alpes_step_force_contact_force_n(q_hat, tau, n, &F_est, work)) return 1;
    F_est = F_est / SCALE;
    F_fb = s->F_fb + ALPHA * ((0.0 > F_est ? 0.0 : F_est) - s->F_fb);
  }}
#endif
  if (alpes_step_force_update_n(&ctl, reference, F_fb, q_hat, n, &u, work)) return 1;
  s->controller = ctl;
  for (i = 0; i < NM; ++i) s->command[i] = command[i] = i == MOTOR ? u : 0.0;
  s->F_fb = F_fb;
  s->k += 1;
  return 0;
}}
"""

_MAIN = r"""/* main.c -- test program of alpes_step.c (alpes-dyn codegen --step).

   alpes_step_main FILE|-              per tick, one line: the command (NM), [q_hat; qd_hat] (NZ), the force fed back
   alpes_step_main -s FILE|-           the same, each tick one step from the state given on its line (after the
                                       readings: STATE_ROW numbers, load_state's order), not from the tick before
   alpes_step_main -t REPEAT FILE|-    time the step: the record REPEAT times, us per step (wall clock, processor;
                                       each step's minimum and median over the passes)

   FILE: one tick per line: counts (NM) torque (NM) force reference normal (3) (%.17g printed: read back exactly).
   Build: {build}
*/
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "alpes_step.h"

#define NM ALPES_STEP_NM
#define NX (2 * NM + 5)  /* the readings of a line */
#define NR (NX + (per_step ? STATE_ROW : 0))
#define STATE_ROW (ALPES_STEP_NZ * (ALPES_STEP_NZ + 1) + NM + 15)
{load_state}
int main(int argc, char** argv) {{
  double work[ALPES_STEP_NWORK], command[NM], *rows = 0;
  long n = 0, cap = 0, k, r, repeat = 0;
  int a = 1, i, e, per_step = 0;
  alpes_step_state s;
  FILE* f;
  if (argc > 1 && strcmp(argv[1], "-s") == 0) {{ per_step = 1; --argc; ++argv; }}
{read_rows}  if (repeat == 0) {{
    alpes_step_init(&s);
    for (k = 0; k < n; ++k) {{
      const double* x = rows + k * NR;
      if (per_step) load_state(&s, x + NX);
      if ((e = alpes_step(&s, x, x + NM, x[2 * NM], x[2 * NM + 1], x + 2 * NM + 2, command, work))) {{
        fprintf(stderr, "%s: line %ld: alpes_step returned %d\n", argv[0], k + 1, e);
        return 1;
      }}
      for (i = 0; i < NM; ++i) printf(i ? " %.17g" : "%.17g", command[i]);
      for (i = 0; i < ALPES_STEP_NZ; ++i) printf(" %.17g", s.z[i]);
      printf(" %.17g\n", s.F_fb);
    }}
{time_steps}  free(rows);
  return 0;
}}
"""


TIME_STEPS_C = r"""  }} else {{  /* -t REPEAT: the record REPEAT times, each step timed on its own (wall clock) */
    struct timespec t0, t1, a0, a1;
    double sec, lo = 0.0, med = 0.0, v, *d, *dt = malloc(sizeof(double) * (n > 0 ? n : 1) * repeat);
    clock_t c0, c1;
    long j;
    if (!dt) {{ fprintf(stderr, "%s: out of memory\n", argv[0]); return 2; }}
    c0 = clock();
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeat; ++r) {{
      {init}
      for (k = 0; k < n; ++k) {{
        const double* x = rows + k * NR;
        clock_gettime(CLOCK_MONOTONIC, &a0);
        {step}
        clock_gettime(CLOCK_MONOTONIC, &a1);
        dt[k * repeat + r] = (a1.tv_sec - a0.tv_sec) + 1e-9 * (a1.tv_nsec - a0.tv_nsec);
      }}
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    c1 = clock();
    for (k = 0; k < n; ++k) {{  /* each step's passes sorted: its minimum and median */
      d = dt + k * repeat;
      for (r = 1; r < repeat; ++r) for (v = d[r], j = r; j > 0 && d[j - 1] > v; --j) d[j] = d[j - 1], d[j - 1] = v;
      lo += d[0];
      med += 0.5 * (d[(repeat - 1) / 2] + d[repeat / 2]);
    }}
    sec = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
    printf("%ld steps x %ld: %.4f us per step, %.4f us of processor time (command[0] = %.17g); "
           "each step's minimum over the passes %.4f us, its median %.4f us (means over the steps)\n", n, repeat,
           1e6 * sec / (n * repeat > 0 ? n * repeat : 1),
           1e6 * (double)(c1 - c0) / CLOCKS_PER_SEC / (n * repeat > 0 ? n * repeat : 1), command[0],
           1e6 * lo / (n > 0 ? n : 1), 1e6 * med / (n > 0 ? n : 1));
    free(dt);
  }}
"""
"""The test programs' ``-t REPEAT`` (C, in ``main``; ``init`` and ``step`` the statements that start a pass and
make one step of row ``x``): the record run REPEAT times, each step timed on its own (wall clock); one line: the
passes' wall clock and processor time per step, then the mean over the steps of each step's minimum over the
passes and of its median (the minimum the step's own cost, the rest the other processes': ``benchmarks/c_step.py``'s
time rule). The two clock reads per step add about 0.05 us to each."""

LOAD_STATE_C = r"""
/* The state from a row (a test's, the Python step's state before a tick; cstep.step_state_row's order): the
   estimate z, its covariance P (column-major), the last command, the force fed back, the ticks done, then the
   controller's memory (integral, tau_prev, F_ref_f, F_ref_f2, nx[2], ny[2], above, below, in_contact, started,
   notch_started). Returns the row past it. */
static const double* {name}({type}* s, const double* x) {{
  size_t i, nz = sizeof(s->z) / sizeof(double), nm = sizeof(s->command) / sizeof(double);
  for (i = 0; i < nz; ++i) s->z[i] = *x++;
  for (i = 0; i < nz * nz; ++i) s->P[i] = *x++;
  for (i = 0; i < nm; ++i) s->command[i] = *x++;
  s->F_fb = *x++;
  s->k = (long) *x++;
  s->controller.integral = *x++;
  s->controller.tau_prev = *x++;
  s->controller.F_ref_f = *x++;
  s->controller.F_ref_f2 = *x++;
  for (i = 0; i < 2; ++i) s->controller.nx[i] = *x++;
  for (i = 0; i < 2; ++i) s->controller.ny[i] = *x++;
  s->controller.above = (long) *x++;
  s->controller.below = (long) *x++;
  s->controller.in_contact = (int) *x++;
  s->controller.started = (int) *x++;
  s->controller.notch_started = (int) *x++;
  return x;
}}
"""
"""A C function ``name`` loading a step's state (of C type ``type``) from a row of :func:`step_state_row`'s layout
(the test programs' ``-s`` mode: one step from a given state); ``.format(name=..., type=...)``."""


def step_c_sources(step: ForceStep, *, about: str = "", prefix: str = "alpes_step") -> dict[str, str]:
    """The C export of ``step.step``: {file name: text} (the module docstring's files).

    Parameters
    ----------
    step : ForceStep
        The step (its settings, :meth:`ForceStep.parts <alpes_dyn.control.step.ForceStep.parts>`, are exported,
        not its state: the C step starts at the first sample).
    about : str
        A line for the header's comment (the model, its parameter file).
    prefix : str
        The C names' prefix (files, functions, types, macros in upper case): ``alpes_step`` gives the module
        docstring's; another lets several steps link into one program (the hand's chains,
        :mod:`alpes_dyn.control.chand`).

    Returns
    -------
    dict of str to str
        ``{prefix}.h``, ``{prefix}.c``, ``{prefix}_force.h``, ``{prefix}_force.c``, ``main.c`` and, but for
        ``"pi"``, ``{prefix}_ekf.h``, ``{prefix}_ekf.c``.

    Raises
    ------
    InputError
        ``step`` not a ForceStep, a prefix that is not a C identifier (one line naming it).
    """
    from .._version import __version__

    if not isinstance(step, ForceStep):
        raise InputError(f"step: expected a ForceStep, got {type(step).__name__}")
    if not isinstance(prefix, str) or not prefix.isidentifier() or not prefix.isascii() or prefix != prefix.lower():
        raise InputError(f"prefix: expected a lower-case C identifier, got {prefix!r}")
    parts = step.parts()
    ctl = parts.controller
    files = controller_c_sources(ctl, prefix="alpes_step_force")
    del files["force_main.c"]
    nz, nm, filt = parts.z0.size, parts.m, parts.ekf is not None  # [q; qd], the LuGre law's bristles after them
    ekf_nwork = 0
    if filt:
        ekf = c_sources(parts.ekf, prefix="alpes_step_ekf", about=about)
        del ekf["main.c"]
        files.update(ekf)
        ekf_nwork = int(ekf["alpes_step_ekf.h"].split("#define ALPES_STEP_EKF_NWORK ")[1].split()[0])
    force_nwork = int(files["alpes_step_force.h"].split("#define ALPES_STEP_FORCE_NWORK ")[1].split()[0])
    nwork = max(nz + nz * nz + 2 * nm + 3 + ekf_nwork, force_nwork)
    sl = parts.sensorless_alpha is not None
    files["alpes_step.c"] = _STEP.format(
        ekf_include='#include "alpes_step_ekf.h"\n' if filt else "", filter=int(filt),
        sensorless=int(sl), needs_force=int(parts.kind != "sensorless"),
        command_input=int(parts.command_input), unstretch=int(parts.unstretch), motor=parts.motor,
        rad_per_count=parts.rad_per_count, offset=parts.encoder_offset,
        alpha=parts.sensorless_alpha if sl else 0.0, scale=parts.force_scale,
        compliance=_doubles(parts.tendon_compliance),
        z0=_doubles(parts.z0).replace("nan", "NAN"), P0=_doubles(parts.P0).replace("nan", "NAN"))
    build = C_STEP_BUILD if filt else C_STEP_BUILD.replace(" alpes_step_ekf.c", "")
    gains = f"Controller {parts.kind}, its tuned gains: " + ", ".join(
        f"{k} {getattr(ctl, k)!r}" for k in ("kp", "ki", "contact_threshold", "approach_rate", "prefilter_s",
                                             "release_s", "onset_s", "loss_s", "notch_hz")) + "."
    name = parts.model.name
    files["alpes_step.h"] = _HEADER.format(
        model=name, version=__version__,
        about=(about or f"Model {name}.").replace("*/", "* /"), dt=parts.dt,
        cpr=int(round(2 * np.pi / parts.rad_per_count)),
        torque_note=("\n" + " " * 22 + "(checked, not used: with the compensation the command held over the period"
                     "\n" + " " * 22 + "is the motor torque)" if parts.command_input else ""),
        force_note=("\n                      (not read by the sensorless controller: any number)"
                    if parts.kind == "sensorless" else ""),
        force_read="" if parts.kind == "sensorless" else ", the force", motor_name=parts.motor_names[parts.motor],
        tau_max=parts.tau_max, gains="\n   ".join(_wrap(gains)), nm=nm, n=parts.n, nz=nz, nwork=nwork,
        observer_note=_observer_note(parts) if filt else "No observer (the pi baseline): s.z and s.P are NaN.",
        z_note="" if filt else "; NaN: no observer", bristles="; z (rad), LuGre's" if nz > 2 * parts.n else "",
        ekf_c=" alpes_step_ekf.c" if filt else "", build=build)
    timed = TIME_STEPS_C.format(init="alpes_step_init(&s);", step="alpes_step(&s, x, x + NM, x[2 * NM], x[2 * NM + 1], "
                                "x + 2 * NM + 2, command, work);")
    files["main.c"] = _MAIN.format(build=build, read_rows=READ_ROWS_C, time_steps=timed,
                                   load_state=LOAD_STATE_C.format(name="load_state", type="alpes_step_state"))
    if prefix != "alpes_step":
        files = {k.replace("alpes_step", prefix): v.replace("alpes_step", prefix).replace("ALPES_STEP", prefix.upper())
                 for k, v in files.items()}
    return dict(sorted(files.items()))


def _observer_note(parts: StepParts) -> str:
    """The header's words on the observer and the compensation."""
    friction = ", with the file's friction" if parts.observer_friction else ""
    words = [f"The EKF (alpes_step_ekf.h{friction}) "
             "takes the known input [tau_m, -F n] (the sensorless estimate of the tick before for F with the "
             "sensorless controller) and the encoder"]
    if parts.unstretch:
        words.append(f"less its zero ({parts.encoder_offset!r} rad) and the tendon's stretch C tau_m")
    if parts.command_input:
        words.append("with the command held over the period as tau_m")
    return "\n   ".join(_wrap(" ".join(words) + "; no filter step at the first tick (the estimate is the rest)."))


def _wrap(text: str, width: int = 108) -> list[str]:
    lines, line = [], ""
    for word in text.split():
        if line and len(line) + 1 + len(word) > width:
            lines.append(line)
            line = word
        else:
            line = f"{line} {word}" if line else word
    return lines + ([line] if line else [])


def write_c_step(step: ForceStep, directory: str | os.PathLike[str], *, what: str = "-o",
                 **kwargs: Any) -> dict[str, Path]:
    """Write :func:`step_c_sources` into ``directory``, a new (or empty) directory, atomically (a temporary
    directory renamed: no partial output). Returns {file name: path}. :class:`~alpes_dyn.InputError` naming
    ``what`` for an existing file or a non-empty directory.

    Parameters
    ----------
    step : ForceStep
        The step exported.
    directory : str or os.PathLike
        The output directory, new or empty.
    what : str, optional
        The option named in errors (default ``"-o"``).
    **kwargs
        Passed to :func:`step_c_sources` (``about``, ``prefix``).

    Returns
    -------
    dict of str to pathlib.Path
        File name -> the path written.

    Raises
    ------
    InputError
        ``directory`` is an existing file or a non-empty directory.
    """
    check_output_directory(directory, what)
    return write_sources(step_c_sources(step, **kwargs), directory, what)


def step_main_input(counts: Any, torque: Any, force: Any, reference: Any, normal: Any, states: Any = None) -> str:
    """The text ``main.c`` reads: per tick counts (N, m), torque (N, m), force (N,) (NaN: 0, unread by the
    sensorless step), reference (N,), normal (3,) or (N, 3); with ``states`` (N, S), each tick's state
    (:func:`step_state_row` of the Python step before that tick) after its readings, for ``main -s`` (one step from
    each given state); ``repr``: read back exactly.

    Parameters
    ----------
    counts : array_like
        The encoder readings, shape (N, m), counts.
    torque : array_like
        The motor torque readings, shape (N, m), N m.
    force : array_like
        The fingertip force readings, shape (N,), N (NaN: no reading, written 0).
    reference : array_like
        The reference forces, shape (N,), N.
    normal : array_like
        The contact normal, shape (3,) or (N, 3).
    states : array_like or None, optional
        Each tick's state, shape (N, S) (:func:`step_state_row`); None (default): none written.

    Returns
    -------
    str
        One line per tick.
    """
    counts = np.asarray(counts, float)
    N = len(counts)
    cols = [counts.reshape(N, -1), np.asarray(torque, float).reshape(N, -1),
            np.nan_to_num(np.asarray(force, float).reshape(N, 1), nan=0.0), np.asarray(reference, float).reshape(N, 1),
            np.broadcast_to(np.asarray(normal, float), (N, 3))]
    if states is not None:
        cols.append(np.asarray(states, float).reshape(N, -1))
    rows = np.hstack(cols)
    return "".join(" ".join(repr(float(x)) for x in row) + "\n" for row in rows)


def step_state_row(step: ForceStep) -> np.ndarray:
    """The state of ``step`` now (before its next :meth:`~alpes_dyn.control.step.ForceStep.step`) as the C step's
    state, in :data:`LOAD_STATE_C`'s order: [z (nz: 2n, 3n with LuGre's bristles); P (nz^2, column-major); the
    last command (m); the force fed back; the ticks done; the controller's integral, tau_prev, F_ref_f, F_ref_f2, notch inputs (2), outputs (2),
    periods above and below the threshold, in contact, started, notch started] (z and P NaN for ``"pi"``).

    Parameters
    ----------
    step : ForceStep
        The step.

    Returns
    -------
    numpy.ndarray
        (nz (nz + 1) + m + 15,) the row.
    """
    nz, c = step.nz, step.controller
    zP = step._s[:nz * (nz + 1)] if step.filter_step is not None else np.full(nz * (nz + 1), np.nan)
    notch = c._notch
    started = c.F_ref_f is not None
    return np.concatenate([zP, step._command, [
        step._F_fb, step.k, c.integral, c.tau_prev, c.F_ref_f if started else 0.0, c.F_ref_f2 if started else 0.0,
        *(notch[1] if notch else (0.0, 0.0)), *(notch[2] if notch else (0.0, 0.0)), c._above, c._below,
        float(c.in_contact), float(started), float(notch is not None)]])


def read_step_output(text: str, m: int, nz: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``main.c``'s printout: (commands (N, m) N m, estimates [q_hat; qd_hat] (N, nz), forces fed back (N,) N).

    Parameters
    ----------
    text : str
        ``main.c``'s standard output.
    m : int
        The number of motors.
    nz : int
        The estimate's length, 2n.

    Returns
    -------
    commands : numpy.ndarray, shape (N, m)
        The motor torque commands, N m.
    estimates : numpy.ndarray, shape (N, nz)
        The estimates [q_hat; qd_hat], rad and rad/s.
    forces : numpy.ndarray, shape (N,)
        The forces fed back, N.

    Raises
    ------
    InputError
        A line is not m + nz + 1 numbers.
    """
    try:
        rows = np.array([[float(x) for x in line.split()] for line in text.splitlines() if line.strip()])
    except ValueError:
        rows = np.zeros((0, 0))
    if rows.ndim != 2 or rows.shape[1] != m + nz + 1:
        raise InputError(f"main.c output: expected lines of {m + nz + 1} numbers")
    return rows[:, :m], rows[:, m:m + nz], rows[:, -1]
