"""Controller curves from tracked video: each take of a :class:`mien.tracking.Track` -> a controller clip.

The offline half of Mascaró et al. (2021): landmarks tracked in a video become the iBUG-68 points, then the
facial parameters and controller curves of :mod:`mien.laughter.controllers`, one clip per take.
"""

from __future__ import annotations

from typing import Any

from mien.facs.clip import Clip
from mien.laughter.controllers import DEFAULT_EPS, controllers_from_points
from mien.laughter.facial_parameters import Neutral
from mien.tracking.ibug68 import ibug68
from mien.tracking.track import resample_on_times

__all__ = ["controllers_from_track"]


def controllers_from_track(track: Any, eps: float = DEFAULT_EPS, neutral: Neutral = None) -> list[Clip]:
    """One controller :class:`Clip` per take of a :class:`mien.tracking.Track` (2-D pixel landmarks).

    Each take has its own neutral reference (by default its first NEUTRAL_FRAMES frames; a frame index
    counts from the take's start). An empty list when the track has no take.
    """
    points = ibug68(track.landmarks_px[..., :2])
    clips = []
    for start, stop in track.takes:  # on a regular grid at track.fps, interpolated on the frames' real times
        regular = resample_on_times(track.timestamps_s[start:stop], points[start:stop], track.fps)
        clips.append(controllers_from_points(regular, track.fps, eps, neutral))
    return clips
