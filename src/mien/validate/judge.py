"""The averaged judge: what one verdict of ``mien validate`` is.

A verdict on a rendered face is never the classifier's answer on one crop. The face is rendered at the run's size and
also taken at :data:`RENDER_SCALES` of it (by default the render reduced by area averaging, :func:`resample`: the
same picture as a camera with fewer pixels records it), its landmarks found once on the larger picture (MediaPipe;
scaled to the smaller), and the classifier reads the face under every crop of :data:`JUDGE_CROPS` on both: both
framings of :data:`~mien.validate.emotion_classifier.FRAMINGS` ("landmarks": brows to chin; "fer": the fer
package's own, forehead to chin), each at its place and jittered by a few percent in position and scale. The
verdict's probabilities are the mean of those 2 x 6 = 12 readings; the top label of the mean is the verdict. Every
reading is kept (:attr:`~mien.validate.scores.StimulusScore.crops`), so each figure can be given with its spread:
the same figure judged by each crop alone, lowest to highest (:meth:`~mien.validate.scores.RecognitionResult.spread`).

So a face that reads under one framing only does not pass on that framing's say: the other framing's six readings
pull the mean away. The jitter is the size of the disagreement between the two ways a face is usually framed
(fer's Haar box sits 0.16-0.19 of the landmark square higher, 1.10-1.20 times wider: the fourteenth pass of
docs/VALIDATION.md), and the two sizes put the 3 m face's 73 px square at 73 and 55 px.

>>> [crop.name for crop in JUDGE_CROPS][:3]
['landmarks', 'landmarks up-left wide', 'landmarks down-right tight']
>>> crop_names(512)[:2]
['landmarks @512', 'landmarks up-left wide @512']
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mien.extras import require
from mien.tracking.ibug68 import ibug68
from mien.validate.emotion_classifier import FRAMINGS, INPUT_SIZE, EmotionClassifier, face_crop, grey

__all__ = [
    "JUDGE_CROPS",
    "RENDER_SCALES",
    "JudgeCrop",
    "crop_names",
    "framing_of",
    "judge",
    "judge_crops",
    "resample",
]


@dataclass(frozen=True)
class JudgeCrop:
    """One crop of the averaged judge: a framing and its jitter."""

    framing: str
    """A name in :data:`~mien.validate.emotion_classifier.FRAMINGS`."""
    dx: float = 0.0
    """Centre moved right by this share of the crop's side."""
    dy: float = 0.0
    """Centre moved down by this share of the side."""
    scale: float = 1.0
    """Side multiplied by this."""
    label: str = ""
    """How the jitter is named (``"up-left wide"``); empty for the framing's own place."""

    @property
    def name(self) -> str:
        """``"landmarks"``, ``"fer up-left wide"``..."""
        return f"{self.framing} {self.label}".strip()

    @property
    def jitter(self) -> tuple[float, float, float]:
        """``(dx, dy, scale)`` for :func:`~mien.validate.emotion_classifier.face_box`."""
        return self.dx, self.dy, self.scale


_JITTERS = ((0.0, 0.0, 1.0, ""), (-0.04, -0.04, 1.06, "up-left wide"), (0.04, 0.04, 0.94, "down-right tight"))

JUDGE_CROPS: tuple[JudgeCrop, ...] = tuple(
    JudgeCrop(framing, dx, dy, scale, label) for framing in FRAMINGS for dx, dy, scale, label in _JITTERS
)
"""The fixed crops every verdict averages, per render size: each framing at its place, then 4% up-left and 6%
wider, then 4% down-right and 6% tighter. Three per framing, six in all."""

RENDER_SCALES: tuple[float, ...] = (1.0, 0.75)
"""Render sizes of each face, relative to the run's size (512x512 -> 512 and 384 pixels)."""


def resample(rgb: np.ndarray, scale: float) -> np.ndarray:
    """``rgb`` ((h, w, 3) uint8) reduced to ``scale`` of its size by area averaging (PIL's box filter): the same
    picture as a camera with fewer pixels records it, each pixel the mean of the scene over its area."""
    image = require("PIL.Image", "render")
    height, width = rgb.shape[:2]
    size = (round(width * scale), round(height * scale))
    return np.asarray(image.fromarray(np.ascontiguousarray(rgb)).resize(size, image.Resampling.BOX))


def crop_names(
    width: int, scales: Sequence[float] = RENDER_SCALES, crops: Sequence[JudgeCrop] = JUDGE_CROPS
) -> list[str]:
    """Names of the readings of one verdict, in :func:`judge`'s order: ``"<crop> @<render width>"``."""
    return [f"{crop.name} @{round(width * scale)}" for scale in scales for crop in crops]


def framing_of(reading: str) -> str:
    """The framing of a reading named by :func:`crop_names` (``"fer up-left wide @384"`` -> ``"fer"``)."""
    return reading.split(" ", 1)[0]


def judge_crops(
    renders: Sequence[tuple[np.ndarray, np.ndarray]], crops: Sequence[JudgeCrop] = JUDGE_CROPS
) -> np.ndarray:
    """(len(renders) x len(crops), 64, 64) grey crops: every crop of each ``(rgb, landmarks)`` render in turn."""
    out = np.empty((len(renders) * len(crops), INPUT_SIZE, INPUT_SIZE), np.float32)
    for r, (rgb, landmarks) in enumerate(renders):
        luma = grey(rgb)
        points = np.asarray(landmarks, np.float64)[:, :2]
        points = ibug68(points) if len(points) >= 468 else points  # once, not once a crop (7 ms each)
        for c, crop in enumerate(crops):
            out[r * len(crops) + c] = face_crop(rgb, points, crop.framing, jitter=crop.jitter, luma=luma)
    return out


def judge(
    classifier: EmotionClassifier,
    renders: Sequence[tuple[np.ndarray, np.ndarray]],
    crops: Sequence[JudgeCrop] = JUDGE_CROPS,
) -> np.ndarray:
    """(len(renders) x len(crops), 7) probabilities of every reading (one batched call); the verdict is their mean.

    ``renders``: the same face at each size of :data:`RENDER_SCALES`, each ``(rgb (h, w, 3) uint8, landmarks
    (n, 2) pixels on it)``.
    """
    return classifier.classify_crops(judge_crops(renders, crops))
