"""alpes-dyn's one BLAS thread (blas_threads): every OpenBLAS the process loaded reads back one thread, the
environment's count is left alone, and the numbers do not change."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from alpes_dyn import blas_threads


def _counts() -> list[int]:
    """Each loaded OpenBLAS's thread count, read by its own getter."""
    out = []
    for path in blas_threads._loaded_openblas():
        lib = ctypes.CDLL(path)
        for name in ("openblas_get_num_threads", "scipy_openblas_get_num_threads", "scipy_openblas_get_num_threads64_"):
            getter = getattr(lib, name, None)
            if getter is not None:
                out.append(int(getter()))
                break
    return out


def test_every_loaded_openblas_set_to_one_thread(monkeypatch):
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    rng = np.random.default_rng(3)
    a = rng.standard_normal((300, 300))
    before = a @ a.T
    n = blas_threads.one_blas_thread()
    counts = _counts()
    if not counts:
        pytest.skip("no OpenBLAS loaded (numpy built on another BLAS)")
    assert n == len(counts) and counts == [1] * len(counts)
    np.testing.assert_allclose(a @ a.T, before, rtol=1e-12, atol=1e-10)


def test_the_environment_s_count_is_left_alone(monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    assert blas_threads.one_blas_thread() == 0
