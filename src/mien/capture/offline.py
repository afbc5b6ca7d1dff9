"""A whole recording captured at once: a video, a track file or a Live Link CSV -> a :class:`Capture`.

Every source runs through the one :class:`~mien.capture.stream.CaptureStream` a live source uses, frame by
frame on the recording's own time stamps; only the neutral differs: offline it is computed from the whole
interval first (the median of its frames with a face) and subtracted from every frame, the first ones included.
Frames where the tracker found no face are pushed as faceless (the track's short-gap interpolation is not
used: the stream's hold covers a dropout, as it does live) and marked in :attr:`Capture.face_found`.

A :class:`Capture` becomes a clip with :meth:`Capture.clip`: the AU route (62 face channels) or the ARKit
pass-through route (the 52 filtered, neutral-subtracted scores and the head rotation, for a head with the
performer's ARKit names), plus the :data:`FACE_FOUND_CHANNEL` mask (1 with a face, 0 without) unless left out.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mien.capture.settings import CaptureSettings
from mien.capture.stream import N_BLENDSHAPES, N_INPUT, CaptureStream
from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.facs.clip import Clip, resample_on_times
from mien.progress import progress

if TYPE_CHECKING:
    from mien.tracking.track import Track

__all__ = [
    "FACE_FOUND_CHANNEL",
    "ROUTES",
    "Capture",
    "capture_file",
    "capture_frames",
    "capture_track",
    "capture_video",
    "capture_weight_clip",
    "neutral_from_frames",
    "neutral_from_image",
    "strip_face_mask",
]

FACE_FOUND_CHANNEL = "face_found"
"""Name of a captured clip's mask channel: 1 on frames with the performer's face, 0 on frames without."""

ROUTES: tuple[str, ...] = ("au", "arkit")
"""Clip routes: AU intensities through the reverse mapping, or the ARKit scores passed straight through."""

_HEAD_CHANNELS = ("head_yaw_deg", "head_pitch_deg", "head_roll_deg")


@dataclass(frozen=True, eq=False)
class Capture:
    """A captured performance, one row per recorded frame."""

    source: str
    """The recording (absolute path)."""
    fps: float
    """Average frame rate of the recording, frames per second (the clip's rate)."""
    times_s: np.ndarray
    """(n,) float64 each frame's own time, seconds from the first frame."""
    frames: np.ndarray
    """(n, 62) float64 face frames over FACE_CHANNELS (AU intensities 0..5, head and gaze degrees)."""
    weights: np.ndarray
    """(n, 52) float64 filtered, neutral-subtracted ARKit scores 0..1 (the pass-through route)."""
    face_found: np.ndarray
    """(n,) bool: the performer's face was found on the frame (others hold, then ease to neutral)."""
    neutral: np.ndarray
    """(55,) the subtracted neutral: 52 ARKit scores, head yaw/pitch/roll degrees (zeros: none)."""
    settings: CaptureSettings
    """The settings it was captured with."""

    @property
    def n_frames(self) -> int:
        """Recorded frames."""
        return int(self.times_s.shape[0])

    def clip(self, route: str = "au", mask: bool = True) -> Clip:
        """The capture as a clip at :attr:`fps` (resampled from the frame times: unchanged at a constant rate).

        route: ``"au"`` (FACE_CHANNELS) or ``"arkit"`` (the 52 ARKit names and the head rotation; gaze is
        in the ``eyeLook*`` scores). mask: add the :data:`FACE_FOUND_CHANNEL` channel (0 on frames without a
        face, and on any grid frame next to one).
        """
        if route not in ROUTES:
            raise InvalidValueError("route", route, " or ".join(ROUTES))
        if route == "au":
            values, channels = self.frames, FACE_CHANNELS
        else:
            head = [FACE_CHANNELS.index(c) for c in _HEAD_CHANNELS]
            values, channels = np.hstack([self.weights, self.frames[:, head]]), (*ARKIT_NAMES, *_HEAD_CHANNELS)
        if mask:
            values = np.hstack([values, self.face_found[:, None].astype(np.float64)])
            channels = (*channels, FACE_FOUND_CHANNEL)
        grid = resample_on_times(self.times_s, values, self.fps) if self.n_frames > 1 else values.copy()
        if mask:
            grid[:, -1] = np.floor(grid[:, -1] + 1e-9)  # a frame between a faceless one and a face is faceless
        return Clip(grid, self.fps, channels)

    def report(self) -> str:
        """One line: frames, faces, neutral."""
        n, found = self.n_frames, int(self.face_found.sum())
        calibrated = "neutral subtracted" if np.any(self.neutral) else "no neutral"
        return (
            f"{Path(self.source).name}: {n} frames at {self.fps:.2f} fps, face on {found} "
            f"({100.0 * found / max(n, 1):.0f}%), {n - found} marked faceless; {calibrated}"
        )


def neutral_from_frames(
    times_s: np.ndarray,
    blendshapes: np.ndarray,
    head_pose_deg: np.ndarray,
    found: np.ndarray,
    settings: CaptureSettings,
) -> np.ndarray:
    """(55,) the neutral of a recording: the median of its frames with a face in the settings' interval.

    Zeros when calibration is off (``neutral_first_s`` 0 and no ``neutral_s``) or no frame has a face. Raises
    :class:`InvalidValueError` when a chosen interval holds no frame with a face.
    """
    if settings.neutral_s is None and settings.neutral_first_s <= 0:
        return np.zeros(N_INPUT)
    hits = np.flatnonzero(found)
    if hits.size == 0:
        return np.zeros(N_INPUT)
    times = np.asarray(times_s, dtype=np.float64)
    inside = [i for i in hits if settings.in_neutral(float(times[i]), float(times[hits[0]]))]
    if not inside:
        start, end = settings.neutral_s or (0.0, 0.0)
        raise InvalidValueError(
            "neutral interval",
            f"{start:g}:{end:g}",
            f"an interval with frames showing the face (the recording lasts {times[-1]:.2f} s; the face is found "
            f"from {times[hits[0]]:.2f} s to {times[hits[-1]]:.2f} s)",
        )
    rows = np.hstack([np.asarray(blendshapes, np.float64)[inside], np.asarray(head_pose_deg, np.float64)[inside]])
    return np.asarray(np.median(rows, axis=0))


def neutral_from_image(image: str | os.PathLike[str], model: str | os.PathLike[str] | None = None) -> np.ndarray:
    """(55,) the neutral from a still picture of the performer's neutral face (52 scores, yaw/pitch/roll).

    Raises :class:`InvalidValueError` (field ``neutral image``) for a missing or unreadable picture or one
    without a face.
    """
    from mien.extras import require
    from mien.tracking.landmarker import Landmarker

    path = Path(image)
    if not path.is_file():
        raise InvalidValueError("neutral image", str(path), "an existing picture of the performer's neutral face")
    pil = require("PIL.Image")
    try:
        with pil.open(path) as picture:
            rgb = np.asarray(picture.convert("RGB"))
    except (OSError, ValueError) as exc:
        raise InvalidValueError("neutral image", str(path), f"a readable picture (PNG, JPEG...): {exc}") from None
    with Landmarker(model, mode="image") as landmarker:
        result = landmarker.detect(rgb)
    if result is None:
        raise InvalidValueError("neutral image", str(path), "a picture showing the performer's face (none found)")
    return np.r_[result.blendshapes.astype(np.float64), result.head_pose_deg]


def capture_frames(
    source: str,
    fps: float,
    times_s: np.ndarray,
    blendshapes: np.ndarray,
    head_pose_deg: np.ndarray,
    found: np.ndarray,
    settings: CaptureSettings | None = None,
    *,
    neutral: np.ndarray | None = None,
    show_progress: bool = False,
) -> Capture:
    """Run a :class:`CaptureStream` over recorded frames: ``times_s`` (n,) seconds, ``blendshapes`` (n, 52),
    ``head_pose_deg`` (n, 3) and ``found`` (n,) bool (values of frames without a face are ignored).

    neutral: a (55,) neutral (default: from the settings' interval, :func:`neutral_from_frames`).
    """
    settings = settings or CaptureSettings()
    found = np.asarray(found, dtype=bool)
    n = found.shape[0]
    times = np.asarray(times_s, dtype=np.float64)
    if times.shape != (n,) or np.asarray(blendshapes).shape != (n, N_BLENDSHAPES):
        raise InvalidValueError("frames", np.asarray(blendshapes).shape, f"({n}, 52) scores for {n} times")
    bad = np.flatnonzero(np.diff(times) <= 0)
    if bad.size or not np.all(np.isfinite(times)):
        where = f"frame {bad[0] + 1} at {times[bad[0] + 1]:.4f} s" if bad.size else "a time stamp that is not finite"
        raise InvalidValueError(f"{Path(source).name} frame times", where, "increasing time stamps (re-encode it)")
    if neutral is None:
        neutral = neutral_from_frames(times, blendshapes, head_pose_deg, found, settings)
    stream = CaptureStream(settings, neutral=neutral)
    frames = np.zeros((n, len(FACE_CHANNELS)))
    weights = np.zeros((n, N_BLENDSHAPES))
    rows = progress(range(n), total=n, desc=f"capturing {Path(source).name}", enabled=show_progress)
    for i in rows:
        face = bool(found[i])
        frames[i] = stream.push(times[i], blendshapes[i] if face else None, head_pose_deg[i] if face else None)
        weights[i] = stream.weights
    return Capture(str(source), float(fps), times, frames, weights, found.copy(), stream.neutral, settings)


def capture_track(
    track: Track, settings: CaptureSettings | None = None, *, neutral: np.ndarray | None = None
) -> Capture:
    """Capture a :class:`~mien.tracking.track.Track` (``mien track``'s output): only frames where the face was
    found count as faces (short gaps the tracker filled are faceless here and held by the stream)."""
    return capture_frames(
        track.source,
        track.fps,
        track.timestamps_s,
        track.blendshapes,
        track.head_pose_deg,
        track.face_found,
        settings,
        neutral=neutral,
    )


def capture_video(
    video: str | os.PathLike[str],
    settings: CaptureSettings | None = None,
    *,
    neutral: np.ndarray | None = None,
    model: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
    show_progress: bool = True,
    workers: int | None = None,
) -> Capture:
    """Track ``video`` (MediaPipe, :func:`mien.tracking.track_video`, cached) and capture it.

    neutral: a (55,) neutral (e.g. :func:`neutral_from_image`); default from the settings' interval. workers:
    tracking processes (:func:`mien.tracking.track_video`; None: one per CPU for a long enough video). A video
    without any face gives a capture whose frames are all neutral and marked faceless.
    """
    from mien.tracking.track import track_video

    track = track_video(video, model, use_cache=use_cache, show_progress=show_progress, workers=workers)
    return capture_track(track, settings, neutral=neutral)


def capture_weight_clip(
    clip: Clip, source: str, settings: CaptureSettings | None = None, *, neutral: np.ndarray | None = None
) -> Capture:
    """Capture a clip of ARKit scores (a Live Link Face CSV read by :mod:`mien.exchange.arkit_csv`): every
    frame has a face; its head rotation channels (when present) are the head pose."""
    missing = [name for name in ARKIT_NAMES if name not in clip.channels]
    if missing:
        raise InvalidValueError("clip channels", missing[:3], "the 52 ARKit names (a Live Link Face CSV)")
    head = np.zeros((clip.n_frames, 3))
    for k, name in enumerate(_HEAD_CHANNELS):
        if name in clip.channels:
            head[:, k] = clip.channel(name)
    return capture_frames(
        source,
        clip.fps,
        clip.times_s,
        clip.select(ARKIT_NAMES).values,
        head,
        np.ones(clip.n_frames, dtype=bool),
        settings,
        neutral=neutral,
    )


_INPUTS = "a video, a mien track (.npz/.json from `mien track`), a Live Link Face CSV or an OpenFace CSV"


def capture_file(
    path: str | os.PathLike[str],
    settings: CaptureSettings | None = None,
    *,
    neutral: np.ndarray | None = None,
    model: str | os.PathLike[str] | None = None,
    use_cache: bool = True,
    show_progress: bool = True,
    workers: int | None = None,
) -> Capture:
    """Capture any recording mien reads: a video (tracked), a track file (``.npz``/``.json``), a Live Link Face
    CSV (its ARKit scores through the same stream) or an OpenFace CSV (AU intensities from OpenFace's own
    detector, kept as read: no scores to filter; :attr:`Capture.weights` are zeros). ``workers`` is for a video
    (:func:`capture_video`).

    Raises :class:`InvalidValueError` naming the file when it is none of these or cannot be read.
    """
    file = Path(path)
    suffix = file.suffix.lower()
    if suffix in (".npz", ".json"):
        from mien.tracking.track import load_track

        return capture_track(load_track(file), settings, neutral=neutral)
    if suffix == ".csv":
        from mien.exchange import format_for, format_module

        name = format_for(file, "read")
        clip = format_module(name).read(file)
        if name == "arkit_csv":
            return capture_weight_clip(clip, str(file.resolve()), settings, neutral=neutral)
        if name == "openface_csv":
            return _openface_capture(clip, str(file.resolve()), settings or CaptureSettings())
        raise InvalidValueError("input", str(file), f"{_INPUTS} (this CSV is a {name} clip)")
    return capture_video(
        file, settings, neutral=neutral, model=model, use_cache=use_cache, show_progress=show_progress, workers=workers
    )


def _openface_capture(clip: Clip, source: str, settings: CaptureSettings) -> Capture:
    frames = np.zeros((clip.n_frames, len(FACE_CHANNELS)))
    for k, name in enumerate(FACE_CHANNELS):
        if name in clip.channels:
            frames[:, k] = clip.channel(name)
    n = clip.n_frames
    ones = np.ones(n, dtype=bool)
    return Capture(
        source, clip.fps, clip.times_s, frames, np.zeros((n, N_BLENDSHAPES)), ones, np.zeros(N_INPUT), settings
    )


def strip_face_mask(clip: Clip) -> tuple[Clip, np.ndarray | None]:
    """``(clip without the mask channel, mask (n,) bool or None)``: a captured clip as other code reads it."""
    if FACE_FOUND_CHANNEL not in clip.channels:
        return clip, None
    kept: Sequence[str] = [c for c in clip.channels if c != FACE_FOUND_CHANNEL]
    return clip.select(kept), clip.channel(FACE_FOUND_CHANNEL) > 0.5


assert set(POSE_CHANNELS) >= set(_HEAD_CHANNELS)
