"""Video tracking: the only package that imports MediaPipe and video decoders (inside functions).

``track_video(path) -> Track``: per-frame MediaPipe landmarks (478), ARKit blendshape scores (52), head pose
and face-found flags, with short gaps filled and takes split at long ones; ``ibug68`` picks the 68 iBUG points.
Importing this package needs numpy only.
"""

from mien.tracking.ibug68 import IBUG68_NAMES, ibug68, ibug68_indices
from mien.tracking.landmarker import MIN_CONFIDENCE, FrameResult, Landmarker, head_pose_deg
from mien.tracking.track import MAX_GAP_S, Track, apply_gaps, fill_gaps, load_track, track_video
from mien.tracking.video import VideoHeader, iter_frames, probe

__all__ = [
    "IBUG68_NAMES",
    "MAX_GAP_S",
    "MIN_CONFIDENCE",
    "FrameResult",
    "Landmarker",
    "Track",
    "VideoHeader",
    "apply_gaps",
    "fill_gaps",
    "head_pose_deg",
    "ibug68",
    "ibug68_indices",
    "iter_frames",
    "load_track",
    "probe",
    "track_video",
]
