"""Exchange formats: .glb export, key reduction and OpenFace import, each against a named baseline in one run.

1. A 60 s, 60 fps clip of all 52 ARKit targets on the ICT head (the built-in head without ICT-FaceKit) written as
   ``.glb`` (mesh, normals, colours, paint texture, sparse morph targets, animation) vs the baseline: the same
   arrays (neutral, faces, every target's ids and deltas, the weights and head rotations) written with
   ``numpy.savez``. Target: under 1 s.
2. Key reduction of the same clip's 52 weight curves at a tolerance of 0.01 (weight units): keys kept vs the
   frames (the baseline: one key per frame). Target: at least 10x fewer keys.
3. The real OpenFace CSV (``$MIEN_SHARED/data/formats/OpenFace_Test.csv``) imported as a clip, validation
   included, vs ``pandas.read_csv`` of the same file alone. Target: no slower (ratio <= 1).

The clip is a seeded character run: six emotions in turn with idle behaviour (blinks, gaze, micro-motion)
and head motion. Timings are medians over interleaved repeats (candidate, baseline, candidate...), with the
spread (min..max). Run: ``.venv/bin/python bench/exchange.py [--repeats 7]``.
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mien.facs.clip import Clip


def interleaved(candidate: Callable[[], object], baseline: Callable[[], object], repeats: int) -> tuple[list, list]:
    """Seconds of ``repeats`` alternating calls of each (after one warm-up call each)."""
    candidate()
    baseline()
    times: tuple[list[float], list[float]] = ([], [])
    for _ in range(repeats):
        for index, function in enumerate((candidate, baseline)):
            start = time.perf_counter()
            function()
            times[index].append(time.perf_counter() - start)
    return times


def describe(name: str, seconds: list[float]) -> str:
    spread = f"{min(seconds) * 1000:.1f}..{max(seconds) * 1000:.1f}"
    return f"{name}: median {statistics.median(seconds) * 1000:.1f} ms (spread {spread})"


def character_clip(seconds: float, fps: float) -> Clip:
    from mien.character import Character

    character = Character(seed=7)
    for k, emotion in enumerate(("joy", "surprise", "anger", "sadness", "disgust", "fear")):
        character.emote(emotion, 1.2, start_s=k * seconds / 6 + 0.5)
    return character.run(seconds, fps)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    from mien.exchange import glb
    from mien.exchange.key_reduction import reduce_keys
    from mien.facs.arkit import ARKIT_NAMES
    from mien.heads import load_head
    from mien.rig.face_weights import clip_to_rig

    rig = load_head("default")
    face = character_clip(60.0, 60.0)
    weights, poses = clip_to_rig(face, rig)
    arkit = Clip(np.hstack([weights[:, :52], poses[:, :3]]), 60.0, (*ARKIT_NAMES, *face.channels[-5:-2]))
    print(f"clip: {arkit.n_frames} frames x {len(ARKIT_NAMES)} targets at {arkit.fps:g} fps on the {rig.name} head")

    folder = Path(tempfile.mkdtemp(prefix="mien-bench-"))
    glb_path, npz_path = folder / "clip.glb", folder / "clip.npz"

    def write_glb() -> None:
        glb.write(arkit, glb_path, rig=rig)

    def write_npz() -> None:
        arrays = {"neutral": rig.neutral, "faces": rig.faces, "weights": weights, "poses": poses}
        for i, target in enumerate(rig.targets):
            arrays[f"ids_{i}"] = target.vertex_ids
            arrays[f"deltas_{i}"] = target.deltas
        np.savez(npz_path, **arrays)  # type: ignore[arg-type]

    glb_s, npz_s = interleaved(write_glb, write_npz, args.repeats)
    ratio = statistics.median(glb_s) / statistics.median(npz_s)
    print("\n1. 60 s x 60 fps x 52 targets to .glb")
    print("  " + describe("mien .glb", glb_s) + f", {glb_path.stat().st_size / 1e6:.1f} MB")
    print(
        "  " + describe("baseline numpy.savez of the same arrays", npz_s) + f", {npz_path.stat().st_size / 1e6:.1f} MB"
    )
    verdict = "met" if statistics.median(glb_s) < 1.0 else "MISSED"
    print(f"  ratio glb / savez: {ratio:.2f}x; target < 1 s: {verdict}")

    print("\n2. key reduction at tolerance 0.01 (weights 0..1)")
    times = arkit.times_s
    keys = sum(len(reduce_keys(times, arkit.values[:, j], 0.01)) for j in range(52))
    frames = arkit.n_frames * 52
    print(f"  keys kept: {keys} of {frames} (baseline: one key per frame per curve)")
    verdict = "met" if frames / keys >= 10 else "MISSED"
    print(f"  ratio frames / keys: {frames / keys:.1f}x fewer keys; target >= 10x: {verdict}")

    shared = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[1].parent / "shared"))
    openface = shared / "data" / "formats" / "OpenFace_Test.csv"
    print("\n3. OpenFace CSV import vs pandas.read_csv alone")
    if not openface.is_file():
        print(f"  skipped: {openface} not found (set MIEN_SHARED)")
        return
    import pandas as pd

    from mien.exchange import openface_csv

    data = openface.read_bytes()
    import_s, pandas_s = interleaved(
        lambda: openface_csv.read(io.BytesIO(data)), lambda: pd.read_csv(io.BytesIO(data)), args.repeats * 3
    )
    ratio = statistics.median(import_s) / statistics.median(pandas_s)
    print("  " + describe("mien openface_csv.read (parse, validate, resample)", import_s))
    print("  " + describe("baseline pandas.read_csv", pandas_s))
    verdict = "met" if ratio <= 1.0 else "MISSED"
    print(f"  ratio import / pandas: {ratio:.2f}x; target <= 1: {verdict}")


if __name__ == "__main__":
    main()
