"""Cameras: names, and the clear errors of a camera that is missing or is no camera (no camera exists here)."""

from __future__ import annotations

import sys

import pytest

from mien.errors import InvalidValueError
from mien.tracking.camera import camera_device, check_camera


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/dev/videoN names are Linux's")
def test_camera_names() -> None:
    assert camera_device("camera:2") == "/dev/video2" and camera_device("/dev/video0") == "/dev/video0"
    assert camera_device("clip.mp4") is None and camera_device("dev/video0") is None
    with pytest.raises(InvalidValueError, match="camera:N"):
        camera_device("camera:front")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="v4l2 devices")
@pytest.mark.parametrize(
    ("device", "words"),
    [("/dev/video97", "an existing camera device"), ("/dev/null", "a camera device (Inappropriate ioctl")],
)
def test_a_missing_device_or_no_camera_is_named(device: str, words: str) -> None:
    pytest.importorskip("av", reason="the track extra (PyAV) is not installed")
    with pytest.raises(InvalidValueError, match=r"camera='" + device) as error:
        check_camera(device)
    assert words in str(error.value)
