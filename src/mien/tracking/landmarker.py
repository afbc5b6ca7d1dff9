"""MediaPipe Face Landmarker (Tasks API): an RGB frame -> 478 landmarks, 52 ARKit blendshapes, head pose.

The model is the ``face_landmarker.task`` bundle found by :func:`mien.paths.require_asset`. Findings checked
on real images (tests/tracking/test_landmarker.py):

- MediaPipe gives 51 of the 52 ARKit names (no ``tongueOut``, left at 0) plus ``_neutral`` (dropped).
- MediaPipe's blendshape ``Left``/``Right`` are the subject's own sides, like ARKit's and mien's: covering the
  eye on the picture's right (the subject's left) raises ``eyeBlinkLeft``. Scores are therefore reordered to
  :data:`~mien.facs.arkit.ARKIT_NAMES` by name, without swapping sides.
- The facial transformation matrix maps MediaPipe's canonical face model into camera space. The canonical
  model's axes are mien's rig axes (+x the subject's left, +y up, +z out of the face) and camera space has +x
  to the picture's right, +y up, +z toward the viewer, so a frontal face gives the identity rotation.
  :func:`head_pose_deg` turns the rotation into mien's yaw/pitch/roll (docs/ARCHITECTURE.md).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Literal

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.paths import require_asset
from mien.tracking.native_logs import quiet_native_logs

__all__ = ["MIN_CONFIDENCE", "NOT_ESTIMATED", "N_LANDMARKS", "FrameResult", "Landmarker", "head_pose_deg"]

MIN_CONFIDENCE = 0.7
"""Default face detection / presence / tracking confidence. MediaPipe's own default, 0.5, took blurred title
text for a face on a few frames of the shared test clips (noface_face.mov, face_noface.mov); 0.7 removed
those without losing any real face frame there."""

N_LANDMARKS = 478
"""Landmarks per face in MediaPipe's face mesh with irises (468 + 2 x 5 iris points)."""


@dataclass(frozen=True, eq=False)
class FrameResult:
    """What the landmarker found on one frame (one face)."""

    landmarks: np.ndarray
    """(478, 3) float32 normalised coordinates: x / width, y / height, z in the same scale as x (smaller is
    nearer the camera), origin at the picture's top-left."""
    blendshapes: np.ndarray
    """(52,) float32 scores 0..1 in :data:`~mien.facs.arkit.ARKIT_NAMES` order (the subject's sides)."""
    matrix: np.ndarray
    """(4, 4) float64 facial transformation matrix (canonical face model -> camera space, centimetres)."""

    @property
    def head_pose_deg(self) -> np.ndarray:
        """(3,) yaw, pitch, roll in degrees, mien convention (see :func:`head_pose_deg`)."""
        return head_pose_deg(self.matrix)


def head_pose_deg(matrix: np.ndarray) -> np.ndarray:
    """(..., 3) yaw, pitch, roll in degrees from (..., 4, 4) (or 3x3) canonical-to-camera transforms.

    The rotation is read as ``R = Ry(yaw) @ Rx(-pitch) @ Rz(-roll)`` about the camera axes (+x picture right,
    +y up, +z toward the viewer), giving mien's convention: yaw > 0 turns the face to the subject's left (the
    picture's right), pitch > 0 tilts it up, roll > 0 tilts the head toward the subject's left shoulder.

    >>> head_pose_deg(np.eye(4)).tolist()
    [0.0, 0.0, 0.0]
    """
    rot = np.asarray(matrix, dtype=np.float64)[..., :3, :3]
    rot = rot / np.linalg.norm(rot, axis=-2, keepdims=True)  # drop any scale from the columns
    yaw = np.arctan2(rot[..., 0, 2], rot[..., 2, 2])
    pitch = -np.arcsin(np.clip(-rot[..., 1, 2], -1.0, 1.0))
    roll = -np.arctan2(rot[..., 1, 0], rot[..., 1, 1])
    return np.degrees(np.stack([yaw, pitch, roll], axis=-1)) + 0.0  # + 0.0 turns -0.0 into 0.0


def _vision() -> Any:
    return require("mediapipe.tasks.python.vision", "track")


class Landmarker:
    """A MediaPipe Face Landmarker for one face, in ``"video"`` (tracking) or ``"image"`` mode.

    Use as a context manager (or call :meth:`close`). In video mode frames must come in time order.

    model: path to ``face_landmarker.task`` (default: the configured ``face_landmarker`` asset).
    min_confidence: face detection, presence and tracking confidence thresholds, 0..1.
    """

    def __init__(
        self,
        model: str | os.PathLike[str] | None = None,
        mode: Literal["video", "image"] = "video",
        min_confidence: float = MIN_CONFIDENCE,
    ) -> None:
        if mode not in ("video", "image"):
            raise InvalidValueError("mode", mode, "'video' or 'image'")
        if not 0.0 <= min_confidence <= 1.0:
            raise InvalidValueError("min_confidence", min_confidence, "a number in [0, 1]")
        self.model_path: Path = require_asset("face_landmarker", model)
        with quiet_native_logs():  # the log levels are set before mediapipe's first import
            self._task = self._create(_vision(), mode, min_confidence)
        self.mode = mode
        self._last_ms = -1
        self._blendshape_order: np.ndarray | None = None

    def _create(self, vision: Any, mode: str, min_confidence: float) -> Any:
        from mediapipe.tasks.python import BaseOptions

        running_mode = vision.RunningMode.VIDEO if mode == "video" else vision.RunningMode.IMAGE
        options = vision.FaceLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(self.model_path)),
            running_mode=running_mode,
            num_faces=1,
            output_face_blendshapes=True,
            output_facial_transformation_matrixes=True,
            min_face_detection_confidence=min_confidence,
            min_face_presence_confidence=min_confidence,
            min_tracking_confidence=min_confidence,
        )
        try:
            return vision.FaceLandmarker.create_from_options(options)
        except (RuntimeError, ValueError) as exc:
            expected = f"a MediaPipe face_landmarker.task ({exc})"
            raise InvalidValueError("model", str(self.model_path), expected) from None

    def __enter__(self) -> Landmarker:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def close(self) -> None:
        """Release the MediaPipe graph (idempotent)."""
        task, self._task = getattr(self, "_task", None), None
        if task is not None:
            task.close()

    def detect(self, rgb: np.ndarray, timestamp_s: float = 0.0) -> FrameResult | None:
        """Find the face on ``rgb`` ((h, w, 3) uint8); ``None`` when there is none.

        ``timestamp_s`` (video mode) is the frame time in seconds; equal or decreasing times are nudged forward
        by a millisecond, as MediaPipe needs strictly increasing timestamps.
        """
        if self._task is None:
            raise InvalidValueError("landmarker", "closed", "an open Landmarker")
        import mediapipe as mp

        image = mp.Image(image_format=mp.ImageFormat.SRGB, data=np.ascontiguousarray(rgb, dtype=np.uint8))
        if self.mode == "video":
            stamp = max(round(timestamp_s * 1000.0), self._last_ms + 1)
            self._last_ms = stamp
            result = self._task.detect_for_video(image, stamp)
        else:
            result = self._task.detect(image)
        if not result.face_landmarks:
            return None
        landmarks = np.array([(p.x, p.y, p.z) for p in result.face_landmarks[0]], dtype=np.float32)
        categories = result.face_blendshapes[0]
        if self._blendshape_order is None:
            self._blendshape_order = _arkit_order([c.category_name for c in categories])
        scores = np.array([c.score for c in categories], dtype=np.float32)
        blendshapes = np.zeros(len(ARKIT_NAMES), dtype=np.float32)
        blendshapes[self._blendshape_order[:, 1]] = scores[self._blendshape_order[:, 0]]
        matrix = np.asarray(result.facial_transformation_matrixes[0], dtype=np.float64).reshape(4, 4)
        return FrameResult(landmarks, blendshapes, matrix)


NOT_ESTIMATED: tuple[str, ...] = ("tongueOut",)
"""ARKit names MediaPipe does not output (its 52 categories are ``_neutral`` + 51 ARKit names); left at 0."""


def _arkit_order(names: list[str]) -> np.ndarray:
    """(51, 2) pairs (index in MediaPipe's list, index in ARKIT_NAMES) for the names MediaPipe gives."""
    pairs = [(i, ARKIT_INDEX[n]) for i, n in enumerate(names) if n in ARKIT_INDEX]
    missing = sorted(set(ARKIT_NAMES) - set(names) - set(NOT_ESTIMATED))
    if missing:
        raise InvalidValueError("MediaPipe blendshapes", missing, "all 52 ARKit names in the model's output")
    return np.array(pairs, dtype=np.intp)
