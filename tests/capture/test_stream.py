"""CaptureStream: the one engine of capture (no assets: synthetic tracked frames)."""

from __future__ import annotations

import numpy as np
import pytest

from mien.capture import CaptureSettings, CaptureStream, OneEuroFilter, capture_frames, gaze_deg
from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_INDEX
from mien.facs.catalogue import channel_index

FPS = 30.0
SMILE = [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]
AU12L = channel_index("AU12L")


def _smile_scores(n: int, onset: int, level: float = 0.8, noise: float = 0.0, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    scores = np.full((n, 52), 0.05)
    scores[onset:, SMILE] = level
    return np.clip(scores + rng.normal(0.0, noise, scores.shape), 0.0, 1.0)


def test_the_filter_removes_jitter_and_keeps_a_step_within_two_frames() -> None:
    n, onset = 90, 45
    raw = _smile_scores(n, onset, noise=0.02)
    stream = CaptureStream(CaptureSettings(neutral_first_s=0.0))
    unfiltered = CaptureStream(CaptureSettings(neutral_first_s=0.0, filter=False))
    out = np.array([stream.push(i / FPS, raw[i], np.zeros(3))[AU12L] for i in range(n)])
    ref = np.array([unfiltered.push(i / FPS, raw[i], np.zeros(3))[AU12L] for i in range(n)])
    still = slice(onset + 15, n)  # a held smile: only tracker noise moves it
    assert np.std(np.diff(out[still])) < 0.5 * np.std(np.diff(ref[still]))
    half = 0.5 * ref[still].mean()
    assert int(np.argmax(out > half)) - int(np.argmax(ref > half)) <= 2


def test_one_euro_at_rest_is_a_low_pass_at_its_cut_off() -> None:
    # beta 0: a first-order low-pass at min_cutoff_hz; a sine far above it is attenuated, far below it passes
    times = np.arange(600) / 60.0
    for hz, low, high in ((0.1, 0.9, 1.01), (10.0, 0.0, 0.2)):
        f = OneEuroFilter(min_cutoff_hz=1.0, beta=0.0)
        out = np.array([f(t, np.array([np.sin(2 * np.pi * hz * t)]))[0] for t in times])
        assert low <= np.abs(out[300:]).max() <= high


def test_a_lost_face_holds_then_eases_to_neutral_and_is_marked() -> None:
    settings = CaptureSettings(neutral_first_s=0.0, filter=False, hold_s=0.5, ease_s=1.0)
    stream = CaptureStream(settings)
    smile = _smile_scores(1, 0)[0]
    shown = stream.push(0.0, smile, np.array([10.0, 0.0, 0.0]))
    assert stream.has_face and shown[AU12L] > 2.0
    values = []
    for i in range(1, 80):
        values.append(stream.push(i / FPS, None, None))
        assert not stream.has_face
    values = np.array(values)
    held = values[: int(0.5 * FPS) - 1]
    assert np.allclose(held, shown)  # held for hold_s
    assert np.abs(values[-1]).max() == 0.0  # neutral after hold_s + ease_s
    assert np.abs(np.diff(values, axis=0)).max() < 0.1 * np.abs(shown).max()  # eased: no jump


def test_a_face_that_comes_back_blends_in_without_a_jump() -> None:
    settings = CaptureSettings(neutral_first_s=0.0, filter=False, enter_s=0.2)
    stream = CaptureStream(settings)
    for i in range(30):  # no face yet: neutral
        assert np.abs(stream.push(i / FPS, None, None)).max() == 0.0
    smile = _smile_scores(1, 0)[0]
    values = np.array([stream.push((30 + i) / FPS, smile, np.zeros(3))[AU12L] for i in range(12)])
    target = values[-1]
    assert values[0] < 0.2 * target and np.all(np.diff(values) >= 0) and values[7] == pytest.approx(target)


def test_the_neutral_is_subtracted_and_a_full_score_stays_reachable() -> None:
    neutral = np.zeros(55)
    neutral[SMILE] = 0.3  # a performer whose resting mouth reads as a slight smile
    neutral[52] = 5.0  # and whose head turns 5 degrees at rest
    stream = CaptureStream(CaptureSettings(filter=False), neutral=neutral)
    rest = neutral[:52].copy()
    assert np.abs(stream.push(0.0, rest, np.array([5.0, 0.0, 0.0]))).max() == pytest.approx(0.0, abs=1e-9)
    full = rest.copy()
    full[SMILE] = 1.0
    frame = stream.push(0.1, full, np.array([15.0, 0.0, 0.0]))
    assert stream.weights[SMILE] == pytest.approx([1.0, 1.0])
    assert frame[channel_index("head_yaw_deg")] == pytest.approx(10.0)


def test_the_first_seconds_give_the_neutral_offline_and_live() -> None:
    n = 60
    raw = _smile_scores(n, onset=30, level=0.8)
    raw[:, SMILE] += 0.2  # a resting smile of 0.25 (0.05 + 0.2) through the first second
    found = np.ones(n, bool)
    capture = capture_frames("x.mp4", FPS, np.arange(n) / FPS, raw, np.zeros((n, 3)), found)
    assert capture.neutral[SMILE] == pytest.approx([0.25, 0.25])
    assert capture.frames[:25, AU12L].max() == pytest.approx(0.0, abs=1e-6)
    live = CaptureStream()
    frames = np.array([live.push(i / FPS, raw[i], np.zeros(3)) for i in range(n)])
    assert np.allclose(frames[20:], capture.frames[20:], atol=1e-6)  # the same neutral once the interval ended


def test_gaze_comes_from_the_eye_look_scores_at_the_rig_eye_angles() -> None:
    scores = np.zeros(52)
    scores[[ARKIT_INDEX["eyeLookOutLeft"], ARKIT_INDEX["eyeLookInRight"]]] = 1.0  # both eyes to the left
    scores[[ARKIT_INDEX["eyeLookUpLeft"], ARKIT_INDEX["eyeLookUpRight"]]] = 0.4
    assert gaze_deg(scores) == pytest.approx([30.0, 10.0])


def test_bad_frames_are_refused_with_the_value() -> None:
    stream = CaptureStream()
    stream.push(0.0, np.zeros(52), None)
    with pytest.raises(InvalidValueError, match="t_s"):
        stream.push(0.0, np.zeros(52), None)
    with pytest.raises(InvalidValueError, match="blendshapes"):
        stream.push(0.1, np.zeros(51), None)
    with pytest.raises(InvalidValueError, match="head_rotation_deg"):
        stream.push(0.2, np.zeros(52), np.array([np.nan, 0, 0]))
    with pytest.raises(InvalidValueError, match="neutral interval"):
        CaptureSettings(neutral_s=(2.0, 1.0))
    stream.reset()
    assert stream.push(0.0, None, None).shape == (62,)


def test_a_one_frame_dropout_comes_back_at_once() -> None:
    stream = CaptureStream(CaptureSettings(neutral_first_s=0.0, filter=False))
    smile = _smile_scores(1, 0)[0]
    first = stream.push(0.0, smile, np.zeros(3))
    assert np.allclose(stream.push(1 / FPS, None, None), first)  # held
    assert np.allclose(stream.push(2 / FPS, smile, np.zeros(3)), first)  # the tracked face again, no blend delay


def test_frame_times_that_do_not_increase_are_refused_naming_the_frame() -> None:
    times = np.array([0.0, 0.1, 0.1, 0.2])
    with pytest.raises(InvalidValueError, match=r"frame 2 at 0.1000 s"):
        capture_frames("v.mp4", 30.0, times, np.zeros((4, 52)), np.zeros((4, 3)), np.ones(4, bool))
