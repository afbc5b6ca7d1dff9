"""The options of a validation run, as one frozen value: what the CLI parses, the library reads (never argparse).

>>> options = ValidateOptions(out_dir=Path("out"), views=("frontal-1m",))
>>> options.size_px, options.bases, options.views
((512, 512), ('facs', 'feature_points'), ('frontal-1m',))
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from mien.paths import require_asset
from mien.render.camera import VIEWS
from mien.validate.emotion_classifier import FRAMINGS
from mien.validate.expressions import EXPRESSIONS
from mien.validate.face_detector import FaceDetector

__all__ = ["ValidateOptions", "open_detector"]


@dataclass(frozen=True)
class ValidateOptions:
    """How to run ``mien validate`` (rig, emotions, report): where to write, what to render, which models judge."""

    out_dir: Path
    """Folder the results are written to (made if missing)."""
    size_px: tuple[int, int] = (512, 512)
    """Render size (width, height), pixels."""
    landmarker_path: Path | None = None
    """MediaPipe ``face_landmarker.task`` (None: ``$MIEN_FACE_LANDMARKER`` or the config)."""
    emotion_model_path: Path | None = None
    """FER emotion classifier ``.tflite`` (None: ``$MIEN_EMOTION_MODEL`` or the config)."""
    framing: str = "averaged"
    """How a verdict is judged: ``"averaged"`` (every crop of :mod:`mien.validate.judge`), or one framing of
    :data:`mien.validate.emotion_classifier.FRAMINGS` (its three jittered crops only, to compare)."""
    show_progress: bool = True
    """Show progress bars."""
    bases: tuple[str, ...] = ("facs", "feature_points")
    """Expression bases of the recognition study: ``"facs"``, ``"feature_points"``."""
    views: tuple[str, ...] = tuple(VIEWS)
    """Camera views of the recognition study (:data:`mien.render.camera.VIEWS`)."""
    intensities: tuple[float, ...] = (1.2, 2.4)
    """Emotion intensities of the recognition study, 0..5 (the study's: 1.2 and 2.4)."""
    expressions: tuple[str, ...] = EXPRESSIONS
    """Expressions of the recognition study (a subset of :data:`mien.validate.expressions.EXPRESSIONS`)."""
    human_data_dir: Path | None = None
    """Folder of real human media (``video/``, ``images/``) for the rig's evidence (None: ``$MIEN_SHARED/data``)."""
    video_path: Path | None = None
    """Video of a person for the report's human comparison (None: no comparison)."""
    video_expression: str = "joy"
    """The expression that video shows (an emotion, blend or AUs such as ``"AU6+AU12D"``)."""


def open_detector(options: ValidateOptions, emotions: bool = True) -> FaceDetector:
    """MediaPipe (and with ``emotions`` the FER classifier) on the options' models; fails first, naming the model
    (:class:`~mien.errors.MissingAssetError`), when one is not configured or not found. Close it when done."""
    require_asset("face_landmarker", options.landmarker_path)
    if emotions:
        require_asset("emotion_model", options.emotion_model_path)
    framing = options.framing if options.framing in FRAMINGS else "landmarks"
    return FaceDetector(options.landmarker_path, options.emotion_model_path, emotions=emotions, framing=framing)
