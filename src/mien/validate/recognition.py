"""Emotion recognition of rendered faces under the Broekens study conditions (a machine Table 4).

Each stimulus is one face at the peak of an emotion event (the character's own engine: the same basis,
intensity rule and blends as a running character), rendered on a head and identity through a camera, and
classified by a detector that gives emotion probabilities (:class:`~mien.validate.face_detector.FaceDetector`).
For views where the landmarker finds no face (the 90-degree profile), the crop comes from the rig's own
landmarks projected through the camera (the ``hint``): that is mien's answer to the lateral condition, and
the detection records it.

Metrics, per expression over all renders:

* every verdict from the averaged judge (:mod:`mien.validate.judge`): the classifier's probabilities averaged over
  twelve crops of the face (two picture sizes, both framings, jittered), each reading kept for the spread;
* recognition rate: share of renders whose top label is the expression's label (basic emotions and neutral);
  for a blend, the share whose top label is one of its components' (as the study judged blends; the share whose
  two top labels are both components is reported beside it);
* confusion matrix: expression x top label;
* quality (Broekens' Table 4 metric ``target / (mean over labels x number of labels)``): with probabilities
  summing to 1 over the classifier's labels, it is the mean probability of the target label; the study's
  human values (:data:`~mien.validate.expressions.HUMAN_QUALITY`) are shown beside it;
* disgust's FACS signs: AU9 (nose wrinkler) and AU10 (upper-lip raiser) estimated from the detected
  blendshapes (:class:`~mien.rig.au_solve.AUSolver`) against the same head's neutral, and the
  geometric shortening of the nose-to-upper-lip distance on the rendered mesh (iBUG landmarks 33 -> 51),
  because the shipped classifier almost never answers "disgust" and cannot be the judge of it;
* the FACS reading (:attr:`~mien.validate.scores.StimulusScore.facs_top`, :mod:`mien.validate.facs_reading`): a
  second judge that reads the face as a FACS coder would. It needs the detector's blendshapes; without them (or
  for a neutral face, or when nothing moved) it is None.

The results themselves (:class:`~mien.validate.scores.RecognitionResult`) live in :mod:`mien.validate.scores`;
this module renders, judges and writes them.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from mien.character import Character
from mien.errors import InvalidValueError, UnknownNameError
from mien.extras import require
from mien.fileio.streams import atomic_path
from mien.heads import load_head
from mien.progress import progress as progress_bar
from mien.render.camera import VIEWS
from mien.render.contact_sheet import contact_sheet
from mien.render.video import write_png
from mien.rig.au_solve import AUSolver
from mien.rig.heads import head_label
from mien.tracking.ibug68 import ibug68
from mien.validate.detector import EMOTION_LABELS, Detector
from mien.validate.emotion_classifier import FRAMINGS, crop_square, face_box
from mien.validate.expressions import EXPRESSIONS
from mien.validate.face_detector import FaceDetector
from mien.validate.facs_reading import with_facs_readings
from mien.validate.figures import plot_confusion, plot_quality
from mien.validate.judge import JUDGE_CROPS, RENDER_SCALES, JudgeCrop, crop_names, judge, resample
from mien.validate.landmark_aus import LandmarkAUs
from mien.validate.options import ValidateOptions, open_detector
from mien.validate.scores import RecognitionResult, Stimulus, StimulusScore
from mien.validate.stimuli import StimulusRenderer

__all__ = [
    "PEAK_TIME_S",
    "judge_crops_for",
    "peak_face",
    "recognition_study",
    "run_recognition",
    "study_stimuli",
    "write_recognition",
]

PEAK_TIME_S = 0.55
"""Time of the sampled frame after the event starts: the middle of the default 0.4/0.3/0.3 s envelope's hold."""


def study_stimuli(
    heads: Sequence[tuple[str, str]],
    bases: Sequence[str] = ("facs", "feature_points"),
    views: Sequence[str] = ("frontal-1m", "frontal-3m"),
    intensities: Sequence[float] = (1.2, 2.4),
    expressions: Sequence[str] = EXPRESSIONS,
    neutral: bool = True,
) -> list[Stimulus]:
    """Every combination of the conditions (plus one neutral face per head, basis and view)."""
    for view in views:
        if view not in VIEWS:
            raise UnknownNameError("view", view, tuple(VIEWS))
    for name in expressions:
        if name not in EXPRESSIONS:
            raise UnknownNameError("expression", name, EXPRESSIONS)
    for basis in bases:
        if basis not in ("facs", "feature_points"):
            raise InvalidValueError("basis", basis, "'facs' or 'feature_points'")
    for value in intensities:
        if not (np.isfinite(value) and 0 < value <= 5):
            raise InvalidValueError("intensity", value, "a number in (0, 5]")
    out = []
    for head, identity in heads:
        for basis in bases:
            for view in views:
                if neutral:
                    out.append(Stimulus("neutral", head, identity, basis, view, 0.0))
                for name in expressions:
                    for value in intensities:
                        out.append(Stimulus(name, head, identity, basis, view, float(value)))
    return out


def peak_face(expression: str, intensity: float, basis: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``(face frame (62,), feature weights (54,) or None)`` at the peak of one emotion event.

    The frame comes from a :class:`~mien.character.Character` with idle behaviour off, so the stimulus is
    exactly what a running character shows (basis, intensity rule, blends).
    """
    character = Character(seed=0, idle=False, expression_basis=basis)
    if expression != "neutral":
        character.emote(expression, intensity, start_s=0.0)
    frame = character.step(PEAK_TIME_S).copy()
    features = character.feature_weights.copy() if basis == "feature_points" else None
    return frame, features


def _judged_crop(rgb: np.ndarray, landmarks: np.ndarray, framing: str, side: int = 160) -> np.ndarray:
    """The colour version of the square the classifier saw (cropped with ``framing``), ``side`` pixels wide."""
    image = require("PIL.Image", "render")
    patch = crop_square(rgb, face_box(landmarks, framing))
    return np.asarray(image.fromarray(patch).resize((side, side), image.Resampling.BILINEAR))


def run_recognition(
    stimuli: Sequence[Stimulus],
    detector: Detector | None = None,
    size: tuple[int, int] = (512, 512),
    keep_images: bool = False,
    progress: bool = True,
    judge_with: str = "averaged",
    samples: int | Sequence[int] = 4,
    rasterise_sizes: bool = False,
) -> RecognitionResult:
    """Render and judge every stimulus (grouped by head and basis so each rig and renderer is built once).

    Each face is judged by the averaged judge (:mod:`mien.validate.judge`) when the detector holds the FER
    classifier: rendered at every size of :data:`~mien.validate.judge.RENDER_SCALES` of ``size``, its landmarks
    found on the first, read under every crop of :data:`~mien.validate.judge.JUDGE_CROPS` (``judge_with`` a framing
    name: that framing's crops only), the verdict the mean. Other detectors give their own probabilities.
    The smaller size is the render reduced by area averaging (:func:`~mien.validate.judge.resample`: what a camera
    with fewer pixels records), or with ``rasterise_sizes`` drawn a second time at that size. ``samples``:
    multisample anti-aliasing of the renders, one value or one per rasterised size (0: off; turning it off changes 19
    of 672 verdicts, docs/VALIDATION.md).
    """
    own = detector is None
    active: Detector = FaceDetector() if detector is None else detector
    classifier = _framed_classifier(active)
    mediapipe = getattr(active, "mediapipe", None) if classifier is not None else None
    crops = judge_crops_for(judge_with) if classifier is not None else ()
    framing = judge_with if classifier is not None else str(getattr(active, "framing", "landmarks"))
    width = int(size[0])
    scales = RENDER_SCALES if classifier is not None else RENDER_SCALES[:1]
    names = crop_names(width, scales, crops)
    timings = {"load": 0.0, "render": 0.0, "detect": 0.0}
    solver = AUSolver()  # the 18 OpenFACS AUs: AU9/AU10 for disgust's signs, all of them for the FACS reading
    scores: list[StimulusScore | None] = [None] * len(stimuli)
    images: dict[int, np.ndarray] = {}
    groups: dict[tuple[str, str, str], dict[str, list[int]]] = {}
    for index, stimulus in enumerate(stimuli):
        setup = groups.setdefault((stimulus.head, stimulus.identity, stimulus.basis), {})
        setup.setdefault(stimulus.view, []).append(index)
    bar = progress_bar(range(len(stimuli)), total=len(stimuli), desc="recognition", enabled=progress)
    ticker = iter(bar)
    rigs: dict[tuple[str, str, bool], Any] = {}
    estimators: dict[tuple[str, str, bool], LandmarkAUs] = {}
    try:
        for (head, identity, basis), by_view in groups.items():
            started = time.perf_counter()
            key: tuple[str, str, bool] = (head, identity, basis == "feature_points")
            if key not in rigs:
                rigs[key] = load_head(head, identity, feature_points=key[2])
            rig = rigs[key]
            timings["load"] += time.perf_counter() - started
            first = VIEWS[next(iter(by_view))].camera
            rasterised = scales if rasterise_sizes else scales[:1]
            sizes = [(round(size[0] * k), round(size[1] * k)) for k in rasterised]
            with contextlib.ExitStack() as stack:
                multisamples = [samples] * len(sizes) if isinstance(samples, int) else list(samples)[: len(sizes)]
                renderers = [
                    stack.enter_context(StimulusRenderer(rig, first, s, samples=m))
                    for s, m in zip(sizes, multisamples, strict=True)
                ]
                renderer = renderers[0]
                if key not in estimators:
                    started = time.perf_counter()
                    estimators[key] = LandmarkAUs(rig, renderer.weights)
                    timings["load"] += time.perf_counter() - started
                landmark_aus = estimators[key]
                for view, indices in by_view.items():
                    for each in renderers:
                        each.set_camera(VIEWS[view].camera)
                    for index in indices:
                        stimulus = stimuli[index]
                        started = time.perf_counter()
                        frame, features = peak_face(stimulus.expression, stimulus.intensity, basis)
                        weights = renderer.weights(frame, features)
                        rgb, hint = renderer.render_weights(weights)
                        deformed = renderer.last_vertices
                        if rasterise_sizes:
                            smaller = [each.draw(deformed) for each in renderers[1:]]
                        else:
                            smaller = [resample(rgb, k) for k in scales[1:]]
                        lm = rig.landmarks
                        nose_lip = float(np.linalg.norm(deformed[lm[33]] - deformed[lm[51]])) * 1e3
                        timings["render"] += time.perf_counter() - started
                        started = time.perf_counter()
                        if mediapipe is not None:
                            found = mediapipe.detect(rgb)
                            landmarks = found.landmarks if found.found else hint
                            from_hint = not found.found
                        else:
                            found = active.detect(rgb, hint)
                            landmarks, from_hint = found.landmarks, found.landmarks_from_hint
                        readings: dict[str, tuple[float, ...]] = {}
                        emotions = found.emotions
                        if landmarks is not None and len(landmarks) >= 468:
                            landmarks = ibug68(np.asarray(landmarks)[:, :2])  # once a face: 7 ms each time
                        if classifier is not None and landmarks is not None:
                            renders = [(rgb, landmarks)]
                            renders += [(small, landmarks * (small.shape[1] / width)) for small in smaller]
                            probabilities = judge(classifier, renders, crops)
                            readings = {
                                n: tuple(float(p) for p in row) for n, row in zip(names, probabilities, strict=True)
                            }
                            emotions = probabilities.mean(axis=0)
                        timings["detect"] += time.perf_counter() - started
                        if emotions is None:
                            emotions = np.full(len(EMOTION_LABELS), np.nan)
                        aus: dict[str, float] = {}
                        if found.blendshapes is not None:
                            values = solver.solve(found.blendshapes)
                            aus = {f"AU{code}": float(v) for code, v in zip(solver.aus, values, strict=True)}
                        scores[index] = StimulusScore(
                            stimulus,
                            tuple(float(p) for p in emotions),
                            bool(found.found and not from_hint),
                            aus,
                            nose_lip,
                            landmark_aus.estimate(deformed),
                            crops=readings,
                        )
                        if keep_images and landmarks is not None:
                            images[index] = _judged_crop(rgb, landmarks, crops[0].framing if crops else framing)
                        next(ticker, None)
    finally:
        if own:
            active.close()
    for _ in ticker:
        pass
    done = with_facs_readings([s for s in scores if s is not None], solver.aus)
    return RecognitionResult(done, active.name, {k: round(v, 3) for k, v in timings.items()}, images, framing)


def _framed_classifier(detector: Any) -> Any:
    """The FER classifier inside ``detector`` (a :class:`~mien.validate.face_detector.FaceDetector` or
    :class:`~mien.validate.face_detector.EmotionDetector`), to judge each render in the other framings too; None
    for other detectors."""
    emotion = getattr(detector, "emotion", detector)
    return getattr(emotion, "classifier", None)


def judge_crops_for(judge_with: str) -> tuple[JudgeCrop, ...]:
    """The crops of the judge named ``judge_with``: ``"averaged"`` (all of
    :data:`~mien.validate.judge.JUDGE_CROPS`) or a framing name (that framing's three)."""
    if judge_with == "averaged":
        return JUDGE_CROPS
    if judge_with not in FRAMINGS:
        raise UnknownNameError("judge", judge_with, ("averaged", *FRAMINGS))
    return tuple(crop for crop in JUDGE_CROPS if crop.framing == judge_with)


def _sheet_label(score: StimulusScore) -> str:
    s = score.stimulus
    order = np.argsort(score.emotions)[::-1]
    probs = " ".join(f"{EMOTION_LABELS[int(i)][:3]} {score.emotions[int(i)]:.2f}" for i in order[:2])
    mark = {True: "ok", False: "MISS", None: ""}[score.correct()]
    level = "" if s.expression == "neutral" else f" x{s.intensity:g}"
    return f"{s.expression}{level} {mark}\n{probs}"


def write_recognition(result: RecognitionResult, out_dir: str | Path) -> dict[str, Path]:
    """Write ``recognition.json``, the judged contact sheets (one per head/identity/basis/view) and the figures.

    Every file is written under a temporary name and renamed when complete; ``recognition.json`` goes last.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written: dict[str, Path] = {}
    groups: dict[tuple[str, str, str, str], list[int]] = {}
    for index, score in enumerate(result.scores):
        s = score.stimulus
        groups.setdefault((s.head, s.identity, s.basis, s.view), []).append(index)
    for (head, identity, basis, view), indices in groups.items():
        shown = [i for i in indices if i in result.images]
        if not shown:
            continue
        slug = "".join(ch if ch.isalnum() or ch in "-." else "_" for ch in head_label(head, identity))
        name = f"sheet_{slug}_{basis}_{view}.png"
        columns = 1 + len({result.scores[i].stimulus.intensity for i in shown if result.scores[i].stimulus.intensity})
        sheet = contact_sheet(
            [result.images[i] for i in shown],
            [_sheet_label(result.scores[i]) for i in shown],
            columns=max(columns, 2) * 3 + 1,
            font_size=12,
        )
        written[name] = write_png(sheet, out / name)  # atomic
    for name, draw in (("confusion.png", plot_confusion), ("quality.png", plot_quality)):
        with atomic_path(out / name) as temporary:
            draw(result, temporary)
        written[name] = out / name
    written["recognition.json"] = result.write_json(out / "recognition.json")
    return written


def recognition_study(heads: Sequence[tuple[str, str]], options: ValidateOptions) -> RecognitionResult:
    """The recognition study on ``heads`` under ``options`` (bases, views, intensities, expressions, size,
    models), with the judged crops kept for the contact sheets. Bad conditions fail before any model loads."""
    stimuli = study_stimuli(heads, options.bases, options.views, options.intensities, options.expressions)
    detector = open_detector(options)
    try:
        return run_recognition(
            stimuli, detector, options.size_px, keep_images=True, progress=options.show_progress,
            judge_with=options.framing,
        )  # fmt: skip
    finally:
        detector.close()
