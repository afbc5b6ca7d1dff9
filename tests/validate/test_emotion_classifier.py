"""The classifier's crop: where each framing puts a face, and that both read a real face's expressions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import UnknownNameError
from mien.validate.emotion_classifier import FRAMINGS, EmotionClassifier, face_box


def _builtin_landmarks(view: str = "frontal-1m", size: int = 512) -> np.ndarray:
    """The built-in head's 68 landmark vertices projected as in the study's frontal view (pixels)."""
    from mien.heads import load_head
    from mien.render.camera import VIEWS

    rig = load_head("builtin", "default")
    return VIEWS[view].camera.project(rig.neutral[rig.landmarks], size, size)


def _fractions(points: np.ndarray, framing: str) -> tuple[float, float, float]:
    """(eyes, chin, inner-feature centre) positions inside the crop, as fractions of its side."""
    x0, y0, side = face_box(points, framing)
    eyes = float(points[36:48, 1].mean() - y0) / side
    chin = float(points[8, 1] - y0) / side
    inner = points[17:, 0]
    centre = float((inner.min() + inner.max()) / 2 - x0) / side
    return eyes, chin, centre


def test_each_framing_puts_the_face_where_it_says() -> None:
    points = _builtin_landmarks()
    eyes, chin, centre = _fractions(points, "landmarks")
    assert 0.18 < eyes < 0.30 and 0.9 < chin < 1.0  # brows near the top edge, chin near the bottom
    # fer's framing starts in the forehead: the eyes come 0.12+ of the side lower, the chin stays inside
    eyes_fer, chin_fer, centre_fer = _fractions(points, "fer")
    assert eyes_fer > eyes + 0.12 and 0.9 < chin_fer < 1.08
    assert centre == pytest.approx(0.5, abs=0.01) and centre_fer == pytest.approx(0.5, abs=0.01)
    assert face_box(points, "fer")[2] == pytest.approx(
        face_box(points)[2] * FRAMINGS["fer"][0] / FRAMINGS["landmarks"][0], abs=1
    )


def test_an_unknown_framing_is_refused_by_name(tmp_path: Path) -> None:
    with pytest.raises(UnknownNameError, match=r"'haar'.*landmarks, fer"):
        face_box(_builtin_landmarks(), "haar")
    from mien.validate.emotion_classifier import EmotionClassifier

    with pytest.raises(UnknownNameError, match="'haar'"):  # before the model is looked for
        EmotionClassifier(tmp_path / "missing.tflite", framing="haar")


@pytest.mark.parametrize("framing", sorted(FRAMINGS))
def test_both_framings_read_a_real_faces_neutral_and_smile(
    framing: str, shared_data: Path, landmarker_path: Path, emotion_model_path: Path
) -> None:
    pytest.importorskip("mediapipe")
    pytest.importorskip("ai_edge_litert")
    from mien.tracking.ibug68 import ibug68
    from mien.tracking.video import iter_frames
    from mien.validate.detector import EMOTION_LABELS
    from mien.validate.face_detector import FaceDetector

    frames = [frame for _, frame in iter_frames(shared_data / "video" / "single_face.mp4")]
    detector = FaceDetector(landmarker_path, emotion_model_path, framing=framing)
    try:
        found = [detector.detect(np.ascontiguousarray(frames[i][..., :3])) for i in (0, 8, 40, 60)]
    finally:
        detector.close()
    # the clip starts neutral and smiles from frame ~20 on (measured: p 0.94-0.98 under both framings)
    assert [EMOTION_LABELS[int(np.argmax(d.emotions))] for d in found] == ["neutral", "neutral", "happy", "happy"]
    # the calibration: on this face fer's own crop has the eyes at 0.42-0.44 of its side, the chin at 1.01-1.06
    eyes, chin, _ = _fractions(ibug68(np.asarray(found[0].landmarks)[:, :2]), framing)
    if framing == "fer":
        assert 0.40 < eyes < 0.46 and 0.95 < chin < 1.08
    else:
        assert eyes < 0.30
    assert (framing in detector.name) == (framing != "landmarks")


def test_the_judge_batches_crops_as_one_at_a_time(emotion_model_path: Path) -> None:
    """The averaged judge sends its twelve crops in one call: the same probabilities as one crop at a time, whatever
    the batch size before."""
    classifier = EmotionClassifier(emotion_model_path)
    crops = np.random.default_rng(0).random((12, 64, 64)).astype(np.float32)
    batch = classifier.classify_crops(crops)
    assert batch.shape == (12, 7)
    np.testing.assert_allclose(batch.sum(axis=1), 1.0, atol=1e-5)
    for crop, row in zip(crops[:3], batch[:3], strict=True):
        np.testing.assert_allclose(classifier.classify_crop(crop), row, atol=1e-6)
    np.testing.assert_allclose(classifier.classify_crops(crops[5:7]), batch[5:7], atol=1e-6)
    assert classifier.classify_crops(np.zeros((0, 64, 64))).shape == (0, 7)
