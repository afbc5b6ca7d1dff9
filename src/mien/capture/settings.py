"""How a performance is captured: the jitter filter, the neutral, and what a lost face does.

Defaults were measured on the real videos of ``../shared/data/video`` (docs/CAPTURE.md, ``bench/capture_filter.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mien.errors import InvalidValueError

__all__ = ["CaptureSettings"]


@dataclass(frozen=True)
class CaptureSettings:
    """Settings of a :class:`~mien.capture.stream.CaptureStream` (and of ``mien capture``)."""

    min_cutoff_hz: float = 1.0
    """One Euro cut-off of the blendshape scores at rest, Hz (the jitter filter's stated cut-off)."""
    beta: float = 4.0
    """One Euro cut-off increase per unit of blendshape speed (score per second): fast moves pass sharp.
    Measured on the shared videos (``bench/capture_filter.py``): 1 Hz and 4 leave 43% of the unfiltered AU
    jitter, no smile-onset lag and 88% of a blink's peak with no delay (2 Hz and 2: 42%, one frame late, 85%)."""
    pose_min_cutoff_hz: float = 1.0
    """One Euro cut-off of the head rotation at rest, Hz."""
    pose_beta: float = 0.05
    """One Euro cut-off increase per degree per second of head speed."""
    d_cutoff_hz: float = 1.0
    """Cut-off of the speed estimate, Hz."""
    neutral_first_s: float = 0.5
    """The performer's neutral is the median of the first this-many seconds of frames with a face (counted
    from the first face, so a face that enters late still calibrates); 0: no calibration. Subtracted from every
    frame as Mascaro's FP_0 is. Ignored when ``neutral_s`` or a neutral vector is given."""
    neutral_s: tuple[float, float] | None = None
    """A chosen interval (start, end) in seconds of the recording whose frames with a face give the neutral."""
    hold_s: float = 0.5
    """A lost face holds its last pose this long, seconds..."""
    ease_s: float = 1.0
    """...then eases to neutral over this many seconds."""
    enter_s: float = 0.2
    """A face that comes back blends from the shown pose to the tracked one over this many seconds (at most
    the time it was away), so it never jumps."""
    filter: bool = True
    """Apply the jitter filter (off: raw scores, for measuring)."""

    def __post_init__(self) -> None:
        for name in ("min_cutoff_hz", "pose_min_cutoff_hz", "d_cutoff_hz"):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= 0:
                raise InvalidValueError(name, value, "a positive cut-off frequency in Hz")
        for name in ("beta", "pose_beta", "hold_s", "ease_s", "enter_s", "neutral_first_s"):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0:
                raise InvalidValueError(name, value, "a finite number >= 0")
        if self.neutral_s is not None:
            start, end = (float(v) for v in self.neutral_s)
            if not (math.isfinite(start) and math.isfinite(end)) or start < 0 or end <= start:
                raise InvalidValueError(
                    "neutral interval", f"{start:g}:{end:g}", "START:END seconds with 0 <= START < END"
                )

    def in_neutral(self, t_s: float, first_face_s: float) -> bool:
        """Whether a face frame at ``t_s`` seconds is part of the neutral (the first face at ``first_face_s``)."""
        if self.neutral_s is not None:
            return self.neutral_s[0] <= t_s <= self.neutral_s[1]
        return self.neutral_first_s > 0 and t_s - first_face_s <= self.neutral_first_s
