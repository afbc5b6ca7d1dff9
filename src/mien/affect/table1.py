"""Broekens' Table 1: displacement of 18 MPEG-4 feature points per basic emotion at intensity 1.

The numbers live in ``data/broekens_table1.csv``, transcribed exactly as printed in Broekens, Qu &
Brinkman, *Dynamic Facial Expression of Emotion Made Easy*, Table 1. The paper's vectors are ``[z, x, y]``
in metres: +z toward the viewer, +x toward the viewer's right, +y down. Features named Left sit on the
character's left. In mien's rig frame (+x to the character's left, +y up, +z forward) a Broekens
``(z, x, y)`` is ``(dx, dy, dz) = (x, -y, z)``.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from mien.affect.emotions import EMOTIONS
from mien.fileio.tables import read_table

__all__ = [
    "FEATURE_NAMES",
    "TABLE1_EMOTION_COLUMNS",
    "broekens_to_rig",
    "table1_rig_vectors",
    "table1_vectors",
]

TABLE1_EMOTION_COLUMNS: dict[str, str] = {
    "surprise": "surprise",
    "happy": "joy",
    "sad": "sadness",
    "angry": "anger",
    "disgust": "disgust",
    "fear": "fear",
}
"""Column of the csv (the paper's header) -> emotion of :data:`~mien.affect.emotions.EMOTIONS`."""


def _read() -> tuple[tuple[str, ...], np.ndarray]:
    rows = read_table("mien.affect", "data/broekens_table1.csv")
    names = tuple(row["feature"] for row in rows)
    vectors = np.zeros((len(EMOTIONS), len(rows), 3))
    for f, row in enumerate(rows):
        for column, emotion in TABLE1_EMOTION_COLUMNS.items():
            vectors[EMOTIONS.index(emotion), f] = [float(v) for v in row[column].split()]
    vectors.setflags(write=False)
    return names, vectors


FEATURE_NAMES: tuple[str, ...] = _read()[0]
"""The 18 feature points in the csv's (the paper's) row order: ``Jaw``, ``Nostrils``, ``LipLowerLeft``..."""


@cache
def table1_vectors() -> np.ndarray:
    """(6, 18, 3) float64 read-only: Table 1 as printed, ``[z, x, y]`` metres, emotions in EMOTIONS order.

    >>> v = table1_vectors()
    >>> v[EMOTIONS.index("surprise"), FEATURE_NAMES.index("Jaw")].tolist()
    [-0.005, 0.0, 0.01]
    """
    return _read()[1]


def broekens_to_rig(vectors: np.ndarray) -> np.ndarray:
    """(..., 3) Broekens ``[z, x, y]`` -> (..., 3) rig-frame ``(dx, dy, dz) = (x, -y, z)`` (new array)."""
    vectors = np.asarray(vectors, dtype=np.float64)
    out = np.empty_like(vectors)
    out[..., 0] = vectors[..., 1]
    out[..., 1] = -vectors[..., 2]
    out[..., 2] = vectors[..., 0]
    return out


@cache
def table1_rig_vectors() -> np.ndarray:
    """(6, 18, 3) float64 read-only: Table 1 in the rig frame ``(dx, dy, dz)`` metres (+x character's left,
    +y up, +z forward).

    Happy pulls both lip corners up and outward; surprise drops the jaw:

    >>> v = table1_rig_vectors()
    >>> joy, surprise = EMOTIONS.index("joy"), EMOTIONS.index("surprise")
    >>> v[joy, FEATURE_NAMES.index("LipCornerLeft")].tolist()
    [0.009, 0.007, -0.005]
    >>> v[joy, FEATURE_NAMES.index("LipCornerRight")].tolist()
    [-0.009, 0.007, -0.005]
    >>> v[surprise, FEATURE_NAMES.index("Jaw")].tolist()
    [0.0, -0.01, -0.005]
    """
    out = broekens_to_rig(table1_vectors())
    out.setflags(write=False)
    return out
