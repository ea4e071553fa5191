"""C code generation for batched step loops: CasADi's generated step wrapped in a C driver that
loops over steps, advances two sequences per SIMD lane pair (a regex rewrite of CasADi's scalar C
into GCC vector extensions) and splits the batch over POSIX threads; compiled once with the system
C compiler (``$CC``, default gcc) and cached on disk (:mod:`alpes_dyn.simulation.buildcache`).

:class:`CompiledStepLoop` is the engine behind :class:`alpes_dyn.simulation.integrate.CompiledRollout`, the
observers' compiled runs and the identification's sensitivities. CasADi's stock path
(``Function.map(N, "thread")`` with ``jit=True``) is the documented fallback where no C compiler
is wanted.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import re
import shutil
from pathlib import Path
from typing import Any

import casadi as cs
import numpy as np

from .buildcache import CompilerError, build_library, cached_library
from ..fileio import writable_directory
from ..errors import InputError, ModelError
from ..progress import _Progress

__all__ = ["CompiledStepLoop", "CasadiStepLoop", "cache_dir", "CompilerError", "CacheFolderError", "check_cache_folder"]

# ----------------------------------------------------------------------------- C compilation and cache
def cache_dir() -> Path:
    """Directory of compiled libraries: ``$ALPES_DYN_CACHE`` if set and not blank, else
    ``$HOME/.cache/alpes_dyn``. With neither (``HOME`` unset, empty or not an absolute path) a
    :class:`CompilerError` asks for ``ALPES_DYN_CACHE``: never a cache at ``/.cache`` or relative to the
    working directory.

    The folder is checked before anything is compiled (:func:`check_cache_folder`): an ``ALPES_DYN_CACHE`` that is
    relative, a symbolic link, a file or a device, or a folder (or, not there yet, a parent) that cannot be written
    is a :class:`CacheFolderError` naming it (an :class:`~alpes_dyn.InputError`: the run stops there, it does not
    fall back to uncompiled code)."""
    env = os.environ.get("ALPES_DYN_CACHE", "").strip()
    if env:
        if not os.path.isabs(env):
            raise CacheFolderError(f"ALPES_DYN_CACHE: {env[:200]!r} is not an absolute path; give the cache's folder "
                                   "as one")
        return check_cache_folder(Path(env), "ALPES_DYN_CACHE")
    home = os.environ.get("HOME", "")
    if not (home.strip() and os.path.isabs(home)):
        raise CompilerError(f"HOME is {'empty' if not home.strip() else 'not an absolute path (%r)' % home}: set "
                            "ALPES_DYN_CACHE to a folder for the compiled-code cache")
    return check_cache_folder(Path(home) / ".cache" / "alpes_dyn", "the compiled-code cache")


class CacheFolderError(InputError):
    """The compiled-code cache's folder cannot be used: a symbolic link, a file, a device, not writable."""


def check_cache_folder(d: Path, what: str) -> Path:
    """``d`` if it can be the cache's folder: an existing folder (not a symbolic link to one) that can be written,
    or a path whose nearest existing parent is such a folder.

    Parameters
    ----------
    d : pathlib.Path
        The folder.
    what : str
        What the error names (the option or variable that gave the folder).

    Returns
    -------
    pathlib.Path
        ``d``.

    Raises
    ------
    CacheFolderError
        A folder that cannot be the cache's, naming ``what``.
    """
    import stat

    where = f"{what} {str(d)[:200]!r}"
    try:
        st = os.lstat(d)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise CacheFolderError(f"{where}: cannot be examined ({exc.strerror or exc})") from None
    if st is not None:
        if stat.S_ISLNK(st.st_mode):
            raise CacheFolderError(f"{where}: is a symbolic link; give the folder it points to (the cache's files are "
                                   "replaced in place)")
        if not stat.S_ISDIR(st.st_mode):
            raise CacheFolderError(f"{where}: is not a folder (a file or a device); the cache needs a folder")
        if not writable_directory(d):
            raise CacheFolderError(f"{where}: is a folder that cannot be written")
        return d
    parent = d.parent
    while not os.path.lexists(parent) and parent != parent.parent:
        parent = parent.parent
    if not os.path.isdir(parent) or not writable_directory(parent):
        raise CacheFolderError(f"{where}: cannot be created ({str(parent)!r} is not a folder that can be written)")
    return d


_CFLAGS = ("-O3", "-fno-math-errno", "-ffp-contract=off", "-shared", "-fPIC", "-pthread")
"""The compiled functions' flags. ``-ffp-contract=off``: no multiply and add fused into one rounding, so that two
builds of the same operations (a compiled function and the exported C, built ``-std=c99``, which fuses none) give
the same numbers on every target, those with a fused multiply-add (aarch64) too."""
_LANES = 2
_LARGE_SOURCE = 500_000
"""Generated C above this many characters is compiled at ``-O1`` instead of ``-O3``: for a source this large
``-O3`` costs several times ``-O1``'s compile time for little or no speed per step; below it (the fingers'
sensitivities and roll-outs) a build takes seconds and ``-O3`` stays."""


_QUICK_LEVEL = "-O1"
_PROMOTE_STEPS = 200_000
"""A loop's source up to :data:`_LARGE_SOURCE`, no level asked, not cached at ``-O3``: built at :data:`_QUICK_LEVEL`
(about 2/3 of ``-O3``'s compiler time, steps up to a third slower), rebuilt at ``-O3`` once :meth:`CompiledStepLoop.
run` has run this many steps (sequences x steps): when the slower steps have cost about an ``-O3`` build (CHANGELOG).
The flags change no floating-point operation (``-ffp-contract=off``, no ``-ffast-math``): the same numbers."""

_LARGE_LEVELS = ("-O1", "-O0")
"""The optimisation levels a caller may ask for a source over :data:`_LARGE_SOURCE` (:class:`CompiledStepLoop`'s
``large_level``): ``-O0`` for a loop run a few thousand steps per process, whose build at ``-O1`` would outlast its
runs (a large source, e.g. the thumb's prediction covariance, builds several times faster at ``-O0``)."""


def _cflags(source: str, large_level: str = "-O1", level: str | None = None) -> tuple[str, ...]:
    """The compiler flags for ``source``: :data:`_CFLAGS`, with ``large_level`` (one of :data:`_LARGE_LEVELS`) for a
    source over :data:`_LARGE_SOURCE`, or with ``level`` (one of them too) whatever its size where given."""
    if level is not None:
        return (level,) + _CFLAGS[1:]
    return _CFLAGS if len(source) <= _LARGE_SOURCE else (large_level,) + _CFLAGS[1:]


def _compiler() -> str:
    cc = os.environ.get("CC", "").strip()
    if cc:  # asked for by name: that compiler or an error, never another one silently
        path = shutil.which(cc)
        if path is None:
            raise CompilerError(f"CC: the C compiler {cc!r} is not found or not executable (unset CC to use gcc)")
        return path
    path = shutil.which("gcc") or shutil.which("cc")
    if path is None:
        raise CompilerError("C compiler gcc not found (install gcc or set CC); it builds the compiled rollout")
    return path


def _build_library(source: str, stem: str, large_level: str = "-O1",
                   level: str | None = None) -> tuple[Path, bool, float, ctypes.CDLL]:
    """Compile ``source`` to a shared library in the cache (once) and load it; return (path,
    compiled_now, seconds, library). The cache is checked, locked and self-healing:
    :mod:`alpes_dyn.simulation.buildcache`."""
    return build_library(source, stem, _compiler(), _cflags(source, large_level, level), cache_dir())


_DRIVER = r"""
/* ---- alpes_dyn batched rollout driver (appended to the CasADi-generated step) ---- */
#include <pthread.h>
#include <string.h>

#define NX {nx}
#define NW {nw}
#define SZ_ARG {sz_arg}
#define SZ_RES {sz_res}
#define SZ_IW {sz_iw}
#define SZ_W {sz_w}
#define LANES {lanes}

typedef struct {{ const double* W; double* X; const double* P; long b0, b1, ntot, k0, k1; int status; }} alpes_job;

{vector_code}

static void alpes_run(alpes_job* j) {{
  long b, k;
#if LANES > 1
  /* LANES trajectories at once, one per SIMD lane; a short last group repeats its last trajectory */
  vd xs[NX], xn[NX], w[NW];
  double* Xp[LANES];
  const double* Wp[LANES];
  int i, l;
  for (b = j->b0; b < j->b1; b += LANES) {{
    for (l = 0; l < LANES; ++l) {{
      long bl = b + l < j->b1 ? b + l : j->b1 - 1;
      Xp[l] = j->X + bl * (j->ntot + 1) * NX;
      Wp[l] = j->W + bl * j->ntot * NW;
    }}
    for (i = 0; i < NX; ++i) for (l = 0; l < LANES; ++l) xs[i][l] = Xp[l][j->k0 * NX + i];
    for (k = j->k0; k < j->k1; ++k) {{
      for (i = 0; i < NW; ++i) for (l = 0; l < LANES; ++l) w[i][l] = Wp[l][k * NW + i];
      alpes_vstep(xs, w, j->P, xn);
      for (i = 0; i < NX; ++i) {{
        xs[i] = xn[i];
        for (l = LANES - 1; l >= 0; --l) Xp[l][(k + 1) * NX + i] = xn[i][l];
      }}
    }}
  }}
#else
  const casadi_real* arg[SZ_ARG];
  casadi_real* res[SZ_RES];
  casadi_int iw[SZ_IW + 1];
  casadi_real w[SZ_W + 1];
  for (b = j->b0; b < j->b1; ++b) {{
    double* X = j->X + b * (j->ntot + 1) * NX;
    const double* W = j->W + b * j->ntot * NW;
    for (k = j->k0; k < j->k1; ++k) {{
      arg[0] = X + k * NX;
      arg[1] = W + k * NW;
      {parg}
      res[0] = X + (k + 1) * NX;
      if ({step}(arg, res, iw, w, 0)) {{ j->status = 1; return; }}
    }}
  }}
#endif
  j->status = 0;
}}

static void* alpes_worker(void* p) {{ alpes_run((alpes_job*) p); return 0; }}

/* X: (B, ntot+1, NX) with X[b, k0] set; W: (B, ntot, NW); P: the step's parameters (its third input; unread by a
   step of two inputs); advances steps k0..k1-1 of every trajectory. */
CASADI_SYMBOL_EXPORT int alpes_rollout(const double* W, double* X, const double* P, long B, long ntot, long k0,
                                       long k1, int nthreads) {{
  alpes_job jobs[64];
  pthread_t th[64];
  int t, started[64], status = 0;
  long groups = (B + LANES - 1) / LANES;
  if (nthreads < 1) nthreads = 1;
  if (nthreads > 64) nthreads = 64;
  if (nthreads > groups) nthreads = (int) groups;
  for (t = 0; t < nthreads; ++t) {{
    jobs[t].W = W; jobs[t].X = X; jobs[t].P = P; jobs[t].ntot = ntot; jobs[t].k0 = k0; jobs[t].k1 = k1; jobs[t].status = 0;
    jobs[t].b0 = LANES * (groups * t / nthreads);
    jobs[t].b1 = LANES * (groups * (t + 1) / nthreads);
    if (jobs[t].b1 > B) jobs[t].b1 = B;
  }}
  if (nthreads == 1) {{ alpes_run(&jobs[0]); return jobs[0].status; }}
  for (t = 1; t < nthreads; ++t) started[t] = pthread_create(&th[t], 0, alpes_worker, &jobs[t]) == 0;
  alpes_run(&jobs[0]);
  for (t = 1; t < nthreads; ++t) {{
    if (started[t]) pthread_join(th[t], 0); else alpes_run(&jobs[t]);
    status |= jobs[t].status;
  }}
  return status | jobs[0].status;
}}
"""

_VEC_UNARY = ("sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "log", "log10", "sqrt",
              "fabs", "floor", "ceil", "erf", "casadi_sq", "casadi_fabs", "casadi_sign")
_VEC_BINARY = ("atan2", "pow", "fmod", "casadi_fmin", "casadi_fmax", "copysign")
_ASSIGN = re.compile(r"^\s*(a\d+)=(.*);$")
_TRIG = re.compile(r"^\s*(a\d+)=(sin|cos)\((a\d+)\);$")


def _fuse_sincos(lines: list[str]) -> tuple[list[str], int]:
    """Pair sin(a) and cos(a) of the same value into one sincos call (as gcc does for scalar code)."""
    lines = list(lines)
    done: set[int] = set()
    nt = 0
    for i, line in enumerate(lines):
        mt = _TRIG.match(line)
        if not mt or i in done:
            continue
        k, fn, a = mt.groups()
        if k == a:
            continue
        other = "cos" if fn == "sin" else "sin"
        for j in range(i + 1, len(lines)):
            m2 = _TRIG.match(lines[j])
            if m2 and m2.group(2) == other and m2.group(3) == a and j not in done:
                t = f"alpes_t{nt}"
                nt += 1
                s_, c_ = (k, t) if fn == "sin" else (t, k)
                lines[i] = f"  v_sincos({a}, &{s_}, &{c_});"
                lines[j] = f"  {m2.group(1)}={t};"
                done.add(j)
                break
            ma = _ASSIGN.match(lines[j])
            if ma and ma.group(1) == a:  # the argument changes: no partner
                break
    return lines, nt


def _vector_step(source: str, lanes: int) -> str | None:
    """SIMD version (GCC vector extension, one trajectory per lane) of the generated step ``casadi_f0``.

    The body of CasADi's scalar SX code is rewritten statement by statement with the same
    operations in the same order, so each lane computes bit for bit what the scalar code computes
    (IEEE + - * / and sqrt are exact per lane; libm functions are called per lane). Returns None
    when the body uses something not handled (work arrays, conditionals, other calls): the
    scalar driver is used then.
    """
    try:
        i = source.index("static int casadi_f0(")
        j = source.index("\n}\n", i)
    except ValueError:
        return None
    body = source[source.index("{", i) + 1: j]
    if "casadi_f1" in source or re.search(r"\b(i?w)\[", body):
        return None
    lines, nt = _fuse_sincos(body.split("\n"))
    b = "\n".join(lines)
    b = re.sub(r"\bcasadi_real\b", "vd", b)
    b = re.sub(r"arg\[0\]\? arg\[0\]\[(\d+)\] : 0", r"X[\1]", b)
    b = re.sub(r"arg\[1\]\? arg\[1\]\[(\d+)\] : 0", r"W[\1]", b)
    b = re.sub(r"arg\[2\]\? arg\[2\]\[(\d+)\] : 0", r"VB(P[\1])", b)  # a parameter, the same in every lane
    b = re.sub(r"if \(res\[0\]!=0\) res\[0\]\[(\d+)\]=", r"Y[\1]=", b)
    b = re.sub(r"^(\s*a\d+)=([-+]?[0-9.]+(?:[eE][-+]?\d+)?);$", r"\1=VB(\2);", b, flags=re.M)
    b = re.sub(r"\b(" + "|".join(_VEC_UNARY + _VEC_BINARY) + r")\(", r"v_\1(", b)  # one pass over the body
    calls = set(re.findall(r"\b([A-Za-z_]\w*)\(", b))
    if calls - {f"v_{n}" for n in _VEC_UNARY + _VEC_BINARY} - {"v_sincos", "VB"}:
        return None
    if re.search(r"[?<>!]|==|&&|\|\||\barg\b|\bres\b", b):
        return None
    decl = ("  vd " + ", ".join(f"alpes_t{k}" for k in range(nt)) + ";\n") if nt else ""
    lane = ", ".join("(c)" for _ in range(lanes))
    helpers = [
        f"typedef double vd __attribute__((vector_size({8 * lanes})));",
        f"#define VB(c) ((vd){{{lane}}})",
        "#define VL for (l = 0; l < LANES; ++l)",
        "static inline void v_sincos(vd x, vd* s, vd* c) { int l; double a, b; "
        "VL { sincos(x[l], &a, &b); (*s)[l] = a; (*c)[l] = b; } }",
    ]
    helpers += [f"static inline vd v_{n}(vd x) {{ vd r; int l; VL r[l] = {n}(x[l]); return r; }}" for n in _VEC_UNARY]
    helpers += [f"static inline vd v_{n}(vd x, vd y) {{ vd r; int l; VL r[l] = {n}(x[l], y[l]); return r; }}"
                for n in _VEC_BINARY]
    return ("\n".join(helpers) + "\nstatic int alpes_vstep(const vd* X, const vd* W, const double* P, vd* Y) {\n"
            + decl + b
            + "\n}\n")


def _check_threads(threads: Any) -> int:
    """``threads`` as an integer in 1..64 (the driver's maximum), default: the CPUs this process may use."""
    if threads is None:
        return _default_threads()
    if isinstance(threads, (bool, np.bool_)) or not isinstance(threads, (int, np.integer)) or not 1 <= threads <= 64:
        raise InputError(f"threads: expected an integer from 1 to 64, got {threads!r}")
    return int(threads)


def _default_threads() -> int:
    """The CPUs this process may use, at most ``OMP_NUM_THREADS`` where that is set to a positive integer (the
    convention of numpy's BLAS, which Dask's workers set to their own thread count: two workers on two cores
    then run one thread each instead of two)."""
    try:
        n = max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        n = max(1, os.cpu_count() or 1)
    omp = os.environ.get("OMP_NUM_THREADS", "").strip()
    return min(n, int(omp)) if omp.isdigit() and int(omp) > 0 else n


def _batch(x0: np.ndarray, W: np.ndarray, nx: int, nw: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """x0 (B, nx) and W (B, N, nw) as contiguous float64, checked; X (B, N+1, nx) with X[:, 0] = x0."""
    x0 = np.asarray(x0, dtype=float)
    W = np.ascontiguousarray(W, dtype=float)
    B, N = W.shape[0], W.shape[1]
    if x0.shape != (B, nx) or W.shape != (B, N, nw):
        raise InputError(f"x0/W: expected ({B}, {nx}) and ({B}, N, {nw}), got {x0.shape} and {W.shape}")
    X = np.empty((B, N + 1, nx))
    X[:, 0] = x0
    return x0, W, X


def _step_parameters(step: cs.Function, parameters: Any) -> np.ndarray:
    """The parameters of a step (x, w, p) as a contiguous (np,) float64 copy; (0,) for a step (x, w). An
    :class:`~alpes_dyn.InputError` naming ``parameters`` where they do not fit the step."""
    if step.n_in() == 2:
        if parameters is not None:
            raise InputError("parameters: the step (x, w) -> x_next takes none; give a step (x, w, p) -> x_next")
        return np.zeros(0)
    n_p = int(step.nnz_in(2))
    try:
        p = np.array(parameters, dtype=float).reshape(-1) if parameters is not None else None
    except (TypeError, ValueError):
        p = None
    if p is None or p.shape != (n_p,) or np.ndim(parameters) > 1:
        raise InputError(f"parameters: expected {n_p} numbers, the step's input p, got {str(parameters)[:60]!r}")
    if not np.isfinite(p).all():
        raise InputError("parameters: contains NaN or inf")
    return np.ascontiguousarray(p)


class CompiledStepLoop:
    """x_{k+1} = step(x_k, w_k) for B sequences of N steps, in compiled C, threaded over the sequences.

    Parameters
    ----------
    step : casadi.Function
        A ``casadi.Function`` ``(x (nx,), w (nw,)) -> x_next (nx,)`` (dense columns), or ``(x, w, p (np,)) ->
        x_next`` with ``parameters``: the numbers of a model as an input (:func:`~alpes_dyn.symbolic.lifted.
        lift_constants`), so that the library is keyed on the step's structure and shared by models of other
        values.
    parameters : array_like or None, optional
        (np,) the values of p for this loop's runs (finite numbers; copied), with a step of three inputs.
    label : str, optional
        Stem of the cached library's file name.
    threads : int or None, optional
        Worker threads, 1 to 64 (default: the CPUs this process may use).
    vectorize : bool, optional
        Advance two sequences at once in SIMD lanes (GCC vector extensions; the same operations
        in the same order as the scalar code, so the same bits); falls back to scalar code when
        the step uses a construct the rewrite does not handle (``lanes`` tells which was built).
    large_level : str, optional
        The optimisation flag of a generated source over :data:`_LARGE_SOURCE` characters: ``"-O1"`` (default) or
        ``"-O0"`` (:data:`_LARGE_LEVELS`) for a loop whose build would cost more than its runs.
    level : str or None, optional
        The optimisation flag whatever the source's size, one of :data:`_LARGE_LEVELS` (default None: ``-O3`` up to
        :data:`_LARGE_SOURCE` characters, quick first: below; ``large_level`` above): ``"-O0"`` for a loop run a few
        thousand steps per process, whose ``-O3`` build costs more than its runs even below the size (the observer
        check's prediction loops of a finger: a few seconds of the compiler, for runs of a fraction of a second).

    The C source is CasADi's code of ``step`` plus a driver looping over steps and splitting the
    sequences over POSIX threads; it is compiled with ``$CC`` (default gcc) and cached in :func:`cache_dir` under a
    hash of the source and the flags, so a later construction (in any process) only loads it. Without ``level`` and
    up to :data:`_LARGE_SOURCE` characters, the ``-O3`` build is loaded if the cache holds it, else the loop is built
    at :data:`_QUICK_LEVEL` and :meth:`run` rebuilds it at ``-O3`` once it has run :data:`_PROMOTE_STEPS` steps (the
    same numbers; :meth:`step` never builds). ``compile_seconds`` is this instance's compilation time (0 when
    loaded from the cache), ``library`` the path of the shared library in use.
    """

    _quick: str | None = None  # a quick build's source, until run() promotes it (steps run: _steps)
    _steps = 0

    def __init__(self, step: cs.Function, label: str = "steploop", threads: int | None = None,
                 vectorize: bool = True, parameters: Any = None, large_level: str = "-O1",
                 level: str | None = None) -> None:
        if large_level not in _LARGE_LEVELS:
            raise InputError(f"large_level: {large_level!r} is not one of {', '.join(_LARGE_LEVELS)}")
        if level is not None and level not in _LARGE_LEVELS:
            raise InputError(f"level: {level!r} is not one of {', '.join(_LARGE_LEVELS)}")
        if step.n_in() not in (2, 3) or step.n_out() != 1:
            raise ModelError(f"step: expected a function (x, w) -> x_next or (x, w, p) -> x_next, got {step}")
        self.parameters = _step_parameters(step, parameters)
        self.nx = int(step.size1_in(0))
        self.nw = int(step.size1_in(1))
        if step.size_out(0) != (self.nx, 1) or step.size2_in(0) != 1 or step.size2_in(1) != 1:
            raise ModelError(f"step: x, w and x_next must be columns with x_next like x, got {step}")
        self.threads = _check_threads(threads)
        ins = step.sx_in() if step.is_a("SXFunction") else step.mx_in()
        step = cs.Function("alpes_step", ins, step.call(ins))  # fixed C symbol name for the driver
        cg = cs.CodeGenerator("alpes_steploop.c", {"with_header": False})
        cg.add(step)
        generated = "#define _GNU_SOURCE\n" + cg.dump()
        fmt = dict(nx=self.nx, nw=self.nw, sz_arg=step.sz_arg(), sz_res=step.sz_res(), sz_iw=step.sz_iw(),
                   sz_w=step.sz_w(), step="alpes_step", parg="arg[2] = j->P;" if step.n_in() == 3 else "")
        vector = _vector_step(generated, _LANES) if vectorize else None
        self.lanes = 1
        if vector is not None:
            try:
                self._open(generated + _DRIVER.format(lanes=_LANES, vector_code=vector, **fmt), label, large_level,
                           level)
                self.lanes = _LANES
            except CompilerError:  # a compiler without GCC vector extensions: the scalar driver
                vector = None
        if vector is None:
            self._open(generated + _DRIVER.format(lanes=1, vector_code="", **fmt), label, large_level, level)
        self._label = label
        self._pp = self.parameters.ctypes.data_as(self._dp)  # the parameters' buffer, held by this loop
        self._one: tuple | None = None  # step()'s buffers

    def _open(self, source: str, label: str, large_level: str, level: str | None) -> None:
        """Build or load ``source``'s library: at ``level`` or ``large_level`` (over the size); else its ``-O3``
        build if cached, or a quick build that :meth:`run` promotes (:data:`_PROMOTE_STEPS`)."""
        if level is None and len(source) <= _LARGE_SOURCE:
            found = cached_library(source, label, _compiler(), _CFLAGS, cache_dir())
            self._quick = None if found is not None else source
            self._bind(*(found or _build_library(source, label, level=_QUICK_LEVEL)))
        else:
            self._bind(*_build_library(source, label, large_level, level))

    def _bind(self, library: Path, compiled: bool, seconds: float, lib: ctypes.CDLL) -> None:
        """Call ``lib``'s loop from now on (its path, whether it was compiled now and the compile's seconds)."""
        fn = lib.alpes_rollout
        dp = ctypes.POINTER(ctypes.c_double)
        fn.argtypes = [dp, dp, dp, ctypes.c_long, ctypes.c_long, ctypes.c_long, ctypes.c_long, ctypes.c_int]
        fn.restype = ctypes.c_int
        self.library, self.compiled, self._lib, self._fn, self._dp = library, compiled, lib, fn, dp
        self.compile_seconds = getattr(self, "compile_seconds", 0.0) + seconds

    def step(self, x: np.ndarray, w: np.ndarray) -> np.ndarray:
        """One step of one sequence, on buffers the loop keeps (a control loop's call at each sample, without
        :meth:`run`'s batch checks and allocations); :meth:`run`'s numbers.

        Parameters
        ----------
        x : ndarray
            (nx,) the state.
        w : ndarray
            (nw,) the input held over the step.

        Returns
        -------
        ndarray
            (nx,) the next state.
        """
        if self._one is None:
            X, W = np.empty((1, 2, self.nx)), np.empty((1, 1, self.nw))
            self._one = (X, W, W.ctypes.data_as(self._dp), X.ctypes.data_as(self._dp))
        X, W, wp, xp = self._one
        X[0, 0] = x
        W[0, 0] = w
        if self._fn(wp, xp, self._pp, 1, 1, 0, 1, 1) != 0:
            raise InputError("step: the compiled step failed")
        return X[0, 1].copy()

    def run(self, x0: np.ndarray, W: np.ndarray, progress: bool = False, label: str = "rollout") -> np.ndarray:
        """The B sequences of N steps.

        Parameters
        ----------
        x0 : ndarray
            (B, nx) the initial states, float64.
        W : ndarray
            (B, N, nw) the inputs, float64 (checked by the caller).
        progress : bool, optional
            A progress bar on stderr.
        label : str, optional
            The bar's and the errors' name.

        Returns
        -------
        ndarray
            X (B, N+1, nx), X[:, 0] = x0.
        """
        x0, W, X = _batch(x0, W, self.nx, self.nw)
        B, N = W.shape[0], W.shape[1]
        chunks = 50 if progress else 1
        bar = _Progress(N, label, progress)
        edges = np.linspace(0, N, chunks + 1).astype(int)
        wp, xp = W.ctypes.data_as(self._dp), X.ctypes.data_as(self._dp)
        for k0, k1 in zip(edges[:-1], edges[1:]):
            if k1 > k0:
                if self._fn(wp, xp, self._pp, B, N, int(k0), int(k1), self.threads) != 0:
                    raise InputError(f"{label}: the compiled step failed")
                bar.update(int(k1 - k0))
        bar.close()
        self._steps += B * N
        if self._quick is not None and self._steps >= _PROMOTE_STEPS:  # its -O3 build pays from here on
            source, self._quick = self._quick, None
            with contextlib.suppress(CompilerError):  # the quick build kept
                self._bind(*_build_library(source, self._label))
        return X


class CasadiStepLoop:
    """The same batched loop as :class:`CompiledStepLoop` on CasADi's stock path: ``step.mapaccum(N)`` over
    the steps and ``.map(B, "thread", threads)`` over the batch, evaluated by CasADi's virtual machine
    (``jit=False``, no compiler needed: the fallback where no C compiler may run) or JIT-compiled by CasADi
    (``jit=True``, the system compiler through CasADi's ``shell`` JIT, rebuilt in every process: no disk cache).

    The same operations as the generated C in the same order: the states agree with
    :class:`CompiledStepLoop`'s to rounding (tested). The margin of the generated driver (SIMD lanes, threads,
    a cached library) over this path: ``benchmarks/results/rollout.json`` (``alpes_dyn_us_per_step`` against
    ``casadi_us_per_step`` and ``casadi-jit_us_per_step``).

    Parameters
    ----------
    step : casadi.Function
        The step (x (nx,), w (nw,)) -> x_next (nx,).
    threads : int or None, optional
        Threads over the batch, 1..64 (default None: the CPUs this process may use).
    jit : bool, optional
        JIT-compile the step through CasADi's ``shell`` compiler (default False: CasADi's virtual machine).

    Raises
    ------
    ModelError
        ``step`` not a function of two inputs and one output.
    InputError
        A bad ``threads``.
    """

    def __init__(self, step: cs.Function, threads: int | None = None, jit: bool = False) -> None:
        if step.n_in() != 2 or step.n_out() != 1:
            raise ModelError(f"step: expected a function (x, w) -> x_next, got {step}")
        self.nx = int(step.size1_in(0))
        self.nw = int(step.size1_in(1))
        self.threads = _check_threads(threads)
        self.jit = bool(jit)
        if self.jit:  # the step JIT-compiled once (C through CasADi's shell compiler), the loops CasADi's
            ins = step.sx_in() if step.is_a("SXFunction") else step.mx_in()
            step = cs.Function("alpes_jit_step", ins, step.call(ins),
                               {"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O2", "-ffp-contract=off"]}})
        self._step = step
        self._maps: dict[tuple[int, int], cs.Function] = {}
        self.library, self.compiled, self.compile_seconds = None, False, 0.0
        self.lanes = 1

    def _map(self, B: int, N: int) -> cs.Function:
        key = (B, N)
        if key not in self._maps:
            self._maps[key] = self._step.mapaccum(N).map(B, "thread", self.threads)
        return self._maps[key]

    def run(self, x0: np.ndarray, W: np.ndarray, progress: bool = False, label: str = "rollout") -> np.ndarray:
        """X (B, N+1, nx) from x0 (B, nx) and W (B, N, nw), as :meth:`CompiledStepLoop.run`.

        Parameters
        ----------
        x0 : numpy.ndarray, shape (B, nx)
            The initial states.
        W : numpy.ndarray, shape (B, N, nw)
            The inputs of each step.
        progress : bool, optional
            Unused here: the rollout is one CasADi evaluation (default False; :class:`CompiledStepLoop`'s interface).
        label : str, optional
            Unused here (default ``"rollout"``; :class:`CompiledStepLoop`'s interface).

        Returns
        -------
        numpy.ndarray, shape (B, N+1, nx)
            The states, X[:, 0] = x0.
        """
        x0, W, X = _batch(x0, W, self.nx, self.nw)
        B, N = W.shape[0], W.shape[1]
        # mapaccum: x0 (nx, 1), W (nw, N) -> X (nx, N); map over the batch stacks columns: (nx, B), (nw, B N)
        Xs = np.array(self._map(B, N)(x0.T, W.transpose(2, 1, 0).reshape(self.nw, N, B).transpose(0, 2, 1)
                                      .reshape(self.nw, B * N)))
        X[:, 1:] = Xs.reshape(self.nx, B, N).transpose(1, 2, 0)
        return X
