"""Heads a user brings: instrumenting a mesh nobody measured (landmarks, size, axes, unit), placing it in
mien's frame, and :func:`load_head`, the one door every job loads its head through."""

from mien.heads.registry import load_head

__all__ = ["load_head"]
