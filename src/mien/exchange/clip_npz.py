"""Clips as NumPy ``.npz``: arrays ``values`` (frames, channels), ``fps`` and ``channels``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.clip import Clip

__all__ = ["read", "write"]


def write(clip: Clip, path: str | Path) -> Path:
    """Write ``clip`` as a compressed ``.npz``."""
    path = Path(path)
    np.savez_compressed(path, values=clip.values, fps=np.float64(clip.fps), channels=np.array(clip.channels))
    return path


def read(path: str | Path) -> Clip:
    """Read a clip written by :func:`write`."""
    with np.load(Path(path), allow_pickle=False) as data:
        missing = {"values", "fps", "channels"} - set(data.files)
        if missing:
            raise InvalidValueError(f"{path}", sorted(data.files), f"arrays values, fps, channels (missing {missing})")
        return Clip(data["values"], float(data["fps"]), tuple(str(c) for c in data["channels"]))
