"""How much a file may decode to: the readers check what a file declares (rows, members, accessor counts)
against these limits *before* they allocate, so a small file cannot make mien take gigabytes.

A 1 MB ``.npz`` of zeros unpacks to 1 GiB and a 476-byte ``.glb`` can declare 10^8 keys: both are refused with
an :class:`~mien.errors.InvalidValueError` naming the file and the count. The defaults fit any real clip (an
hour of 62 channels at 1000 fps stays under them); a server lowers them for uploads with :func:`decode_limits`.

>>> current().clip_values
33554432
>>> with decode_limits(clip_values=100):
...     try:
...         check_count("take.csv", "values (frames x channels)", 120, current().clip_values)
...     except InvalidValueError as exc:
...         print(exc.field, "|", exc.value, "|", exc.expected)
take.csv size | 120 values (frames x channels) | at most 100 (the decode limit of mien.fileio.limits)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

from mien.errors import InvalidValueError

__all__ = ["DecodeLimits", "check_count", "current", "decode_limits"]


@dataclass(frozen=True)
class DecodeLimits:
    """Upper bounds on what one file may decode to."""

    clip_values: int = 2**25
    """Numbers a clip file may hold, frames x channels (2^25 float64 = 256 MiB)."""
    zip_members: int = 64
    """Members of a zip container (``.npz``)."""
    zip_bytes: int = 2**30
    """Bytes all the arrays of a zip container unpack to together, as their headers declare them."""
    accessor_components: int = 2**25
    """Numbers one glTF accessor may hold, count x components (2^25 float32 = 128 MiB)."""


_DEFAULT = DecodeLimits()
_LIMITS: ContextVar[DecodeLimits] = ContextVar("mien_decode_limits", default=_DEFAULT)  # frozen: safe to share


def current() -> DecodeLimits:
    """The limits in force (the defaults unless inside :func:`decode_limits`)."""
    return _LIMITS.get()


@contextmanager
def decode_limits(**changes: int) -> Iterator[DecodeLimits]:
    """Lower (or raise) some limits for the readers called inside the ``with`` block (this thread or task).

    ``changes`` are :class:`DecodeLimits` fields, e.g. ``decode_limits(clip_values=2**22)``.
    """
    for name, value in changes.items():
        if not isinstance(value, int) or isinstance(value, bool) or value < 0:
            raise InvalidValueError(name, value, "a count >= 0")
    limits = dataclasses.replace(_LIMITS.get(), **changes)
    token = _LIMITS.set(limits)
    try:
        yield limits
    finally:
        _LIMITS.reset(token)


def check_count(name: str, what: str, count: int, limit: int) -> None:
    """Raise naming ``name`` (the file and place) when ``count`` ``what`` exceed ``limit``."""
    if count > limit:
        raise InvalidValueError(f"{name} size", f"{count} {what}", f"at most {limit} (the decode limit of {__name__})")
