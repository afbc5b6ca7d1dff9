"""Tracking whole videos: Track contents, faces coming and going, gaps, takes, cache, files."""

from __future__ import annotations

import os
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mien.tracking.track as track_module
from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_INDEX
from mien.tracking.track import Track, apply_gaps, fill_gaps, load_track, track_video


@pytest.fixture(scope="module")
def smile_track(single_face_video: Path, landmarker_path: Path) -> Track:
    return track_video(single_face_video, landmarker_path, use_cache=False, show_progress=False)


def _track(shared_data: Path, landmarker_path: Path, name: str) -> Track:
    return track_video(shared_data / "video" / name, landmarker_path, use_cache=False, show_progress=False)


def test_single_face_track(smile_track: Track) -> None:
    assert smile_track.n_frames == 72 and smile_track.fps == 30.0
    assert (smile_track.width, smile_track.height) == (640, 360)
    assert smile_track.face_found.all() and not smile_track.interpolated.any()
    assert smile_track.takes == ((0, 72),)
    assert smile_track.landmarks.shape == (72, 478, 3) and np.isfinite(smile_track.landmarks).all()
    assert smile_track.landmarks_px[..., 0].max() < 640 and smile_track.landmarks_px[..., 1].max() < 360
    assert smile_track.head_pose_deg.shape == (72, 3) and np.all(np.abs(smile_track.head_pose_deg) < 15)
    smile = smile_track.blendshapes[:, [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]].mean(axis=1)
    assert smile[:15].mean() < 0.1 and smile[-30:].mean() > 0.6  # the person breaks into a smile
    assert Path(smile_track.source).is_absolute()


def test_no_face_video_gives_zero_takes(shared_data: Path, landmarker_path: Path) -> None:
    track = _track(shared_data, landmarker_path, "no_face.mp4")
    assert track.n_frames > 90 and not track.face_found.any() and track.takes == ()
    assert np.isnan(track.landmarks).all()
    assert "no face found on any frame: 0 takes" in track.report()


def test_face_then_no_face(shared_data: Path, landmarker_path: Path) -> None:
    track = _track(shared_data, landmarker_path, "face_noface.mov")
    found = track.face_found
    assert found[:60].all() and not found[-60:].any()
    assert len(track.takes) == 1 and track.takes[0][0] == 0 and 60 <= track.takes[0][1] < track.n_frames - 60
    assert np.isnan(track.landmarks[-1]).all() and np.isfinite(track.landmarks[0]).all()
    assert "1 take(s)" in track.report()


def test_no_face_then_face(shared_data: Path, landmarker_path: Path) -> None:
    track = _track(shared_data, landmarker_path, "noface_face.mov")
    found = track.face_found
    assert not found[:80].any() and found[100:160].all()
    assert len(track.takes) == 1 and 80 <= track.takes[0][0] <= 100


def test_fill_gaps_rules() -> None:
    found = np.array([0, 1, 1, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0], bool)
    filled, takes = fill_gaps(found, fps=10.0, max_gap_s=0.2)  # up to 2 missing frames are filled
    assert filled.tolist() == [0, 0, 0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0]
    assert takes == [(1, 6), (10, 12)]
    assert fill_gaps(found, 10.0, 0.0)[1] == [(1, 3), (5, 6), (10, 12)]
    assert fill_gaps(found, 10.0, 1.0)[1] == [(1, 12)]
    assert fill_gaps(np.zeros(5, bool), 10.0)[1] == []
    with pytest.raises(InvalidValueError, match="max_gap_s"):
        fill_gaps(found, 10.0, -1.0)


def test_short_gaps_are_interpolated_long_ones_split(smile_track: Track) -> None:
    found = smile_track.face_found.copy()
    found[20:23] = False  # 0.1 s: filled
    found[40:50] = False  # 0.33 s: splits
    holed = replace(smile_track, face_found=found)
    track = apply_gaps(holed, max_gap_s=0.2)
    assert track.takes == ((0, 40), (50, 72))
    assert track.interpolated[20:23].all() and track.interpolated.sum() == 3
    assert np.isnan(track.landmarks[40:50]).all()
    # Interpolated landmarks sit close to what was actually tracked there (the face barely moves in 0.1 s).
    error_px = np.abs(track.landmarks_px[20:23, :, :2] - smile_track.landmarks_px[20:23, :, :2]).max()
    assert error_px < 8.0
    expected = smile_track.landmarks[19] + (smile_track.landmarks[23] - smile_track.landmarks[19]) * 0.5
    assert np.allclose(track.landmarks[21], expected, atol=1e-6)
    # Re-applying with no gap tolerance empties the filled frames again.
    strict = apply_gaps(track, 0.0)
    assert not strict.interpolated.any() and np.isnan(strict.landmarks[21]).all() and len(strict.takes) == 3


def test_cache_makes_the_second_run_identical_without_tracking(
    single_face_video: Path, landmarker_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    video = tmp_path / "copy.mp4"
    shutil.copyfile(single_face_video, video)
    first = track_video(video, landmarker_path, show_progress=False)

    def no_tracking(*args: object, **kwargs: object) -> Track:
        raise AssertionError("tracked again instead of using the cache")

    monkeypatch.setattr(track_module, "_track_frames", no_tracking)
    second = track_video(video, landmarker_path, show_progress=False)
    for key, value in first.arrays().items():
        assert np.array_equal(value, second.arrays()[key], equal_nan=value.dtype.kind == "f"), key
    assert second.takes == first.takes and second.meta() == first.meta()
    # Gap options are re-applied on the cached per-frame result, without tracking again.
    assert track_video(video, landmarker_path, max_gap_s=1.0, show_progress=False).max_gap_s == 1.0
    # A changed file (new modification time) is tracked again.
    os.utime(video, ns=(video.stat().st_atime_ns, video.stat().st_mtime_ns + 10**9))
    with pytest.raises(AssertionError, match="tracked again"):
        track_video(video, landmarker_path, show_progress=False)
    # --no-cache tracks again too.
    with pytest.raises(AssertionError, match="tracked again"):
        track_video(single_face_video, landmarker_path, use_cache=False, show_progress=False)


@pytest.mark.parametrize("suffix", [".npz", ".json"])
def test_save_and_load(smile_track: Track, tmp_path: Path, suffix: str) -> None:
    found = smile_track.face_found.copy()
    found[30:40] = False
    track = apply_gaps(replace(smile_track, face_found=found))
    path = track.save(tmp_path / f"track{suffix}")
    loaded = load_track(path)
    assert loaded.takes == track.takes and loaded.meta() == track.meta()
    assert np.array_equal(loaded.face_found, track.face_found)
    atol = 1e-6 if suffix == ".json" else 0.0
    assert np.allclose(loaded.landmarks, track.landmarks, atol=atol, equal_nan=True)
    assert np.allclose(loaded.head_pose_deg, track.head_pose_deg, atol=atol, equal_nan=True)
    if suffix == ".npz":
        with np.load(path) as data:
            assert data["landmarks_px"].shape == (72, 478, 3)


def test_bad_inputs_name_the_file(single_face_video: Path, landmarker_path: Path, tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.mov"
    garbage.write_bytes(os.urandom(4096))
    with pytest.raises(InvalidValueError, match=r"garbage\.mov"):
        track_video(garbage, landmarker_path, show_progress=False)
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(single_face_video.read_bytes()[:50_000])
    with pytest.raises(InvalidValueError, match=r"truncated\.mp4"):
        track_video(truncated, landmarker_path, show_progress=False)
    with pytest.raises(InvalidValueError, match="max_gap_s"):
        track_video(single_face_video, landmarker_path, max_gap_s=float("nan"))
    with pytest.raises(InvalidValueError, match="output"):
        Track.save(_tiny_track(), tmp_path / "x.csv")
    with pytest.raises(InvalidValueError, match=r"track file"):
        load_track(garbage)


def _tiny_track() -> Track:
    """A tiny synthetic track (for argument checks)."""
    n = 2
    return Track(
        source="/x.mp4",
        fps=30.0,
        width=10,
        height=10,
        timestamps_s=np.arange(n) / 30.0,
        landmarks=np.zeros((n, 478, 3), np.float32),
        blendshapes=np.zeros((n, 52), np.float32),
        head_pose_deg=np.zeros((n, 3)),
        face_found=np.ones(n, bool),
        interpolated=np.zeros(n, bool),
        takes=((0, n),),
    )


def test_damaged_cache_entry_is_replaced(
    single_face_video: Path, landmarker_path: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("MIEN_CACHE_DIR", str(tmp_path / "cache"))
    first = track_video(single_face_video, landmarker_path, show_progress=False)
    (entry,) = (tmp_path / "cache" / "tracks").glob("*.npz")
    entry.write_bytes(b"PK\x03\x04 damaged")
    again = track_video(single_face_video, landmarker_path, show_progress=False)
    assert np.array_equal(again.landmarks, first.landmarks) and entry.stat().st_size > 1000
