"""Facial parameters FP1..FP15: the Table 2 data, scale invariance, the neutral reference."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.laughter.facial_parameters import (
    FP_NAMES,
    NEUTRAL_FRAMES,
    face_size,
    facial_parameter_table,
    facial_parameters,
    neutral_reference,
)

SPEC_PAIRS = [(46, 47), (22, 27), (40, 41), (21, 27), (22, 42), (21, 39), (48, 54), (33, 54), (33, 48),
              (51, 57), (51, 33), (35, 54), (31, 48), (8, 33), (0, 16)]  # fmt: skip


def _face(n_frames: int = 8, seed: int = 3) -> np.ndarray:
    """(n, 68, 2) jittered face-like points: a fixed layout plus small per-frame noise (pixels)."""
    rng = np.random.default_rng(seed)
    base = rng.uniform(100.0, 300.0, size=(68, 2))
    base[36], base[45] = (150.0, 200.0), (250.0, 200.0)  # 100 px between the outer eye corners
    return base + rng.normal(0.0, 1.0, size=(n_frames, 68, 2))


def test_table_matches_the_paper() -> None:
    table = facial_parameter_table()
    assert FP_NAMES == tuple(f"FP{i}" for i in range(1, 16))
    assert [p.landmarks for p in table] == SPEC_PAIRS  # FP11's "51-53" read as 51-33
    assert table[0].paper_side == "right" and table[0].performer_side == "left"
    assert {name for p in table for name, _ in p.controllers} >= {"jaw", "smileFrown", "neck"}


def test_units_are_inter_ocular_distances() -> None:
    points = np.zeros((1, 68, 2))
    points[0, 45] = (4.0, 0.0)  # eye distance 4
    points[0, 57] = (0.0, 2.0)  # 51 at the origin: mouth height 2
    assert facial_parameters(points)[0, 9] == pytest.approx(0.5)
    assert face_size(points) == pytest.approx(4.0)


@pytest.mark.parametrize("scale", [2.0, 0.37])
def test_scaling_and_moving_the_face_changes_nothing(scale: float) -> None:
    """Doubling the resolution, or moving the face away (shrinking it), and shifting it, give the same FPs."""
    points = _face()
    moved = points * scale + np.array([40.0, -25.0])
    assert np.allclose(facial_parameters(moved), facial_parameters(points))


def test_three_dimensional_points() -> None:
    points = np.concatenate([_face(), np.zeros((8, 68, 1))], axis=2)
    assert np.allclose(facial_parameters(points), facial_parameters(points[..., :2]))
    assert facial_parameters(points * 3.0).shape == (8, 15)


def test_neutral_reference_choices(tmp_path: Path) -> None:
    fp = facial_parameters(_face())
    assert np.allclose(neutral_reference(fp), fp[:NEUTRAL_FRAMES].mean(axis=0))
    assert np.allclose(neutral_reference(fp, 6), fp[6])
    assert np.allclose(neutral_reference(fp, -1), fp[-1])
    given = np.linspace(0.1, 1.5, 15)
    assert np.allclose(neutral_reference(fp, given), given)
    np.save(tmp_path / "fp0.npy", given)
    assert np.allclose(neutral_reference(fp, tmp_path / "fp0.npy"), given)
    (tmp_path / "fp0.json").write_text(json.dumps(dict(zip(FP_NAMES, given.tolist(), strict=True))))
    assert np.allclose(neutral_reference(fp, str(tmp_path / "fp0.json")), given)
    # The face size follows a chosen neutral frame.
    points = _face()
    points[2] *= 2.0
    assert face_size(points, neutral=2) == pytest.approx(2.0 * face_size(points[3:4]), rel=0.05)


def test_bad_inputs() -> None:
    with pytest.raises(InvalidValueError, match="points68"):
        facial_parameters(np.zeros((5, 66, 2)))
    with pytest.raises(InvalidValueError, match="points68"):
        facial_parameters(np.zeros((0, 68, 2)))
    with pytest.raises(InvalidValueError, match="face size"):
        facial_parameters(np.zeros((3, 68, 2)))  # eyes on top of each other
    with pytest.raises(InvalidValueError, match="size"):
        facial_parameters(_face(), size=-1.0)
    fp = facial_parameters(_face())
    with pytest.raises(InvalidValueError, match="neutral"):
        neutral_reference(fp, 99)
    with pytest.raises(InvalidValueError, match="neutral"):
        neutral_reference(fp, np.ones(14))
    with pytest.raises(InvalidValueError, match="neutral"):
        neutral_reference(fp, "fp0.txt")
    with pytest.raises(InvalidValueError, match="parameters"):
        neutral_reference(np.ones((4, 3)))
