"""Where format modules read from and write to: a path or an open binary stream, one way for every format.

A *source* is a path (``str`` or :class:`os.PathLike`) or a binary stream with ``read()``; a *target* is a path or
a binary stream with ``write()``. Writing to a path is atomic (a temporary file in the same folder, then a
rename), so a reader never sees half a file and a failed write leaves the old file in place. Every atomic write
of mien goes through :func:`atomic_path` (for libraries that write by path: PIL, matplotlib, ffmpeg, numpy) or
:func:`atomic_open` (a stream); the temporary file is ``.<stem>.<random>.tmp<suffix>`` next to the target, so
a library that picks the format by suffix still sees it.

>>> import io
>>> buffer = io.BytesIO()
>>> write_bytes(b"abc", buffer) is None, buffer.getvalue()
(True, b'abc')
>>> read_bytes(io.BytesIO(b"xyz"))
b'xyz'
"""

from __future__ import annotations

import os
import secrets
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, TypeVar, Union

from mien.errors import InvalidValueError, MissingAssetError

__all__ = [
    "Source",
    "Target",
    "TargetT",
    "atomic_open",
    "atomic_path",
    "read_bytes",
    "read_text",
    "refuse_rig",
    "source_name",
    "temporary_path",
    "write_bytes",
    "write_text",
]

Source = Union[str, "os.PathLike[str]", IO[bytes]]
"""A path or a readable binary stream."""

Target = Union[str, "os.PathLike[str]", IO[bytes]]
"""A path or a writable binary stream."""

TargetT = TypeVar("TargetT", bound=Target)
"""A writer's target type: writers return the target they were given."""


def source_name(source: Source | Target) -> str:
    """A name for messages: the file name of a path, the stream's ``name`` or ``"<stream>"``."""
    if isinstance(source, (str, os.PathLike)):
        return Path(source).name
    name = getattr(source, "name", None)
    return Path(name).name if isinstance(name, str) else "<stream>"


def read_bytes(source: Source) -> bytes:
    """All bytes of ``source``; a missing file raises :class:`MissingAssetError` naming it."""
    if isinstance(source, (str, os.PathLike)):
        path = Path(source)
        if not path.is_file():
            raise MissingAssetError(f"{path}: no such file; check the path")
        return path.read_bytes()
    data = source.read()
    if not isinstance(data, bytes):
        raise InvalidValueError("source", type(source).__name__, "a path or a binary stream (open(..., 'rb'))")
    return data


def read_text(source: Source) -> str:
    """``source`` decoded as UTF-8 (a byte-order mark is dropped); bad bytes raise naming the file."""
    data = read_bytes(source)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        where = f"{source_name(source)} byte {exc.start}"
        raise InvalidValueError(where, data[exc.start : exc.start + 4], "UTF-8 text") from None


def write_bytes(data: bytes, target: Target) -> Path | None:
    """Write ``data`` to ``target``: atomically to a path (returned), or into a stream (returns None)."""
    if not isinstance(target, (str, os.PathLike)):
        target.write(data)
        return None
    path = Path(target)
    if path.parent and not path.parent.is_dir():
        raise InvalidValueError("output", str(path), "a path in an existing folder")
    with atomic_open(path) as stream:
        stream.write(data)
    return path


_NEW_FILE_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)


def temporary_path(path: str | os.PathLike[str]) -> Path:
    """A new empty file ``.<stem>.<random>.tmp<suffix>`` in ``path``'s folder (which must exist): where an
    atomic write of ``path`` goes before its rename.

    Its permissions follow the user's umask as a plain ``open(path, "w")`` would (``0o666 & ~umask``, so
    ``0644`` under the usual umask ``022``), not :func:`tempfile.mkstemp`'s private ``0600``: the file becomes
    the output, and an output replacing a ``0644`` file stays ``0644``.

    >>> temporary = temporary_path(Path(tempfile.mkdtemp()) / "take.csv")
    >>> temporary.name.startswith(".take.") and temporary.name.endswith(".tmp.csv"), temporary.stat().st_size
    (True, 0)
    """
    path = Path(path)
    for _ in range(tempfile.TMP_MAX):
        temporary = path.with_name(f".{path.stem}.{secrets.token_hex(4)}.tmp{path.suffix}")
        try:
            # 0o666 and the kernel applies the umask (and a folder's default ACL): no process-wide os.umask() call.
            handle = os.open(temporary, _NEW_FILE_FLAGS, 0o666)
        except FileExistsError:
            continue
        os.close(handle)
        return temporary
    raise FileExistsError(f"{path.parent}: no free temporary name for {path.name}")


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path (see :func:`temporary_path`) to write ``path``'s content to; a clean exit renames it
    onto ``path`` (replacing any old file), an exception removes it and leaves ``path`` as it was.

    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> with atomic_path(folder / "a.txt") as temporary:
    ...     _ = temporary.write_text("done")
    >>> (folder / "a.txt").read_text(), sorted(p.name for p in folder.iterdir())
    ('done', ['a.txt'])
    """
    temporary = temporary_path(path)
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_open(path: str | os.PathLike[str]) -> Iterator[IO[bytes]]:
    """Yield a binary stream whose bytes become ``path`` atomically on a clean exit (see :func:`atomic_path`)."""
    with atomic_path(path) as temporary, open(temporary, "wb") as stream:
        yield stream


def write_text(text: str, target: Target) -> Path | None:
    """Write ``text`` as UTF-8 to ``target`` (see :func:`write_bytes`)."""
    return write_bytes(text.encode("utf-8"), target)


def refuse_rig(rig: object, suffix: str) -> None:
    """Raise when a ``rig`` is given to a format that carries no geometry (``suffix`` names the format)."""
    if rig is not None:
        raise InvalidValueError("head", getattr(rig, "name", rig), f"no head for {suffix} (only .glb carries a mesh)")
