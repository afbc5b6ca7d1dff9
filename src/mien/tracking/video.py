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
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from mien.errors import InvalidValueError, MissingExtraError
from mien.extras import available

__all__ = ["VideoHeader", "iter_frames", "prefetch", "probe"]

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
