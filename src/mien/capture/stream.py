"""One performer, frame by frame: tracked blendshapes and head rotation -> mien face frames.

:class:`CaptureStream` is the one engine of capture: ``mien capture`` (a whole video, :mod:`mien.capture.offline`)
and a live capture source push the same frames through it. Each frame goes

1. through the jitter filter (:class:`~mien.capture.smoothing.OneEuroFilter`, cut-offs in
   :class:`~mien.capture.settings.CaptureSettings`), on the frame's own time stamp;
2. minus the performer's neutral (Mascaro's FP_0): a score ``b`` becomes ``(b - b0) / (1 - b0)`` clipped to
   0..1 (so a full score stays reachable) and the head rotation loses the neutral's;
3. through the reverse AU mapping (:class:`~mien.rig.au_solve.AUSolver`) into AU intensities of both sides,
   with gaze read from the ``eyeLook*`` scores at the rig's own eye angles
   (:data:`~mien.rig.head_targets.EYE_YAW_RAD`, :data:`~mien.rig.head_targets.EYE_PITCH_RAD`).

A frame without a face (``blendshapes`` None) holds the last pose for ``hold_s`` and then eases to neutral over
``ease_s``; when the face comes back the output blends from what was shown to the tracked pose over
``enter_s`` (at most the time it was away), so nothing jumps. :attr:`CaptureStream.has_face` says whether the
last frame had a face.

>>> import numpy as np
>>> from mien.facs.arkit import ARKIT_INDEX
>>> from mien.facs.catalogue import channel_index
>>> stream = CaptureStream(CaptureSettings(neutral_first_s=0.0, filter=False))
>>> smile = np.zeros(52); smile[[ARKIT_INDEX["mouthSmileLeft"], ARKIT_INDEX["mouthSmileRight"]]] = 0.6
>>> frame = stream.push(0.0, smile, np.zeros(3))
>>> bool(frame[channel_index("AU12L")] > 1.0), stream.has_face
(True, True)
>>> held = stream.push(0.1, None, None)
>>> bool(np.allclose(held, frame)), stream.has_face
(True, False)
>>> float(np.abs(stream.push(3.0, None, None)).max())
0.0
"""

from __future__ import annotations

import numpy as np

from mien.capture.settings import CaptureSettings
from mien.capture.smoothing import OneEuroFilter
from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_INDEX, ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, channel_index
from mien.rig.au_solve import AUSolver
from mien.rig.head_targets import EYE_PITCH_RAD, EYE_YAW_RAD

__all__ = ["N_INPUT", "CaptureStream", "gaze_deg", "smoothstep"]

N_BLENDSHAPES = len(ARKIT_NAMES)
N_INPUT = N_BLENDSHAPES + 3
"""Length of a stream's input vector: 52 ARKit scores, then head yaw, pitch, roll (degrees)."""

_HEAD = np.array([channel_index(f"head_{a}_deg") for a in ("yaw", "pitch", "roll")], dtype=np.intp)
_GAZE = np.array([channel_index(f"gaze_{a}_deg") for a in ("yaw", "pitch")], dtype=np.intp)


def _ids(*names: str) -> np.ndarray:
    return np.array([ARKIT_INDEX[n] for n in names], dtype=np.intp)


# Looking to the performer's left: the left eye looks out, the right eye looks in.
_LOOK_LEFT = _ids("eyeLookOutLeft", "eyeLookInRight")
_LOOK_RIGHT = _ids("eyeLookInLeft", "eyeLookOutRight")
_LOOK_UP = _ids("eyeLookUpLeft", "eyeLookUpRight")
_LOOK_DOWN = _ids("eyeLookDownLeft", "eyeLookDownRight")


def gaze_deg(blendshapes: np.ndarray) -> np.ndarray:
    """(..., 2) gaze yaw, pitch in degrees (mien's signs) from (..., 52) ARKit scores, at the rig's eye angles."""
    b = np.asarray(blendshapes, dtype=np.float64)
    yaw = (b[..., _LOOK_LEFT].mean(axis=-1) - b[..., _LOOK_RIGHT].mean(axis=-1)) * np.degrees(EYE_YAW_RAD)
    pitch = (b[..., _LOOK_UP].mean(axis=-1) - b[..., _LOOK_DOWN].mean(axis=-1)) * np.degrees(EYE_PITCH_RAD)
    return np.stack([yaw, pitch], axis=-1)


def smoothstep(x: float) -> float:
    """0 below 0, 1 above 1, ``3x^2 - 2x^3`` between: an ease with no jump in value or speed."""
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


class CaptureStream:
    """Tracked frames of one performer -> (62,) face frames over :data:`~mien.facs.catalogue.FACE_CHANNELS`.

    settings: filter, neutral and lost-face timing (default :class:`CaptureSettings`). neutral: the performer's
    neutral as an (55,) vector (52 scores, head yaw/pitch/roll degrees), e.g. from
    :func:`mien.capture.offline.neutral_from_image`; without it the frames with a face inside
    ``settings.neutral_s`` give it (their running median, frozen when the interval ends). solver: the reverse
    AU mapping (default :class:`AUSolver` over the default mapping).
    """

    def __init__(
        self,
        settings: CaptureSettings | None = None,
        *,
        neutral: np.ndarray | None = None,
        solver: AUSolver | None = None,
    ) -> None:
        self.settings = settings or CaptureSettings()
        self.solver = solver or AUSolver()
        self._fixed_neutral = None if neutral is None else self._check_neutral(neutral)
        s = self.settings
        self._filter = OneEuroFilter(
            np.r_[np.full(N_BLENDSHAPES, s.min_cutoff_hz), np.full(3, s.pose_min_cutoff_hz)],
            np.r_[np.full(N_BLENDSHAPES, s.beta), np.full(3, s.pose_beta)],
            s.d_cutoff_hz,
        )
        self.reset()

    @staticmethod
    def _check_neutral(neutral: np.ndarray) -> np.ndarray:
        value = np.asarray(neutral, dtype=np.float64)
        if value.shape != (N_INPUT,) or not np.all(np.isfinite(value)):
            raise InvalidValueError(
                "neutral", value.shape, f"({N_INPUT},) finite: 52 ARKit scores, then yaw/pitch/roll"
            )
        return value

    def reset(self) -> None:
        """Start over: no past frames, no collected neutral (a neutral given to the constructor stays)."""
        self._filter.reset()
        self._samples: list[np.ndarray] = []
        self._neutral = self._fixed_neutral if self._fixed_neutral is not None else np.zeros(N_INPUT)
        self._last_t: float | None = None
        self._previous_t: float | None = None
        self._shown = np.zeros(len(FACE_CHANNELS))
        self._last_face = np.zeros(len(FACE_CHANNELS))
        self._last_face_t: float | None = None
        self._first_face_t: float | None = None
        self._away_since: float | None = None
        self._enter: tuple[float, float, np.ndarray] | None = None  # (start, duration, pose shown at entry)
        self._weights = np.zeros(N_BLENDSHAPES)
        self._held = (self._shown, self._weights)  # what was shown when the face was lost
        self._has_face = False

    @property
    def has_face(self) -> bool:
        """Whether the last pushed frame had a face."""
        return self._has_face

    @property
    def neutral(self) -> np.ndarray:
        """(55,) the neutral subtracted now: 52 scores, head yaw/pitch/roll degrees (zeros before any)."""
        return self._neutral.copy()

    @property
    def weights(self) -> np.ndarray:
        """(52,) the last face's filtered, neutral-subtracted ARKit scores 0..1 (the pass-through route), held
        and eased like the face frame when the face is lost."""
        return self._weights.copy()

    def push(self, t_s: float, blendshapes: np.ndarray | None, head_rotation_deg: np.ndarray | None) -> np.ndarray:
        """The face frame (62,) at ``t_s`` seconds for one tracked frame.

        blendshapes: (52,) ARKit scores 0..1 in :data:`~mien.facs.arkit.ARKIT_NAMES` order, or None when the
        frame has no face. head_rotation_deg: (3,) yaw, pitch, roll (mien's convention); None reads as 0.
        Times must increase; a repeated or earlier time is an :class:`InvalidValueError`.
        """
        t = float(t_s)
        if not np.isfinite(t) or (self._last_t is not None and t <= self._last_t):
            raise InvalidValueError("t_s", t_s, f"a finite time after the last frame's ({self._last_t})")
        self._previous_t, self._last_t = self._last_t, t
        if blendshapes is None:
            return self._lost(t)
        scores = np.asarray(blendshapes, dtype=np.float64)
        if scores.shape != (N_BLENDSHAPES,) or not np.all(np.isfinite(scores)):
            raise InvalidValueError("blendshapes", scores.shape, "(52,) finite ARKit scores, or None")
        pose = np.zeros(3) if head_rotation_deg is None else np.asarray(head_rotation_deg, dtype=np.float64)
        if pose.shape != (3,) or not np.all(np.isfinite(pose)):
            raise InvalidValueError("head_rotation_deg", pose.shape, "(3,) finite yaw, pitch, roll in degrees")
        return self._found(t, np.r_[scores, pose])

    def _found(self, t: float, raw: np.ndarray) -> np.ndarray:
        s = self.settings
        if self._first_face_t is None:
            self._first_face_t = t
        if self._fixed_neutral is None and s.in_neutral(t, self._first_face_t):
            self._samples.append(raw)
            self._neutral = np.median(np.stack(self._samples), axis=0)
        if self._away_since is not None:  # back after a gap: blend from what is shown
            away_s = t - self._away_since
            if away_s > s.hold_s:
                self._filter.reset()  # an old state would smear the new take
            # the blend starts at the last faceless frame, so a one-frame dropout comes back at once
            start = t if self._previous_t is None else self._previous_t
            self._enter = (start, min(s.enter_s, away_s), self._shown.copy())
            self._away_since = None
        value = self._filter(t, raw) if s.filter else raw
        base = self._neutral[:N_BLENDSHAPES]
        weights = np.clip((value[:N_BLENDSHAPES] - base) / np.maximum(1.0 - base, 1e-6), 0.0, 1.0)
        frame = np.zeros(len(FACE_CHANNELS))
        frame[self.solver.channels] = self.solver.solve_channels(weights)
        frame[_HEAD] = value[N_BLENDSHAPES:] - self._neutral[N_BLENDSHAPES:]
        frame[_GAZE] = gaze_deg(weights)
        if self._enter is not None:
            start, duration, shown = self._enter
            mix = smoothstep((t - start) / duration) if duration > 0 else 1.0
            if mix >= 1.0:
                self._enter = None
            else:
                frame = shown + mix * (frame - shown)
                weights = self._weights + mix * (weights - self._weights)
        self._has_face = True
        self._last_face, self._last_face_t = frame, t
        self._shown, self._weights = frame, weights
        return frame.copy()

    def _lost(self, t: float) -> np.ndarray:
        self._has_face = False
        if self._away_since is None:
            self._away_since = t
            self._held = (self._shown.copy(), self._weights.copy())
        s = self.settings
        age = t - self._away_since
        keep = 1.0 - (smoothstep((age - s.hold_s) / s.ease_s) if s.ease_s > 0 else float(age > s.hold_s))
        self._shown = self._held[0] * keep
        self._weights = self._held[1] * keep
        return self._shown.copy()
