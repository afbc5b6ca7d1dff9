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

import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tracking import Timed, _shared, load, long_video, spread, timed  # bench/tracking.py, beside this file


def main() -> int:
    """Run the benchmark and print the results."""
    with tempfile.TemporaryDirectory() as folder:
        video = Path(sys.argv[1]) if len(sys.argv) > 1 and sys.argv[1] else long_video(Path(folder), 20.0)
        return _bench(video, int(sys.argv[2]) if len(sys.argv) > 2 else 5)


def _bench(video: Path, repeats: int) -> int:
    from mien.capture import Capture, capture_track
    from mien.paths import asset_path
    from mien.tracking.parallel import default_workers
    from mien.tracking.track import Track, track_video
    from mien.tracking.video import probe

    model = asset_path("face_landmarker") or _shared() / "models" / "face_landmarker.task"
    info = probe(video)
    print(load())

    def tracking(workers: int | None) -> Track:
        return track_video(video, model, use_cache=False, show_progress=False, workers=workers)

    capture_track(tracking(1))  # warm-up: file cache, model load, XNNPACK, scipy
    workers = default_workers(info.n_frames)
    seq: list[Timed] = []
    par: list[Timed] = []
    cap: list[Timed] = []
    solve: list[Timed] = []
    tracks: list[Track] = []
    captures: list[Capture] = []
    for _ in range(repeats):
        seq.append(timed(lambda: tracking(1)))
        par.append(timed(lambda: tracks.append(tracking(None))))
        cap.append(timed(lambda: captures.append(capture_track(tracking(None)))))  # = capture_video(video, ...)
        solve.append(timed(lambda: capture_track(tracks[-1])))
    n_frames = captures[-1].n_frames
    duration_s = n_frames / info.fps
    print(
        f"video: {video.name}, {n_frames} frames, {info.width}x{info.height} at {info.fps:g} fps ({duration_s:.2f} s)"
    )
    print(f"{repeats} interleaved rounds after a warm-up, cache disabled, default workers here: {workers}")
    print("wall: wall-clock time; busiest CPU: CPU seconds of the busiest process (~ its length on an idle machine)")
    rows = (
        ("baseline tracking alone, sequential (workers=1)", seq, 1),
        (f"tracking alone, parallel (workers={workers})         ", par, workers),
        ("capture_video (parallel tracking + solve+filter)", cap, workers),
        ("solve + filter alone (capture_track)            ", solve, 1),
    )
    for label, runs, w in rows:
        print(f"  {label}: wall {spread([r.wall_s for r in runs], 1000, ' ms')}")
        idle = statistics.median(r.idle_share for r in runs)
        busy = spread([r.busiest_cpu_s(w) for r in runs], 1000, " ms")
        print(f"  {' ' * len(label)}  busiest CPU {busy}  machine idle during the run {idle:.0%}")
    print(f"  solve + filter per frame: {spread([r.wall_s / n_frames for r in solve], 1e6, ' us')}")
    short = ("sequential tracking", "parallel tracking  ", "capture_video      ")
    for label, (_, runs, w) in zip(short, rows, strict=False):
        wall = spread([duration_s / r.wall_s for r in runs], 1, "x")
        idle = spread([duration_s / r.busiest_cpu_s(w) for r in runs], 1, "x")
        print(f"  {label} vs real time: wall {wall}")
        print(f"  {' ' * len(label)}   idle (busiest CPU) {idle}  (target >= 4x)")
    ratio = spread([p.wall_s / s.wall_s for p, s in zip(par, seq, strict=True)], 1, "")
    busy = spread([p.busiest_cpu_s(workers) / s.busiest_cpu_s(1) for p, s in zip(par, seq, strict=True)], 1, "")
    print(f"  parallel / sequential tracking (same round): wall {ratio}; busiest CPU {busy}")
    whole = spread([c.wall_s / t.wall_s - 1.0 for c, t in zip(cap, par, strict=True)], 100, " %")
    print(f"  capture_video / parallel tracking - 1 (whole runs, wall): {whole}  (target <= 10%)")
    for name, base in (("sequential", seq), ("parallel", par)):
        share = spread([s.wall_s / t.wall_s for s, t in zip(solve, base, strict=True)], 100, " %")
        print(f"  solve + filter / {name} tracking (same round, wall): {share}  (target <= 10%)")
    print(load())
    return 0


if __name__ == "__main__":
    sys.exit(main())
