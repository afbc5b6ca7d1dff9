"""Names shared across the laughter package: the 13 laugh/smile types and the rig controllers.

Types follow Mascaró et al. (2021) after Faigin; controllers follow the paper's Table 2 (16 names: the paper
counts 17 controllers, jaw being driven by both FP10 and FP14).
"""

from __future__ import annotations

__all__ = ["CONTROLLER_NAMES", "LAUGH_TYPES"]

LAUGH_TYPES: tuple[str, ...] = (
    "uproarious_laughter",
    "laughter",
    "smiling_open_mouthed",
    "smiling_closed_mouth",
    "stifled_smile",
    "melancholy_smile",
    "eager_laugh",
    "ingratiating_smile",
    "sly_smile",
    "debauched_smile",
    "closed_eye_smile",
    "false_smile",
    "false_laughter",
)
"""The 13 laugh and smile types, as identifiers."""

CONTROLLER_NAMES: tuple[str, ...] = (
    "rightTwich",
    "leftTwich",
    "upsetSad",
    "shocked",
    "rightBrowRaise",
    "leftBrowRaise",
    "rightBlink",
    "leftBlink",
    "smileFrown",
    "rightSmileFrown",
    "leftSmileFrown",
    "jaw",
    "sneer",
    "rightSneer",
    "leftSneer",
    "neck",
)
"""Rig controllers of the paper's Table 2, spelled as the paper spells them."""
