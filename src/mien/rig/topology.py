"""Which vertices of a mesh hang together: connected parts (a head, its eyeballs, its teeth) of a triangle mesh.

>>> import numpy as np
>>> vertex_components(5, np.array([[0, 1, 2], [3, 4, 3]])).tolist()
[0, 0, 0, 3, 3]
"""

from __future__ import annotations

import numpy as np

__all__ = ["vertex_components"]


def vertex_components(n_vertices: int, triangles: np.ndarray) -> np.ndarray:
    """(n_vertices,) int64 label of each vertex's connected part: the smallest vertex id in that part.

    Vertices joined by triangle edges share a label; a vertex in no triangle is a part of its own. Labels
    spread along edges with pointer jumping, numpy only (a few dozen passes on a 30,000-vertex head).
    """
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    a, b = edges[:, 0], edges[:, 1]
    labels = np.arange(n_vertices, dtype=np.int64)
    while True:
        low = np.minimum(labels[a], labels[b])
        updated = labels.copy()
        np.minimum.at(updated, a, low)
        np.minimum.at(updated, b, low)
        updated = updated[updated]  # pointer jumping: follow each label to its own label
        if np.array_equal(updated, labels):
            return labels
        labels = updated
