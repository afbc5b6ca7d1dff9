"""PAD (pleasure, arousal, dominance) factor space and its mapping to basic-emotion intensities.

Broekens et al.: "If the model is configured to use factor-based emotions then the emotion intensities are
based on the distance to the emotion prototypes in factor space." The prototype coordinates are in
``data/pad_prototypes.csv`` (Russell & Mehrabian 1977; anger and fear also as in Gebhard's ALMA 2005).

mien's mapping (:func:`pad_to_emotions`) splits a state ``s`` into *which* emotion (its direction) and *how
much* (its length)::

    d_e         = || s / |s|  -  p_e / |p_e| ||          chord distance of the directions, 0..2
    intensity_e = (|s| / |p_e|) * max(0, 1 - d_e / radius)

so the state at a prototype gives that emotion intensity exactly 1, the origin (neutral) gives all zeros,
scaling the state scales every intensity by the same factor (Broekens' geometric intensity), and an emotion
whose prototype direction is ``radius`` or farther away (default 0.75, about 44 degrees) gets 0. Anger and
disgust lie close in PAD space (22 degrees apart), so a state at either also carries some of the other.
"""

from __future__ import annotations

import math

import numpy as np

from mien.affect.emotions import EMOTIONS
from mien.errors import InvalidValueError
from mien.fileio.tables import read_table

__all__ = [
    "PAD_FACTORS",
    "PAD_PROTOTYPES",
    "PAD_RADIUS",
    "PAD_SOURCES",
    "check_pad",
    "pad_intensities",
    "pad_to_emotions",
]

PAD_FACTORS: tuple[str, ...] = ("pleasure", "arousal", "dominance")
"""The three factors, in the order of every (3,) PAD vector."""

PAD_RADIUS: float = 0.75
"""Default reach of a prototype: chord distance between unit directions (0..2) where intensity falls to 0."""


def _load() -> tuple[np.ndarray, tuple[str, ...]]:
    rows = {r["emotion"]: r for r in read_table("mien.affect", "data/pad_prototypes.csv")}
    table = np.array([[float(rows[e][f]) for f in PAD_FACTORS] for e in EMOTIONS])
    table.setflags(write=False)
    return table, tuple(rows[e]["source"] for e in EMOTIONS)


PAD_PROTOTYPES, PAD_SOURCES = _load()
"""(6, 3) read-only PAD coordinates of the emotions in EMOTIONS order, and the source of each row."""

# Plain-float copies for the per-frame path (no numpy call overhead for a 3-vector).
_UNIT = tuple(tuple(float(v) / float(np.linalg.norm(row)) for v in row) for row in PAD_PROTOTYPES)
_NORM = tuple(float(np.linalg.norm(row)) for row in PAD_PROTOTYPES)


def check_pad(pleasure: object, arousal: object, dominance: object) -> tuple[float, float, float]:
    """The three factors as floats, or :class:`~mien.errors.InvalidValueError` naming the bad factor.

    Each must be finite and in [-1, 1].
    """
    out = []
    for name, value in zip(PAD_FACTORS, (pleasure, arousal, dominance), strict=True):
        try:
            v = float(value)  # type: ignore[arg-type]
        except (TypeError, ValueError):
            raise InvalidValueError(name, value, "a number in [-1, 1]") from None
        if not (-1.0 <= v <= 1.0):  # also false for NaN
            raise InvalidValueError(name, value, "a number in [-1, 1]")
        out.append(v)
    return out[0], out[1], out[2]


def pad_intensities(pleasure: float, arousal: float, dominance: float, radius: float = PAD_RADIUS) -> list[float]:
    """Unvalidated fast form of :func:`pad_to_emotions` on plain floats: 6 intensities as a list."""
    length = math.sqrt(pleasure * pleasure + arousal * arousal + dominance * dominance)
    if length == 0.0:
        return [0.0] * 6
    p, a, d = pleasure / length, arousal / length, dominance / length
    out = []
    for (up, ua, ud), norm in zip(_UNIT, _NORM, strict=True):
        dist = math.sqrt((p - up) ** 2 + (a - ua) ** 2 + (d - ud) ** 2)
        out.append(length / norm * (1.0 - dist / radius) if dist < radius else 0.0)
    return out


def pad_to_emotions(pad: object, *, radius: float = PAD_RADIUS) -> np.ndarray:
    """(6,) emotion intensities (EMOTIONS order) of a PAD state ``pad`` (3,), each factor in [-1, 1].

    See the module docstring for the formula. ``radius`` is the chord distance (0, 2] at which an emotion's
    intensity reaches 0. Bad factors raise :class:`~mien.errors.InvalidValueError` naming the factor.

    >>> pad_to_emotions([0.81, 0.51, 0.46]).round(2).tolist()   # the joy prototype
    [1.0, 0.0, 0.0, 0.01, 0.0, 0.0]
    >>> pad_to_emotions([0.0, 0.0, 0.0]).tolist()
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    """
    try:
        values = np.asarray(pad, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise InvalidValueError("pad", pad, "three factors (pleasure, arousal, dominance)") from None
    if values.shape != (3,):
        raise InvalidValueError("pad", pad, "three factors (pleasure, arousal, dominance)")
    r = float(radius)
    if not (0.0 < r <= 2.0):
        raise InvalidValueError("radius", radius, "a number in (0, 2]")
    return np.array(pad_intensities(*check_pad(*values.tolist()), radius=r))
