"""OpenFace 2.x ``FeatureExtraction`` CSV import: a tracked human performance as a face-channel clip.

OpenFace (Baltrusaitis et al. 2018) writes one row per video frame; its header names carry a leading space
(``frame, face_id, timestamp, confidence, success, ...``). Columns used, found by name:

- ``frame`` and ``timestamp`` (seconds): the clip has one frame per row and its rate is estimated from the time
  stamps (``(n - 1) / (last - first)``); rows are resampled onto that uniform grid; time stamps must increase;
- ``AUxx_r`` intensities 0..5 -> the mien AU channel (both sides of a lateral AU: OpenFace does not tell sides
  apart); ``AUxx_c`` presence (0/1) -> intensity 1.0 (trace) for an AU that has only a presence column (AU28);
- ``pose_Rx, pose_Ry, pose_Rz`` (radians, camera frame: +x image right, +y down, +z from the camera to the
  face) -> ``head_pitch_deg = -Rx``, ``head_yaw_deg = -Ry``, ``head_roll_deg = +Rz`` (mien signs: yaw to the
  character's left, chin up, tilt to the left shoulder are positive);
- ``gaze_angle_x, gaze_angle_y`` (radians) -> ``gaze_yaw_deg = +x``, ``gaze_pitch_deg = -y``; files without
  them (older 2.x) get the angles from the mean of the ``gaze_0_*`` and ``gaze_1_*`` direction vectors, as
  OpenFace computes them (``atan2(x, -z)``, ``atan2(y, -z)``).

Rows with ``success`` 0 (no face found; OpenFace writes zeros) are documented skips: they take the values of
the nearest tracked rows (linear interpolation in time) and a warning says how many. A file in which no
row has a face raises. OpenFace AUs mien has no channel for are skipped with a warning naming them.
"""

from __future__ import annotations

import re
import warnings

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.csv_table import check_increasing, columns_from_text
from mien.exchange.timing import uniform_clip
from mien.facs.catalogue import FACE_AU_CODES, FACE_CHANNELS, au_channels
from mien.facs.clip import Clip
from mien.facs.intensity import MAX_INTENSITY
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, read_text, source_name

__all__ = ["PRESENCE_INTENSITY", "SUFFIXES", "read", "sniff"]

SUFFIXES: tuple[str, ...] = (".csv",)
"""File suffixes of this format (told from other CSV files by :func:`sniff`)."""

HEADER_HINT = "frame, face_id, timestamp, ..., AU01_r, ... (OpenFace 2.x)"
"""What the first line of such a file looks like (for messages)."""

PRESENCE_INTENSITY = 1.0
"""Intensity given to an AU OpenFace reports only as present (``AUxx_c`` = 1, no ``AUxx_r``)."""

_AU_COLUMN = re.compile(r"^AU(\d+)_([rc])$")


def sniff(head: str) -> bool:
    """True when the header names OpenFace columns (``frame``, ``timestamp`` and ``AUxx_r``)."""
    first = head.lstrip().split("\n", 1)[0].replace(" ", "").split(",")
    return "timestamp" in first and "frame" in first and any(_AU_COLUMN.match(c) for c in first)


def read(source: Source) -> Clip:
    """Read an OpenFace CSV as a clip over :data:`~mien.facs.catalogue.FACE_CHANNELS` (see the module doc)."""
    name = source_name(source)
    text = read_text(source)
    first = text.lstrip().split("\n", 1)[0]
    header = [c.strip() for c in first.split(",")]
    if "frame" not in header or "timestamp" not in header:
        raise InvalidValueError(f"{name} line 1", first[:40], "an OpenFace header with frame and timestamp columns")
    intensities = {int(m.group(1)): c for c in header if (m := _AU_COLUMN.match(c)) and m.group(2) == "r"}
    presences = {int(m.group(1)): c for c in header if (m := _AU_COLUMN.match(c)) and m.group(2) == "c"}
    if not intensities and not presences:
        raise InvalidValueError(f"{name} line 1", "no AUxx_r or AUxx_c column", "OpenFace AU columns")
    unusable = sorted(code for code in {*intensities, *presences} if code not in FACE_AU_CODES)
    if unusable:
        warnings.warn(f"{name}: skipped AUs mien has no channel for: {unusable}", stacklevel=2)
    used_r = {code: c for code, c in intensities.items() if code in FACE_AU_CODES}
    used_c = {code: c for code, c in presences.items() if code in FACE_AU_CODES and code not in used_r}
    pose = [c for c in ("pose_Rx", "pose_Ry", "pose_Rz") if c in header]
    if pose and len(pose) != 3:
        missing = sorted({"pose_Rx", "pose_Ry", "pose_Rz"} - set(pose))
        raise InvalidValueError(f"{name} line 1", f"no column {', '.join(missing)}", "all three pose_R columns")
    gaze: list[str] = [c for c in ("gaze_angle_x", "gaze_angle_y") if c in header]
    vectors = [f"gaze_{e}_{a}" for e in (0, 1) for a in "xyz"]
    if not gaze and all(v in header for v in vectors):
        gaze = vectors
    optional = [c for c in ("success",) if c in header]
    wanted = ["frame", "timestamp", *optional, *used_r.values(), *used_c.values(), *pose, *gaze]
    table = columns_from_text(text, name, wanted)
    n_rows = len(table.lines)
    if n_rows == 0:
        raise InvalidValueError(name, "no data rows", "at least one frame after the header")
    check_increasing(table, "timestamp")
    check_increasing(table, "frame")
    for column in used_r.values():
        values = table.values[column]
        bad = np.flatnonzero((values < 0) | (values > MAX_INTENSITY))
        if bad.size:
            where, value = table.where(int(bad[0]), column), float(values[bad[0]])
            raise InvalidValueError(where, value, f"an intensity in 0..{MAX_INTENSITY:g}")
    check_count(name, "values (frames x channels)", n_rows * len(FACE_CHANNELS), current().clip_values)
    values = np.zeros((n_rows, len(FACE_CHANNELS)))
    for code, column in used_r.items():
        values[:, list(au_channels(code))] = table.values[column][:, None]
    for code, column in used_c.items():
        values[:, list(au_channels(code))] = PRESENCE_INTENSITY * (table.values[column][:, None] > 0.5)
    if pose:
        rx, ry, rz = (np.degrees(table.values[c]) for c in pose)
        for channel, column in (("head_yaw_deg", -ry), ("head_pitch_deg", -rx), ("head_roll_deg", rz)):
            values[:, FACE_CHANNELS.index(channel)] = column
    if gaze:
        if len(gaze) == 2:
            yaw, pitch = table.values["gaze_angle_x"], table.values["gaze_angle_y"]
        else:
            x, y, z = ((table.values[f"gaze_0_{a}"] + table.values[f"gaze_1_{a}"]) / 2 for a in "xyz")
            yaw, pitch = np.arctan2(x, -z), np.arctan2(y, -z)
        values[:, FACE_CHANNELS.index("gaze_yaw_deg")] = np.degrees(yaw)
        values[:, FACE_CHANNELS.index("gaze_pitch_deg")] = -np.degrees(pitch)
    times = table.values["timestamp"]
    tracked = table.values["success"] > 0.5 if "success" in table.values else np.ones(n_rows, bool)
    if not tracked.any():
        raise InvalidValueError(f"{name} success", "0 in every row", "at least one row where OpenFace found a face")
    lost = ~tracked
    if lost.any():
        first = table.lines[int(np.argmax(lost))]
        warnings.warn(
            f"{name}: {int(lost.sum())} of {n_rows} rows without a face (success 0, first at line {first}) "
            "filled from the nearest tracked rows",
            stacklevel=2,
        )
    for j in range(values.shape[1]):  # untracked rows (zeros in the file) take the tracked rows around them
        values[lost, j] = np.interp(times[lost], times[tracked], values[tracked, j])
    return uniform_clip(times, values, FACE_CHANNELS)
