"""Benchmark: offline capture (decode + MediaPipe tracking + capture solve and filter) against tracking alone.

On data/video/single_face.mp4 (2.4 s, 30 fps, 640x360), cache disabled, REPEATS interleaved rounds after a
warm-up; each round times, on the same frames:
- the named baseline "tracking alone": :func:`mien.tracking.track_video` (decode in a thread + MediaPipe);
- "capture_video": tracking + :func:`mien.capture.capture_track` (the CaptureStream per frame: One Euro filter,
  neutral, reverse AU mapping by NNLS) - what ``mien capture`` runs;
- "solve + filter": capture_track alone on the round's track (the capture's own cost).
Prints medians and spread (min..max), capture_video against real time (target >= 4x) and the capture's cost on
top of tracking (target <= 10%), both as the ratio of whole runs and as solve + filter / tracking per round.

Run: .venv/bin/python bench/capture_speed.py [VIDEO] [REPEATS] (needs the shared data and face_landmarker.task,
found through $MIEN_SHARED or ../shared, and $MIEN_FACE_LANDMARKER or the shared model).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path


def _shared() -> Path:
    return Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))


def _spread(values: list[float], scale: float = 1.0, unit: str = "") -> str:
    return (
        f"median {statistics.median(values) * scale:8.3f}{unit}  "
        f"(min {min(values) * scale:.3f}, max {max(values) * scale:.3f})"
    )


def main() -> int:
    """Run the benchmark and print the results."""
    from mien.capture import capture_track
    from mien.paths import asset_path
    from mien.tracking.track import track_video
    from mien.tracking.video import probe

    video = Path(sys.argv[1]) if len(sys.argv) > 1 else _shared() / "data" / "video" / "single_face.mp4"
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    model = asset_path("face_landmarker") or _shared() / "models" / "face_landmarker.task"
    info = probe(video)

    def tracking() -> object:
        return track_video(video, model, use_cache=False, show_progress=False)

    capture_track(tracking())  # warm-up: file cache, model load, XNNPACK, scipy
    track_s: list[float] = []
    capture_s: list[float] = []
    solve_s: list[float] = []
    n_frames = 0
    for _ in range(repeats):
        start = time.perf_counter()
        track = tracking()
        track_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        capture = capture_track(tracking())  # = capture_video(video, use_cache=False)
        capture_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        capture_track(track)
        solve_s.append(time.perf_counter() - start)
        n_frames = capture.n_frames
    duration_s = n_frames / info.fps
    print(
        f"video: {video.name}, {n_frames} frames, {info.width}x{info.height} at {info.fps:g} fps ({duration_s:.2f} s)"
    )
    print(f"{repeats} interleaved rounds after a warm-up, cache disabled, {os.cpu_count()} CPUs")
    print(f"  baseline tracking alone (decode + MediaPipe) : {_spread(track_s, 1000, ' ms')}")
    print(f"  capture_video (tracking + solve + filter)    : {_spread(capture_s, 1000, ' ms')}")
    print(f"  solve + filter alone (capture_track)         : {_spread(solve_s, 1000, ' ms')}")
    per_frame = [s / n_frames for s in solve_s]
    print(f"  solve + filter per frame                     : {_spread(per_frame, 1e6, ' us')}")
    real_time = [duration_s / s for s in capture_s]
    print(f"  capture_video vs real time                   : {_spread(real_time, 1, 'x')}  (target >= 4x)")
    whole = [c / t - 1.0 for c, t in zip(capture_s, track_s, strict=True)]
    print(f"  capture_video / tracking - 1 (whole runs)    : {_spread(whole, 100, ' %')}  (target <= 10%)")
    share = [s / t for s, t in zip(solve_s, track_s, strict=True)]
    print(f"  solve + filter / tracking (same round)       : {_spread(share, 100, ' %')}  (target <= 10%)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
