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

from mien.paths import cache_dir


def timed(function: Callable[[], object]) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def describe(name: str, seconds: list[float]) -> str:
    return f"{name}: median {statistics.median(seconds):.3f} s (spread {min(seconds):.3f}..{max(seconds):.3f})"


def heads() -> list[tuple[str, Callable[[], object], Callable[[], object]]]:
    """``(name, instrument once, from the cache)`` per head: mien's own heads bare, a VALID avatar as
    :func:`mien.heads.load_head` instruments it (its own textured render, the eyes the reader found)."""
    from mien.heads.instrument import instrument, instrument_cached
    from mien.heads.registry import file_fingerprint, instrument_head
    from mien.rig.builtin_head import builtin_head
    from mien.rig.heads import open_head

    found: list[tuple[str, Callable[[], object], Callable[[], object]]] = []
    rigs = [("built-in", builtin_head())]
    if os.environ.get("MIEN_ICT_FACEKIT"):
        from mien.rig.ict_facekit import load_ict_facekit

        rigs.insert(0, ("ICT-FaceKit", load_ict_facekit()))
    for name, rig in rigs:
        key = hashlib.sha256(rig.neutral.tobytes()).hexdigest()
        found.append((
            f"{name} ({rig.n_vertices:,} vertices, bare render)",
            lambda rig=rig, name=name: instrument(rig.neutral, rig.faces, name=name),
            lambda rig=rig, key=key, name=name: instrument_cached(rig.neutral, rig.faces, key, name=name),
        ))  # fmt: skip
    shared = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    for path in sorted((shared / "avatars" / "valid").glob("*.glb"))[:1]:
        raw = open_head(str(path))
        cache = cache_dir("heads") / f"{file_fingerprint(path)}.instrument.json"

        def once(raw=raw, cache=cache) -> object:  # type: ignore[no-untyped-def]
            cache.unlink(missing_ok=True)
            return instrument_head(raw)

        label = f"{path.name} ({raw.n_vertices:,} vertices, textured render)"
        found.append((label, once, lambda raw=raw: instrument_head(raw)))
    return found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    os.environ["MIEN_CACHE_DIR"] = tempfile.mkdtemp(prefix="mien-bench-")
    from mien.heads.instrument import _RENDER_PX
    from mien.tracking.landmarker import Landmarker

    picture = np.full((_RENDER_PX, _RENDER_PX, 3), 128, np.uint8)

    def landmarker_alone() -> None:
        with Landmarker(mode="image") as landmarker:
            landmarker.detect(picture)

    for name, once_call, cached_call in heads():
        once, floor = [], []
        for _ in range(args.repeats):
            once.append(timed(once_call))
            floor.append(timed(landmarker_alone))
        cached_call()
        cached, read = [], []
        for _ in range(max(args.repeats, 5)):
            cached.append(timed(cached_call))
            read.append(timed(lambda: sorted(cache_dir("heads").glob("*.json"))[0].read_text(encoding="utf-8")))
        print(name)
        print("  " + describe("instrument once", once) + "  (target < 10 s)")
        print("  " + describe("baseline: landmarker load + one detection", floor))
        print(f"  ratio to baseline: {statistics.median(once) / statistics.median(floor):.1f}x")
        print("  " + describe("from the cache", cached) + "  (target < 0.2 s)")
        print("  " + describe("baseline: read of a cached JSON alone", read))

if __name__ == "__main__":
    main()
