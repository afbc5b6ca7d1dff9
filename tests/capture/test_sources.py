"""Every recording mien reads gives the same kind of captured clip: a track file, a Live Link CSV, an OpenFace
CSV, a variable-frame-rate recording, a neutral from a picture."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.capture import FACE_FOUND_CHANNEL, capture_file, capture_frames, capture_video, neutral_from_image
from mien.cli import main
from mien.errors import InvalidValueError
from mien.exchange import arkit_csv, openface_csv
from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, channel_index
from mien.facs.clip import Clip
from mien.tracking import track_video

SMILE = [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]


def test_a_live_link_csv_goes_through_the_same_stream(tmp_path: Path) -> None:
    n, fps = 60, 60.0
    weights = np.full((n, 52), 0.02)
    weights[30:, SMILE] = 0.9
    head = np.zeros((n, 3))
    head[:, 0] = np.linspace(0.0, 12.0, n)  # a slow head turn to the left
    clip = Clip(np.hstack([weights, head]), fps, (*ARKIT_NAMES, "head_yaw_deg", "head_pitch_deg", "head_roll_deg"))
    path = arkit_csv.write(clip, tmp_path / "take.csv")
    captured = capture_file(path)
    again = capture_frames("x", fps, np.arange(n) / fps, weights, head, np.ones(n, bool))
    assert captured.face_found.all() and captured.n_frames == n
    np.testing.assert_allclose(captured.frames, again.frames, atol=1e-3)  # the CSV's 0.001 s time stamps
    assert captured.frames[-1, channel_index("AU12L")] > 3.0
    # the neutral is the first 0.5 s: the head turned 0 to 6 degrees then, so yaw ends near 12 - 3 (less the
    # head filter's lag on a 12 degree/s ramp, about half a degree)
    assert captured.frames[-1, channel_index("head_yaw_deg")] == pytest.approx(12.0 - np.median(head[:31, 0]), abs=1.0)


def test_an_openface_csv_is_kept_as_read(shared_data: Path) -> None:
    path = shared_data / "formats" / "OpenFace_Test.csv"
    read = openface_csv.read(path)
    captured = capture_file(path)
    clip = captured.clip()
    assert clip.channels == (*FACE_CHANNELS, FACE_FOUND_CHANNEL) and clip.n_frames == read.n_frames
    np.testing.assert_allclose(clip.select(read.channels).values, read.values)
    assert not captured.weights.any()


@pytest.mark.parametrize("option", [["--route", "arkit"], ["--neutral", "0:1"], ["--no-filter"]])
def test_options_that_do_not_apply_to_an_openface_csv_are_refused(
    shared_data: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], option: list[str]
) -> None:
    path = str(shared_data / "formats" / "OpenFace_Test.csv")
    assert main(["capture", path, "-o", str(tmp_path / "x.npz"), *option]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and option[0] in err and "OpenFace's own AU intensities" in err


def test_a_track_file_gives_the_capture_of_its_video(shared_data: Path, landmarker_path: Path, tmp_path: Path) -> None:
    video = shared_data / "video" / "face_noface.mov"
    track = track_video(video, landmarker_path, show_progress=False)
    for suffix in (".npz", ".json"):
        from_file = capture_file(track.save(tmp_path / f"track{suffix}"))
        direct = capture_video(video, model=landmarker_path, show_progress=False)
        np.testing.assert_array_equal(from_file.face_found, direct.face_found)
        np.testing.assert_allclose(from_file.frames, direct.frames, atol=1e-4)


def test_a_variable_frame_rate_keeps_its_timing() -> None:
    rng = np.random.default_rng(7)
    times = np.cumsum(rng.choice([1 / 30, 1 / 24, 1 / 60], size=90))
    times -= times[0]
    scores = np.zeros((90, 52))
    onset_s = 1.5
    scores[times >= onset_s, SMILE[0]] = 0.8
    scores[times >= onset_s, SMILE[1]] = 0.8
    found = np.ones(90, bool)
    found[60:70] = False
    captured = capture_frames("vfr", 30.0, times, scores, np.zeros((90, 3)), found)
    clip = captured.clip()
    assert clip.fps == 30.0 and clip.n_frames == int(np.floor(times[-1] * 30.0 + 1e-6)) + 1
    au12 = clip.channel("AU12L")
    crossing = int(np.argmax(au12 > 0.5 * au12.max())) / 30.0
    assert abs(crossing - onset_s) <= 2 / 30.0  # the onset on its own time, not at frame index / rate
    mask = clip.channel(FACE_FOUND_CHANNEL)
    face = (clip.times_s <= times[59] + 1e-9) | (clip.times_s >= times[70] - 1e-9)
    assert (~face).sum() >= 8 and mask[~face].max() == 0.0 and mask[face].min() == 1.0


def test_a_neutral_from_a_picture(shared_data: Path, landmarker_path: Path) -> None:
    neutral = neutral_from_image(shared_data / "images" / "single_face.jpg", landmarker_path)
    assert neutral.shape == (55,) and neutral[SMILE].min() > 0.5  # that picture smiles: its smile is "neutral"
    captured = capture_video(
        shared_data / "video" / "single_face.mp4", neutral=neutral, model=landmarker_path, show_progress=False
    )
    assert captured.frames[:, channel_index("AU12L")].max() < 2.0  # against a smiling neutral, little smile left
    with pytest.raises(InvalidValueError, match="neutral image"):
        neutral_from_image(shared_data / "formats" / "OpenFace_Test.csv", landmarker_path)
