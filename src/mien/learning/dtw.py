"""Exact dynamic time warping (DTW) for univariate and multivariate curves.

Definition (the same as dtaidistance's ``distance`` and tslearn's ``dtw``): with the local cost
``c(i, j) = sum_k (a[i, k] - b[j, k]) ** 2`` (squared euclidean over channels),
``D(i, j) = c(i, j) + min(D(i-1, j-1), D(i-1, j), D(i, j-1))``, ``D(0, 0) = c(0, 0)``, and the distance is
``sqrt(D(n-1, m-1))``. An optional Sakoe-Chiba ``window`` follows dtaidistance: cell ``(i, j)`` is allowed when
``i - j < window + max(0, n - m)`` and ``j - i < window + max(0, m - n)`` (so ``window=1`` on equal lengths is
the euclidean distance).

Series are ``(n_frames, n_channels)`` arrays; a 1-D array is one univariate series. Collections are a
``(n_series, n_frames, n_channels)`` array, a ``(n_series, n_frames)`` array (univariate, as in tslearn) or a
list of ``(n_frames_i, n_channels)`` arrays of different lengths.

The kernels are compiled with numba (``pip install 'mien[laughter]'``): one pair is an anti-diagonal sweep whose
inner loops vectorise, and matrices run the pairs in parallel (``prange``). Without numba the same kernels run
as plain Python (correct, slow). :func:`dtw_distance_reference` is a direct full-matrix implementation kept for
tests.

>>> import numpy as np
>>> round(dtw_distance(np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.0, 1.0, 2.0])), 6)
0.0
>>> round(dtw_distance(np.array([0.0, 1.0]), np.array([0.0, 3.0])), 6)
2.0
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import available, require

__all__ = [
    "as_series",
    "as_series_list",
    "dtw_cross_distance_matrix",
    "dtw_distance",
    "dtw_distance_matrices_per_channel",
    "dtw_distance_matrix",
    "dtw_distance_reference",
    "dtw_path",
    "have_numba",
]

_numba: Any
_HAVE_NUMBA = available("numba")
if _HAVE_NUMBA:
    _numba = require("numba", "fast")
    _njit: Callable[..., Any] = _numba.njit
    _prange: Callable[..., Any] = _numba.prange
else:  # pragma: no cover - exercised only without numba
    _numba = None
    _prange = range

    def _njit(*args: Any, **kwargs: Any) -> Any:
        if args and callable(args[0]):
            return args[0]
        return lambda function: function


SeriesInput = np.ndarray | Sequence[np.ndarray]
"""A collection of series: ``(n_series, n_frames[, n_channels])`` array or list of ``(n_frames_i[, c])`` arrays."""

_NO_WINDOW = 1 << 40


def have_numba() -> bool:
    """True when the numba kernels are compiled (otherwise they run as slow plain Python)."""
    return _HAVE_NUMBA


# ---------------------------------------------------------------------------------------------------------------
# Kernels


@_njit(cache=True, nogil=True)
def _pair_sq(
    data: np.ndarray,
    data_rev: np.ndarray,
    offset_a: int,
    n: int,
    offset_b: int,
    m: int,
    k0: int,
    k1: int,
    window: int,
    buf: np.ndarray,
) -> float:
    """Squared DTW cost between two packed series, channels ``k0:k1``, by anti-diagonals.

    ``data`` is ``(c, total)`` channel-major, ``data_rev`` the same with every series reversed in time, so the
    local costs along an anti-diagonal read both series contiguously. ``buf`` is ``(4, n + 2)`` scratch.
    """
    inf = np.inf
    wl = window - 1 + max(0, n - m)  # allowed i - j
    wu = window - 1 + max(0, m - n)  # allowed j - i
    prev2 = buf[0]
    prev1 = buf[1]
    cur = buf[2]
    cost = buf[3]
    for q in range(n + 2):
        prev2[q] = inf
        prev1[q] = inf
        cur[q] = inf
    # Unsigned indices: numba then emits no negative-index wraparound, so the inner loops vectorise.
    one = np.uint64(1)
    for d in range(n + m - 1):
        lo = max(0, d - m + 1, (d - wu + 1) // 2)
        hi = min(d, n - 1, (d + wl) // 2)
        count = np.uint64(hi + 1 - lo)
        row0 = np.uint64(lo)
        a0 = np.uint64(offset_a + lo)
        # b[j] with j = d - i is data_rev[m - 1 - j] = data_rev[(m - 1 - d) + i]
        b0 = np.uint64(offset_b + m - 1 - d + lo)
        for t in range(count):
            cost[row0 + t] = 0.0
        for k in range(k0, k1):
            channel = np.uint64(k)
            for t in range(count):
                diff = data[channel, a0 + t] - data_rev[channel, b0 + t]
                cost[row0 + t] += diff * diff
        if d == 0:
            cur[1] = cost[0]
        else:
            for t in range(count):
                i = row0 + t
                best = prev2[i]
                up = prev1[i]
                left = prev1[i + one]
                if up < best:
                    best = up
                if left < best:
                    best = left
                cur[i + one] = cost[i] + best
        cur[lo] = inf
        cur[hi + 2] = inf
        prev2, prev1, cur = prev1, cur, prev2
    return float(prev1[n])


@_njit(cache=True, parallel=True)
def _pairs_kernel(
    data: np.ndarray,
    data_rev: np.ndarray,
    offsets: np.ndarray,
    lengths: np.ndarray,
    first: np.ndarray,
    second: np.ndarray,
    channel_ranges: np.ndarray,
    window: int,
    out: np.ndarray,
) -> None:
    """``out[r, p] = sqrt(D)`` for pair ``(first[p], second[p])`` and channel range ``channel_ranges[r]``."""
    n_pairs = first.shape[0]
    n_ranges = channel_ranges.shape[0]
    max_len = 0
    for s in range(lengths.shape[0]):
        max_len = max(max_len, lengths[s])
    for t in _prange(n_pairs * n_ranges):
        r = t // n_pairs
        p = t - r * n_pairs
        a = first[p]
        b = second[p]
        buf = np.empty((4, max_len + 2))
        value = _pair_sq(
            data,
            data_rev,
            offsets[a],
            lengths[a],
            offsets[b],
            lengths[b],
            channel_ranges[r, 0],
            channel_ranges[r, 1],
            window,
            buf,
        )
        out[r, p] = math.sqrt(value)


@_njit(cache=True)
def _path_kernel(a: np.ndarray, b: np.ndarray, window: int) -> tuple[np.ndarray, float]:
    """Full accumulated-cost matrix and back-tracked optimal path (diagonal preferred on ties)."""
    n = a.shape[0]
    m = b.shape[0]
    c = a.shape[1]
    wl = window - 1 + max(0, n - m)
    wu = window - 1 + max(0, m - n)
    acc = np.full((n + 1, m + 1), np.inf)
    acc[0, 0] = 0.0
    for i in range(n):
        j_start = max(0, i - wl)
        j_end = min(m, i + wu + 1)
        for j in range(j_start, j_end):
            cost = 0.0
            for k in range(c):
                diff = a[i, k] - b[j, k]
                cost += diff * diff
            best = acc[i, j]
            if acc[i, j + 1] < best:
                best = acc[i, j + 1]
            if acc[i + 1, j] < best:
                best = acc[i + 1, j]
            acc[i + 1, j + 1] = cost + best
    path = np.empty((n + m, 2), dtype=np.int64)
    i = n
    j = m
    length = 0
    while True:
        path[length, 0] = i - 1
        path[length, 1] = j - 1
        length += 1
        if i == 1 and j == 1:
            break
        diag = acc[i - 1, j - 1]
        up = acc[i - 1, j]
        left = acc[i, j - 1]
        if diag <= up and diag <= left:
            i -= 1
            j -= 1
        elif up <= left:
            i -= 1
        else:
            j -= 1
    return path[:length][::-1].copy(), math.sqrt(acc[n, m])


# ---------------------------------------------------------------------------------------------------------------
# Input handling


def as_series(values: Any, name: str = "series") -> np.ndarray:
    """One series as a ``(n_frames, n_channels)`` C-contiguous float64 array (1-D input: one channel).

    Raises :class:`InvalidValueError` naming ``name`` on a wrong shape, no frames or a non-finite value.
    """
    array = np.asarray(values, dtype=np.float64)
    if array.ndim == 1:
        array = array[:, None]
    if array.ndim != 2:
        raise InvalidValueError(name, f"array of shape {array.shape}", "(n_frames,) or (n_frames, n_channels)")
    if array.shape[0] == 0:
        raise InvalidValueError(name, "0 frames", "at least 1 frame")
    if array.shape[1] == 0:
        raise InvalidValueError(name, "0 channels", "at least 1 channel")
    if not np.all(np.isfinite(array)):
        frame, channel = np.argwhere(~np.isfinite(array))[0]
        raise InvalidValueError(f"{name}[{frame}, {channel}]", array[frame, channel], "a finite number")
    return np.ascontiguousarray(array)


def as_series_list(series: SeriesInput, name: str = "series") -> list[np.ndarray]:
    """Validate a collection of series into a list of ``(n_frames_i, n_channels)`` float64 arrays.

    Accepts ``(n_series, n_frames, n_channels)``, ``(n_series, n_frames)`` (univariate) or a list of arrays.
    Raises :class:`InvalidValueError` on an empty collection, an empty series, a non-finite value or a channel
    count that differs between series.
    """
    if isinstance(series, np.ndarray):
        if series.ndim not in (2, 3):
            raise InvalidValueError(
                name, f"array of shape {series.shape}", "(n_series, n_frames) or (n_series, n_frames, n_channels)"
            )
        items: Sequence[Any] = list(series)
    else:
        items = list(series)
    if len(items) == 0:
        raise InvalidValueError(name, "0 series", "at least one series")
    out = [as_series(item, f"{name}[{index}]") for index, item in enumerate(items)]
    channels = out[0].shape[1]
    for index, item in enumerate(out):
        if item.shape[1] != channels:
            raise InvalidValueError(
                f"{name}[{index}]", f"{item.shape[1]} channels", f"{channels} channels like {name}[0]"
            )
    return out


def _check_window(window: int | None) -> int:
    if window is None:
        return _NO_WINDOW
    if isinstance(window, bool) or not isinstance(window, int | np.integer) or window < 1:
        raise InvalidValueError("window", window, "None or an integer >= 1 (frames)")
    return int(window)


def _pack(series: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Channel-major packing: data ``(c, total)``, time-reversed copy, offsets and lengths ``(n_series,)``."""
    lengths = np.array([s.shape[0] for s in series], dtype=np.int64)
    offsets = np.concatenate(([0], np.cumsum(lengths)[:-1])).astype(np.int64)
    data = np.ascontiguousarray(np.concatenate(series, axis=0).T)
    data_rev = np.ascontiguousarray(np.concatenate([s[::-1] for s in series], axis=0).T)
    return data, data_rev, offsets, lengths


def _run_pairs(
    series: list[np.ndarray],
    first: np.ndarray,
    second: np.ndarray,
    channel_ranges: np.ndarray,
    window: int,
    n_jobs: int | None,
) -> np.ndarray:
    """(n_ranges, n_pairs) DTW distances, using ``n_jobs`` numba threads (None: all)."""
    data, data_rev, offsets, lengths = _pack(series)
    out = np.zeros((channel_ranges.shape[0], first.shape[0]))
    if first.shape[0] == 0:
        return out
    args = (data, data_rev, offsets, lengths, first, second, channel_ranges, window, out)
    if n_jobs is not None and (isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or n_jobs < 1):
        raise InvalidValueError("n_jobs", n_jobs, "None (all cores) or an integer >= 1")
    if _numba is None or n_jobs is None:
        _pairs_kernel(*args)
        return out
    previous = _numba.get_num_threads()
    _numba.set_num_threads(min(n_jobs, int(_numba.config.NUMBA_NUM_THREADS)))
    try:
        _pairs_kernel(*args)
    finally:
        _numba.set_num_threads(previous)
    return out


def _upper_pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    first, second = np.triu_indices(n, k=1)
    return first.astype(np.int64), second.astype(np.int64)


def _symmetric(values: np.ndarray, n: int) -> np.ndarray:
    """(n, n) symmetric matrix with zero diagonal from upper-triangle values in ``np.triu_indices`` order."""
    matrix = np.zeros((n, n))
    first, second = np.triu_indices(n, k=1)
    matrix[first, second] = values
    matrix[second, first] = values
    return matrix


# ---------------------------------------------------------------------------------------------------------------
# Public API


def dtw_distance(a: np.ndarray, b: np.ndarray, window: int | None = None) -> float:
    """DTW distance between two series.

    ``a`` : (n,) or (n, c) float; ``b`` : (m,) or (m, c) float (same ``c``); ``window`` : Sakoe-Chiba band in
    frames (module docstring) or None. Returns the distance in the units of the values.
    """
    pair = [as_series(a, "a"), as_series(b, "b")]
    if pair[0].shape[1] != pair[1].shape[1]:
        raise InvalidValueError("b", f"{pair[1].shape[1]} channels", f"{pair[0].shape[1]} channels like a")
    channels = np.array([[0, pair[0].shape[1]]], dtype=np.int64)
    out = _run_pairs(pair, np.array([0]), np.array([1]), channels, _check_window(window), 1)
    return float(out[0, 0])


def dtw_path(a: np.ndarray, b: np.ndarray, window: int | None = None) -> tuple[np.ndarray, float]:
    """Optimal warping path and DTW distance.

    Returns ``(path, distance)``: ``path`` is ``(k, 2)`` int64 of matched frame indices ``(i, j)`` from
    ``(0, 0)`` to ``(n - 1, m - 1)``, each step advancing ``i``, ``j`` or both by one.

    >>> import numpy as np
    >>> path, distance = dtw_path(np.array([0.0, 1.0, 1.0]), np.array([0.0, 1.0]))
    >>> path.tolist(), distance
    ([[0, 0], [1, 1], [2, 1]], 0.0)
    """
    first = as_series(a, "a")
    second = as_series(b, "b")
    if first.shape[1] != second.shape[1]:
        raise InvalidValueError("b", f"{second.shape[1]} channels", f"{first.shape[1]} channels like a")
    path, distance = _path_kernel(first, second, _check_window(window))
    return path, float(distance)


def dtw_distance_matrix(series: SeriesInput, window: int | None = None, n_jobs: int | None = None) -> np.ndarray:
    """(n_series, n_series) symmetric float64 DTW distances (multivariate cost over all channels).

    ``series``: see the module docstring. ``n_jobs``: numba threads (None: all). The diagonal is 0.
    """
    items = as_series_list(series)
    first, second = _upper_pairs(len(items))
    channels = np.array([[0, items[0].shape[1]]], dtype=np.int64)
    values = _run_pairs(items, first, second, channels, _check_window(window), n_jobs)
    return _symmetric(values[0], len(items))


def dtw_distance_matrices_per_channel(
    series: SeriesInput, window: int | None = None, n_jobs: int | None = None
) -> np.ndarray:
    """(n_channels, n_series, n_series) univariate DTW distance matrices, one per channel.

    The paper's Table 3 is one such matrix (one controller of one expression type across performers).
    """
    items = as_series_list(series)
    n_channels = items[0].shape[1]
    first, second = _upper_pairs(len(items))
    channels = np.stack([np.arange(n_channels), np.arange(1, n_channels + 1)], axis=1).astype(np.int64)
    values = _run_pairs(items, first, second, channels, _check_window(window), n_jobs)
    return np.stack([_symmetric(values[k], len(items)) for k in range(n_channels)])


def dtw_cross_distance_matrix(
    series_a: SeriesInput, series_b: SeriesInput, window: int | None = None, n_jobs: int | None = None
) -> np.ndarray:
    """(n_a, n_b) DTW distances between every series of ``series_a`` and every series of ``series_b``."""
    items_a = as_series_list(series_a, "series_a")
    items_b = as_series_list(series_b, "series_b")
    if items_a[0].shape[1] != items_b[0].shape[1]:
        raise InvalidValueError(
            "series_b", f"{items_b[0].shape[1]} channels", f"{items_a[0].shape[1]} channels like series_a"
        )
    first, second = np.meshgrid(np.arange(len(items_a)), np.arange(len(items_b)) + len(items_a), indexing="ij")
    channels = np.array([[0, items_a[0].shape[1]]], dtype=np.int64)
    values = _run_pairs(
        items_a + items_b,
        first.ravel().astype(np.int64),
        second.ravel().astype(np.int64),
        channels,
        _check_window(window),
        n_jobs,
    )
    return values[0].reshape(len(items_a), len(items_b))


def dtw_distance_reference(a: np.ndarray, b: np.ndarray, window: int | None = None) -> float:
    """Straightforward full-matrix DTW in numpy/Python (slow; the definition the kernels are tested against)."""
    first = as_series(a, "a")
    second = as_series(b, "b")
    n, m = first.shape[0], second.shape[0]
    band = _check_window(window)
    cost = ((first[:, None, :] - second[None, :, :]) ** 2).sum(axis=2)
    acc = np.full((n + 1, m + 1), np.inf)
    acc[0, 0] = 0.0
    for i in range(n):
        for j in range(m):
            if i - j >= band + max(0, n - m) or j - i >= band + max(0, m - n):
                continue
            acc[i + 1, j + 1] = cost[i, j] + min(acc[i, j], acc[i, j + 1], acc[i + 1, j])
    return math.sqrt(acc[n, m])
