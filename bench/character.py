"""Character stepping speed: one character, and 1,000 characters as a batch vs a Python loop.

Targets (issue 2): one character's step (FACS + emotions + idle) <= 20 us median; 1,000 characters as a
batch <= 2 ms median on one core and >= 20x faster than a Python loop over 1,000 single characters, both
measured here in the same run. Run: ``python bench/character.py``.

Since issue 8 a single :class:`Character` is a :class:`CharacterBatch` of one (one implementation, so the two
cannot drift): its step pays numpy's per-call overhead on one row, and the 20 us target of issue 2 is traded
for that (see ``bench/engine_tick.py`` for the server tick, the cost that matters live).
"""

from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")  # "on one core"
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from mien.character import Character, CharacterBatch

FPS = 60.0
N_BATCH = 1000


def busy_character(seed: int) -> Character:
    character = Character(seed=seed)
    character.set_au("AU4", 2.0)
    character.set_au("AU12", 3.0)
    return character


def single_step_us(repeats: int = 5, n_steps: int = 6000) -> list[float]:
    medians = []
    for r in range(repeats):
        character = busy_character(r)
        times = []
        for i in range(n_steps):
            if i % 90 == 0:  # a new emotion event every 1.5 s, overlapping the previous one
                character.emote(("joy", "anger", "surprise")[i // 90 % 3], 1.2)
            t0 = time.perf_counter()
            character.step(i / FPS)
            times.append(time.perf_counter() - t0)
        medians.append(statistics.median(times) * 1e6)
    return medians


def batch_step_ms(repeats: int = 5, n_steps: int = 300) -> list[float]:
    medians = []
    for r in range(repeats):
        batch = CharacterBatch(np.arange(N_BATCH) + r * N_BATCH)
        batch.set_au(slice(None), "AU4", 2.0)
        batch.set_au(slice(None), "AU12", 3.0)
        times = []
        for i in range(n_steps):
            if i % 90 == 0:
                batch.emote(slice(None), ("joy", "anger", "surprise")[i // 90 % 3], 1.2, start_s=i / FPS)
            t0 = time.perf_counter()
            batch.step(i / FPS)
            times.append(time.perf_counter() - t0)
        medians.append(statistics.median(times) * 1e3)
    return medians


def loop_step_ms(repeats: int = 3, n_steps: int = 30) -> list[float]:
    medians = []
    for r in range(repeats):
        characters = [busy_character(r * N_BATCH + k) for k in range(N_BATCH)]
        times = []
        for i in range(n_steps):
            if i % 90 == 0:
                for character in characters:
                    character.emote("joy", 1.2)
            t0 = time.perf_counter()
            for character in characters:
                character.step(i / FPS)
            times.append(time.perf_counter() - t0)
        medians.append(statistics.median(times) * 1e3)
    return medians


def main() -> None:
    single = statistics.median(single_step_us())
    batch = statistics.median(batch_step_ms())
    loop = statistics.median(loop_step_ms())
    print(f"one character step:          {single:8.2f} us median  (target <= 20 us: {20.0 / single:5.2f}x margin)")
    print(f"batch of {N_BATCH} step:          {batch:8.3f} ms median  (target <= 2 ms: {2.0 / batch:5.2f}x margin)")
    print(f"python loop over {N_BATCH} (baseline): {loop:8.3f} ms median")
    print(f"batch speed-up vs loop:       {loop / batch:8.1f}x  (target >= 20x)")


if __name__ == "__main__":
    main()
