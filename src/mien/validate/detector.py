"""The detector interface: an RGB frame in; landmarks, blendshape scores and emotion probabilities out.

A detector gives what it can and ``None`` for the rest: MediaPipe Face Landmarker gives landmarks and the 52
ARKit blendshape scores; the FER classifier gives emotion probabilities; :class:`FaceDetector` combines the
two (the classifier's crop comes from the landmarks). A frame on which no face is found gives a
:class:`Detection` whose ``found`` is False.

For rendered frames the caller knows where the face is (the rig's landmarks projected through the camera),
and passes them as ``hint``: a detector that finds no face by itself (MediaPipe at a 90-degree profile) may
still classify the crop the hint gives. The detection then says ``landmarks_from_hint``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["EMOTION_LABELS", "Detection", "Detector"]

EMOTION_LABELS: tuple[str, ...] = ("angry", "disgust", "fear", "happy", "sad", "surprise", "neutral")
"""The classifier's seven classes (FER2013 order), the columns of :attr:`Detection.emotions`."""


@dataclass(frozen=True, eq=False)
class Detection:
    """What a detector found on one frame; ``None`` where it cannot say."""

    found: bool
    """True when a face was found (by the detector itself, or from the caller's hint)."""
    landmarks: np.ndarray | None = None
    """(n, 2) float32 pixel coordinates (x right, y down) of the face landmarks, or None."""
    blendshapes: np.ndarray | None = None
    """(52,) float32 ARKit blendshape scores 0..1 in :data:`~mien.facs.arkit.ARKIT_NAMES` order, or None."""
    emotions: np.ndarray | None = None
    """(7,) float32 probabilities over :data:`EMOTION_LABELS` (sum 1), or None."""
    head_pose_deg: np.ndarray | None = None
    """(3,) yaw, pitch, roll in degrees (mien convention), or None."""
    landmarks_from_hint: bool = False
    """True when the landmarks are the caller's hint, not the detector's own finding."""

    @property
    def top_emotion(self) -> str | None:
        """The most probable of :data:`EMOTION_LABELS`, or None without emotion probabilities."""
        if self.emotions is None:
            return None
        return EMOTION_LABELS[int(np.argmax(self.emotions))]


@runtime_checkable
class Detector(Protocol):
    """Anything that turns an RGB frame into a :class:`Detection`."""

    name: str
    """Short name with version (``"mediapipe-face-landmarker"``...), written into reports."""

    def detect(self, rgb: np.ndarray, hint: np.ndarray | None = None) -> Detection:
        """Detect on ``rgb`` ((h, w, 3) uint8); ``hint`` (n, 2) pixel landmarks known from elsewhere, or None."""
        ...

    def close(self) -> None:
        """Release the detector's resources (idempotent)."""
        ...
