"""Benchmark: offline rendering of a changing expression to H.264 MP4, end to end, at 512 x 512.

Renders N = 120 frames of the ICT-FaceKit head (or the built-in head, saying so, when ICT-FaceKit is not
installed) through ``mien.render.render_clip``: morph-target blending + normals + rasterisation + MP4
encoding. Prints the median of 3 repeats as frames per second, its ratio to the 30 fps target, and the
split (render-only ms per frame, encode-only ms per frame). The named baseline measured in the same run is
"serial": render-only time + encode-only time, i.e. the same work without overlapping the two.

Run: ``.venv/bin/python bench/render.py [--frames 120] [--samples 0 4] [--preset veryfast]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mien.render import CAMERA_PRESETS, render_clip, write_mp4
from mien.render.clip_render import iter_frames, make_renderer
from mien.rig.model import Rig

SIZE = (512, 512)
TARGET_FPS = 30.0
REPEATS = 3


def load_rig() -> Rig:
    """ICT-FaceKit (configured path, else ../shared beside the checkout), else the built-in head."""
    from mien.errors import MissingAssetError
    from mien.rig.ict_facekit import load_ict_facekit

    shared = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    for path in (None, shared / "assets" / "ict-facekit"):
        try:
            return load_ict_facekit(path)
        except MissingAssetError:
            continue
    print("ICT-FaceKit not found: benchmarking the built-in head instead")
    from mien.rig.builtin_head import builtin_head  # type: ignore[import-not-found,unused-ignore]

    rig: Rig = builtin_head()
    return rig


def expression_weights(rig: Rig, n_frames: int) -> np.ndarray:
    """(n_frames, n_targets) smooth, changing weights: each ARKit target a slow raised sine, ~1/3 active."""
    n_targets = len(rig.targets)
    t = np.arange(n_frames)[:, None] / 30.0
    rng = np.random.default_rng(7)
    period_s = rng.uniform(1.0, 4.0, n_targets)
    phase = rng.uniform(0.0, 2 * np.pi, n_targets)
    weights = np.clip(np.sin(2 * np.pi * t / period_s + phase) * 1.5 - 0.5, 0.0, 1.0)
    weights[:, 52:] = 0.0  # ARKit targets only
    return weights.astype(np.float32)


def median_s(function: Callable[[], object], repeats: int = REPEATS) -> float:
    """Median wall time of ``function()`` over ``repeats`` runs, seconds."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def measure(rig: Rig, weights: np.ndarray, samples: int, out: Path, crf: int, preset: str) -> str:
    """One line of results for ``samples``-times MSAA: end to end, serial baseline, and the split."""
    camera = CAMERA_PRESETS["portrait"]
    n = len(weights)
    frames: list[np.ndarray] = []
    with make_renderer(rig, camera, SIZE, samples=samples) as renderer:
        render_s = median_s(lambda: frames.__setitem__(slice(None), list(iter_frames(rig, weights, renderer))))
    encode_s = median_s(lambda: write_mp4(frames, out, 30, crf=crf, preset=preset))
    total_s = median_s(
        lambda: render_clip(
            rig, weights, out, 30, camera, SIZE, progress=False, crf=crf, preset=preset, samples=samples
        )
    )
    fps, serial_fps = n / total_s, n / (render_s + encode_s)
    return (
        f"samples={samples}: end to end {fps:.1f} fps ({fps / TARGET_FPS:.2f} x the {TARGET_FPS:.0f} fps target; "
        f"{fps / serial_fps:.2f} x the serial baseline of {serial_fps:.1f} fps); "
        f"render {1000 * render_s / n:.1f} ms/frame, encode {1000 * encode_s / n:.1f} ms/frame"
    )


def main() -> None:
    """Run the benchmark and print one line per MSAA setting."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--samples", type=int, nargs="+", default=[0, 4], help="MSAA settings (0 = clip default)")
    parser.add_argument("--preset", default="veryfast", help="x264 preset")
    parser.add_argument("--crf", type=int, default=20)
    args = parser.parse_args()

    rig = load_rig()
    weights = expression_weights(rig, args.frames)
    print(f"rig {rig.name}: {rig.n_vertices} vertices, {len(rig.faces)} triangles; {args.frames} frames 512x512")
    load = os.getloadavg()[0]
    print(f"x264 {args.preset} crf {args.crf}; {os.cpu_count()} CPUs, load {load:.1f}; median of {REPEATS} repeats")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "bench.mp4"
        render_clip(rig, weights[:2], out, 30, CAMERA_PRESETS["portrait"], SIZE, progress=False)  # warm-up
        for samples in args.samples:
            print(measure(rig, weights, samples, out, args.crf, args.preset))


if __name__ == "__main__":
    main()
