"""A standalone C export of the fingertip force controller (issue 20): :class:`~.controller.ForceController`'s
``update`` as C, beside the observer's (:mod:`alpes_dyn.estimation.cexport.cexport`).

:func:`controller_c_sources` writes ``alpes_force.h`` (the API, the settings in its comment), ``alpes_force.c``
(the controller's logic -- prefilter, contact onset and loss, bumpless transfer, saturation, anti-windup, the
notch -- line for line as :meth:`ForceController.update <alpes_dyn.control.controller.ForceController.update>`,
and CasADi's generated code of its feedforward, the static balance :func:`~.controller.static_motor_torque`, and
of :func:`~.controller.static_contact_force`, the sensorless loop's force estimate, the surface normal an input
of both) and
``force_main.c`` (reads F_ref F_fb q_hat per line, prints the torque command and that force)::

    typedef struct { ... } alpes_force_state;          /* the controller's memory: zero it to start */
    void alpes_force_init(alpes_force_state* s);
    int alpes_force_update(alpes_force_state* s, double F_ref, double F_fb, const double q_hat[ALPES_FORCE_NQ],
                           double* tau, double work[ALPES_FORCE_NWORK]);
    int alpes_force_contact_force(const double q_hat[ALPES_FORCE_NQ], double tau_m, double* F_z,
                                  double work[ALPES_FORCE_NWORK]);   /* the sensorless loop's estimate */
    /* the same at a unit normal n given at run time (a curved object's, or another object's) */
    int alpes_force_update_n(alpes_force_state* s, double F_ref, double F_fb, const double q_hat[NQ],
                             const double n[3], double* tau, double work[ALPES_FORCE_NWORK]);
    int alpes_force_contact_force_n(const double q_hat[NQ], const double tau_m[NM], const double n[3], double* F_z,
                                    double work[ALPES_FORCE_NWORK]);

No heap, no global state; ``-lm``. ``alpes_force_update`` presses along the controller's normal at export (a
block's face); ``alpes_force_update_n`` along any unit normal given at each call (``ForceController.update(
normal=)``). The whole force step -- observer, compensation and this controller -- is
:mod:`alpes_dyn.control.cstep`'s.
"""

from __future__ import annotations

from typing import Any

import casadi as cs
import numpy as np

from ..errors import InputError
from ..symbolic.dynamics import SymbolicDynamics
from .controller import ForceController, _notch_coefficients

__all__ = ["controller_c_sources", "block_controller", "robot_controller", "force_main_input", "read_force_output", "READ_ROWS_C"]

_LOGIC = r"""
/* ---- alpes_dyn: ForceController.update, line for line ---- */
#include <math.h>
#include <string.h>
#include "{prefix}.h"

#define KIND_PI {is_pi}
#define DT {dt!r}
#define TAU_MAX {tau_max!r}
#define KP {kp!r}
#define KI {ki!r}
#define THRESHOLD {contact_threshold!r}
#define APPROACH_RATE {approach_rate!r}
#define PREFILTER_S {prefilter_s!r}
#define RELEASE_S {release_s!r}
#define LOSS_S {loss_s!r}
#define ONSET_S {onset_s!r}
#define ORDER {prefilter_order}
#define SETPOINT_WEIGHT {setpoint_weight!r}
#define NOTCH {notch}
#define NB0 {b0!r}
#define NB1 {b1!r}
#define NB2 {b2!r}
#define NA1 {a1!r}
#define NA2 {a2!r}

static double mn(double a, double b) {{ return b < a ? b : a; }}  /* Python's min(a, b) */
static double mx(double a, double b) {{ return b > a ? b : a; }}  /* Python's max(a, b) */

/* the surface normal at export (the fixed-normal API's) */
static const double NORMAL[3] = {{{normal}}};

void {prefix}_init({prefix}_state* s) {{ memset(s, 0, sizeof(*s)); }}

int {prefix}_unit_normal(const double normal[3], double n[3]) {{
  const double x = normal[0], y = normal[1], z = normal[2];
  const double q = x * x + y * y + z * z;
  if (!(q > 0.0 && q < HUGE_VAL)) return 1;
  n[0] = x / sqrt(q);
  n[1] = y / sqrt(q);
  n[2] = z / sqrt(q);
  return 0;
}}

/* one of CasADi's functions f(q (NQ), x (nx), n (3)) -> out (1), its arguments laid out in work */
static int call_qxn(int (*f)(const casadi_real**, casadi_real**, casadi_int*, casadi_real*, int), const double* q,
                    const double* x, int nx, const double* n, double* out, double* work) {{
  const casadi_real* arg[{n_arg}];
  casadi_real* res[{n_res}];
  casadi_int iw[{n_iw} + 1];
  double* qi = work;
  memcpy(qi, q, sizeof(double) * {P}_NQ);
  memcpy(qi + {P}_NQ, x, sizeof(double) * nx);
  memcpy(qi + {P}_NQ + nx, n, sizeof(double) * 3);
  arg[0] = qi;
  arg[1] = qi + {P}_NQ;
  arg[2] = qi + {P}_NQ + nx;
  res[0] = out;
  return f(arg, res, iw, qi + {P}_NQ + nx + 3, 0);
}}

int {prefix}_contact_force_n(const double q_hat[{P}_NQ], const double tau_m[{P}_NM], const double n[3], double* F_z,
                             double work[{P}_NWORK]) {{
  return call_qxn({prefix}_cs_fz, q_hat, tau_m, {P}_NM, n, F_z, work);
}}

int {prefix}_contact_force(const double q_hat[{P}_NQ], double tau_m, double* F_z, double work[{P}_NWORK]) {{
  double t[{P}_NM];
  memset(t, 0, sizeof(t));
  t[{motor}] = tau_m;
  return {prefix}_contact_force_n(q_hat, t, NORMAL, F_z, work);
}}

/* ForceController.command: the command before the notch */
static int command(double* tau_out, {prefix}_state* s, double F_ref, double F_fb, const double* q_hat,
                   const double* n, double* work) {{
  double F_raw = F_ref, ff = 0.0, e, e_p, tau, tau_u;
#if !KIND_PI
  double a;
  if (!s->started) {{ s->F_ref_f = s->F_ref_f2 = F_ref; s->started = 1; }}
  a = DT / ((F_ref < s->F_ref_f ? RELEASE_S : PREFILTER_S) + DT);  /* the release while the reference falls */
  s->F_ref_f += a * (F_ref - s->F_ref_f);
  s->F_ref_f2 += a * (s->F_ref_f - s->F_ref_f2);
  F_ref = ORDER == 2 ? s->F_ref_f2 : s->F_ref_f;
  if (call_qxn({prefix}_cs_ff, q_hat, &F_ref, 1, n, &ff, work)) return 1;
#else
  (void) q_hat; (void) work; (void) n;
#endif
  e = F_ref - F_fb;
  e_p = e + SETPOINT_WEIGHT * (F_raw - F_ref);
  if (s->in_contact) {{
    s->below = F_fb < THRESHOLD ? s->below + 1 : 0;
    if ((double) s->below * DT >= LOSS_S) {{
      s->in_contact = 0;
      s->below = 0;
      s->tau_prev = KIND_PI ? 0.5 * s->tau_prev : mn(s->tau_prev, mx(ff, 0.0));
    }}
  }}
  if (!s->in_contact) {{
    s->above = F_fb >= THRESHOLD ? s->above + 1 : 0;
    if (s->above == 0 || (double) s->above * DT < ONSET_S) {{ /* approach: bounded torque rate */
      tau = mn(s->tau_prev + APPROACH_RATE * DT, TAU_MAX);
      if (!KIND_PI) tau = mn(tau, mx(ff, s->tau_prev));
      s->tau_prev = tau;
      *tau_out = tau;
      return 0;
    }}
    s->in_contact = 1;
    s->integral = s->tau_prev - ff - KP * e_p; /* bumpless transfer */
  }}
  tau_u = ff + KP * e_p + s->integral;
  tau = mn(mx(tau_u, 0.0), TAU_MAX);
  if (tau == tau_u || (tau_u > TAU_MAX && e < 0) || (tau_u < 0 && e > 0)) s->integral += KI * e * DT; /* anti-windup */
  s->tau_prev = tau;
  *tau_out = tau;
  return 0;
}}

int {prefix}_update_n({prefix}_state* s, double F_ref, double F_fb, const double q_hat[{P}_NQ], const double n[3],
                      double* tau_out, double work[{P}_NWORK]) {{
  double tau, out;
  if (command(&tau, s, F_ref, F_fb, q_hat, n, work)) return 1;
#if NOTCH /* ForceController.update: the command through the notch at the cable's mode, clipped again */
  if (!s->notch_started) {{ s->nx[0] = s->nx[1] = s->ny[0] = s->ny[1] = tau; s->notch_started = 1; }}
  out = NB0 * tau + NB1 * s->nx[0] + NB2 * s->nx[1] - NA1 * s->ny[0] - NA2 * s->ny[1];
  s->nx[1] = s->nx[0];
  s->nx[0] = tau;
  s->ny[1] = s->ny[0];
  s->ny[0] = out;
  tau = mn(mx(out, 0.0), TAU_MAX);
#else
  (void) out;
#endif
  *tau_out = tau;
  return 0;
}}

int {prefix}_update({prefix}_state* s, double F_ref, double F_fb, const double q_hat[{P}_NQ], double* tau_out,
                    double work[{P}_NWORK]) {{
  return {prefix}_update_n(s, F_ref, F_fb, q_hat, NORMAL, tau_out, work);
}}
"""

_HEADER = r"""/* {prefix}.h -- the {kind} fingertip force controller of {model} (ForceController.update in C), exported by
   alpes_dyn {version} (alpes-dyn codegen).

   One motor's loop ({which}) at dt = {dt!r} s: the motor torque command tau (N m, in [0, {tau_max!r}]) for the force
   reference F_ref (N) and the force fed back F_fb (N: the FlexiForce reading, or the sensorless estimate),
   with the feedforward S (G(q_hat) + F_ref J(q_hat)^T n) / (S S^T) at the observer's joint angles q_hat
   ({nq}, rad){pi_note}. Surface normal n = {normal} (base frame) in {prefix}_update, any given at
   run time in {prefix}_update_n. Settings: kp {kp!r} N m/N, ki {ki!r}
   N m/(N s), contact threshold {contact_threshold!r} N (onset {onset_s!r} s, loss {loss_s!r} s), approach rate
   {approach_rate!r} N m/s, prefilter {prefilter_s!r} s ({release_s!r} s while the reference falls;
   {prefilter_order} stage(s)), set-point weight
   {setpoint_weight!r}{notch_note}.

   Start: {prefix}_state s; {prefix}_init(&s); then each period: {prefix}_update(&s, F_ref, F_fb, q_hat, &tau, work).
   No heap, no global state; returns 0 (1 if the generated feedforward failed). Build: cc -O2 -c {prefix}.c
   (link with -lm); the test program: cc -O2 -o {prefix}_main force_main.c {prefix}.c -lm
*/
#ifndef {P}_H
#define {P}_H

#ifdef __cplusplus
extern "C" {{
#endif

#define {P}_NQ {nq}        /* joint angles of q_hat */
#define {P}_NM {nm}        /* motors (the torque readings of the sensorless estimate) */
#define {P}_NWORK {nwork}  /* doubles of the work array */
#define {P}_DT {dt!r}  /* control period, s */

typedef struct {{
  double integral;   /* the PI's integral, N m */
  double tau_prev;   /* the last command before the notch, N m */
  double F_ref_f, F_ref_f2;  /* the prefilter's stages, N */
  double nx[2], ny[2];       /* the notch's last inputs and outputs, N m */
  long above, below; /* periods above / below the contact threshold */
  int in_contact, started, notch_started;
}} {prefix}_state;

void {prefix}_init({prefix}_state* s);

/* The command tau (N m) for this period, at the surface normal of the export. */
int {prefix}_update({prefix}_state* s, double F_ref, double F_fb, const double q_hat[{P}_NQ], double* tau,
                    double work[{P}_NWORK]);

/* The same at the unit surface normal n (3, base frame; {prefix}_unit_normal makes one) given at run time. */
int {prefix}_update_n({prefix}_state* s, double F_ref, double F_fb, const double q_hat[{P}_NQ], const double n[3],
                      double* tau, double work[{P}_NWORK]);

/* The static contact force F_z (N) that balances the motor torque tau_m (N m, the controller's motor alone) at
   q_hat (rad): the sensorless loop's estimate (static_contact_force; the loop low-passes it, max(F_z, 0), before
   feeding it back), at the normal of the export. */
int {prefix}_contact_force(const double q_hat[{P}_NQ], double tau_m, double* F_z, double work[{P}_NWORK]);

/* The same for every motor's torque tau_m (NM) at the unit normal n (3) given at run time. */
int {prefix}_contact_force_n(const double q_hat[{P}_NQ], const double tau_m[{P}_NM], const double n[3], double* F_z,
                             double work[{P}_NWORK]);

/* n = normal / |normal| (Python's _normal); 1 for a zero or non-finite normal. */
int {prefix}_unit_normal(const double normal[3], double n[3]);

#ifdef __cplusplus
}}
#endif
#endif
"""

READ_ROWS_C = r"""  if (argc > 2 && strcmp(argv[1], "-t") == 0) { repeat = atol(argv[2]); a = 3; }
  if (argc != a + 1 || (a == 3 && repeat < 1)) { fprintf(stderr, "usage: %s [-t REPEAT] FILE|-\n", argv[0]); return 2; }
  f = strcmp(argv[a], "-") == 0 ? stdin : fopen(argv[a], "r");
  if (!f) { fprintf(stderr, "%s: cannot open %s\n", argv[0], argv[a]); return 2; }
  for (;;) {
    if (n == cap) {
      double* more = realloc(rows, sizeof(double) * NR * (cap = cap ? 2 * cap : 1024));
      if (!more) { fprintf(stderr, "%s: out of memory\n", argv[0]); return 2; }
      rows = more;
    }
    for (i = 0; i < NR; ++i) if (fscanf(f, "%lf", &rows[n * NR + i]) != 1) break;
    if (i == 0) break;
    if (i != NR) { fprintf(stderr, "%s: line %ld: expected %d numbers\n", argv[0], n + 1, NR); return 2; }
    ++n;
  }
"""
"""The test programs' reading of their input (C, in ``main``): ``-t REPEAT`` parsed, then every line of NR numbers
into ``rows`` (n of them), one line naming a malformed line; :mod:`~alpes_dyn.control.cstep`'s ``main.c`` shares it."""

_MAIN = r"""/* force_main.c -- test program of {prefix}.c: reads lines F_ref F_fb q_hat ({nq}), prints per line the command tau
   and the contact force that balances it at q_hat, {prefix}_contact_force (%.17g);
   with -t REPEAT times the updates instead. Build: cc -O2 -o {prefix}_main force_main.c {prefix}.c -lm */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "{prefix}.h"

#define NR (2 + {P}_NQ)

int main(int argc, char** argv) {{
  double work[{P}_NWORK], tau = 0.0, Fz = 0.0, *rows = 0;
  long n = 0, cap = 0, k, r, repeat = 0;
  int a = 1, i;
  {prefix}_state s;
  FILE* f;
{read_rows}  if (repeat == 0) {{
    {prefix}_init(&s);
    for (k = 0; k < n; ++k) {{
      if ({prefix}_update(&s, rows[k * NR], rows[k * NR + 1], rows + k * NR + 2, &tau, work)) return 1;
      if ({prefix}_contact_force(rows + k * NR + 2, tau, &Fz, work)) return 1;
      printf("%.17g %.17g\n", tau, Fz);
    }}
  }} else {{
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (r = 0; r < repeat; ++r) {{
      {prefix}_init(&s);
      for (k = 0; k < n; ++k) {prefix}_update(&s, rows[k * NR], rows[k * NR + 1], rows + k * NR + 2, &tau, work);
    }}
    clock_gettime(CLOCK_MONOTONIC, &t1);
    printf("%ld updates x %ld: %.4f us per update (tau = %.17g)\n", n, repeat,
           1e6 * ((t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec)) / (n * repeat > 0 ? n * repeat : 1), tau);
  }}
  free(rows);
  return 0;
}}
"""


def _feedforward_function(ctl: ForceController, name: str) -> cs.Function:
    """tau_ff(q, F, n) = S_k (G(q) + F J(q)^T n) / (S_k S_k^T): :func:`~.controller.static_motor_torque` in CasADi,
    S_k the controller's motor's row, J the Jacobian of its tip frame (``ctl.tip``; None: the model's default tip),
    n the unit surface normal (3,), an input."""
    m = ctl.model
    sym = SymbolicDynamics(m)
    q, F, n = cs.SX.sym("q", m.n), cs.SX.sym("F"), cs.SX.sym("n", 3)
    S = np.asarray(m.transmission.S[ctl.motor], dtype=float)
    b = sym.gravity_torque(q) + F * cs.mtimes(sym.fingertip_jacobian(q, ctl.tip).T, n)
    if m.transmission.curved:  # the motor's row of rho(q)
        row = m.transmission.curve.ratio(q, cs)[ctl.motor, :].T
        return cs.Function(name, [q, F, n], [cs.dot(row, b) / cs.dot(row, row)], ["q", "F", "n"], ["tau_ff"])
    return cs.Function(name, [q, F, n], [cs.dot(cs.DM(S), b) / float(S @ S)], ["q", "F", "n"], ["tau_ff"])


def _contact_force_function(ctl: ForceController, name: str) -> cs.Function:
    """F_z(q, tau_m, n) = -(J^T n) . (G(q) - S^T tau_m) / |J^T n|^2: :func:`~.controller.static_contact_force` with
    every motor's torque tau_m (m,) at the controller's tip frame, n the unit surface normal (3,), an input."""
    m = ctl.model
    sym = SymbolicDynamics(m)
    tr = m.transmission
    nm = len(tr.motor_names)
    q, tau, n = cs.SX.sym("q", m.n), cs.SX.sym("tau_m", nm), cs.SX.sym("n", 3)
    jn = cs.mtimes(sym.fingertip_jacobian(q, ctl.tip).T, n)
    rho = tr.curve.ratio(q, cs) if tr.curved else cs.DM(np.asarray(tr.S, dtype=float))
    r = sym.gravity_torque(q) - cs.mtimes(rho.T, tau)
    return cs.Function(name, [q, tau, n], [-cs.dot(jn, r) / cs.dot(jn, jn)], ["q", "tau_m", "n"], ["F_z"])


def controller_c_sources(ctl: ForceController, *, prefix: str = "alpes_force") -> dict[str, str]:
    """The C export of ``ctl.update``: ``{"<prefix>.h": ..., "<prefix>.c": ..., "force_main.c": ...}`` (see the
    module docstring): the settings (gains, notch) of ``ctl``, a fresh controller (not its state), compiled in; the
    surface normal ``ctl.normal`` that of ``<prefix>_update``, any other given at run time to
    ``<prefix>_update_n``.

    Parameters
    ----------
    ctl : ForceController
        The controller exported (its settings; its state is not).
    prefix : str, optional
        The C names' and files' prefix, a C identifier of at most 40 characters (default ``"alpes_force"``).

    Returns
    -------
    dict of str to str
        File name -> its text.

    Raises
    ------
    InputError
        ``ctl`` is not a ForceController, ``prefix`` not a C identifier, or a setting not finite.
    """
    from .._version import __version__

    if not isinstance(ctl, ForceController):
        raise InputError(f"ctl: expected a ForceController, got {type(ctl).__name__}")
    if not (prefix.isidentifier() and prefix.isascii() and len(prefix) <= 40):
        raise InputError(f"prefix: expected a C identifier of at most 40 characters, got {prefix!r}")
    P = prefix.upper()
    ff = _feedforward_function(ctl, f"{prefix}_cs_ff")
    fc = _contact_force_function(ctl, f"{prefix}_cs_fz")
    cg = cs.CodeGenerator(f"{prefix}.c", {"with_header": False, "casadi_real": "double"})
    cg.add(ff)
    cg.add(fc)
    nq, nm = ctl.model.n, len(ctl.model.transmission.motor_names)
    nwork = nq + nm + 3 + max(ff.sz_w(), fc.sz_w())
    settings: dict[str, Any] = {k: float(getattr(ctl, k)) for k in (
        "dt", "tau_max", "kp", "ki", "contact_threshold", "approach_rate", "prefilter_s", "loss_s", "onset_s",
        "setpoint_weight")}
    for k, v in settings.items():
        if not np.isfinite(v):
            raise InputError(f"{k}: expected a finite number, got {v!r}")
    settings["release_s"] = settings["prefilter_s"] if ctl.release_s is None else float(ctl.release_s)
    if not np.isfinite(settings["release_s"]):
        raise InputError(f"release_s: expected a finite number, got {ctl.release_s!r}")
    settings["prefilter_order"] = int(ctl.prefilter_order)
    notch = ctl.notch_hz is not None
    coef = _notch_coefficients(ctl.notch_hz, ctl.notch_zeta, ctl.dt) if notch else (0.0,) * 5
    is_pi = int(ctl.kind == "pi")
    normal = ", ".join(repr(float(x)) for x in ctl.normal)
    source = (f"/* {prefix}.c -- generated by alpes_dyn (alpes-dyn codegen); the API is in {prefix}.h */\n"
              + cg.dump() + _LOGIC.format(prefix=prefix, P=P, is_pi=is_pi, n_arg=max(ff.sz_arg(), fc.sz_arg()),
                                          n_res=max(ff.sz_res(), fc.sz_res()), n_iw=max(ff.sz_iw(), fc.sz_iw()),
                                          notch=int(notch), **dict(zip(("b0", "b1", "b2", "a1", "a2"), coef)),
                                          normal=normal, motor=int(ctl.motor), **settings))
    tr = ctl.model.transmission
    which = f"motor {tr.motor_names[ctl.motor]}, frame {ctl.tip or ctl.model.default_tip}"
    notch_note = (f", the command through a notch at {ctl.notch_hz!r} Hz (damping ratio {ctl.notch_zeta!r})"
                  if notch else "")
    header = _HEADER.format(prefix=prefix, P=P, kind=ctl.kind, model=ctl.model.name, version=__version__, nq=nq,
                            nm=nm, which=which, nwork=nwork,
                            normal="[" + ", ".join(f"{x:.17g}" for x in ctl.normal) + "]",
                            pi_note=" (the pi baseline: no feedforward, q_hat unused)" if is_pi else "",
                            notch_note=notch_note, **settings)
    return {f"{prefix}.h": header, f"{prefix}.c": source,
            "force_main.c": _MAIN.format(prefix=prefix, P=P, nq=nq, read_rows=READ_ROWS_C)}


def block_controller(kind: str = "sensor", model: str = "finger3", params: Any = None,
                     force: bool = False) -> ForceController:
    """The controller of ``alpes-dyn control`` (:func:`~.finger_loop.run_control`'s block scene): ``kind`` from
    :data:`~.controller.CONTROLLERS` with its :data:`~.controller.DEFAULT_GAINS`, on ``model`` (finger2,
    finger3) with the parameter file ``params``, the block's face normal, the scenario's period and
    ``tau_max``; a fresh one (its state at zero). A file marked not trustworthy: :class:`~alpes_dyn.ModelError`
    naming it unless ``force`` (:func:`~alpes_dyn.model.trust.check_trusted`).

    Parameters
    ----------
    kind : str, optional
        The controller, a key of :data:`~.controller.CONTROLLERS` (default ``"sensor"``).
    model : str, optional
        ``"finger2"`` or ``"finger3"`` (default ``"finger3"``).
    params : HandParams, str, path or None, optional
        The parameter file (or its loaded parameters); None: the defaults of
        :func:`~alpes_dyn.model.params.load_params`.
    force : bool, optional
        Accept a file marked not trustworthy (default False).

    Returns
    -------
    ForceController
        A fresh controller.

    Raises
    ------
    InputError
        An unknown ``kind`` or a ``model`` other than finger2/finger3.
    """
    from ..model.mjcf import BLOCK_CONTACT_Q, block_normal
    from ..model.params import HandParams, load_params
    from ..model.trust import check_trusted
    from ..model.robot import Model
    from .controller import CONTROLLERS, DEFAULT_GAINS
    from .finger_loop import ControlScenario

    if kind not in CONTROLLERS:
        raise InputError(f"controller: unknown controller {kind!r} (expected one of {', '.join(CONTROLLERS)})")
    if model not in ("finger2", "finger3"):
        raise InputError(f"model: the force controller's C export is defined for finger2 and finger3 on the block, "
                         f"got {model!r}")
    sc = ControlScenario(model=model, controller=kind)
    p = params if isinstance(params, HandParams) else load_params(params)
    check_trusted(p, force)
    m = Model.alpes(model, params=p)
    return ForceController(kind, m, block_normal(tuple((sc.contact_q or BLOCK_CONTACT_Q)[: m.n])), sc.dt, p.tau_max, **DEFAULT_GAINS[kind])


def robot_controller(kind: str, model: Any, *, frame: str | None = None, motor: str | None = None,
                     contact_q: Any = None, tau_max: float | None = None) -> ForceController:
    """The controller of ``alpes-dyn control --model ROBOT.urdf --spec FILE.toml`` (:func:`~.finger_loop.run_control`
    on a URDF + spec :class:`~alpes_dyn.Model`): ``kind`` with the gains scaled to the robot, on the robot without
    its spec's friction, its motor ``motor`` pulling and its frame ``frame`` pressing the block placed from the
    robot's kinematics at ``contact_q`` (:func:`~alpes_dyn.model.block_scene.place_block`; the defaults those of
    ``control``), the motor limit ``tau_max`` (N m; default twice the static torque of the largest reference force);
    a fresh one (its state at zero). The same controller as the loop's (tested against its commands).

    Parameters
    ----------
    kind : str
        The controller, a key of :data:`~.controller.CONTROLLERS`.
    model : Model
        The URDF + spec :class:`~alpes_dyn.Model` (with a transmission spec).
    frame : str or None, optional
        The frame pressing the block (None: ``control``'s default).
    motor : str or None, optional
        The motor pulling (None: ``control``'s default).
    contact_q : array_like or None, optional
        The joint angles (n,), rad, at which the block is placed (None: ``control``'s default).
    tau_max : float or None, optional
        The motor limit, N m (None: twice the static torque of the largest reference force).

    Returns
    -------
    ForceController
        A fresh controller.

    Raises
    ------
    InputError
        ``model`` is not a Model or has no transmission spec, or the scenario's check fails.
    """
    from ..model.robot import Model
    from .finger_loop import ControlScenario, robot_control_settings

    if not isinstance(model, Model):
        raise InputError(f"model: expected an alpes_dyn Model of a URDF and its spec, got {type(model).__name__}")
    if model.spec is None or model.transmission is None:
        raise InputError(f"model: {model.name!r} has no transmission spec (its motors): the force controller needs one")
    sc = ControlScenario(model=model, controller=kind, frame=frame, motor=motor, tau_max=tau_max,
                         contact_q=None if contact_q is None else tuple(np.asarray(contact_q, dtype=float).ravel()))
    sc.check()
    m, block, limit, gains = robot_control_settings(sc)
    return ForceController(kind, m, block.normal, sc.dt, limit, motor=block.motor_index, tip=block.frame, **gains)


def force_main_input(F_ref: Any, F_fb: Any, q_hat: Any) -> str:
    """The text ``force_main.c`` reads: F_ref F_fb q_hat per line (``repr``: read back exactly).

    Parameters
    ----------
    F_ref : array_like
        The reference forces, shape (N,), N.
    F_fb : array_like
        The forces fed back, shape (N,), N.
    q_hat : array_like
        The estimated joint angles, shape (N, n), rad.

    Returns
    -------
    str
        One line per sample.
    """
    F_ref, F_fb = np.asarray(F_ref, float).reshape(-1), np.asarray(F_fb, float).reshape(-1)
    Q = np.asarray(q_hat, float).reshape(len(F_ref), -1)
    return "".join(" ".join(repr(float(x)) for x in np.r_[a, b, q]) + "\n" for a, b, q in zip(F_ref, F_fb, Q))


def read_force_output(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``force_main.c``'s printout: (tau (N,) torque commands, N m; F_z (N,) the contact forces balancing them, N).

    Parameters
    ----------
    text : str
        ``force_main.c``'s standard output, two numbers per line.

    Returns
    -------
    tau : numpy.ndarray, shape (N,)
        The torque commands, N m.
    F_z : numpy.ndarray, shape (N,)
        The contact forces balancing them, N.

    Raises
    ------
    InputError
        A line is not two numbers.
    """
    try:
        rows = np.array([[float(x) for x in line.split()] for line in text.splitlines() if line.strip()])
    except ValueError:
        rows = np.zeros((0, 0))
    if rows.ndim != 2 or rows.shape[1] != 2:
        raise InputError("force_main.c output: expected two numbers per line")
    return rows[:, 0], rows[:, 1]
