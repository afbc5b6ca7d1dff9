"""What the judges are asked: the study's expressions, the classifier label naming each, and the people's answers.

The expressions themselves are :mod:`mien.affect.emotions`' (the ten of the Broekens study, the five held to the
recognition targets, each blend's components, the user's blends too); this module adds only what validation needs
on top: which of the classifier's labels (:data:`~mien.validate.detector.EMOTION_LABELS`) names an expression, and
the quality the study's people reached (Table 4).

>>> expected_labels("furious")
('angry', 'surprise')
>>> expected_labels("joy")
('happy',)
"""

from __future__ import annotations

from mien.affect.emotions import RECOGNISED_FIVE, STUDY_EXPRESSIONS, blend_emotions
from mien.errors import UnknownNameError
from mien.fileio.tables import read_table

__all__ = ["BASICS", "EXPRESSIONS", "HUMAN_QUALITY", "LABEL_OF", "blend_components", "expected_labels"]

EXPRESSIONS: tuple[str, ...] = STUDY_EXPRESSIONS
"""The ten expressions of the Broekens study: six basic emotions, then the four blends."""

BASICS: tuple[str, ...] = RECOGNISED_FIVE
"""The five basic emotions the classifier's targets are on (disgust has its own: the FACS reading)."""

LABEL_OF: dict[str, str] = {
    "joy": "happy",
    "sadness": "sad",
    "anger": "angry",
    "surprise": "surprise",
    "disgust": "disgust",
    "fear": "fear",
    "neutral": "neutral",
}
"""Expression -> the classifier label that names it (the six basic emotions and neutral)."""


def blend_components(name: str) -> tuple[str, ...] | None:
    """The basic emotions of the blend ``name`` (the study's or one a user defined), or None when ``name`` is a
    basic emotion, neutral or not an expression at all.

    >>> blend_components("evil"), blend_components("joy")
    (('joy', 'anger'), None)
    """
    if name in LABEL_OF:
        return None
    try:
        return blend_emotions(name)
    except UnknownNameError:
        return None


def expected_labels(name: str) -> tuple[str, ...] | None:
    """The classifier labels that recognise ``name``: its own label, or a blend's components' labels (the top two
    must be these); None when the classifier has no label for it."""
    if name in LABEL_OF:
        return (LABEL_OF[name],)
    components = blend_components(name)
    return None if components is None else tuple(LABEL_OF[c] for c in components)


def _paper_quality() -> dict[str, float]:
    rows = read_table("mien.affect", "data/broekens_table4.csv")
    return {row["expression"]: float(row["quality"]) for row in rows}


HUMAN_QUALITY: dict[str, float] = _paper_quality()
"""Broekens et al.'s Table 4: recognition quality by the study's 19 participants (ten labels), read from
``mien/affect/data/broekens_table4.csv`` (the one copy; :func:`mien.study.quality.paper_table4` reads it too)."""
