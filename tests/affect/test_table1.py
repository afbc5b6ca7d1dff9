"""Table 1: every value of the csv against SPEC.md and the paper, spot values, and the rig-frame conversion."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from mien.affect.emotions import EMOTIONS
from mien.affect.table1 import (
    FEATURE_NAMES,
    TABLE1_EMOTION_COLUMNS,
    broekens_to_rig,
    table1_rig_vectors,
    table1_vectors,
)

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("MIEN_SHARED", REPO.parent / "shared"))


def _shared_file(relative: str) -> Path:
    path = SHARED / relative
    if not path.is_file():
        pytest.skip(f"{relative} not available: set MIEN_SHARED to the shared folder")
    return path


def _vec(cell: str) -> list[float]:
    return [float(v) for v in cell.replace(",", " ").split()]


def _check_all(table: dict[str, dict[str, list[float]]], header: list[str]) -> None:
    assert header == list(TABLE1_EMOTION_COLUMNS)
    assert tuple(table) == FEATURE_NAMES
    vectors = table1_vectors()
    for f, feature in enumerate(FEATURE_NAMES):
        for column, emotion in TABLE1_EMOTION_COLUMNS.items():
            expected = table[feature][column]
            got = vectors[EMOTIONS.index(emotion), f].tolist()
            assert got == expected, (feature, column)


def test_every_value_matches_the_spec_table() -> None:
    lines = _shared_file("SPEC.md").read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.replace(" ", "").startswith("|feature|surprise|"))
    header = [c.strip() for c in lines[start].strip().strip("|").split("|")][1:]
    table: dict[str, dict[str, list[float]]] = {}
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        table[cells[0]] = {column: _vec(cell) for column, cell in zip(header, cells[1:], strict=True)}
    assert len(table) == 18
    _check_all(table, header)


def test_every_value_matches_the_paper() -> None:
    lines = _shared_file("seeds/dynamic-facial-expression-made-easy-broekens.txt").read_text("utf-8").splitlines()
    start = next(
        i for i, line in enumerate(lines) if line.split() == ["surprise", "happy", "sad", "angry", "disgust", "fear"]
    )
    header = lines[start].split()
    table = {}
    for line in lines[start + 1 : start + 19]:
        cells = line.split("\t")
        table[cells[0]] = {column: _vec(cell) for column, cell in zip(header, cells[1:], strict=True)}
    _check_all(table, header)


def test_spot_values() -> None:
    v = table1_vectors()
    assert v.shape == (6, 18, 3) and v.dtype == np.float64
    assert len(FEATURE_NAMES) == 18
    joy, anger, surprise, disgust = (EMOTIONS.index(e) for e in ("joy", "anger", "surprise", "disgust"))
    assert v[joy, FEATURE_NAMES.index("LipCornerLeft")].tolist() == [-0.005, 0.009, -0.007]
    assert v[anger, FEATURE_NAMES.index("BrowInnerLeft")].tolist() == [0.0, -0.013, 0.012]
    assert v[surprise, FEATURE_NAMES.index("Jaw")].tolist() == [-0.005, 0.0, 0.01]
    assert v[disgust, FEATURE_NAMES.index("LipLowerRight")].tolist() == [-0.004, -0.002, 0.0025]


def test_rig_frame_conversion_and_directions() -> None:
    z, x, y = table1_vectors()[..., 0], table1_vectors()[..., 1], table1_vectors()[..., 2]
    rig = table1_rig_vectors()
    assert rig.shape == (6, 18, 3)
    np.testing.assert_array_equal(rig[..., 0], x)
    np.testing.assert_array_equal(rig[..., 1], -y)
    np.testing.assert_array_equal(rig[..., 2], z)
    np.testing.assert_array_equal(broekens_to_rig(np.array([1.0, 2.0, 3.0])), [2.0, -3.0, 1.0])
    joy, anger, surprise = (EMOTIONS.index(e) for e in ("joy", "anger", "surprise"))
    left, right = rig[joy, FEATURE_NAMES.index("LipCornerLeft")], rig[joy, FEATURE_NAMES.index("LipCornerRight")]
    assert left[0] > 0 > right[0]  # both corners outward (+x is the character's left)
    assert left[1] > 0 and right[1] > 0  # and up
    assert rig[surprise, FEATURE_NAMES.index("Jaw"), 1] < 0  # jaw drops
    assert rig[surprise, FEATURE_NAMES.index("BrowInnerLeft"), 1] > 0  # brows rise
    brow_l, brow_r = rig[anger, FEATURE_NAMES.index("BrowInnerLeft")], rig[anger, FEATURE_NAMES.index("BrowInnerRight")]
    assert brow_l[0] < 0 < brow_r[0] and brow_l[1] < 0  # inner brows toward each other, and down


def test_tables_are_read_only() -> None:
    with pytest.raises(ValueError):
        table1_vectors()[0, 0, 0] = 1.0
    with pytest.raises(ValueError):
        table1_rig_vectors()[0, 0, 0] = 1.0
