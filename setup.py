"""setuptools hooks; everything else about the build is in pyproject.toml.

The wheel carries the part of the npm ``three`` package the viewer loads, with its licence, in
``mien/viewer/three`` (copied by ``scripts/vendor_three.py`` from ``node_modules``, installed by ``npm ci``, or
``$MIEN_NODE_MODULES``), so that ``pip install 'mien[serve]'`` serves the viewer. The sdist carries the same
files under ``node_modules/three``, so a wheel built from it has them too. Without them the build stops and says
what to do; ``MIEN_WHEEL_WITHOUT_THREE=1`` builds a wheel whose viewer page says three.js is missing. An
editable install (``pip install -e``) copies nothing: it serves the checkout's ``node_modules``.
"""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path
from types import ModuleType

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = Path(__file__).resolve().parent
WITHOUT_THREE = "MIEN_WHEEL_WITHOUT_THREE"


def _vendor() -> ModuleType:
    spec = importlib.util.spec_from_file_location("vendor_three", HERE / "scripts" / "vendor_three.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _copy_three(into: Path) -> None:
    vendor = _vendor()
    try:
        files = vendor.copy_three(into)
    except vendor.VendorError as exc:
        if os.environ.get(WITHOUT_THREE) == "1":
            print(f"mien: building without the viewer's three.js ({WITHOUT_THREE}=1): {exc}")
            return
        raise SystemExit(
            f"mien: the viewer's three.js cannot be packaged: {exc} (or set MIEN_NODE_MODULES to a node_modules "
            f"folder with three), or set {WITHOUT_THREE}=1 to build without it."
        ) from None
    print(f"mien: {len(files)} files of three.js copied into {into}")


class BuildPyWithThree(build_py):
    """build_py, then the viewer's three.js into ``<build_lib>/mien/viewer/three``."""

    def run(self) -> None:
        super().run()
        if not getattr(self, "editable_mode", False):
            _copy_three(Path(self.build_lib) / "mien" / "viewer" / "three")


class SdistWithThree(sdist):
    """sdist, with the viewer's three.js under ``node_modules/three`` for the wheel built from it."""

    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        super().make_release_tree(base_dir, files)
        _copy_three(Path(base_dir) / "node_modules" / "three")


setup(cmdclass={"build_py": BuildPyWithThree, "sdist": SdistWithThree})
