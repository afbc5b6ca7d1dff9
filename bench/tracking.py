"""Benchmark: tracking a video (decode + MediaPipe Face Landmarker), sequential against parallel, cache disabled.

The shared videos are short (single_face.mp4: 2.4 s, 72 frames at 640x360), too short for worker processes to
pay for their start-up, so the main video here is a longer one made from single_face.mp4's real frames:
played forward then backward (no cut: the face moves continuously) up to SECONDS s, 640x360, 30 fps, H.264
with a keyframe every 2 s (like a phone or webcam recording), written to a temporary folder.

Prints, with the load average beside the figures:
1. agreement: ``track_video(workers=2)`` against the named baseline ``workers=1`` on the long video and on each
   shared video: time stamps identical, faceless frames the same, and at each join the landmark and blendshape
   differences per frame (max / median over the coordinates), beside the tracker's own frame-to-frame change;
2. speed, REPEATS interleaved rounds after a warm-up: sequential (workers=1, the baseline) and parallel
   (workers=2) on videos of 2.4, 5, 10 and 20 s:
   median and spread, ratio to real time, parallel / sequential time: the break-even length behind
   :data:`mien.tracking.parallel.MIN_FRAMES_PER_WORKER`.

Run: .venv/bin/python bench/tracking.py [SECONDS] [REPEATS] (needs the shared data and face_landmarker.task,
found through $MIEN_SHARED or ../shared, and $MIEN_FACE_LANDMARKER or the shared model).
"""

from __future__ import annotations

import os
import resource
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np


def _shared() -> Path:
    return Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))


def load() -> str:
    """The 1, 5 and 15 minute load averages, as text."""
    one, five, fifteen = os.getloadavg()
    return f"load average {one:.2f} {five:.2f} {fifteen:.2f} on {os.cpu_count()} CPUs"


@dataclass(frozen=True)
class Timed:
    """One run: wall-clock seconds and CPU seconds of this process and of its (finished) worker processes."""

    wall_s: float
    self_cpu_s: float
    workers_cpu_s: float
    idle_share: float = float("nan")
    """Share of the machine's CPU time left idle during the run (/proc/stat; NaN elsewhere): near 0, the
    run had no spare core to use, whatever its worker count."""

    def busiest_cpu_s(self, workers: int) -> float:
        """CPU seconds of the busiest process (this one, or a worker on average): the run's length on an idle
        machine with a core per process, the load-insensitive figure on a shared machine."""
        return max(self.self_cpu_s, self.workers_cpu_s / max(workers - 1, 1))


def _machine_ticks() -> tuple[int, int]:
    """(idle, total) CPU ticks of the whole machine so far (/proc/stat; (0, 0) where it does not exist)."""
    try:
        fields = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    except (OSError, ValueError):
        return 0, 0
    return fields[3] + fields[4], sum(fields[:8])  # idle + iowait; user..steal


def timed(work: Callable[[], object]) -> Timed:
    """Run ``work()`` and measure it (:class:`Timed`)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    idle, total = _machine_ticks()
    start = time.perf_counter()
    work()
    wall = time.perf_counter() - start
    idle_after, total_after = _machine_ticks()
    own_after, kids_after = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return Timed(
        wall,
        own_after.ru_utime + own_after.ru_stime - own.ru_utime - own.ru_stime,
        kids_after.ru_utime + kids_after.ru_stime - kids.ru_utime - kids.ru_stime,
        (idle_after - idle) / (total_after - total) if total_after > total else float("nan"),
    )


def spread(values: list[float], scale: float = 1.0, unit: str = "") -> str:
    """Median and min..max of ``values`` times ``scale``."""
    return (
        f"median {statistics.median(values) * scale:8.3f}{unit}  "
        f"(min {min(values) * scale:.3f}, max {max(values) * scale:.3f})"
    )


def long_video(folder: Path, seconds: float, source: Path | None = None) -> Path:
    """A ``seconds``-long 640x360 30 fps H.264 video (keyframe every 2 s) of single_face.mp4's frames played
    forward then backward, written to ``folder``; returns its path."""
    import av

    from mien.tracking.video import iter_frames

    source = source or _shared() / "data" / "video" / "single_face.mp4"
    frames = [rgb for _, rgb in iter_frames(source)]
    loop = frames + frames[-2:0:-1]
    n = round(seconds * 30)
    out = folder / f"single_face_{seconds:g}s.mp4"
    with av.open(str(out), "w") as container:
        stream = container.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        stream.options = {"g": "60", "keyint_min": "60", "sc_threshold": "0"}
        for i in range(n):
            container.mux(stream.encode(av.VideoFrame.from_ndarray(loop[i % len(loop)], format="rgb24")))
        container.mux(stream.encode(None))
    return out


def agreement(video: Path, model: Path) -> None:
    """Print how ``workers=2`` agrees with ``workers=1`` on ``video``, per join frame (even segments: the join in
    the middle of the video)."""
    import mien.tracking.parallel as parallel
    from mien.tracking.parallel import WARMUP_FRAMES
    from mien.tracking.track import track_video
    from mien.tracking.video import plan_segments

    seq = track_video(video, model, use_cache=False, show_progress=False, workers=1)
    lead, parallel.LEAD_FRAMES = parallel.LEAD_FRAMES, 0
    try:
        par = track_video(video, model, use_cache=False, show_progress=False, workers=2)
    finally:
        parallel.LEAD_FRAMES = lead
    same_times = np.array_equal(seq.timestamps_s, par.timestamps_s)
    same_faces = np.array_equal(seq.face_found, par.face_found)
    both = seq.face_found & par.face_found
    step = np.abs(np.diff(seq.blendshapes[seq.face_found], axis=0))
    noise = f"{np.median(step.max(axis=1)):.4f}" if step.size else "-"
    print(
        f"  {video.name}: {seq.n_frames} frames; time stamps identical {same_times}, faceless frames the same "
        f"{same_faces}; tracker's own frame-to-frame change of the blendshapes (median of the per-frame max): {noise}"
    )
    plan = plan_segments(video, 2, WARMUP_FRAMES)
    assert plan is not None
    for segment in plan[1][1:]:
        for j in range(segment.first_frame, min(segment.first_frame + 3, seq.n_frames)):
            if not both[j]:
                print(f"    join frame {j}: no face in {'both' if not seq.face_found[j] else 'one'}")
                continue
            marks = np.abs(seq.landmarks_px[j] - par.landmarks_px[j])
            scores = np.abs(seq.blendshapes[j] - par.blendshapes[j])
            print(
                f"    join frame {j}: landmarks max {marks.max():.2f} px median {np.median(marks):.3f} px; "
                f"blendshapes max {scores.max():.4f} median {np.median(scores):.5f}"
            )
    if both.any():
        scores = np.abs(seq.blendshapes[both] - par.blendshapes[both])
        print(
            f"    every frame: blendshapes max {scores.max():.4f}, mean of the per-frame max {scores.max(1).mean():.4f}"
        )


def main() -> int:
    """Run the benchmark and print the results."""
    from mien.paths import asset_path
    from mien.tracking.track import track_video

    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 20.0
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    model = asset_path("face_landmarker") or _shared() / "models" / "face_landmarker.task"
    shared = _shared() / "data" / "video"
    print(load())
    with tempfile.TemporaryDirectory() as folder:
        lengths = sorted({2.4, 5.0, 10.0, seconds})
        videos = {s: shared / "single_face.mp4" if s == 2.4 else long_video(Path(folder), s) for s in lengths}
        print("agreement, workers=2 against workers=1 (the baseline):")
        for video in (
            videos[seconds],
            *(shared / n for n in ("single_face.mp4", "face_noface.mov", "noface_face.mov")),
        ):
            agreement(video, model)

        def run(video: Path, workers: int) -> Timed:
            return timed(lambda: track_video(video, model, use_cache=False, show_progress=False, workers=workers))

        run(videos[2.4], 1)  # warm-up: file cache, model load
        timings: dict[tuple[float, int], list[Timed]] = {(s, w): [] for s in lengths for w in (1, 2)}
        for _ in range(repeats):
            for s in lengths:
                for w in (1, 2):
                    timings[s, w].append(run(videos[s], w))
        print(f"speed, {repeats} interleaved rounds after a warm-up, cache disabled ({load()}):")
        print(
            "  wall: wall-clock time; busiest CPU: CPU seconds of the busiest process (its length on an idle machine)"
        )
        for s in lengths:
            seq, par = timings[s, 1], timings[s, 2]
            for label, runs, w in (("workers=1 (baseline)", seq, 1), ("workers=2           ", par, 2)):
                wall = spread([r.wall_s for r in runs], 1000, " ms")
                busy = spread([r.busiest_cpu_s(w) for r in runs], 1000, " ms")
                idle = statistics.median(r.idle_share for r in runs)
                print(f"  {s:4.1f} s video, {label}: wall {wall}  busiest CPU {busy}  machine idle {idle:.0%}")
            ratio = spread([p.wall_s / q.wall_s for p, q in zip(par, seq, strict=True)], 1, "")
            print(f"  {s:4.1f} s video, parallel / sequential, wall       : {ratio}")
            busy = [p.busiest_cpu_s(2) / q.busiest_cpu_s(1) for p, q in zip(par, seq, strict=True)]
            print(f"  {s:4.1f} s video, parallel / sequential, busiest CPU: {spread(busy, 1, '')}")
            idle = spread([s / p.busiest_cpu_s(2) for p in par], 1, "x")
            print(f"  {s:4.1f} s video, workers=2 vs real time on an idle machine (busiest CPU): {idle}")
    print(load())
    return 0


if __name__ == "__main__":
    sys.exit(main())
