"""How badly a deformation treats a mesh: edge strain and flipped triangles.

A smooth facial deformation stretches and squashes the skin's edges a little and never turns a triangle
over; a tear, flap or seam shows as a few edges changing length by a large fraction, or as triangles whose
normal reverses. These measures compare a deformed mesh with the rig's neutral, over the ``"skin"`` region
(all vertices when a rig has none), so the eyes, teeth and mouth socket do not count. The natural yardstick
is the head's own artist-made shapes: :func:`max_target_strain` gives the worst of the ARKit targets.

>>> from mien.rig.builtin_head import builtin_head
>>> rig = builtin_head()
>>> max_edge_strain(rig, rig.neutral)
0.0
>>> int(flipped_triangles(rig, rig.neutral).size)
0
"""

from __future__ import annotations

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_NAMES
from mien.rig.model import Rig

__all__ = [
    "edge_strain",
    "flipped_triangles",
    "fragile_faces",
    "max_edge_strain",
    "max_target_strain",
    "region_edges",
    "region_faces",
]


def _region_mask(rig: Rig, region: str | None) -> np.ndarray:
    mask = np.zeros(rig.n_vertices, bool)
    if region is None or region not in rig.regions:
        mask[:] = True
    else:
        mask[rig.regions[region]] = True
    return mask


def region_faces(rig: Rig, region: str | None = "skin") -> np.ndarray:
    """(m,) int64 ids of the triangles with all three vertices in ``region`` (every triangle if it is absent)."""
    mask = _region_mask(rig, region)
    return np.flatnonzero(mask[rig.faces].all(axis=1))


def region_edges(rig: Rig, region: str | None = "skin") -> np.ndarray:
    """(e, 2) int64 unique undirected edges (low id first) of the triangles of :func:`region_faces`."""
    faces = rig.faces[region_faces(rig, region)].astype(np.int64)
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = np.sort(edges, axis=1)
    edges = edges[edges[:, 0] != edges[:, 1]]
    # One int64 key per edge (low * n + high sorts as the pairs do): np.unique(axis=0) sorts pairs ~4x slower.
    keys = np.unique(edges[:, 0] * rig.n_vertices + edges[:, 1])
    return np.stack([keys // rig.n_vertices, keys % rig.n_vertices], axis=1)


def _check_vertices(rig: Rig, vertices: np.ndarray) -> np.ndarray:
    vertices = np.asarray(vertices, dtype=np.float64)
    if vertices.shape != (rig.n_vertices, 3):
        raise InvalidValueError("vertices", vertices.shape, f"({rig.n_vertices}, 3) deformed positions, metres")
    return vertices


def edge_strain(rig: Rig, vertices: np.ndarray, region: str | None = "skin") -> np.ndarray:
    """(e,) float64 relative length change ``|len' - len| / len`` of each edge of :func:`region_edges`.

    ``vertices`` (n_vertices, 3) are deformed positions in metres; edges of zero rest length are skipped.
    """
    deformed = _check_vertices(rig, vertices)
    edges = region_edges(rig, region)
    neutral = np.asarray(rig.neutral, dtype=np.float64)
    rest = np.linalg.norm(neutral[edges[:, 0]] - neutral[edges[:, 1]], axis=1)
    now = np.linalg.norm(deformed[edges[:, 0]] - deformed[edges[:, 1]], axis=1)
    keep = rest > 1e-9
    return np.abs(now[keep] - rest[keep]) / rest[keep]


def max_edge_strain(rig: Rig, vertices: np.ndarray, region: str | None = "skin") -> float:
    """The largest relative edge-length change of ``region`` between the neutral and ``vertices`` (0 = rigid).

    ``vertices`` (n_vertices, 3) metres. 0.5 means some edge grew or shrank by half its rest length.
    """
    strain = edge_strain(rig, vertices, region)
    return float(strain.max()) if strain.size else 0.0


def _normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    p = vertices[faces]
    return np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])


def flipped_triangles(
    rig: Rig, vertices: np.ndarray, region: str | None = "skin", faces: np.ndarray | None = None
) -> np.ndarray:
    """(k,) int64 ids of the triangles whose normal turned by more than 90 degrees from the neutral's.

    ``vertices`` (n_vertices, 3) metres. Only ``faces`` (triangle ids; default :func:`region_faces` of
    ``region``) are checked, and triangles of zero rest area are skipped.
    """
    deformed = _check_vertices(rig, vertices)
    ids = region_faces(rig, region) if faces is None else np.asarray(faces, dtype=np.int64)
    tri = rig.faces[ids]
    before = _normals(np.asarray(rig.neutral, dtype=np.float64), tri)
    after = _normals(deformed, tri)
    area = np.linalg.norm(before, axis=1)
    flipped = (np.einsum("ij,ij->i", before, after) <= 0.0) & (area > 1e-12)
    return ids[flipped]


def max_target_strain(rig: Rig, names: tuple[str, ...] | None = None, region: str | None = "skin") -> tuple[str, float]:
    """``(name, strain)`` of the target (default: the 52 ARKit ones the rig has) with the largest
    :func:`max_edge_strain` at weight 1: the head's own most extreme artist-made shape."""

    names = tuple(n for n in (names or ARKIT_NAMES) if n in rig.target_names)
    if not names:
        raise InvalidValueError(f"{rig.name} targets", rig.target_names[:5], "at least one of the named targets")
    neutral = np.asarray(rig.neutral, dtype=np.float64)
    scores = [(n, max_edge_strain(rig, neutral + rig.target(n).dense(rig.n_vertices), region)) for n in names]
    return max(scores, key=lambda item: item[1])


FRAGILE_TARGETS = (
    "jawOpen",
    "mouthClose",
    "eyeBlinkLeft",
    "eyeBlinkRight",
    "mouthSmileLeft",
    "mouthSmileRight",
    "cheekSquintLeft",
    "cheekSquintRight",
)
"""ARKit shapes whose own flips mark a head's fragile slivers (mouth corners, lid margins): the opening and
closing shapes, and the smile and cheek shapes the feature-point rig's correctives carry
(:mod:`mien.rig.fp_correctives`; ICT's own smile folds the sliver at each inner lip corner)."""


def fragile_faces(rig: Rig, names: tuple[str, ...] = FRAGILE_TARGETS, region: str | None = "skin") -> np.ndarray:
    """(k,) int64 ids of the triangles of ``region`` that the head's own ``names`` targets (at weight 1) turn over.

    These are slivers where the mouth opens or the lids close: the artist-made shapes fold them too, so a
    deformation is judged on the other triangles (:func:`flipped_triangles` with ``faces=``).
    """
    neutral = np.asarray(rig.neutral, dtype=np.float64)
    ids = [
        flipped_triangles(rig, neutral + rig.target(n).dense(rig.n_vertices), region)
        for n in names
        if n in rig.target_names
    ]
    return np.unique(np.concatenate(ids)) if ids else np.zeros(0, np.int64)
