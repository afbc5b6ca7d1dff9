"""PAD prototypes (with sources) and the PAD -> emotion-intensity mapping."""

from __future__ import annotations

import numpy as np
import pytest

from mien.affect.emotions import EMOTIONS
from mien.affect.pad import PAD_PROTOTYPES, PAD_SOURCES, pad_intensities, pad_to_emotions
from mien.errors import InvalidValueError


def test_prototypes_and_sources() -> None:
    assert PAD_PROTOTYPES.shape == (6, 3)
    assert PAD_PROTOTYPES[EMOTIONS.index("anger")].tolist() == [-0.51, 0.59, 0.25]
    assert PAD_PROTOTYPES[EMOTIONS.index("fear")].tolist() == [-0.64, 0.60, -0.43]
    assert PAD_PROTOTYPES[EMOTIONS.index("joy")].tolist() == [0.81, 0.51, 0.46]
    assert all("Russell & Mehrabian 1977" in s for s in PAD_SOURCES)
    assert np.all(np.abs(PAD_PROTOTYPES) <= 1.0)


@pytest.mark.parametrize("emotion", EMOTIONS)
def test_a_prototype_gives_its_emotion_at_one_and_most(emotion: str) -> None:
    i = EMOTIONS.index(emotion)
    intensities = pad_to_emotions(PAD_PROTOTYPES[i])
    assert intensities[i] == pytest.approx(1.0)
    assert int(np.argmax(intensities)) == i
    assert np.all(intensities >= 0.0)


def test_origin_is_neutral_and_scaling_is_geometric() -> None:
    assert pad_to_emotions([0.0, 0.0, 0.0]).tolist() == [0.0] * 6
    state = np.array([-0.3, 0.25, 0.1])
    np.testing.assert_allclose(pad_to_emotions(2 * state), 2 * pad_to_emotions(state))
    # far from every prototype's direction: nothing (relaxed: pleasant, calm)
    assert pad_to_emotions([0.5, -0.5, 0.0]).tolist() == [0.0] * 6
    # a tighter radius isolates the prototypes (anger and disgust are 22 degrees apart)
    assert np.count_nonzero(pad_to_emotions(PAD_PROTOTYPES[2], radius=0.3)) == 1
    assert pad_intensities(*PAD_PROTOTYPES[1].tolist()) == pytest.approx(pad_to_emotions(PAD_PROTOTYPES[1]).tolist())


@pytest.mark.parametrize(
    ("pad", "field"),
    [
        ([1.5, 0.0, 0.0], "pleasure"),
        ([0.0, float("nan"), 0.0], "arousal"),
        ([0.0, 0.0, -float("inf")], "dominance"),
        ([0.0, 0.0], "pad"),
        (["a", 0, 0], "pad"),
    ],
)
def test_bad_states_name_the_factor(pad: list[object], field: str) -> None:
    with pytest.raises(InvalidValueError) as info:
        pad_to_emotions(pad)
    assert info.value.field == field
    with pytest.raises(InvalidValueError):
        pad_to_emotions([0.1, 0.1, 0.1], radius=0.0)
