"""Clips as JSON: ``{"fps": ..., "channels": [...], "values": [[...], ...]}`` (:meth:`Clip.to_json`)."""

from __future__ import annotations

import json

from mien.errors import InvalidValueError
from mien.facs.clip import Clip
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, TargetT, read_text, refuse_rig, source_name, write_text

__all__ = ["SUFFIXES", "read", "write"]

SUFFIXES: tuple[str, ...] = (".json",)
"""File suffixes of this format."""


def write(clip: Clip, target: TargetT, rig: object = None) -> TargetT:
    """Write ``clip`` as JSON to ``target`` (a path, written atomically, or a binary stream)."""
    refuse_rig(rig, ".json")
    write_text(clip.to_json(), target)
    return target


def read(source: Source) -> Clip:
    """Read a clip written by :func:`write`; bad JSON raises naming the file, line and column."""
    name = source_name(source)
    text = read_text(source)
    # every value but one follows a comma: a bound known before json builds a Python float per value
    check_count(name, "commas (one per value)", text.count(","), current().clip_values)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InvalidValueError(f"{name} line {exc.lineno} column {exc.colno}", exc.msg, "valid JSON") from None
    if not isinstance(data, dict) or not {"fps", "channels", "values"} <= set(data):
        keys = sorted(data) if isinstance(data, dict) else type(data).__name__
        raise InvalidValueError(f"{name}", keys, 'an object with "fps", "channels" and "values"')
    try:
        return Clip.from_dict(data)
    except (TypeError, ValueError) as exc:
        if isinstance(exc, InvalidValueError):
            raise InvalidValueError(f"{name} {exc.field}", exc.value, exc.expected) from None
        raise InvalidValueError(f"{name}", str(exc), "numeric values, one row per frame") from None
