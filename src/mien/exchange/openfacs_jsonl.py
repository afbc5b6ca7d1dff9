"""OpenFACS JSON lines (``.jsonl``): one OpenFACS face-state message per line, with its time.

Each line is a JSON object as an OpenFACS client sends it (Cuculo & D'Amelio 2019; mien's wire protocol,
:mod:`mien.server.protocol`): ``{"time_s": 0.0333, "AU1": 0, "AU2": 0, ..., "AU45": 0, "Speed": 1}``, where

- ``time_s`` is the time of the state in seconds (required, increasing);
- ``AU<n>`` is an intensity 0..5 applied to both sides of the AU, ``AU<n>L`` / ``AU<n>R`` one side;
- ``head_yaw_deg``, ``head_pitch_deg``, ``head_roll_deg``, ``gaze_yaw_deg``, ``gaze_pitch_deg`` are mien's
  pose channels in degrees (extensions; OpenFACS has none);
- ``Speed`` (OpenFACS's per-tick smoothing) is written as 1 (the state is reached at once, as in the file)
  and ignored when read.

The writer puts all 18 OpenFACS AUs on every line (a full state; an AU not named is 0 for OpenFACS), other AUs
and pose channels when non-zero, and a lateral AU's two sides as ``AU<n>L``/``AU<n>R`` when they differ.
The reader skips keys it does not know with one warning naming them and the first line they are on; the clip
rate is estimated from the time stamps and the states are resampled onto that uniform grid.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.timing import uniform_clip
from mien.facs.catalogue import FACE_AU_CODES, FACE_CHANNELS, OPENFACS_AUS, POSE_CHANNELS, au_channels
from mien.facs.clip import Clip
from mien.facs.intensity import MAX_INTENSITY
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, TargetT, read_text, refuse_rig, source_name, write_text

__all__ = ["SUFFIXES", "TIME_KEY", "read", "write"]

SUFFIXES: tuple[str, ...] = (".jsonl",)
"""File suffixes of this format."""

TIME_KEY = "time_s"
"""The key holding each state's time in seconds."""

_AU_KEY = re.compile(r"^AU(\d+)([LR]?)$")


def _face_values(clip: Clip) -> np.ndarray:
    """(n, 62) face-channel values of a clip whose channels are face channels."""
    unknown = [c for c in clip.channels if c not in FACE_CHANNELS]
    if unknown:
        raise InvalidValueError("clip channel", unknown[0], "face channels (AU12L, head_yaw_deg...) for .jsonl")
    values = np.zeros((clip.n_frames, len(FACE_CHANNELS)))
    values[:, [FACE_CHANNELS.index(c) for c in clip.channels]] = clip.values
    return values


def write(clip: Clip, target: TargetT, rig: object = None) -> TargetT:
    """Write a face-channel ``clip`` as OpenFACS JSON lines to a path (atomically) or a binary stream."""
    refuse_rig(rig, ".jsonl")
    values = _face_values(clip)
    lines = []
    for i, time_s in enumerate(clip.times_s.tolist()):
        state: dict[str, Any] = {TIME_KEY: time_s}
        row = values[i]
        for code in FACE_AU_CODES:
            ids = au_channels(code)
            sides = [float(row[j]) for j in ids]
            if len(sides) == 2 and sides[0] != sides[1]:
                state[f"AU{code}L"], state[f"AU{code}R"] = sides
            elif code in OPENFACS_AUS or sides[0] != 0.0:
                state[f"AU{code}"] = sides[0]
        for name in POSE_CHANNELS:
            value = float(row[FACE_CHANNELS.index(name)])
            if value != 0.0:
                state[name] = value
        state["Speed"] = 1
        lines.append(json.dumps(state, separators=(",", ":")))
    write_text("\n".join(lines) + ("\n" if lines else ""), target)
    return target


def _intensity(value: Any, where: str, key: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InvalidValueError(f"{where} key {key}", value, "a finite number")
    return float(value)


def read(source: Source) -> Clip:
    """Read OpenFACS JSON lines as a face-channel clip; bad lines raise naming the file, line and key."""
    name = source_name(source)
    lines = read_text(source).splitlines()
    check_count(name, "values (lines x channels)", len(lines) * len(FACE_CHANNELS), current().clip_values)
    times: list[float] = []
    rows = np.zeros((len(lines), len(FACE_CHANNELS)))  # one row per line, sized before any line is read
    unknown: dict[str, int] = {}
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        where = f"{name} line {number}"
        try:
            state = json.loads(line)
        except json.JSONDecodeError as exc:
            raise InvalidValueError(f"{where} column {exc.colno}", exc.msg, "one JSON object per line") from None
        if not isinstance(state, dict):
            raise InvalidValueError(where, type(state).__name__, "a JSON object")
        if TIME_KEY not in state:
            raise InvalidValueError(where, sorted(state)[:5], f"a {TIME_KEY!r} entry (seconds)")
        time_s = _intensity(state[TIME_KEY], where, TIME_KEY)
        if times and time_s <= times[-1]:
            raise InvalidValueError(f"{where} key {TIME_KEY}", time_s, f"a time after {times[-1]} (increasing)")
        row = rows[len(times)]
        for key, value in state.items():
            if key in (TIME_KEY, "Speed"):
                continue
            match = _AU_KEY.match(key)
            if key in POSE_CHANNELS:
                row[FACE_CHANNELS.index(key)] = _intensity(value, where, key)
            elif match and (key in FACE_CHANNELS or (not match.group(2) and int(match.group(1)) in FACE_AU_CODES)):
                intensity = _intensity(value, where, key)
                if not 0.0 <= intensity <= MAX_INTENSITY:
                    raise InvalidValueError(f"{where} key {key}", intensity, f"an intensity in 0..{MAX_INTENSITY:g}")
                if match.group(2):
                    row[FACE_CHANNELS.index(key)] = intensity
                else:
                    row[list(au_channels(int(match.group(1))))] = intensity
            else:
                unknown.setdefault(key, number)
        times.append(time_s)
    if unknown:
        shown = ", ".join(f"{k} (line {n})" for k, n in unknown.items())
        warnings.warn(f"{name}: skipped unknown keys {shown}", stacklevel=2)
    if not times:
        raise InvalidValueError(name, "no states", "at least one JSON line")
    return uniform_clip(np.asarray(times), rows[: len(times)], FACE_CHANNELS)
