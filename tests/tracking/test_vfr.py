"""Variable frame rate: time comes from each frame's time stamp (pts x time_base), never from an average rate."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from tests.videos import encode_with_pts

from mien.errors import InvalidValueError
from mien.tracking.track import Track, apply_gaps, fill_gaps, resample_on_times, track_video
from mien.tracking.video import iter_frames, probe

INTERVALS_MS = (10, 50, 20, 80, 40)
"""A deliberately irregular frame spacing, milliseconds."""


def test_irregular_time_stamps_come_back_exactly(tmp_path: Path) -> None:
    n = 30
    pts = np.concatenate([[0], np.cumsum([INTERVALS_MS[i % len(INTERVALS_MS)] for i in range(n - 1)])]).tolist()
    frames = [np.full((64, 64, 3), 8 * i, np.uint8) for i in range(n)]  # brightness numbers the frame
    video = tmp_path / "vfr.mp4"
    encode_with_pts(video, frames, pts, Fraction(1, 1000))
    decoded = list(iter_frames(video))
    times = np.array([t for t, _ in decoded])
    assert len(decoded) == n
    assert np.allclose(times, np.array(pts) / 1000.0, atol=1e-6)  # the real times, not i / average rate
    brightness = np.array([rgb.mean() for _, rgb in decoded])
    assert np.allclose(brightness, 8 * np.arange(n), atol=3)  # and the frames in presentation order
    average = probe(video).fps
    assert not np.allclose(times, np.arange(n) / average, atol=5e-3)  # an average rate would have lost this


def test_gaps_are_measured_in_real_time() -> None:
    found = np.array([1, 0, 0, 1, 1, 0, 0, 1], bool)
    # Two missing frames each time; the first gap spans 0.1 s, the second 0.5 s of real time.
    times = np.array([0.0, 0.05, 0.1, 0.15, 0.2, 0.45, 0.7, 0.7 + 0.25])
    filled, takes = fill_gaps(found, fps=20.0, max_gap_s=0.2, times_s=times)
    assert filled.tolist() == [0, 1, 1, 0, 0, 0, 0, 0] and takes == [(0, 5), (7, 8)]
    # At a constant rate the same frames count k / fps, as before.
    assert fill_gaps(found, fps=20.0, max_gap_s=0.2)[1] == [(0, 8)]


def test_filled_values_interpolate_on_real_times() -> None:
    n = 4
    times = np.array([0.0, 0.1, 0.4, 0.5])  # the missing frame lies a quarter of the way from 0.0 s to 0.4 s
    found = np.array([1, 0, 1, 1], bool)
    pose = np.zeros((n, 3))
    pose[:, 0] = [0.0, np.nan, 40.0, 50.0]
    raw = Track(
        source="/x.mp4",
        fps=10.0,
        width=8,
        height=8,
        timestamps_s=times,
        landmarks=np.zeros((n, 478, 3), np.float32),
        blendshapes=np.zeros((n, 52), np.float32),
        head_pose_deg=pose,
        face_found=found,
        interpolated=np.zeros(n, bool),
        takes=(),
    )
    track = apply_gaps(raw, max_gap_s=0.5)
    assert track.interpolated.tolist() == [False, True, False, False]
    assert track.head_pose_deg[1, 0] == pytest.approx(10.0)  # 0.1 s of 0.4 s: a quarter, not the half by index
    assert track.duration_s == pytest.approx(0.6)


def test_resample_on_times() -> None:
    times = np.array([0.0, 0.01, 0.06, 0.08, 0.16, 0.2])
    values = np.stack([times * 10.0, -times], axis=1)  # linear in time: resampling must stay on the line
    grid = resample_on_times(times, values, 50.0)
    assert grid.shape == (11, 2)
    assert np.allclose(grid[:, 0], np.arange(11) / 50.0 * 10.0) and np.allclose(grid[:, 1], -np.arange(11) / 50.0)
    regular = np.arange(5) / 30.0
    same = np.random.default_rng(0).normal(size=(5, 68, 2))
    assert np.array_equal(resample_on_times(regular, same, 30.0), same)  # a constant-rate take is unchanged
    with pytest.raises(InvalidValueError, match="times_s"):
        resample_on_times(np.array([0.0, 0.1, 0.1]), np.zeros(3), 30.0)


def test_a_variable_rate_copy_of_a_real_video_keeps_its_timing(
    single_face_video: Path, landmarker_path: Path, tmp_path: Path
) -> None:
    """Drop frames of the real smile video unevenly, keep the survivors' time stamps: the smile still starts
    at the same second, and the laughter controllers come out on a regular grid over the real duration."""
    import av

    with av.open(str(single_face_video)) as source:
        stream = source.streams.video[0]
        time_base = stream.time_base
        assert time_base is not None
        decoded = [(int(frame.pts or 0), frame.to_ndarray(format="rgb24")) for frame in source.decode(stream)]
    keep = [i for i in range(len(decoded)) if i < 20 or i % 3 == 0]  # 30 fps, then 10 fps
    vfr = tmp_path / "smile_vfr.mp4"
    first_pts = decoded[0][0]
    encode_with_pts(vfr, [decoded[i][1] for i in keep], [decoded[i][0] - first_pts for i in keep], time_base)

    original = track_video(single_face_video, landmarker_path, use_cache=False, show_progress=False)
    variable = track_video(vfr, landmarker_path, use_cache=False, show_progress=False)
    assert variable.n_frames == len(keep)
    assert np.allclose(variable.timestamps_s, original.timestamps_s[keep], atol=1e-3)
    assert variable.duration_s == pytest.approx(original.duration_s, abs=0.07)

    def onset_s(track: Track) -> float:
        from mien.facs.arkit import ARKIT_INDEX

        columns = [ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]
        smile = track.blendshapes[:, columns].mean(axis=1)
        return float(track.timestamps_s[int(np.argmax(smile > 0.4))])

    assert onset_s(variable) == pytest.approx(onset_s(original), abs=0.1)  # 3 frames at the sparse rate
    from mien.learning.takes import controllers_from_track

    (curves,) = controllers_from_track(variable)
    assert curves.fps == pytest.approx(variable.fps)
    assert curves.n_frames == int(np.floor(variable.timestamps_s[-1] * variable.fps + 1e-6)) + 1


def test_segments_of_a_variable_rate_video_keep_every_time_stamp(tmp_path: Path) -> None:
    """The parallel tracker's segments (mien.tracking.parallel) read an irregular video's frames with the same
    time stamps, to the bit, as one reader."""
    from mien.tracking.video import iter_segment, plan_segments

    rng = np.random.default_rng(3)
    frames = [rng.integers(0, 255, (48, 64, 3), dtype=np.uint8) for _ in range(30)]
    stamps = np.concatenate([[0], np.cumsum([INTERVALS_MS[i % len(INTERVALS_MS)] for i in range(29)])]).tolist()
    video = tmp_path / "vfr.mp4"
    encode_with_pts(video, frames, stamps, Fraction(1, 1000))
    whole = [t for t, _ in iter_frames(video)]
    plan = plan_segments(video, 3, warmup_frames=2)
    assert plan is not None
    origin_s, segments = plan
    joined = [t for segment in segments for t, _, warm in iter_segment(video, segment, origin_s) if not warm]
    assert joined == whole and np.allclose(np.diff(whole), np.diff(stamps) / 1000.0)
