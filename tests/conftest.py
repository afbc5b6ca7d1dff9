"""Shared pytest fixtures: where the shared assets and data are (skip with a reason when absent)."""

from __future__ import annotations

import os
import shutil
import subprocess
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


def valid_avatars() -> list[Path]:
    """The four VALID avatars under ``$MIEN_SHARED/avatars/valid`` (skips the test when absent)."""
    root = shared_root()
    folder = None if root is None else root / "avatars" / "valid"
    if folder is None or not folder.is_dir():
        pytest.skip("VALID avatars not available: set MIEN_SHARED to the shared folder (needs avatars/valid)")
    return sorted(folder.glob("*.glb"))


def valid_avatar(name: str = "White_F_1_Casual.glb") -> Path:
    """One VALID avatar by file name (skips the test when absent, or when the heads extra is not installed)."""
    path = next((p for p in valid_avatars() if p.name == name), None)
    if path is None:
        pytest.skip(f"VALID avatar {name} not available under $MIEN_SHARED/avatars/valid")
    pytest.importorskip("meshopt", reason="the heads extra (pip install 'mien[heads]') is not installed")
    return path


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


FIXTURE_MARKERS = {"chromium": "browser", "postgres_url": "database", "ict_glb": "blender"}
"""A test that uses one of these fixtures (directly or through another fixture) gets the marker, so
``-m "not browser"`` or ``-m "not database"`` leaves out every test that would start the service. Tests that
ask for the fixture at run time (``request.getfixturevalue``) carry the marker on their parameter."""


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        for fixture, marker in FIXTURE_MARKERS.items():
            if fixture in getattr(item, "fixturenames", ()):
                item.add_marker(marker)


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


@pytest.fixture(scope="session")
def postgres_url() -> Iterator[str]:
    """A real PostgreSQL server started for this test session in a temporary folder (Debian's package).

    Yields a SQLAlchemy URL (``postgresql+psycopg://postgres@127.0.0.1:PORT/postgres``); the server is
    stopped and its folder removed afterwards (see :func:`mien.study._postgres.temporary_postgres`).
    """
    from mien.study._postgres import postgres_available, temporary_postgres

    if not postgres_available():
        pytest.skip("PostgreSQL server binaries not found: apt install postgresql (scripts/install does)")
    with temporary_postgres() as url:
        yield url


_BLENDER_SCRIPT = r"""
import sys
from pathlib import Path
import bpy
import numpy as np
argv = sys.argv[sys.argv.index("--") + 1 :]
model, out, names = Path(argv[0]), argv[1], argv[2].split(",")
def read(path, faces=False):
    verts, polys = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            verts.append(line.split()[1:4])
        elif faces and line.startswith("f "):
            polys.append([int(t.split("/")[0]) - 1 for t in line.split()[1:]])
    v = np.array(verts, dtype=np.float64)
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1), polys  # OBJ +Y up -> Blender +Z up
bpy.ops.wm.read_factory_settings(use_empty=True)
neutral, polys = read(model / "generic_neutral_mesh.obj", faces=True)
mesh = bpy.data.meshes.new("ict_head")
mesh.from_pydata(neutral.tolist(), [], polys)
mesh.update()
obj = bpy.data.objects.new("ict_head", mesh)
bpy.context.scene.collection.objects.link(obj)
obj.shape_key_add(name="Basis", from_mix=False)
for name in names:
    key = obj.shape_key_add(name=name, from_mix=False)
    key.data.foreach_set("co", read(model / f"{name}.obj")[0].astype(np.float32).ravel())
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_morph=True, export_morph_normal=False,
                          export_materials="NONE")
"""


@pytest.fixture(scope="session")
def ict_glb(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ICT-FaceKit's neutral and expression shapes as shape keys, written by Blender's own glTF exporter."""
    blender = shutil.which("blender")
    if blender is None:
        pytest.skip("Blender not installed (apt-get install blender): it writes the ICT-FaceKit .glb")
    from mien.rig.conventions import load_convention

    names = [*sorted(load_convention("ict").source_names), "cheekRaiser_L", "cheekRaiser_R"]
    folder = tmp_path_factory.mktemp("ict-glb")
    script, out = folder / "export.py", folder / "ict.glb"
    script.write_text(_BLENDER_SCRIPT)
    args = [blender, "-b", "--factory-startup", "--python", str(script), "--",
            str(ict_dir / "FaceXModel"), str(out), ",".join(names)]  # fmt: skip
    result = subprocess.run(args, capture_output=True, text=True, timeout=300, check=False)
    if not out.is_file():
        pytest.fail(f"Blender did not write {out}: {result.stdout[-2000:]} {result.stderr[-2000:]}")
    return out
