"""Emotion names, aliases, blends (built-in and user-defined) and emotion vectors."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from mien.affect.emotions import (
    BLENDS,
    EMOTIONS,
    Blend,
    blend_components,
    define_blend,
    emotion_index,
    emotion_vector,
    get_blend,
    remove_blend,
    resolve_emotion,
)
from mien.errors import InvalidValueError, UnknownNameError


@pytest.fixture
def cleanup() -> Iterator[list[str]]:
    names: list[str] = []
    yield names
    for name in names:
        remove_blend(name)


def test_canonical_order() -> None:
    assert EMOTIONS == ("joy", "sadness", "anger", "surprise", "disgust", "fear")


@pytest.mark.parametrize(
    ("alias", "emotion"),
    [
        ("happy", "joy"),
        ("Happiness", "joy"),
        ("sad", "sadness"),
        ("ANGRY", "anger"),
        ("surprised", "surprise"),
        ("disgusted", "disgust"),
        ("afraid", "fear"),
        ("fearful", "fear"),
        ("scared", "fear"),
        (" joy ", "joy"),
        ("Enthusiasm", "enthusiastic"),
        ("naughty", "evil"),
    ],
)
def test_aliases(alias: str, emotion: str) -> None:
    assert resolve_emotion(alias) == emotion


def test_unknown_name_lists_known_names_including_blends() -> None:
    with pytest.raises(UnknownNameError) as info:
        resolve_emotion("melancholic")
    message = str(info.value)
    assert "melancholic" in message and "joy" in message and "evil" in message and "furious" in message
    assert "frustrated" in info.value.known
    with pytest.raises(UnknownNameError):
        not_a_name: Any = 3
        resolve_emotion(not_a_name)
    with pytest.raises(UnknownNameError):
        emotion_index("evil")  # a blend has no single index


def test_paper_blends_are_equal_shares_at_full_intensity() -> None:
    assert {name: dict(b.components) for name, b in BLENDS.items()} == {
        "enthusiastic": {"joy": 1.0, "surprise": 1.0},
        "furious": {"anger": 1.0, "surprise": 1.0},
        "frustrated": {"anger": 1.0, "sadness": 1.0},
        "evil": {"joy": 1.0, "anger": 1.0},
    }
    for name, blend in BLENDS.items():
        expected = sum(emotion_vector(e, 2.4) * w for e, w in blend.components)
        np.testing.assert_allclose(emotion_vector(name, 2.4), expected)
    assert emotion_vector("frustrated", 1.2).tolist() == [0.0, 1.2, 1.2, 0.0, 0.0, 0.0]
    assert blend_components("evil") == ((0, 1.0), (2, 1.0))


def test_emotion_vector_and_intensity_checks() -> None:
    assert emotion_vector("fear", 2.4).tolist() == [0.0, 0.0, 0.0, 0.0, 0.0, 2.4]
    assert emotion_vector("joy").tolist() == [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    bad_values: tuple[Any, ...] = (-0.1, 5.01, float("nan"), float("inf"), "lots")
    for bad in bad_values:
        with pytest.raises(InvalidValueError) as info:
            emotion_vector("joy", bad)
        assert info.value.field == "intensity"


def test_define_blend_registers_and_validates(cleanup: list[str]) -> None:
    smug = define_blend("Smug", {"happy": 0.6, "disgusted": 0.4})
    cleanup.append("smug")
    assert smug == Blend("smug", (("joy", 0.6), ("disgust", 0.4)))
    assert resolve_emotion("SMUG") == "smug" and get_blend("smug") is smug
    np.testing.assert_allclose(emotion_vector("smug", 2.0), [1.2, 0, 0, 0, 0.8, 0])
    redefined = define_blend("smug", {"joy": 0.5, "joy ": 0.5})  # repeated emotions add up
    assert redefined.components == (("joy", 1.0),)
    for name in ("joy", "happy", "evil"):
        with pytest.raises(InvalidValueError):
            define_blend(name, {"joy": 1.0})
    with pytest.raises(InvalidValueError) as info:
        define_blend("odd", {"joy": -1.0})
    assert "joy" in info.value.field
    for weights in ({}, {"joy": float("nan")}, {"joy": 0.0}, {"joy": 6.0}):
        with pytest.raises(InvalidValueError):
            define_blend("odd", weights)
    with pytest.raises(UnknownNameError):
        define_blend("odd", {"smugness": 1.0})
    with pytest.raises(UnknownNameError):
        define_blend("odd", {"evil": 1.0})  # components must be basic emotions
    unregistered = define_blend("wistful", {"sad": 0.5, "joy": 0.3}, register=False)
    with pytest.raises(UnknownNameError):
        resolve_emotion("wistful")
    assert emotion_vector(unregistered, 1.0).tolist() == [0.3, 0.5, 0.0, 0.0, 0.0, 0.0]
    with pytest.raises(UnknownNameError):
        remove_blend("evil")
