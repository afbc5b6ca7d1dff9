"""Clips as NumPy ``.npz``: a :mod:`~mien.fileio.container` of kind ``mien-clip`` (array ``values``
(frames, channels) float64; metadata ``fps`` and ``channels``).

Files from before the container (arrays ``values``, ``fps`` and ``channels``, no metadata) still read.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.facs.clip import Clip
from mien.fileio.container import load_container, save_container
from mien.fileio.streams import Source, TargetT, refuse_rig, source_name

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "SUFFIXES", "read", "write"]

SUFFIXES: tuple[str, ...] = (".npz",)
"""File suffixes of this format."""

FORMAT_NAME = "mien-clip"
"""The container kind of a clip file."""

FORMAT_VERSION = 1
"""The clip file version this module writes (and the newest it reads)."""


def write(clip: Clip, target: TargetT, rig: object = None) -> TargetT:
    """Write ``clip`` as a compressed ``.npz`` container to ``target`` (a path, written atomically, or a stream)."""
    refuse_rig(rig, ".npz")
    meta = {"fps": clip.fps, "channels": list(clip.channels)}
    save_container(target, FORMAT_NAME, FORMAT_VERSION, meta, {"values": clip.values})
    return target


def read(source: Source) -> Clip:
    """Read a clip written by :func:`write` (or by mien before the container)."""
    name = source_name(source)
    meta, arrays = _load(source)
    if "values" not in arrays or "fps" not in meta or "channels" not in meta:
        raise InvalidValueError(f"{name}", sorted(arrays), "a clip file (array values; fps and channels)")
    try:
        return Clip(arrays["values"], float(meta["fps"]), tuple(str(c) for c in meta["channels"]))
    except InvalidValueError as exc:
        raise InvalidValueError(f"{name} {exc.field}", exc.value, exc.expected) from None


def _load(source: Source) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """(metadata, arrays) of a clip container, or of a pre-container clip file (``fps``/``channels`` arrays)."""
    name = source_name(source)
    try:
        box = load_container(source, FORMAT_NAME, FORMAT_VERSION)
        return box.meta, box.arrays
    except InvalidValueError as exc:
        if "mien container" not in exc.expected or hasattr(source, "read"):
            raise
    with np.load(source, allow_pickle=False) as data:
        if not {"values", "fps", "channels"} <= set(data.files):
            raise InvalidValueError(f"{name}", sorted(data.files), "a clip file (arrays values, fps, channels)")
        meta = {"fps": float(data["fps"]), "channels": [str(c) for c in data["channels"]]}
        return meta, {"values": np.array(data["values"])}
