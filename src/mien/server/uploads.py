"""Clip uploads (``POST /api/characters/{id}/clip``): read in a worker process, never on the event loop.

Reading a file is slow (a 26 MB CSV takes seconds of Python) and a hostile file may ask for gigabytes, so the
server's loop, which runs the clock, does none of it:

- the body is read while it streams, up to :data:`MAX_CLIP_BYTES` (413 as soon as it passes) and within
  :data:`BODY_TIMEOUT_S` (408);
- at most :data:`MAX_PARALLEL_UPLOADS` are read at once (503 with ``Retry-After`` beyond: a burst of uploads
  cannot fill the server's memory with bodies);
- the reader runs in a fresh worker process (``python -m mien.server.uploads``, its bytes on stdin) under
  :data:`UPLOAD_LIMITS` (what a file may decode to, checked before allocating; see :mod:`mien.fileio.limits`),
  with its address space capped at :data:`WORKER_MEMORY_BYTES` more than it starts with and a time limit of
  :data:`PARSE_TIMEOUT_S` (the worker is killed after it). Only the clip's channels, rate and float64 values come
  back (a JSON line and raw bytes; no pickle).
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import os
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.exchange import readable_suffixes, reader_for
from mien.facs.clip import Clip
from mien.fileio.limits import decode_limits

__all__ = [
    "BODY_TIMEOUT_S",
    "MAX_CLIP_BYTES",
    "MAX_PARALLEL_UPLOADS",
    "PARSE_TIMEOUT_S",
    "UPLOAD_LIMITS",
    "WORKER_MEMORY_BYTES",
    "Uploads",
    "UploadsBusy",
    "check_suffix",
    "parse_clip",
    "parse_in_worker",
    "worker_main",
]

MAX_CLIP_BYTES = 32 * 1024 * 1024
"""Largest clip upload, bytes."""

BODY_TIMEOUT_S = 30.0
"""Seconds a client has to send a whole clip (32 MiB at 10 Mbit/s takes 27 s)."""

PARSE_TIMEOUT_S = 20.0
"""Seconds the worker may read one clip before it is killed."""

MAX_PARALLEL_UPLOADS = 2
"""Uploads read at once; more get 503."""

UPLOAD_LIMITS: dict[str, int] = {
    "clip_values": 2**22,
    "zip_members": 8,
    "zip_bytes": 2**26,
    "accessor_components": 2**22,
}
"""What an uploaded file may decode to (:class:`mien.fileio.limits.DecodeLimits` fields): 2^22 values is 32 MiB
of float64, 18 minutes of every face channel at 60 fps."""

WORKER_MEMORY_BYTES = 2**30
"""Address space the worker may add to what it starts with, bytes."""


class UploadsBusy(MienError):
    """Too many uploads are being read (the server answers 503 with ``Retry-After``)."""


def check_suffix(suffix: str) -> None:
    """Raise :class:`~mien.errors.InvalidValueError` unless some format reads ``suffix`` (``.csv``, ``.npz``...)."""

    if not suffix.startswith(".") or "/" in suffix or len(suffix) > 16:
        raise InvalidValueError("suffix", suffix, "a file suffix such as .json or .npz")
    if suffix.lower() not in readable_suffixes():
        known = ", ".join(sorted(readable_suffixes()))
        raise InvalidValueError("suffix", suffix, f"a clip format mien reads ({known})")


def parse_clip(data: bytes, suffix: str) -> Clip:
    """The clip in ``data``, read by the reader of ``suffix`` (in this process; the server calls it in a worker)."""

    check_suffix(suffix)
    try:
        # a path that is never a file, so that a suffix shared by several formats sniffs the uploaded bytes,
        # not a file of that name in the server's folder
        reader = reader_for(Path(os.devnull) / f"clip{suffix.lower()}")
    except ImportError as exc:
        raise InvalidValueError("suffix", suffix, f"a clip format this install can read ({exc})") from None
    stream = io.BytesIO(data)
    stream.name = f"uploaded clip{suffix}"
    try:
        clip = reader(stream)
    except MienError:
        raise
    except MemoryError:
        raise  # the worker says how much memory it had
    except Exception as exc:  # a reader's own parse error on garbage bytes
        raise InvalidValueError("clip", f"{len(data)} bytes", f"a readable {suffix} clip ({exc})") from None
    if not isinstance(clip, Clip):
        raise InvalidValueError("clip", type(clip).__name__, "a clip file")
    return clip


def _limit_memory(extra_bytes: int) -> None:
    """Cap this process's address space at what it has now plus ``extra_bytes`` (Linux; elsewhere nothing)."""
    try:
        import resource

        with open("/proc/self/statm") as statm:
            now = int(statm.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
        _, hard = resource.getrlimit(resource.RLIMIT_AS)
        limit = now + extra_bytes if hard == resource.RLIM_INFINITY else min(hard, now + extra_bytes)
        resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    except (ImportError, OSError, ValueError):
        pass


def _answer(clip: Clip | None, error: str = "") -> bytes:
    """The worker's reply: a JSON line, then the clip's float64 values (no pickle: the parent trusts no bytes)."""
    if clip is None:
        return json.dumps({"error": error}).encode() + b"\n"
    values = np.ascontiguousarray(clip.values, dtype="<f8")
    head = {"fps": clip.fps, "channels": list(clip.channels), "shape": list(values.shape)}
    return json.dumps(head).encode() + b"\n" + values.tobytes()


def _clip_of(reply: bytes, size: int) -> Clip:
    """The clip in a worker's reply (:func:`_answer`), or the worker's error raised."""
    line, _, data = reply.partition(b"\n")
    try:
        head = json.loads(line)
    except ValueError:
        raise InvalidValueError("clip", f"{size} bytes", "a clip the upload worker can read") from None
    if "error" in head:
        raise MienError(str(head["error"]))
    rows, columns = (int(n) for n in head["shape"])
    if len(data) != rows * columns * 8:
        raise InvalidValueError("clip", f"{size} bytes", "a clip the upload worker can read")
    values = np.frombuffer(data, dtype="<f8").reshape(rows, columns)
    return Clip(values.astype(np.float64), float(head["fps"]), tuple(str(c) for c in head["channels"]))


def worker_main(argv: list[str]) -> int:
    """``python -m mien.server.uploads SUFFIX LIMITS_JSON MEMORY_BYTES``: the clip's bytes on stdin, the reply
    (:func:`_answer`) on stdout."""
    suffix, limits, memory_bytes = argv[0], json.loads(argv[1]), int(argv[2])
    _limit_memory(memory_bytes)
    warnings.simplefilter("ignore")  # a reader's warning (skipped columns) is no failure here
    data = sys.stdin.buffer.read()
    try:
        with decode_limits(**limits):
            reply = _answer(parse_clip(data, suffix))
    except MienError as exc:
        reply = _answer(None, str(exc))
    except MemoryError:
        reply = _answer(None, f"clip of {len(data)} bytes needs more than the upload's {memory_bytes >> 20} MiB")
    except Exception as exc:  # never leave the server waiting on a silent worker
        reply = _answer(None, f"clip of {len(data)} bytes could not be read ({type(exc).__name__}: {exc})"[:300])
    sys.stdout.buffer.write(reply)
    sys.stdout.buffer.flush()
    return 0


async def parse_in_worker(
    data: bytes,
    suffix: str,
    timeout_s: float = PARSE_TIMEOUT_S,
    limits: dict[str, int] | None = None,
    memory_bytes: int = WORKER_MEMORY_BYTES,
) -> Clip:
    """:func:`parse_clip` in a fresh worker process (``python -m mien.server.uploads``) under ``limits``
    (default :data:`UPLOAD_LIMITS`), killed after ``timeout_s`` seconds; the event loop only waits on its pipes."""
    check_suffix(suffix)
    chosen = UPLOAD_LIMITS if limits is None else limits
    process = await asyncio.create_subprocess_exec(
        sys.executable, "-m", __name__, suffix, json.dumps(chosen), str(memory_bytes),
        stdin=asyncio.subprocess.PIPE, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.DEVNULL,
    )  # fmt: skip
    try:
        reply, _ = await asyncio.wait_for(process.communicate(data), timeout_s)
    except TimeoutError:
        raise InvalidValueError("clip", f"{len(data)} bytes", f"a clip the server reads in {timeout_s:g} s") from None
    finally:
        if process.returncode is None:
            process.kill()
            await process.wait()
    if not reply:
        raise InvalidValueError("clip", f"{len(data)} bytes", f"a clip readable within {memory_bytes >> 20} MiB")
    return _clip_of(reply, len(data))


class Uploads:
    """The uploads of one server: how many are being read, and reading one (see the module doc)."""

    def __init__(
        self, parallel: int = MAX_PARALLEL_UPLOADS, timeout_s: float = PARSE_TIMEOUT_S,
        limits: dict[str, int] | None = None,
    ) -> None:  # fmt: skip
        self.parallel = parallel
        """Uploads read at once."""
        self.timeout_s = timeout_s
        """Seconds a worker may read one clip."""
        self.limits = dict(UPLOAD_LIMITS if limits is None else limits)
        """What a file may decode to."""
        self.active = 0
        """Uploads being received or read now."""

    @contextlib.contextmanager
    def slot(self) -> Iterator[None]:
        """Hold one of the :attr:`parallel` places (raises :class:`UploadsBusy` when none is free)."""
        if self.active >= self.parallel:
            raise UploadsBusy(f"{self.active} clip uploads are being read; retry in a moment")
        self.active += 1
        try:
            yield
        finally:
            self.active -= 1

    async def read(self, data: bytes, suffix: str) -> Clip:
        """The clip in ``data``, read in a worker process (the event loop only waits)."""
        return await parse_in_worker(data, suffix, self.timeout_s, self.limits)


if __name__ == "__main__":
    sys.exit(worker_main(sys.argv[1:]))
