"""The iBUG-68 subset of MediaPipe's landmarks: table and geometry on a real photo."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.tracking.ibug68 import IBUG68_NAMES, ibug68, ibug68_indices
from mien.tracking.landmarker import Landmarker


def test_table_anchors() -> None:
    pairs = ibug68_indices()
    assert pairs.shape == (68, 2) and pairs.min() >= 0 and pairs.max() < 478
    anchors = {36: 33, 39: 133, 42: 362, 45: 263, 27: 168, 30: 4, 33: 2, 48: 61, 54: 291, 8: 152}
    for ibug, mesh in anchors.items():
        assert tuple(pairs[ibug]) == (mesh, mesh), ibug
    assert len(set(IBUG68_NAMES)) == 68 and IBUG68_NAMES[8] == "chin"


def test_shapes() -> None:
    points = np.arange(478 * 2, dtype=float).reshape(478, 2)
    out = ibug68(points)
    assert out.shape == (68, 2)
    assert np.allclose(out[27], points[168])  # the nose root, one landmark


def test_contour_points_are_spaced_evenly_along_mediapipes_contour() -> None:
    """The jaw's nine points from ear level to the chin split MediaPipe's contour into eight equal lengths,
    however unevenly MediaPipe's own points lie on it."""
    rng = np.random.default_rng(3)
    points = rng.normal(size=(478, 2))
    contour = [127, 234, 93, 132, 58, 172, 136, 150, 149, 176, 148, 152]
    points[contour] = np.c_[np.cumsum(rng.uniform(0.1, 2.0, len(contour))), np.zeros(len(contour))]
    jaw = ibug68(points)[0:9]
    assert np.allclose(jaw[:, 1], 0.0)
    assert np.allclose(np.diff(jaw[:, 0]), (points[152, 0] - points[127, 0]) / 8)
    assert np.allclose(jaw[[0, 8]], points[[127, 152]])
    assert ibug68(np.zeros((4, 2, 478, 3))).shape == (4, 2, 68, 3)
    with pytest.raises(InvalidValueError, match="landmarks"):
        ibug68(np.zeros((68, 2)))


@pytest.fixture(scope="module")
def photo_points(landmarker_path: Path, single_face_rgb: np.ndarray) -> np.ndarray:
    """(68, 2) iBUG points of the shared photo in pixels (y down)."""
    with Landmarker(landmarker_path, mode="image") as landmarker:
        result = landmarker.detect(single_face_rgb)
    assert result is not None
    height, width = single_face_rgb.shape[:2]
    return ibug68(result.landmarks[:, :2] * [width, height])


def test_vertical_order(photo_points: np.ndarray) -> None:
    y = photo_points[:, 1]
    eyes = y[36:48].mean()
    assert y[17:27].mean() < eyes < y[30] < y[33] < y[[48, 54]].mean() < y[57] < y[8]
    assert y[51] < y[62] < y[66] < y[57]  # outer upper lip, inner lips, outer lower lip
    assert y[8] == y[0:17].max()  # the chin is the lowest jaw point


def test_left_right_order(photo_points: np.ndarray) -> None:
    """Subject's right on the picture's left: 36 < 39 < 42 < 45, 48 < 54, 0 < 16, 31 < 35."""
    x = photo_points[:, 0]
    assert x[0] < x[36] < x[39] < x[42] < x[45] < x[16]
    assert x[17] < x[21] < x[22] < x[26]
    assert x[31] < x[33] < x[35] and x[48] < x[54]
    assert x[39] < x[30] < x[42]  # nose tip between the inner eye corners
    assert x[54] - x[48] > x[35] - x[31]  # mouth corners wider than the nostrils
    assert np.all(np.diff(x[1:16]) > 0)  # the jaw runs left to right (ear-level ends may curl in)


def test_eye_contours(photo_points: np.ndarray) -> None:
    y = photo_points[:, 1]
    assert y[37] < y[41] and y[38] < y[40]  # upper lid above lower lid, right eye
    assert y[43] < y[47] and y[44] < y[46]  # and left eye
