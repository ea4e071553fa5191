"""One BLAS thread for a command-line process: OpenBLAS's workers spin after each call and, on a machine whose
cores are all busy, take the cores the library's compiled loops run on.

numpy and scipy each load their own OpenBLAS, whose worker threads wait by spinning; on two cores shared with other
processes a small BLAS or LAPACK call then costs its spin, not its arithmetic: on the whole Shadow hand's
identification (a band of 3840 columns, half-bandwidth 95) LAPACK's band LU took two hundred times its
one-thread CPU time, the band's solve with 500 right-hand sides six times. :func:`one_blas_thread` sets every
OpenBLAS this process has loaded to one thread, unless ``OPENBLAS_NUM_THREADS`` (or ``OMP_NUM_THREADS``) names the
count; the library's compiled loops keep their own threads (:func:`alpes_dyn.simulation.codegen`'s ``threads``).
``alpes-dyn`` calls it at start; a Python user sets the environment variable before importing numpy instead.
"""

from __future__ import annotations

import ctypes
import os

__all__ = ["SETTERS", "one_blas_thread"]

SETTERS = ("openblas_set_num_threads", "scipy_openblas_set_num_threads", "scipy_openblas_set_num_threads64_")
"""The names under which an OpenBLAS exports its thread-count setter (upstream, scipy's and numpy's builds)."""


def _loaded_openblas() -> list[str]:
    """The paths of the OpenBLAS libraries this process has loaded (Linux's ``/proc/self/maps``; none elsewhere)."""
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as f:
            paths = {line.split()[-1] for line in f if "openblas" in line.rsplit("/", 1)[-1]}
    except OSError:
        return []
    return sorted(p for p in paths if p.startswith("/"))


def one_blas_thread() -> int:
    """Every loaded OpenBLAS set to one thread, unless ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` is set.

    Returns
    -------
    int
        The libraries set (0 where the environment names the count or none is found).
    """
    if os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS"):
        return 0
    import numpy  # noqa: F401  (both libraries loaded before they are set: scipy's is loaded by scipy.linalg)
    import scipy.linalg  # noqa: F401

    count = 0
    for path in _loaded_openblas():
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for name in SETTERS:
            setter = getattr(lib, name, None)
            if setter is not None:
                setter.argtypes = [ctypes.c_int]
                setter(1)
                count += 1
                break
    return count
