"""Capture: a person's tracked face (MediaPipe blendshapes and head rotation) -> a mien face clip.

:class:`CaptureStream` turns one tracked frame at a time into a face frame over
:data:`~mien.facs.catalogue.FACE_CHANNELS` (jitter filter, neutral subtracted, reverse AU mapping, a lost face
held then eased to neutral); :func:`capture_video` and :func:`capture_track` run that same stream over a whole
video or track file (``mien capture``). Importing this package needs numpy only.
"""

from mien.capture.settings import CaptureSettings
from mien.capture.smoothing import OneEuroFilter
from mien.capture.stream import CaptureStream, gaze_deg

__all__ = ["CaptureSettings", "CaptureStream", "OneEuroFilter", "gaze_deg"]
