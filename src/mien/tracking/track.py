"""Tracking a video: the :class:`Track` result, gap filling and takes, the per-video cache.

A frame without a face is marked (``face_found`` False). A gap of missing frames between two tracked frames
lasting at most ``max_gap_s`` (default :data:`MAX_GAP_S` = 0.2 s: a blink-length dropout, 6 frames at 30 fps)
is filled by linear interpolation and flagged in ``interpolated``; a longer gap ends the current take. Time
comes from each frame's own time stamp, never from an average rate, so variable-frame-rate videos keep their
timing: a gap lasts from its first missing frame to the next found frame (``k / fps`` seconds for ``k``
missing frames of a constant-rate video), and filled values are interpolated on the frames' real times.
Frames before the first and after the last face are never filled. A take is a maximal run of tracked or
filled frames, as a half-open ``(start, stop)`` frame range; :func:`resample_on_times` puts a take on a
regular grid where a fixed frame rate is needed.

Tracking results are cached under ``mien.paths.cache_dir("tracks")``, keyed by the video's absolute path,
size and modification time, the model file's SHA-256 and the tracker options, so a re-run is instant.
"""

from __future__ import annotations

import itertools
import json
import os
import zipfile
from dataclasses import dataclass, replace
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.clip import resample_on_times
from mien.fileio.container import load_container, save_container
from mien.fileio.hashing import file_sha256, key_sha256
from mien.fileio.streams import write_text
from mien.paths import cache_dir, require_asset
from mien.tracking.landmarker import MIN_CONFIDENCE, N_LANDMARKS, head_pose_deg
from mien.tracking.video import VideoHeader, probe

__all__ = [
    "MAX_GAP_S",
    "TRACKER_VERSION",
    "Track",
    "apply_gaps",
    "fill_gaps",
    "load_track",
    "resample_on_times",
    "track_video",
]

MAX_GAP_S = 0.2
"""Default longest gap (seconds) filled by interpolation instead of splitting the take."""

TRACKER_VERSION = 1
"""Bumped whenever per-frame tracking output changes, so old cache entries are not reused."""

TRACK_FORMAT = "mien-track"
"""Container kind of a ``.npz`` track file (:mod:`mien.fileio.container`)."""

TRACK_FORMAT_VERSION = 1
"""Track file version written (and the newest read; files from before the container read as version 0)."""


@dataclass(frozen=True, eq=False)
class Track:
    """Per-frame tracking of one face through a video.

    Arrays hold NaN on frames that are neither tracked nor filled (outside every take).
    """

    source: str
    """Absolute path of the tracked video."""
    fps: float
    """Average frame rate of the video, frames per second (a summary only: times come from ``timestamps_s``)."""
    width: int
    """Frame width, pixels."""
    height: int
    """Frame height, pixels."""
    timestamps_s: np.ndarray
    """(n,) float64 presentation time of each frame (its pts x time_base), seconds from the first frame;
    irregular for a variable-frame-rate video."""
    landmarks: np.ndarray
    """(n, 478, 3) float32 MediaPipe landmarks, normalised (x / width, y / height, z in x's scale)."""
    blendshapes: np.ndarray
    """(n, 52) float32 blendshape scores 0..1 in ARKIT_NAMES order (the subject's own sides)."""
    head_pose_deg: np.ndarray
    """(n, 3) float64 head yaw, pitch, roll in degrees (mien convention: yaw > 0 to the subject's left,
    pitch > 0 up, roll > 0 toward the left shoulder)."""
    face_found: np.ndarray
    """(n,) bool: the landmarker found a face on this frame."""
    interpolated: np.ndarray
    """(n,) bool: no face was found but the frame lies in a short gap and was filled by interpolation."""
    takes: tuple[tuple[int, int], ...]
    """Half-open frame ranges ``(start, stop)`` of continuous tracking (found or filled frames)."""
    max_gap_s: float = MAX_GAP_S
    """Longest gap (seconds) that was filled instead of splitting a take."""

    @property
    def n_frames(self) -> int:
        """Number of decoded frames."""
        return int(self.timestamps_s.shape[0])

    @property
    def duration_s(self) -> float:
        """Seconds covered: the last frame's time plus one median frame interval (``n / fps`` at a constant rate)."""
        times = self.timestamps_s
        if times.shape[0] == 0:
            return 0.0
        step = float(np.median(np.diff(times))) if times.shape[0] > 1 else 1.0 / self.fps
        return float(times[-1] - times[0]) + step

    @property
    def landmarks_px(self) -> np.ndarray:
        """(n, 478, 3) float32 landmarks in pixels: x * width, y * height, z * width (z in x's scale)."""
        return self.landmarks * np.array([self.width, self.height, self.width], dtype=np.float32)

    @property
    def tracked(self) -> np.ndarray:
        """(n,) bool: frames inside a take (found or filled)."""
        return self.face_found | self.interpolated

    def report(self) -> str:
        """One human-readable paragraph: frames, faces found, gaps filled, takes."""
        name = Path(self.source).name
        n = self.n_frames
        head = f"{name}: {n} frames at {self.fps:.2f} fps ({self.duration_s:.2f} s), {self.width}x{self.height}"
        found = int(self.face_found.sum())
        if not self.takes:
            return f"{head}; no face found on any frame: 0 takes."
        lines = [
            f"{head}; face found on {found} frames ({100.0 * found / max(n, 1):.0f}%), "
            f"{int(self.interpolated.sum())} filled by interpolation (gaps <= {self.max_gap_s:g} s), "
            f"{len(self.takes)} take(s):"
        ]
        for start, stop in self.takes:
            lines.append(
                f"  frames {start}-{stop - 1} ({self.timestamps_s[start]:.2f}-{self.timestamps_s[stop - 1]:.2f} s)"
            )
        return "\n".join(lines)

    def arrays(self) -> dict[str, np.ndarray]:
        """The per-frame arrays by field name (plus ``landmarks_px`` and ``takes`` as an (k, 2) array)."""
        return {
            "timestamps_s": self.timestamps_s,
            "landmarks": self.landmarks,
            "landmarks_px": self.landmarks_px,
            "blendshapes": self.blendshapes,
            "head_pose_deg": self.head_pose_deg,
            "face_found": self.face_found,
            "interpolated": self.interpolated,
            "takes": np.array(self.takes, dtype=np.int64).reshape(-1, 2),
        }

    def meta(self) -> dict[str, Any]:
        """Scalar fields: source, fps, size, max_gap_s, blendshape names."""
        return {
            "source": self.source,
            "fps": self.fps,
            "width": self.width,
            "height": self.height,
            "max_gap_s": self.max_gap_s,
            "blendshape_names": list(ARKIT_NAMES),
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write to ``.npz`` (a :mod:`mien.fileio.container` of kind ``mien-track``, written atomically) or
        ``.json`` (NaN as null); returns the path."""
        out = Path(path)
        if out.suffix == ".npz":
            save_container(out, TRACK_FORMAT, TRACK_FORMAT_VERSION, self.meta(), self.arrays())
        elif out.suffix == ".json":
            data: dict[str, Any] = self.meta()
            for key, value in self.arrays().items():
                data[key] = _json_array(value)
            write_text(json.dumps(data, separators=(",", ":")), out)
        else:
            raise InvalidValueError("output", str(out), "a path ending in .npz or .json")
        return out


def _json_array(values: np.ndarray) -> Any:
    if values.dtype.kind == "f":
        rounded = np.round(values.astype(np.float64), 6).astype(object)
        rounded[np.isnan(values)] = None
        return rounded.tolist()
    return values.tolist()


def load_track(path: str | os.PathLike[str]) -> Track:
    """Read a track written by :meth:`Track.save` (``.npz`` or ``.json``)."""
    file = Path(path)
    try:
        if file.suffix == ".npz":
            box = load_container(file, TRACK_FORMAT, TRACK_FORMAT_VERSION)
            meta, arrays = box.meta, box.arrays
        elif file.suffix == ".json":
            raw = json.loads(file.read_text("utf-8"))
            meta = {k: raw[k] for k in ("source", "fps", "width", "height", "max_gap_s")}
            arrays = {
                k: np.array(raw[k], dtype=np.float64 if k not in ("face_found", "interpolated", "takes") else None)
                for k in ("timestamps_s", "landmarks", "blendshapes", "head_pose_deg", "face_found", "interpolated")
            }
            arrays["takes"] = np.array(raw["takes"], dtype=np.int64).reshape(-1, 2)
        else:
            raise InvalidValueError("track file", str(file), "a .npz or .json track")
        return Track(
            source=str(meta["source"]),
            fps=float(meta["fps"]),
            width=int(meta["width"]),
            height=int(meta["height"]),
            timestamps_s=np.asarray(arrays["timestamps_s"], dtype=np.float64),
            landmarks=np.asarray(arrays["landmarks"], dtype=np.float32).reshape(-1, N_LANDMARKS, 3),
            blendshapes=np.asarray(arrays["blendshapes"], dtype=np.float32).reshape(-1, len(ARKIT_NAMES)),
            head_pose_deg=np.asarray(arrays["head_pose_deg"], dtype=np.float64).reshape(-1, 3),
            face_found=np.asarray(arrays["face_found"], dtype=bool),
            interpolated=np.asarray(arrays["interpolated"], dtype=bool),
            takes=tuple((int(a), int(b)) for a, b in np.asarray(arrays["takes"]).reshape(-1, 2)),
            max_gap_s=float(meta["max_gap_s"]),
        )
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        if isinstance(exc, InvalidValueError):
            raise
        raise InvalidValueError("track file", str(file), f"a track written by mien ({exc})") from None


def fill_gaps(
    face_found: np.ndarray, fps: float, max_gap_s: float = MAX_GAP_S, times_s: np.ndarray | None = None
) -> tuple[np.ndarray, list[tuple[int, int]]]:
    """Which missing frames to fill, and the takes.

    face_found: (n,) bool. times_s: (n,) frame times in seconds (default ``arange(n) / fps``: a constant
    rate). Returns ``(interpolated (n,) bool, takes)``: interior runs of missing frames lasting at most
    ``max_gap_s`` seconds (from the first missing frame to the next found one: ``k / fps`` for ``k`` frames
    at a constant rate) are filled; longer runs split takes.

    >>> fill_gaps(np.array([1, 0, 1, 0, 0, 0, 1], bool), fps=10.0, max_gap_s=0.2)[1]
    [(0, 3), (6, 7)]
    """
    if not np.isfinite(max_gap_s) or max_gap_s < 0:
        raise InvalidValueError("max_gap_s", max_gap_s, "a finite number of seconds >= 0")
    found = np.asarray(face_found, dtype=bool)
    filled = np.zeros_like(found)
    hits = np.flatnonzero(found)
    if hits.size == 0:
        return filled, []
    times = np.arange(found.shape[0]) / float(fps) if times_s is None else np.asarray(times_s, dtype=np.float64)
    takes: list[tuple[int, int]] = []
    start = int(hits[0])
    for previous, current in itertools.pairwise(hits):
        missing = int(current - previous - 1)
        if missing == 0:
            continue
        if times[current] - times[previous + 1] <= max_gap_s + 1e-9:
            filled[previous + 1 : current] = True
        else:
            takes.append((start, int(previous) + 1))
            start = int(current)
    takes.append((start, int(hits[-1]) + 1))
    return filled, takes


def _interpolate(values: np.ndarray, found: np.ndarray, fill: np.ndarray, times_s: np.ndarray) -> np.ndarray:
    """Linear interpolation on the frames' real times ``times_s`` (n,) of ``values`` (n, ...) on ``fill``
    frames from ``found`` frames."""
    out = values.copy()
    out[~found] = np.nan  # frames filled for an earlier max_gap_s start empty again
    if not fill.any():
        return out
    known, wanted = np.flatnonzero(found), np.flatnonzero(fill)
    after = np.searchsorted(known, wanted)  # filled frames always lie between two found ones
    before_frame, after_frame = known[after - 1], known[after]
    times = np.asarray(times_s, dtype=np.float64)
    span = np.maximum(times[after_frame] - times[before_frame], 1e-12)
    weight = ((times[wanted] - times[before_frame]) / span).reshape((-1,) + (1,) * (values.ndim - 1))
    out[wanted] = (1.0 - weight) * out[before_frame] + weight * out[after_frame]
    return out


def apply_gaps(raw: Track, max_gap_s: float = MAX_GAP_S) -> Track:
    """``raw`` with missing frames re-filled and takes re-split for ``max_gap_s`` (from ``face_found``)."""
    times = raw.timestamps_s
    filled, takes = fill_gaps(raw.face_found, raw.fps, max_gap_s, times)
    return replace(
        raw,
        landmarks=_interpolate(raw.landmarks, raw.face_found, filled, times),
        blendshapes=_interpolate(raw.blendshapes, raw.face_found, filled, times),
        head_pose_deg=_interpolate(raw.head_pose_deg, raw.face_found, filled, times),
        interpolated=filled,
        takes=tuple(takes),
        max_gap_s=float(max_gap_s),
    )


@cache
def _file_sha256(path: str, size: int, mtime_ns: int) -> str:
    return file_sha256(path)  # cached per (size, mtime): the model is hashed once per process


def _cache_key(video: Path, model: Path, min_confidence: float) -> str:
    stat, model_stat = video.stat(), model.stat()
    key = {
        "video": str(video),
        "size": stat.st_size,
        "mtime_ns": stat.st_mtime_ns,
        "model_sha256": _file_sha256(str(model), model_stat.st_size, model_stat.st_mtime_ns),
        "options": {"num_faces": 1, "min_confidence": min_confidence, "version": TRACKER_VERSION},
    }
    return key_sha256(key, 32)


def track_video(
    video: str | os.PathLike[str],
    model: str | os.PathLike[str] | None = None,
    *,
    max_gap_s: float = MAX_GAP_S,
    min_confidence: float = MIN_CONFIDENCE,
    use_cache: bool = True,
    show_progress: bool = True,
    workers: int | None = None,
) -> Track:
    """Track the face through ``video``: landmarks, blendshapes and head pose on every frame.

    model: ``face_landmarker.task`` (default: the configured asset). max_gap_s: longest gap filled by
    interpolation (seconds). min_confidence: MediaPipe's detection / presence / tracking thresholds.
    use_cache: reuse / store the per-frame result (gap filling is re-applied, so changing ``max_gap_s`` needs
    no re-tracking). show_progress: a progress bar on stderr. workers: processes tracking contiguous segments of
    the video at once (:mod:`mien.tracking.parallel`; None: one per CPU for a video long enough to gain, else 1;
    1: the whole video in this process). The results of any worker count agree within tracker noise, so the cache
    entry does not depend on it (an entry written by a run with more workers serves a run with fewer and the other
    way round). A video without any face gives a Track with no takes.
    Raises :class:`InvalidValueError` naming the file when it is missing, truncated or not a video.
    """
    from mien.tracking.parallel import check_workers

    if not np.isfinite(max_gap_s) or max_gap_s < 0:
        raise InvalidValueError("max_gap_s", max_gap_s, "a finite number of seconds >= 0")
    check_workers(workers)
    path = Path(video).expanduser().resolve()
    info = probe(path)
    model_path = require_asset("face_landmarker", model)
    cached = cache_dir("tracks") / f"{_cache_key(path, model_path, min_confidence)}.npz" if use_cache else None
    if cached is not None and cached.is_file():
        try:
            return apply_gaps(load_track(cached), max_gap_s)
        except InvalidValueError:
            cached.unlink(missing_ok=True)  # a damaged cache entry: track again
    raw = _track_frames(path, model_path, min_confidence, info, workers, show_progress)
    if cached is not None:
        raw.save(cached)  # atomic: a temporary file, then a rename
    return apply_gaps(raw, max_gap_s)


def _track_frames(
    path: Path, model: Path, min_confidence: float, info: VideoHeader, workers: int | None, show_progress: bool
) -> Track:
    from mien.tracking.parallel import track_frames

    frames = track_frames(path, model, min_confidence, info.n_frames, workers, show_progress)
    n = frames.times_s.shape[0]
    return Track(
        source=str(path),
        fps=info.fps,
        width=info.width,
        height=info.height,
        timestamps_s=frames.times_s,
        landmarks=frames.landmarks,
        blendshapes=frames.blendshapes,
        head_pose_deg=head_pose_deg(frames.matrices) if n else np.zeros((0, 3)),
        face_found=frames.found,
        interpolated=np.zeros(n, dtype=bool),
        takes=(),
        max_gap_s=0.0,
    )
