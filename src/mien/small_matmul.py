"""Matrix products of many small rows that never go through a multi-threaded BLAS.

A per-tick product such as (n_characters, 6) @ (6, 62) or (n, 62) @ (62, 52) is small, but OpenBLAS spreads any
product of more than ``m * n * k = 262,144`` multiply-adds over all its threads, and on a machine whose cores
are busy that hand-off costs far more than the arithmetic (a 100x slowdown was measured at 1,000 rows on two
loaded cores). :func:`matmul_rows` cuts the rows into chunks below that threshold, so each call stays on the
calling thread whatever ``OPENBLAS_NUM_THREADS`` says, with no extra dependency and no allocation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["SINGLE_THREAD_MNK", "matmul_rows"]

SINGLE_THREAD_MNK = 65_536
"""Largest ``rows * k * n`` of one BLAS call (a quarter of OpenBLAS's multi-threading threshold)."""


def matmul_rows(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> np.ndarray:
    """``out[:] = a @ b`` for (m, k) ``a`` and (k, n) ``b``, in row chunks that BLAS runs single-threaded.

    ``out`` is a C-contiguous (m, n) array of the product's dtype (``a`` and ``b`` of one dtype). Returns ``out``.

    >>> a = np.arange(6.0).reshape(3, 2); b = np.eye(2)
    >>> matmul_rows(a, b, np.empty((3, 2))).tolist()
    [[0.0, 1.0], [2.0, 3.0], [4.0, 5.0]]
    """
    m, k = a.shape
    n = b.shape[1]
    step = max(1, SINGLE_THREAD_MNK // max(1, k * n))
    if m <= step:
        return np.matmul(a, b, out=out)
    for start in range(0, m, step):
        np.matmul(a[start : start + step], b, out=out[start : start + step])
    return out
