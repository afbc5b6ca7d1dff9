"""Instrumenting a head: once (render, MediaPipe landmarks, cast back, axes and unit) and from the cache.

Targets (issue 28): under 10 s once, under 0.2 s from the cache. The baseline named beside each figure is the
part of the work no method can skip: for the first run, loading MediaPipe's landmarker and one detection on a
picture of the same size; for the cache, reading the cached JSON text alone. Heads: ICT-FaceKit (26,719
vertices) when ``MIEN_ICT_FACEKIT`` is set, the built-in head, and the VALID avatars under
``$MIEN_SHARED/avatars/valid`` when the glTF reader can load them. Medians of interleaved repeats with the
spread. Run: ``.venv/bin/python bench/head_instrument.py [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np


def timed(function: Callable[[], object]) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def describe(name: str, seconds: list[float]) -> str:
    return f"{name}: median {statistics.median(seconds):.3f} s (spread {min(seconds):.3f}..{max(seconds):.3f})"


def heads() -> list[tuple[str, np.ndarray, np.ndarray]]:
    from mien.rig.builtin_head import builtin_head

    found = []
    if os.environ.get("MIEN_ICT_FACEKIT"):
        from mien.rig.ict_facekit import load_ict_facekit

        rig = load_ict_facekit()
        found.append(("ICT-FaceKit", rig.neutral, rig.faces))
    rig = builtin_head()
    found.append(("built-in", rig.neutral, rig.faces))
    shared = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    try:
        from mien.heads.registry import load_file_mesh
    except ImportError:
        return found
    for path in sorted((shared / "avatars" / "valid").glob("*.glb"))[:1]:
        vertices, faces = load_file_mesh(path)
        found.append((path.name, vertices, faces))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    os.environ["MIEN_CACHE_DIR"] = tempfile.mkdtemp(prefix="mien-bench-")
    from mien.heads.instrument import _RENDER_PX, instrument, instrument_cached
    from mien.paths import cache_dir
    from mien.tracking.landmarker import Landmarker

    picture = np.full((_RENDER_PX, _RENDER_PX, 3), 128, np.uint8)

    def landmarker_alone() -> None:
        with Landmarker(mode="image") as landmarker:
            landmarker.detect(picture)

    for name, vertices, faces in heads():
        digest = hashlib.sha256(vertices.tobytes()).hexdigest()
        once, floor = [], []
        for _ in range(args.repeats):
            once.append(timed(lambda: instrument(vertices, faces, name=name)))  # noqa: B023
            floor.append(timed(landmarker_alone))
        instrument_cached(vertices, faces, digest, name=name)
        cached_path = cache_dir("heads") / f"{digest}.instrument.json"
        cached, read = [], []
        for _ in range(max(args.repeats, 5)):
            cached.append(timed(lambda: instrument_cached(vertices, faces, digest, name=name)))  # noqa: B023
            read.append(timed(lambda: cached_path.read_text(encoding="utf-8")))  # noqa: B023
        print(f"{name} ({len(vertices):,} vertices)")
        print("  " + describe("instrument once", once) + "  (target < 10 s)")
        print("  " + describe("baseline: landmarker load + one detection", floor))
        print(f"  ratio to baseline: {statistics.median(once) / statistics.median(floor):.1f}x")
        print("  " + describe("from the cache", cached) + "  (target < 0.2 s)")
        print("  " + describe("baseline: read of the JSON alone", read))


if __name__ == "__main__":
    main()
