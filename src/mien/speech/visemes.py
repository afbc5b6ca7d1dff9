"""The 15 visemes: mien's speech vocabulary, their mouth shapes in AU and ARKit terms, and rigs' own viseme shapes.

The shapes and dominances are versioned data (``data/visemes.csv``, sources cited there); a head's own viseme
morph targets are matched through ``data/rig_visemes.csv``.

>>> VISEMES[:4]
('sil', 'PP', 'FF', 'TH')
>>> float(viseme_aus()[VISEMES.index("aa"), FACE_CHANNELS.index("AU26")])
3.5
"""

from __future__ import annotations

from collections.abc import Iterable
from functools import cache

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, au_channels
from mien.facs.intensity import check_intensity
from mien.fileio.tables import read_table, table_version

__all__ = [
    "VISEMES",
    "VISEMES_VERSION",
    "check_viseme",
    "rig_viseme_targets",
    "viseme_arkit",
    "viseme_aus",
    "viseme_dominance",
]

_TABLE = ("mien.speech", "data/visemes.csv")

VISEMES: tuple[str, ...] = tuple(row["viseme"] for row in read_table(*_TABLE))
"""The 15 visemes lip-sync tools share (Meta/Oculus LipSync, OpenFaceFX): sil PP FF TH DD kk CH SS nn RR aa E I O U."""

VISEMES_VERSION: str = table_version(*_TABLE)
"""The ``# version:`` of the shipped viseme table."""

_INDEX = {name: i for i, name in enumerate(VISEMES)}


def check_viseme(name: object) -> int:
    """Index of viseme ``name`` in :data:`VISEMES`, or :class:`UnknownNameError` (names are case-sensitive)."""
    if not isinstance(name, str) or name not in _INDEX:
        raise UnknownNameError("viseme", name, VISEMES)
    return _INDEX[name]


def _pairs(text: str, where: str) -> list[tuple[str, float]]:
    pairs = []
    for token in text.split():
        key, _, value = token.partition(":")
        try:
            pairs.append((key, float(value)))
        except ValueError:
            raise InvalidValueError(where, token, "name:value") from None
    return pairs


@cache
def _aus() -> np.ndarray:
    table = np.zeros((len(VISEMES), len(FACE_CHANNELS)))
    for i, row in enumerate(read_table(*_TABLE)):
        for key, value in _pairs(row["aus"], f"aus of {row['viseme']}"):
            intensity = check_intensity(value, f"{key} ({row['viseme']})")
            for channel in au_channels(int(key.removeprefix("AU"))):
                table[i, channel] = intensity
    table.setflags(write=False)
    return table


@cache
def _arkit() -> np.ndarray:
    table = np.zeros((len(VISEMES), len(ARKIT_NAMES)))
    for i, row in enumerate(read_table(*_TABLE)):
        for key, value in _pairs(row["arkit"], f"arkit of {row['viseme']}"):
            if key not in ARKIT_NAMES:
                raise UnknownNameError("ARKit blendshape", key, ARKIT_NAMES)
            table[i, ARKIT_NAMES.index(key)] = value
    table.setflags(write=False)
    return table


def viseme_aus() -> np.ndarray:
    """(15, 62) read-only: each viseme's mouth shape over :data:`~mien.facs.catalogue.FACE_CHANNELS`, AU
    intensity 0..5 (``sil`` is all zeros: the mouth at rest)."""
    return _aus()


def viseme_arkit() -> np.ndarray:
    """(15, 52) read-only: each viseme's mouth shape as ARKit blendshape weights 0..1 (:data:`ARKIT_NAMES` order)."""
    return _arkit()


@cache
def viseme_dominance() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(dominance (15,), rate_per_s (15,), min_s (15,))``: Cohen & Massaro's alpha and theta per viseme and
    the shortest time each shape is held, seconds (see :mod:`mien.speech.coarticulation`)."""
    rows = read_table(*_TABLE)
    columns = tuple(np.array([float(row[name]) for row in rows]) for name in ("dominance", "rate_per_s", "min_s"))
    for column in columns:
        column.setflags(write=False)
    return columns[0], columns[1], columns[2]


def rig_viseme_targets(target_names: Iterable[str]) -> dict[str, str]:
    """``{viseme: target name}`` for the head's own viseme morph targets among ``target_names``.

    Matched on the part of each name after its last ``"."`` against ``data/rig_visemes.csv`` (Oculus
    ``viseme_PP``..., Rocketbox ``h_expressions.MPB_h``...); the first convention with a match wins, and
    visemes it does not name are left out (an empty dict: the head has no viseme shapes).

    >>> rig_viseme_targets(["h_expressions.AE_AA_h", "h_expressions.MPB_h", "jawOpen"])
    {'PP': 'h_expressions.MPB_h', 'aa': 'h_expressions.AE_AA_h'}
    """
    by_short = {name.rsplit(".", 1)[-1]: name for name in target_names}
    conventions: dict[str, dict[str, str]] = {}
    for row in read_table("mien.speech", "data/rig_visemes.csv"):
        if row["target"] in by_short:
            conventions.setdefault(row["convention"], {})[row["viseme"]] = by_short[row["target"]]
    if not conventions:
        return {}
    found = next(iter(conventions.values()))
    return {viseme: found[viseme] for viseme in VISEMES if viseme in found}
