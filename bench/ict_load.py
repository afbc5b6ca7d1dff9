"""Benchmark: loading ICT-FaceKit from its OBJ files (baseline) against loading from mien's .npz cache.

Run: ``.venv/bin/python bench/ict_load.py``. Needs the asset (``MIEN_ICT_FACEKIT``, the config file, or
``../shared/assets/ict-facekit``). Uses a temporary cache folder, so the user's cache is left alone. Prints the
median of several loads each way and the ratio.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from _ict import ict_facekit_folder, temporary_cache  # noqa: E402

from mien.rig.ict_facekit import ict_identity_presets, load_ict_facekit  # noqa: E402


def _median_s(run: object, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()  # type: ignore[operator]
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> None:
    folder = ict_facekit_folder()
    if folder is None:
        return
    with temporary_cache():
        parse = _median_s(lambda: load_ict_facekit(folder, cache=False), 3)
        load_ict_facekit(folder)  # writes the cache
        cached = _median_s(lambda: load_ict_facekit(folder), 7)
        identity = ict_identity_presets()["a"]
        cached_identity = _median_s(lambda: load_ict_facekit(folder, identity=identity), 7)
    print(f"ICT-FaceKit at {folder}")
    print(f"  parse OBJ folder (baseline, cache=False) {parse:8.3f} s  (median of 3)")
    print(f"  cached .npz load                        {cached:8.3f} s  (median of 7)")
    print(f"  cached load with identity 'a'           {cached_identity:8.3f} s  (median of 7)")
    print(f"ratio parse / cached: {parse / cached:.0f}x")


if __name__ == "__main__":
    main()
