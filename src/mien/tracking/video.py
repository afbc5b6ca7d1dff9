"""Video decoding: a file (mp4, mov, avi, mkv, webm...) -> RGB frames with timestamps.

PyAV (FFmpeg) is the decoder; OpenCV is the fallback when PyAV is not installed. Any failure to open or
decode a file becomes one :class:`~mien.errors.InvalidValueError` naming the file, never a decoder-specific
exception. :func:`prefetch` runs an iterator in a background thread so decoding overlaps with the work done on
each frame (the FFmpeg decoder releases the GIL).
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass, replace
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from mien.errors import InvalidValueError, MissingExtraError
from mien.extras import available

__all__ = ["Segment", "VideoHeader", "iter_frames", "iter_segment", "plan_segments", "prefetch", "probe"]

T = TypeVar("T")


@dataclass(frozen=True)
class VideoHeader:
    """What a video's container declares (the frame count is an estimate), read before tracking it;
    :class:`mien.render.video.EncodedVideo` is a written video with its frames counted."""

    path: Path
    """The file."""
    fps: float
    """Average frame rate, frames per second (a summary: frame times come from each frame's time stamp)."""
    n_frames: int
    """Frame count declared by the container (an estimate; 0 when unknown)."""
    width: int
    """Frame width, pixels."""
    height: int
    """Frame height, pixels."""


def _unreadable(path: Path, reason: object) -> InvalidValueError:
    return InvalidValueError("video", str(path), f"a readable video file ({reason})")


def _check_file(path: str | os.PathLike[str]) -> Path:
    file = Path(path)
    if not file.is_file():
        raise InvalidValueError("video", str(file), "an existing video file")
    if file.stat().st_size == 0:
        raise _unreadable(file, "the file is empty")
    return file


def _open_av(file: Path) -> tuple[Any, Any]:
    import av

    try:
        container = av.open(str(file))
    except (av.FFmpegError, UnicodeDecodeError, ValueError) as exc:
        raise _unreadable(file, exc) from None
    if not container.streams.video:
        container.close()
        raise _unreadable(file, "it has no video stream")
    stream = container.streams.video[0]
    if stream.codec_context is None or not stream.codec_context.width:
        container.close()
        raise _unreadable(file, "its video stream has no decodable frames")
    stream.thread_type = "AUTO"  # frame + slice threads inside FFmpeg
    return container, stream


def _has_av() -> bool:
    return available("av")


def probe(path: str | os.PathLike[str]) -> VideoHeader:
    """Open ``path`` and read its frame rate, frame count and size (decodes nothing).

    Raises :class:`InvalidValueError` (field ``video``) when the file is missing or not a readable video.
    """
    file = _check_file(path)
    if _has_av():
        container, stream = _open_av(file)
        try:
            rate = stream.average_rate or stream.guessed_rate or Fraction(30)
            return VideoHeader(file, float(rate), int(stream.frames or 0), stream.width, stream.height)
        finally:
            container.close()
    capture = _open_cv(file)
    try:
        import cv2

        return VideoHeader(
            file,
            float(capture.get(cv2.CAP_PROP_FPS) or 30.0),
            int(capture.get(cv2.CAP_PROP_FRAME_COUNT) or 0),
            int(capture.get(cv2.CAP_PROP_FRAME_WIDTH)),
            int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT)),
        )
    finally:
        capture.release()


def iter_frames(path: str | os.PathLike[str]) -> Iterator[tuple[float, np.ndarray]]:
    """Yield ``(timestamp_s, rgb)`` for every frame of ``path``.

    ``timestamp_s`` is the frame's own presentation time (pts x time_base) in seconds from the first frame,
    never ``index / average rate``, so a variable-frame-rate video keeps its timing; ``rgb`` is an
    (height, width, 3) uint8 C-contiguous array. Raises :class:`InvalidValueError` (field ``video``) when the
    file cannot be opened, decoding fails part-way (a truncated or corrupt file), or it holds no frame.
    """
    file = _check_file(path)
    frames = _iter_av(file) if _has_av() else _iter_cv(file)
    count = 0
    for item in frames:
        count += 1
        yield item
    if count == 0:
        raise _unreadable(file, "no frame could be decoded")


def _iter_av(file: Path) -> Iterator[tuple[float, np.ndarray]]:
    import av

    container, stream = _open_av(file)
    rate = float(stream.average_rate or stream.guessed_rate or 30)
    declared = int(stream.frames or 0)
    start: float | None = None
    previous: float | None = None
    index = 0
    packets = 0
    try:
        try:
            for packet in container.demux(stream):
                packets += packet.size > 0
                for frame in packet.decode():
                    time_s = frame.time  # pts x time_base
                    if time_s is None:  # no time stamp (rare raw streams): one nominal frame after the last
                        time_s = 0.0 if previous is None else previous + 1.0 / rate
                    previous = time_s
                    if start is None:
                        start = time_s
                    # rgb24 straight from the decoder's reformatter: one conversion, no extra copy.
                    yield time_s - start, frame.to_ndarray(format="rgb24")
                    index += 1
        except av.FFmpegError as exc:
            raise _unreadable(file, f"decoding failed after {index} frames: {exc}") from None
        # FFmpeg stops quietly at the end of a truncated file: compare the packets read with the count the
        # container declares (decoded frames may be fewer than packets because of edit lists).
        if declared and packets < declared - 1:
            raise _unreadable(file, f"truncated: only {packets} of the {declared} declared frames are present")
    finally:
        container.close()


@dataclass(frozen=True)
class Segment:
    """A contiguous run of a video's frames, in presentation order, that can be decoded on its own
    (:func:`plan_segments`, :func:`iter_segment`). Frame positions are presentation time stamps (pts) in the
    stream's time base; ``None`` means the video's start (or, for ``stop_pts``, its end)."""

    index: int
    """The segment's place in the video (0 first)."""
    first_frame: int
    """Index of the segment's first frame among the video's frames (for messages and progress)."""
    n_frames: int
    """Frames in the segment (from the container's packets: an estimate when an edit list drops frames)."""
    seek_pts: int | None
    """The keyframe decoding starts from (None: the file's start, no seek)."""
    warm_pts: int | None
    """First frame decoded and handed out as a warm-up frame (before ``start_pts``; None: no warm-up)."""
    start_pts: int | None
    """The segment's first frame (None: the video's first)."""
    stop_pts: int | None
    """The next segment's first frame, not part of this one (None: to the end of the video)."""


def plan_segments(
    path: str | os.PathLike[str], n_segments: int, warmup_frames: int = 0, lead_frames: int = 0
) -> tuple[float, tuple[Segment, ...]] | None:
    """Split a video into ``n_segments`` contiguous runs of frames that separate decoders can read in parallel.

    Reads the container's packets (decodes one frame: the first, whose time is the origin of every time stamp)
    and returns ``(origin_s, segments)``: the first frame's time in seconds (what :func:`iter_frames` subtracts)
    and the segments, cut evenly by frame count except that the first gets ``lead_frames`` more than an even
    share minus an even share of them (the frames its reader handles while the others are still starting;
    every segment keeps at least two frames). Each later segment decodes from the last keyframe at or before
    its first warm-up frame (``warmup_frames`` frames before its first frame). Returns None where a video
    cannot be split safely, so the caller reads it whole with :func:`iter_frames` (which then raises the usual
    error for a damaged file): PyAV missing, fewer than ``2 * n_segments`` frames, packets without time stamps,
    a demuxing error or a truncated file (fewer packets than the container declares).
    """
    if n_segments < 2 or not _has_av():
        return None
    import av

    file = _check_file(path)
    try:
        container, stream = _open_av(file)
    except InvalidValueError:
        return None
    try:
        declared = int(stream.frames or 0)
        stamps: list[int] = []
        keys: list[int] = []
        for packet in container.demux(stream):
            if packet.size <= 0:
                continue
            if packet.pts is None:
                return None
            stamps.append(int(packet.pts))
            if packet.is_keyframe:
                keys.append(int(packet.pts))
        if declared and len(stamps) < declared - 1:
            return None
        container.seek(0)
        first = next(container.decode(stream), None)
        if first is None or first.pts is None or first.time is None:
            return None
        origin_pts, origin_s = int(first.pts), float(first.time)
    except (av.FFmpegError, StopIteration, ValueError):
        return None
    finally:
        container.close()
    frames = sorted(p for p in stamps if p >= origin_pts)  # frames an edit list drops come before the first
    if len(frames) < 2 * n_segments or not keys:
        return None
    keys.sort()
    n = len(frames)
    first = min(max(round((n + lead_frames * (n_segments - 1)) / n_segments), 2), n - 2 * (n_segments - 1))
    cuts = [0] + [first + round(i * (n - first) / (n_segments - 1)) for i in range(n_segments)]
    segments = []
    for i in range(n_segments):
        start, stop = cuts[i], cuts[i + 1]
        stop_pts = frames[stop] if stop < len(frames) else None
        if i == 0:
            segments.append(Segment(0, 0, stop - start, None, None, None, stop_pts))
            continue
        warm_pts = frames[max(start - warmup_frames, 0)]
        before = [k for k in keys if k <= warm_pts]
        seek_pts = before[-1] if before else None
        segments.append(Segment(i, start, stop - start, seek_pts, warm_pts, frames[start], stop_pts))
    return origin_s, tuple(segments)


def iter_segment(
    path: str | os.PathLike[str], segment: Segment, origin_s: float
) -> Iterator[tuple[float, np.ndarray, bool]]:
    """Yield ``(timestamp_s, rgb, warm_up)`` for the frames of one :class:`Segment` of ``path`` (PyAV only).

    ``timestamp_s`` is computed as :func:`iter_frames` computes it (the frame's time minus ``origin_s``, from
    :func:`plan_segments`), so a video read in segments gives the same time stamps, bit for bit. Frames from
    ``segment.warm_pts`` up to its first frame come first, flagged ``warm_up`` True. Raises
    :class:`InvalidValueError` (field ``video``) when decoding fails, naming the frame index in the video.
    """
    import av

    file = _check_file(path)
    container, stream = _open_av(file)
    stream.codec_context.thread_count = 1  # every core tracks a segment: FFmpeg's threads would cost CPU, not time
    rate = float(stream.average_rate or stream.guessed_rate or 30)
    index = segment.first_frame
    previous: float | None = None
    try:
        try:
            if segment.seek_pts is not None:
                container.seek(segment.seek_pts, stream=stream, backward=True, any_frame=False)
            first = True
            for packet in container.demux(stream):
                for frame in packet.decode():
                    pts = frame.pts
                    if pts is not None and segment.warm_pts is not None and pts < segment.warm_pts:
                        continue  # between the keyframe and the warm-up: decoded only
                    if first and segment.seek_pts is not None and pts != segment.warm_pts:
                        break  # the seek landed past the warm-up's first frame: decode from the start instead
                    first = False
                    if pts is not None and segment.stop_pts is not None and pts >= segment.stop_pts:
                        return
                    time_s = frame.time
                    if time_s is None:  # as iter_frames: one nominal frame after the last
                        time_s = origin_s if previous is None else previous + 1.0 / rate
                    previous = time_s
                    warm = pts is not None and segment.start_pts is not None and pts < segment.start_pts
                    yield time_s - origin_s, frame.to_ndarray(format="rgb24"), warm
                    index += not warm
                else:
                    continue
                break
            else:
                return
        except av.FFmpegError as exc:
            raise _unreadable(file, f"decoding failed after {index} frames: {exc}") from None
    finally:
        container.close()
    yield from iter_segment(file, replace(segment, seek_pts=None), origin_s)  # only after a seek went too far


def _open_cv(file: Path) -> Any:
    if not available("cv2"):  # no extra brings OpenCV: name both ways to read a video
        raise MissingExtraError("av (PyAV) or opencv-python", "track")
    import cv2

    capture = cv2.VideoCapture(str(file))
    if not capture.isOpened():
        raise _unreadable(file, "OpenCV cannot open it")
    return capture


def _iter_cv(file: Path) -> Iterator[tuple[float, np.ndarray]]:
    import cv2

    capture = _open_cv(file)
    rate = float(capture.get(cv2.CAP_PROP_FPS) or 30.0)
    start: float | None = None
    index = 0
    try:
        while True:
            ok, bgr = capture.read()
            if not ok:
                break
            time_s = capture.get(cv2.CAP_PROP_POS_MSEC) / 1000.0  # the frame just read: its own time stamp
            if index and time_s <= 0:  # a backend without time stamps
                time_s = index / rate
            start = time_s if start is None else start
            yield time_s - start, np.ascontiguousarray(bgr[:, :, ::-1])
            index += 1
    finally:
        capture.release()


_DONE = object()


def prefetch(items: Iterator[T], depth: int = 8) -> Iterator[T]:
    """Iterate ``items`` in a background thread, keeping up to ``depth`` ready; re-raises its errors here.

    Closing the returned generator early stops the thread after its next item.
    """
    slots: queue.Queue[Any] = queue.Queue(maxsize=depth)
    stop = threading.Event()

    def work() -> None:
        try:
            for item in items:
                if stop.is_set():
                    return
                slots.put(item)
        except BaseException as exc:  # handed to the consumer, raised there
            slots.put(_Raised(exc))
            return
        slots.put(_DONE)

    thread = threading.Thread(target=work, name="mien-decode", daemon=True)
    thread.start()
    try:
        while True:
            item = slots.get()
            if item is _DONE:
                return
            if isinstance(item, _Raised):
                raise item.error
            yield item
    finally:
        stop.set()
        while thread.is_alive():  # unblock a producer waiting on a full queue
            try:
                slots.get(timeout=0.05)
            except queue.Empty:
                pass
        thread.join()


@dataclass(frozen=True)
class _Raised:
    error: BaseException
