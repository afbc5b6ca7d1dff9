"""The one set of argument checks every ``mien`` subcommand uses: the CLI contract.

A user's mistake never ends in a traceback: it ends with exit code 2 and one line that names the value and
says what to do. The rules, the same in every command:

* **Numbers.** Frame rates and durations are finite and > 0 (:func:`positive_fps`, :func:`positive_seconds`);
  onsets, holds and start times are finite and >= 0 (:func:`non_negative_seconds`).
* **Input files** must exist and not be empty; a typo gets a "did you mean" from the folder's own files
  (:func:`input_file`, :func:`input_folder`).
* **Output paths**: missing output folders are **created**, in every command, once all arguments have
  parsed (:func:`prepare_outputs`). A destination that is an existing folder where a file is needed, that
  lies under a file, or that cannot be written is refused (:func:`output_file`, :func:`output_folder`).
* **Request size**: a request that would hold more than :data:`DEFAULT_REQUEST_LIMIT_BYTES` (2 GiB) of
  samples or frames in memory is refused naming the limit; ``MIEN_MAX_REQUEST_BYTES`` (bytes, or with a
  unit: ``8GiB``, ``500MB``) raises or lowers it (:func:`check_request_size`).
* **Dask scheduler** addresses are connected to with a short timeout before any work starts
  (:func:`check_scheduler`).
* **Options that do not apply** to an input are refused, not ignored (:func:`refuse_option`).

The ``type=`` functions raise :class:`argparse.ArgumentTypeError` (argparse turns it into the one-line usage
error, exit 2); the ``check_*`` functions raise :class:`~mien.errors.InvalidValueError` (``mien.cli`` turns
it into exit 2).
"""

from __future__ import annotations

import argparse
import difflib
import math
import os
import re
import socket
import tempfile
from pathlib import Path

from mien.errors import InvalidValueError

__all__ = [
    "DEFAULT_REQUEST_LIMIT_BYTES",
    "PENDING_OUTPUTS",
    "REQUEST_LIMIT_ENV",
    "check_curve_request",
    "check_request_size",
    "check_scheduler",
    "did_you_mean",
    "input_file",
    "input_folder",
    "missing_file_message",
    "non_negative_seconds",
    "output_file",
    "output_folder",
    "output_target",
    "parse_bytes",
    "positive_fps",
    "positive_seconds",
    "prepare_outputs",
    "refuse_option",
    "request_limit_bytes",
]

DEFAULT_REQUEST_LIMIT_BYTES = 2 * 1024**3
"""Largest request (samples or frames held in memory), bytes: 2 GiB."""

REQUEST_LIMIT_ENV = "MIEN_MAX_REQUEST_BYTES"
"""Environment variable that overrides :data:`DEFAULT_REQUEST_LIMIT_BYTES`."""

SCHEDULER_TIMEOUT_S = 3.0
"""Seconds to wait for a Dask scheduler to accept a connection."""


# ------------------------------------------------------------------------------------------------ numbers


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number: give {what}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not finite: give {what}")
    return value


def positive_fps(text: str) -> float:
    """argparse type: a frame rate, frames per second, finite and > 0.

    >>> positive_fps("30")
    30.0
    """
    value = _number(text, "a frame rate > 0 (frames per second), e.g. 30")
    if value <= 0:
        raise argparse.ArgumentTypeError(f"fps {text!r} must be > 0 (frames per second), e.g. 30")
    return value


def positive_seconds(text: str) -> float:
    """argparse type: a duration in seconds, finite and > 0.

    >>> positive_seconds("2.5")
    2.5
    """
    value = _number(text, "a duration > 0 in seconds, e.g. 2")
    if value <= 0:
        raise argparse.ArgumentTypeError(f"duration {text!r} must be > 0 seconds, e.g. 2")
    return value


def non_negative_seconds(text: str) -> float:
    """argparse type: a time or span in seconds, finite and >= 0 (onset, hold, start...).

    >>> non_negative_seconds("0")
    0.0
    """
    value = _number(text, "a time >= 0 in seconds")
    if value < 0:
        raise argparse.ArgumentTypeError(f"seconds {text!r} must be >= 0")
    return value


# ------------------------------------------------------------------------------------------------ inputs


def did_you_mean(path: Path) -> str | None:
    """The closest existing name in ``path``'s folder (or its closest existing ancestor), or None."""
    folder = path.parent
    wanted = path.name
    while not folder.is_dir():  # a typo in a folder name: suggest from the nearest folder that exists
        if folder.parent == folder:
            return None
        wanted, folder = folder.name, folder.parent
    try:
        names = sorted(entry.name for entry in os.scandir(folder))[:5000]
    except OSError:
        return None
    close = difflib.get_close_matches(wanted, names, n=1, cutoff=0.6)
    return str(folder / close[0]) if close else None


def missing_file_message(path: Path, what: str = "file") -> str:
    """``"no such file: X (did you mean Y?)"``: the message for a missing input."""
    suggestion = did_you_mean(path)
    hint = f"; did you mean {suggestion}?" if suggestion else "; check the name and folder"
    if not path.parent.is_dir():
        return f"no such {what}: {path} (folder {path.parent} does not exist{hint})"
    return f"no such {what}: {path}{hint}"


def input_file(text: str) -> Path:
    """argparse type: an existing, non-empty, readable file (a typo gets a "did you mean")."""
    path = Path(text).expanduser()
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder: give a file")
    if not path.is_file():
        raise argparse.ArgumentTypeError(missing_file_message(path))
    if not os.access(path, os.R_OK):
        raise argparse.ArgumentTypeError(f"{text} cannot be read (permission denied)")
    if path.stat().st_size == 0:
        raise argparse.ArgumentTypeError(f"{text} is empty (0 bytes): give a file with data")
    return path


def input_folder(text: str) -> Path:
    """argparse type: an existing folder (a typo gets a "did you mean")."""
    path = Path(text).expanduser()
    if path.is_file():
        raise argparse.ArgumentTypeError(f"{text} is a file: give a folder")
    if not path.is_dir():
        raise argparse.ArgumentTypeError(missing_file_message(path, "folder"))
    return path


# ------------------------------------------------------------------------------------------------ outputs


PENDING_OUTPUTS: list[tuple[Path, str]] = []
"""Output folders named by the arguments parsed so far, with the text the user gave: created (and proved
writable) by :func:`prepare_outputs` once every argument has parsed, so a usage error leaves no folder behind."""


def _check_folder_can_be_made(folder: Path, shown: str) -> None:
    """Refuse a folder under a regular file; note the folder for :func:`prepare_outputs`."""
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise argparse.ArgumentTypeError(f"{shown}: {existing} is a file, so no folder can be made under it")
    PENDING_OUTPUTS.append((folder, shown))


def prepare_outputs() -> None:
    """Create the output folders the parsed arguments name and prove each takes a file (``mien.cli`` calls this
    after parsing). Raises :class:`InvalidValueError` naming the path when one cannot be made or written."""
    while PENDING_OUTPUTS:
        folder, shown = PENDING_OUTPUTS.pop(0)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            with tempfile.TemporaryFile(dir=folder, prefix=".mien-write-test-"):
                pass
        except OSError as exc:
            reason = exc.strerror or str(exc)
            raise InvalidValueError(
                "output", shown, f"a place that can be written: cannot write in {folder} ({reason}); choose another"
            ) from None


def output_file(text: str) -> Path:
    """argparse type: a file to write. Missing folders are created; a folder or unwritable place is refused."""
    path = Path(text).expanduser()
    if not text or text.endswith(os.sep):
        raise argparse.ArgumentTypeError(f"{text!r} names a folder: give a file name")
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is an existing folder: give a file name inside it")
    _check_folder_can_be_made(path.parent, text)
    if path.exists() and not os.access(path, os.W_OK):
        raise argparse.ArgumentTypeError(f"{text} is read-only: choose another file")
    return path


def output_folder(text: str) -> Path:
    """argparse type: a folder to write into; created when missing. A file or unwritable place is refused."""
    path = Path(text).expanduser()
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file: give a folder")
    _check_folder_can_be_made(path, text)
    return path


# ------------------------------------------------------------------------------------------------ size


_UNITS = {"": 1, "b": 1, "kb": 1000, "mb": 1000**2, "gb": 1000**3, "tb": 1000**4,
          "kib": 1024, "mib": 1024**2, "gib": 1024**3, "tib": 1024**4}  # fmt: skip


def parse_bytes(text: str) -> int:
    """``"2GiB"``, ``"500MB"``, ``"1048576"`` -> bytes.

    >>> parse_bytes("2GiB")
    2147483648
    """
    match = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([kmgt]i?b|b)?\s*", text.lower())
    if not match:
        raise InvalidValueError(REQUEST_LIMIT_ENV, text, "a size in bytes, e.g. 4294967296, 4GiB or 500MB")
    value = float(match.group(1)) * _UNITS[match.group(2) or ""]
    if value <= 0:
        raise InvalidValueError(REQUEST_LIMIT_ENV, text, "a size > 0")
    return int(value)


def request_limit_bytes() -> int:
    """The request limit in bytes: ``$MIEN_MAX_REQUEST_BYTES`` or :data:`DEFAULT_REQUEST_LIMIT_BYTES`."""
    text = os.environ.get(REQUEST_LIMIT_ENV, "").strip()
    return parse_bytes(text) if text else DEFAULT_REQUEST_LIMIT_BYTES


def _size(n_bytes: float) -> str:
    return f"{n_bytes / 1024**3:.3g} GiB" if n_bytes >= 1024**3 else f"{n_bytes / 1024**2:.3g} MiB"


def check_request_size(what: str, n_frames: float, bytes_per_frame: float) -> None:
    """Refuse a request of ``n_frames`` frames of ``bytes_per_frame`` bytes over :func:`request_limit_bytes`.

    ``what`` describes the request for the message (``"--duration 1e6 at --fps 60"``).

    >>> check_request_size("2 s at 60 fps", 120, 8 * 100)
    """
    limit = request_limit_bytes()
    total = float(n_frames) * float(bytes_per_frame)
    if not math.isfinite(total) or total > limit:
        raise InvalidValueError(
            "request",
            what,
            f"at most {_size(limit)} in memory ({n_frames:.4g} frames x {bytes_per_frame:.4g} bytes = "
            f"{_size(total)}); ask for less, or raise the limit with {REQUEST_LIMIT_ENV}=8GiB",
        )


# ------------------------------------------------------------------------------------------------ dask


def check_scheduler(address: str, timeout_s: float = SCHEDULER_TIMEOUT_S) -> None:
    """Connect to a Dask scheduler ``address`` (``tcp://host:port`` or ``host:port``) before any work starts.

    Raises :class:`InvalidValueError` naming the address when it is malformed or nothing answers within
    ``timeout_s`` seconds.
    """
    match = re.fullmatch(r"(?:(tcp|tls)://)?\[?([^\]\s/]+?)\]?:([0-9]{1,5})/?", address.strip())
    if not match or not 0 < int(match.group(3)) < 65536:
        raise InvalidValueError("scheduler", address, "a Dask scheduler address such as tcp://127.0.0.1:8786")
    host, port = match.group(2), int(match.group(3))
    try:
        with socket.create_connection((host, port), timeout=timeout_s):
            pass
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise InvalidValueError(
            "scheduler",
            address,
            f"a reachable Dask scheduler ({reason}); start one with `dask scheduler` or leave --scheduler out",
        ) from None


# ------------------------------------------------------------------------------------------------ options


def refuse_option(option: str, value: object, reason: str) -> None:
    """Refuse an option that does not apply to this input (never silently ignore it)."""
    raise InvalidValueError(option, value, f"no {option}: {reason}")


def check_curve_request(duration_s: float, fps: float, n_channels: int) -> None:
    """Refuse curves of ``duration_s`` seconds at ``fps`` over ``n_channels`` float64 channels over the limit.

    >>> check_curve_request(2.0, 60.0, 80)
    """
    check_request_size(f"--duration {duration_s:g} s at --fps {fps:g}", math.ceil(duration_s * fps), 8.0 * n_channels)


def output_target(text: str) -> Path:
    """argparse type: a path with a suffix is a file to write (:func:`output_file`), one without a suffix a
    folder to write into (:func:`output_folder`), e.g. a folder of PNG frames."""
    return output_file(text) if Path(text).suffix else output_folder(text)
