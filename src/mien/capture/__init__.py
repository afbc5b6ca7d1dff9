"""Capture: a person's tracked face (MediaPipe blendshapes and head rotation) -> a mien face clip.

:class:`CaptureStream` turns one tracked frame at a time into a face frame over
:data:`~mien.facs.catalogue.FACE_CHANNELS` (jitter filter, neutral subtracted, reverse AU mapping, a lost face
held then eased to neutral); :func:`capture_video` and :func:`capture_track` run that same stream over a whole
video or track file (``mien capture``). Importing this package needs numpy only.
"""

from mien.capture.offline import (
    FACE_FOUND_CHANNEL,
    ROUTES,
    Capture,
    capture_file,
    capture_frames,
    capture_track,
    capture_video,
    capture_weight_clip,
    neutral_from_frames,
    neutral_from_image,
    strip_face_mask,
)
from mien.capture.settings import CaptureSettings
from mien.capture.smoothing import OneEuroFilter
from mien.capture.stream import CaptureStream, gaze_deg

__all__ = [
    "FACE_FOUND_CHANNEL",
    "ROUTES",
    "Capture",
    "CaptureSettings",
    "CaptureStream",
    "OneEuroFilter",
    "capture_file",
    "capture_frames",
    "capture_track",
    "capture_video",
    "capture_weight_clip",
    "gaze_deg",
    "neutral_from_frames",
    "neutral_from_image",
    "strip_face_mask",
]
