"""Server tick while characters talk: 100 characters, every one saying a sentence (issue 32, live server).

Two registries of 100 built-in characters (idle on) are stepped tick by tick on the same 60 Hz timeline,
their ticks interleaved (the order flips every tick) and compared on the ticks where at least 80 % of the
characters talk: **silent** (the named baseline: the same server with no ``say``) and **talking** (every
character gets a ``say`` of a 4-5 s sentence through :func:`mien.server.protocol.parse_message` and
:meth:`Registry.submit`, fed to the TTS worker as its queue frees; espeak-ng runs in the worker thread, so each
tick only starts the utterances the worker finished and steps the speech layer). Printed: the median and p99
tick cost of each, their ratio, and the largest tick cost of the ticks that started utterances. Repeats: 3
runs; the spread is the runs' range. Thread CPU time is the tick's own work (the worker's synthesis runs on
another thread). ``python bench/server_say.py [--seconds 7]``.
"""

from __future__ import annotations

import argparse
import json
import os
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from mien.server.protocol import parse_message
from mien.server.registry import CharacterSpec, Registry
from mien.server.speech import MAX_PENDING_SAYS

N_CHARACTERS = 100
TICK_HZ = 60.0
SENTENCES = (
    "my mama made a map of the town, and the town was made of paper and string",
    "the quick brown fox jumps over the lazy dog, and the dog does not mind at all",
    "please bring me the paper before noon, or the editor will be very cross",
    "we will meet again at the old bridge, when the river is low and the sun is up",
)
"""Sentences of 4-5 s: one TTS worker starts them all within about 3 s, so most characters talk at once."""
CROWD = 0.8
"""Ticks compared: those where at least this share of the characters is talking."""


def _registry() -> Registry:
    registry = Registry()
    for i in range(N_CHARACTERS):
        registry.add(CharacterSpec(f"c{i}", head="builtin", seed=i))
    registry.warm_up()
    return registry


def _tick(registry: Registry, t_s: float) -> float:
    begin = time.thread_time()
    registry.step(t_s)
    return time.thread_time() - begin


def run(seconds: float) -> dict[str, float]:
    silent, talking = _registry(), _registry()
    waiting = [f"c{i}" for i in range(N_CHARACTERS)]
    costs: dict[str, list[float]] = {"silent": [], "talking": []}
    starting: list[float] = []
    talkers: list[int] = []
    for tick in range(int(seconds * TICK_HZ)):
        t_s = tick / TICK_HZ
        while waiting and talking.speech.pending() < MAX_PENDING_SAYS:
            character = waiting.pop()
            text = SENTENCES[len(waiting) % len(SENTENCES)]
            talking.submit(parse_message(json.dumps({"say": text, "character": character}).encode()))
        spoken_before = talking.speech.spoken
        order = (("silent", silent), ("talking", talking)) if tick % 2 else (("talking", talking), ("silent", silent))
        for name, registry in order:
            costs[name].append(_tick(registry, t_s))
        if talking.speech.spoken > spoken_before:
            starting.append(costs["talking"][-1])
        talkers.append(int((talking.batch.speech.presence > 0).sum()))
        time.sleep(max(0.0, 1.0 / TICK_HZ - 0.002))  # let the TTS worker run, as the real clock does
    crowd = np.array(talkers) >= CROWD * N_CHARACTERS
    quiet = np.array(costs["silent"])[crowd] * 1e3
    busy = np.array(costs["talking"])[crowd] * 1e3
    return {
        "ticks_compared": float(crowd.sum()),
        "most_talking": float(max(talkers)),
        "silent_median_ms": float(np.median(quiet)),
        "talking_median_ms": float(np.median(busy)),
        "silent_p99_ms": float(np.percentile(quiet, 99)),
        "talking_p99_ms": float(np.percentile(busy, 99)),
        "ratio_median": float(np.median(busy) / np.median(quiet)),
        "max_starting_tick_ms": float(max(starting) * 1e3) if starting else float("nan"),
        "utterances_started": float(talking.speech.spoken),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=7.0, help="simulated seconds per run (default 7)")
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    results = [run(args.seconds) for _ in range(args.runs)]
    print(f"{N_CHARACTERS} characters, {args.seconds:g} s at {TICK_HZ:g} Hz, {args.runs} runs (thread CPU time)")
    for key in results[0]:
        values = [r[key] for r in results]
        print(f"  {key:22s} median {np.median(values):8.3f}  range {min(values):8.3f} .. {max(values):8.3f}")
    ratio = np.median([r["ratio_median"] for r in results])
    print(f"talking / silent (median tick): {ratio:.2f}x")


if __name__ == "__main__":
    main()
