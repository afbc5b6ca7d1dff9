"""EMFACS prototypes of the six basic emotions as AU intensities (data in ``data/emfacs_prototypes.csv``)."""

from __future__ import annotations

import numpy as np

from mien.errors import UnknownNameError
from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.facs.intensity import check_intensity, parse_au
from mien.fileio.tables import read_table, table_version

__all__ = ["EMFACS_PROTOTYPES", "PROTOTYPES_VERSION", "prototype_vector"]


_TABLE = ("mien.facs", "data/emfacs_prototypes.csv")


def _load() -> dict[str, dict[str, float]]:
    rows = read_table(*_TABLE)
    table: dict[str, dict[str, float]] = {}
    for row in rows:
        entry: dict[str, float] = {}
        for token in row["aus"].split():
            name, _, value = token.partition(":")
            spec = parse_au(name if value else token)
            entry[f"AU{spec.code}"] = (
                check_intensity(float(value), f"{token} ({row['emotion']})") if value else float(spec.intensity or 0.0)
            )
        table[row["emotion"]] = entry
    return table


EMFACS_PROTOTYPES: dict[str, dict[str, float]] = _load()
"""Emotion -> {``"AU6"``: 3.5, ...}: the prototype AUs and their intensities (0..5) at emotion intensity 1."""

PROTOTYPES_VERSION: str = table_version(*_TABLE)
"""The ``# version:`` of the shipped prototype table (``"2"``)."""


def prototype_vector(emotion: str) -> np.ndarray:
    """(62,) face-frame vector (over :data:`~mien.facs.catalogue.FACE_CHANNELS`) of an emotion's prototype.

    >>> v = prototype_vector("surprise")
    >>> float(v[FACE_CHANNELS.index("AU26")]), float(v[FACE_CHANNELS.index("AU1L")])
    (3.5, 3.5)
    """
    try:
        aus = EMFACS_PROTOTYPES[emotion]
    except KeyError:
        raise UnknownNameError("emotion", emotion, tuple(EMFACS_PROTOTYPES)) from None
    vector = np.zeros(len(FACE_CHANNELS))
    for label, value in aus.items():
        vector[list(au_channels(int(label[2:])))] = value
    return vector
