"""The iBUG-68 (300-W, dlib) points taken from MediaPipe's 478 face-mesh landmarks.

The correspondence is data (``data/mediapipe_to_ibug68.csv``, which says how it was derived): each iBUG point
lies at a fraction of the length of a path of MediaPipe landmarks. A point one landmark marks is that landmark;
a point between two is their mean; a point of a contour (jaw, nose ridge, lids, lips) is taken along
MediaPipe's denser contour at iBUG's even spacing, measured on the landmarks given (pixels or 3-D points).
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.tables import read_table

__all__ = ["IBUG68_NAMES", "ibug68", "ibug68_indices"]


@cache
def _table() -> tuple[tuple[tuple[np.ndarray, float], ...], tuple[str, ...]]:
    rows = read_table("mien.tracking", "data/mediapipe_to_ibug68.csv")
    if [int(r["ibug68"]) for r in rows] != list(range(68)):
        raise InvalidValueError("mediapipe_to_ibug68.csv", "rows", "iBUG points 0..67 in order")
    paths = []
    for row in rows:
        path = np.array([int(k) for k in row["mediapipe"].split()], dtype=np.intp)
        at = float(Fraction(row["at"]))
        if not len(path) or path.min() < 0 or path.max() >= 478 or not 0.0 <= at <= 1.0:
            raise InvalidValueError("mediapipe_to_ibug68.csv row", row["ibug68"], "landmarks 0..477 and 0 <= at <= 1")
        paths.append((path, at))
    return tuple(paths), tuple(r["name"] for r in rows)


def ibug68_indices() -> np.ndarray:
    """(68, 2) the two MediaPipe landmarks each iBUG point lies between on its path, counted in path steps
    (the same index twice where one landmark marks it); :func:`ibug68` places it by length."""
    out = np.empty((68, 2), np.intp)
    for k, (path, at) in enumerate(_table()[0]):
        step = at * (len(path) - 1)
        out[k] = path[int(np.floor(step))], path[int(np.ceil(step))]
    return out


IBUG68_NAMES: tuple[str, ...] = _table()[1]
"""Names of the 68 points (``chin``, ``eye_right_outer``...; sides are the subject's own)."""


def _along(points: np.ndarray, path: np.ndarray, at: float) -> np.ndarray:
    """(..., k) the point at fraction ``at`` of the length of the polyline ``points[..., path, :]``."""
    line = points[..., path, :]
    if len(path) == 1:
        return line[..., 0, :]
    lengths = np.linalg.norm(np.diff(line, axis=-2), axis=-1)  # (..., m - 1)
    walked = np.cumsum(lengths, axis=-1)
    goal = at * walked[..., -1:]
    # the segment the goal falls in (the last one for at = 1), and how far along it
    segment = np.minimum((walked < goal).sum(axis=-1, keepdims=True), len(path) - 2)
    end = np.take_along_axis(walked, segment, axis=-1)
    length = np.take_along_axis(lengths, segment, axis=-1)
    t = np.clip(1.0 - (end - goal) / np.where(length > 0, length, 1.0), 0.0, 1.0)
    start = np.take_along_axis(line, segment[..., None], axis=-2)[..., 0, :]
    stop = np.take_along_axis(line, segment[..., None] + 1, axis=-2)[..., 0, :]
    return start + t * (stop - start)


def ibug68(landmarks: np.ndarray) -> np.ndarray:
    """(..., 68, k) iBUG-68 points from (..., 478, k) MediaPipe landmarks (any k: 2 or 3, any units).

    >>> ibug68(np.zeros((2, 478, 3))).shape
    (2, 68, 3)
    """
    points = np.asarray(landmarks, dtype=np.float64)
    if points.ndim < 2 or points.shape[-2] < 468:
        raise InvalidValueError("landmarks", f"array of shape {points.shape}", "(..., 478, k) MediaPipe landmarks")
    return np.stack([_along(points, path, at) for path, at in _table()[0]], axis=-2)
