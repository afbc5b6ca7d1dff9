"""A live capture source: a camera or a video file played at its real rate drives characters' faces.

Two threads, so the server's clock never waits on a camera or a tracker (MediaPipe and FFmpeg release the GIL
while they work):

- the *reader* reads the camera (:func:`mien.tracking.camera.iter_camera`), or decodes the video file
  (:func:`mien.tracking.video.iter_frames`) and hands each frame over when its own time stamp comes due, so a
  variable frame rate keeps its timing (``loop``: the file starts again at its end). It keeps only the newest
  frame: a frame that arrives while the tracker is still busy replaces the waiting one (``frames_dropped``), as a
  camera's driver does, so the latency never grows a queue;
- the *tracker* runs MediaPipe's face landmarker (:class:`mien.tracking.landmarker.Landmarker`, video mode) on the
  newest frame and turns blendshapes and head rotation into a (62,) face frame through
  :class:`mien.capture.stream.CaptureStream` (the performer's neutral subtracted, jitter filtered, a lost face
  held then eased to neutral).

Each tick, the registry gives the newest face frame to every character that follows the source
(:meth:`CaptureSource.latest` -> :meth:`mien.character.CharacterBatch.set_performance`): the performance is a layer
under emotions, laughter and idle, which add on top or are switched off as on any character. Several characters
may follow one source (a second character mirrors the first; one tracker serves them all).

Fallbacks, each visible in ``GET /api/capture`` (``state``, counters, ``error``): no face in the picture (``no_face``:
the face holds its last pose, then eases to neutral, ``frames_without_face``); a face narrower than
:attr:`CaptureConfig.min_face_px` pixels (treated as no face: its blendshapes are tracker noise,
``frames_face_too_small``); a camera that stops or a video that turns out corrupt or truncated while playing
(``failed`` with the error, the face eases to neutral); a video at its end (``ended``). A camera that does not
exist or is busy, a file that is no readable video, and a missing landmarker model are refused before the server
starts (:meth:`CaptureSource.check`).
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.errors import InvalidValueError

__all__ = ["MIN_FACE_PX", "CaptureConfig", "CaptureSource"]

log = logging.getLogger("mien.server")

MIN_FACE_PX = 48.0
"""Narrowest face tracked, pixels (the horizontal extent of its landmarks): below it MediaPipe's blendshapes are
mostly noise, so such a frame counts as one without a face."""

TIMINGS_KEPT = 1024
"""Frames whose timings ``GET /api/capture`` lists (the newest)."""

_STALL_S = 0.25  # no new frame for this long: the face counts as lost (a camera that stalls)
_EASE_PERIOD_S = 1.0 / 30.0  # how often a lost face's ease to neutral is stepped


@dataclass(frozen=True)
class CaptureConfig:
    """A capture source of ``mien serve --capture``."""

    source: str
    """A camera (``/dev/video0``, ``camera:0``) or a video file played at its real rate."""
    characters: tuple[str, ...] = ()
    """Ids of the characters that follow it at start (empty: the first character)."""
    loop: bool = False
    """A video file starts again at its end (a camera ignores it)."""
    model: str | None = None
    """MediaPipe ``face_landmarker.task`` (None: the configured ``face_landmarker`` asset)."""
    min_face_px: float = MIN_FACE_PX
    """Narrowest face tracked, pixels (:data:`MIN_FACE_PX`)."""

    def __post_init__(self) -> None:
        if not isinstance(self.source, str) or not self.source:
            raise InvalidValueError("capture", self.source, "a camera (/dev/video0, camera:0) or a video file")
        if not (isinstance(self.min_face_px, int | float) and math.isfinite(self.min_face_px)) or self.min_face_px < 0:
            raise InvalidValueError("min_face_px", self.min_face_px, "a face width in pixels >= 0")


class _Newest:
    """A one-frame mailbox: put replaces what waits (and says so), get waits up to a timeout."""

    def __init__(self) -> None:
        self._item: tuple[float, float, np.ndarray] | None = None
        self._ready = threading.Condition()

    def put(self, item: tuple[float, float, np.ndarray]) -> bool:
        with self._ready:
            replaced = self._item is not None
            self._item = item
            self._ready.notify()
            return replaced

    def get(self, timeout_s: float) -> tuple[float, float, np.ndarray] | None:
        with self._ready:
            if self._item is None:
                self._ready.wait(timeout_s)
            item, self._item = self._item, None
            return item

    def wake(self) -> None:
        with self._ready:
            self._ready.notify_all()


class CaptureSource:
    """A camera or video file tracked in its own threads; see the module docstring.

    >>> source = CaptureSource(CaptureConfig("/work/no/such/video.mp4"))
    >>> source.kind
    'file'
    """

    def __init__(self, config: CaptureConfig) -> None:
        from mien.tracking.camera import camera_device

        self.config = config
        """How it was configured."""
        self.device = camera_device(config.source)
        """The camera device, or None for a video file."""
        self.kind = "file" if self.device is None else "camera"
        """``"camera"`` or ``"file"``."""
        self.state = "stopped"
        """``starting``, ``tracking``, ``no_face``, ``ended``, ``failed`` or ``stopped``."""
        self.error: str | None = None
        """Why it failed (``state == "failed"``)."""
        self.counts = dict.fromkeys(
            ("frames_read", "frames_tracked", "frames_dropped", "frames_without_face", "frames_face_too_small"), 0
        )
        """Frames read, tracked, replaced before the tracker took them, without a face, with a face too small."""
        self._lock = threading.Lock()
        self._newest = _Newest()
        self._stop = threading.Event()
        self._finished = threading.Event()  # the reader has no more frames (end, failure, stop)
        self._ready = threading.Event()  # the tracker is warm: the reader may start (a video's time starts then)
        self._threads: list[threading.Thread] = []
        self._frame: np.ndarray | None = None  # newest (62,) face frame
        self._seq = 0  # its number (0: none yet)
        self._consumed = 0  # newest number a tick took
        self._has_face = False
        self._costs: deque[float] = deque(maxlen=256)  # tracking seconds of the recent frames
        self._timings: deque[list[Any]] = deque(maxlen=TIMINGS_KEPT)  # [seq, arrival, start, tracked, tick, source_s]
        self._origin = 0.0  # time.monotonic() of the capture's time 0

    # ------------------------------------------------------------------ set-up

    def check(self) -> None:
        """Refuse what cannot work before the server starts (:class:`InvalidValueError` naming the value): a camera
        that does not exist, is busy or is no camera; a missing file or one that is no readable video; a missing
        landmarker model or one MediaPipe refuses."""
        from mien.paths import require_asset

        if self.device is not None:
            from mien.tracking.camera import check_camera

            check_camera(self.device)
        else:
            from mien.tracking.video import probe

            header = probe(self.config.source)
            if header.width <= 0 or header.height <= 0:
                raise InvalidValueError("video", self.config.source, "a video with frames (its size is 0)")
        require_asset("face_landmarker", self.config.model)
        from mien.tracking.landmarker import Landmarker

        Landmarker(self.config.model, mode="image").close()  # a file MediaPipe refuses is named here, not later

    def start(self) -> None:
        """Start the reader and the tracker threads (idempotent while running)."""
        if self._threads:
            return
        self.state, self.error = "starting", None
        self._stop.clear()
        self._finished.clear()
        self._ready.clear()
        self._origin = time.monotonic()
        self._threads = [
            threading.Thread(target=self._read, name="mien-capture-read", daemon=True),
            threading.Thread(target=self._track, name="mien-capture-track", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop both threads (a camera is released) and wait for them up to ``timeout_s``."""
        self._stop.set()
        self._newest.wake()
        for thread in self._threads:
            thread.join(timeout_s)
        self._threads = []
        if self.state not in ("failed", "ended"):
            self.state = "stopped"

    # ------------------------------------------------------------------ the clock's side

    def latest(self) -> tuple[int, np.ndarray | None]:
        """``(number, (62,) face frame)`` of the newest tracked frame (``(0, None)`` before the first); the tick
        that takes it is noted for its timings (:meth:`on_tick`). Never blocks on the tracker beyond a copy."""
        with self._lock:
            self._consumed = max(self._consumed, self._seq)
            return self._seq, self._frame

    def on_tick(self, tick: int, t_s: float) -> None:
        """Clock listener: note ``tick`` as the first to show the frames taken since the last tick."""
        with self._lock:
            consumed = self._consumed
            for timing in reversed(self._timings):
                if timing[4] is not None:
                    break
                if timing[0] <= consumed:
                    timing[4] = tick

    def status(self) -> dict[str, Any]:
        """What ``GET /api/capture`` shows: source, kind, state, error, face found, the counters, tracking time
        (median and 99th percentile of the recent frames, ms) and the recent frames' timings."""
        with self._lock:
            costs = np.array(self._costs) * 1e3 if self._costs else None
            timings = [
                {
                    "frame": seq,
                    "source_s": source_s,
                    "arrival_s": arrival,
                    "track_start_s": start,
                    "tracked_s": tracked,
                    "tick": tick,
                }
                for seq, arrival, start, tracked, tick, source_s in self._timings
            ]
            return {
                "source": self.config.source,
                "kind": self.kind,
                "loop": self.config.loop and self.kind == "file",
                "state": self.state,
                "error": self.error,
                "has_face": self._has_face,
                **self.counts,
                "tracking_ms": float(np.median(costs)) if costs is not None else None,
                "tracking_p99_ms": float(np.percentile(costs, 99)) if costs is not None else None,
                "timings": timings,
            }

    # ------------------------------------------------------------------ threads

    def _frames(self) -> Iterator[tuple[float, float, np.ndarray]]:
        """``(arrival monotonic s, source time s, rgb)``: a camera's frames as read (source time: since the start), a
        file's when their time stamps come due (source time: the time stamp, plus the earlier passes of a loop)."""
        if self.device is not None:
            from mien.tracking.camera import iter_camera

            for arrival_s, rgb in iter_camera(self.device):
                yield arrival_s, arrival_s - self._origin, rgb
            return
        from mien.tracking.video import iter_frames

        offset_s = self._origin
        while True:
            last_s, period_s = 0.0, 1.0 / 30.0
            for pts_s, rgb in iter_frames(self.config.source):
                due = offset_s + pts_s
                if self._stop.wait(max(0.0, due - time.monotonic())):
                    return
                if pts_s > last_s:
                    period_s = pts_s - last_s
                last_s = pts_s
                yield time.monotonic(), offset_s - self._origin + pts_s, rgb
            if not self.config.loop:
                return
            offset_s += last_s + period_s  # the next pass starts one frame after the last one

    def _read(self) -> None:
        try:
            while not self._ready.wait(0.05):  # the landmarker loads first, so the video does not play unseen
                if self._stop.is_set() or self.state == "failed":
                    return
            for arrival_s, source_s, rgb in self._frames():
                if self._stop.is_set():
                    return
                with self._lock:
                    self.counts["frames_read"] += 1
                if self._newest.put((arrival_s, source_s, rgb)):
                    with self._lock:
                        self.counts["frames_dropped"] += 1
            with self._lock:
                if not self._stop.is_set() and self.state != "failed":
                    self.state = "ended"
        except Exception as exc:  # a corrupt or truncated video, an unplugged camera: the server goes on
            with self._lock:
                self.state, self.error = "failed", str(exc)[:300]
            log.warning("capture %s failed: %s", self.config.source, exc)
        finally:
            self._finished.set()
            self._newest.wake()

    def _track(self) -> None:
        try:
            from mien.capture.stream import CaptureStream
            from mien.tracking.landmarker import Landmarker

            stream = CaptureStream()
            with Landmarker(self.config.model, mode="video") as landmarker:
                landmarker.detect(np.zeros((64, 64, 3), np.uint8), 0.0)  # MediaPipe's first frame is slow
                self._origin = time.monotonic()
                self._ready.set()
                last_s = time.monotonic()  # when the last frame came
                stream_s = -1.0  # the stream's last time: times pushed must increase
                while not self._stop.is_set():
                    item = self._newest.get(_EASE_PERIOD_S)
                    now = time.monotonic()
                    if item is None:  # nothing new: a stalled camera or a video at its end loses the face
                        if self._finished.is_set() or now - last_s >= _STALL_S:
                            stream_s = max(now - self._origin, stream_s + 1e-6)
                            self._publish(stream.push(stream_s, None, None), None, 0.0, now, now, False)
                        continue
                    arrival_s, source_s, rgb = item
                    last_s = now
                    begin = time.perf_counter()
                    found = landmarker.detect(rgb, arrival_s - self._origin)
                    cost = time.perf_counter() - begin
                    small = found is not None and self._face_px(found.landmarks, rgb.shape[1]) < self.config.min_face_px
                    face = found is not None and not small
                    blendshapes = found.blendshapes if face and found is not None else None
                    rotation = found.head_pose_deg if face and found is not None else None
                    stream_s = max(arrival_s - self._origin, stream_s + 1e-6)
                    frame = stream.push(stream_s, blendshapes, rotation)
                    with self._lock:
                        self._costs.append(cost)
                        self.counts["frames_tracked"] += 1
                        self.counts["frames_without_face"] += found is None
                        self.counts["frames_face_too_small"] += small
                    self._publish(frame, arrival_s, source_s, now, time.monotonic(), face)
        except Exception as exc:  # a model MediaPipe refuses, a bug: the followers drop to neutral at once
            with self._lock:
                self.state, self.error = "failed", f"tracking failed: {exc}"[:300]
                self._frame = None
            log.warning("capture %s: tracking failed: %s", self.config.source, exc)

    @staticmethod
    def _face_px(landmarks: np.ndarray, width: int) -> float:
        """The face's width in pixels (its landmarks' horizontal extent)."""
        x = landmarks[:, 0]
        return float((x.max() - x.min()) * width)

    def _publish(
        self,
        frame: np.ndarray,
        arrival_s: float | None,
        source_s: float,
        start_s: float,
        tracked_s: float,
        face: bool,
    ) -> None:
        values = np.array(frame, dtype=np.float64)
        if not np.isfinite(values).all():
            values = np.nan_to_num(values, nan=0.0, posinf=0.0, neginf=0.0)
        with self._lock:
            self._seq += 1
            self._frame = values
            self._has_face = face
            if arrival_s is not None:
                self._timings.append([self._seq, arrival_s, start_s, tracked_s, None, source_s])
            if self.state in ("starting", "tracking", "no_face"):
                self.state = "tracking" if face else "no_face"
