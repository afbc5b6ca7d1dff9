"""Detector implementations: MediaPipe Face Landmarker, the FER classifier, and the two combined.

* :class:`MediaPipeDetector`: landmarks (478, pixels), the 52 ARKit blendshape scores and head pose.
* :class:`EmotionDetector`: FER emotion probabilities of the crop around landmarks it is given (``hint``).
* :class:`FaceDetector`: MediaPipe first; the classifier then crops around MediaPipe's landmarks, or around
  the caller's hint when MediaPipe finds no face (a 90-degree profile, where it finds almost none).
"""

from __future__ import annotations

import os

import numpy as np

from mien.errors import InvalidValueError
from mien.tracking.landmarker import Landmarker
from mien.validate.detector import Detection
from mien.validate.emotion_classifier import EmotionClassifier

__all__ = ["EmotionDetector", "FaceDetector", "MediaPipeDetector"]


class MediaPipeDetector:
    """MediaPipe Face Landmarker in image mode: landmarks, blendshapes, pose; no emotions."""

    name = "mediapipe-face-landmarker"

    def __init__(self, model: str | os.PathLike[str] | None = None, min_confidence: float = 0.5) -> None:
        self._landmarker: Landmarker | None = Landmarker(model, mode="image", min_confidence=min_confidence)
        self.model_path = self._landmarker.model_path

    def detect(self, rgb: np.ndarray, hint: np.ndarray | None = None) -> Detection:
        """Landmarks and blendshapes on ``rgb``; ``hint`` is ignored (MediaPipe finds the face itself)."""
        if self._landmarker is None:
            raise InvalidValueError("detector", "closed", "an open detector")
        result = self._landmarker.detect(rgb)
        if result is None:
            return Detection(found=False)
        height, width = rgb.shape[:2]
        pixels = (result.landmarks[:, :2] * np.array([width, height], np.float32)).astype(np.float32)
        return Detection(True, pixels, result.blendshapes, None, result.head_pose_deg)

    def close(self) -> None:
        """Release the MediaPipe graph (idempotent)."""
        if self._landmarker is not None:
            self._landmarker.close()
            self._landmarker = None


class EmotionDetector:
    """The FER classifier on the crop around ``hint`` landmarks; no face found without a hint."""

    name = "fer-emotion-tflite"

    def __init__(self, model: str | os.PathLike[str] | None = None, framing: str = "landmarks") -> None:
        self.classifier = EmotionClassifier(model, framing)
        self.model_path = self.classifier.model_path
        self.framing = framing

    def detect(self, rgb: np.ndarray, hint: np.ndarray | None = None) -> Detection:
        """Emotion probabilities of the face around ``hint`` ((n, 2) pixels)."""
        if hint is None:
            return Detection(found=False)
        landmarks = np.asarray(hint, np.float32)[:, :2]
        return Detection(True, landmarks, None, self.classifier.classify(rgb, landmarks), None, True)

    def close(self) -> None:
        """Nothing to release."""


class FaceDetector:
    """MediaPipe landmarks and blendshapes plus FER emotions from the crop around them.

    ``landmarker`` / ``emotion_model``: model paths (default: the configured assets). ``emotions=False``
    skips the classifier (no emotion model needed). ``framing``: how the classifier's crop is framed
    (:data:`mien.validate.emotion_classifier.FRAMINGS`); a framing other than ``"landmarks"`` is named in
    :attr:`name`, so reports and JSON say how their figures were measured.
    """

    name = "mediapipe-face-landmarker+fer-emotion-tflite"

    def __init__(
        self,
        landmarker: str | os.PathLike[str] | None = None,
        emotion_model: str | os.PathLike[str] | None = None,
        emotions: bool = True,
        framing: str = "landmarks",
    ) -> None:
        self.framing = framing
        self.emotion = EmotionDetector(emotion_model, framing) if emotions else None
        self.mediapipe = MediaPipeDetector(landmarker)
        if framing != "landmarks":
            self.name = f"{FaceDetector.name} ({framing} framing)"

    def detect(self, rgb: np.ndarray, hint: np.ndarray | None = None) -> Detection:
        """MediaPipe on ``rgb``; emotions from its landmarks, or from ``hint`` when it finds no face."""
        found = self.mediapipe.detect(rgb)
        if self.emotion is None:
            return found
        if found.found and found.landmarks is not None:
            emotions = self.emotion.classifier.classify(rgb, found.landmarks)
            return Detection(True, found.landmarks, found.blendshapes, emotions, found.head_pose_deg)
        return self.emotion.detect(rgb, hint)

    def close(self) -> None:
        """Release both models (idempotent)."""
        self.mediapipe.close()
