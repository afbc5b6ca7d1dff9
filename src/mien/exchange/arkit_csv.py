"""Live Link Face (Epic Games' iPhone app) CSV: ARKit blendshape weights per frame, read and written.

Layout, as the app records it: a header ``Timecode,BlendShapeCount,EyeBlinkLeft,EyeLookDownLeft,...,TongueOut,
HeadYaw,HeadPitch,HeadRoll,LeftEyeYaw,LeftEyePitch,LeftEyeRoll,RightEyeYaw,RightEyePitch,RightEyeRoll`` (the
52 ARKit names with a capital first letter, in ARKit order, then 9 rotations), then one row per frame:
``HH:MM:SS:FF.mmm`` (hours, minutes, seconds, frame number at the timecode rate and the sub-frame fraction),
the number of values that follow (61), the 52 weights 0..1 and the rotations in radians.

Reading: columns are found by name (any order); the 52 blendshape columns are required; the head and eye
columns are optional. Rotations become mien pose channels in degrees: ``HeadYaw/HeadPitch/HeadRoll`` ->
``head_yaw_deg/head_pitch_deg/head_roll_deg``, the mean of the two eyes' yaw and pitch -> ``gaze_yaw_deg``
/ ``gaze_pitch_deg``, with the app's signs (not checked against a recorded head turn). Columns that are not
known names are skipped with a warning that lists them. The timecode rate is the smallest of 24, 25, 30, 48,
50, 60 above the last frame number before a change of the seconds field (60, the app's default, when the
seconds never change);
the clip's frame rate is estimated from the time stamps, and the rows are resampled onto that uniform grid.
The result is a weight clip (ARKit names, 0..1); :func:`mien.rig.face_weights.weights_to_au` turns it into
AU intensities (``mien import --au``).

Writing: an ARKit weight clip (or a face-channel clip, through the AU mapping on the built-in ARKit
vocabulary) as the app writes it, starting at timecode ``00:00:00:00.000``, with a 60 fps timecode and the
sub-frame in milliseconds of a frame (so any clip rate is kept). With ``names="file"`` and a head read from a
character file, the blendshape columns are that file's own shape names (``mien export --head face.glb --names
file``).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.csv_table import check_increasing, columns_from_text
from mien.exchange.file_shapes import file_shape_names, shape_weights, source_rows
from mien.exchange.timing import uniform_clip
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import POSE_CHANNELS
from mien.facs.clip import Clip
from mien.fileio.streams import Source, TargetT, read_text, refuse_rig, source_name, write_text
from mien.rig.builtin_head import builtin_head
from mien.rig.face_weights import clip_to_rig, is_weight_clip
from mien.rig.model import Rig

__all__ = ["COLUMNS", "ROTATION_COLUMNS", "SUFFIXES", "format_timecode", "parse_timecode", "read", "sniff", "write"]

SUFFIXES: tuple[str, ...] = (".csv",)
"""File suffixes of this format (told from other CSV files by :func:`sniff`)."""

HEADER_HINT = "Timecode,BlendShapeCount,EyeBlinkLeft,... (Live Link Face)"
"""What the first line of such a file looks like (for messages)."""

ROTATION_COLUMNS: tuple[str, ...] = (
    "HeadYaw",
    "HeadPitch",
    "HeadRoll",
    "LeftEyeYaw",
    "LeftEyePitch",
    "LeftEyeRoll",
    "RightEyeYaw",
    "RightEyePitch",
    "RightEyeRoll",
)
"""Rotation columns after the blendshapes, radians."""

COLUMNS: tuple[str, ...] = tuple(n[0].upper() + n[1:] for n in ARKIT_NAMES) + ROTATION_COLUMNS
"""The 61 value columns, in the app's order."""

TIMECODE_RATES: tuple[int, ...] = (24, 25, 30, 48, 50, 60)
"""Timecode frame rates the reader chooses from."""

WRITE_TIMECODE_FPS = 60
"""Timecode rate of written files (the app's default), whatever the clip's frame rate."""


def sniff(head: str) -> bool:
    """True when the file starts with a Live Link Face header."""
    return head.lstrip().replace(" ", "").startswith("Timecode,BlendShapeCount")


def parse_timecode(text: str, rate: float) -> float:
    """Seconds of an ``HH:MM:SS:FF.mmm`` timecode at ``rate`` frames per second; ``ValueError`` if malformed.

    >>> parse_timecode("00:00:01:15.500", 30)
    1.5166666666666666
    """
    parts = text.strip().split(":")
    if len(parts) != 4:
        raise ValueError(text)
    hours, minutes, seconds = (int(p) for p in parts[:3])
    frame = float(parts[3])
    if minutes >= 60 or seconds >= 60 or frame < 0 or hours < 0:
        raise ValueError(text)
    return hours * 3600.0 + minutes * 60.0 + seconds + frame / rate


def format_timecode(seconds: float, rate: int) -> str:
    """``HH:MM:SS:FF.mmm`` of ``seconds`` at timecode ``rate`` (the inverse of :func:`parse_timecode`).

    >>> format_timecode(1.5166666666666666, 30)
    '00:00:01:15.500'
    """
    frames = seconds * rate
    whole = math.floor(frames + 1e-6)
    fraction = max(0.0, frames - whole)
    total_s, frame = divmod(whole, rate)
    hours, rest = divmod(int(total_s), 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours:02d}:{minutes:02d}:{secs:02d}:{int(frame):02d}.{round(fraction * 1000):03d}"


def _timecode_parts(text: str) -> float:
    """``HH:MM:SS:FF.mmm`` -> whole seconds * 1000 + FF.mmm (both parts in one float; the rate comes later)."""
    parts = text.strip().split(":")
    if len(parts) != 4:
        raise ValueError(text)
    hours, minutes, seconds = (int(p) for p in parts[:3])
    frame = float(parts[3])
    if not (0 <= minutes < 60 and 0 <= seconds < 60 and hours >= 0 and 0 <= frame < 1000):
        raise ValueError(text)
    return (hours * 3600 + minutes * 60 + seconds) * 1000.0 + frame


def read(source: Source, timecode_fps: int | None = None) -> Clip:
    """Read a Live Link Face CSV as an ARKit weight clip (see the module doc); ``timecode_fps`` overrides the
    timecode rate the reader infers."""
    name = source_name(source)
    text = read_text(source)
    first = text.lstrip().split("\n", 1)[0]
    if not sniff(first):
        raise InvalidValueError(f"{name} line 1", first[:40], "a Live Link Face header 'Timecode,BlendShapeCount,...'")
    header = [c.strip() for c in first.split(",")]
    known = set(COLUMNS) | {"Timecode", "BlendShapeCount"}
    unknown = [c for c in header if c not in known]
    if unknown:
        warnings.warn(f"{name}: skipped unknown columns {', '.join(unknown)}", stacklevel=2)
    missing = [c for c in COLUMNS[:52] if c not in header]
    if missing:
        column_list = ", ".join(missing[:6]) + (", ..." if len(missing) > 6 else "")
        raise InvalidValueError(f"{name} line 1", f"no column {column_list}", "all 52 ARKit blendshape columns")
    rotations = [c for c in ROTATION_COLUMNS if c in header]
    wanted = ["Timecode", *COLUMNS[:52], *rotations]
    table = columns_from_text(text, name, wanted, {"Timecode": _timecode_parts})
    if len(table.lines) == 0:
        raise InvalidValueError(f"{name}", "no data rows", "at least one frame after the header")
    whole_s = np.floor(table.values["Timecode"] / 1000.0)
    frame_numbers = table.values["Timecode"] - whole_s * 1000.0
    rate = timecode_fps
    if rate is None:
        rate = 60
        change = np.flatnonzero(np.diff(whole_s) > 0)
        if change.size:  # the last frame number before the seconds change shows the rate
            last = float(frame_numbers[change].max())
            rate = next((r for r in TIMECODE_RATES if r > last), 60)
    times = whole_s + frame_numbers / rate
    table.values["Timecode"] = times
    check_increasing(table, "Timecode")
    for column in COLUMNS[:52]:
        weights = table.values[column]
        bad = np.flatnonzero((weights < -1e-6) | (weights > 1.0 + 1e-6))
        if bad.size:
            raise InvalidValueError(table.where(int(bad[0]), column), float(weights[bad[0]]), "a weight in 0..1")
    columns = [table.values[c] for c in COLUMNS[:52]]
    channels = list(ARKIT_NAMES)
    if {"HeadYaw", "HeadPitch", "HeadRoll"} <= set(rotations):
        columns += [np.degrees(table.values[c]) for c in ("HeadYaw", "HeadPitch", "HeadRoll")]
        channels += list(POSE_CHANNELS[:3])
    eyes = ("LeftEyeYaw", "RightEyeYaw", "LeftEyePitch", "RightEyePitch")
    if set(eyes) <= set(rotations):
        for left, right in (eyes[:2], eyes[2:]):
            columns.append(np.degrees(0.5 * (table.values[left] + table.values[right])))
        channels += list(POSE_CHANNELS[3:])
    return uniform_clip(times, np.stack(columns, axis=1), channels)


def write(clip: Clip, target: TargetT, rig: object = None, names: str = "arkit") -> TargetT:
    """Write ``clip`` as a Live Link Face CSV (see the module doc) to a path (atomically) or a binary stream.

    ``clip``: ARKit names (weights 0..1) and optional pose channels (degrees), face channels, which go
    through the AU mapping, or laughter-controller curves, which go through the controllers' ARKit mapping.
    Missing ARKit channels are written as 0; weight channels beyond ARKit's 52 (ICT's ``browInnerUpLeft``...)
    have no column and are skipped with a warning.

    ``names="file"`` writes the columns under the own shape names of ``rig``, a head read from a character file
    (``--head face.glb``): one column per file shape its targets are built from, at the weights
    :mod:`mien.exchange.file_shapes` gives (a tool that maps those names, such as a game engine's pose asset,
    then plays the clip on that character). Such a file is for that character; this reader reads ARKit columns.
    """

    if names not in ("arkit", "file"):
        raise InvalidValueError("names", names, "arkit (Live Link Face's columns) or file (the head file's shapes)")
    columns: tuple[str, ...] = COLUMNS[:52]
    if names == "file":
        if not isinstance(rig, Rig):
            raise InvalidValueError("names", names, "a head read from a character file to take the names from")
        rows = source_rows(rig)
        columns = file_shape_names(rows)
        bad = next((c for c in columns if any(ch in c for ch in ',"\r\n')), None)
        if bad is not None:
            raise InvalidValueError(f"shape name of {rig.name}", bad, "a name without commas, quotes or line breaks")
        rig_weights, poses = clip_to_rig(clip, rig)
        shapes = shape_weights(rig_weights, rig.target_names, rows)
        weights = np.stack([shapes[c] for c in columns], axis=1).astype(np.float64)
    elif is_weight_clip(clip, ARKIT_NAMES):
        refuse_rig(rig, "Live Link Face .csv")
        weights = np.zeros((clip.n_frames, 52))
        poses = np.zeros((clip.n_frames, len(POSE_CHANNELS)))
        skipped = [c for c in clip.channels if c not in ARKIT_NAMES and c not in POSE_CHANNELS]
        if skipped:
            warnings.warn(f"no Live Link Face column for {', '.join(skipped)}: skipped", stacklevel=2)
        for j, channel in enumerate(clip.channels):
            if channel in POSE_CHANNELS:
                poses[:, POSE_CHANNELS.index(channel)] = clip.values[:, j]
            elif channel in ARKIT_NAMES:
                weights[:, ARKIT_NAMES.index(channel)] = clip.values[:, j]
    else:
        refuse_rig(rig, "Live Link Face .csv")

        all_weights, poses = clip_to_rig(clip, builtin_head())
        weights = np.asarray(all_weights[:, :52], np.float64)
    rate = WRITE_TIMECODE_FPS
    radians = np.radians(poses)
    zero = np.zeros(clip.n_frames)
    # head yaw, pitch, roll; then each eye's yaw, pitch, roll (both eyes follow the one gaze)
    rotations = np.column_stack(
        [*radians[:, :3].T, radians[:, 3], radians[:, 4], zero, radians[:, 3], radians[:, 4], zero]
    )
    header = (*columns, *ROTATION_COLUMNS)
    rows_out = ["Timecode,BlendShapeCount," + ",".join(header)]
    for i, time_s in enumerate(clip.times_s):
        values = ",".join(repr(float(v)) for v in np.concatenate([weights[i], rotations[i]]))
        rows_out.append(f"{format_timecode(float(time_s), rate)},{len(header)},{values}")
    write_text("\n".join(rows_out) + "\n", target)
    return target
