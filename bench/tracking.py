"""Benchmark: tracking a video (decode + MediaPipe Face Landmarker), cache disabled.

Prints, as the median of REPEATS runs after a warm-up run on data/video/single_face.mp4 (2.4 s, 30 fps, 640x360):
- the named baseline "decode only" (PyAV to RGB arrays, nothing else);
- "landmarker only" on frames decoded beforehand (the model's own cost);
- "track_video" (decode in a thread + landmarker + gap filling), its processed fps and the ratio to real time
  (target >= 2x), and its time over the decode-only baseline.

Run: .venv/bin/python bench/tracking.py [VIDEO] (needs the shared data and face_landmarker.task, found through
$MIEN_SHARED or ../shared, and $MIEN_FACE_LANDMARKER or the shared model).
"""

from __future__ import annotations

import os
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

REPEATS = 3


def _shared() -> Path:
    return Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))


def _median_s(work: Callable[[], object]) -> float:
    work()  # warm-up: file cache, model load, XNNPACK setup
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> int:
    """Run the benchmark and print the results."""
    from mien.paths import asset_path
    from mien.tracking.landmarker import Landmarker
    from mien.tracking.track import track_video
    from mien.tracking.video import iter_frames, probe

    video = Path(sys.argv[1]) if len(sys.argv) > 1 else _shared() / "data" / "video" / "single_face.mp4"
    model = asset_path("face_landmarker") or _shared() / "models" / "face_landmarker.task"
    info = probe(video)
    frames = list(iter_frames(video))
    n = len(frames)
    duration_s = n / info.fps

    decode_s = _median_s(lambda: sum(1 for _ in iter_frames(video)))

    def landmarker_only() -> None:
        with Landmarker(model, mode="video") as landmarker:
            for time_s, rgb in frames:
                landmarker.detect(rgb, time_s)

    landmark_s = _median_s(landmarker_only)
    track_s = _median_s(lambda: track_video(video, model, use_cache=False, show_progress=False))

    print(f"video: {video.name}, {n} frames, {info.width}x{info.height} at {info.fps:g} fps ({duration_s:.2f} s)")
    print(f"median of {REPEATS} runs after a warm-up, cache disabled")
    print(f"  baseline decode only : {decode_s * 1000:8.1f} ms  {n / decode_s:7.1f} fps")
    print(f"  landmarker only      : {landmark_s * 1000:8.1f} ms  {n / landmark_s:7.1f} fps")
    print(f"  track_video          : {track_s * 1000:8.1f} ms  {n / track_s:7.1f} fps")
    print(f"  track_video vs real time        : {duration_s / track_s:5.2f}x (target >= 2x)")
    print(f"  track_video / decode-only time  : {track_s / decode_s:5.2f}x")
    overlap = (decode_s + landmark_s) / track_s
    print(f"  (decode + landmarker separately) / track_video: {overlap:5.2f}x (decode overlapped in a thread)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
