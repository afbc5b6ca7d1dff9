"""Emotion names, their aliases, and blends of emotions (Broekens, Qu & Brinkman).

Every emotion vector in :mod:`mien.affect` is ordered as :data:`EMOTIONS`. A name given by a user is
resolved case-insensitively through aliases (``"happy"`` -> ``"joy"``, ``"scared"`` -> ``"fear"``...).

Blends are linear: a blend event of intensity ``i`` adds ``i * weight`` to each component emotion.
Broekens et al. built their four blends as "50/50 linear blends" of two basic emotions. mien reads 50/50 as
*equal shares, each at the full event intensity* (weight 1.0 per component), so a blend at intensity 1
moves every feature by the sum of both prototypes. Why: the paper reports that furious and enthusiastic
read as *intense* anger and joy and that enthusiastic was "too extreme" at high intensity, which a mix at
half strength (each component weaker than the basic emotion alone) could not produce. The weights are data
on each :class:`Blend`; :func:`define_blend` makes blends with other weights (e.g. 0.5 and 0.5).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.intensity import MAX_INTENSITY, check_intensity

__all__ = [
    "BLENDS",
    "BLEND_COMPONENT_WEIGHT",
    "EMOTIONS",
    "EMOTION_ALIASES",
    "MAX_INTENSITY",
    "RECOGNISED_FIVE",
    "STUDY_EXPRESSIONS",
    "Blend",
    "blend_components",
    "blend_emotions",
    "check_intensity",
    "define_blend",
    "emotion_index",
    "emotion_vector",
    "get_blend",
    "known_names",
    "remove_blend",
    "resolve_emotion",
]

EMOTIONS: tuple[str, ...] = ("joy", "sadness", "anger", "surprise", "disgust", "fear")
"""The six basic emotions, in the order every (6,) emotion vector of mien uses."""

BLEND_COMPONENT_WEIGHT: float = 1.0
"""Weight of each component of the paper's 50/50 blends (see the module docstring for why 1.0, not 0.5)."""

EMOTION_ALIASES: dict[str, str] = {
    # joy
    "happy": "joy",
    "happiness": "joy",
    "joyful": "joy",
    "glad": "joy",
    # sadness
    "sad": "sadness",
    "sorrow": "sadness",
    "unhappy": "sadness",
    # anger
    "angry": "anger",
    "mad": "anger",
    # surprise
    "surprised": "surprise",
    # disgust
    "disgusted": "disgust",
    # fear
    "afraid": "fear",
    "fearful": "fear",
    "scared": "fear",
    "frightened": "fear",
    # blends (the paper's labels and their nouns; "naughty" is the paper's neutral term for evil)
    "enthusiasm": "enthusiastic",
    "fury": "furious",
    "frustration": "frustrated",
    "naughty": "evil",
}
"""Lower-case alias -> canonical emotion or blend name. The labels are those of the study's rating form."""

_INDEX: dict[str, int] = {name: i for i, name in enumerate(EMOTIONS)}


@dataclass(frozen=True)
class Blend:
    """A named linear blend of basic emotions.

    >>> b = Blend("evil", (("joy", 1.0), ("anger", 1.0)))
    >>> emotion_vector(b, 2.0).tolist()
    [2.0, 0.0, 2.0, 0.0, 0.0, 0.0]
    """

    name: str
    """Lower-case name, e.g. ``"evil"``."""
    components: tuple[tuple[str, float], ...]
    """``(emotion, weight)`` pairs; a blend event of intensity ``i`` adds ``i * weight`` to each emotion."""

    def __post_init__(self) -> None:
        name = str(self.name).strip().lower()
        if not name:
            raise InvalidValueError("blend name", self.name, "a non-empty name")
        if not self.components:
            raise InvalidValueError(f"blend {name!r} components", self.components, "at least one (emotion, weight)")
        merged: dict[str, float] = {}
        for emotion, weight in self.components:
            canonical = _resolve_basic(emotion)
            w = _check_weight(f"blend {name!r} weight of {canonical}", weight)
            merged[canonical] = merged.get(canonical, 0.0) + w
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "components", tuple(merged.items()))

    def vector(self, intensity: float = 1.0) -> np.ndarray:
        """(6,) emotion intensities of this blend at event ``intensity``."""
        return emotion_vector(self, intensity)


def _check_weight(field: str, weight: object) -> float:
    try:
        w = float(weight)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InvalidValueError(field, weight, f"a number in (0, {MAX_INTENSITY:g}]") from None
    if not math.isfinite(w) or w <= 0.0 or w > MAX_INTENSITY:
        raise InvalidValueError(field, weight, f"a number in (0, {MAX_INTENSITY:g}]")
    return w


def _resolve_basic(name: object) -> str:
    key = name.strip().lower() if isinstance(name, str) else ""
    key = EMOTION_ALIASES.get(key, key)
    if key not in _INDEX:
        raise UnknownNameError("basic emotion", name, EMOTIONS + tuple(EMOTION_ALIASES))
    return key


_PAPER = BLEND_COMPONENT_WEIGHT
BLENDS: dict[str, Blend] = {
    # Broekens, Qu & Brinkman, section 3: the four blends of the study.
    "enthusiastic": Blend("enthusiastic", (("joy", _PAPER), ("surprise", _PAPER))),
    "furious": Blend("furious", (("anger", _PAPER), ("surprise", _PAPER))),
    "frustrated": Blend("frustrated", (("anger", _PAPER), ("sadness", _PAPER))),
    "evil": Blend("evil", (("joy", _PAPER), ("anger", _PAPER))),
}
"""The paper's blends by name (read-only by convention; add your own with :func:`define_blend`)."""

_USER_BLENDS: dict[str, Blend] = {}

STUDY_EXPRESSIONS: tuple[str, ...] = EMOTIONS + tuple(BLENDS)
"""The ten expressions of the Broekens study: the six basic emotions, then the four blends (SPEC section 3)."""

RECOGNISED_FIVE: tuple[str, ...] = tuple(name for name in EMOTIONS if name != "disgust")
"""The five basic emotions held to the recognition targets: the classifier reads disgust unreliably (it is
judged by the FACS reading instead, SPEC section 6)."""


def blend_emotions(name: str) -> tuple[str, ...]:
    """The basic emotions of the blend ``name`` (the paper's or a user's), in the blend's order.

    >>> blend_emotions("furious")
    ('anger', 'surprise')
    """
    return tuple(emotion for emotion, _ in get_blend(name).components)


def known_names() -> tuple[str, ...]:
    """Every name :func:`resolve_emotion` accepts: emotions, blends (built-in, then user), then aliases."""
    return EMOTIONS + tuple(BLENDS) + tuple(_USER_BLENDS) + tuple(EMOTION_ALIASES)


def _canonical(name: object) -> str:
    if not isinstance(name, str):
        raise UnknownNameError("emotion", name, known_names())
    key = name.strip().lower()
    key = EMOTION_ALIASES.get(key, key)
    if key in _INDEX or key in BLENDS or key in _USER_BLENDS:
        return key
    raise UnknownNameError("emotion", name, known_names())


def resolve_emotion(name: str) -> str:
    """Canonical name (a basic emotion or a blend) of ``name``, case-insensitive, through aliases.

    Raises :class:`~mien.errors.UnknownNameError` listing the known names (blends included).

    >>> resolve_emotion("Happy"), resolve_emotion("scared"), resolve_emotion("EVIL")
    ('joy', 'fear', 'evil')
    """
    return _canonical(name)


def emotion_index(name: str) -> int:
    """Position of a basic emotion (or alias) in :data:`EMOTIONS`; blends raise UnknownNameError."""
    return _INDEX[_resolve_basic(name)]


def get_blend(name: str) -> Blend:
    """The blend called ``name`` (alias allowed), built-in or user-defined."""
    key = _canonical(name)
    blend = BLENDS.get(key) or _USER_BLENDS.get(key)
    if blend is None:
        raise UnknownNameError("blend", name, tuple(BLENDS) + tuple(_USER_BLENDS))
    return blend


def blend_components(name_or_blend: str | Blend) -> tuple[tuple[int, float], ...]:
    """``(emotion index, weight)`` pairs of an emotion (weight 1) or a blend.

    >>> blend_components("furious")
    ((2, 1.0), (3, 1.0))
    """
    if isinstance(name_or_blend, Blend):
        return tuple((_INDEX[e], w) for e, w in name_or_blend.components)
    key = _canonical(name_or_blend)
    if key in _INDEX:
        return ((_INDEX[key], 1.0),)
    return blend_components(get_blend(key))


def define_blend(name: str, weights: Mapping[str, float], *, register: bool = True) -> Blend:
    """Make (and by default register, so events may name it) a blend ``{emotion: weight}``.

    Weights are in (0, 5]; emotion names may be aliases. A name that is already an emotion, an alias or a
    built-in blend is refused (:class:`~mien.errors.InvalidValueError`); a user blend may be redefined.

    >>> smug = define_blend("smug", {"happy": 0.6, "disgust": 0.4})
    >>> emotion_vector("Smug", 1.0).round(2).tolist()
    [0.6, 0.0, 0.0, 0.0, 0.4, 0.0]
    >>> remove_blend("smug")
    """
    key = str(name).strip().lower()
    if key in _INDEX or key in EMOTION_ALIASES or key in BLENDS:
        raise InvalidValueError("blend name", name, "a name that is not an emotion, alias or built-in blend")
    if not isinstance(weights, Mapping):
        raise InvalidValueError(f"blend {key!r} weights", weights, "a mapping {emotion: weight}")
    blend = Blend(key, tuple(weights.items()))
    if register:
        _USER_BLENDS[blend.name] = blend
    return blend


def remove_blend(name: str) -> None:
    """Forget a user-defined blend (built-in blends cannot be removed)."""
    key = str(name).strip().lower()
    if key not in _USER_BLENDS:
        raise UnknownNameError("user blend", name, tuple(_USER_BLENDS))
    del _USER_BLENDS[key]


def emotion_vector(name_or_blend: str | Blend, intensity: float = 1.0) -> np.ndarray:
    """(6,) float64 emotion intensities (in :data:`EMOTIONS` order) of an emotion or blend at ``intensity``.

    ``intensity`` is in [0, 5] (1 = the prototype magnitude).

    >>> emotion_vector("angry", 1.2).tolist()
    [0.0, 0.0, 1.2, 0.0, 0.0, 0.0]
    >>> emotion_vector("enthusiastic", 1.0).tolist()
    [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]
    """
    value = check_intensity(intensity)
    out = np.zeros(len(EMOTIONS))
    for index, weight in blend_components(name_or_blend):
        out[index] += value * weight
    return out
