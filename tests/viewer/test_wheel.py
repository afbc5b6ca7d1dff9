"""The wheel carries the three.js the viewer loads, with its licence, and an installed mien serves it (issue 29
case 16: a pip user got a 503 page telling them to run ``npm ci`` in a checkout they do not have).

Before: the wheel held no three.js (``mien/viewer/static`` only) and ``three_dir()`` of an installed mien was None.
"""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path
from types import ModuleType

import pytest

REPO = Path(__file__).resolve().parents[2]
THREE = REPO / "node_modules" / "three"
OFFLINE_SIGNS = (
    "No matching distribution found",
    "Could not find a version that satisfies",
    "NewConnectionError",
    "Temporary failure in name resolution",
    "Network is unreachable",
)
"""pip's words for an unreachable index (setuptools for the isolated build): a skip, not a failure."""


def _vendor() -> ModuleType:
    spec = importlib.util.spec_from_file_location("vendor_three", REPO / "scripts" / "vendor_three.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def vendor() -> ModuleType:
    if not (THREE / "build" / "three.module.js").is_file():
        pytest.skip("node_modules/three missing: run `npm ci`")
    return _vendor()


def test_the_files_copied_are_what_the_viewer_imports(vendor: ModuleType, tmp_path: Path) -> None:
    files = vendor.three_files(THREE)
    assert {
        "LICENSE",
        "package.json",
        "build/three.module.js",
        "build/three.core.js",  # imported by three.module.js
        "examples/jsm/loaders/GLTFLoader.js",
        "examples/jsm/utils/BufferGeometryUtils.js",  # imported by GLTFLoader.js
        "examples/jsm/controls/OrbitControls.js",
        "examples/jsm/libs/meshopt_decoder.module.js",
        "examples/jsm/libs/draco/gltf/draco_decoder.wasm",  # the decoder path viewer.js gives DRACOLoader
        "examples/jsm/libs/draco/README.md",  # the Draco decoder's licence note
    } <= set(files)
    assert not [f for f in files if f.startswith(("src/", "build/three.webgpu", "examples/jsm/Addons"))]
    assert len(files) < 20
    copied = vendor.copy_three(tmp_path / "three", THREE)
    assert (
        sorted(p.relative_to(tmp_path / "three").as_posix() for p in (tmp_path / "three").rglob("*") if p.is_file())
        == copied
    )


def test_a_missing_three_or_an_unknown_import_is_refused(vendor: ModuleType, tmp_path: Path) -> None:
    with pytest.raises(vendor.VendorError, match="npm ci"):
        vendor.three_files(tmp_path / "no-three")
    static = tmp_path / "static"
    shutil.copytree(REPO / "src" / "mien" / "viewer" / "static", static)
    (static / "extra.js").write_text('import { VRM } from "@pixiv/three-vrm";\n')
    with pytest.raises(vendor.VendorError, match="@pixiv/three-vrm"):
        vendor.three_files(THREE, static)


def _copy_sources(into: Path) -> Path:
    """What a build reads (pyproject, setup.py, MANIFEST.in, README, the helper, src/), without residue."""
    into.mkdir()
    for name in ("pyproject.toml", "setup.py", "MANIFEST.in", "README.md"):
        shutil.copy2(REPO / name, into / name)
    (into / "scripts").mkdir()
    shutil.copy2(REPO / "scripts" / "vendor_three.py", into / "scripts" / "vendor_three.py")
    shutil.copytree(REPO / "src", into / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return into


def _pip(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "pip", *args], capture_output=True, text=True, env=env, timeout=600)


@pytest.mark.slow
def test_the_wheel_ships_three_and_an_installed_mien_serves_it(vendor: ModuleType, tmp_path: Path) -> None:
    pytest.importorskip("fastapi", reason="the serve extra is not installed")
    sources = _copy_sources(tmp_path / "mien")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PIP_USER", "PIP_TARGET", "PIP_PREFIX")}
    env["MIEN_NODE_MODULES"] = str(REPO / "node_modules")  # the copy has no node_modules of its own
    built = _pip("wheel", "--no-deps", "-q", "-w", str(tmp_path / "dist"), str(sources), env=env)
    output = built.stdout + built.stderr
    if built.returncode != 0 and any(sign in output for sign in OFFLINE_SIGNS):
        pytest.skip(f"no package index reachable for the build backend: {output.strip()[-300:]}")
    assert built.returncode == 0, output
    (wheel,) = (tmp_path / "dist").glob("mien-*.whl")

    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        licence = archive.read("mien/viewer/three/LICENSE").decode()
        version = json.loads(archive.read("mien/viewer/three/package.json"))["version"]
    shipped = sorted(n.removeprefix("mien/viewer/three/") for n in names if n.startswith("mien/viewer/three/"))
    assert shipped == vendor.three_files(THREE)
    assert "MIT License" in licence and "three.js authors" in licence
    assert version == json.loads((THREE / "package.json").read_text())["version"]
    # nothing else from npm: mien's own package and its metadata only
    assert all(n.startswith(("mien/", "mien-")) for n in names)
    assert not [n for n in names if "node_modules" in n or "@pixiv" in n or "three-vrm" in n or "validator" in n]

    site = tmp_path / "site"
    installed = _pip("install", "--no-deps", "-q", "--target", str(site), str(wheel), env=env)
    assert installed.returncode == 0, installed.stdout + installed.stderr
    del env["MIEN_NODE_MODULES"]
    env["PYTHONPATH"] = str(site)
    probe = (
        "import json, mien\n"
        "from fastapi import FastAPI\n"
        "from fastapi.testclient import TestClient\n"
        "from mien.viewer.routes import mount\n"
        "from mien.viewer.vendor import three_dir\n"
        "app = FastAPI()\n"
        "mount(app)\n"
        "client = TestClient(app)\n"
        "paths = ['/', '/vendor/three/build/three.module.js', '/vendor/three/build/three.core.js',\n"
        "         '/vendor/three/examples/jsm/loaders/GLTFLoader.js',\n"
        "         '/vendor/three/examples/jsm/libs/draco/gltf/draco_decoder.wasm', '/vendor/three/LICENSE']\n"
        "print(json.dumps({'mien': mien.__file__, 'three': str(three_dir()),\n"
        "                  'status': {p: client.get(p).status_code for p in paths}}))\n"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    assert Path(seen["mien"]).is_relative_to(site)  # the installed copy, not the checkout
    assert seen["three"] == str(site / "mien" / "viewer" / "three")
    assert set(seen["status"].values()) == {200}, seen["status"]


def test_an_installed_layout_is_found_first(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from mien.viewer import vendor as lookup

    packaged = tmp_path / "three"
    (packaged / "build").mkdir(parents=True)
    (packaged / "build" / "three.module.js").write_text("export {};\n")
    monkeypatch.delenv("MIEN_NODE_MODULES", raising=False)
    monkeypatch.setattr(lookup, "PACKAGED_THREE", packaged)
    assert lookup.three_dir() == packaged
    monkeypatch.setenv("MIEN_NODE_MODULES", str(tmp_path / "elsewhere"))  # an explicit choice wins, alone
    assert lookup.three_candidates() == [tmp_path / "elsewhere" / "three"]
    assert lookup.three_dir() is None
