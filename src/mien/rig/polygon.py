"""Point-in-polygon tests on 2D projections of meshes (landmark contours, face regions)."""

from __future__ import annotations

import numpy as np

__all__ = ["LIP_DEPTH_M", "inside_polygon", "lip_vertices"]

LIP_DEPTH_M = 0.005
"""How far behind the outer lip contour's rearmost landmark the lips' surface reaches, metres."""


def inside_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(k,) bool: which (k, 2) points lie inside the closed (m, 2) polygon (even-odd rule).

    >>> square = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    >>> inside_polygon(np.array([[0.5, 0.5], [2.0, 0.5]]), square).tolist()
    [True, False]
    """
    x, y = points[:, 0:1], points[:, 1:2]
    x0, y0 = polygon[:, 0], polygon[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    crosses = (y0 > y) != (y1 > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
    return np.asarray(((crosses & (x < x_at)).sum(axis=1) % 2) == 1)


def lip_vertices(neutral: np.ndarray, candidates: np.ndarray, contour: np.ndarray) -> np.ndarray:
    """The ``candidates`` (vertex ids of ``neutral`` (n, 3), +z out of the face) on the lips: inside the outer lip
    contour ``contour`` (12, 3) (iBUG 48-59) seen from the front, and no more than :data:`LIP_DEPTH_M` behind
    its rearmost point (the mouth's inside lies further back)."""
    ids = np.asarray(candidates, np.int64)
    inside = inside_polygon(neutral[ids, :2], contour[:, :2])
    in_front = neutral[ids, 2] > contour[:, 2].min() - LIP_DEPTH_M
    return ids[inside & in_front]
