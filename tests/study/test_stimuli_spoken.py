"""Spoken stimuli: a design's ``say`` sentence spoken in every rendered stimulus, its emotion the condition.

The MP4s carry the sound, starting at the design's onset (decoded back with PyAV, within a video frame); the
manifest records the text and the timing source; a changed sentence renders again; bad ``say`` entries and a
voice espeak-ng lacks exit 2 with one line naming the file and key.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mien.cli import main
from mien.render.video import read_video_info
from mien.study.design import load_design
from mien.study.stimuli import make_stimuli

espeak = pytest.importorskip("mien.speech.espeak")
av = pytest.importorskip("av", reason="PyAV is not installed (track extra)")

SENTENCE = "my mama made a map"
FPS = 15
SPOKEN = f"""
[study]
name = "spoken"
protocol = "broekens"
[stimuli]
expressions = ["joy", "sadness"]
heads = ["builtin"]
duration_s = 0.8
onset_s = 0.3
fps = {FPS}
size = 48
say = "{SENTENCE}"
"""


def _sound(video: Path) -> tuple[np.ndarray, int]:
    """The video's audio track decoded to mono float samples, and its rate."""
    with av.open(str(video)) as container:
        assert container.streams.audio, f"{video.name} has no sound"
        stream = container.streams.audio[0]
        chunks = [frame.to_ndarray().astype(np.float64).mean(axis=0) for frame in container.decode(stream)]
        return np.concatenate(chunks), int(stream.rate)


def _first_loud_s(samples: np.ndarray, rate: int) -> float:
    """Seconds to the first 10 ms window whose RMS reaches a tenth of the loudest window's."""
    hop = rate // 100
    windows = samples[: len(samples) // hop * hop].reshape(-1, hop)
    rms = np.sqrt((windows**2).mean(axis=1))
    return float(np.argmax(rms >= 0.1 * rms.max()) * hop / rate)


def test_spoken_stimuli_carry_the_sound_from_the_onset(tmp_path: Path) -> None:
    try:
        utterance = espeak.speak(SENTENCE)
    except Exception as exc:  # MissingAssetError without libespeak-ng
        pytest.skip(f"espeak-ng cannot speak here: {exc}")
    design_path = tmp_path / "design.toml"
    design_path.write_text(SPOKEN)
    design = load_design(design_path)
    assert design.say is not None and design.say.text == SENTENCE
    result = make_stimuli(design, progress=False)
    folder = tmp_path / "stimuli"
    entries = result.manifest["stimuli"]
    assert [e["expression"] for e in entries] == ["joy", "sadness"]  # the emotion is the condition
    expected_s = 0.3 + utterance.duration_s + 0.4  # onset, the sentence, its tail
    for entry in entries:
        speech = entry["speech"]
        assert speech["text"] == SENTENCE and speech["timing_source"] == "espeak-ng"
        assert speech["language"] == "en" and speech["onset_s"] == 0.3
        assert speech["duration_s"] == pytest.approx(utterance.duration_s, abs=0.01)
        video = folder / entry["file"]
        info = read_video_info(video)
        assert abs(info.n_frames / FPS - expected_s) <= 1.0 / FPS  # the whole sentence, past duration_s
        assert entry["duration_s"] == pytest.approx(info.n_frames / FPS)
        samples, rate = _sound(video)
        assert len(samples) / rate == pytest.approx(0.3 + utterance.audio.duration_s, abs=0.05)
        loud_offline = _first_loud_s(utterance.audio.samples.astype(np.float64), utterance.audio.sample_rate)
        assert abs(_first_loud_s(samples, rate) - (0.3 + loud_offline)) <= 1.0 / FPS  # in sync with the frames
    assert not list(folder.glob(".*.silent.mp4"))  # the silent intermediates are gone
    assert json.loads((folder / "manifest.json").read_text()) == result.manifest
    # a re-run keeps them; another sentence renders them again
    kept = make_stimuli(design, progress=False)
    assert (kept.rendered, kept.skipped) == (0, 2)
    design_path.write_text(SPOKEN.replace(SENTENCE, "a map"))
    again = make_stimuli(load_design(design_path), progress=False)
    assert (again.rendered, again.skipped) == (2, 0)
    assert again.manifest["stimuli"][0]["speech"]["text"] == "a map"


@pytest.mark.parametrize(
    ("say", "named"),
    [
        ('say = ""', "stimuli.say.text"),
        ('say = { text = "hi", language = "en us" }', "stimuli.say.language"),
        ('say = { text = "hi", rate_wpm = 5 }', "stimuli.say.rate_wpm"),
        ('say = { text = "hi", voice = "x" }', "voice"),
        ('say = { text = "hi", language = "xx" }', "espeak-ng"),
    ],
)
def test_bad_say_entries_exit_2_naming_the_key(tmp_path: Path, capsys, say: str, named: str) -> None:
    design = tmp_path / "design.toml"
    design.write_text(SPOKEN.replace(f'say = "{SENTENCE}"', say))
    assert main(["study", "stimuli", str(design), "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mien study: error:") and named in err[0], err
    assert not (tmp_path / "out" / "manifest.json").exists()


def test_say_is_refused_where_it_cannot_apply(tmp_path: Path) -> None:
    from mien.errors import InvalidValueError

    mascaro = tmp_path / "mascaro.toml"
    mascaro.write_text('[study]\nname = "m"\nprotocol = "mascaro"\n[stimuli]\nsay = "hello"\n')
    with pytest.raises(InvalidValueError, match=r"stimuli\.say"):
        load_design(mascaro)
    files = tmp_path / "files.toml"
    files.write_text(
        '[study]\nname = "f"\n[stimuli]\nsource = "files"\nsay = "hello"\n'
        '[[stimuli.file]]\npath = "a.mp4"\nexpression = "joy"\n'
    )
    with pytest.raises(InvalidValueError, match=r"stimuli\.say"):
        load_design(files)
