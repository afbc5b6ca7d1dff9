"""Recognition results: each rendered condition, what the detector said about it, and the rates over them.

A :class:`RecognitionResult` holds one :class:`StimulusScore` per :class:`Stimulus` (made by
:func:`mien.validate.recognition.run_recognition`, or by :mod:`mien.study.machine` from a study's videos) and
answers the questions of the report: recognition rate (top label; a blend's top label one of its components'), the
spread of each rate across the averaged judge's crops,
confusion, Broekens' quality, the FACS reading's verdicts, the targets per head (:mod:`mien.validate.targets`).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.validate.detector import EMOTION_LABELS
from mien.validate.expressions import BASICS, EXPRESSIONS, HUMAN_QUALITY, LABEL_OF, blend_components, expected_labels
from mien.validate.judge import framing_of
from mien.validate.targets import FRONTAL, OBLIQUE, check_targets

__all__ = ["RecognitionResult", "Stimulus", "StimulusScore"]


@dataclass(frozen=True)
class Stimulus:
    """One rendered condition."""

    expression: str
    """One of :data:`~mien.validate.expressions.EXPRESSIONS` or ``"neutral"``."""
    head: str
    """Head name (``"builtin"``, ``"ict"``)."""
    identity: str
    """Identity preset of the head."""
    basis: str
    """Expression basis: ``"facs"`` or ``"feature_points"``."""
    view: str
    """A key of :data:`~mien.render.camera.VIEWS`."""
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
    crops: dict[str, tuple[float, ...]] = field(default_factory=dict)
    """Every reading of the averaged judge (:mod:`mien.validate.judge`): reading name (``"fer up-left wide @384"``)
    -> the classifier's probabilities on that crop; :attr:`emotions` is their mean. Empty for other detectors."""

    def probabilities(self, framing: str | None = None, reading: str | None = None) -> tuple[float, ...]:
        """The probabilities judged: :attr:`emotions`; with ``reading`` that one crop's; with ``framing`` the mean
        of that framing's readings (:func:`~mien.validate.judge.framing_of`); ``()`` when not measured."""
        if reading is not None:
            return self.crops.get(reading, ())
        if framing is not None:
            rows = [p for name, p in self.crops.items() if framing_of(name) == framing]
            return tuple(float(v) for v in np.mean(rows, axis=0)) if rows else ()
        return self.emotions

    @property
    def top(self) -> str:
        """Top label."""
        return EMOTION_LABELS[int(np.argmax(self.emotions))]

    @property
    def top2(self) -> tuple[str, str]:
        """The two top labels, most probable first."""
        order = np.argsort(self.emotions)[::-1]
        return EMOTION_LABELS[int(order[0])], EMOTION_LABELS[int(order[1])]

    def correct(self, framing: str | None = None, reading: str | None = None) -> bool | None:
        """Recognised? The top label is the expression's (a blend: one of its components'); None if not judgeable.

        ``framing`` / ``reading``: judge the probabilities of :meth:`probabilities` instead of the averaged
        verdict; None when they were not measured.
        """
        return self._judged(framing, reading, both=False)

    def both_components(self, framing: str | None = None, reading: str | None = None) -> bool | None:
        """For a blend: are its two top labels both its components' (reported beside :meth:`correct`, no bar)?
        None for anything else or when not judgeable."""
        if blend_components(self.stimulus.expression) is None:
            return None
        return self._judged(framing, reading, both=True)

    def facs_agrees(self, read_as: str | None = None) -> bool | None:
        """Is the FACS reading (:attr:`facs_top`) ``read_as`` (default: this face's own expression; a blend: one of its
        components)? None when the face has no FACS reading (a neutral face, a profile, nothing detected)."""
        if self.facs_top is None:
            return None
        name = self.stimulus.expression
        return self.facs_top in ((read_as,) if read_as is not None else (blend_components(name) or (name,)))

    def _top_two(self, framing: str | None, reading: str | None) -> tuple[str, str] | None:
        """The two top labels of :meth:`probabilities` (None when not measured), worked out once per judge: a
        scorecard asks each score about every reading of every target."""
        cache: dict[tuple[str | None, str | None], tuple[str, str] | None] = self.__dict__.setdefault("_ranked", {})
        key = (framing, reading)
        if key not in cache:
            probabilities = self.probabilities(framing, reading)
            if len(probabilities) != len(EMOTION_LABELS) or not np.all(np.isfinite(probabilities)):
                cache[key] = None
            else:
                order = np.argsort(probabilities)[::-1]
                cache[key] = EMOTION_LABELS[int(order[0])], EMOTION_LABELS[int(order[1])]
        return cache[key]

    def _judged(self, framing: str | None, reading: str | None, both: bool) -> bool | None:
        ranked = self._top_two(framing, reading)
        expected = expected_labels(self.stimulus.expression)
        if ranked is None or expected is None:
            return None  # not measured, or the classifier has no label for it (a laughter type...)
        first, second = ranked
        return {first, second} == set(expected) if both else first in expected


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
    """How :attr:`StimulusScore.emotions` was judged: ``"averaged"`` (every reading of :mod:`mien.validate.judge`),
    or the one crop framing of a detector without readings."""

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

    def rate(self, framing: str | None = None, reading: str | None = None, **conditions: Any) -> float:
        """Share of matching stimuli recognised (nan when none match); ``framing`` / ``reading``: judged by that
        framing's readings or that one reading alone (:meth:`StimulusScore.correct`)."""
        scores = self.subset(**conditions)
        judged = [float(j) for j in (s.correct(framing, reading) for s in scores) if j is not None]
        return float(np.mean(judged)) if judged else float("nan")

    def both_rate(self, reading: str | None = None, **conditions: Any) -> float:
        """Share of matching blends whose two top labels are both components (nan when none)."""
        scores = self.subset(**conditions)
        judged = [float(j) for j in (s.both_components(reading=reading) for s in scores) if j is not None]
        return float(np.mean(judged)) if judged else float("nan")

    def framed_rate(self, framing: str, **conditions: Any) -> float:
        """:meth:`rate` judged by the readings of one crop framing only (their mean), or by the verdict when
        ``framing`` is the result's :attr:`framing`; nan when that framing was not measured."""
        if framing == self.framing:
            return self.rate(**conditions)
        return self.rate(framing=framing, **conditions)

    @property
    def readings(self) -> tuple[str, ...]:
        """Every reading of the averaged judge, in the order measured (empty for other detectors)."""
        return tuple(dict.fromkeys(name for score in self.scores for name in score.crops))

    def spread(self, measure: str = "rate", **conditions: Any) -> tuple[float, float]:
        """``(lowest, highest)`` of a figure (:meth:`rate` or :meth:`both_rate`, ``measure``) judged by each reading
        alone: how far one crop could move it. ``(nan, nan)`` without readings."""
        figure = self.rate if measure == "rate" else self.both_rate
        values = [v for v in (figure(reading=name, **conditions) for name in self.readings) if v == v]
        return (min(values), max(values)) if values else (float("nan"), float("nan"))

    @property
    def framings(self) -> tuple[str, ...]:
        """Every way the figures can be judged: :attr:`framing` first, then each crop framing measured."""
        others = {framing_of(name) for name in self.readings}
        return (self.framing, *sorted(others - {self.framing}))

    def framing_summary(self) -> dict[str, dict[str, float]]:
        """``{framing: {"frontal": .., "oblique": .., "neutral": ..}}``: the five basic emotions recognised frontally
        and at 45 degrees, and neutral read as neutral, by the verdict and by each framing's readings alone."""
        views = {"frontal": FRONTAL, "oblique": OBLIQUE}
        return {
            framing: {
                **{name: self.framed_rate(framing, expression=BASICS, view=v) for name, v in views.items()},
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
        judged = [agrees for s in self.subset(**conditions) if (agrees := s.facs_agrees(read_as)) is not None]
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
                    "both_components": s.both_components(),
                    "crops": {k: [round(float(p), 4) for p in v] for k, v in s.crops.items()},
                }
                for s in self.scores
            ],
            "recognition": {e: self.rate(expression=e) for e in ("neutral", *EXPRESSIONS)},
            "recognition_spread": {e: list(self.spread(expression=e)) for e in ("neutral", *EXPRESSIONS)},
            "blends_both_components": {
                e: {"value": self.both_rate(expression=e), "spread": list(self.spread("both", expression=e))}
                for e in EXPRESSIONS
                if blend_components(e) is not None
            },
            "readings": list(self.readings),
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
                    "spread": list(c.spread),
                    "decided": c.decided,
                    "facs_reading": {"hits": c.second[0], "n": c.second[1]} if c.second[1] else None,
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
