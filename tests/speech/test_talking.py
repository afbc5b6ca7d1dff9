"""A sentence spoken by espeak-ng, on a face: closures, vowels, the jaw against the sound, the MP4's sync, joy.

The lips are measured on the deformed mesh (the built-in head's inner-lip landmarks 62 and 66, iBUG 0-based),
so the test covers the viseme shapes, the arbitration, the AU -> ARKit mapping and the rig together.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.character import Character
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip
from mien.facs.envelope import Envelope
from mien.speech.audio import energy_envelope
from mien.speech.track import Utterance

FPS = 30.0
BILABIAL_VISEME = "PP"
VOWEL_VISEMES = ("aa", "E", "I", "O", "U")
CLOSED_MM = 1.0
"""A lip gap at most this much wider than the resting mouth's is closed (millimetres)."""
OPEN_MM = 2.5
"""A lip gap at least this much wider than the resting mouth's is open."""


def _talk(spoken: Utterance, emotion: str | None, fps: float = FPS) -> Clip:
    face = Character(seed=5, idle=False)
    if emotion is not None:
        face.emote(emotion, 1.2, start_s=0.0, envelope=Envelope(0.2, 60.0, 0.3))
    face.say(spoken, start_s=0.0)
    return face.run(spoken.duration_s, fps)


def _lip_gap_mm(clip: Clip) -> np.ndarray:
    """(n_frames,) vertical distance between the inner-lip midpoints of the built-in head, mm."""
    from mien.rig.animate import face_to_rig
    from mien.rig.builtin_head import builtin_head
    from mien.rig.deform import Deformer

    rig = builtin_head()
    weights, _ = face_to_rig(rig, clip)
    deformer = Deformer(rig, backend="numpy")
    upper, lower = rig.landmarks[62], rig.landmarks[66]
    gaps = [deformer.deform(np.asarray(w, np.float32)) for w in weights]
    rest = deformer.deform(np.zeros(weights.shape[1], np.float32))
    return 1000.0 * (np.array([v[upper, 1] - v[lower, 1] for v in gaps]) - (rest[upper, 1] - rest[lower, 1]))


@pytest.mark.parametrize("emotion", [None, "joy"])
def test_lips_close_on_every_bilabial_and_open_on_every_vowel(spoken: Utterance, emotion: str | None) -> None:
    gap = _lip_gap_mm(_talk(spoken, emotion))
    times = np.arange(len(gap)) / FPS
    bilabials = [s for s in spoken.segments if s.viseme == BILABIAL_VISEME]
    vowels = [s for s in spoken.segments if s.viseme in VOWEL_VISEMES]
    assert len(bilabials) >= 10 and len(vowels) >= 15
    for s in bilabials:  # closed on a frame within one frame of the phoneme event
        near = (times >= s.start_s - 1 / FPS) & (times <= s.end_s + 1 / FPS)
        assert gap[near].min() <= CLOSED_MM, (s, gap[near].round(2))
    for s in vowels:  # open on a frame within the vowel (or the frame after a vowel shorter than a frame)
        near = (times >= s.start_s) & (times <= s.end_s + 1 / FPS)
        assert gap[near].max() >= OPEN_MM, (s, gap[near].round(2))
    if emotion == "joy":  # joy alone parts the lips (AU25): speech closes them anyway
        silent = Character(seed=5, idle=False)
        silent.emote("joy", 1.2, start_s=0.0, envelope=Envelope(0.2, 60.0, 0.3))
        assert _lip_gap_mm(silent.run(1.0, FPS))[-1] > CLOSED_MM


def test_the_jaw_follows_the_sound(spoken: Utterance) -> None:
    clip = _talk(spoken, None)
    jaw = clip.channel("AU26")
    assert spoken.audio is not None
    envelope = energy_envelope(spoken.audio, FPS)
    n = min(len(jaw), len(envelope))
    r = float(np.corrcoef(jaw[:n], envelope[:n])[0, 1])
    shift = round(0.25 * FPS)  # the same curves a quarter second apart: sync, not just shape, makes r
    r_shifted = float(np.corrcoef(jaw[shift:n], envelope[: n - shift])[0, 1])
    assert r > 0.4, r
    assert r > r_shifted + 0.2, (r, r_shifted)


def test_mien_say_muxes_the_sound_in_sync(tmp_path: Path) -> None:
    """The MP4's audio is the utterance's sound, starting with the first frame (within one frame)."""
    av = pytest.importorskip("av")
    pytest.importorskip("moderngl")
    from mien.cli import main
    from mien.commands.say import TAIL_S
    from mien.speech.audio import read_audio
    from mien.speech.espeak import speak

    spoken = speak("my mama made a map")  # a short sentence: a short render

    out = tmp_path / "say.mp4"
    code = main(["say", spoken.text, "--emotion", "joy", "-o", str(out), "--head", "builtin", "--size", "128x128",
                 "--fps", str(int(FPS)), "--quiet", "--no-idle"])  # fmt: skip
    assert code == 0 and out.is_file() and out.with_suffix(".wav").is_file()
    with av.open(str(out)) as container:
        video, audio = container.streams.video[0], container.streams.audio[0]
        video_start = float(video.start_time * video.time_base)
        audio_start = float(audio.start_time * audio.time_base)
        n_frames = sum(1 for _ in container.decode(video=0))
    assert abs(video_start - audio_start) <= 1 / FPS
    assert n_frames == round((spoken.duration_s + TAIL_S) * FPS)
    muxed = read_audio(out)  # AAC decoded back (ffmpeg), at 22,050 Hz like espeak-ng's sound
    kept = read_audio(out.with_suffix(".wav"))
    assert spoken.audio is not None and kept.duration_s == pytest.approx(spoken.audio.duration_s, abs=0.01)
    a, b = energy_envelope(muxed, 1000.0), energy_envelope(kept, 1000.0)  # 1 ms envelopes
    n = min(len(a), len(b))
    lags = range(-100, 101)
    score = [np.dot(a[max(0, k) : n + min(0, k)], b[max(0, -k) : n - max(0, k)]) for k in lags]
    lag_ms = list(lags)[int(np.argmax(score))]
    assert abs(lag_ms) <= 1000 / FPS, lag_ms


@pytest.mark.slow
def test_joy_still_reads_while_speaking(
    spoken: Utterance, ict_dir: Path, landmarker_path: Path, emotion_model_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The classifier's joy on speaking frames is at least 80 % of its rate on the silent joy (ICT, frontal)."""
    pytest.importorskip("moderngl")
    from mien.heads import load_head
    from mien.render.camera import CAMERA_PRESETS
    from mien.render.clip_render import iter_frames, make_renderer
    from mien.rig.animate import face_to_rig
    from mien.validate.face_detector import FaceDetector

    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(ict_dir))
    rig = load_head("ict")
    fps = 5.0
    speaking = _talk(spoken, "joy", fps)
    silent_face = Character(seed=5, idle=False)
    silent_face.emote("joy", 1.2, start_s=0.0, envelope=Envelope(0.2, 60.0, 0.3))
    silent = silent_face.run(spoken.duration_s, fps)
    times = speaking.times_s
    mouth_moving = np.abs(speaking.values - silent.values).max(axis=1) > 0.5
    chosen = np.flatnonzero(mouth_moving & (times > 0.3))[:10]
    assert len(chosen) >= 8
    detector = FaceDetector(landmarker_path, emotion_model_path)
    rates = {}
    try:
        with make_renderer(rig, CAMERA_PRESETS["frontal-1m"], (320, 320), samples=0) as renderer:
            for name, clip in (("speaking", speaking), ("silent", silent)):
                weights, poses = face_to_rig(rig, clip.values[chosen])
                tops = [detector.detect(image).top_emotion for image in iter_frames(rig, weights, renderer, poses)]
                rates[name] = sum(top == "happy" for top in tops) / len(tops)
    finally:
        detector.close()
    assert rates["silent"] >= 0.75, rates  # the emotion reads on its own first
    assert rates["speaking"] >= 0.8 * rates["silent"], rates
    assert FACE_CHANNELS  # frames are face channels throughout
