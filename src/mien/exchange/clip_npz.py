"""Clips as NumPy ``.npz``: a :mod:`~mien.fileio.container` of kind ``mien-clip`` (array ``values``
(frames, channels) float64; metadata ``fps`` and ``channels``).

Files from before the container (arrays ``values``, ``fps`` and ``channels``, no metadata) still read.
What the arrays unpack to is checked against :mod:`mien.fileio.limits` before they are unpacked (:func:`check_npz`).
"""

from __future__ import annotations

import math
import zipfile
from typing import Any

import numpy as np
from numpy.lib import format as npy

from mien.errors import InvalidValueError
from mien.facs.clip import Clip
from mien.fileio.container import load_container, save_container
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, TargetT, refuse_rig, source_name

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "SUFFIXES", "check_npz", "read", "write"]

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


def check_npz(source: Source) -> None:
    """Refuse an ``.npz`` whose arrays would unpack to more than :mod:`mien.fileio.limits` allows, from the zip
    directory and each ``.npy`` header alone (a zip bomb of zeros is caught before anything is unpacked).

    A stream is left at the position it had; a file that is no zip is left for the reader to report.
    """
    name = source_name(source)
    limits = current()
    at = source.tell() if hasattr(source, "tell") else None
    try:
        with zipfile.ZipFile(source) as archive:
            members = archive.infolist()
            check_count(name, "zip members", len(members), limits.zip_members)
            total = 0
            for member in members:
                with archive.open(member) as stream:
                    shape, dtype = _npy_header(stream, f"{name} {member.filename}")
                count = math.prod(shape)
                if member.filename == "values.npy":
                    check_count(name, "values (frames x channels)", count, limits.clip_values)
                total += count * dtype.itemsize
                check_count(name, "bytes unpacked (as the arrays' headers declare)", total, limits.zip_bytes)
    except (zipfile.BadZipFile, EOFError, OSError):
        pass  # not a zip, or a damaged one: the reader names the file and the fault
    finally:
        if at is not None:
            source.seek(at)  # type: ignore[union-attr]


def _npy_header(stream: Any, name: str) -> tuple[tuple[int, ...], np.dtype[Any]]:
    """(shape, dtype) an ``.npy`` member declares (numpy's header readers; versions 1 to 3 share a layout)."""
    try:
        version = npy.read_magic(stream)
        read_header = npy.read_array_header_1_0 if version == (1, 0) else npy.read_array_header_2_0
        shape, _, dtype = read_header(stream)
    except ValueError as exc:
        raise InvalidValueError(name, str(exc)[:120], "a NumPy .npy array") from None
    return tuple(int(n) for n in shape), np.dtype(dtype)


def _load(source: Source) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """(metadata, arrays) of a clip container, or of a pre-container clip file (``fps``/``channels`` arrays)."""
    name = source_name(source)
    check_npz(source)
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
