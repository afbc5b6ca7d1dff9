"""The laugh library: one representative controller curve per laugh/smile type, and its file format.

A library is what the learning pipeline (:mod:`mien.learning.learn`) produces from video and what the
generator (:mod:`mien.laughter.generator`) plays back; the built-in one
(:func:`mien.laughter.builtin_library.default_library`) has the same form.

File format (``.npz``, version 1; a :mod:`mien.fileio.container`, written atomically): one ``float64`` array
``curve/<type>`` of shape ``(n_frames, 16)`` per type (columns in :data:`~mien.laughter.names.CONTROLLER_NAMES`
order), and ``meta``, a 0-d string array holding JSON: ``{"format": "mien-laugh-library", "version": 1,
"source", "eps", "fps", "n_takes", "created", "method", "extra", "types", "channels"}``. Loading never unpickles
objects.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.clip import Clip
from mien.fileio.container import load_container, save_container
from mien.laughter.names import CONTROLLER_NAMES, LAUGH_TYPES

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "LaughLibrary", "LibraryMetadata", "load_library", "utc_now"]

FORMAT_NAME = "mien-laugh-library"
"""The ``format`` entry of a library file's metadata."""
FORMAT_VERSION = 1
"""The file format version this module writes (and the newest it reads)."""


def utc_now() -> str:
    """The current UTC time as ISO 8601 text (seconds precision)."""
    return _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat()


@dataclass(frozen=True)
class LibraryMetadata:
    """Where a library came from."""

    source: str
    """``"builtin"`` or ``"learned:<folder>"``."""
    eps: float
    """The controller hardness factor of the paper's Eq 1 the curves were made with."""
    fps: float
    """Frame rate of the curves, frames per second."""
    n_takes: Mapping[str, int]
    """Per type, how many takes (performances) the curve summarises (0 for built-in curves)."""
    created: str
    """ISO 8601 UTC creation time."""
    method: str = "medoid"
    """How representatives were chosen: ``"medoid"``, ``"dba"`` or ``"recipe"`` (built-in)."""
    extra: Mapping[str, Any] = field(default_factory=dict)
    """JSON-safe details (per-type takes used, cluster sizes, DTW summaries...)."""

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict."""
        return {
            "source": self.source,
            "eps": self.eps,
            "fps": self.fps,
            "n_takes": dict(self.n_takes),
            "created": self.created,
            "method": self.method,
            "extra": dict(self.extra),
        }


@dataclass(frozen=True, eq=False)
class LaughLibrary:
    """Representative controller curves by laugh type, plus metadata."""

    curves: Mapping[str, Clip]
    """Type id -> clip over :data:`~mien.laughter.names.CONTROLLER_NAMES` (controller values, eps-scaled)."""
    metadata: LibraryMetadata
    """Provenance."""

    def __post_init__(self) -> None:
        ordered: dict[str, Clip] = {}
        for name in sorted(self.curves, key=lambda n: LAUGH_TYPES.index(n) if n in LAUGH_TYPES else -1):
            if name not in LAUGH_TYPES:
                raise UnknownNameError("laugh type", name, LAUGH_TYPES)
            clip = self.curves[name]
            if clip.channels != CONTROLLER_NAMES:
                raise InvalidValueError(f"curves[{name}].channels", clip.channels, "CONTROLLER_NAMES in order")
            if clip.n_frames < 2:
                raise InvalidValueError(f"curves[{name}]", f"{clip.n_frames} frames", "at least 2 frames")
            ordered[name] = clip
        if not math.isfinite(self.metadata.eps) or self.metadata.eps <= 0:
            raise InvalidValueError("eps", self.metadata.eps, "a positive number")
        object.__setattr__(self, "curves", ordered)

    @property
    def types(self) -> tuple[str, ...]:
        """Types the library has curves for, in taxonomy order."""
        return tuple(self.curves)

    def curve(self, type_name: str) -> Clip:
        """The representative controller clip of ``type_name``; :class:`UnknownNameError` if absent."""
        try:
            return self.curves[type_name]
        except KeyError:
            raise UnknownNameError("laugh type in this library", type_name, self.types or LAUGH_TYPES) from None

    def save(self, path: str | Path) -> Path:
        """Write the library to ``path`` (``.npz`` appended when missing) and return the path written."""
        path = Path(path)
        if path.suffix != ".npz":
            path = path.with_name(path.name + ".npz")
        meta = {
            "format": FORMAT_NAME,
            "version": FORMAT_VERSION,
            "types": list(self.types),
            "channels": list(CONTROLLER_NAMES),
            "curve_fps": {name: clip.fps for name, clip in self.curves.items()},
            **self.metadata.to_dict(),
        }
        arrays: dict[str, np.ndarray] = {f"curve/{name}": clip.values for name, clip in self.curves.items()}

        save_container(path, FORMAT_NAME, FORMAT_VERSION, meta, arrays)  # atomic: temporary file, then rename
        return path

    @classmethod
    def load(cls, path: str | Path) -> LaughLibrary:
        """Read a library written by :meth:`save`; :class:`InvalidValueError` for a file that is not one."""
        return load_library(path)

    def equals(self, other: LaughLibrary, ignore: tuple[str, ...] = ("created",)) -> bool:
        """True when curves are identical and metadata match (except the fields in ``ignore``)."""
        if self.types != other.types:
            return False
        if any(self.curves[n] != other.curves[n] for n in self.types):
            return False
        mine = {k: v for k, v in self.metadata.to_dict().items() if k not in ignore}
        theirs = {k: v for k, v in other.metadata.to_dict().items() if k not in ignore}
        return mine == theirs


def load_library(path: str | Path) -> LaughLibrary:
    """Read a library file (see the module docstring for the format)."""
    path = Path(path)
    if not path.is_file():
        raise InvalidValueError("library", str(path), "an existing .npz library file")

    box = load_container(path)  # corrupt, truncated or foreign files raise naming the file
    meta = box.meta
    arrays = {key: value for key, value in box.arrays.items() if key.startswith("curve/")}
    if meta.get("format") != FORMAT_NAME:
        raise InvalidValueError("library format", meta.get("format"), f"{FORMAT_NAME!r}")
    version = meta.get("version")
    if not isinstance(version, int) or version > FORMAT_VERSION:
        raise InvalidValueError("library version", version, f"an integer <= {FORMAT_VERSION}")
    channels = tuple(meta["channels"])
    if channels != CONTROLLER_NAMES:
        raise InvalidValueError("library channels", channels, "CONTROLLER_NAMES")
    curve_fps = meta.get("curve_fps", {})
    curves = {
        name: Clip(arrays[f"curve/{name}"], float(curve_fps.get(name, meta["fps"])), channels) for name in meta["types"]
    }
    metadata = LibraryMetadata(
        source=str(meta["source"]),
        eps=float(meta["eps"]),
        fps=float(meta["fps"]),
        n_takes={str(k): int(v) for k, v in meta["n_takes"].items()},
        created=str(meta["created"]),
        method=str(meta.get("method", "medoid")),
        extra=dict(meta.get("extra", {})),
    )
    return LaughLibrary(curves, metadata)
