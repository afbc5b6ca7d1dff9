"""One container for mien's own binary files: NumPy arrays plus JSON metadata in an ``.npz``.

Track files (:mod:`mien.tracking.track`), laugh libraries and learning checkpoints (:mod:`mien.laughter`),
the parsed ICT-FaceKit cache (:mod:`mien.rig.ict_facekit`) and ``.npz`` clips all use it.

Layout: a standard NumPy ``.npz`` (a zip of ``.npy`` arrays, readable without mien) whose array ``meta`` is a
0-d string holding a JSON object ``{"format": KIND, "version": N, ...}``; every other array is data.
Writing to a path is atomic (a temporary file in the same folder, then a rename), so a crash never leaves half
a file under the real name. Reading checks the kind and the version and turns a corrupt or truncated file into
one :class:`~mien.errors.InvalidValueError` naming the file. Arrays are read with ``allow_pickle=False``.

>>> import io
>>> buffer = io.BytesIO()
>>> _ = save_container(buffer, "mien-example", 1, {"fps": 30.0}, {"values": np.arange(3.0)})
>>> _ = buffer.seek(0)
>>> box = load_container(buffer, "mien-example", 1)
>>> box.meta["fps"], box.arrays["values"].tolist(), box.version
(30.0, [0.0, 1.0, 2.0], 1)
"""

from __future__ import annotations

import contextlib
import json
import os
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MissingAssetError
from mien.fileio.streams import Source, Target, atomic_open, source_name

__all__ = ["Container", "load_container", "save_container"]

META_KEY = "meta"
"""Name of the array holding the JSON metadata."""

_SAVERS = {True: np.savez_compressed, False: np.savez}


@dataclass(frozen=True, eq=False)
class Container:
    """What a container file holds."""

    kind: str
    """The ``format`` entry (``"mien-track"``, ``"mien-laugh-library"``...); ``""`` for a file from before the
    container had one (such files are accepted as version 0)."""
    version: int
    """The ``version`` entry."""
    meta: dict[str, Any]
    """The whole metadata object (``format`` and ``version`` included)."""
    arrays: dict[str, np.ndarray]
    """Data arrays by name (the ``meta`` array excluded), fully read into memory."""


def save_container(
    target: Target,
    kind: str,
    version: int,
    meta: Mapping[str, Any],
    arrays: Mapping[str, np.ndarray],
    compress: bool = True,
) -> Path | None:
    """Write ``arrays`` and ``meta`` (JSON-serialisable) as a container of ``kind`` and ``version``.

    ``target``: a path (written atomically; missing folders are made) or a writable binary stream.
    Returns the path, or None for a stream. ``compress`` trades write speed for size.
    """
    if META_KEY in arrays:
        raise InvalidValueError("arrays", META_KEY, f"array names other than {META_KEY!r}")
    for key, array in arrays.items():
        if np.asarray(array).dtype.kind == "O":  # would need pickle to read back, which loading refuses
            raise InvalidValueError(f"arrays[{key!r}]", "an object array", "numeric, bool or string arrays")
    header = {"format": kind, "version": int(version), **meta}
    payload: dict[str, Any] = {META_KEY: np.array(json.dumps(header, sort_keys=True)), **arrays}
    save = _SAVERS[compress]
    if not isinstance(target, (str, os.PathLike)):
        save(target, **payload)
        return None
    path = Path(target)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_open(path) as stream:
        save(stream, **payload)
    return path


def load_container(source: Source, kind: str | None = None, max_version: int | None = None) -> Container:
    """Read a container; check its ``kind`` and that its version is at most ``max_version``.

    Raises :class:`MissingAssetError` for a missing path and :class:`InvalidValueError` naming the file for a
    corrupt or truncated file, a file of another kind or a newer version.
    """
    name = source_name(source)
    if isinstance(source, (str, os.PathLike)) and not Path(source).is_file():
        raise MissingAssetError(f"{source}: no such file; check the path")
    try:
        with contextlib.ExitStack() as stack:  # open a path here: np.load leaks the handle of a damaged file
            stream = stack.enter_context(open(source, "rb")) if isinstance(source, (str, os.PathLike)) else source
            data = stack.enter_context(np.load(stream, allow_pickle=False))
            if META_KEY not in data.files:
                raise InvalidValueError(f"{name}", sorted(data.files), f"a mien container (a {META_KEY!r} array)")
            meta = json.loads(str(data[META_KEY][()]))
            arrays = {key: np.array(data[key]) for key in data.files if key != META_KEY}
    except InvalidValueError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        reason = f"corrupt or truncated ({type(exc).__name__}: {exc})"
        raise InvalidValueError(f"{name}", reason, "a complete .npz container: write the file again") from None
    if not isinstance(meta, dict):
        raise InvalidValueError(f"{name} meta", type(meta).__name__, "a JSON object")
    found_kind = str(meta.get("format", ""))
    version = meta.get("version", 0)
    if kind is not None and found_kind and found_kind != kind:
        raise InvalidValueError(f"{name} format", found_kind, f"a {kind!r} file")
    if not isinstance(version, int) or (max_version is not None and version > max_version):
        raise InvalidValueError(f"{name} version", version, f"a version <= {max_version} (a newer mien wrote it?)")
    return Container(kind=found_kind, version=version, meta=meta, arrays=arrays)
