"""What the detector does on real human faces: the evidence that it can see an AU at all.

An AU *moves* on a set of faces when the largest range (max - min) of one of its primary blendshapes' scores over
those faces is at least :data:`~mien.validate.rig_fidelity.MOVE_THRESHOLD` (:mod:`mien.validate.rig_fidelity`). On
human faces that is measured on the shared media (``human_data``: ``video/single_face.mp4``, every frame with a
face; ``images/*.jpg``, each face found; ``multi_face.jpg`` in overlapping tiles, as the landmarker finds one face
per call).

The human data available is small: one clip of one person going from neutral into a broad smile with a blink, and
two photographs of smiles. Which AUs it performs was coded by eye from the frames (:data:`HUMAN_DATA_AUS`: AU6,
AU12, AU25 throughout, AU45 in the clip).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.facs.arkit import ARKIT_NAMES
from mien.tracking import Landmarker, track_video
from mien.validate.json_values import rounded, unrounded

__all__ = ["HUMAN_DATA_AUS", "HumanEvidence", "default_human_folder", "human_evidence"]

HUMAN_DATA_AUS: dict[str, tuple[int, ...]] = {
    "video/single_face.mp4": (6, 12, 25, 45),
    "images/single_face.jpg": (6, 12, 25),
    "images/multi_face.jpg": (6, 12, 25),
}
"""AUs each shared human medium performs, coded by eye from its frames by a mien developer (not a certified FACS
coder): the clip goes from neutral into a Duchenne smile with parted lips and teeth shown (AU6+12+25) and blinks
once (AU45, frame 27); the photographs show open-mouthed smiles (AU6+12+25). Paths are relative to the shared
data folder."""

_TILES = 3
"""``multi_face.jpg``: the landmarker finds one face per call, so the image is scanned in vertical strips a
third of its width wide at half-strip steps; faces found twice are kept once."""


@dataclass(frozen=True, eq=False)
class HumanEvidence:
    """How much MediaPipe's blendshapes move on the real human faces available."""

    folder: str | None
    """The human data folder measured (absolute), or None when none was available."""
    sources: dict[str, int] = field(default_factory=dict)
    """Faces measured per medium (path relative to :attr:`folder`): frames with a face, or faces found."""
    performed: tuple[int, ...] = ()
    """AUs the measured media perform (:data:`HUMAN_DATA_AUS` of the media with a face)."""
    blendshape_range: np.ndarray = field(default_factory=lambda: np.full(52, np.nan))
    """(52,) range (max - min) of each ARKit blendshape score over all human faces; NaN without faces."""
    blendshapes: np.ndarray = field(default_factory=lambda: np.zeros((0, 52)))
    """(n_faces, 52) the scores themselves (video frames first, then image faces)."""

    @property
    def n_faces(self) -> int:
        """Faces measured (video frames with a face plus faces in images)."""
        return sum(self.sources.values())

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form (ranges by ARKit name, rounded to 1e-4; the per-face scores are left out)."""
        return {
            "folder": self.folder,
            "sources": dict(self.sources),
            "n_faces": self.n_faces,
            "performed": [f"AU{code}" for code in self.performed],
            "performed_source": "coded by eye from the frames (mien.validate.human_evidence.HUMAN_DATA_AUS)",
            "blendshape_range": {
                name: rounded(value) for name, value in zip(ARKIT_NAMES, self.blendshape_range, strict=True)
            },
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HumanEvidence:
        """Inverse of :meth:`to_dict` (without the per-face scores)."""
        ranges = data["blendshape_range"]
        return cls(
            folder=data["folder"],
            sources={str(k): int(v) for k, v in data["sources"].items()},
            performed=tuple(int(str(name).removeprefix("AU")) for name in data["performed"]),
            blendshape_range=np.array([unrounded(ranges[name]) for name in ARKIT_NAMES]),
        )


def default_human_folder() -> Path | None:
    """``$MIEN_SHARED/data`` when it is a folder, else None."""
    shared = os.environ.get("MIEN_SHARED")
    if shared and (Path(shared) / "data").is_dir():
        return Path(shared) / "data"
    return None


def _image_faces(landmarker: Any, rgb: np.ndarray, tiled: bool) -> list[np.ndarray]:
    """(52,) scores of each face found in ``rgb``: the whole image, or overlapping vertical strips."""
    if not tiled:
        found = landmarker.detect(rgb)
        return [] if found is None else [found.blendshapes]
    width = rgb.shape[1]
    strip = width // _TILES
    faces: list[tuple[float, np.ndarray]] = []
    for start in range(0, width - strip + 1, max(1, strip // 2)):
        found = landmarker.detect(np.ascontiguousarray(rgb[:, start : start + strip]))
        if found is None:
            continue
        centre = start + float(found.landmarks[:, 0].mean()) * strip
        if all(abs(centre - seen) > 0.05 * width for seen, _ in faces):  # the same face in two strips
            faces.append((centre, found.blendshapes))
    return [scores for _, scores in faces]


def human_evidence(
    folder: str | os.PathLike[str] | None, model: str | os.PathLike[str] | None = None, progress: bool = False
) -> HumanEvidence:
    """MediaPipe's blendshape scores on the human media of :data:`HUMAN_DATA_AUS` found in ``folder``.

    The clip is tracked with :func:`mien.tracking.track_video` (video mode, cached; frames with a face), the
    images with a :class:`~mien.tracking.Landmarker` in image mode. ``folder`` None gives empty evidence.
    """
    if folder is None:
        return HumanEvidence(folder=None)
    root = Path(folder).expanduser().resolve()
    if not root.is_dir():
        raise InvalidValueError("human_data", str(root), "a folder holding video/single_face.mp4 and images/")
    image = require("PIL.Image", "render")
    sources: dict[str, int] = {}
    rows: list[np.ndarray] = []
    performed: set[int] = set()
    for relative, aus in HUMAN_DATA_AUS.items():
        path = root / relative
        if not path.is_file():
            continue
        if path.suffix == ".mp4":
            track = track_video(path, model, show_progress=progress)
            scores = np.asarray(track.blendshapes[track.face_found], dtype=np.float64)
        else:
            with Landmarker(model, mode="image") as landmarker:
                rgb = np.asarray(image.open(path).convert("RGB"))
                scores = np.array(_image_faces(landmarker, rgb, tiled="multi" in path.stem)).reshape(-1, 52)
        sources[relative] = len(scores)
        if len(scores):
            rows.append(scores)
            performed.update(aus)
    stacked = np.round(np.concatenate(rows), 4) if rows else np.zeros((0, 52))
    ranges = stacked.max(axis=0) - stacked.min(axis=0) if len(stacked) else np.full(52, np.nan)
    return HumanEvidence(str(root), sources, tuple(sorted(performed)), ranges, stacked)
