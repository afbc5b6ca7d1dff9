"""Error-bounded key reduction: a sampled curve -> few keys joined by straight lines.

The kept keys are a subset of the samples (always the first and the last). Between two kept keys the curve
is the straight line through them, and every original sample lies within ``tolerance`` (absolute, in the
curve's units) of that line, measured vertically (value error at the sample's own time). The keys are found by
Ramer-Douglas-Peucker splitting with the vertical error: a segment whose worst sample is off by more than the
tolerance is split at that sample, until no segment is.

:data:`DEFAULT_RELATIVE_TOLERANCE` (0.5 % of the curve's value range) is the tolerance used by the ``.anim``
writer when none is given.

>>> import numpy as np
>>> times = np.arange(5) / 30.0
>>> reduce_keys(times, np.array([0.0, 1.0, 2.0, 3.0, 0.0]), tolerance=1e-9).tolist()
[0, 3, 4]
"""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError

__all__ = ["DEFAULT_RELATIVE_TOLERANCE", "default_tolerance", "interpolate_keys", "reduce_keys"]

DEFAULT_RELATIVE_TOLERANCE = 0.005
"""Default key-reduction tolerance as a fraction of the curve's value range (max - min)."""


def default_tolerance(values: np.ndarray, relative: float = DEFAULT_RELATIVE_TOLERANCE) -> float:
    """``relative`` times the value range of ``values`` (0 for a constant curve): an absolute tolerance."""
    array = np.asarray(values, dtype=np.float64)
    return float(relative * (array.max() - array.min())) if array.size else 0.0


def _check(times: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(times, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if t.ndim != 1 or v.shape != t.shape or t.size == 0:
        raise InvalidValueError("values", f"shape {v.shape} for times of shape {t.shape}", "(n,) and (n,), n >= 1")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
        raise InvalidValueError("values", "non-finite entries", "finite times and values")
    if np.any(np.diff(t) <= 0):
        index = int(np.argmax(np.diff(t) <= 0)) + 1
        raise InvalidValueError(f"times[{index}]", float(t[index]), "strictly increasing times")
    return t, v


def reduce_keys(times: np.ndarray, values: np.ndarray, tolerance: float) -> np.ndarray:
    """Indices (k,) int64, increasing, of the samples to keep as linear keys.

    ``times`` (n,) strictly increasing seconds (or frames); ``values`` (n,); ``tolerance`` >= 0 absolute.
    Guarantee: ``abs(interpolate_keys(times[kept], values[kept], times) - values) <= tolerance`` for every
    sample (computed in float64 with the same formula as :func:`interpolate_keys`).
    """
    t, v = _check(times, values)
    if not np.isfinite(tolerance) or tolerance < 0:
        raise InvalidValueError("tolerance", tolerance, "a finite number >= 0")
    n = t.size
    if n <= 2:
        return np.arange(n, dtype=np.int64)
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    stack = [(0, n - 1)]
    while stack:
        start, end = stack.pop()
        if end - start < 2:
            continue
        inner = slice(start + 1, end)
        line = _line(t[start], v[start], t[end], v[end], t[inner])
        errors = np.abs(line - v[inner])
        worst = int(np.argmax(errors))
        if errors[worst] > tolerance:
            split = start + 1 + worst
            keep[split] = True
            stack.append((split, end))
            stack.append((start, split))
    return np.flatnonzero(keep).astype(np.int64)


def _line(t0: float, v0: float, t1: float, v1: float, t: np.ndarray) -> np.ndarray:
    """Values at ``t`` on the straight line through ``(t0, v0)`` and ``(t1, v1)``."""
    fraction = (t - t0) / (t1 - t0)
    return v0 + fraction * (v1 - v0)


def interpolate_keys(key_times: np.ndarray, key_values: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Piecewise-linear evaluation of keys at ``times`` (constant before the first / after the last key)."""
    kt, kv = _check(key_times, key_values)
    t = np.asarray(times, dtype=np.float64)
    if kt.size == 1:
        return np.full(t.shape, kv[0])
    segment = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, kt.size - 2)
    out = _line(kt[segment], kv[segment], kt[segment + 1], kv[segment + 1], t)  # type: ignore[arg-type]
    out = np.where(t <= kt[0], kv[0], out)
    return np.where(t >= kt[-1], kv[-1], out)
