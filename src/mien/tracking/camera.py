"""Cameras: a video device (``/dev/video0``, ``camera:0``) -> RGB frames stamped with their arrival time.

PyAV (FFmpeg) reads the device: ``v4l2`` on Linux, ``avfoundation`` on macOS, ``dshow`` on Windows. A device that
does not exist, is busy (another program holds it) or is no camera raises one
:class:`~mien.errors.InvalidValueError` naming the device and what to do, at open time: ``mien serve --capture``
checks the camera before the server starts.
"""

from __future__ import annotations

import errno
import glob
import sys
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require

__all__ = ["CAMERA_PREFIX", "camera_device", "check_camera", "iter_camera"]

CAMERA_PREFIX = "camera:"
"""``camera:N`` names the N-th camera (``/dev/videoN`` on Linux)."""


def camera_device(text: str) -> str | None:
    """The device ``text`` names (``camera:0`` -> ``/dev/video0`` on Linux, ``/dev/video2`` as is), or None when
    it names no camera (a video file).

    >>> camera_device("camera:1") if sys.platform == "linux" else "/dev/video1"
    '/dev/video1'
    >>> camera_device("smile.mp4") is None
    True
    """
    if text.startswith(CAMERA_PREFIX):
        index = text[len(CAMERA_PREFIX) :]
        if not index.isdigit():
            raise InvalidValueError("camera", text, "camera:N with N a camera number (camera:0)")
        return f"/dev/video{int(index)}" if sys.platform.startswith("linux") else index
    if text.startswith("/dev/"):
        return text
    return None


def _input_format() -> str:
    if sys.platform == "darwin":
        return "avfoundation"
    if sys.platform == "win32":
        return "dshow"
    return "v4l2"


def _cameras_here() -> str:
    found = sorted(glob.glob("/dev/video*"))
    return f"cameras here: {', '.join(found)}" if found else "this machine shows no camera (/dev/video*)"


def _open(device: str) -> Any:
    av = require("av", "track")
    options = {"framerate": "30"}
    name = f"video={device}" if _input_format() == "dshow" else device
    try:
        return av.open(name, format=_input_format(), options=options, timeout=5.0)
    except (av.FFmpegError, OSError) as exc:
        code = getattr(exc, "errno", None)
        if code == errno.ENOENT:
            raise InvalidValueError("camera", device, f"an existing camera device ({_cameras_here()})") from None
        if code == errno.EBUSY:
            raise InvalidValueError(
                "camera", device, "a camera no other program is using (it is busy: close the program holding it)"
            ) from None
        reason = getattr(exc, "strerror", None) or str(exc)
        raise InvalidValueError("camera", device, f"a camera device ({reason}; {_cameras_here()})") from None


def check_camera(device: str) -> None:
    """Open ``device`` and close it again: raises :class:`InvalidValueError` naming it when it does not exist, is
    busy or is no camera."""
    _open(device).close()


def iter_camera(device: str) -> Iterator[tuple[float, np.ndarray]]:
    """Yield ``(arrival_s, rgb)`` for each frame of ``device`` until closed: ``arrival_s`` is ``time.monotonic()``
    when the frame was read, ``rgb`` an (height, width, 3) uint8 array. Raises :class:`InvalidValueError` when it
    cannot be opened or stops delivering (unplugged)."""
    av = require("av", "track")
    container = _open(device)
    try:
        stream = container.streams.video[0]
        try:
            for frame in container.decode(stream):
                arrival_s = time.monotonic()
                yield arrival_s, frame.to_ndarray(format="rgb24")
        except (av.FFmpegError, OSError) as exc:
            raise InvalidValueError("camera", device, f"a camera that keeps delivering frames ({exc})") from None
    finally:
        container.close()
