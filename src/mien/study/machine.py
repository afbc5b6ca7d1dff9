"""The machine's judgement of a study's stimuli, to sit beside the people's (the automatic Table 4).

For each video in a stimuli folder (``manifest.json`` of ``mien study stimuli``), frames sampled every
``sample_s`` seconds go through mien's detector (:class:`~mien.validate.face_detector.FaceDetector`:
MediaPipe landmarks and blendshapes, the FER classifier on the face crop). The *peak frame* is the sampled
frame whose blendshape scores are farthest (L1) from the first frame's, blinks and gaze left out: the moment
the face moved most from rest, whatever the expression's timing in the video. The classifier's probabilities
on that frame are judged exactly as ``mien validate emotions`` judges a rendered peak face: the scores go into
:class:`~mien.validate.recognition.StimulusScore` and :class:`~mien.validate.recognition.RecognitionResult`
(top label, recognised: top label for a basic emotion / the two components' labels for a blend, machine
quality: mean probability of the target label).

A video on which MediaPipe finds no face in any sampled frame (a 90-degree profile) is counted, not judged:
``mien validate emotions`` crops such faces from the rig's projected landmarks, which a video does not carry.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mien.affect.emotions import resolve_emotion
from mien.errors import InvalidValueError, MienError, UnknownNameError
from mien.extras import available
from mien.facs.arkit import ARKIT_NAMES
from mien.paths import require_asset
from mien.progress import progress as progress_bar
from mien.study.stimuli import MANIFEST_NAME, load_manifest
from mien.tracking.video import iter_frames
from mien.validate.detector import EMOTION_LABELS
from mien.validate.expressions import expected_labels
from mien.validate.face_detector import FaceDetector
from mien.validate.scores import Stimulus

if TYPE_CHECKING:
    import pandas as pd

    from mien.validate.detector import Detector
    from mien.validate.scores import RecognitionResult

__all__ = ["MachineJudgement", "judge_stimuli", "machine_unavailable"]

SAMPLE_S = 0.1
"""Seconds between the frames examined for the peak."""


@dataclass(frozen=True, eq=False)
class MachineJudgement:
    """The detector's verdict on every stimulus of a manifest."""

    result: RecognitionResult
    """Scores in manifest order (renders with no face found carry NaN probabilities)."""
    stimulus_ids: tuple[str, ...]
    """Manifest ids, parallel to ``result.scores``."""
    peak_s: tuple[float, ...]
    """Time (seconds from the video's start) of the judged frame, parallel to ``result.scores``."""
    manifest: str
    """Path of the manifest judged."""
    timings_s: dict[str, float] = field(default_factory=dict)
    """Seconds spent decoding and detecting."""
    models: dict[str, str] = field(default_factory=dict)
    """Model name (``face_landmarker``, ``emotion_model``) -> the file the detector loaded, where it says."""

    def table(self) -> pd.DataFrame:
        """Per expression: ``expression, n_stimuli, faces_found, top_label, top_share, recognised, quality``.

        ``top_label``: the classifier's most frequent top label over the judged stimuli (``top_share`` of them);
        ``recognised``: share judged correct (NaN for a name the classifier has no label for, e.g. a laughter
        type); ``quality``: mean probability of the target label (basic emotions; NaN for blends).
        """
        import pandas as pd

        rows = []
        for expression in dict.fromkeys(s.stimulus.expression for s in self.result.scores):
            scores = self.result.subset(expression=expression)
            judged = [s for s in scores if np.all(np.isfinite(s.emotions))]
            tops = Counter(s.top for s in judged)
            top, count = tops.most_common(1)[0] if tops else ("", 0)
            knows = expected_labels(expression) is not None
            recognised = float(np.mean([bool(s.correct()) for s in judged])) if knows and judged else float("nan")
            rows.append(
                [
                    expression,
                    len(scores),
                    sum(s.face_found for s in scores),
                    top,
                    count / len(judged) if judged else float("nan"),
                    recognised,
                    self.result.quality(expression) if judged else float("nan"),
                ]
            )
        columns = ["expression", "n_stimuli", "faces_found", "top_label", "top_share", "recognised", "quality"]
        return pd.DataFrame(rows, columns=columns)


def machine_unavailable(
    landmarker: str | os.PathLike[str] | None = None, emotion_model: str | os.PathLike[str] | None = None
) -> str:
    """Why the machine judgement cannot run here (a model not configured or not found), or ``""`` when it can."""

    try:
        require_asset("face_landmarker", landmarker)
        require_asset("emotion_model", emotion_model)
    except MienError as error:
        return str(error)
    if not available("mediapipe"):
        return "mediapipe is not installed: pip install 'mien[validate]'"
    return ""


def _canonical(expression: str) -> str:

    try:
        return resolve_emotion(expression)
    except UnknownNameError:
        return expression


def _stimulus(entry: dict[str, Any]) -> Any:

    conditions = entry.get("conditions", {}) or {}
    view = str(conditions.get("view", conditions.get("laughter_type", "")))
    if "distance_m" in conditions:
        view = f"{view}-{float(conditions['distance_m']):g}m"
    intensity = conditions.get("intensity", 0.0)
    return Stimulus(
        _canonical(str(entry["expression"])),
        str(conditions.get("head", "")),
        str(conditions.get("identity", "")),
        str(conditions.get("basis", "")),
        view,
        float(intensity) if intensity not in ("", None) else 0.0,
    )


def _moving(names: tuple[str, ...]) -> np.ndarray:
    """Mask of the blendshapes that show expression (not blinks or gaze)."""
    return np.array([not n.startswith(("eyeBlink", "eyeLook")) for n in names], dtype=bool)


def _peak(path: Path, detector: Detector, sample_s: float) -> tuple[float, Any]:
    """``(time_s, detection)`` of the frame that moved most from the first sampled one."""

    mask = _moving(tuple(ARKIT_NAMES))
    rest: np.ndarray | None = None
    best: tuple[float, float, Any] | None = None  # (distance, time, detection)
    first: tuple[float, Any] | None = None
    next_s = 0.0
    for time_s, rgb in iter_frames(path):
        if time_s + 1e-6 < next_s:
            continue
        next_s = time_s + sample_s
        found = detector.detect(rgb)
        if first is None:
            first = (time_s, found)
        if found.blendshapes is None:
            continue
        scores = np.asarray(found.blendshapes, np.float64)[mask]
        if rest is None:
            rest = scores
        distance = float(np.abs(scores - rest).sum())
        if best is None or distance > best[0]:
            best = (distance, time_s, found)
    if best is None:
        assert first is not None  # iter_frames raises on a video without frames
        return first
    return best[1], best[2]


def judge_stimuli(
    stimuli: str | os.PathLike[str],
    detector: Detector | None = None,
    landmarker: str | os.PathLike[str] | None = None,
    emotion_model: str | os.PathLike[str] | None = None,
    sample_s: float = SAMPLE_S,
    progress: bool = False,
) -> MachineJudgement:
    """Judge every video of the stimuli folder ``stimuli`` (its ``manifest.json``; files checked against their
    SHA-256 by :func:`mien.study.stimuli.load_manifest`). ``detector``: default a
    :class:`~mien.validate.face_detector.FaceDetector` on the configured models (closed at the end).

    Raises :class:`~mien.errors.MissingAssetError` for a missing manifest, video or model, and
    :class:`~mien.errors.InvalidValueError` naming a video that changed or does not decode.
    """
    from mien.validate.scores import RecognitionResult, StimulusScore

    if not (np.isfinite(sample_s) and sample_s > 0):
        raise InvalidValueError("sample_s", sample_s, "a positive number of seconds")
    folder = Path(stimuli)
    manifest = load_manifest(folder, verify=True)
    own = detector is None
    if detector is None:
        require_asset("face_landmarker", landmarker)
        require_asset("emotion_model", emotion_model)
        detector = FaceDetector(landmarker, emotion_model)
    scores, ids, peaks = [], [], []
    started = time.perf_counter()
    try:
        entries = list(manifest.get("stimuli", []))
        for entry in progress_bar(entries, total=len(entries), desc="machine judgement", enabled=progress):
            peak_s, found = _peak(folder / entry["file"], detector, sample_s)
            emotions = found.emotions if found.emotions is not None else np.full(len(EMOTION_LABELS), np.nan)
            scores.append(
                StimulusScore(
                    _stimulus(entry),
                    tuple(float(p) for p in emotions),
                    bool(found.found and not found.landmarks_from_hint),
                )
            )
            ids.append(str(entry["id"]))
            peaks.append(float(peak_s))
    finally:
        if own:
            detector.close()
    result = RecognitionResult(tuple(scores), detector.name, {"decode+detect": time.perf_counter() - started})
    models = {
        name: str(getattr(part, "model_path", ""))
        for name, part in (
            ("face_landmarker", getattr(detector, "mediapipe", None)),
            ("emotion_model", getattr(detector, "emotion", None)),
        )
        if part is not None
    }
    return MachineJudgement(
        result, tuple(ids), tuple(peaks), str(folder / MANIFEST_NAME), dict(result.timings_s), models
    )
