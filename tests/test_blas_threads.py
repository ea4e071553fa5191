"""alpes-dyn's one BLAS thread (blas_threads): every loaded BLAS reads back one thread (threadpoolctl's own
report), the environment's count is left alone, and the numbers do not change."""

from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

from alpes_dyn import blas_threads


def _counts() -> list[int]:
    """Each loaded BLAS's thread count, as threadpoolctl reads it from the library."""
    return [int(i["num_threads"]) for i in threadpool_info() if i.get("user_api") == "blas"]


def test_every_loaded_blas_set_to_one_thread(monkeypatch):
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    rng = np.random.default_rng(3)
    a = rng.standard_normal((300, 300))
    before = a @ a.T
    with threadpool_limits(limits=2, user_api="blas"):  # restored after: the rest of the session as it was
        assert all(c >= 1 for c in _counts())
        n = blas_threads.one_blas_thread()
        counts = _counts()
        assert counts, "numpy and scipy load at least one BLAS"
        assert n == len(counts) and counts == [1] * len(counts)
        np.testing.assert_allclose(a @ a.T, before, rtol=1e-12, atol=1e-10)


def test_the_environment_s_count_is_left_alone(monkeypatch):
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    assert blas_threads.one_blas_thread() == 0
