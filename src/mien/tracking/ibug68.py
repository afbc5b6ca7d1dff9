"""The iBUG-68 (300-W, dlib) points taken from MediaPipe's 478 face-mesh landmarks.

The correspondence is data (``data/mediapipe_to_ibug68.csv``, which says how it was derived); a point that
falls between two mesh vertices is their mean.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.tables import read_table

__all__ = ["IBUG68_NAMES", "ibug68", "ibug68_indices"]


@cache
def _table() -> tuple[np.ndarray, tuple[str, ...]]:
    rows = read_table("mien.tracking", "data/mediapipe_to_ibug68.csv")
    pairs = np.array([(int(r["mediapipe_a"]), int(r["mediapipe_b"] or r["mediapipe_a"])) for r in rows], dtype=np.intp)
    if [int(r["ibug68"]) for r in rows] != list(range(68)):
        raise InvalidValueError("mediapipe_to_ibug68.csv", "rows", "iBUG points 0..67 in order")
    return pairs, tuple(r["name"] for r in rows)


def ibug68_indices() -> np.ndarray:
    """(68, 2) MediaPipe landmark indices per iBUG point (the same index twice where one vertex suffices)."""
    return _table()[0].copy()


IBUG68_NAMES: tuple[str, ...] = _table()[1]
"""Names of the 68 points (``chin``, ``eye_right_outer``...; sides are the subject's own)."""


def ibug68(landmarks: np.ndarray) -> np.ndarray:
    """(..., 68, k) iBUG-68 points from (..., 478, k) MediaPipe landmarks (any k: 2 or 3, any units).

    >>> ibug68(np.zeros((2, 478, 3))).shape
    (2, 68, 3)
    """
    points = np.asarray(landmarks)
    if points.ndim < 2 or points.shape[-2] < 468:
        raise InvalidValueError("landmarks", f"array of shape {points.shape}", "(..., 478, k) MediaPipe landmarks")
    pairs = _table()[0]
    return 0.5 * (points[..., pairs[:, 0], :] + points[..., pairs[:, 1], :])
