"""Tracking in parallel worker processes: segments cover every frame once, results equal the sequential run's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mien.tracking.parallel as parallel_module
from mien.errors import InvalidValueError
from mien.tracking.parallel import MIN_FRAMES_PER_WORKER, check_workers, default_workers, usable_cpus
from mien.tracking.track import Track, track_video
from mien.tracking.video import iter_frames, iter_segment, plan_segments

BLENDSHAPE_TOLERANCE = 0.05
"""Largest blendshape score difference allowed between a parallel and the sequential run on any frame. A later
segment's landmarker starts on its warm-up frames by detecting the face afresh, where the sequential run had
tracked it: bench/tracking.py measures 0.03 at the joins of the shared videos, fading over ~10 frames; away from
the joins the runs are identical."""

LANDMARK_TOLERANCE = 0.006
"""Largest landmark difference allowed (normalised coordinates; 0.006 is under 6 px on a 960-pixel-wide frame)."""


@pytest.mark.parametrize(("name", "n_segments"), [("single_face.mp4", 3), ("face_noface.mov", 4), ("no_face.mp4", 2)])
def test_segments_decode_every_frame_once(shared_data: Path, name: str, n_segments: int) -> None:
    """One keyframe with B-frames (mp4), a keyframe every 30 frames (HEVC mov), an edit list dropping the first
    packets (no_face.mp4): the segments' frames, joined, are the whole video's, pixel for pixel, with the same
    time stamps to the bit; warm-up frames come just before each later segment."""
    video = shared_data / "video" / name
    whole = list(iter_frames(video))
    plan = plan_segments(video, n_segments, warmup_frames=3)
    assert plan is not None
    origin_s, segments = plan
    assert len(segments) == n_segments and segments[0].seek_pts is None
    joined = []
    for segment in segments:
        frames = list(iter_segment(video, segment, origin_s))
        warm = [f for f in frames if f[2]]
        assert len(warm) == (0 if segment.index == 0 else 3) and all(f[2] for f in frames[: len(warm)])
        assert frames[len(warm)][0] == whole[segment.first_frame][0]
        joined += [f for f in frames if not f[2]]
    assert [t for t, _, _ in joined] == [t for t, _ in whole]
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(joined, whole, strict=True))


def test_short_or_unsplittable_videos_are_not_planned(shared_data: Path, tmp_path: Path) -> None:
    video = shared_data / "video" / "single_face.mp4"
    assert plan_segments(video, 1) is None
    assert plan_segments(video, 40) is None  # fewer than two frames per segment
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(video.read_bytes()[:50_000])
    assert plan_segments(truncated, 2) is None  # read whole, which raises the usual error


@pytest.fixture(scope="module")
def sequential(shared_data: Path, landmarker_path: Path) -> Track:
    return track_video(shared_data / "video" / "face_noface.mov", landmarker_path, use_cache=False, workers=1)


@pytest.mark.slow
def test_parallel_equals_sequential(sequential: Track, landmarker_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """face_noface.mov in 3 processes, even segments: joins at frame 56 (a face) and 113 (none); HEVC keyframes
    every 30 frames."""
    monkeypatch.setattr(parallel_module, "LEAD_FRAMES", 0)
    parallel = track_video(sequential.source, landmarker_path, use_cache=False, show_progress=False, workers=3)
    assert np.array_equal(parallel.timestamps_s, sequential.timestamps_s)
    assert np.array_equal(parallel.face_found, sequential.face_found)
    assert parallel.takes == sequential.takes
    assert np.array_equal(parallel.interpolated, sequential.interpolated)
    both = sequential.tracked
    assert both[56] and not both[113]
    scores = np.abs(parallel.blendshapes[both] - sequential.blendshapes[both])
    assert scores.max() < BLENDSHAPE_TOLERANCE
    assert np.abs(parallel.landmarks[both] - sequential.landmarks[both]).max() < LANDMARK_TOLERANCE
    assert np.array_equal(parallel.blendshapes[:50], sequential.blendshapes[:50])  # the first segment: same run
    assert np.isnan(parallel.landmarks[~both]).all()
    assert np.abs(parallel.head_pose_deg[both] - sequential.head_pose_deg[both]).max() < 2.0


def test_one_worker_is_the_plain_sequential_loop(shared_data: Path, landmarker_path: Path) -> None:
    """workers=1 (the default for a 2.4 s video) is one landmarker over iter_frames, bit for bit."""
    from mien.tracking.landmarker import Landmarker

    video = shared_data / "video" / "single_face.mp4"
    assert default_workers(72) == 1
    track = track_video(video, landmarker_path, use_cache=False, show_progress=False)
    with Landmarker(landmarker_path, mode="video") as landmarker:
        results = [(t, landmarker.detect(rgb, t)) for t, rgb in iter_frames(video)]
    assert track.timestamps_s.tolist() == [t for t, _ in results]
    assert all(r is not None for _, r in results)
    assert np.array_equal(track.blendshapes, np.stack([r.blendshapes for _, r in results if r is not None]))
    assert np.array_equal(track.landmarks, np.stack([r.landmarks for _, r in results if r is not None]))


@pytest.mark.slow
def test_truncated_video_errors_the_same_way(single_face_video: Path, landmarker_path: Path, tmp_path: Path) -> None:
    """Cut in the middle: the parallel request gives the sequential run's error, word for word."""
    truncated = tmp_path / "truncated.mp4"
    truncated.write_bytes(single_face_video.read_bytes()[:120_000])
    messages = []
    for workers in (1, 2):
        with pytest.raises(InvalidValueError, match=r"truncated\.mp4") as caught:
            track_video(truncated, landmarker_path, use_cache=False, show_progress=False, workers=workers)
        messages.append(str(caught.value))
    assert messages[0] == messages[1]


def test_worker_counts() -> None:
    assert default_workers(0) == 1 and default_workers(2 * MIN_FRAMES_PER_WORKER - 1) == 1
    assert default_workers(100_000) == min(usable_cpus(), 8)
    check_workers(None)
    check_workers(3)
    for bad in (0, -1, 1.5, True, "2"):
        with pytest.raises(InvalidValueError, match="workers"):
            check_workers(bad)  # type: ignore[arg-type]


def _children(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (from /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    found.append(int(entry.name))
            except (OSError, IndexError, ValueError):
                continue
    return found


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process tree from /proc")
def test_sigterm_stops_the_workers(shared_data: Path, landmarker_path: Path) -> None:
    """SIGTERM a second into `mien track --workers 2` (face_noface.mov: 169 frames, 960x540): exit 130
    ("interrupted") and no worker process left."""
    import signal
    import subprocess
    import sys
    import time

    video = shared_data / "video" / "face_noface.mov"
    command = [sys.executable, "-m", "mien.cli", "track", str(video), "--landmarker", str(landmarker_path)]
    process = subprocess.Popen([*command, "--workers", "2", "--no-cache", "--quiet"], stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    children: list[int] = []
    while not children and process.poll() is None and time.monotonic() < deadline:
        children = _children(process.pid)
        time.sleep(0.02)
    assert children, "the worker processes never started"
    time.sleep(1.0)
    assert process.poll() is None, "tracking finished before the signal"
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130 and "interrupted" in err
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_running(pid) for pid in children):
        time.sleep(0.05)
    assert not [pid for pid in children if _running(pid)]


def _running(pid: int) -> bool:
    """The process exists and is not a zombie (exited, waiting to be reaped)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False
