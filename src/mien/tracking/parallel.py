"""Tracking a video on several cores: contiguous time segments tracked at once, joined in time order.

:func:`track_frames` is what :func:`mien.tracking.track_video` runs. With ``workers`` > 1 the video is cut into
``workers`` segments of consecutive frames (:func:`mien.tracking.video.plan_segments`); the calling process
tracks the first while ``workers - 1`` worker processes (``concurrent.futures.ProcessPoolExecutor``, ``spawn``
context: nothing of the caller's state is inherited) each open their own decoder, seek to the keyframe before
their segment, and track it with their own MediaPipe landmarker in video mode. The per-frame results are joined
in segment order; each frame keeps its own time stamp, computed exactly as a sequential run computes it.

A landmarker that starts on a segment's first frame detects the face afresh, as a sequential run does on the
video's first frame, where the sequential run had tracked it from the frame before. So each later segment first
tracks the :data:`WARMUP_FRAMES` frames before it and drops them: at the joins the results then differ from a
sequential run by tracker noise only (bench/tracking.py measures it). One progress bar counts every process's
frames. Ctrl-C, SIGTERM (through :func:`mien.signals.termination_as_interrupt`) or an error stops the workers;
a worker whose parent died stops on its next frame.
"""

from __future__ import annotations

import multiprocessing
import os
import queue
import signal
from collections.abc import Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.facs.arkit import ARKIT_NAMES
from mien.progress import progress
from mien.tracking.landmarker import N_LANDMARKS

__all__ = [
    "LEAD_FRAMES",
    "MAX_WORKERS",
    "MIN_FRAMES_PER_WORKER",
    "WARMUP_FRAMES",
    "FrameArrays",
    "default_workers",
    "track_frames",
]

WARMUP_FRAMES = 3
"""Frames before a later segment that its worker tracks and drops, so the tracker has the face at the join."""

MIN_FRAMES_PER_WORKER = 150
"""Fewest frames per process worth a worker: a worker's start-up (Python, mien, MediaPipe, the model: about 2 s
on the 2-core development machine) costs about as much as tracking 60 to 150 frames (bench/tracking.py), so a
video shorter than ``2 * MIN_FRAMES_PER_WORKER`` frames (10 s at 30 fps) is tracked in one process."""

LEAD_FRAMES = 100
"""Frames the calling process tracks, beyond an even share, while its workers start (:data:`MIN_FRAMES_PER_WORKER`
explains the start-up; both it and a frame's tracking are CPU work, so the ratio holds on a busy machine)."""

MAX_WORKERS = 8
"""Most processes :func:`default_workers` picks (each holds a MediaPipe graph, ~100 MB)."""

_PROGRESS_EVERY = 4
"""A worker reports its frames to the progress bar in batches of this many."""


def usable_cpus() -> int:
    """CPUs this process may run on (its affinity where the platform says, else ``os.cpu_count()``)."""
    counter = getattr(os, "process_cpu_count", None)  # Python 3.13
    if counter is not None:
        return int(counter() or 1)
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def default_workers(n_frames: int) -> int:
    """Processes to track ``n_frames`` frames with: one per usable CPU, at most :data:`MAX_WORKERS`, and no more
    than leave every process :data:`MIN_FRAMES_PER_WORKER` frames (1 for a short video or an unknown count)."""
    return max(1, min(usable_cpus(), MAX_WORKERS, n_frames // MIN_FRAMES_PER_WORKER))


def check_workers(workers: int | None) -> None:
    """Raise :class:`InvalidValueError` unless ``workers`` is None (automatic) or an int >= 1."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
        raise InvalidValueError("workers", workers, "a whole number of processes >= 1 (or None: one per CPU)")


@dataclass(frozen=True, eq=False)
class FrameArrays:
    """Per-frame tracker output of a run of frames (the raw part of a :class:`mien.tracking.Track`)."""

    times_s: np.ndarray
    """(n,) float64 frame time stamps, seconds from the video's first frame."""
    landmarks: np.ndarray
    """(n, 478, 3) float32 normalised landmarks (NaN without a face)."""
    blendshapes: np.ndarray
    """(n, 52) float32 scores in ARKIT_NAMES order (NaN without a face)."""
    matrices: np.ndarray
    """(n, 4, 4) float64 facial transformation matrices (NaN without a face)."""
    found: np.ndarray
    """(n,) bool: a face was found."""

    @staticmethod
    def join(parts: Iterable[FrameArrays]) -> FrameArrays:
        """The parts one after the other."""
        items = list(parts)
        return FrameArrays(*(np.concatenate([getattr(p, f) for p in items]) for f in _FIELDS))


_FIELDS = ("times_s", "landmarks", "blendshapes", "matrices", "found")


class _Run:
    """Tracks ``(time_s, rgb, warm_up)`` frames with one video-mode landmarker when iterated, yielding once per
    kept frame (warm-up frames are tracked but not kept); :attr:`result` holds the arrays afterwards."""

    def __init__(self, frames: Iterable[tuple[float, np.ndarray, bool]], model: Path, min_confidence: float) -> None:
        self.frames = frames
        self.model = model
        self.min_confidence = min_confidence
        self.result: FrameArrays | None = None

    def __iter__(self) -> Iterator[None]:
        from mien.tracking.landmarker import Landmarker

        times: list[float] = []
        landmarks: list[np.ndarray] = []
        blendshapes: list[np.ndarray] = []
        matrices: list[np.ndarray] = []
        found: list[bool] = []
        missing_landmarks = np.full((N_LANDMARKS, 3), np.nan, np.float32)
        missing_scores = np.full(len(ARKIT_NAMES), np.nan, np.float32)
        missing_matrix = np.full((4, 4), np.nan)
        with Landmarker(self.model, mode="video", min_confidence=self.min_confidence) as landmarker:
            for time_s, rgb, warm_up in self.frames:
                result = landmarker.detect(rgb, time_s)
                if warm_up:
                    continue
                times.append(time_s)
                found.append(result is not None)
                landmarks.append(missing_landmarks if result is None else result.landmarks)
                blendshapes.append(missing_scores if result is None else result.blendshapes)
                matrices.append(missing_matrix if result is None else result.matrix)
                yield None
        n = len(times)
        self.result = FrameArrays(
            np.array(times, dtype=np.float64),
            np.stack(landmarks) if n else np.zeros((0, N_LANDMARKS, 3), np.float32),
            np.stack(blendshapes) if n else np.zeros((0, len(ARKIT_NAMES)), np.float32),
            np.stack(matrices) if n else np.zeros((0, 4, 4)),
            np.array(found, dtype=bool),
        )


def _whole(frames: Iterable[tuple[float, np.ndarray]]) -> Iterator[tuple[float, np.ndarray, bool]]:
    for time_s, rgb in frames:
        yield time_s, rgb, False


def track_frames(
    path: Path,
    model: Path,
    min_confidence: float,
    n_frames: int,
    workers: int | None = None,
    show_progress: bool = True,
) -> FrameArrays:
    """Track every frame of ``path`` in ``workers`` processes (None: :func:`default_workers`); one process reads
    the video whole (decoding in a thread, :func:`mien.tracking.video.prefetch`). ``n_frames`` is the container's
    frame count (for the bar and the default). A video that cannot be split safely is read whole.
    Raises :class:`InvalidValueError` naming the file when it is unreadable, truncated or corrupt."""
    from mien.tracking.video import iter_frames, plan_segments, prefetch

    check_workers(workers)
    count = default_workers(n_frames) if workers is None else workers
    plan = plan_segments(path, count, WARMUP_FRAMES, LEAD_FRAMES) if count > 1 else None
    desc = f"tracking {path.name}"
    if plan is None:
        run = _Run(_whole(prefetch(iter_frames(path))), model, min_confidence)
        for _ in progress(run, total=n_frames or None, desc=desc, enabled=show_progress):
            pass
        assert run.result is not None
        return run.result
    origin_s, segments = plan
    return _track_parallel(path, model, min_confidence, origin_s, segments, n_frames, desc, show_progress)


# ------------------------------------------------------------------------------------------------ workers

_progress_queue: Any = None
_parent_pid = 0


def _start_worker(progress_queue: Any, parent_pid: int) -> None:
    """Worker initializer: Ctrl-C is the parent's to handle (it stops the workers), progress goes to the queue."""
    global _progress_queue, _parent_pid
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _progress_queue, _parent_pid = progress_queue, parent_pid


@dataclass(frozen=True)
class _Failure:
    """An :class:`InvalidValueError` raised in a worker (its arguments: the exception itself does not pickle)."""

    field: str
    value: Any
    expected: str


def _track_segment(
    path: Path, model: Path, min_confidence: float, origin_s: float, segment: Any
) -> FrameArrays | _Failure:
    """Worker: track one segment with its own decoder and landmarker."""
    from mien.tracking.video import iter_segment

    try:
        run = _Run(iter_segment(path, segment, origin_s), model, min_confidence)
        done = 0
        for _ in run:
            done += 1
            if done % _PROGRESS_EVERY == 0:
                if os.getppid() != _parent_pid:  # the parent died without stopping us
                    os._exit(1)
                _progress_queue.put(_PROGRESS_EVERY)
        _progress_queue.put(done % _PROGRESS_EVERY)
        assert run.result is not None
        return run.result
    except InvalidValueError as exc:
        return _Failure(exc.field, exc.value, exc.expected)


def _drain(progress_queue: Any, timeout_s: float = 0.0) -> Iterator[None]:
    """One item per frame the workers reported since the last call (waits up to ``timeout_s`` for the first)."""
    try:
        count = progress_queue.get(timeout=timeout_s) if timeout_s > 0 else progress_queue.get_nowait()
        while True:
            for _ in range(count):
                yield None
            count = progress_queue.get_nowait()
    except queue.Empty:
        return


def _track_parallel(
    path: Path,
    model: Path,
    min_confidence: float,
    origin_s: float,
    segments: tuple[Any, ...],
    n_frames: int,
    desc: str,
    show_progress: bool,
) -> FrameArrays:
    from mien.tracking.video import iter_segment, prefetch

    context = multiprocessing.get_context("spawn")
    progress_queue = context.Queue()
    pool = ProcessPoolExecutor(
        max_workers=len(segments) - 1,
        mp_context=context,
        initializer=_start_worker,
        initargs=(progress_queue, os.getpid()),
    )
    finished = False
    try:
        futures: list[Future[FrameArrays | _Failure]] = [
            pool.submit(_track_segment, path, model, min_confidence, origin_s, segment) for segment in segments[1:]
        ]
        own = _Run(prefetch(iter_segment(path, segments[0], origin_s)), model, min_confidence)

        def ticks() -> Iterator[None]:
            for _ in own:  # the first segment, here, while the workers start and track theirs
                yield None
                yield from _drain(progress_queue)
            while not all(future.done() for future in futures):
                yield from _drain(progress_queue, 0.1)
            yield from _drain(progress_queue)

        for _ in progress(ticks(), total=n_frames or None, desc=desc, enabled=show_progress):
            pass
        parts: list[FrameArrays] = []
        assert own.result is not None
        parts.append(own.result)
        for future in futures:
            try:
                part = future.result()
            except BrokenProcessPool as exc:  # a worker killed from outside (out of memory, a kill)
                raise MienError(f"a tracking worker process stopped ({exc}); track with workers=1") from None
            if isinstance(part, _Failure):
                raise InvalidValueError(part.field, part.value, part.expected)
            parts.append(part)
        finished = True
    finally:
        if not finished:  # Ctrl-C, SIGTERM or an error: stop the workers now rather than after their segments
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
        progress_queue.close()
        progress_queue.join_thread()
    return FrameArrays.join(parts)
