"""Benchmark: offline capture (decode + MediaPipe tracking + capture solve and filter) against tracking alone,
tracked sequentially and in parallel worker processes.

The video (default: a 20 s, 640x360, 30 fps H.264 video made from single_face.mp4's real frames played forward
then backward, keyframe every 2 s, ``bench/tracking.py``'s ``long_video``; the shared videos are 2.4 to 6.4 s,
where a worker's start-up of ~2 s weighs; give ``single_face.mp4`` to see it), cache disabled, REPEATS
interleaved rounds after a warm-up; each round times, on the same frames:
- the named baseline "tracking alone, sequential": :func:`mien.tracking.track_video` with ``workers=1`` (decode
  in a thread + MediaPipe in this process);
- "tracking alone, parallel": ``workers=None`` (the default: one process per CPU for a long enough video);
- "capture_video": parallel tracking + :func:`mien.capture.capture_track` (the CaptureStream per frame: One
  Euro filter, neutral, reverse AU mapping by NNLS) - what ``mien capture`` runs;
- "solve + filter": capture_track alone on the round's track (the capture's own cost).
Prints medians and spread (min..max), each against real time (target >= 4x for capture_video), parallel /
sequential tracking, and the capture's cost on top of tracking (target <= 10%), both as the ratio of whole runs
and as solve + filter / tracking per round; the load average before and after (the machine is shared).

Run: .venv/bin/python bench/capture_speed.py [VIDEO or ""] [REPEATS] (needs the shared data and face_landmarker.task,
found through $MIEN_SHARED or ../shared, and $MIEN_FACE_LANDMARKER or the shared model).
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tracking import _shared, load, long_video, spread  # bench/tracking.py, beside this file


def main() -> int:
    """Run the benchmark and print the results."""
    with tempfile.TemporaryDirectory() as folder:
        video = Path(sys.argv[1]) if len(sys.argv) > 1 and sys.argv[1] else long_video(Path(folder), 20.0)
        return _bench(video, int(sys.argv[2]) if len(sys.argv) > 2 else 5)


def _bench(video: Path, repeats: int) -> int:
    from mien.capture import capture_track
    from mien.paths import asset_path
    from mien.tracking.parallel import default_workers
    from mien.tracking.track import track_video
    from mien.tracking.video import probe

    model = asset_path("face_landmarker") or _shared() / "models" / "face_landmarker.task"
    info = probe(video)
    print(load())

    def tracking(workers: int | None) -> object:
        return track_video(video, model, use_cache=False, show_progress=False, workers=workers)

    capture_track(tracking(1))  # warm-up: file cache, model load, XNNPACK, scipy
    seq_s: list[float] = []
    par_s: list[float] = []
    capture_s: list[float] = []
    solve_s: list[float] = []
    n_frames = 0
    for _ in range(repeats):
        start = time.perf_counter()
        tracking(1)
        seq_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        track = tracking(None)
        par_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        capture = capture_track(tracking(None))  # = capture_video(video, use_cache=False)
        capture_s.append(time.perf_counter() - start)
        start = time.perf_counter()
        capture_track(track)
        solve_s.append(time.perf_counter() - start)
        n_frames = capture.n_frames
    duration_s = n_frames / info.fps
    workers = default_workers(info.n_frames)
    print(
        f"video: {video.name}, {n_frames} frames, {info.width}x{info.height} at {info.fps:g} fps ({duration_s:.2f} s)"
    )
    print(f"{repeats} interleaved rounds after a warm-up, cache disabled, default workers here: {workers}")
    print(f"  baseline tracking alone, sequential (workers=1) : {spread(seq_s, 1000, ' ms')}")
    print(f"  tracking alone, parallel (workers={workers})          : {spread(par_s, 1000, ' ms')}")
    print(f"  capture_video (parallel tracking + solve + filter): {spread(capture_s, 1000, ' ms')}")
    print(f"  solve + filter alone (capture_track)            : {spread(solve_s, 1000, ' ms')}")
    print(f"  solve + filter per frame                        : {spread([s / n_frames for s in solve_s], 1e6, ' us')}")
    for label, values in (
        ("sequential tracking", seq_s),
        ("parallel tracking  ", par_s),
        ("capture_video      ", capture_s),
    ):
        print(f"  {label} vs real time          : {spread([duration_s / s for s in values], 1, 'x')}")
    ratio = [p / s for p, s in zip(par_s, seq_s, strict=True)]
    print(f"  parallel / sequential tracking (same round)     : {spread(ratio, 1, '')}")
    whole = [c / t - 1.0 for c, t in zip(capture_s, par_s, strict=True)]
    print(f"  capture_video / parallel tracking - 1 (runs)    : {spread(whole, 100, ' %')}  (target <= 10%)")
    share = [s / t for s, t in zip(solve_s, seq_s, strict=True)]
    print(f"  solve + filter / sequential tracking (round)    : {spread(share, 100, ' %')}  (target <= 10%)")
    share = [s / t for s, t in zip(solve_s, par_s, strict=True)]
    print(f"  solve + filter / parallel tracking (round)      : {spread(share, 100, ' %')}  (target <= 10%)")
    print(load())
    return 0


if __name__ == "__main__":
    sys.exit(main())
