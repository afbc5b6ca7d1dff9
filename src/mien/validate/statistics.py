"""The statistics validation reports: Pearson's r, least-squares slopes, Wilson intervals of shares.

Numpy only. One Pearson correlation serves every report: :func:`pearson` along an axis (activation maps, their
rows) and :func:`pearson_r` over the finite pairs of two series (rig fidelity). A correlation with no variance
is NaN, never a 0 that would read as "unrelated".

>>> round(pearson_r(np.array([0.0, 1, 2, 3]), np.array([0.0, 2, 4, 7])), 4)
0.9944
>>> [round(x, 2) for x in wilson_interval(7, 8)]
[0.53, 0.98]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MIN_SPREAD", "finite_pairs", "least_squares_slope", "pearson", "pearson_r", "wilson_interval"]

MIN_SPREAD = 1e-12
"""A sum of squared deviations (or their product) at or below this is no variance: the statistic is NaN."""


def pearson(a: np.ndarray, b: np.ndarray, axis: int | None = None) -> np.ndarray:
    """Pearson correlation of ``a`` and ``b`` (same shape, finite) along ``axis`` (None: over all cells), in
    [-1, 1]; NaN where either has no variance.

    >>> pearson(np.array([[0.0, 1, 3], [2, 2, 0]]), np.array([[0.0, 2, 6], [1, 1, 1]]), axis=1).tolist()
    [1.0, nan]
    """
    first, second = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    da = first - first.mean(axis=axis, keepdims=True)
    db = second - second.mean(axis=axis, keepdims=True)
    denominator = np.sqrt((da * da).sum(axis=axis) * (db * db).sum(axis=axis))
    numerator = (da * db).sum(axis=axis)
    defined = denominator > MIN_SPREAD
    r = np.where(defined, numerator / np.where(defined, denominator, 1.0), np.nan)
    return np.clip(r, -1.0, 1.0)


def finite_pairs(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(x, y)`` as float64 arrays ((n,) each) without the pairs where either is NaN or infinite."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    keep = np.isfinite(x) & np.isfinite(y)
    return x[keep], y[keep]


def pearson_r(x: np.ndarray, y: np.ndarray) -> float:
    """Pearson correlation of the finite pairs of ``x`` and ``y`` ((n,) each); NaN when fewer than 3 pairs or
    either is constant."""
    x, y = finite_pairs(x, y)
    if len(x) < 3:
        return math.nan
    return float(pearson(x, y))


def least_squares_slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope (with an intercept) of ``y`` on ``x`` over their finite pairs; NaN when fewer than 2
    pairs or ``x`` is constant.

    >>> least_squares_slope(np.array([0.0, 1, 2, 3]), np.array([0.0, 2, 4, 7]))
    2.3
    """
    x, y = finite_pairs(x, y)
    if len(x) < 2:
        return math.nan
    dx = x - x.mean()
    spread = float(dx @ dx)
    if spread <= MIN_SPREAD:
        return math.nan
    return float(dx @ (y - y.mean())) / spread


def wilson_interval(hits: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval (95% for ``z`` = 1.96) of a share of ``hits`` in ``n``; (nan, nan) for n = 0.

    >>> [round(x, 2) for x in wilson_interval(0, 8)]
    [0.0, 0.32]
    """
    if n <= 0:
        return float("nan"), float("nan")
    p = hits / n
    scale = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / scale
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / scale
    return max(centre - half, 0.0), min(centre + half, 1.0)
