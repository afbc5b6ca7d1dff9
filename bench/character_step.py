"""One character's step with idle on, and 10,000 characters as a batch: now vs before the batch of one was made cheap.

Issue 27 asks: one ``Character.step`` at 60 Hz with idle on at most 30 us median and 100 us at the 99.9th
percentile, with 10,000 characters still at or under the baseline's cost per character.

Named baseline, measured in the same run and interleaved step by step: the engine code at git
BASELINE_COMMIT (``mien.character`` with its idle, counter-based random, dynamics and emotion modules,
loaded from git into a temporary package ``mien_before``; the modules it shares with today's code come from
the working tree). Both sides step the same seeds at the same times, so their frames are compared too.

Run ``python bench/character_step.py``; ``--steps`` and ``--repeats`` shorten it. Each repeat makes fresh
characters; percentiles are over every step of every repeat, the spread is min..max of the repeats' values.
Times are wall-clock (what a live loop sees, the OS preempting this process on a busy machine included) and
the process's CPU time (what the code costs, preemption excluded).
"""

from __future__ import annotations

import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

BASELINE_COMMIT = "5c169d4379587e6e0e2c3cbed29ea471c1fd01c7"
"""The last commit before issue 27's one engine (Character a hand-written facade over a one-row batch)."""

FPS = 60.0
N_CROWD = 10_000
REPO = Path(__file__).resolve().parents[1]
_RENAMES = {
    "mien.facs.counter_random": "mien_before.counter_random",
    "mien.facs.idle": "mien_before.idle",
    "mien.facs.dynamics": "mien_before.dynamics",
    "mien.affect.engine": "mien_before.engine",
    "mien.character": "mien_before.character",
}


def load_baseline() -> ModuleType:
    """``mien.character`` of BASELINE_COMMIT with its engine modules, as ``mien_before.character``."""
    folder = Path(tempfile.mkdtemp(prefix="mien_before_"))
    package = folder / "mien_before"
    package.mkdir()
    (package / "__init__.py").write_text("")
    for module, new in _RENAMES.items():
        path = "src/" + module.replace(".", "/") + ".py"
        text = subprocess.run(
            ["git", "show", f"{BASELINE_COMMIT}:{path}"], cwd=REPO, check=True, capture_output=True, text=True
        ).stdout
        for old_name, new_name in _RENAMES.items():
            text = text.replace(f"from {old_name} import", f"from {new_name} import")
        (package / f"{new.split('.')[1]}.py").write_text(text)
    sys.path.insert(0, str(folder))
    return importlib.import_module("mien_before.character")


def one_character(n_steps: int, seed: int, before: ModuleType) -> tuple[np.ndarray, float]:
    """(4, n_steps) seconds per step: wall new, wall baseline, CPU new, CPU baseline; and max |frame difference|."""
    from mien.character import Character

    new, old = Character(seed=seed), before.Character(seed=seed)
    times = np.empty((4, n_steps))
    worst = 0.0
    clock, cpu = time.perf_counter, time.process_time
    for i in range(n_steps):
        t = i / FPS
        t0, c0 = clock(), cpu()
        frame = new.step(t)
        t1, c1 = clock(), cpu()
        old_frame = old.step(t)
        t2, c2 = clock(), cpu()
        times[:, i] = (t1 - t0, t2 - t1, c1 - c0, c2 - c1)
        if i % 60 == 0:
            worst = max(worst, float(np.abs(frame - old_frame).max()))
    return times, worst


def crowd(n_steps: int, seed: int, before: ModuleType) -> tuple[np.ndarray, float]:
    """(2, n_steps) seconds per step of N_CROWD characters (idle on), new and baseline; max |frame difference|."""
    from mien.character import CharacterBatch

    seeds = np.arange(N_CROWD) + seed * N_CROWD
    new, old = CharacterBatch(seeds), before.CharacterBatch(seeds)
    times = np.empty((2, n_steps))
    worst = 0.0
    for i in range(n_steps):
        t = i / FPS
        t0 = time.perf_counter()
        frames = new.step(t)
        t1 = time.perf_counter()
        old_frames = old.step(t)
        t2 = time.perf_counter()
        times[:, i] = (t1 - t0, t2 - t1)
        worst = max(worst, float(np.abs(frames - old_frames).max()))
    return times, worst


def _stats_us(times_s: np.ndarray) -> tuple[float, float, float]:
    us = times_s * 1e6
    return float(np.median(us)), float(np.percentile(us, 99)), float(np.percentile(us, 99.9))


def _line(name: str, runs: list[np.ndarray]) -> tuple[float, float, float]:
    pooled = _stats_us(np.concatenate(runs))
    each = np.array([_stats_us(run) for run in runs])
    spread = "  ".join(f"{each[:, k].min():.1f}..{each[:, k].max():.1f}" for k in range(3))
    print(
        f"  {name:34s} median {pooled[0]:7.1f}  p99 {pooled[1]:7.1f}  p99.9 {pooled[2]:7.1f} us"
        f"   (repeats: {spread})"
    )
    return pooled


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=6000, help="steps of one character per repeat (60 Hz)")
    parser.add_argument("--crowd-steps", type=int, default=40, help="steps of the 10,000 per repeat")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    before = load_baseline()
    single: list[np.ndarray] = []
    many: list[np.ndarray] = []
    worst_one = worst_many = 0.0
    started = time.perf_counter()
    for r in range(args.repeats):  # the two parts alternate too, so slow phases of a busy machine hit both
        times, worst = one_character(args.steps, seed=1 + r, before=before)
        single.append(times)
        worst_one = max(worst_one, worst)
        crowd_times, worst = crowd(args.crowd_steps, seed=r, before=before)
        many.append(crowd_times[:, 1:])  # the first step fills caches
        worst_many = max(worst_many, worst)
    elapsed = time.perf_counter() - started
    print(
        f"character step: {args.repeats} repeats x {args.steps} steps of one character at {FPS:g} Hz (idle on), "
        f"{args.repeats} x {args.crowd_steps - 1} steps of {N_CROWD:,} characters; {os.cpu_count()} CPUs, "
        f"load {os.getloadavg()[0]:.1f}, {elapsed:.0f} s"
    )
    print(f"baseline = git {BASELINE_COMMIT[:8]} (the engine modules before this change), interleaved step by step")
    print("one Character.step, wall-clock:")
    new = _line("new (a batch of one)", [t[0] for t in single])
    old = _line("baseline", [t[1] for t in single])
    print("one Character.step, CPU time (preemption excluded):")
    new_cpu = _line("new (a batch of one)", [t[2] for t in single])
    old_cpu = _line("baseline", [t[3] for t in single])
    for label, n, o in (("wall", new, old), ("CPU", new_cpu, old_cpu)):
        print(
            f"  {label:4s} baseline / new: median {o[0] / n[0]:5.2f}x  p99 {o[1] / n[1]:5.2f}x  "
            f"p99.9 {o[2] / n[2]:5.2f}x;"
            f"  targets median <= 30 us: {'met' if n[0] <= 30 else 'NOT met'}, "
            f"p99.9 <= 100 us: {'met' if n[2] <= 100 else 'NOT met'}"
        )
    per_new = [t[0] / N_CROWD for t in many]
    per_old = [t[1] / N_CROWD for t in many]
    print(f"{N_CROWD:,} characters, CharacterBatch.step per character, wall-clock:")
    crowd_new = _line("new", per_new)
    crowd_old = _line("baseline", per_old)
    print(
        f"  baseline / new: median {crowd_old[0] / crowd_new[0]:5.2f}x "
        f"(target: new <= baseline: {'met' if crowd_new[0] <= crowd_old[0] else 'NOT met'})"
    )
    print(
        f"largest |new - baseline| frame value: one character {worst_one:.3g}, {N_CROWD:,} characters {worst_many:.3g}"
    )


if __name__ == "__main__":
    main()
