"""The whole hand's force step in C: :meth:`HandForceStep.step <alpes_dyn.control.hand_step.HandForceStep.step>` as
standalone C, each chain's contact normal an input of each call.

:func:`hand_c_sources` writes, for a :class:`~alpes_dyn.control.hand_step.HandForceStep` (its parameter file,
controller, gains, compensation, noise settings and ab/adduction PD compiled in):

* per flexion chain ``c`` (index, middle, ring, little, thumb): the chain's whole force step,
  :func:`~alpes_dyn.control.cstep.step_c_sources` of its :class:`~alpes_dyn.control.step.ForceStep` with the prefix
  ``alpes_hand_<c>`` (``alpes_hand_<c>.h/.c``, its EKF ``alpes_hand_<c>_ekf.h/.c`` but for ``"pi"``, its controller
  ``alpes_hand_<c>_force.h/.c``);
* ``alpes_hand.h`` / ``alpes_hand.c`` -- the hand's step: the readings checked, each chain's step with its normal, the
  ab/adduction's PD (its target ramped, its command clipped to [-tau_max, tau_max]: a gear, both ways), in
  :meth:`~alpes_dyn.control.hand_step.HandForceStep.step`'s order;
* ``main.c`` -- a test program: reads one line per tick (counts (6), torque (6), force (5), reference (5), normals
  (15, each chain's 3 in turn)), prints per tick the commands (6), the chains' estimates (:data:`HAND_NZ` in the
  chains' order) and the forces fed back (5) (``%.17g``), or times the step (``-t REPEAT``).

The API (``alpes_hand.h``)::

    void alpes_hand_init(alpes_hand_state* s);
    int alpes_hand_step(alpes_hand_state* s, const double counts[6], const double torque[6], const double force[5],
                        const double reference[5], const double normals[15], double command[6],
                        double work[ALPES_HAND_NWORK]);

No heap, no global state, ``-lm`` only. Build (every ``.c`` file of the directory)::

    cc -O2 -std=c99 -o alpes_hand_main *.c -lm

The normals are the caller's (the object is given at run time): the Python step's default, the cylinder's at the
fingertip of each chain's last estimate, is :attr:`HandForceStep.normals
<alpes_dyn.control.hand_step.HandForceStep.normals>` after each call, which a test feeds to the C step.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..estimation.cexport.cexport import check_output_directory, write_sources
from .cexport import READ_ROWS_C
from .cstep import LOAD_STATE_C, TIME_STEPS_C, step_c_sources, step_state_row
from .hand_step import HandForceStep

__all__ = ["hand_c_sources", "write_c_hand", "hand_main_input", "hand_state_row", "read_hand_output", "C_HAND_BUILD",
           "HAND_NZ"]

C_HAND_BUILD = "cc -O2 -std=c99 -o alpes_hand_main *.c -lm"
"""The build of the test program."""

HAND_NZ = 28
"""The chains' estimates [q_hat; qd_hat] in the chains' order: four fingers of 6, the thumb's 4."""

_HEADER = r"""/* alpes_hand.h -- the whole hand's force step (alpes_dyn.control.hand_step.HandForceStep.step in C),
   exported by alpes_dyn {version} (alpes-dyn codegen --step --model hand).

   {about}

   One tick at dt = {dt!r} s, called once per tick with that tick's readings; the commands are held over
   [t_k, t_k+1). The motors: {motors}.
     counts (6)      the encoders' counts at t_k;
     torque (6)      the motor torques the current sensors report at t_k, N m (the ab/adduction's not read);
     force (5)       the fingertip sensors' normal forces at t_k, N, the chains' order{force_note};
     reference (5)   the chains' force references at t_k, N;
     normals (15)    each chain's contact normal (3, its base frame, from the fingertip into the object, any length).
   Out: command (6), N m, the chains' in [0, {tau_max!r}], the ab/adduction's in [-{tau_max!r}, {tau_max!r}].
   Each chain is the force step of its alpes_hand_<chain>.h; the thumb's ab/adduction a PD on its encoder toward
   {target!r} rad (its target ramped from 0 over {ramp!r} s), kp {kp!r} N m/rad, kd {kd!r} N m s/rad, its velocity
   low-passed with weight {alpha!r}, its command clipped to [-{tau_max!r}, {tau_max!r}] (a gear, both ways).

   Start: alpes_hand_state s; alpes_hand_init(&s); double work[ALPES_HAND_NWORK];
   each tick: if (alpes_hand_step(&s, counts, torque, force, reference, normals, command, work)) stop the motors.
   Returns 0, or 2 (a reading not finite{force_read}, or a zero or non-finite normal: nothing advanced), or
   10 * (chain + 1) + the chain's error (1: the generated code failed, 3: its EKF diverged; the chains before it
   have advanced). No heap, no global state; reentrant. Build: {build}
*/
#ifndef ALPES_HAND_H
#define ALPES_HAND_H

{includes}

#ifdef __cplusplus
extern "C" {{
#endif

#define ALPES_HAND_NM 6
#define ALPES_HAND_NC 5
#define ALPES_HAND_NZ {nz}
#define ALPES_HAND_NWORK {nwork}
#define ALPES_HAND_DT {dt!r}

typedef struct {{
{chain_states}
  double abd_prev, abd_v;   /* the PD: the last joint angle (rad), the filtered velocity (rad/s) */
  long k;                   /* ticks done */
}} alpes_hand_state;

void alpes_hand_init(alpes_hand_state* s);
int alpes_hand_step(alpes_hand_state* s, const double counts[6], const double torque[6], const double force[5],
                    const double reference[5], const double normals[15], double command[6],
                    double work[ALPES_HAND_NWORK]);
/* The chains' [q_hat; qd_hat] after a call, in the chains' order (ALPES_HAND_NZ). */
void alpes_hand_estimate(const alpes_hand_state* s, double z[ALPES_HAND_NZ]);
/* The forces the chains fed back at the last call, N (5). */
void alpes_hand_force_fed_back(const alpes_hand_state* s, double F[5]);

#ifdef __cplusplus
}}
#endif
#endif
"""

_STEP = r"""/* alpes_hand.c -- generated by alpes_dyn (alpes-dyn codegen --step --model hand); the API: alpes_hand.h */
#include <math.h>
#include <string.h>
#include "alpes_hand.h"

#define NEEDS_FORCE {needs_force}
#define RAD_PER_COUNT {rad_per_count!r}
#define TARGET {target!r}
#define RAMP {ramp!r}
#define KP {kp!r}
#define KD {kd!r}
#define ALPHA {alpha!r}
#define RATIO {ratio!r}
#define TAU_MAX {tau_max!r}

void alpes_hand_init(alpes_hand_state* s) {{
  memset(s, 0, sizeof(*s));
{inits}
}}

int alpes_hand_step(alpes_hand_state* s, const double counts[6], const double torque[6], const double force[5],
                    const double reference[5], const double normals[15], double command[6],
                    double work[ALPES_HAND_NWORK]) {{
  double u[6], y, target, c;
  int i, e;
  for (i = 0; i < 6; ++i) if (!isfinite(counts[i]) || !isfinite(torque[i])) return 2;
  for (i = 0; i < 5; ++i) if ((NEEDS_FORCE && !isfinite(force[i])) || !isfinite(reference[i])) return 2;
  for (i = 0; i < 15; ++i) if (!isfinite(normals[i])) return 2;
  for (i = 0; i < 5; ++i) {{
    const double* n = normals + 3 * i;
    if (!(n[0] * n[0] + n[1] * n[1] + n[2] * n[2] > 0.0)) return 2;
  }}
{steps}
  /* the ab/adduction's PD (EncoderPD), its target ramped up */
  y = counts[5] * RAD_PER_COUNT / RATIO;
  if (s->k > 0) s->abd_v += ALPHA * ((y - s->abd_prev) / {dt!r} - s->abd_v);
  s->abd_prev = y;
  target = RAMP > 0 ? TARGET * ((double) s->k * {dt!r} / RAMP < 1.0 ? (double) s->k * {dt!r} / RAMP : 1.0) : TARGET;
  c = KP * (target - y) - KD * s->abd_v;
  u[5] = c < -TAU_MAX ? -TAU_MAX : (c > TAU_MAX ? TAU_MAX : c);
  memcpy(command, u, sizeof(u));
  s->k += 1;
  return 0;
}}

void alpes_hand_estimate(const alpes_hand_state* s, double z[ALPES_HAND_NZ]) {{
{estimates}
}}

void alpes_hand_force_fed_back(const alpes_hand_state* s, double F[5]) {{
{forces}
}}
"""

_MAIN = r"""/* main.c -- test program of alpes_hand.c (alpes-dyn codegen --step --model hand).

   alpes_hand_main FILE|-              per tick: the commands (6), the chains' estimates (ALPES_HAND_NZ), the forces fed
                                       back (5)
   alpes_hand_main -s FILE|-           the same, each tick one step from the state given on its line (after the
                                       readings: STATE_ROW numbers, load_state's order), not from the tick before
   alpes_hand_main -t REPEAT FILE|-    time the step: the record REPEAT times, us per step (wall clock, processor;
                                       each step's minimum and median over the passes)

   FILE: one tick per line: counts (6) torque (6) force (5) reference (5) normals (15).
   Build: {build}
*/
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "alpes_hand.h"

#define NX 37  /* the readings of a line */
#define NR (NX + (per_step ? STATE_ROW : 0))
#define STATE_ROW {state_row}
{load_chain}
/* The hand's state from a row (chand.hand_state_row's order): each chain's, then the PD's and the ticks done. */
static void load_state(alpes_hand_state* s, const double* x) {{
{load_chains}
  s->abd_prev = *x++;
  s->abd_v = *x++;
  s->k = (long) *x;
}}

int main(int argc, char** argv) {{
  double work[ALPES_HAND_NWORK], command[6], z[ALPES_HAND_NZ], F[5], *rows = 0;
  long n = 0, cap = 0, k, r, repeat = 0;
  int a = 1, i, e, per_step = 0;
  alpes_hand_state s;
  FILE* f;
  if (argc > 1 && strcmp(argv[1], "-s") == 0) {{ per_step = 1; --argc; ++argv; }}
{read_rows}  if (repeat == 0) {{
    alpes_hand_init(&s);
    for (k = 0; k < n; ++k) {{
      const double* x = rows + k * NR;
      if (per_step) load_state(&s, x + NX);
      if ((e = alpes_hand_step(&s, x, x + 6, x + 12, x + 17, x + 22, command, work))) {{
        fprintf(stderr, "%s: line %ld: alpes_hand_step returned %d\n", argv[0], k + 1, e);
        return 1;
      }}
      alpes_hand_estimate(&s, z);
      alpes_hand_force_fed_back(&s, F);
      for (i = 0; i < 6; ++i) printf(i ? " %.17g" : "%.17g", command[i]);
      for (i = 0; i < ALPES_HAND_NZ; ++i) printf(" %.17g", z[i]);
      for (i = 0; i < 5; ++i) printf(" %.17g", F[i]);
      printf("\n");
    }}
{time_steps}  free(rows);
  return 0;
}}
"""


def hand_c_sources(step: HandForceStep, *, about: str = "") -> dict[str, str]:
    """The C export of ``step.step``: {file name: text} (the module docstring's files).

    Parameters
    ----------
    step : HandForceStep
        The hand's step (its settings are exported, not its state: the C step starts at the first sample).
    about : str
        A line for the header's comment (the parameter file).

    Returns
    -------
    dict of str to str
        The chains' files, ``alpes_hand.h``, ``alpes_hand.c``, ``main.c``.

    Raises
    ------
    InputError
        ``step`` not a HandForceStep (one line).
    """
    from .._version import __version__

    if not isinstance(step, HandForceStep):
        raise InputError(f"step: expected a HandForceStep, got {type(step).__name__}")
    files: dict[str, str] = {}
    nwork, nzs = 0, []
    for c, s in step.chain_steps.items():
        chain = step_c_sources(s, about=f"{about} Chain {c} of the hand.".strip(), prefix=f"alpes_hand_{c}")
        del chain["main.c"]
        files.update(chain)
        head = chain[f"alpes_hand_{c}.h"]
        nwork = max(nwork, int(head.split(f"#define ALPES_HAND_{c.upper()}_NWORK ")[1].split()[0]))
        nzs.append(2 * s.n)  # its [q_hat; qd_hat], the first entries of its state (LuGre's bristles after them)
    if sum(nzs) != HAND_NZ:
        raise InputError(f"step: expected chains of {HAND_NZ} states in all, got {sum(nzs)}")
    pd, chains = step.abduction, step.chains
    steps, estimates, forces, z0 = [], [], [], 0
    for i, c in enumerate(chains):
        steps.append(f"  if ((e = alpes_hand_{c}(&s->{c}, counts + {i}, torque + {i}, force[{i}], reference[{i}], "
                     f"normals + {3 * i}, u + {i}, work))) return 10 * {i + 1} + e;")
        estimates.append(f"  memcpy(z + {z0}, s->{c}.z, sizeof(double) * {nzs[i]});")
        forces.append(f"  F[{i}] = s->{c}.F_fb;")
        z0 += nzs[i]
    settings = dict(rad_per_count=float(step.abduction_rad_per_count), target=float(step.abduction_target),
                    ramp=float(step.abduction_ramp_s), kp=float(pd.kp), kd=float(pd.kd), alpha=float(pd.alpha),
                    ratio=float(pd.ratio), tau_max=float(step.tau_max), dt=float(step.dt))
    files["alpes_hand.c"] = _STEP.format(
        needs_force=int(step.kind != "sensorless"), inits="\n".join(f"  alpes_hand_{c}_init(&s->{c});" for c in chains),
        steps="\n".join(steps), estimates="\n".join(estimates), forces="\n".join(forces), **settings)
    files["alpes_hand.h"] = _HEADER.format(
        version=__version__, about=(about or "The Alpes hand.").replace("*/", "* /"),
        motors=", ".join(step.motor_names), force_note=(" (not read by the sensorless controller)"
                                                         if step.kind == "sensorless" else ""),
        force_read="" if step.kind == "sensorless" else " (counts, torque, force, reference)",
        build=C_HAND_BUILD, includes="\n".join(f'#include "alpes_hand_{c}.h"' for c in chains), nz=HAND_NZ,
        nwork=nwork, chain_states="\n".join(f"  alpes_hand_{c}_state {c};" for c in chains),
        **{k: v for k, v in settings.items() if k in ("dt", "target", "ramp", "kp", "kd", "alpha", "tau_max")})
    files["main.c"] = _MAIN.format(
        build=C_HAND_BUILD, read_rows=READ_ROWS_C, state_row=len(hand_state_row(step)),
        time_steps=TIME_STEPS_C.format(init="alpes_hand_init(&s);",
                                       step="alpes_hand_step(&s, x, x + 6, x + 12, x + 17, x + 22, command, work);"),
        load_chain="".join(LOAD_STATE_C.format(name=f"load_{c}", type=f"alpes_hand_{c}_state") for c in chains),
        load_chains="\n".join(f"  x = load_{c}(&s->{c}, x);" for c in chains))
    return dict(sorted(files.items()))


def hand_state_row(step: HandForceStep) -> np.ndarray:
    """The state of ``step`` now (before its next :meth:`~alpes_dyn.control.hand_step.HandForceStep.step`) as the
    C step's, ``main -s``'s row: each chain's :func:`~alpes_dyn.control.cstep.step_state_row` in the chains' order,
    then the ab/adduction PD's last joint angle (rad, 0 before the first tick) and filtered velocity (rad/s), the
    ticks done.

    Parameters
    ----------
    step : HandForceStep
        The hand's step.

    Returns
    -------
    numpy.ndarray
        The row (its length: ``main.c``'s STATE_ROW).
    """
    pd = step.abduction
    return np.concatenate([*(step_state_row(s) for s in step.chain_steps.values()),
                           [pd._prev if pd._prev is not None else 0.0, pd._v, step.k]])


def write_c_hand(step: HandForceStep, directory: str | os.PathLike[str], *, what: str = "-o",
                 **kwargs: Any) -> dict[str, Path]:
    """Write :func:`hand_c_sources` into ``directory``, a new (or empty) directory, atomically (no partial output).
    Returns {file name: path}. :class:`~alpes_dyn.InputError` naming ``what`` for an existing file or a non-empty
    directory.

    Parameters
    ----------
    step : HandForceStep
        The hand's step exported.
    directory : str or os.PathLike
        The output directory, new or empty.
    what : str, optional
        The option named in errors (default ``"-o"``).
    **kwargs
        Passed to :func:`hand_c_sources` (``about``).

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
    return write_sources(hand_c_sources(step, **kwargs), directory, what)


def hand_main_input(counts: Any, torque: Any, force: Any, reference: Any, normals: Any, states: Any = None) -> str:
    """The text ``main.c`` reads: per tick counts (N, 6), torque (N, 6), force (N, 5) (NaN: 0), reference (N, 5),
    normals (N, 5, 3); with ``states`` (N, S), each tick's state (:func:`hand_state_row` of the Python step before
    that tick) after its readings, for ``main -s`` (one step from each given state); ``repr``: read back exactly.

    Parameters
    ----------
    counts : array_like
        The encoder readings, shape (N, 6), counts.
    torque : array_like
        The motor torque readings, shape (N, 6), N m.
    force : array_like
        The fingertip force readings, shape (N, 5), N (NaN: no reading, written 0).
    reference : array_like
        The reference forces, shape (N, 5) (or broadcast to it), N.
    normals : array_like
        The contact normals, shape (N, 5, 3).
    states : array_like or None, optional
        Each tick's state, shape (N, S) (:func:`hand_state_row`); None (default): none written.

    Returns
    -------
    str
        One line per tick.
    """
    counts = np.asarray(counts, float)
    N = len(counts)
    cols = [counts.reshape(N, 6), np.asarray(torque, float).reshape(N, 6),
            np.nan_to_num(np.asarray(force, float).reshape(N, 5), nan=0.0),
            np.broadcast_to(np.asarray(reference, float).reshape(N, -1), (N, 5)),
            np.asarray(normals, float).reshape(N, 15)]
    if states is not None:
        cols.append(np.asarray(states, float).reshape(N, -1))
    rows = np.hstack(cols)
    return "".join(" ".join(repr(float(x)) for x in row) + "\n" for row in rows)


def read_hand_output(text: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``main.c``'s printout: (commands (N, 6) N m, the chains' estimates (N, :data:`HAND_NZ`), forces fed back
    (N, 5) N).

    Parameters
    ----------
    text : str
        ``main.c``'s standard output.

    Returns
    -------
    commands : numpy.ndarray, shape (N, 6)
        The motor torque commands, N m.
    estimates : numpy.ndarray, shape (N, HAND_NZ)
        The chains' estimates.
    forces : numpy.ndarray, shape (N, 5)
        The forces fed back, N.

    Raises
    ------
    InputError
        A line is not 6 + HAND_NZ + 5 numbers.
    """
    try:
        rows = np.array([[float(x) for x in line.split()] for line in text.splitlines() if line.strip()])
    except ValueError:
        rows = np.zeros((0, 0))
    if rows.ndim != 2 or rows.shape[1] != 6 + HAND_NZ + 5:
        raise InputError(f"main.c output: expected lines of {6 + HAND_NZ + 5} numbers")
    return rows[:, :6], rows[:, 6:6 + HAND_NZ], rows[:, -5:]
