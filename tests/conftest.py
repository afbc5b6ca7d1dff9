"""Shared pytest fixtures: where the shared assets and data are (skip with a reason when absent)."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import tempfile
from collections.abc import Iterator
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


CHROMIUM = os.environ.get("MIEN_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking"]


@pytest.fixture(scope="module")
def chromium() -> Iterator[object]:
    """A real headless Debian Chromium driven by Playwright (never a downloaded browser).

    Yields a ``playwright.sync_api.Browser``; open pages with ``chromium.new_page()`` and close them. Scoped
    to one test module: Playwright's sync API keeps an event loop running on the main thread while it is
    open, which would break ``asyncio.run`` in the modules after it.
    """
    playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright not installed (dev extra)")
    if not Path(CHROMIUM).exists():
        pytest.skip(f"Chromium not found at {CHROMIUM}: apt install chromium (scripts/install does)")
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS, headless=True)
        try:
            yield browser
        finally:
            browser.close()


def free_port() -> int:
    """A free TCP port on 127.0.0.1 (for servers a test starts)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def _postgres_bin(name: str) -> str | None:
    found = shutil.which(name)
    if found:
        return found
    candidates = sorted(Path("/usr/lib/postgresql").glob(f"*/bin/{name}"))
    return str(candidates[-1]) if candidates else None


@pytest.fixture(scope="session")
def postgres_url() -> Iterator[str]:
    """A real PostgreSQL server started for this test session in a temporary folder (Debian's package).

    Yields a SQLAlchemy URL (``postgresql+psycopg://postgres@127.0.0.1:PORT/postgres``); the server is
    stopped and its folder removed afterwards. PostgreSQL refuses to run as root, so as root the server
    runs as the ``postgres`` system user.
    """
    initdb, pg_ctl = _postgres_bin("initdb"), _postgres_bin("pg_ctl")
    if initdb is None or pg_ctl is None:
        pytest.skip("PostgreSQL server binaries not found: apt install postgresql (scripts/install does)")
    as_user: list[str] = []
    folder = Path(tempfile.mkdtemp(prefix="mien-pg-"))
    if os.geteuid() == 0:
        shutil.chown(folder, "postgres")
        as_user = ["runuser", "-u", "postgres", "--"]
    data, port = folder / "data", free_port()
    subprocess.run(
        [*as_user, initdb, "-D", str(data), "-U", "postgres", "-A", "trust"], check=True, capture_output=True
    )
    options = f"-p {port} -h 127.0.0.1 -k {folder}"
    subprocess.run(
        [*as_user, pg_ctl, "-D", str(data), "-o", options, "-l", str(folder / "log"), "-w", "start"],
        check=True,
        capture_output=True,
    )
    try:
        yield f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres"
    finally:
        subprocess.run([*as_user, pg_ctl, "-D", str(data), "-m", "fast", "-w", "stop"], capture_output=True)
        shutil.rmtree(folder, ignore_errors=True)
