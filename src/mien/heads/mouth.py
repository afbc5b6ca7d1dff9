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

from mien.rig.polygon import inside_polygon, lip_vertices
from mien.rig.topology import vertex_components

__all__ = ["BEHIND_LIPS_M", "CELL_M", "EYE_SOCKET_DEPTH_M", "MOUTH_DEPTH_M", "TOOTH_MAX_VERTICES", "mouth_regions"]

CELL_M = 0.002
"""Grid cell (metres, seen from the front) in which the frontmost vertex is taken as the lips' surface."""

BEHIND_LIPS_M = 0.003
"""A vertex this far or further behind its cell's frontmost vertex is inside the mouth."""

MOUTH_DEPTH_M = 0.06
"""How far behind the lips the mouth reaches (to the throat), metres."""

EYE_SOCKET_DEPTH_M = 0.03
"""How far behind the lids the eye socket reaches (an eyeball is 24 mm across), metres."""

TOOTH_MAX_VERTICES = 600
"""A separate part inside the mouth with at most this many vertices is a tooth (or a row of teeth)."""

_LIP_CONTOUR = slice(48, 60)
_LEFT_LIDS = slice(42, 48)
"""iBUG points of the character's left eye's lid contour (the subject's left: 42-47)."""
_RIGHT_LIDS = slice(36, 42)


def _behind(points: np.ndarray, contour: np.ndarray, depth_m: float) -> np.ndarray:
    """Ids of the vertices (``points`` (n, 3), +z out of the face) inside the closed ``contour`` (k, 3) seen from
    the front that lie at least :data:`BEHIND_LIPS_M` behind the frontmost vertex of their :data:`CELL_M` cell
    and at most ``depth_m`` behind the contour's rearmost point (not the back of the head)."""
    candidates = np.flatnonzero(inside_polygon(points[:, :2], contour[:, :2]))
    candidates = candidates[points[candidates, 2] >= contour[:, 2].min() - depth_m]
    if len(candidates) == 0:
        return candidates
    cells = np.floor(points[candidates, :2] / CELL_M).astype(np.int64)
    _, cell_of = np.unique(cells, axis=0, return_inverse=True)
    cell_of = cell_of.ravel()
    front = np.full(cell_of.max() + 1, -np.inf)
    np.maximum.at(front, cell_of, points[candidates, 2])
    return candidates[points[candidates, 2] < front[cell_of] - BEHIND_LIPS_M]


def mouth_regions(
    neutral: np.ndarray, faces: np.ndarray, landmarks: np.ndarray, regions: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """New regions ``mouth_socket``, ``teeth``, ``gums_tongue``, ``lips``, ``eye_socket_L`` and ``eye_socket_R``
    of a head in mien's frame (+z out of the face), from its 68 landmark vertices; a region the head already has
    is kept as it is (not returned)."""
    if len(landmarks) < 68:
        return {}
    points = np.asarray(neutral, np.float64)
    marks = np.asarray(landmarks, np.int64)
    labels = vertex_components(len(points), np.asarray(faces, np.int64))
    skin = int(np.bincount(labels[marks]).argmax())
    claimed = np.zeros(len(points), bool)
    for name in ("eye_L", "eye_R", "eye_shell_L", "eye_shell_R"):
        if name in regions:
            claimed[np.asarray(regions[name], np.int64)] = True
    found: dict[str, list[np.ndarray]] = {"mouth_socket": [], "teeth": [], "gums_tongue": []}
    interior = _behind(points, points[marks[_LIP_CONTOUR]], MOUTH_DEPTH_M)
    if len(interior):
        found["mouth_socket"].append(interior[(labels[interior] == skin) & ~claimed[interior]])
    for part in np.unique(labels[interior]):
        if part == skin:
            continue
        ids = np.flatnonzero(labels == part)
        if claimed[ids].any():
            continue
        found["teeth" if len(ids) <= TOOTH_MAX_VERTICES else "gums_tongue"].append(ids)
    on_skin = np.flatnonzero(labels == skin)
    lips = lip_vertices(points, on_skin, points[marks[_LIP_CONTOUR]])
    found["lips"] = [np.setdiff1d(lips, interior)]
    for name, lids in (("eye_socket_L", _LEFT_LIDS), ("eye_socket_R", _RIGHT_LIDS)):
        # the skin seen through the lid opening behind the lids' front: the socket and the lids' inner surfaces
        behind = _behind(points, points[marks[lids]], EYE_SOCKET_DEPTH_M)
        found[name] = [behind[(labels[behind] == skin) & ~claimed[behind]]]
    out = {}
    for name, pieces in found.items():
        ids = np.unique(np.concatenate(pieces)) if pieces else np.zeros(0, np.int64)
        if len(ids) and name not in regions:
            out[name] = ids.astype(np.int32)
    return out
