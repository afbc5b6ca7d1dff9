"""What a participant answers and in which order: the questions of each protocol, the per-participant label
order, and the stimulus sequence (within-subject blocks in a balanced Latin square over participants).

Broekens, Qu & Brinkman: per stimulus, ten emotion labels on 5-point scales (1..5) in an on-screen order
random between subjects, then naturalness (1..5). Mascaró et al.: "Does the motion feel right?" and "Does
the motion represent the description?" (0..5). Every order is seeded by the study and participant id, so a
participant who comes back gets the same plan even if the database were lost.
"""

from __future__ import annotations

import hashlib
import random
from dataclasses import dataclass
from typing import TYPE_CHECKING

from mien.affect.emotions import STUDY_EXPRESSIONS

if TYPE_CHECKING:
    from mien.study.design import Design

__all__ = [
    "BROEKENS_LABELS",
    "Plan",
    "Question",
    "balanced_latin_square",
    "participant_plan",
    "questions",
]

_SHOWN_LABEL: dict[str, str] = {
    "joy": "joyful",
    "sadness": "sad",
    "anger": "angry",
    "surprise": "surprised",
    "disgust": "disgusted",
    "fear": "afraid",
}
"""Basic emotion -> the adjective the participants rated (a blend is shown by its own name)."""

BROEKENS_LABELS: tuple[tuple[str, str], ...] = tuple((name, _SHOWN_LABEL.get(name, name)) for name in STUDY_EXPRESSIONS)
"""(name as in :mod:`mien.affect.emotions`, label shown) of the ten rated emotions: the study's six basic
emotions and four blends (Broekens et al., section 3: joy, sad, angry, surprised, disgusted, afraid,
enthusiastic, furious, frustrated, evil)."""


@dataclass(frozen=True)
class Question:
    """One rating asked per stimulus."""

    key: str
    """Stored question name: ``"label:joy"``..., ``"naturalness"``, ``"feels_right"``, ``"represents_description"``."""
    text: str
    """What the page shows."""
    low: int
    """Smallest rating (1 Broekens, 0 Mascaró)."""
    high: int
    """Largest rating (5)."""
    low_text: str
    """Anchor of the smallest rating."""
    high_text: str
    """Anchor of the largest rating."""
    is_label: bool = False
    """True for the ten emotion labels (shown in the participant's random order)."""


def questions(protocol: str) -> tuple[Question, ...]:
    """The questions of ``protocol`` in their canonical order (labels first for Broekens).

    >>> [q.key for q in questions("mascaro")]
    ['feels_right', 'represents_description']
    >>> len(questions("broekens"))
    11
    """
    if protocol == "mascaro":
        return (
            Question("feels_right", "Does the motion feel right?", 0, 5, "not at all", "completely"),
            Question(
                "represents_description", "Does the motion represent the description?", 0, 5, "not at all", "completely"
            ),
        )
    labels = tuple(
        Question(f"label:{name}", shown, 1, 5, "not at all", "very", is_label=True) for name, shown in BROEKENS_LABELS
    )
    return (*labels, Question("naturalness", "How natural is the expression?", 1, 5, "not natural", "very natural"))


def balanced_latin_square(n: int, row: int) -> tuple[int, ...]:
    """Row ``row`` of a balanced (Williams) Latin square over ``n`` conditions: each condition appears once
    per position and follows every other condition equally often over ``n`` rows (``2n`` when ``n`` is odd).

    >>> [balanced_latin_square(4, r) for r in range(4)]
    [(0, 1, 3, 2), (1, 2, 0, 3), (2, 3, 1, 0), (3, 0, 2, 1)]
    """
    sequence, low, high = [], 0, 0
    for i in range(n):
        if i < 2 or i % 2:
            value, low = low, low + 1
        else:
            value, high = n - high - 1, high + 1
        sequence.append((value + row) % n)
    if n % 2 and (row // n) % 2:
        sequence.reverse()
    return tuple(sequence)


@dataclass(frozen=True)
class Plan:
    """One participant's orders (stored when they first arrive)."""

    sequence: tuple[str, ...]
    """Stimulus ids in presentation order (position 0 first)."""
    label_order: tuple[str, ...]
    """Question keys in on-screen order (labels shuffled, then the other questions)."""
    block_order: tuple[int, ...]
    """Indices of the within-subject blocks (distinct within-factor level combinations, in design order) in
    the order shown."""
    between: tuple[tuple[str, object], ...]
    """(factor, level) of the between-subject factors this participant was assigned."""


def _rng(study: str, participant: str) -> random.Random:
    digest = hashlib.sha256(f"{study}\0{participant}".encode()).digest()
    return random.Random(int.from_bytes(digest[:8], "big"))


def participant_plan(design: Design, participant: str, ordinal: int) -> Plan:
    """The plan of ``participant``, the ``ordinal``-th (0-based) participant of the study.

    Multi-level factors not in ``design.within`` are between-subject: participant ``ordinal`` gets level
    combination ``ordinal % n``. Within-subject blocks follow row ``ordinal // n`` of the balanced Latin
    square (``order = "counterbalanced"``), a seeded shuffle (``"random"``) or the design order
    (``"fixed"``); stimuli inside a block and the emotion labels are shuffled with a seed from the study and
    participant id.
    """
    rng = _rng(design.name, participant)
    asked = questions(design.protocol)
    labels = [q.key for q in asked if q.is_label]
    rng.shuffle(labels)
    label_order = (*labels, *(q.key for q in asked if not q.is_label))
    factors = design.factors if design.protocol == "broekens" else ()
    within = [f for f in factors if f in design.within]
    between = [f for f in factors if f not in design.within and len(design.levels(f)) > 1]
    combos: dict[tuple, None] = {}
    for spec in design.stimuli:
        combos.setdefault(tuple(spec.conditions.get(f) for f in between), None)
    between_levels = list(combos)[ordinal % len(combos)] if combos else ()
    chosen = [s for s in design.stimuli if tuple(s.conditions.get(f) for f in between) == tuple(between_levels)]
    blocks: dict[tuple, list[str]] = {}
    for spec in chosen:
        blocks.setdefault(tuple(spec.conditions.get(f) for f in within), []).append(spec.id)
    n = len(blocks)
    if design.order == "counterbalanced":
        block_order = balanced_latin_square(n, ordinal // max(1, len(combos)))
    elif design.order == "random":
        block_order = tuple(rng.sample(range(n), n))
    else:
        block_order = tuple(range(n))
    block_lists = list(blocks.values())
    sequence: list[str] = []
    for index in block_order:
        ids = list(block_lists[index])
        rng.shuffle(ids)
        sequence.extend(ids)
    return Plan(tuple(sequence), label_order, block_order, tuple(zip(between, between_levels, strict=True)))
