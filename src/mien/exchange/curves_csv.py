"""Plain CSV curves: a ``time_s`` column then one column per channel, one row per frame."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.clip import Clip

__all__ = ["read", "write"]


def write(clip: Clip, path: str | Path) -> Path:
    """Write ``clip`` as CSV (``time_s,<channel>,...``; values with full precision)."""
    path = Path(path)
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(("time_s", *clip.channels))
        for time_s, row in zip(clip.times_s.tolist(), clip.values.tolist(), strict=True):
            writer.writerow((repr(time_s), *(repr(v) for v in row)))
    return path


def read(path: str | Path) -> Clip:
    """Read a CSV written by :func:`write` (or any CSV with a ``time_s`` column and numeric columns).

    The frame rate is taken from the mean time step; a file with one frame is read at 30 fps.
    """
    path = Path(path)
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    if not rows or not rows[0] or rows[0][0] != "time_s":
        raise InvalidValueError(f"{path} header", rows[0] if rows else None, "a first column named time_s")
    header = rows[0]
    try:
        data = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=np.float64)
    except ValueError as exc:
        raise InvalidValueError(f"{path} values", str(exc), "numbers in every cell") from None
    if data.size == 0:
        return Clip(np.zeros((0, len(header) - 1)), 30.0, tuple(header[1:]))
    if data.shape[1] != len(header):
        raise InvalidValueError(f"{path} rows", data.shape[1], f"{len(header)} cells per row")
    times = data[:, 0]
    fps = 30.0 if len(times) < 2 else (len(times) - 1) / float(times[-1] - times[0])
    return Clip(data[:, 1:], round(fps, 6), tuple(header[1:]))
