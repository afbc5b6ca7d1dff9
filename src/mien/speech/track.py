"""Timed speech: segments, viseme tracks, audio, and the utterance a character says.

Every source of timing (espeak-ng, a timing file, OpenFaceFX, audio energy) ends as an :class:`Utterance`:
a :class:`VisemeTrack` (per-frame weights of the 15 visemes, each frame summing to 1), the segments it came
from, and the sound. :meth:`Utterance.speech_frames` compiles it for the character engine.
"""

from __future__ import annotations

import math
import wave
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.clip import Clip, interpolate_frames
from mien.fileio.streams import atomic_path
from mien.speech.visemes import VISEMES, check_viseme, viseme_aus

__all__ = ["TRACK_FPS", "Audio", "Segment", "Utterance", "VisemeTrack"]

TRACK_FPS = 100.0
"""Frame rate (Hz) of the viseme tracks mien computes: 10 ms, finer than any video or server tick."""

_SIL = VISEMES.index("sil")


@dataclass(frozen=True)
class Segment:
    """One timed speech unit: a phoneme or a viseme over ``[start_s, end_s)``."""

    start_s: float
    """Start, seconds from the utterance's start."""
    end_s: float
    """End, seconds (> ``start_s``)."""
    viseme: str
    """The viseme that shows it (one of :data:`~mien.speech.visemes.VISEMES`)."""
    phoneme: str = ""
    """The source's own label (espeak ``"aI"``, ARPABET ``"AY1"``...); ``""`` when the source gave visemes."""

    def __post_init__(self) -> None:
        if not (math.isfinite(self.start_s) and math.isfinite(self.end_s) and self.end_s > self.start_s >= 0):
            raise InvalidValueError("segment", (self.start_s, self.end_s), "0 <= start_s < end_s, finite seconds")
        check_viseme(self.viseme)


@dataclass(frozen=True, eq=False)
class VisemeTrack:
    """Viseme weights over time: ``weights`` (n_frames, 15) in 0..1, each frame summing to 1, at ``fps``."""

    weights: np.ndarray
    """(n_frames, 15) float64, :data:`~mien.speech.visemes.VISEMES` order; ``sil`` takes what the others leave."""
    fps: float = TRACK_FPS
    """Frames per second."""

    def __post_init__(self) -> None:
        weights = np.asarray(self.weights, dtype=np.float64)
        if weights.ndim != 2 or weights.shape[1] != len(VISEMES) or weights.shape[0] < 1:
            raise InvalidValueError("weights", weights.shape, f"(n_frames >= 1, {len(VISEMES)}) viseme weights")
        if not np.isfinite(weights).all() or not (math.isfinite(self.fps) and self.fps > 0):
            raise InvalidValueError("weights", "non-finite", "finite weights and a positive fps")
        object.__setattr__(self, "weights", _normalised(weights))

    @property
    def n_frames(self) -> int:
        """Number of frames."""
        return int(self.weights.shape[0])

    @property
    def duration_s(self) -> float:
        """``n_frames / fps``, seconds."""
        return self.n_frames / self.fps

    @property
    def presence(self) -> np.ndarray:
        """(n_frames,) how much speech holds the mouth, 0..1: ``1 - weight of sil``."""
        return np.asarray(1.0 - self.weights[:, _SIL])

    def dominant(self) -> list[str]:
        """The strongest viseme of each frame."""
        return [VISEMES[i] for i in self.weights.argmax(axis=1).tolist()]

    def face_clip(self) -> Clip:
        """The speech alone on a neutral face: (n_frames, 62) AU intensities (``weights @ viseme_aus()``)."""
        return Clip(self.weights @ viseme_aus(), self.fps, FACE_CHANNELS)


def _normalised(weights: np.ndarray) -> np.ndarray:
    """Clip to 0..1, give ``sil`` what the others leave, and scale frames over 1 down to a sum of 1."""
    weights = np.clip(weights, 0.0, 1.0)
    others = weights.sum(axis=1) - weights[:, _SIL]
    weights[:, _SIL] = np.maximum(weights[:, _SIL], 1.0 - np.minimum(others, 1.0))
    weights /= weights.sum(axis=1, keepdims=True)
    weights.setflags(write=False)
    return weights


@dataclass(frozen=True, eq=False)
class Audio:
    """Mono sound: ``samples`` (n,) float32 in [-1, 1] at ``sample_rate`` Hz."""

    samples: np.ndarray
    """(n_samples,) float32, -1..1."""
    sample_rate: int
    """Samples per second."""

    @property
    def duration_s(self) -> float:
        """Seconds of sound."""
        return len(self.samples) / self.sample_rate

    def write_wav(self, path: str | Path) -> Path:
        """Write a 16-bit PCM mono WAV (atomically) and return its path."""
        target = Path(path)
        pcm = np.round(np.clip(self.samples, -1.0, 1.0) * 32767.0).astype("<i2")
        with atomic_path(target) as temporary, wave.open(str(temporary), "wb") as out:
            out.setnchannels(1)
            out.setsampwidth(2)
            out.setframerate(int(self.sample_rate))
            out.writeframes(pcm.tobytes())
        return target


@dataclass(frozen=True, eq=False)
class Utterance:
    """What a character says: its viseme track, the segments it came from and its sound.

    Times are seconds from the utterance's start (the first audio sample is t = 0).
    """

    track: VisemeTrack
    """The coarticulated viseme weights."""
    segments: tuple[Segment, ...] = ()
    """The timed units it came from (empty for a track read as a track, or for audio alone)."""
    audio: Audio | None = None
    """The sound, if any (``write_wav`` keeps it)."""
    text: str = ""
    """The text spoken, if known."""
    source: str = ""
    """Where the timing came from: ``"espeak-ng"``, ``"timing file"``, ``"openfacefx"`` or ``"audio"``."""
    metadata: dict[str, object] = field(default_factory=dict)
    """Source facts (voice, language, file paths)."""

    @property
    def duration_s(self) -> float:
        """The longer of the track and the sound, seconds."""
        return max(self.track.duration_s, self.audio.duration_s if self.audio is not None else 0.0)

    def face_clip(self, fps: float | None = None) -> Clip:
        """The speech alone on a neutral face as a (n, 62) AU clip, resampled to ``fps`` if given."""
        if fps is None:
            return self.track.face_clip()
        n = max(1, math.floor(self.duration_s * fps) + 1)
        weights = interpolate_frames(self.track.weights, self.track.fps, np.arange(n) / fps)
        return Clip(weights @ viseme_aus(), fps, FACE_CHANNELS)  # the shapes are linear in the weights
