"""mien installed with numpy alone (no extra, no system site-packages) runs its core: characters, clips, the
CSV and JSON formats; importing it loads no third-party module but numpy; a laugh, which needs the laughter
extra, works or raises MissingExtraError naming the extra, never a raw ModuleNotFoundError.

The venv is built in a temporary folder from a copy of the checkout's sources (the checkout is left clean);
pip fetches numpy and the build backend (setuptools) from the configured index. Without an index the test
skips and says so; any other install failure fails it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parents[1]
SCRIPT = Path(__file__).with_name("minimal_core.py")
OFFLINE_SIGNS = (
    "No matching distribution found",
    "Could not find a version that satisfies",
    "NewConnectionError",
    "Temporary failure in name resolution",
    "Network is unreachable",
    "ProxyError",
)
"""Phrases of pip's output that mean the index is unreachable (a skip), not that mien failed to build."""


def _copy_sources(into: Path) -> Path:
    """The files a build needs (pyproject, README, src/) copied into ``into``: no build residue in the checkout."""
    into.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(REPO / name, into / name)
    shutil.copytree(REPO / "src", into / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return into


@pytest.fixture(scope="module")
def minimal_python(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The python of a fresh venv holding numpy and mien only."""
    root = tmp_path_factory.mktemp("minimal-install")
    sources = _copy_sources(root / "mien")
    venv = root / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--without-pip", venv], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip(f"cannot create a venv here: {made.stderr.strip()}")
    python = venv / "bin" / "python"
    # The test's own pip installs into the new venv (--python): the venv needs no pip of its own.
    install = [sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "numpy", str(sources)]
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PIP_USER", "PIP_TARGET", "PIP_PREFIX")}
    done = subprocess.run(install, capture_output=True, text=True, env=env, timeout=600)
    output = done.stdout + done.stderr
    if done.returncode != 0 and any(sign in output for sign in OFFLINE_SIGNS):
        pytest.skip(f"no package index reachable to install numpy and setuptools: {output.strip()[-300:]}")
    assert done.returncode == 0, f"pip install numpy + mien failed:\n{output}"
    return python


def test_the_core_runs_with_numpy_alone(minimal_python: Path, tmp_path: Path) -> None:
    packages = subprocess.run(
        [minimal_python, "-c", "import importlib.metadata as m; print(sorted(d.name for d in m.distributions()))"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert packages.strip() == str(sorted(["mien", "numpy"]))
    # Run from an empty folder with no PYTHONPATH, so the installed mien is the one imported, not the checkout.
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    run = subprocess.run([minimal_python, SCRIPT], capture_output=True, text=True, cwd=tmp_path, env=env)
    assert run.returncode == 0, run.stderr
    seen = json.loads(run.stdout)
    assert seen["imported_by_mien"] == ["numpy"]
    assert seen["frame_shape"] == [62] and seen["joy_AU12L_at_0.5s"] > 3.0
    assert seen["clip_shape"] == [30, 62] and seen["clip_fps"] == 30.0
    assert seen["round_trip_max_error"] == {"curves.csv": 0.0, "clip.json": 0.0}
    laugh = seen["laugh"]
    if laugh != "works":
        assert laugh["error"] == "MissingExtraError", f"a laugh without its extra raised {laugh}"
        assert "pip install 'mien[" in laugh["message"], laugh["message"]
