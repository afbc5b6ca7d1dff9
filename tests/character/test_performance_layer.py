"""A person's performance as a layer of the one engine: held under emotions, laughter and idle, per row."""

from __future__ import annotations

import numpy as np
import pytest

from mien.character import Character, CharacterBatch
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS

AU12L = FACE_CHANNELS.index("AU12L")
AU4L = FACE_CHANNELS.index("AU4L")
YAW = FACE_CHANNELS.index("head_yaw_deg")


def _performance(**channels: float) -> np.ndarray:
    frame = np.zeros(len(FACE_CHANNELS))
    for name, value in channels.items():
        frame[FACE_CHANNELS.index(name)] = value
    return frame


def test_the_performance_is_held_on_its_rows_until_removed() -> None:
    batch = CharacterBatch(3, idle=False)
    batch.set_performance(np.array([0, 2]), _performance(AU12L=2.0, head_yaw_deg=10.0))
    frames = batch.step(0.1)
    assert frames[:, AU12L].tolist() == [2.0, 0.0, 2.0] and frames[:, YAW].tolist() == [10.0, 0.0, 10.0]
    assert batch.step(0.2)[0, AU12L] == 2.0  # held between updates
    batch.set_performance(0, None)
    assert batch.step(0.3)[:, AU12L].tolist() == [0.0, 0.0, 2.0]


def test_emotions_and_held_aus_add_on_top_and_aus_stay_in_range() -> None:
    character = Character(seed=1, idle=False)
    character.set_performance(_performance(AU12L=4.0))
    character.set_au("AU4", 1.5, tau_s=0.0)
    character.emote("joy", 1.0)
    frame = character.step(0.5)  # joy's hold phase adds AU12 on top of the performer's
    assert frame[AU4L] == 1.5 and frame[AU12L] == 5.0  # 4 + 3.5, clipped to the AU range


def test_a_freed_row_forgets_its_performance_and_bad_frames_change_nothing() -> None:
    batch = CharacterBatch(0, idle=False)
    row = batch.add_character(seed=1, idle=False)
    batch.set_performance(row, _performance(AU12L=3.0))
    batch.remove_character(row)
    again = batch.add_character(seed=2, idle=False)
    assert again == row and batch.step(0.1)[row, AU12L] == 0.0
    batch.set_performance(row, _performance(AU12L=1.0))
    for bad in (np.zeros(5), np.full(len(FACE_CHANNELS), np.nan)):
        with pytest.raises(InvalidValueError, match="frame"):
            batch.set_performance(row, bad)
    assert batch.step(0.2)[row, AU12L] == 1.0
