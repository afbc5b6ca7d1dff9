"""Benchmark: validation is never the bottleneck, and the full report for one head fits in 5 minutes.

1. Per frame, interleaved: rendering one 512 x 512 stimulus (deform + normals + rasterise + read back) vs
   detecting on it (MediaPipe Face Landmarker in image mode + the FER classifier on its crop). Baseline:
   rendering. Prints the medians, the spread (min..max) of REPEATS rounds over N frames each, and the ratio
   detect / render (target <= 1).
2. The whole `mien validate report` for one head (ICT-FaceKit identity a when installed, else the built-in head)
   with the shared human video, as a user runs it, timed once end to end (it is 30-60 s, so run-to-run noise of a
   few seconds does not matter against the 300 s budget). Baseline: the 300 s target. Prints the ratio.

Run: ``.venv/bin/python bench/validate.py [--frames 40] [--repeats 5] [--no-report]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SHARED = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))


def _point_at_shared() -> None:
    defaults = {
        "MIEN_ICT_FACEKIT": SHARED / "assets" / "ict-facekit",
        "MIEN_FACE_LANDMARKER": SHARED / "models" / "face_landmarker.task",
        "MIEN_EMOTION_MODEL": SHARED / "models" / "emotion" / "fer_emotion_model_quantized.tflite",
    }
    for name, path in defaults.items():
        if name not in os.environ and path.exists():
            os.environ[name] = str(path)


def per_frame(frames: int, repeats: int) -> None:
    from mien.heads import load_head
    from mien.render.camera import CAMERA_PRESETS
    from mien.rig.heads import ict_installed
    from mien.validate.expressions import EXPRESSIONS
    from mien.validate.face_detector import FaceDetector
    from mien.validate.recognition import peak_face
    from mien.validate.stimuli import StimulusRenderer

    head = ("ict", "a") if ict_installed() else ("builtin", "default")
    rig = load_head(*head)
    faces = [peak_face(EXPRESSIONS[i % len(EXPRESSIONS)], 1.2 + 1.2 * (i % 2), "facs")[0] for i in range(frames)]
    detector = FaceDetector()
    render_ms: list[float] = []
    detect_ms: list[float] = []
    with StimulusRenderer(rig, CAMERA_PRESETS["frontal-1m"], (512, 512)) as renderer:
        renderer.render(faces[0])  # warm-up: shaders, first allocation
        detector.detect(*renderer.render(faces[0]))
        for _ in range(repeats):  # interleaved: each round renders then detects the same frames
            images = []
            started = time.perf_counter()
            for face in faces:
                images.append(renderer.render(face))
            render_ms.append((time.perf_counter() - started) * 1e3 / frames)
            started = time.perf_counter()
            for rgb, hint in images:
                detector.detect(rgb, hint)
            detect_ms.append((time.perf_counter() - started) * 1e3 / frames)
    detector.close()
    r, d = statistics.median(render_ms), statistics.median(detect_ms)
    print(f"head {head[0]}:{head[1]}, 512x512, {frames} frames x {repeats} interleaved rounds")
    print(f"  render (baseline)  {r:6.1f} ms/frame  (min {min(render_ms):.1f}, max {max(render_ms):.1f})")
    print(f"  detect             {d:6.1f} ms/frame  (min {min(detect_ms):.1f}, max {max(detect_ms):.1f})")
    print(f"  ratio detect/render: {d / r:.2f}  (target <= 1.00)")


def full_report() -> None:
    from mien.rig.heads import ict_installed

    head = "ict:a" if ict_installed() else "builtin:default"
    video = SHARED / "data" / "video" / "single_face.mp4"
    with tempfile.TemporaryDirectory() as folder:
        argv = [sys.executable, "-m", "mien.cli", "validate", "report", "--head", head, "--quiet", "-o", folder]
        if video.is_file():
            argv += ["--video", str(video)]
        started = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        seconds = time.perf_counter() - started
    print(f"full report for {head}{' with the human video' if video.is_file() else ''}: {seconds:.1f} s")
    print(f"  ratio to the 300 s target: {seconds / 300:.2f}  (target <= 1.00; one run, noise a few seconds)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-report", action="store_true")
    args = parser.parse_args()
    _point_at_shared()
    np.random.default_rng(0)
    per_frame(args.frames, args.repeats)
    if not args.no_report:
        full_report()


if __name__ == "__main__":
    main()
