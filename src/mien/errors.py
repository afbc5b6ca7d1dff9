"""Typed errors raised by mien.

Every error that comes from bad input names the offending field and value, so a user (or a server log)
can see exactly what was rejected. All of them derive from :class:`MienError`.
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "InvalidValueError",
    "MienError",
    "MissingAssetError",
    "MissingExtraError",
    "UnknownNameError",
]


class MienError(Exception):
    """Base class of every error mien raises on purpose."""


class InvalidValueError(MienError, ValueError):
    """A value is out of range, not finite, or has the wrong shape.

    ``field`` names the input (``"intensity"``, ``"onset_s"``, ``"pleasure"``...) and ``value`` is what
    was given.
    """

    def __init__(self, field: str, value: Any, expected: str) -> None:
        self.field = field
        self.value = value
        self.expected = expected
        super().__init__(f"{field}={value!r} is invalid: expected {expected}")


class UnknownNameError(MienError, KeyError):
    """A name (action unit, emotion, blendshape, laugh type...) is not known.

    ``kind`` says what kind of name it is and ``known`` lists (some of) the valid ones.
    """

    def __init__(self, kind: str, name: Any, known: tuple[str, ...] = ()) -> None:
        self.kind = kind
        self.name = name
        self.known = known
        hint = ""
        if known:
            shown = ", ".join(known[:30]) + (", ..." if len(known) > 30 else "")
            hint = f"; known: {shown}"
        super().__init__(f"unknown {kind} {name!r}{hint}")

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0])


class MissingAssetError(MienError, FileNotFoundError):
    """An asset file or folder (a head, a model) is missing or incomplete; says where to get it."""


class MissingExtraError(MienError, ImportError):
    """An optional dependency is not installed; says which ``pip install 'mien[extra]'`` fixes it."""

    def __init__(self, module: str, extra: str) -> None:
        self.module = module
        self.extra = extra
        super().__init__(f"{module} is needed for this; install it with: pip install 'mien[{extra}]'")
