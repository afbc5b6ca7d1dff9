"""Time to render the stimuli of the full Broekens design with ``mien study stimuli``, against the 10-minute budget,
and the per-stimulus cost against a named baseline measured in the same run.

Run: .venv/bin/python bench/study_stimuli.py [--quick]

1. The full design of docs/STUDIES.md (10 expressions x 2 bases x 2 views x 2 distances x 2 intensities = 160
   clips of 3 s at 30 fps, 256 x 256, on the default head): total seconds and the ratio to the 600 s budget.
   ``--quick`` renders only the first 16 stimuli and extrapolates.
2. Baseline ``render_clip``: mien's one-call clip renderer (:func:`mien.render.clip_render.render_clip`, a new
   offscreen renderer per clip) on the same 6 stimuli, against :func:`mien.study.stimuli.make_stimuli` (one
   renderer for every stimulus sharing head, basis and camera); medians over interleaved repeats, with the
   spread (min..max).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from importlib import resources
from pathlib import Path

FULL = resources.files("mien.study").joinpath("data/broekens_full.toml").read_text(encoding="utf-8")
"""The shipped example design: the paper's 160 stimuli."""

SMALL = """
[study]
name = "broekens-small"
[stimuli]
expressions = ["joy", "anger", "evil"]
heads = ["default"]
intensities = [1.2, 2.4]
duration_s = 3.0
fps = 30
size = 256
"""
"""6 stimuli: 3 expressions x 2 intensities (one head, the FACS basis, the frontal 1 m camera)."""

BUDGET_S = 600.0
REPEATS = 3


def baseline_render_clip(design, out: Path) -> float:  # type: ignore[no-untyped-def]
    """Seconds to render every stimulus with one render_clip call each (a new renderer per clip)."""
    from mien.render.camera import camera_from_options
    from mien.render.clip_render import render_clip
    from mien.rig.animate import face_to_rig
    from mien.study.stimuli import _face_clip, _Scenes

    scenes = _Scenes(design.size)
    start = time.perf_counter()
    for spec in design.stimuli:
        c = spec.conditions
        rig = scenes.rig(c["head"], c["identity"], c["basis"])
        clip, features = _face_clip(design, spec)
        weights, poses = face_to_rig(rig, clip, features)
        camera = camera_from_options(f"{c['view']}-1m", distance_m=c["distance_m"])
        render_clip(rig, weights, out / f"{spec.id}.mp4", clip.fps, camera, (design.size,) * 2, poses, progress=False)
    return time.perf_counter() - start


def main() -> None:
    from mien.study.design import load_design
    from mien.study.stimuli import make_stimuli

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="render 16 of the 160 stimuli and extrapolate")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mien-bench-stimuli-") as tmp:
        folder = Path(tmp)
        small_path = folder / "small.toml"
        small_path.write_text(SMALL)
        small = load_design(small_path)
        make_stimuli(small, folder / "warm", progress=False)  # load heads and compile shaders once
        ours, base = [], []
        for r in range(REPEATS):
            start = time.perf_counter()
            make_stimuli(small, folder / f"ours{r}", progress=False)
            ours.append(time.perf_counter() - start)
            (folder / f"base{r}").mkdir()
            base.append(baseline_render_clip(small, folder / f"base{r}"))
        n = len(small.stimuli)
        print(f"per stimulus (3 s, 90 frames, 256 px), {n} stimuli, median of {REPEATS} interleaved repeats:")
        print(
            f"  make_stimuli          {statistics.median(ours) / n:6.2f} s  ({min(ours) / n:.2f}..{max(ours) / n:.2f})"
        )
        print(
            f"  baseline render_clip  {statistics.median(base) / n:6.2f} s  ({min(base) / n:.2f}..{max(base) / n:.2f})"
        )
        print(f"  ratio baseline / make_stimuli: {statistics.median(base) / statistics.median(ours):.2f}x")

        full_path = folder / "full.toml"
        full_path.write_text(FULL)
        design = load_design(full_path)
        if args.quick:
            from dataclasses import replace

            design = replace(design, stimuli=design.stimuli[::10])
        start = time.perf_counter()
        make_stimuli(design, folder / "full", progress=False)
        elapsed = time.perf_counter() - start
        total = elapsed * (160 / len(design.stimuli))
        label = "extrapolated from 16" if args.quick else "measured"
        print(f"full Broekens design: 160 stimuli in {total:.0f} s ({label}); budget {BUDGET_S:.0f} s; "
              f"ratio to budget {total / BUDGET_S:.2f} (< 1 passes)")  # fmt: skip


if __name__ == "__main__":
    main()
