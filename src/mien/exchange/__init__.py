"""File formats, one module per format, each registered in :data:`WRITERS` / :data:`READERS` by suffix.

A writer is ``write(clip_or_curves, path, **options)``; a reader is ``read(path) -> object``. Modules are
imported lazily, so a format's optional dependency is needed only when that format is used.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from mien.errors import UnknownNameError

__all__ = ["READERS", "WRITERS", "reader_for", "writer_for"]

WRITERS: dict[str, str] = {
    ".csv": "mien.exchange.curves_csv:write",
    ".json": "mien.exchange.clip_json:write",
    ".npz": "mien.exchange.clip_npz:write",
    ".anim": "mien.exchange.maya_anim:write",
}
"""Suffix -> ``"module:function"`` of the writer."""

READERS: dict[str, str] = {
    ".csv": "mien.exchange.curves_csv:read",
    ".json": "mien.exchange.clip_json:read",
    ".npz": "mien.exchange.clip_npz:read",
    ".anim": "mien.exchange.maya_anim:read",
}
"""Suffix -> ``"module:function"`` of the reader."""


def _resolve(table: dict[str, str], path: str | Path, kind: str) -> Callable[..., Any]:
    suffix = Path(path).suffix.lower()
    if suffix not in table:
        raise UnknownNameError(f"{kind} file format", suffix or str(path), tuple(table))
    module_name, function = table[suffix].split(":")
    return getattr(importlib.import_module(module_name), function)


def writer_for(path: str | Path) -> Callable[..., Any]:
    """The writer function for ``path``'s suffix."""
    return _resolve(WRITERS, path, "output")


def reader_for(path: str | Path) -> Callable[..., Any]:
    """The reader function for ``path``'s suffix."""
    return _resolve(READERS, path, "input")
