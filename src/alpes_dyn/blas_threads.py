"""One BLAS thread for a command-line process: OpenBLAS's workers spin after each call and, on a machine whose
cores are all busy, take the cores the library's compiled loops run on.

numpy and scipy each load their own OpenBLAS, whose worker threads wait by spinning; on two cores shared with other
processes a small BLAS or LAPACK call then costs its spin, not its arithmetic: on the whole Shadow hand's
identification (a band of 3840 columns, half-bandwidth 95) LAPACK's band LU took two hundred times its
one-thread CPU time, the band's solve with 500 right-hand sides six times. :func:`one_blas_thread` sets every
BLAS this process has loaded to one thread (through threadpoolctl, which knows each BLAS build's setter), unless
``OPENBLAS_NUM_THREADS`` (or ``OMP_NUM_THREADS``) names the count; the library's compiled loops keep their own
threads (:func:`alpes_dyn.simulation.codegen`'s ``threads``). ``alpes-dyn`` calls it at start, the test suite too; a Python user calls it, or sets the environment variable before importing numpy.
"""

from __future__ import annotations

import os

__all__ = ["one_blas_thread"]


def one_blas_thread() -> int:
    """Every BLAS this process has loaded (numpy's and scipy's OpenBLAS, or an MKL) set to one thread, through
    threadpoolctl, unless ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` names the count.

    Returns
    -------
    int
        The BLAS libraries set (0 where the environment names the count or none is found).
    """
    if os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS"):
        return 0
    import numpy  # noqa: F401  (both libraries loaded before they are set: scipy's is loaded by scipy.linalg)
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_info, threadpool_limits

    count = sum(1 for info in threadpool_info() if info.get("user_api") == "blas")
    threadpool_limits(limits=1, user_api="blas")  # not as a context: the limit stays for the process
    return count
