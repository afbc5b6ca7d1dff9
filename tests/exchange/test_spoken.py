"""A spoken clip exported with its sound side by side: ``mien say TEXT -o out.glb`` and ``mien export --audio``.

Round trip: the .glb read back animates the jaw open on the vowels and shut on the /m/ and /p/ of espeak-ng's
phoneme events; the .wav beside it is the utterance's sound, from t = 0; ``mien export out.glb out.anim --audio
out.wav`` carries both on.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.exchange import read_clip
from mien.speech.audio import read_audio

espeak = pytest.importorskip("mien.speech.espeak")

SENTENCE = "my mama made a map"


@pytest.fixture(scope="module")
def spoken(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    """``mien say SENTENCE -o out.glb`` on the built-in head, and the same sentence spoken in-process."""
    try:
        utterance = espeak.speak(SENTENCE)
    except Exception as exc:  # MissingAssetError without libespeak-ng
        pytest.skip(f"espeak-ng cannot speak here: {exc}")
    folder = tmp_path_factory.mktemp("spoken")
    out = folder / "out.glb"
    assert main(["say", SENTENCE, "-o", str(out), "--head", "builtin", "--no-idle", "--fps", "60"]) == 0
    return out, utterance


def _jaw_at(clip, t_s: float) -> float:
    column = clip.channels.index("jawOpen")
    return float(np.interp(t_s, np.arange(clip.n_frames) / clip.fps, clip.values[:, column]))


def test_say_writes_the_glb_with_the_animation_and_the_wav_beside_it(spoken) -> None:
    out, utterance = spoken
    wav = out.with_suffix(".wav")
    assert out.is_file() and wav.is_file()
    sound = read_audio(wav)
    assert sound.sample_rate == utterance.audio.sample_rate
    assert abs(sound.duration_s - utterance.audio.duration_s) < 0.01
    clip = read_clip(out)
    assert clip.fps == pytest.approx(60.0)
    assert (clip.n_frames - 1) / clip.fps >= sound.duration_s  # the animation covers the sound
    closures = opens = 0
    for segment in utterance.segments:
        middle = (segment.start_s + segment.end_s) / 2
        if segment.phoneme in ("m", "p"):
            closures += 1
            assert _jaw_at(clip, middle) < 0.08, segment
        elif segment.viseme == "aa":
            opens += 1
            assert _jaw_at(clip, middle) > 0.2, segment
    assert closures >= 5 and opens >= 3
    assert _jaw_at(clip, 0.0) < 0.05 and clip.values[-1, clip.channels.index("jawOpen")] < 0.01


def test_export_carries_the_sound_on_beside_another_format(spoken, tmp_path: Path, capsys) -> None:
    out, _ = spoken
    anim = tmp_path / "again.anim"
    assert main(["export", str(out), str(anim), "--audio", str(out.with_suffix(".wav"))]) == 0
    assert "sound beside it" in capsys.readouterr().out
    first, again = read_audio(out.with_suffix(".wav")), read_audio(tmp_path / "again.wav")
    assert first.samples.shape == again.samples.shape and first.sample_rate == again.sample_rate
    assert np.abs(first.samples - again.samples).max() <= 2 / 32768  # re-encoded as 16-bit PCM: within 1-2 steps
    assert read_clip(anim).n_frames == read_clip(out).n_frames


def test_export_warns_when_the_sound_outlasts_the_clip(spoken, tmp_path: Path, capsys) -> None:
    out, _ = spoken
    short = tmp_path / "short.json"
    assert main(["export", str(out), str(short), "--audio", str(out.with_suffix(".wav")), "--fps", "60"]) == 0
    capsys.readouterr()
    clip = read_clip(short)
    cut = tmp_path / "cut.json"
    from mien.exchange import format_module
    from mien.facs.clip import Clip

    format_module("clip_json").write(Clip(clip.values[:20], clip.fps, clip.channels), cut)
    assert main(["export", str(cut), str(tmp_path / "cut.csv"), "--audio", str(out.with_suffix(".wav"))]) == 0
    assert "the face stops" in capsys.readouterr().out
