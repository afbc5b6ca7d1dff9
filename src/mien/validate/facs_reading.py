"""The FACS reading: a second judge that reads a face as a FACS coder would, beside the emotion classifier.

The 18 OpenFACS AUs are estimated from the detected blendshapes (AU9 from the mesh's landmarks,
:mod:`mien.validate.landmark_aus`, as the detector cannot see it), the same head, basis and view's neutral is
subtracted (clipped at 0), and the emotion whose EMFACS prototype (:mod:`mien.facs.prototypes`) has the largest
cosine similarity with what was detected is the reading. It tells disgust from anger by their signs
(AU9/AU10/AU15/AU17 against AU4/AU5/AU7/AU23 and the open mouth) where the classifier cannot.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from functools import cache

import numpy as np

from mien.facs.prototypes import EMFACS_PROTOTYPES
from mien.validate.landmark_aus import merged_aus
from mien.validate.scores import StimulusScore

__all__ = ["READING_VARIANTS", "facs_reading", "with_facs_readings"]


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


def with_facs_readings(scores: Sequence[StimulusScore], aus: Sequence[int]) -> tuple[StimulusScore, ...]:
    """``scores`` with :attr:`StimulusScore.facs_top` set against each setup's neutral (zeros where none)."""

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
