"""Writing frames to H.264 MP4 (imageio-ffmpeg's bundled ffmpeg) and PNG (Pillow); reading MP4 facts (PyAV).

:class:`Mp4Writer` pipes raw RGB frames into an ffmpeg subprocess from a background thread, so the caller
renders the next frame while ffmpeg encodes (two cores busy). The video is written to a temporary file next to
it (:func:`mien.fileio.streams.temporary_path`) and renamed when complete; if the caller fails midway, the
encoder is closed cleanly so the frames so far form a valid, shorter video kept as ``<name>.partial.mp4``,
and the error propagates. :func:`mien.signals.termination_as_interrupt` makes SIGTERM and SIGHUP (a ``kill``,
a closed terminal) end the writing the way Ctrl-C does, so they leave no temporary file behind either.
"""

from __future__ import annotations

import contextlib
import os
import queue
import subprocess
import tempfile
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.extras import require
from mien.fileio.streams import atomic_path, temporary_path
from mien.progress import progress as progress_bar

__all__ = [
    "EncodedVideo",
    "Mp4Writer",
    "read_video_info",
    "write_mp4",
    "write_png",
]

X264_PRESETS = (
    "ultrafast",
    "superfast",
    "veryfast",
    "faster",
    "fast",
    "medium",
    "slow",
    "slower",
    "veryslow",
)
"""libx264 speed presets, fastest first."""


def _ffmpeg_exe() -> str:
    return str(require("imageio_ffmpeg", "render").get_ffmpeg_exe())


def partial_path(path: str | os.PathLike[str]) -> Path:
    """Where an interrupted :func:`write_mp4` to ``path`` leaves its frames: ``<stem>.partial.mp4``."""
    path = Path(path)
    return path.with_name(path.stem + ".partial.mp4")


class Mp4Writer:
    """An H.264 (libx264, yuv420p) MP4 encoder fed with (height, width, 3) uint8 RGB frames.

    ``fps`` frames per second (> 0); ``crf`` x264 constant rate factor 0..51 (lower = better, 18 is
    visually lossless); ``preset`` an x264 speed preset. Width and height must be even (yuv420p).
    Use as a context manager: a clean exit renames the temporary file to ``path``; an exception keeps the
    frames written so far as ``<stem>.partial.mp4`` (see :func:`partial_path`).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        fps: float,
        crf: int = 20,
        preset: str = "veryfast",
        queue_frames: int = 8,
    ) -> None:
        if not (isinstance(fps, int | float) and np.isfinite(fps) and 0 < fps <= 1000):
            raise InvalidValueError("fps", fps, "frames per second in (0, 1000]")
        if isinstance(crf, bool) or not isinstance(crf, int) or not 0 <= crf <= 51:
            raise InvalidValueError("crf", crf, "an x264 constant rate factor, an integer 0..51")
        if preset not in X264_PRESETS:
            raise InvalidValueError("preset", preset, f"one of {', '.join(X264_PRESETS)}")
        self.path = Path(path)
        if self.path.suffix.lower() != ".mp4":
            raise InvalidValueError("path", str(path), "a file name ending in .mp4")
        self.fps, self.crf, self.preset = float(fps), crf, preset
        self.temp_path: Path | None = None
        """Where ffmpeg writes: a :func:`~mien.fileio.streams.temporary_path` next to ``path`` once the first
        frame arrives, renamed onto ``path`` by :meth:`close`."""
        self.n_frames = 0
        self.encode_wait_s = 0.0
        """Seconds the feeding thread spent blocked on ffmpeg (time ffmpeg was the bottleneck)."""
        self._size: tuple[int, int] | None = None
        self._process: subprocess.Popen[bytes] | None = None
        self._log: IO[bytes] | None = None
        self._queue: queue.Queue[np.ndarray | None] = queue.Queue(maxsize=max(1, queue_frames))
        self._thread: threading.Thread | None = None
        self._error: BaseException | None = None

    def _start(self, width: int, height: int) -> None:
        if width % 2 or height % 2:
            raise InvalidValueError("frame size", (width, height), "even width and height (H.264 yuv420p)")
        executable = _ffmpeg_exe()
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.temp_path = temporary_path(self.path)
        self._size = (width, height)
        command = [
            executable,
            *("-y", "-loglevel", "error", "-nostats"),
            *("-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", f"{self.fps:g}", "-i", "-"),
            *("-an", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", str(self.crf), "-preset", self.preset),
            *("-movflags", "+faststart", "-f", "mp4", str(self.temp_path)),
        ]
        self._log = tempfile.TemporaryFile()
        self._process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=self._log)
        self._thread = threading.Thread(target=self._feed, name="mien-mp4-writer", daemon=True)
        self._thread.start()

    def _feed(self) -> None:
        assert self._process is not None and self._process.stdin is not None
        stdin = self._process.stdin
        while True:
            frame = self._queue.get()
            if frame is None:
                return
            if self._error is not None:
                continue  # drain the queue so the producer never blocks
            try:
                stdin.write(frame.data.cast("B"))
            except BaseException as error:  # ffmpeg died (BrokenPipe) or similar: report to the producer
                self._error = error

    def write(self, frame: np.ndarray) -> None:
        """Queue one (height, width, 3) uint8 RGB frame; do not modify it afterwards."""
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise InvalidValueError("frame", (frame.shape, str(frame.dtype)), "(height, width, 3) uint8 RGB")
        height, width = frame.shape[:2]
        if self._size is None:
            self._start(width, height)
        elif (width, height) != self._size:
            raise InvalidValueError("frame size", (width, height), f"{self._size}, the size of the first frame")
        if self._error is not None:
            raise MienError(f"ffmpeg stopped taking frames: {self._ffmpeg_log() or self._error}")
        self._queue.put(np.ascontiguousarray(frame))
        self.n_frames += 1

    def _ffmpeg_log(self) -> str:
        if self._log is None:
            return ""
        self._log.seek(0)
        return self._log.read().decode(errors="replace").strip()

    def _finish(self) -> int:
        """Flush the queue, close ffmpeg's input, wait for it; returns ffmpeg's exit status."""
        if self._process is None:
            return 0
        self._queue.put(None)
        assert self._thread is not None and self._process.stdin is not None
        self._thread.join()
        with contextlib.suppress(BrokenPipeError):
            self._process.stdin.close()
        return self._process.wait()

    def close(self) -> Path:
        """Finish the video and move it to ``path``; returns ``path``."""
        status = self._finish()
        if self._process is None:
            raise InvalidValueError("frames", 0, "at least one frame to encode")
        assert self.temp_path is not None  # set with the process
        if status != 0 or self._error is not None:
            log = self._ffmpeg_log()
            self._cleanup()
            self.temp_path.unlink(missing_ok=True)
            raise MienError(f"ffmpeg failed (exit {status}) writing {self.path}: {log or self._error}")
        self._cleanup()
        os.replace(self.temp_path, self.path)
        return self.path

    def abort(self) -> Path | None:
        """Close the encoder after a failure; keeps the frames so far as ``<stem>.partial.mp4`` (returned)."""
        status = self._finish()
        self._cleanup()
        if self.temp_path is None:
            return None
        if self._process is None or status != 0 or not self.temp_path.exists() or self.n_frames == 0:
            self.temp_path.unlink(missing_ok=True)
            return None
        kept = partial_path(self.path)
        os.replace(self.temp_path, kept)
        return kept

    def _cleanup(self) -> None:
        if self._log is not None:
            self._log.close()
            self._log = None

    def __enter__(self) -> Mp4Writer:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *rest: object) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def write_mp4(
    frames: Iterable[np.ndarray],
    path: str | os.PathLike[str],
    fps: float,
    crf: int = 20,
    preset: str = "veryfast",
    total: int | None = None,
    progress: bool = False,
) -> Path:
    """Encode ``frames`` ((height, width, 3) uint8 RGB each, even sizes) to an H.264 MP4 at ``path``.

    ``frames`` may be a lazy iterator (rendering overlaps encoding). ``total`` (frame count) feeds the
    progress bar. If iterating ``frames`` raises, the frames so far are kept as ``<stem>.partial.mp4`` and
    the error propagates. Returns ``path``.
    """
    with Mp4Writer(path, fps, crf=crf, preset=preset) as writer:
        for frame in progress_bar(frames, total=total, desc=f"writing {Path(path).name}", enabled=progress):
            writer.write(frame)
    return Path(path)


def _check_image(image: np.ndarray) -> np.ndarray:
    image = np.asarray(image)
    if image.dtype != np.uint8 or not (image.ndim == 2 or (image.ndim == 3 and image.shape[2] in (3, 4))):
        raise InvalidValueError("image", (image.shape, str(image.dtype)), "(h, w), (h, w, 3) or (h, w, 4) uint8")
    if image.shape[0] == 0 or image.shape[1] == 0:
        raise InvalidValueError("image", image.shape, "a non-empty image")
    return image


def write_png(image: np.ndarray, path: str | os.PathLike[str], compress_level: int = 6) -> Path:
    """Save a (h, w) grey, (h, w, 3) RGB or (h, w, 4) RGBA uint8 ``image`` as PNG; returns ``path``.

    ``compress_level`` 0..9 trades speed for size (1 is several times faster than 6 for frame sequences).
    """
    image = _check_image(image)
    image_module = require("PIL.Image", "render")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as temporary:
        image_module.fromarray(image).save(temporary, format="PNG", compress_level=compress_level)
    return path


@dataclass(frozen=True)
class EncodedVideo:
    """Facts about an encoded video file's first video stream, its frames counted (what :func:`read_video_info`
    checks after writing); :class:`mien.tracking.video.VideoHeader` is what a video's container declares."""

    n_frames: int
    """Number of frames."""
    fps: float
    """Frames per second."""
    width: int
    """Frame width, pixels."""
    height: int
    """Frame height, pixels."""
    codec: str
    """Codec name (``"h264"``)."""
    pixel_format: str
    """Pixel format (``"yuv420p"``)."""

    @property
    def duration_s(self) -> float:
        """Length in seconds (frames / fps)."""
        return self.n_frames / self.fps


def read_video_info(path: str | os.PathLike[str]) -> EncodedVideo:
    """Frame count, fps, size, codec and pixel format of the video at ``path`` (PyAV; counts packets)."""
    av = require("av", "track")
    with av.open(str(path)) as container:
        stream = container.streams.video[0]
        n_frames = sum(1 for packet in container.demux(stream) if packet.size)
        context = stream.codec_context
        rate = stream.average_rate or stream.base_rate
        return EncodedVideo(
            n_frames=n_frames,
            fps=float(rate) if rate else 0.0,
            width=int(context.width),
            height=int(context.height),
            codec=str(context.name),
            pixel_format=str(context.pix_fmt),
        )
