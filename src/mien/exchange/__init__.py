"""File formats: one module per format, one contract, a plain registry.

Every format module (named in :data:`FORMATS`) declares

- ``SUFFIXES``: the file suffixes it answers to (``(".glb",)``);
- ``read(source) -> Clip`` when it can be read, ``source`` a path or a binary stream;
- ``write(clip, target, rig=None, **options)`` when it can be written, ``target`` a path (written atomically)
  or a binary stream; formats that carry geometry (``.glb``) use ``rig``, the others refuse one;
- optionally ``sniff(head: str) -> bool``, which tells its files from other formats sharing a suffix by their
  first characters (three CSV dialects share ``.csv``).

Raw readers keep their own names (:func:`mien.exchange.maya_anim.read_curves` returns the ``.anim`` curves and
their keys). Format modules import only numpy at module level, so the registry is cheap; a format's optional
dependency is needed only when that format is used.

>>> sorted(readable_suffixes())
['.anim', '.csv', '.glb', '.json', '.jsonl', '.npz', '.vrm']
>>> writer_for("face.anim").__module__
'mien.exchange.maya_anim'
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

from mien.errors import InvalidValueError, UnknownNameError
from mien.fileio.streams import read_bytes, source_name

__all__ = [
    "FORMATS",
    "READERS",
    "WRITERS",
    "format_for",
    "format_module",
    "read_clip",
    "readable_suffixes",
    "reader_for",
    "writable_suffixes",
    "writer_for",
]

FORMATS: dict[str, str] = {
    "curves_csv": "mien.exchange.curves_csv",
    "arkit_csv": "mien.exchange.arkit_csv",
    "openface_csv": "mien.exchange.openface_csv",
    "clip_json": "mien.exchange.clip_json",
    "openfacs_jsonl": "mien.exchange.openfacs_jsonl",
    "clip_npz": "mien.exchange.clip_npz",
    "maya_anim": "mien.exchange.maya_anim",
    "glb": "mien.exchange.glb",
    "vrm": "mien.exchange.vrm",
}
"""Format name -> module. For a suffix shared by several formats the first listed is the default writer."""

_SNIFF_CHARACTERS = 4096


def format_module(name: str) -> ModuleType:
    """The module of format ``name`` (a key of :data:`FORMATS`)."""
    if name not in FORMATS:
        raise UnknownNameError("file format", name, tuple(FORMATS))
    return importlib.import_module(FORMATS[name])


def _formats_with(suffix: str, function: str) -> list[str]:
    found = []
    for name in FORMATS:
        module = format_module(name)
        if suffix in module.SUFFIXES and hasattr(module, function):
            found.append(name)
    return found


def readable_suffixes() -> set[str]:
    """Suffixes some format reads."""
    return {s for name in FORMATS if hasattr(format_module(name), "read") for s in format_module(name).SUFFIXES}


def writable_suffixes() -> set[str]:
    """Suffixes some format writes."""
    return {s for name in FORMATS if hasattr(format_module(name), "write") for s in format_module(name).SUFFIXES}


def _head(path: str | os.PathLike[str]) -> str:
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as handle:
            return handle.read(_SNIFF_CHARACTERS)
    except OSError:
        return ""


def format_for(path: str | os.PathLike[str], mode: str = "read", format: str | None = None) -> str:
    """The format name that reads (``mode="read"``) or writes (``"write"``) ``path``.

    ``format`` (a :data:`FORMATS` name) forces one; otherwise the suffix decides, and among several readers of
    one suffix the one whose ``sniff`` accepts the file's first characters.
    """
    function = "read" if mode == "read" else "write"
    suffix = Path(path).suffix.lower()
    if format is not None:
        module = format_module(format)
        if not hasattr(module, function):
            raise InvalidValueError("--format", format, f"a format that can {function} ({', '.join(_can(function))})")
        return format
    candidates = _formats_with(suffix, function)
    if not candidates:
        kind = "input" if mode == "read" else "output"
        known = sorted(readable_suffixes() if mode == "read" else writable_suffixes())
        raise UnknownNameError(f"{kind} file suffix", suffix or str(path), tuple(known))
    if len(candidates) == 1 or mode != "read":
        return candidates[0]
    return _sniff(_head(path), candidates, Path(path).name)


def _sniff(head: str, candidates: list[str], name: str) -> str:
    """The candidate whose ``sniff`` accepts ``head``; none raises naming what each format starts with."""
    for candidate in candidates:
        sniff = getattr(format_module(candidate), "sniff", None)
        if sniff is not None and sniff(head):
            return candidate
    hints = "; ".join(f"{c}: {getattr(format_module(c), 'HEADER_HINT', '?')}" for c in candidates)
    first = head.lstrip().split("\n", 1)[0][:60]
    raise InvalidValueError(f"{name} line 1", first, f"the header of a format mien reads ({hints})")


def _can(function: str) -> list[str]:
    return [name for name in FORMATS if hasattr(format_module(name), function)]


def reader_for(path: str | os.PathLike[str], format: str | None = None) -> Callable[..., Any]:
    """The ``read(source) -> Clip`` function for ``path`` (see :func:`format_for`).

    When several formats read the suffix and ``path`` does not exist yet, the function returned sniffs the
    source it is given (a path or a binary stream) when called.
    """
    suffix = Path(path).suffix.lower()
    if format is None and not Path(path).is_file() and len(_formats_with(suffix, "read")) > 1:
        return _sniffing_reader(suffix)
    return getattr(format_module(format_for(path, "read", format)), "read")  # noqa: B009


def _sniffing_reader(suffix: str) -> Callable[..., Any]:
    def read(source: Any) -> Any:
        import io

        if isinstance(source, (str, os.PathLike)):
            return reader_for(source)(source)
        data = read_bytes(source)
        head = data[:_SNIFF_CHARACTERS].decode("utf-8-sig", errors="replace")
        stream = io.BytesIO(data)
        stream.name = getattr(source, "name", "<stream>")
        chosen = _sniff(head, _formats_with(suffix, "read"), source_name(stream))
        return format_module(chosen).read(stream)

    return read


def writer_for(path: str | os.PathLike[str], format: str | None = None) -> Callable[..., Any]:
    """The ``write(clip, target, rig=None, ...)`` function for ``path`` (see :func:`format_for`)."""
    return getattr(format_module(format_for(path, "write", format)), "write")  # noqa: B009


def __getattr__(name: str) -> dict[str, tuple[str, ...]]:
    """``READERS`` / ``WRITERS``: suffix -> names of the formats that read / write it (computed on use)."""
    if name in ("READERS", "WRITERS"):
        function = "read" if name == "READERS" else "write"
        suffixes = readable_suffixes() if function == "read" else writable_suffixes()
        return {suffix: tuple(_formats_with(suffix, function)) for suffix in sorted(suffixes)}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def read_clip(path: str | os.PathLike[str], format: str | None = None) -> Any:
    """Read the clip in ``path`` with the reader :func:`reader_for` picks."""
    return reader_for(path, format)(path)
