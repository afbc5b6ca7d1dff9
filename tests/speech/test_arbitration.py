"""Arbitration in the one engine, channel by channel: speech over emotion, laughter, idle and blinks."""

from __future__ import annotations

import numpy as np
import pytest

from mien.character import Character, CharacterBatch
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.envelope import Envelope
from mien.speech.arbitration import RULES
from mien.speech.coarticulation import coarticulate
from mien.speech.track import Segment, Utterance

FPS = 100.0
AU = FACE_CHANNELS.index
EMOTION_KEEPS = [c for c in FACE_CHANNELS if c not in RULES]
"""Brows, lids, cheeks, nose, lip corners, upper lip, blinks, head and gaze."""


def _utterance(start_s: float = 0.0) -> Utterance:
    """Repeated "ma-pa-u" syllables from a timing, 1.6 s: closures, open vowels and rounding."""
    units = ["sil"] + ["PP", "aa", "PP", "aa", "SS", "U"] * 4 + ["sil"]
    segments = [Segment(start_s + 0.06 * i, start_s + 0.06 * (i + 1), unit) for i, unit in enumerate(units)]
    return Utterance(coarticulate(segments), tuple(segments), None, "", "timing file")


def _run(*, say: bool, emotion: str | None = "joy", laugh: tuple[float, float] | None = None, idle: bool = False,
         seconds: float = 1.8) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    face = Character(seed=7, idle=idle)
    if emotion:
        face.emote(emotion, 1.0, start_s=0.0, envelope=Envelope(0.2, 5.0, 0.2))
    if say:
        face.say(_utterance())
    if laugh is not None:
        face.laugh("laughter", 1.0, duration_s=laugh[1], start_s=laugh[0], seed=3)
    frames, presence = [], []
    for i in range(round(seconds * FPS)):
        frames.append(face.step(i / FPS).copy())
        presence.append(float(face.batch.speech.presence[0]))
    return np.array(frames), np.array(presence)


def test_emotion_keeps_brows_lids_cheeks_and_lip_corners() -> None:
    talking, presence = _run(say=True)
    silent, _ = _run(say=False)
    keep = [AU(c) for c in EMOTION_KEEPS]
    assert np.array_equal(talking[:, keep], silent[:, keep])
    assert silent[60, AU("AU12L")] > 3 and silent[60, AU("AU6L")] > 3  # joy is there, in both
    # speech owns the opening: joy's parted lips (AU25 1.5) close on each /p/ and open on /a/
    lips = talking[:, AU("AU25")]
    closures = [round((0.06 * i + 0.03) * FPS) for i in (7, 9, 13, 15)]
    vowels = [round((0.06 * i + 0.03) * FPS) for i in (8, 10, 14, 16)]
    assert silent[closures, AU("AU25")].min() > 1.4
    assert lips[closures].max() < 0.3 and lips[vowels].min() > 1.8
    assert presence[closures].min() > 0.9
    # the spread of /s/ adds to the emotion's lip stretcher (rule "add"), not replacing it
    assert RULES["AU20L"] == "add"


def test_a_smile_keeps_its_corners_and_a_sad_mouth_still_articulates() -> None:
    sad_talking, _ = _run(say=True, emotion="sadness")
    sad_silent, _ = _run(say=False, emotion="sadness")
    assert np.array_equal(sad_talking[:, AU("AU15L")], sad_silent[:, AU("AU15L")])
    assert sad_silent[60, AU("AU15L")] > 3
    assert sad_talking[round(0.15 * FPS), AU("AU26")] > 2  # an /a/ opens the jaw over the sad mouth


def test_laughter_interrupts_speech_and_speech_resumes() -> None:
    laugh = (0.5, 0.6)
    both, presence = _run(say=True, emotion=None, laugh=laugh)
    laugh_only, _ = _run(say=False, emotion=None, laugh=laugh)
    speech_only, _ = _run(say=True, emotion=None)
    during = slice(round(0.65 * FPS), round(0.95 * FPS))
    assert presence[during].max() == 0.0
    assert np.allclose(both[during], laugh_only[during])  # the laugh has the mouth
    after = slice(round(1.25 * FPS), round(1.6 * FPS))
    assert presence[after].max() > 0.9
    assert np.allclose(both[after], speech_only[after])  # speech is back, on its own clock
    before = slice(0, round(0.35 * FPS))
    assert np.allclose(both[before], speech_only[before])


def test_idle_mouth_yields_and_blinks_continue() -> None:
    talking, presence = _run(say=True, emotion=None, idle=True, seconds=1.6)
    silent, _ = _run(say=False, emotion=None, idle=True, seconds=1.6)
    still, _ = _run(say=True, emotion=None, idle=False, seconds=1.6)
    blinks = [AU("AU45L"), AU("AU45R"), AU("AU43L")]
    assert np.array_equal(talking[:, blinks], silent[:, blinks])
    corners = [AU("AU12L"), AU("AU12R"), AU("AU15L"), AU("AU15R")]
    idle_part = np.abs(talking[:, corners] - still[:, corners]).max(axis=1)
    silent_part = np.abs(silent[:, corners]).max()
    assert silent_part > 0.01  # idle moves the corners when silent
    speaking = presence > 0.95
    assert speaking.sum() > 50
    assert idle_part[speaking].max() <= 0.05 * silent_part + 1e-9


def test_a_batch_of_talking_characters_steps_as_its_rows_alone() -> None:
    utterances = [_utterance(), _utterance(0.1), _utterance(0.25)]
    batch = CharacterBatch(np.array([1, 2, 3]), idle=True)
    singles = [Character(seed=s, idle=True) for s in (1, 2, 3)]
    for row, (face, utterance) in enumerate(zip(singles, utterances, strict=True)):
        batch.emote(row, ["joy", "sadness", "anger"][row], 1.0)
        face.emote(["joy", "sadness", "anger"][row], 1.0)
        batch.say(row, utterance, start_s=0.05 * row)
        face.say(utterance, start_s=0.05 * row)
    for i in range(150):
        t = i / 60
        frames = batch.step(t)
        for row, face in enumerate(singles):
            assert np.allclose(frames[row], face.step(t), atol=1e-9), (row, t)
    assert np.allclose(batch.speech.viseme_weights[:, 0], 0.0)


def test_say_replaces_and_removal_silences() -> None:
    batch = CharacterBatch(2, idle=False)
    batch.say(slice(None), _utterance())
    batch.step(0.2)
    assert (batch.speech.presence > 0.5).all()
    batch.remove_character(1)
    assert batch.speech.presence[1] == 0.0 and batch.speech.utterance(1) is None
    row = batch.add_character(seed=5, idle=False)
    assert row == 1 and batch.step(0.3)[1, AU("AU26")] == 0.0
    batch.step(5.0)  # after the end: the utterance is dropped
    assert batch.speech.utterance(0) is None and batch.speech.presence[0] == 0.0
    with pytest.raises(InvalidValueError, match="Utterance"):
        batch.say(0, 42)  # type: ignore[arg-type]
    with pytest.raises(InvalidValueError, match="start_s"):
        batch.say(0, _utterance(), start_s=float("nan"))


def test_many_utterances_through_a_compacting_pool_stay_right() -> None:
    """Fresh utterances said again and again (the pool compacts and grows) give each row what it alone gives."""
    batch = CharacterBatch(np.array([1, 2, 3, 4]), idle=False)
    singles = [Character(seed=s, idle=False) for s in (1, 2, 3, 4)]
    for i in range(120):
        t = i / 20
        if i % 4 == 0:
            row = (i // 4) % 4
            utterance = _utterance()  # a new object each time: compiled and stored anew
            batch.say(row, utterance)
            singles[row].say(utterance)
        frames = batch.step(t)
        for row, face in enumerate(singles):
            assert np.allclose(frames[row], face.step(t), atol=1e-9), (row, t)
    assert batch.speech._pool.shape[0] >= 1024
