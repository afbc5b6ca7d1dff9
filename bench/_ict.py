"""Where the ICT-FaceKit benchmarks find the asset, and a throw-away cache folder so the user's cache is left alone."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from mien.paths import asset_path

REPO = Path(__file__).resolve().parents[1]


def ict_facekit_folder() -> Path | None:
    """The ICT-FaceKit folder (``MIEN_ICT_FACEKIT``, the config file, or ``../shared/assets/ict-facekit``).

    None, after printing where it looked, when it is absent (the benchmark then has nothing to time).
    """
    folder = asset_path("ict_facekit") or REPO.parent / "shared" / "assets" / "ict-facekit"
    if not folder.exists():
        print(f"ICT-FaceKit not found (looked at {folder}); set MIEN_ICT_FACEKIT to run this benchmark")
        return None
    return folder


@contextmanager
def temporary_cache() -> Iterator[Path]:
    """Point ``MIEN_CACHE_DIR`` at a new temporary folder (removed on exit); yields the folder."""
    with tempfile.TemporaryDirectory() as cache:
        os.environ["MIEN_CACHE_DIR"] = cache
        yield Path(cache)
