"""Shared pytest fixtures: where the shared assets and data are (skip with a reason when absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def shared_root() -> Path | None:
    """``$MIEN_SHARED`` or ``../shared`` beside the checkout, if it exists."""
    candidate = Path(os.environ.get("MIEN_SHARED", REPO.parent / "shared"))
    return candidate if candidate.is_dir() else None


def _point_assets_at_shared() -> None:
    """Default the asset variables to the shared folder, as .ci/run does, unless the user set them."""
    root = shared_root()
    if root is None:
        return
    defaults = {
        "MIEN_ICT_FACEKIT": root / "assets" / "ict-facekit",
        "MIEN_FACE_LANDMARKER": root / "models" / "face_landmarker.task",
        "MIEN_EMOTION_MODEL": root / "models" / "emotion" / "fer_emotion_model_quantized.tflite",
    }
    for variable, path in defaults.items():
        if variable not in os.environ and path.exists():
            os.environ[variable] = str(path)


_point_assets_at_shared()


def _shared(relative: str, what: str) -> Path:
    root = shared_root()
    if root is None or not (root / relative).exists():
        pytest.skip(f"{what} not available: set MIEN_SHARED to the shared folder (needs {relative})")
    return root / relative


@pytest.fixture(scope="session")
def ict_dir() -> Path:
    """The ICT-FaceKit folder (holds FaceXModel/)."""
    return _shared("assets/ict-facekit", "ICT-FaceKit")


@pytest.fixture(scope="session")
def landmarker_path() -> Path:
    """MediaPipe face_landmarker.task."""
    return _shared("models/face_landmarker.task", "MediaPipe Face Landmarker model")


@pytest.fixture(scope="session")
def emotion_model_path() -> Path:
    """The FER .tflite emotion classifier."""
    return _shared("models/emotion/fer_emotion_model_quantized.tflite", "FER emotion model")


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """The shared data folder (video/, images/, formats/)."""
    return _shared("data", "shared test data")


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> None:
    """Keep caches of one test session out of the user's home (shared by all tests of the session)."""
    if "MIEN_CACHE_DIR" not in os.environ:
        monkeypatch.setenv("MIEN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mien-cache"))
