"""Sources of timing: espeak-ng's phoneme events, timing files, OpenFaceFX tracks, audio alone."""

from __future__ import annotations

import json
import subprocess
import sys
import wave
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError, UnknownNameError
from mien.speech.audio import energy_envelope, read_audio, utterance_from_audio
from mien.speech.openfacefx import read_openfacefx
from mien.speech.timing_file import read_timing
from mien.speech.track import Audio, Utterance
from mien.speech.visemes import VISEMES


def _espeak() -> None:
    from mien.speech.espeak import voices

    try:
        voices()
    except MissingAssetError as error:
        pytest.skip(f"libespeak-ng not installed ({error})")


def test_my_mama_made_a_map_gives_the_issues_phonemes_and_times() -> None:
    _espeak()
    from mien.speech.espeak import speak

    utterance = speak("my mama made a map")
    phonemes = [s.phoneme for s in utterance.segments if not s.phoneme.startswith("_")]
    assert phonemes == "m aI m a m a# m eI d a# m a p".split()
    starts_ms = [round(s.start_s * 1000) for s in utterance.segments]
    assert starts_ms[0] == 0 and 940 <= starts_ms[12] <= 980  # /p/ at about 960 ms, as libespeak-ng reports it
    assert utterance.audio is not None and utterance.audio.sample_rate == 22050
    assert 0.9 < utterance.audio.duration_s < 1.3 and np.abs(utterance.audio.samples).max() > 0.1
    assert utterance.source == "espeak-ng" and utterance.text == "my mama made a map"


def test_espeak_refuses_empty_text_and_a_missing_language() -> None:
    _espeak()
    from mien.speech.espeak import speak, voices

    with pytest.raises(InvalidValueError, match="empty"):
        speak("   ")
    with pytest.raises(UnknownNameError, match="xx-nope") as caught:
        speak("hello", "xx-nope")
    assert "en-us" in caught.value.known and "de" in voices()
    german = speak("Guten Tag", "de")  # another voice works through the same events
    assert len(german.segments) > 5


def test_the_sound_is_kept_as_a_wav(spoken: Utterance, tmp_path: Path) -> None:
    assert spoken.audio is not None
    path = spoken.audio.write_wav(tmp_path / "s.wav")
    with wave.open(str(path)) as file:
        assert (file.getframerate(), file.getnchannels(), file.getsampwidth()) == (22050, 1, 2)
    again = read_audio(path)
    assert np.abs(again.samples - spoken.audio.samples).max() < 1e-4


def test_timing_file_json_and_csv_read_alike(tmp_path: Path) -> None:
    segments = [(0.0, 0.08, "m"), (0.08, 0.2, "a"), (0.2, 0.28, "p"), (0.28, 0.4, "_")]
    (tmp_path / "t.json").write_text(json.dumps({
        "format": "mien.speech.timing", "version": 1, "alphabet": "espeak",
        "segments": [{"start_s": a, "end_s": b, "unit": u} for a, b, u in segments],
    }))  # fmt: skip
    (tmp_path / "t.csv").write_text("# from some TTS\nstart_ms,end_ms,espeak\n" +
                                    "".join(f"{a * 1000:g},{b * 1000:g},{u}\n" for a, b, u in segments))  # fmt: skip
    from_json, from_csv = read_timing(tmp_path / "t.json"), read_timing(tmp_path / "t.csv")
    assert [s.viseme for s in from_json.segments] == ["PP", "aa", "PP", "sil"]
    assert from_json.segments == from_csv.segments
    assert np.allclose(from_json.track.weights, from_csv.track.weights)
    assert from_json.track.dominant()[round(0.14 * 100)] == "aa"


def test_timing_file_with_its_audio(tmp_path: Path) -> None:
    Audio(np.zeros(8820, np.float32), 22050).write_wav(tmp_path / "v.wav")
    (tmp_path / "t.json").write_text(json.dumps({
        "alphabet": "arpabet", "audio": "v.wav",
        "segments": [{"start_s": 0.0, "end_s": 0.1, "unit": "M"}, {"start_s": 0.1, "end_s": 0.3, "unit": "AA1"}],
    }))  # fmt: skip
    utterance = read_timing(tmp_path / "t.json")
    assert utterance.audio is not None and utterance.audio.duration_s == pytest.approx(0.4)
    assert utterance.duration_s == pytest.approx(0.4, abs=0.011)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("start_s,end_s,viseme\n0,0.1,PP\n0.05,0.2,aa\n", "no overlap"),
        ("start_s,end_s,viseme\n0,0.1,PP\n0.15,0.2,aa\n", "no gap"),
        ("start_frames,end_frames,viseme\n0,3,PP\n", "start_s,end_s"),
        ("start_s,end_s,viseme\n0,0.1,pp\n", "unknown viseme"),
        ("start_s,end_s,klingon\n0,0.1,pp\n", "unknown alphabet"),
        ("start_s,end_s,viseme\n0.1,0.1,PP\n", "0 <= start < end"),
    ],
)
def test_bad_timing_files(tmp_path: Path, text: str, match: str) -> None:
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises((InvalidValueError, UnknownNameError), match=match):
        read_timing(tmp_path / "bad.csv")


def test_openfacefx_output_is_read_as_a_track(tmp_path: Path) -> None:
    """A real track.json from the openfacefx package (its naive aligner), read as curves, not re-derived."""
    pytest.importorskip("openfacefx")
    Audio(np.zeros(22050 * 2, np.float32), 22050).write_wav(tmp_path / "v.wav")
    subprocess.run(
        [sys.executable, "-m", "openfacefx", "naive", "--text", "my mama made a map", "--wav",
         str(tmp_path / "v.wav"), "-o", str(tmp_path / "track.json")],
        check=True, capture_output=True, timeout=120,
    )  # fmt: skip
    data = json.loads((tmp_path / "track.json").read_text())
    utterance = read_openfacefx(tmp_path / "track.json", tmp_path / "v.wav")
    assert utterance.source == "openfacefx" and utterance.track.duration_s == pytest.approx(data["duration"], abs=0.011)
    pp = next(c for c in data["channels"] if c["name"] == "PP")
    t, value = max(pp["keys"], key=lambda key: key[1])  # the file's strongest PP key comes back at its time
    weights = utterance.track.weights[round(t * 100)]
    total = sum(max(c_keys[1] for c_keys in c["keys"] if abs(c_keys[0] - t) < 1e-9) if any(abs(k[0] - t) < 1e-9
                for k in c["keys"]) else 0.0 for c in data["channels"])  # fmt: skip
    assert weights[VISEMES.index("PP")] >= value / max(total, 1.0) - 0.05
    assert "PP" in utterance.track.dominant() and "aa" in utterance.track.dominant()


def test_openfacefx_refuses_other_json(tmp_path: Path) -> None:
    (tmp_path / "x.json").write_text('{"format": "something.else", "channels": []}')
    with pytest.raises(InvalidValueError, match=r"openfacefx\.track"):
        read_openfacefx(tmp_path / "x.json")


def _bursts(rate: int = 22050) -> Audio:
    """0.3 s tone, 0.3 s silence, 0.3 s tone, 0.3 s silence."""
    t = np.arange(int(0.3 * rate)) / rate
    tone = (0.5 * np.sin(2 * np.pi * 220 * t)).astype(np.float32)
    gap = np.zeros_like(tone)
    return Audio(np.concatenate([tone, gap, tone, gap]), rate)


def test_audio_alone_opens_the_jaw_with_energy_and_closes_in_silence() -> None:
    utterance = utterance_from_audio(_bursts())
    presence = utterance.track.presence
    jaw = utterance.track.face_clip().channel("AU26")
    assert presence[15] > 0.9 and presence[45] < 0.05 and presence[75] > 0.9 and presence[110] < 0.05
    envelope = energy_envelope(utterance.audio, 100.0)[: len(jaw)]  # type: ignore[arg-type]
    assert np.corrcoef(envelope, jaw[: len(envelope)])[0, 1] > 0.9


def test_compressed_audio_decodes_through_ffmpeg_and_garbage_is_refused(tmp_path: Path) -> None:
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg")
    _bursts().write_wav(tmp_path / "b.wav")
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(tmp_path / "b.wav"), "-c:a", "flac",
                    str(tmp_path / "b.flac")], check=True, timeout=60)  # fmt: skip
    flac = read_audio(tmp_path / "b.flac")
    assert flac.duration_s == pytest.approx(1.2, abs=0.01)
    (tmp_path / "junk.mp3").write_bytes(b"ID3" + bytes(range(256)) * 8)
    with pytest.raises(InvalidValueError, match="decode"):
        read_audio(tmp_path / "junk.mp3")
