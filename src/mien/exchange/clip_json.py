"""Clips as JSON: ``{"fps": ..., "channels": [...], "values": [[...], ...]}``."""

from __future__ import annotations

from pathlib import Path

from mien.facs.clip import Clip

__all__ = ["read", "write"]


def write(clip: Clip, path: str | Path) -> Path:
    """Write ``clip`` as JSON (:meth:`Clip.to_json`)."""
    path = Path(path)
    path.write_text(clip.to_json(), encoding="utf-8")
    return path


def read(path: str | Path) -> Clip:
    """Read a clip written by :func:`write`."""
    return Clip.from_json(Path(path).read_text(encoding="utf-8"))
