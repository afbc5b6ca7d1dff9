"""Clip time for readers and writers: from time-stamped rows to a uniform clip, and from one rate to another.

Recorded files (Live Link Face, OpenFace, OpenFACS lines, glTF keys) carry a time stamp per row, with jitter or
dropped frames; a :class:`~mien.facs.clip.Clip` has a constant rate. :func:`uniform_clip` estimates the rate as
``(n - 1) / (last - first)`` (rounded to 0.001 fps) and interpolates every channel linearly onto that grid,
keeping the row count. :func:`resample` changes a clip's rate.

>>> clip = uniform_clip(np.array([0.0, 0.1, 0.21, 0.3]), np.array([[0.0], [1.0], [2.1], [3.0]]), ("x",))
>>> clip.fps, clip.values[:, 0].round(6).tolist()
(10.0, [0.0, 1.0, 2.0, 3.0])
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.clip import Clip, resample_on_times

__all__ = ["DEFAULT_FPS", "resample", "uniform_clip"]

DEFAULT_FPS = 30.0
"""Rate given to a file with a single row (no time step to measure)."""


def uniform_clip(times_s: np.ndarray, values: np.ndarray, channels: Sequence[str]) -> Clip:
    """A clip of the (n, c) ``values`` stamped at increasing ``times_s`` (n,), on a uniform grid of n frames."""
    times = np.asarray(times_s, dtype=np.float64)
    data = np.asarray(values, dtype=np.float64).reshape(len(times), len(channels))
    if len(times) > 1 and not np.all(np.diff(times) > 0):
        raise InvalidValueError("times_s", "not increasing", "increasing time stamps")
    if len(times) < 2:
        return Clip(data, DEFAULT_FPS, tuple(channels))
    fps = round((len(times) - 1) / float(times[-1] - times[0]), 3)
    return Clip(resample_on_times(times, data, fps, n_frames=len(times)), fps, tuple(channels))


def resample(clip: Clip, fps: float, cover_end: bool = False) -> Clip:
    """``clip`` linearly resampled to ``fps`` from its first frame.

    The new clip ends at the last new frame not after the old last frame, or, with ``cover_end``, at the first
    one at or after it (holding the last value), so no part of the clip is lost.
    """
    rate = float(fps)
    if not math.isfinite(rate) or rate <= 0:
        raise InvalidValueError("fps", fps, "a positive finite number")
    if clip.n_frames < 2 or rate == clip.fps:
        return Clip(clip.values, rate, clip.channels) if clip.n_frames < 2 else clip
    span = (clip.n_frames - 1) / clip.fps * rate
    n_frames = (math.ceil(span - 1e-9) if cover_end else math.floor(span + 1e-9)) + 1
    return Clip(clip.sample(np.arange(n_frames) / rate), rate, clip.channels)
