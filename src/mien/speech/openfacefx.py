"""OpenFaceFX viseme output (``openfacefx.track`` JSON, PyPI ``openfacefx``) read as a track, not re-derived.

The file holds sparse ``[time_s, weight]`` keyframes per viseme channel over the same 15 visemes (its
``viseme_set``) plus ``fps`` and ``duration``; mien samples each channel linearly at
:data:`~mien.speech.track.TRACK_FPS` (OpenFaceFX's reference reader interpolates linearly between keys and
holds the ends). OpenFaceFX has already coarticulated and smoothed the curves, so mien applies no
coarticulation of its own; ``sil`` takes what the other weights leave. Channels outside the 15 visemes (gesture
or emotion channels a newer OpenFaceFX may add) are ignored and listed in the utterance's metadata.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.speech.audio import read_audio
from mien.speech.track import TRACK_FPS, Audio, Utterance, VisemeTrack
from mien.speech.visemes import VISEMES

__all__ = ["FORMAT", "MAX_DURATION_S", "read_openfacefx"]

FORMAT = "openfacefx.track"
"""The ``format`` value OpenFaceFX writes."""

MAX_DURATION_S = 3600.0
"""Longest track read, seconds."""


def read_openfacefx(path: str | Path, audio: Audio | str | Path | None = None) -> Utterance:
    """An :class:`Utterance` from OpenFaceFX's ``track.json`` at ``path``, with ``audio`` as its sound."""
    source = Path(path)
    try:
        data = json.loads(source.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InvalidValueError("openfacefx track", str(path), f"a readable openfacefx.track JSON ({error})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("channels"), list):
        raise InvalidValueError("openfacefx track", str(path), f'JSON with "format": "{FORMAT}" and "channels"')
    try:
        duration = float(data.get("duration", 0.0))
    except (TypeError, ValueError):
        raise InvalidValueError("openfacefx duration", data.get("duration"), "seconds") from None
    ignored = []
    curves: dict[str, np.ndarray] = {}
    for channel in data["channels"]:
        name = channel.get("name") if isinstance(channel, dict) else None
        if name not in VISEMES:
            ignored.append(str(name))
            continue
        try:
            keys = np.asarray(channel.get("keys", []), dtype=np.float64).reshape(-1, 2)
        except (TypeError, ValueError):
            raise InvalidValueError(
                f"openfacefx channel {name} keys", "not [time, value] pairs", "[[t, w], ...]"
            ) from None
        if keys.size and (not np.isfinite(keys).all() or np.any(np.diff(keys[:, 0]) < 0)):
            raise InvalidValueError(f"openfacefx channel {name} keys", "unordered or not finite", "increasing times")
        curves[str(name)] = keys
        if keys.size:
            duration = max(duration, float(keys[-1, 0]))
    if not curves:
        raise InvalidValueError("openfacefx track", str(path), f"at least one viseme channel ({', '.join(VISEMES)})")
    if not (math.isfinite(duration) and 0.0 < duration <= MAX_DURATION_S):
        raise InvalidValueError("openfacefx duration", duration, f"0 < seconds <= {MAX_DURATION_S:g}")
    times = np.arange(math.floor(duration * TRACK_FPS) + 1) / TRACK_FPS
    weights = np.zeros((len(times), len(VISEMES)))
    for name, keys in curves.items():
        if keys.size:
            weights[:, VISEMES.index(name)] = np.interp(times, keys[:, 0], keys[:, 1])
    sound = read_audio(audio) if isinstance(audio, str | Path) else audio
    metadata: dict[str, object] = {"openfacefx": str(path), "ignored_channels": ignored}
    return Utterance(VisemeTrack(weights, TRACK_FPS), (), sound, "", "openfacefx", metadata)
