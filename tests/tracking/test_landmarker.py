"""MediaPipe Face Landmarker on real images: outputs, blendshape sides, head-pose signs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_INDEX
from mien.tracking.landmarker import FrameResult, Landmarker, head_pose_deg


@pytest.fixture(scope="module")
def image_landmarker(landmarker_path: Path):  # type: ignore[no-untyped-def]
    with Landmarker(landmarker_path, mode="image") as landmarker:
        yield landmarker


@pytest.fixture(scope="module")
def photo_result(image_landmarker: Landmarker, single_face_rgb: np.ndarray) -> FrameResult:
    result = image_landmarker.detect(single_face_rgb)
    assert result is not None
    return result


def test_outputs_on_a_photo(photo_result: FrameResult) -> None:
    assert photo_result.landmarks.shape == (478, 3)
    assert np.all((photo_result.landmarks[:, :2] > 0) & (photo_result.landmarks[:, :2] < 1))
    assert photo_result.blendshapes.shape == (52,)
    assert np.all((photo_result.blendshapes >= 0) & (photo_result.blendshapes <= 1))
    assert photo_result.blendshapes[ARKIT_INDEX["tongueOut"]] == 0.0  # MediaPipe does not estimate it
    # The photo is of a broad smile, nearly frontal.
    assert photo_result.blendshapes[ARKIT_INDEX["mouthSmileLeft"]] > 0.6
    assert np.all(np.abs(photo_result.head_pose_deg) < 15)


def test_no_face_on_a_blank_image(image_landmarker: Landmarker) -> None:
    assert image_landmarker.detect(np.full((240, 320, 3), 127, np.uint8)) is None


def _cover_eye(rgb: np.ndarray, landmarks: np.ndarray, eye: list[int]) -> np.ndarray:
    """Paint over one eye with the skin just below it (a crude closed eye)."""
    height, width = rgb.shape[:2]
    xs, ys = landmarks[eye, 0] * width, landmarks[eye, 1] * height
    x0, x1 = int(xs.min()) - 6, int(xs.max()) + 6
    y0, y1 = int(ys.min()) - 8, int(ys.max()) + 6
    out = rgb.copy()
    out[y0:y1, x0:x1] = rgb[y1 + 14 : y1 + 14 + (y1 - y0), x0:x1]
    return out


def test_blendshape_sides_are_the_subjects(
    image_landmarker: Landmarker, single_face_rgb: np.ndarray, photo_result: FrameResult
) -> None:
    """Covering the eye on the picture's right (the subject's left, mesh 362..263) raises eyeBlinkLeft."""
    left, right = ARKIT_INDEX["eyeBlinkLeft"], ARKIT_INDEX["eyeBlinkRight"]
    base = photo_result.blendshapes
    subject_left = image_landmarker.detect(_cover_eye(single_face_rgb, photo_result.landmarks, [362, 263, 386, 374]))
    subject_right = image_landmarker.detect(_cover_eye(single_face_rgb, photo_result.landmarks, [33, 133, 159, 145]))
    assert subject_left is not None and subject_right is not None
    assert subject_left.blendshapes[left] - base[left] > subject_left.blendshapes[right] - base[right] + 0.1
    assert subject_right.blendshapes[right] - base[right] > subject_right.blendshapes[left] - base[left] + 0.1


def test_yaw_sign_follows_the_nose(
    image_landmarker: Landmarker, single_face_rgb: np.ndarray, photo_result: FrameResult
) -> None:
    """yaw > 0 when the nose points to the picture's right (the subject's left); mirroring flips yaw and roll."""
    flipped = image_landmarker.detect(np.ascontiguousarray(single_face_rgb[:, ::-1]))
    assert flipped is not None
    for result in (photo_result, flipped):
        points = result.landmarks
        nose_offset = points[1, 0] - 0.5 * (points[33, 0] + points[263, 0])
        assert np.sign(result.head_pose_deg[0]) == np.sign(nose_offset)
    assert flipped.head_pose_deg[0] == pytest.approx(-photo_result.head_pose_deg[0], abs=3.0)
    assert flipped.head_pose_deg[2] == pytest.approx(-photo_result.head_pose_deg[2], abs=3.0)
    assert flipped.head_pose_deg[1] == pytest.approx(photo_result.head_pose_deg[1], abs=3.0)


def test_roll_sign_on_a_rotated_photo(
    image_landmarker: Landmarker, single_face_rgb: np.ndarray, photo_result: FrameResult
) -> None:
    """Turning the picture 20 degrees counter-clockwise tilts the head toward the subject's right shoulder."""
    from PIL import Image

    rotated = np.asarray(Image.fromarray(single_face_rgb).rotate(20, resample=Image.Resampling.BILINEAR))
    result = image_landmarker.detect(np.ascontiguousarray(rotated))
    assert result is not None
    assert result.head_pose_deg[2] - photo_result.head_pose_deg[2] == pytest.approx(-20.0, abs=4.0)


def _rotation(axis: int, degrees: float) -> np.ndarray:
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    rot = np.eye(4)
    rot[i, i], rot[i, j], rot[j, i], rot[j, j] = c, -s, s, c
    return rot


def test_head_pose_convention_on_synthetic_rotations() -> None:
    # Yaw: a right-handed turn about +y moves the nose (+z) toward +x, the subject's left.
    assert head_pose_deg(_rotation(1, 25.0)) == pytest.approx([25.0, 0.0, 0.0])
    # Pitch up: the nose moves toward +y, a negative turn about +x.
    assert head_pose_deg(_rotation(0, -10.0)) == pytest.approx([0.0, 10.0, 0.0])
    # Roll toward the left shoulder: the top of the head (+y) moves toward +x, a negative turn about +z.
    assert head_pose_deg(_rotation(2, -15.0)) == pytest.approx([0.0, 0.0, 15.0])
    combined = _rotation(1, 20.0) @ _rotation(0, -5.0) @ _rotation(2, 8.0)
    assert head_pose_deg(combined) == pytest.approx([20.0, 5.0, -8.0])
    assert head_pose_deg(np.stack([np.eye(4)] * 3)).shape == (3, 3)


def test_bad_arguments(landmarker_path: Path, tmp_path: Path) -> None:
    with pytest.raises(InvalidValueError, match="mode"):
        Landmarker(landmarker_path, mode="stream")  # type: ignore[arg-type]
    with pytest.raises(InvalidValueError, match="min_confidence"):
        Landmarker(landmarker_path, min_confidence=1.5)
    fake = tmp_path / "fake.task"
    fake.write_bytes(b"not a model")
    with pytest.raises(InvalidValueError, match=r"fake\.task"):
        Landmarker(fake)
