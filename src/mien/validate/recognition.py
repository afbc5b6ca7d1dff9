"""Emotion recognition of rendered faces under the Broekens study conditions (a machine Table 4).

Each stimulus is one face at the peak of an emotion event (the character's own engine: the same basis,
intensity rule and blends as a running character), rendered on a head and identity through a camera, and
classified by a detector that gives emotion probabilities (:class:`~mien.validate.face_detector.FaceDetector`).
For views where the landmarker finds no face (the 90-degree profile), the crop comes from the rig's own
landmarks projected through the camera (the ``hint``): that is mien's answer to the lateral condition, and
the detection records it.

Metrics, per expression over all renders:

* recognition rate: share of renders whose top label is the expression's label (basic emotions and neutral);
  for a blend, the share whose two top labels are its components' labels (where the classifier has them);
* confusion matrix: expression x top label;
* quality (Broekens' Table 4 metric ``target / (mean over labels x number of labels)``): with probabilities
  summing to 1 over the classifier's labels, it is the mean probability of the target label; the study's
  human values (:data:`HUMAN_QUALITY`) are shown beside it;
* disgust's FACS signs: AU9 (nose wrinkler) and AU10 (upper-lip raiser) estimated from the detected
  blendshapes (:class:`~mien.rig.au_solve.AUSolver`) against the same head's neutral, and the
  geometric shortening of the nose-to-upper-lip distance on the rendered mesh (iBUG landmarks 33 -> 51),
  because the shipped classifier almost never answers "disgust" and cannot be the judge of it;
* the FACS reading (:attr:`StimulusScore.facs_top`): a second judge that reads the face as a FACS coder would.
  The 18 OpenFACS AUs are estimated from the detected blendshapes, the same head, basis and view's neutral is
  subtracted (clipped at 0), and the emotion whose EMFACS prototype (:mod:`mien.facs.prototypes`) has the
  largest cosine similarity with what was detected is the reading. It tells disgust from anger by their signs
  (AU9/AU10/AU15/AU17 against AU4/AU5/AU7/AU23 and the open mouth) where the classifier cannot. It needs the
  detector's blendshapes; without them (or for a neutral face, or when nothing moved) it is None.
"""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.render.camera import VIEWS
from mien.validate.detector import EMOTION_LABELS, Detector

__all__ = [
    "BLEND_COMPONENTS",
    "EXPRESSIONS",
    "HUMAN_QUALITY",
    "LABEL_OF",
    "READING_VARIANTS",
    "VIEWS",
    "RecognitionResult",
    "Stimulus",
    "StimulusScore",
    "facs_reading",
    "peak_face",
    "run_recognition",
    "study_stimuli",
]

EXPRESSIONS: tuple[str, ...] = (
    "joy", "sadness", "anger", "surprise", "disgust", "fear", "enthusiastic", "furious", "frustrated", "evil",
)  # fmt: skip
"""The ten expressions of the Broekens study: six basic emotions, then the four blends."""

LABEL_OF: dict[str, str] = {
    "joy": "happy",
    "sadness": "sad",
    "anger": "angry",
    "surprise": "surprise",
    "disgust": "disgust",
    "fear": "fear",
    "neutral": "neutral",
}
"""Expression -> the classifier label that names it."""

BLEND_COMPONENTS: dict[str, tuple[str, str]] = {
    "enthusiastic": ("joy", "surprise"),
    "furious": ("anger", "surprise"),
    "frustrated": ("anger", "sadness"),
    "evil": ("joy", "anger"),
}
"""The study's blends and their components (SPEC section 3)."""


def _paper_quality() -> dict[str, float]:
    import csv
    from importlib import resources

    text = resources.files("mien.affect").joinpath("data/broekens_table4.csv").read_text(encoding="utf-8")
    rows = csv.DictReader(line for line in text.splitlines() if not line.startswith("#"))
    return {row["expression"]: float(row["quality"]) for row in rows}


HUMAN_QUALITY: dict[str, float] = _paper_quality()
"""Broekens et al.'s Table 4: recognition quality by the study's 19 participants (ten labels), read from
``mien/affect/data/broekens_table4.csv`` (the one copy; :func:`mien.study.quality.paper_table4` reads it too)."""

PEAK_TIME_S = 0.55
"""Time of the sampled frame after the event starts: the middle of the default 0.4/0.3/0.3 s envelope's hold."""


@dataclass(frozen=True)
class Stimulus:
    """One rendered condition."""

    expression: str
    """One of :data:`EXPRESSIONS` or ``"neutral"``."""
    head: str
    """Head name (``"builtin"``, ``"ict"``)."""
    identity: str
    """Identity preset of the head."""
    basis: str
    """Expression basis: ``"facs"`` or ``"feature_points"``."""
    view: str
    """A key of :data:`VIEWS`."""
    intensity: float
    """Emotion intensity (the study: 1.2 and 2.4; 0 for neutral)."""


@dataclass(frozen=True)
class StimulusScore:
    """What the detector said about one stimulus."""

    stimulus: Stimulus
    """The condition."""
    emotions: tuple[float, ...]
    """Probabilities over :data:`~mien.validate.detector.EMOTION_LABELS`."""
    face_found: bool
    """True when the landmarker found the face itself (False: the crop came from the rig's landmarks)."""
    aus: dict[str, float] = field(default_factory=dict)
    """Detected AU intensities (``"AU9"`` -> 0..5) when the detector gives blendshapes."""
    nose_lip_mm: float = float("nan")
    """Nose-base to upper-lip-top distance on the rendered mesh, millimetres (iBUG 33 -> 51)."""
    landmark_aus: dict[str, float] = field(default_factory=dict)
    """AU9 and AU10 (0..5) measured on the rendered mesh's landmarks (:mod:`mien.validate.landmark_aus`); the FACS
    reading takes AU9 from here, as the detector cannot see it."""
    facs_top: str | None = None
    """The FACS reading: the emotion whose EMFACS prototype best matches the AUs detected above the same
    setup's neutral (see the module docstring); None without blendshapes, for neutral, or when nothing moved."""
    other_framings: dict[str, tuple[float, ...]] = field(default_factory=dict)
    """The classifier's probabilities on the same render cropped in its other framings
    (:data:`~mien.validate.emotion_classifier.FRAMINGS`), keyed by framing; empty for other detectors."""

    def _probabilities(self, framing: str | None) -> tuple[float, ...]:
        if framing is None:
            return self.emotions
        return self.other_framings.get(framing, ())

    @property
    def top(self) -> str:
        """Top label."""
        return EMOTION_LABELS[int(np.argmax(self.emotions))]

    @property
    def top2(self) -> tuple[str, str]:
        """The two top labels, most probable first."""
        order = np.argsort(self.emotions)[::-1]
        return EMOTION_LABELS[int(order[0])], EMOTION_LABELS[int(order[1])]

    def correct(self, framing: str | None = None) -> bool | None:
        """Recognised? (top label for basics and neutral; top two for blends); None if not judgeable.

        ``framing``: judge the probabilities of that other crop framing (:attr:`other_framings`) instead; None
        when it was not measured.
        """
        probabilities = self._probabilities(framing)
        if len(probabilities) != len(EMOTION_LABELS) or not np.all(np.isfinite(probabilities)):
            return None if framing is not None else self._correct_labels(self.top, self.top2)
        order = np.argsort(probabilities)[::-1]
        first, second = EMOTION_LABELS[int(order[0])], EMOTION_LABELS[int(order[1])]
        return self._correct_labels(first, (first, second))

    def _correct_labels(self, top: str, top2: tuple[str, str]) -> bool:
        name = self.stimulus.expression
        if name in BLEND_COMPONENTS:
            return set(top2) == {LABEL_OF[c] for c in BLEND_COMPONENTS[name]}
        return top == LABEL_OF[name]


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
    from mien.character import Character

    character = Character(seed=0, idle=False, expression_basis=basis)
    if expression != "neutral":
        character.emote(expression, intensity, start_s=0.0)
    frame = character.step(PEAK_TIME_S).copy()
    features = character.feature_weights.copy() if basis == "feature_points" else None
    return frame, features


def _camera(view: str) -> Any:
    return VIEWS[view].camera


@dataclass(frozen=True, eq=False)
class RecognitionResult:
    """Scores of every stimulus, with the images that were judged."""

    scores: tuple[StimulusScore, ...]
    """One per stimulus, in the order rendered."""
    detector: str
    """The detector's name."""
    timings_s: dict[str, float]
    """Seconds spent per stage (``render``, ``detect``, ``load``)."""
    images: dict[int, np.ndarray] = field(default_factory=dict, repr=False)
    """Index into :attr:`scores` -> the (s, s, 3) uint8 colour crop the classifier judged (kept when asked)."""
    framing: str = "landmarks"
    """The crop framing of :attr:`StimulusScore.emotions` (the others are in
    :attr:`StimulusScore.other_framings`)."""

    def subset(self, **conditions: Any) -> list[StimulusScore]:
        """Scores whose stimulus matches every ``field=value`` (a value may be a tuple of allowed values)."""
        out = []
        for score in self.scores:
            ok = True
            for key, wanted in conditions.items():
                value = getattr(score.stimulus, key)
                ok &= value in wanted if isinstance(wanted, tuple) else value == wanted
            if ok:
                out.append(score)
        return out

    def rate(self, **conditions: Any) -> float:
        """Share of matching stimuli recognised (nan when none match)."""
        judged = [float(j) for j in (s.correct() for s in self.subset(**conditions)) if j is not None]
        return float(np.mean(judged)) if judged else float("nan")

    def framed_rate(self, framing: str, **conditions: Any) -> float:
        """:meth:`rate` with the classifier's crop in ``framing`` (nan when that framing was not measured)."""
        if framing == self.framing:
            return self.rate(**conditions)
        judged = [float(j) for j in (s.correct(framing) for s in self.subset(**conditions)) if j is not None]
        return float(np.mean(judged)) if judged else float("nan")

    @property
    def framings(self) -> tuple[str, ...]:
        """Every crop framing measured: :attr:`framing` first, then the others."""
        others = {name for score in self.scores for name in score.other_framings}
        return (self.framing, *sorted(others - {self.framing}))

    def framing_summary(self) -> dict[str, dict[str, float]]:
        """``{framing: {"frontal": .., "oblique": .., "neutral": ..}}``: the five basic emotions recognised frontally
        and at 45 degrees, and neutral read as neutral, with the classifier's crop in each measured framing."""
        basics = ("joy", "sadness", "anger", "surprise", "fear")
        views = {
            "frontal": tuple(v for v in VIEWS if v.startswith("frontal")),
            "oblique": tuple(v for v in VIEWS if v.startswith("oblique")),
        }
        return {
            framing: {
                **{name: self.framed_rate(framing, expression=basics, view=v) for name, v in views.items()},
                "neutral": self.framed_rate(framing, expression="neutral"),
            }
            for framing in self.framings
        }

    def label_rate(self, label: str, **conditions: Any) -> float:
        """Share of matching stimuli whose top classifier label is ``label`` (``"angry"``...); nan when none match."""
        scores = self.subset(**conditions)
        return float(np.mean([s.top == label for s in scores])) if scores else float("nan")

    def landmark_au(self, au: str, **conditions: Any) -> float:
        """Mean landmark estimate of ``au`` (``"AU9"``, ``"AU10"``; 0..5) over matching stimuli; nan when none."""
        values = [s.landmark_aus[au] for s in self.subset(**conditions) if au in s.landmark_aus]
        return float(np.mean(values)) if values else float("nan")

    def disgust_signs(self) -> dict[str, dict[str, dict[str, float]]]:
        """``{basis: {"disgust" | "anger": {"AU9": mean, "AU10": mean}}}``: disgust's nose wrinkle and upper-lip
        raise on the mesh's landmarks next to anger's (:meth:`landmark_au`), for each basis that has disgust."""
        return {
            basis: {
                name: {au: self.landmark_au(au, expression=name, basis=basis) for au in ("AU9", "AU10")}
                for name in ("disgust", "anger")
            }
            for basis in ("facs", "feature_points")
            if self.subset(expression="disgust", basis=basis)
        }

    def facs_rate(self, read_as: str | None = None, **conditions: Any) -> float:
        """Share of matching stimuli whose FACS reading is ``read_as`` (default: each one's own expression; a
        blend counts when the reading is one of its components); nan when none has a reading."""
        judged = []
        for score in self.subset(**conditions):
            if score.facs_top is None:
                continue
            name = score.stimulus.expression
            wanted = {read_as} if read_as is not None else set(BLEND_COMPONENTS.get(name, (name,)))
            judged.append(score.facs_top in wanted)
        return float(np.mean(judged)) if judged else float("nan")

    def quality(self, expression: str, **conditions: Any) -> float:
        """Machine quality (mean probability of the target label) of a basic emotion; nan for blends."""
        if expression not in LABEL_OF:
            return float("nan")
        column = EMOTION_LABELS.index(LABEL_OF[expression])
        scores = self.subset(expression=expression, **conditions)
        return float(np.mean([s.emotions[column] for s in scores])) if scores else float("nan")

    def confusion(self, **conditions: Any) -> tuple[list[str], np.ndarray]:
        """(row expressions, (n_expressions, 7) counts of top labels over EMOTION_LABELS)."""
        rows = [e for e in ("neutral", *EXPRESSIONS) if self.subset(expression=e, **conditions)]
        matrix = np.zeros((len(rows), len(EMOTION_LABELS)), np.int64)
        for r, name in enumerate(rows):
            for score in self.subset(expression=name, **conditions):
                matrix[r, EMOTION_LABELS.index(score.top)] += 1
        return rows, matrix

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready summary: per-stimulus scores, rates, quality next to the human values, the targets per head
        (:mod:`mien.validate.targets`), timings."""
        from mien.validate.targets import check_targets

        rows, matrix = self.confusion()
        return {
            "detector": self.detector,
            "framing": self.framing,
            "labels": list(EMOTION_LABELS),
            "stimuli": [
                {
                    **vars(s.stimulus),
                    "emotions": [round(float(p), 4) for p in s.emotions],
                    "top": s.top,
                    "correct": s.correct(),
                    "face_found": s.face_found,
                    "aus": {k: round(v, 3) for k, v in s.aus.items()},
                    "nose_lip_mm": None if not np.isfinite(s.nose_lip_mm) else round(s.nose_lip_mm, 3),
                    "landmark_aus": {k: round(v, 3) for k, v in s.landmark_aus.items()},
                    "facs_top": s.facs_top,
                    "other_framings": {k: [round(float(p), 4) for p in v] for k, v in s.other_framings.items()},
                }
                for s in self.scores
            ],
            "recognition": {e: self.rate(expression=e) for e in ("neutral", *EXPRESSIONS)},
            "recognition_by_framing": {
                framing: {e: self.framed_rate(framing, expression=e) for e in ("neutral", *EXPRESSIONS)}
                for framing in self.framings
            },
            "quality": {e: {"machine": self.quality(e), "human": HUMAN_QUALITY.get(e)} for e in EXPRESSIONS},
            "facs_reading": {e: self.facs_rate(expression=e) for e in EXPRESSIONS},
            "confusion": {"rows": rows, "matrix": matrix.tolist()},
            "targets": [
                {
                    "head": c.head,
                    "target": c.target.name,
                    "rule": c.target.rule,
                    "hits": c.hits,
                    "n": c.n,
                    "value": c.value,
                    "interval95": list(c.interval),
                    "met": c.met,
                    "decided": c.decided,
                }
                for c in check_targets(self)
            ],
            "timings_s": self.timings_s,
        }

    def write_json(self, path: str | Path) -> Path:
        """Write :meth:`to_json` to ``path`` (atomically: a temporary name renamed at the end)."""
        target = Path(path)
        partial = target.with_name(target.name + ".partial")
        partial.write_text(json.dumps(self.to_json(), indent=1, default=_json_default), encoding="utf-8")
        partial.replace(target)
        return target


def _json_default(value: object) -> object:
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


READING_VARIANTS: dict[str, tuple[tuple[str, str], ...]] = {"disgust": (("AU9", "AU10"),)}
"""Emotion -> AU pairs whose intensities :func:`facs_reading` also tries swapped in that emotion's prototype.

EMFACS lists disgust led by the nose wrinkle and by the upper-lip raise alike (9+17 and 10+17; 9+16+15/26 and
10+16+25/26: Ekman, Friesen & Hager 2002, Table 10-1). The v2 prototype renders the AU10-led form with a trace of
AU9 (its AU9-led draft bared the teeth in a snarl read as anger), so the reading also matches the AU9-led form:
Table 1's disgust wrinkles the nose hard (landmark AU9 4.0 at intensity 1.2) and is disgust to a FACS coder."""


@cache
def _reading_templates(aus: tuple[int, ...]) -> tuple[tuple[str, ...], np.ndarray]:
    """(emotion of each row, (rows, len(aus)) prototype intensities): each EMFACS prototype, then its variants
    (built once per AU list; the array is read-only)."""
    from mien.facs.prototypes import EMFACS_PROTOTYPES

    names: list[str] = []
    rows: list[list[float]] = []
    for name, prototype in EMFACS_PROTOTYPES.items():
        variants = [dict(prototype)]
        for a, b in READING_VARIANTS.get(name, ()):
            variants.append(prototype | {a: prototype.get(b, 0.0), b: prototype.get(a, 0.0)})
        for variant in variants:
            names.append(name)
            rows.append([variant.get(f"AU{code}", 0.0) for code in aus])
    table = np.array(rows)
    table.setflags(write=False)
    return tuple(names), table


def facs_reading(detected: np.ndarray, neutral: np.ndarray, aus: Sequence[int]) -> str | None:
    """The emotion whose EMFACS prototype best matches AUs ``detected`` above ``neutral`` (cosine similarity).

    ``detected`` / ``neutral``: (len(aus),) AU intensities 0..5 of the face and of the same setup's neutral, over
    AU numbers ``aus``. An emotion's prototype may also match in the variant forms of :data:`READING_VARIANTS`.
    None when nothing rose above the neutral (by more than 0.05 in total).

    >>> aus = (1, 2, 4, 5, 9, 10, 15, 17, 26)
    >>> face = np.array([0, 0, 0, 0, 1.0, 3.5, 2.5, 3.0, 0])
    >>> facs_reading(face, np.zeros(9), aus)
    'disgust'
    >>> facs_reading(np.array([0, 0, 0.7, 0, 4.0, 0.7, 0, 0, 1.6]), np.zeros(9), aus)  # nose wrinkled hard
    'disgust'
    """
    rise = np.clip(np.asarray(detected, np.float64) - np.asarray(neutral, np.float64), 0.0, None)
    if rise.sum() <= 0.05:
        return None
    names, table = _reading_templates(tuple(int(code) for code in aus))
    norms = np.linalg.norm(table, axis=1) * np.linalg.norm(rise)
    cosine = table @ rise / np.where(norms > 0, norms, 1.0)
    return names[int(np.argmax(cosine))]


def _with_facs_readings(scores: Sequence[StimulusScore], aus: Sequence[int]) -> tuple[StimulusScore, ...]:
    """``scores`` with :attr:`StimulusScore.facs_top` set against each setup's neutral (zeros where none)."""
    from dataclasses import replace

    from mien.validate.landmark_aus import merged_aus

    def vector(score: StimulusScore) -> np.ndarray:
        seen = merged_aus(score.aus, score.landmark_aus)
        return np.array([seen.get(f"AU{code}", 0.0) for code in aus])

    def setup(score: StimulusScore) -> tuple[str, str, str, str]:
        s = score.stimulus
        return s.head, s.identity, s.basis, s.view

    neutrals = {setup(s): vector(s) for s in scores if s.stimulus.expression == "neutral" and s.aus}
    out = []
    for score in scores:
        if score.stimulus.expression == "neutral" or not score.aus:
            out.append(score)
            continue
        base = neutrals.get(setup(score), np.zeros(len(aus)))
        out.append(replace(score, facs_top=facs_reading(vector(score), base, aus)))
    return tuple(out)


def _judged_crop(rgb: np.ndarray, landmarks: np.ndarray, framing: str, side: int = 160) -> np.ndarray:
    """The colour version of the square the classifier saw (cropped with ``framing``), ``side`` pixels wide."""
    from PIL import Image

    from mien.validate.emotion_classifier import crop_square, face_box

    patch = crop_square(rgb, face_box(landmarks, framing))
    return np.asarray(Image.fromarray(patch).resize((side, side), Image.Resampling.BILINEAR))


def run_recognition(
    stimuli: Sequence[Stimulus],
    detector: Detector | None = None,
    size: tuple[int, int] = (512, 512),
    keep_images: bool = False,
    progress: bool = True,
) -> RecognitionResult:
    """Render and classify every stimulus (grouped by head, basis and view so each setup is built once)."""
    from mien.progress import progress as progress_bar
    from mien.rig.au_solve import AUSolver
    from mien.rig.heads import load_head
    from mien.validate.emotion_classifier import FRAMINGS
    from mien.validate.face_detector import FaceDetector
    from mien.validate.landmark_aus import LandmarkAUs
    from mien.validate.stimuli import StimulusRenderer

    own = detector is None
    active: Detector = FaceDetector() if detector is None else detector
    framing = str(getattr(active, "framing", "landmarks"))
    classifier = _framed_classifier(active)
    timings = {"load": 0.0, "render": 0.0, "detect": 0.0}
    solver = AUSolver()  # the 18 OpenFACS AUs: AU9/AU10 for disgust's signs, all of them for the FACS reading
    scores: list[StimulusScore | None] = [None] * len(stimuli)
    images: dict[int, np.ndarray] = {}
    groups: dict[tuple[str, str, str, str], list[int]] = {}
    for index, stimulus in enumerate(stimuli):
        groups.setdefault((stimulus.head, stimulus.identity, stimulus.basis, stimulus.view), []).append(index)
    bar = progress_bar(range(len(stimuli)), total=len(stimuli), desc="recognition", enabled=progress)
    ticker = iter(bar)
    rigs: dict[tuple[str, str, bool], Any] = {}
    estimators: dict[tuple[str, str, bool], LandmarkAUs] = {}
    try:
        for (head, identity, basis, view), indices in groups.items():
            started = time.perf_counter()
            key = (head, identity, basis == "feature_points")
            if key not in rigs:
                rigs[key] = load_head(head, identity, feature_points=key[2])
            rig = rigs[key]
            timings["load"] += time.perf_counter() - started
            with StimulusRenderer(rig, _camera(view), size) as renderer:
                if key not in estimators:
                    started = time.perf_counter()
                    estimators[key] = LandmarkAUs(rig, renderer.weights)
                    timings["load"] += time.perf_counter() - started
                landmark_aus = estimators[key]
                for index in indices:
                    stimulus = stimuli[index]
                    started = time.perf_counter()
                    frame, features = peak_face(stimulus.expression, stimulus.intensity, basis)
                    weights = renderer.weights(frame, features)
                    rgb, hint = renderer.render_weights(weights)
                    deformed = renderer.last_vertices
                    nose_lip = float(np.linalg.norm(deformed[rig.landmarks[33]] - deformed[rig.landmarks[51]])) * 1e3
                    timings["render"] += time.perf_counter() - started
                    started = time.perf_counter()
                    found = active.detect(rgb, hint)
                    others = {}
                    if classifier is not None and found.landmarks is not None:
                        for name in FRAMINGS:
                            if name != framing:
                                probabilities = classifier.classify(rgb, found.landmarks, name)
                                others[name] = tuple(float(p) for p in probabilities)
                    timings["detect"] += time.perf_counter() - started
                    emotions = found.emotions if found.emotions is not None else np.full(len(EMOTION_LABELS), np.nan)
                    aus: dict[str, float] = {}
                    if found.blendshapes is not None:
                        values = solver.solve(found.blendshapes)
                        aus = {f"AU{code}": float(v) for code, v in zip(solver.aus, values, strict=True)}
                    scores[index] = StimulusScore(
                        stimulus,
                        tuple(float(p) for p in emotions),
                        bool(found.found and not found.landmarks_from_hint),
                        aus,
                        nose_lip,
                        landmark_aus.estimate(deformed),
                        other_framings=others,
                    )
                    if keep_images and found.landmarks is not None:
                        images[index] = _judged_crop(rgb, found.landmarks, framing)
                    next(ticker, None)
    finally:
        if own:
            active.close()
    for _ in ticker:
        pass
    done = _with_facs_readings([s for s in scores if s is not None], solver.aus)
    return RecognitionResult(done, active.name, {k: round(v, 3) for k, v in timings.items()}, images, framing)


def _framed_classifier(detector: Any) -> Any:
    """The FER classifier inside ``detector`` (a :class:`~mien.validate.face_detector.FaceDetector` or
    :class:`~mien.validate.face_detector.EmotionDetector`), to judge each render in the other framings too; None
    for other detectors."""
    emotion = getattr(detector, "emotion", detector)
    return getattr(emotion, "classifier", None)


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
    from mien.render.contact_sheet import contact_sheet
    from mien.render.video import write_png
    from mien.validate.figures import plot_confusion, plot_quality

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
        name = f"sheet_{head}_{identity}_{basis}_{view}.png"
        columns = 1 + len({result.scores[i].stimulus.intensity for i in shown if result.scores[i].stimulus.intensity})
        sheet = contact_sheet(
            [result.images[i] for i in shown],
            [_sheet_label(result.scores[i]) for i in shown],
            columns=max(columns, 2) * 3 + 1,
            font_size=12,
        )
        partial = out / f".{name}.partial.png"
        write_png(sheet, partial)
        written[name] = partial.replace(out / name)
    for name, draw in (("confusion.png", plot_confusion), ("quality.png", plot_quality)):
        partial = out / f".{name}.partial.png"
        draw(result, partial)
        written[name] = partial.replace(out / name)
    written["recognition.json"] = result.write_json(out / "recognition.json")
    return written
