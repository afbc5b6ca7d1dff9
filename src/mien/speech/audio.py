"""Sound files in and out, the energy envelope, and speech from audio alone.

:func:`read_audio` decodes a WAV file with the standard library (PCM 8/16/24/32-bit, any rate, channels
averaged to mono) and any other format (MP3, OGG, FLAC, M4A...) with ffmpeg (imageio-ffmpeg's bundled binary,
the ``render`` extra). :func:`energy_envelope` is the RMS per frame. :func:`utterance_from_audio` is the
documented fallback with no text: the jaw opens with the sound's energy and closes in silence.
"""

from __future__ import annotations

import struct
import subprocess
import wave
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.speech.track import TRACK_FPS, Audio, Utterance, VisemeTrack
from mien.speech.visemes import VISEMES

__all__ = [
    "ENERGY_CUTOFF_HZ",
    "MAX_AUDIO_S",
    "SILENCE_DB",
    "energy_envelope",
    "mux_audio",
    "read_audio",
    "utterance_from_audio",
]

MAX_AUDIO_S = 3600.0
"""Longest sound read, seconds (one hour)."""

SILENCE_DB = -35.0
"""Energy below this, dB relative to the sound's 95th-percentile frame, counts as silence (the mouth closes)."""

ENERGY_CUTOFF_HZ = 8.0
"""Smoothing of the envelope that drives the jaw (a one-pole low-pass, Hz): syllable rate is 4-8 Hz."""

_DECODE_RATE = 22050


def read_audio(path: str | Path) -> Audio:
    """Decode the sound file ``path`` to mono float32; :class:`InvalidValueError` if it cannot be decoded."""
    source = Path(path)
    if not source.is_file():
        raise InvalidValueError("audio", str(path), "an existing sound file (WAV, MP3, OGG, FLAC...)")
    try:
        audio = _read_wav(source)
    except (wave.Error, EOFError, RuntimeError, ValueError, struct.error):
        audio = _read_with_ffmpeg(source)
    if audio.samples.size == 0:
        raise InvalidValueError("audio", str(path), "a sound file with at least one sample")
    if audio.duration_s > MAX_AUDIO_S:
        raise InvalidValueError("audio", f"{audio.duration_s:.0f} s", f"at most {MAX_AUDIO_S:.0f} s of sound")
    return audio


def _read_wav(source: Path) -> Audio:
    with wave.open(str(source), "rb") as file:
        width, channels, rate = file.getsampwidth(), file.getnchannels(), file.getframerate()
        if file.getnframes() / max(rate, 1) > MAX_AUDIO_S:
            raise InvalidValueError("audio", str(source), f"at most {MAX_AUDIO_S:.0f} s of sound")
        raw = file.readframes(file.getnframes())
    if width == 1:
        data = (np.frombuffer(raw, np.uint8).astype(np.float32) - 128.0) / 128.0
    elif width == 2:
        data = np.frombuffer(raw, "<i2").astype(np.float32) / 32768.0
    elif width == 3:
        bytes3 = np.frombuffer(raw, np.uint8).reshape(-1, 3).astype(np.int32)
        value = bytes3[:, 0] | (bytes3[:, 1] << 8) | (bytes3[:, 2] << 16)
        data = (np.where(value >= 1 << 23, value - (1 << 24), value) / float(1 << 23)).astype(np.float32)
    else:
        data = (np.frombuffer(raw, "<i4").astype(np.float64) / 2.0**31).astype(np.float32)
    usable = len(data) // channels * channels
    return Audio(data[:usable].reshape(-1, channels).mean(axis=1), rate)


def _read_with_ffmpeg(source: Path) -> Audio:
    executable = str(require("imageio_ffmpeg", "render").get_ffmpeg_exe())
    command = [executable, "-v", "error", "-nostdin", "-i", str(source), "-t", str(MAX_AUDIO_S), "-vn",
               "-ac", "1", "-ar", str(_DECODE_RATE), "-f", "f32le", "-"]  # fmt: skip
    result = subprocess.run(command, capture_output=True, check=False, timeout=600)
    if result.returncode != 0 or not result.stdout:
        reason = result.stderr.decode("utf-8", "replace").strip().splitlines()
        raise InvalidValueError(
            "audio", str(source), f"a sound file ffmpeg can decode ({reason[-1] if reason else 'no audio stream'})"
        )
    return Audio(np.frombuffer(result.stdout, "<f4").copy(), _DECODE_RATE)


def energy_envelope(audio: Audio, fps: float = TRACK_FPS) -> np.ndarray:
    """(n_frames,) RMS of ``audio`` in windows of ``1 / fps`` centred on each frame ``i / fps``, not smoothed."""
    hop = audio.sample_rate / fps
    n = int(np.ceil(audio.duration_s * fps)) + 1
    padded = np.concatenate([np.zeros(int(hop)), audio.samples.astype(np.float64), np.zeros(int(hop) + 1)])
    squares = np.concatenate([[0.0], np.cumsum(padded * padded)])
    centres = (np.arange(n) * hop).astype(np.int64) + int(hop)
    low = np.clip(centres - int(hop / 2), 0, len(padded))
    high = np.clip(low + max(1, int(hop)), 0, len(padded))
    return np.sqrt((squares[high] - squares[low]) / np.maximum(high - low, 1))


def _smooth(values: np.ndarray, fps: float, cutoff_hz: float) -> np.ndarray:
    """Zero-phase one-pole low-pass (forward then backward), so the jaw neither leads nor lags the sound."""
    a = float(np.exp(-2.0 * np.pi * cutoff_hz / fps))
    out = np.array(values, dtype=np.float64)
    for order in (range(1, len(out)), range(len(out) - 2, -1, -1)):
        previous = out[0] if order.start == 1 else out[-1]
        for i in order:
            previous = out[i] = (1.0 - a) * out[i] + a * previous
    return out


def utterance_from_audio(audio: Audio | str | Path, fps: float = TRACK_FPS) -> Utterance:
    """Speech from the sound alone (no text): the ``aa`` viseme (the open jaw) in proportion to the energy.

    The RMS envelope (:func:`energy_envelope`) in dB relative to its 95th percentile maps linearly from
    :data:`SILENCE_DB` (closed, ``sil``) to 0 dB (fully open), smoothed at :data:`ENERGY_CUTOFF_HZ`. There is
    no articulation (no closures on /p b m/): give text or a timing file for that.
    """
    sound = audio if isinstance(audio, Audio) else read_audio(audio)
    envelope = energy_envelope(sound, fps)
    reference = float(np.percentile(envelope, 95))
    if reference <= 0.0:
        opening = np.zeros_like(envelope)
    else:
        level_db = 20.0 * np.log10(np.maximum(envelope, 1e-12) / reference)
        opening = np.clip(1.0 - level_db / SILENCE_DB, 0.0, 1.0)
    opening = np.clip(_smooth(opening, fps, ENERGY_CUTOFF_HZ), 0.0, 1.0)
    weights = np.zeros((len(opening), len(VISEMES)))
    weights[:, VISEMES.index("aa")] = opening
    metadata: dict[str, object] = {} if isinstance(audio, Audio) else {"audio": str(audio)}
    return Utterance(VisemeTrack(weights, fps), (), sound, "", "audio", metadata)


def mux_audio(video_path: str | Path, audio: Audio, out_path: str | Path) -> Path:
    """Write ``out_path``: the H.264 video of ``video_path`` (copied, not re-encoded) with ``audio`` as AAC.

    Both streams start at t = 0, the first frame and the first sample together (the AAC encoder's priming
    delay is removed by the MP4 edit list ffmpeg writes). The output is written atomically; ffmpeg is
    imageio-ffmpeg's (the ``render`` extra).
    """
    import tempfile

    from mien.fileio.streams import atomic_path

    executable = str(require("imageio_ffmpeg", "render").get_ffmpeg_exe())
    target = Path(out_path)
    with tempfile.TemporaryDirectory(prefix="mien-mux-") as folder:
        wav = audio.write_wav(Path(folder) / "speech.wav")
        with atomic_path(target) as temporary:
            command = [executable, "-y", "-v", "error", "-nostdin", "-i", str(video_path), "-i", str(wav),
                       "-map", "0:v:0", "-map", "1:a:0", "-c:v", "copy", "-c:a", "aac", "-b:a", "128k",
                       "-movflags", "+faststart", "-f", "mp4", str(temporary)]  # fmt: skip
            result = subprocess.run(command, capture_output=True, check=False, timeout=600)
            if result.returncode != 0:
                log = result.stderr.decode("utf-8", "replace").strip()
                raise InvalidValueError("video", str(video_path), f"a video ffmpeg can mux with audio ({log})")
    return target
