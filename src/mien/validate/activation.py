"""AU activation maps (AU x time) and their 2D correlation, as in OpenFACS's synthetic-expert validation.

An activation map has one row per AU and one column per time sample: a detector's AU intensities (0..5)
over a clip, linearly resampled in time to a common number of samples, so clips of different lengths and
frame rates can be compared cell by cell (Cuculo & D'Amelio 2019, Fig. 5).

:func:`map_correlation` is MATLAB's ``corr2``: the Pearson correlation over all cells of two maps. A map
(or AU row) with no variance has no defined correlation; mien returns NaN for it, as ``corr2`` does, rather
than a 0 that would read as "unrelated", and :func:`correlation_note` says why in words for reports.

>>> times = np.array([0.0, 0.5, 1.0])
>>> activation_map(np.array([[0.0], [2.0], [4.0]]), times, length=5).round(2).tolist()
[[0.0, 1.0, 2.0, 3.0, 4.0]]
>>> a = np.array([[0.0, 1.0, 3.0], [2.0, 2.0, 0.0]])
>>> round(map_correlation(a, a), 12), map_correlation(a, np.ones_like(a))
(1.0, nan)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mien.errors import InvalidValueError
from mien.validate.statistics import pearson

__all__ = [
    "DEFAULT_LENGTH",
    "MIN_SAMPLES",
    "activation_map",
    "correlation_note",
    "map_correlation",
    "row_correlations",
]

DEFAULT_LENGTH = 100
"""Time samples per activation map by default."""

MIN_SAMPLES = 2
"""Fewest time samples a clip (and a resampled map) may have: linear interpolation needs two."""


def activation_map(
    aus_over_time: np.ndarray,
    times_s: np.ndarray | Sequence[float],
    length: int = DEFAULT_LENGTH,
    span_s: tuple[float, float] | None = None,
) -> np.ndarray:
    """(n_aus, length) float64 activation map of AU intensities over time.

    aus_over_time: (n_frames, n_aus) intensities 0..5, one row per frame. times_s: (n_frames,) strictly
    increasing frame times in seconds (frames may be irregular, or have gaps where no face was found).
    length: samples of the map, evenly spaced from ``span_s[0]`` to ``span_s[1]`` (default the first and
    last frame time), both endpoints included; samples outside the frames take the nearest frame's value.
    """
    values = np.asarray(aus_over_time, dtype=np.float64)
    times = np.asarray(times_s, dtype=np.float64)
    if values.ndim != 2 or not np.all(np.isfinite(values)):
        raise InvalidValueError("aus_over_time", f"array of shape {values.shape}", "(n_frames, n_aus) finite values")
    if times.shape != (values.shape[0],) or not np.all(np.isfinite(times)):
        raise InvalidValueError("times_s", f"array of shape {times.shape}", f"({values.shape[0]},) finite seconds")
    if values.shape[0] < MIN_SAMPLES:
        raise InvalidValueError("aus_over_time", f"{values.shape[0]} frame(s)", f"at least {MIN_SAMPLES} frames")
    if np.any(np.diff(times) <= 0):
        raise InvalidValueError("times_s", times.tolist()[:8], "strictly increasing frame times")
    if int(length) != length or length < MIN_SAMPLES:
        raise InvalidValueError("length", length, f"an integer >= {MIN_SAMPLES}")
    start, stop = (float(times[0]), float(times[-1])) if span_s is None else (float(span_s[0]), float(span_s[1]))
    if not (np.isfinite(start) and np.isfinite(stop) and stop > start):
        raise InvalidValueError("span_s", span_s, "(start, stop) seconds with stop > start")
    grid = np.linspace(start, stop, int(length))
    return np.stack([np.interp(grid, times, column) for column in values.T])


def _check_pair(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    first, second = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    if first.shape != second.shape or first.ndim != 2:
        raise InvalidValueError("maps", f"shapes {first.shape} and {second.shape}", "two (n_aus, length) maps")
    if not (np.all(np.isfinite(first)) and np.all(np.isfinite(second))):
        raise InvalidValueError("maps", "non-finite cells", "finite activation values")
    return first, second


def map_correlation(a: np.ndarray, b: np.ndarray) -> float:
    """2D correlation coefficient of two (n_aus, length) maps (MATLAB ``corr2``), in [-1, 1].

    NaN when either map is constant (no variance: the correlation is undefined).
    """
    first, second = _check_pair(a, b)
    return float(pearson(first.ravel(), second.ravel(), axis=None))


def row_correlations(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n_aus,) Pearson correlation of each AU row of ``a`` with the same row of ``b``; NaN for a constant row."""
    first, second = _check_pair(a, b)
    return np.asarray(pearson(first, second, axis=1), dtype=np.float64)


def correlation_note(a: np.ndarray, b: np.ndarray, what: str = "map") -> str:
    """Why a correlation of ``a`` with ``b`` is undefined (``""`` when it is defined)."""
    flat = [name for name, m in (("first", a), ("second", b)) if np.ptp(np.asarray(m, dtype=np.float64)) == 0]
    if not flat:
        return ""
    return f"undefined: the {' and '.join(flat)} {what}{'s are' if len(flat) > 1 else ' is'} constant (no variance)"
