"""Plain CSV curves: a ``time_s`` column then one column per channel, one row per frame.

The default ``.csv`` format (other CSV dialects, Live Link Face and OpenFace, are told apart by their
headers). Values are written with full precision (Python's shortest round-trip ``repr``), so a round trip
is exact.
"""

from __future__ import annotations

import csv
import io

import numpy as np

from mien.exchange.csv_table import check_increasing, read_columns
from mien.facs.clip import Clip
from mien.fileio.streams import Source, TargetT, refuse_rig, write_text

__all__ = ["SUFFIXES", "read", "sniff", "write"]

SUFFIXES: tuple[str, ...] = (".csv",)
"""File suffixes of this format."""

HEADER_HINT = "time_s,<channel>,... (time in seconds, one column per channel)"
"""What the first line of such a file looks like (for messages)."""


def sniff(head: str) -> bool:
    """True when the first characters of a file start a ``time_s`` header."""
    return head.lstrip().startswith("time_s")


def write(clip: Clip, target: TargetT, rig: object = None) -> TargetT:
    """Write ``clip`` as CSV (``time_s,<channel>,...``) to a path (atomically) or a binary stream."""
    refuse_rig(rig, ".csv")
    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(("time_s", *clip.channels))
    for time_s, row in zip(clip.times_s.tolist(), clip.values.tolist(), strict=True):
        writer.writerow((repr(time_s), *(repr(v) for v in row)))
    write_text(text.getvalue(), target)
    return target


def read(source: Source) -> Clip:
    """Read a CSV written by :func:`write` (or any CSV with a ``time_s`` column and numeric columns).

    The frame rate is taken from the mean time step; a file with one frame is read at 30 fps. Bad cells,
    short rows, NaN and time stamps that do not increase raise naming the file, line and column.
    """
    table = read_columns(source, first_column="time_s")
    check_increasing(table, "time_s")
    times = table.values["time_s"]
    count = len(times)
    fps = 30.0 if count < 2 else (count - 1) / float(times[-1] - times[0])
    channels = table.header[1:]
    values = np.stack([table.values[c] for c in channels], axis=1) if channels else np.zeros((count, 0))
    return Clip(values, round(fps, 6), tuple(channels))
