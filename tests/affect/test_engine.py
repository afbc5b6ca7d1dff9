"""EmotionEngine: events and envelopes, several emotions at once, mood, decay to mood, PAD mode, bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mien.affect.basis import expression, facs_basis, feature_point_basis, feature_target_names
from mien.affect.emotions import EMOTIONS, define_blend, emotion_vector, remove_blend
from mien.affect.engine import EmotionEngine, mood_step, shown_mood
from mien.affect.pad import PAD_PROTOTYPES, pad_to_emotions
from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.envelope import Envelope, envelope_values

JOY, SAD, ANGER, SURPRISE = (EMOTIONS.index(e) for e in ("joy", "sadness", "anger", "surprise"))


def run(engine: EmotionEngine, until_s: float, fps: float = 60.0, start_s: float = 0.0) -> None:
    """Advance frame by frame, as a character does."""
    for i in range(round((until_s - start_s) * fps) + 1):
        engine.intensities(start_s + i / fps)


def test_event_follows_the_envelope() -> None:
    engine = EmotionEngine()
    engine.trigger("happy", 1.2, t_s=1.0)
    assert engine.intensities(0.9).tolist() == [0.0] * 6
    assert engine.intensities(1.2)[JOY] == pytest.approx(0.6)
    assert engine.intensities(1.5)[JOY] == pytest.approx(1.2)
    assert engine.intensities(1.85)[JOY] == pytest.approx(0.6)
    assert engine.intensities(2.0).tolist() == [0.0] * 6
    assert engine.n_events == 0  # pruned


def test_several_emotions_at_once_blends_and_custom_envelopes() -> None:
    engine = EmotionEngine(envelope=Envelope(0.5, 1.0, 0.5))
    engine.trigger("joy", 1.0, 0.0)
    engine.trigger("sad", 0.5, 0.0)
    engine.trigger("evil", 2.4, 0.0, envelope=Envelope(0.0, 3.0, 0.0))
    engine.trigger("joy", 1.0, 0.25)
    np.testing.assert_allclose(engine.intensities(1.0), [1.0 + 1.0 + 2.4, 0.5, 2.4, 0, 0, 0])
    np.testing.assert_allclose(engine.intensities(0.25), [0.5 + 2.4, 0.25, 2.4, 0, 0, 0])
    engine.trigger("joy", 5.0, 1.0, envelope=Envelope(0.0, 1.0, 0.0))
    assert engine.intensities(1.1)[JOY] == 5.0  # capped at the top of the scale
    out = np.empty(6)
    assert engine.intensities(2.5, out=out) is out
    np.testing.assert_allclose(out, [2.4, 0, 2.4, 0, 0, 0])


def test_user_blend_event() -> None:
    define_blend("bittersweet", {"joy": 0.5, "sadness": 0.5})
    try:
        engine = EmotionEngine()
        engine.trigger("Bittersweet", 2.0, 0.0)
        np.testing.assert_allclose(engine.intensities(0.5), emotion_vector("bittersweet", 2.0))
    finally:
        remove_blend("bittersweet")


def test_mood_is_an_exponential_average_independent_of_frame_rate() -> None:
    tau = 2.0
    sustained = Envelope(0.0, 100.0, 0.0)
    moods = []
    for fps in (120.0, 30.0, 7.0):
        engine = EmotionEngine(mood_time_constant_s=tau)
        engine.trigger("anger", 1.0, 0.0, envelope=sustained)
        run(engine, 3.0, fps)
        moods.append(engine.mood(3.0)[ANGER])
    jump = EmotionEngine(mood_time_constant_s=tau)
    jump.trigger("anger", 1.0, 0.0, envelope=sustained)
    jump.intensities(0.0)
    moods.append(jump.mood(3.0)[ANGER])  # one sparse call: sub-stepped
    expected = 1.0 - math.exp(-3.0 / tau)
    np.testing.assert_allclose(moods, expected, rtol=1e-9)
    gained = EmotionEngine(mood_time_constant_s=tau, mood_gain=0.5)
    gained.trigger("anger", 1.0, 0.0, envelope=sustained)
    run(gained, 3.0)
    assert gained.mood(3.0)[ANGER] == pytest.approx(0.5 * expected)


def test_mood_moves_toward_recent_emotion_and_is_expressed_with_the_mouth_closed() -> None:
    engine = EmotionEngine(mood_time_constant_s=5.0)
    engine.trigger("surprised", 2.4, 0.0)
    run(engine, 3.0)
    emotion, mood = engine.state(3.0)
    assert emotion.tolist() == [0.0] * 6
    assert mood[SURPRISE] > 0.1 and np.count_nonzero(mood) == 1
    # the moving average by quadrature: (1 / tau) * integral of emotion(s) * exp(-(t - s) / tau) ds
    s = np.linspace(0.0, 1.0, 100_001)
    weighted = 2.4 * envelope_values(s, 0.4, 0.3, 0.3) * np.exp(-(3.0 - s) / 5.0) / 5.0
    exact = float(np.sum((weighted[1:] + weighted[:-1]) / 2) * (s[1] - s[0]))
    assert mood[SURPRISE] == pytest.approx(exact, rel=1e-3)
    shown_emotion, shown_mood = engine.expressed(3.0)
    np.testing.assert_array_equal(shown_mood, mood)  # nothing occludes the mood any more
    for full, closed in ((feature_point_basis(), feature_point_basis(True)), (facs_basis(), facs_basis(True))):
        face = expression(shown_emotion, full) + expression(shown_mood, closed)
        np.testing.assert_allclose(face, expression(mood, closed))
        assert np.any(face != 0.0)
    face = expression(shown_mood, feature_point_basis(True))
    jaw = [feature_target_names().index(f"fp_Jaw_{a}") for a in "xyz"]
    assert face[jaw].tolist() == [0.0, 0.0, 0.0]  # mouth closed although surprise drops the jaw
    assert expression(mood, feature_point_basis())[jaw[1]] < 0.0
    later = engine.mood(10.0)[SURPRISE]
    assert 0.0 < later < mood[SURPRISE]  # the mood fades without new emotion


def test_emotion_occludes_the_mood_in_proportion_to_its_intensity() -> None:
    engine = EmotionEngine()
    engine.set_mood([0.4, 0, 0, 0, 0, 0])
    engine.trigger("anger", 1.0, 0.0)
    _, shown = engine.expressed(0.0)
    assert shown[JOY] == pytest.approx(0.4)
    emotion, shown = engine.expressed(0.2)  # anger at 0.5
    assert emotion[ANGER] == pytest.approx(0.5)
    assert shown[JOY] == pytest.approx(0.5 * engine.mood(0.2)[JOY])
    _, shown = engine.expressed(0.5)  # hold: the emotion alone
    assert shown.tolist() == [0.0] * 6
    emotion_out, mood_out = np.empty(6), np.empty(6)
    got = engine.expressed(0.6, emotion_out, mood_out)
    assert got[0] is emotion_out and got[1] is mood_out


def test_earlier_queries_do_not_rewind_the_mood() -> None:
    engine = EmotionEngine()
    engine.trigger("joy", 1.0, 0.0)
    mood = engine.mood(0.6).copy()
    assert engine.intensities(0.2)[JOY] == pytest.approx(0.5)
    np.testing.assert_array_equal(engine.mood(0.3), mood)
    engine.reset()
    assert engine.n_events == 0 and engine.mood(0.0).tolist() == [0.0] * 6


def test_pad_mode() -> None:
    engine = EmotionEngine(mode="pad")
    anger = PAD_PROTOTYPES[ANGER]
    engine.set_pad(float(anger[0]), float(anger[1]), float(anger[2]), t_s=0.0)
    np.testing.assert_allclose(engine.pad(0.2), 0.5 * anger)
    np.testing.assert_allclose(engine.intensities(0.2), pad_to_emotions(0.5 * anger))
    np.testing.assert_allclose(engine.intensities(1.0), pad_to_emotions(anger))
    assert engine.intensities(5.0)[ANGER] == pytest.approx(1.0)  # held until changed
    engine.trigger("surprise", 1.0, 5.0)  # events add on top of the factor state
    assert engine.intensities(5.5)[SURPRISE] == pytest.approx(1.0)
    engine.set_pad(0.0, 0.0, 0.0, 6.0)
    run(engine, 8.0, start_s=6.0)
    emotion, mood = engine.state(8.0)
    assert emotion.tolist() == [0.0] * 6 and mood[ANGER] > 0.0
    instant = EmotionEngine(mode="pad", envelope=Envelope(0.0, 0.3, 0.3))
    instant.set_pad(0.5, 0.5, 0.5, 1.0)
    assert instant.pad(0.5).tolist() == [0.0, 0.0, 0.0] and instant.pad(1.0).tolist() == [0.5, 0.5, 0.5]
    with pytest.raises(InvalidValueError) as info:
        engine.set_pad(0.0, 1.2, 0.0, 9.0)
    assert (info.value.field, info.value.value) == ("arousal", 1.2)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda e: e.trigger("joy", 5.5, 0.0), "intensity"),
        (lambda e: e.trigger("joy", -1.0, 0.0), "intensity"),
        (lambda e: e.trigger("joy", float("nan"), 0.0), "intensity"),
        (lambda e: e.trigger("joy", float("inf"), 0.0), "intensity"),
        (lambda e: e.trigger("joy", 1.0, float("nan")), "t_s"),
        (lambda e: e.trigger("joy", 1.0, 0.0, envelope=Envelope(-0.1)), "onset_s"),
        (lambda e: e.trigger("joy", 1.0, 0.0, envelope=(0.4, 0.3, 0.3)), "envelope"),
        (lambda e: e.intensities(float("inf")), "t_s"),
        (lambda e: e.set_pad(0.1, 0.1, 0.1, 0.0), "mode"),
        (lambda e: e.set_mood([1.0, 2.0]), "mood"),
        (lambda e: e.set_mood([1.0, 0, 0, 0, 0, 9.0]), "mood[fear]"),
        (lambda e: EmotionEngine(mode="factors"), "mode"),
        (lambda e: EmotionEngine(mood_time_constant_s=0.0), "mood_time_constant_s"),
        (lambda e: EmotionEngine(mood_gain=float("nan")), "mood_gain"),
    ],
)
def test_bad_input_names_the_field(call: object, field: str) -> None:
    engine = EmotionEngine()
    with pytest.raises(InvalidValueError) as info:
        call(engine)  # type: ignore[operator]
    assert info.value.field == field


def test_unknown_emotion() -> None:
    with pytest.raises(UnknownNameError):
        EmotionEngine().trigger("smugness", 1.0, 0.0)


def test_vectorised_helpers_match_the_engine() -> None:
    engine = EmotionEngine(mood_time_constant_s=3.0, mood_gain=0.8)
    engine.trigger("furious", 1.2, 0.1)
    engine.trigger("sad", 0.7, 0.5)
    mood = np.zeros((2, 6))  # a batch of two identical characters
    previous = np.zeros((2, 6))
    for i in range(1, 121):
        t = i / 60.0
        current = np.tile(engine.intensities(t), (2, 1))
        mood_step(mood, previous, current, 1 / 60.0, 3.0, 0.8)
        previous = current
        _, shown = engine.expressed(t)
        np.testing.assert_allclose(mood[1], engine.mood(t), rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(shown_mood(current, mood)[0], shown, rtol=1e-9, atol=1e-15)
