"""The inside of a head file's mouth, found from its lip landmarks: socket, teeth, gums and tongue.

mien's own heads name the parts inside the mouth, so an open mouth is drawn dark with light teeth
(:mod:`mien.render.cavity`, :data:`mien.render.appearance.REGION_ALBEDO`). A head file drawn without a look of
its own (no textures) names none of them, and its open mouth shows a skin-coloured plug: the socket and tongue
lit like a cheek, which a reader (person or classifier) takes for closed lips. Once the lips' outer contour is
known (iBUG 48-59), everything that lies behind the lips inside that contour, seen from the front, is inside the
mouth: such vertices of the skin's own part are the socket; the separate parts they reach are teeth (small parts:
one tooth, or a row) or gums and tongue (larger ones).

"""

from __future__ import annotations

import numpy as np

from mien.rig.polygon import inside_polygon
from mien.rig.topology import vertex_components

__all__ = ["BEHIND_LIPS_M", "CELL_M", "TOOTH_MAX_VERTICES", "mouth_regions"]

CELL_M = 0.002
"""Grid cell (metres, seen from the front) in which the frontmost vertex is taken as the lips' surface."""

BEHIND_LIPS_M = 0.003
"""A vertex this far or further behind its cell's frontmost vertex is inside the mouth."""

TOOTH_MAX_VERTICES = 600
"""A separate part inside the mouth with at most this many vertices is a tooth (or a row of teeth)."""

_LIP_CONTOUR = slice(48, 60)


def mouth_regions(
    neutral: np.ndarray, faces: np.ndarray, landmarks: np.ndarray, regions: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """New regions ``mouth_socket``, ``teeth``, ``gums_tongue`` of a head in mien's frame (+z out of the face),
    from its 68 landmark vertices; a region the head already has is kept as it is (not returned)."""
    if len(landmarks) < 68:
        return {}
    points = np.asarray(neutral, np.float64)
    lips = points[np.asarray(landmarks, np.int64)[_LIP_CONTOUR], :2]
    candidates = np.flatnonzero(inside_polygon(points[:, :2], lips))
    if len(candidates) == 0:
        return {}
    cells = np.floor(points[candidates, :2] / CELL_M).astype(np.int64)
    _, cell_of = np.unique(cells, axis=0, return_inverse=True)
    cell_of = cell_of.ravel()
    front = np.full(cell_of.max() + 1, -np.inf)
    np.maximum.at(front, cell_of, points[candidates, 2])
    interior = candidates[points[candidates, 2] < front[cell_of] - BEHIND_LIPS_M]
    if len(interior) == 0:
        return {}
    labels = vertex_components(len(points), np.asarray(faces, np.int64))
    counts = np.bincount(labels)
    skin = int(np.argmax(counts))
    claimed = np.zeros(len(points), bool)
    for name in ("eye_L", "eye_R", "eye_shell_L", "eye_shell_R"):
        if name in regions:
            claimed[np.asarray(regions[name], np.int64)] = True
    found: dict[str, list[np.ndarray]] = {"mouth_socket": [], "teeth": [], "gums_tongue": []}
    found["mouth_socket"].append(interior[(labels[interior] == skin) & ~claimed[interior]])
    for part in np.unique(labels[interior]):
        if part == skin:
            continue
        ids = np.flatnonzero(labels == part)
        if claimed[ids].any():
            continue
        found["teeth" if len(ids) <= TOOTH_MAX_VERTICES else "gums_tongue"].append(ids)
    out = {}
    for name, pieces in found.items():
        ids = np.unique(np.concatenate(pieces)) if pieces else np.zeros(0, np.int64)
        if len(ids) and name not in regions:
            out[name] = ids.astype(np.int32)
    return out
