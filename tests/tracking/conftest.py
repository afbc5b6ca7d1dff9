"""Fixtures for the tracking tests: the shared videos and image, tracked once per module."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest


@pytest.fixture(scope="session")
def single_face_video(shared_data: Path) -> Path:
    """2.4 s, 30 fps, 640x360: a person breaking into a smile."""
    return shared_data / "video" / "single_face.mp4"


@pytest.fixture(scope="session")
def single_face_rgb(shared_data: Path) -> np.ndarray:
    """The shared single-face photo as an (h, w, 3) uint8 RGB array."""
    from PIL import Image

    with Image.open(shared_data / "images" / "single_face.jpg") as image:
        return np.asarray(image.convert("RGB")).copy()
