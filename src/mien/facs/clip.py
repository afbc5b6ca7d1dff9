"""Clips: a ``(frames, channels)`` array of face states with a frame rate and channel names.

A :class:`Clip` is generic over its channel names: AU clips use :data:`~mien.facs.catalogue.FACE_CHANNELS`,
blendshape clips use the ARKit names, laughter-controller clips use the controller names.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError

__all__ = ["Clip", "interpolate_frames", "resample_on_times"]


def interpolate_frames(values: np.ndarray, fps: float, times_s: np.ndarray | float) -> np.ndarray:
    """Linear interpolation of (n_frames, n_channels) ``values`` sampled at ``fps`` at ``times_s`` seconds.

    Returns (len(times_s), n_channels), or (n_channels,) for a scalar time; times outside the clip take the
    first or last frame.

    >>> interpolate_frames(np.array([[0.0], [2.0]]), 10.0, [0.05, 1.0]).tolist()
    [[1.0], [2.0]]
    """
    values = np.asarray(values, dtype=np.float64)
    times = np.asarray(times_s, dtype=np.float64)
    position = np.clip(times * fps, 0.0, values.shape[0] - 1.0)
    low = np.floor(position).astype(np.int64)
    high = np.minimum(low + 1, values.shape[0] - 1)
    weight = (position - low)[..., None]
    return (1.0 - weight) * values[low] + weight * values[high]


def resample_on_times(times_s: np.ndarray, values: np.ndarray, fps: float, n_frames: int | None = None) -> np.ndarray:
    """``values`` (n, ...) sampled at the real times ``times_s`` (n,) seconds -> a regular grid at ``fps``.

    The grid starts at ``times_s[0]`` and steps ``1 / fps``: ``n_frames`` frames, or by default up to
    ``times_s[-1]``. Each grid value is linearly interpolated between the two frames around it (times past
    the end hold the last value), so a variable-frame-rate recording keeps its timing. A constant-rate
    recording at ``fps`` comes back unchanged. Returns (m, ...) float64. The one resampler of time-stamped
    data: video tracks (:mod:`mien.tracking.track`) and recorded files (:mod:`mien.exchange.timing`) use it.

    >>> resample_on_times(np.array([0.0, 0.1, 0.4]), np.array([0.0, 1.0, 4.0]), 10.0).round(6).tolist()
    [0.0, 1.0, 2.0, 3.0, 4.0]
    """
    times = np.asarray(times_s, dtype=np.float64)
    data = np.asarray(values, dtype=np.float64)
    if not np.isfinite(fps) or fps <= 0:
        raise InvalidValueError("fps", fps, "a positive finite frame rate")
    if times.ndim != 1 or data.shape[:1] != times.shape:
        raise InvalidValueError("times_s", f"shape {times.shape}", f"(n,) matching values of shape {data.shape}")
    if times.shape[0] < 2:
        return data.copy()
    if np.any(np.diff(times) <= 0):
        raise InvalidValueError("times_s", "not increasing", "strictly increasing time stamps")
    count = int(np.floor((times[-1] - times[0]) * fps + 1e-6)) + 1 if n_frames is None else int(n_frames)
    grid = times[0] + np.arange(count) / fps
    if count == times.shape[0] and np.allclose(grid, times, rtol=0.0, atol=1e-6):
        return data.copy()
    flat = data.reshape(times.shape[0], -1)
    out = np.empty((count, flat.shape[1]))
    for column in range(flat.shape[1]):
        out[:, column] = np.interp(grid, times, flat[:, column])
    return out.reshape((count, *data.shape[1:]))


@dataclass(frozen=True, eq=False)
class Clip:
    """Sampled curves: ``values[i, j]`` is channel ``channels[j]`` at time ``i / fps`` seconds."""

    values: np.ndarray
    """(n_frames, n_channels) float64 values (AU intensity 0..5, weight 0..1, degrees...)."""
    fps: float
    """Frames per second."""
    channels: tuple[str, ...]
    """Channel names, one per column."""

    def __post_init__(self) -> None:
        values = np.asarray(self.values, dtype=np.float64)
        if values.ndim != 2 or values.shape[1] != len(self.channels):
            raise InvalidValueError(
                "values", f"array of shape {values.shape}", f"(n_frames, {len(self.channels)}) matching channels"
            )
        if not np.all(np.isfinite(values)):
            bad = np.argwhere(~np.isfinite(values))[0]
            raise InvalidValueError(f"values[{bad[0]}, {self.channels[bad[1]]}]", values[tuple(bad)], "a finite number")
        fps = float(self.fps)
        if not math.isfinite(fps) or fps <= 0:
            raise InvalidValueError("fps", self.fps, "a positive finite number")
        if len(set(self.channels)) != len(self.channels):
            raise InvalidValueError("channels", self.channels, "unique names")
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "fps", fps)
        object.__setattr__(self, "channels", tuple(str(c) for c in self.channels))

    @property
    def n_frames(self) -> int:
        """Number of frames."""
        return int(self.values.shape[0])

    @property
    def duration_s(self) -> float:
        """Duration in seconds (``n_frames / fps``)."""
        return self.n_frames / self.fps

    @property
    def times_s(self) -> np.ndarray:
        """(n_frames,) time of each frame in seconds."""
        return np.arange(self.n_frames) / self.fps

    def channel(self, name: str) -> np.ndarray:
        """(n_frames,) curve of one channel."""
        try:
            return self.values[:, self.channels.index(name)]
        except ValueError:
            raise UnknownNameError("channel", name, self.channels) from None

    def select(self, names: Sequence[str]) -> Clip:
        """A clip with only ``names`` (in that order)."""
        columns = [self.channels.index(n) if n in self.channels else -1 for n in names]
        missing = [n for n, c in zip(names, columns, strict=True) if c < 0]
        if missing:
            raise UnknownNameError("channel", missing[0], self.channels)
        return Clip(self.values[:, columns], self.fps, tuple(names))

    def sample(self, times_s: np.ndarray | float) -> np.ndarray:
        """Values at ``times_s`` seconds by linear interpolation (see :func:`interpolate_frames`)."""
        return interpolate_frames(self.values, self.fps, times_s)

    def active_channels(self, threshold: float = 1e-6) -> tuple[str, ...]:
        """Names of channels whose absolute value exceeds ``threshold`` somewhere."""
        mask = np.abs(self.values).max(axis=0, initial=0.0) > threshold
        return tuple(n for n, m in zip(self.channels, mask, strict=True) if m)

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict form: ``{"fps", "channels", "values"}`` (values as nested lists)."""
        return {"fps": self.fps, "channels": list(self.channels), "values": self.values.tolist()}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Clip:
        """Inverse of :meth:`to_dict`; raises :class:`InvalidValueError` on a malformed dict."""
        if not isinstance(data, dict):
            raise InvalidValueError("clip", type(data).__name__, "a dict with fps, channels, values")
        for key in ("fps", "channels", "values"):
            if key not in data:
                raise InvalidValueError(key, None, f"a '{key}' entry in the clip dict")
        values = np.asarray(data["values"], dtype=np.float64)
        channels = tuple(data["channels"])
        if values.size == 0:
            values = values.reshape(0, len(channels))
        return cls(values, float(data["fps"]), channels)

    def to_json(self) -> str:
        """JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict())

    @classmethod
    def from_json(cls, text: str) -> Clip:
        """Inverse of :meth:`to_json`."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InvalidValueError("clip JSON", text[:40], f"valid JSON ({exc.msg} at {exc.pos})") from None
        return cls.from_dict(data)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Clip):
            return NotImplemented
        return (
            self.channels == other.channels
            and self.fps == other.fps
            and self.values.shape == other.values.shape
            and bool(np.array_equal(self.values, other.values))
        )

    __hash__ = None  # type: ignore[assignment]
