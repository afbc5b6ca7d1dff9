"""Server tick with OpenFACS traffic: 100 characters receiving 20 full-state messages a tick (issue 27).

Each tick parses and queues 20 OpenFACS datagrams (the 18 AUs of the original client plus ``Speed``, to random
characters), then runs :meth:`mien.server.scheduler.Clock.run_tick` (apply the queued states, step the one
batch of 100 idle characters, encode a frame for each of 10 viewers). Target: p99.9 tick at most 3 ms.

Named baseline, measured in the same run: the code before issue 27's change, i.e. the parser of git
BASELINE_COMMIT (loaded from git; a message with a ``character`` id took its full per-key path) and the per-AU
apply path the registry used (``set_aus`` re-parsing every AU name with a regular expression and writing it
alone, then ``set_speed``), kept here as :class:`PerAuRegistry`. Both servers get the same datagrams; their
ticks are interleaved (the order flips every tick) and their frames are compared on every tick. Repeats: 3
runs; the spread is the runs' range of the p99.9. Wall time includes waiting for a CPU on a shared machine;
thread CPU time is the tick's own work. Run ``python bench/server_tick.py`` (``--ticks`` per run, default 2000).
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from mien.client import openfacs_message
from mien.facs.catalogue import OPENFACS_AUS
from mien.server.protocol import Message, parse_message
from mien.server.registry import CharacterSpec, Entry, Registry
from mien.server.scheduler import Clock
from mien.server.websocket import Hub, Viewer

BASELINE_COMMIT = "5c169d4379587e6e0e2c3cbed29ea471c1fd01c7"
"""The last commit before the server's one-write state path (issue 27)."""

REPO = Path(__file__).resolve().parents[1]
N_CHARACTERS = 100
N_MESSAGES = 20
N_VIEWERS = 10
TICK_HZ = 60.0
TARGET_MS = 3.0


class PerAuRegistry(Registry):
    """The baseline: each state message applied alone through the per-AU path (as before issue 27)."""

    def _apply_states(self, states: list[tuple[Entry, Message]]) -> None:
        for entry, message in states:
            aus = dict(message.aus or ())
            self.batch.set_aus(entry.row, aus, replace=True)
            if message.speed is not None:
                self.batch.set_speed(entry.row, message.speed)


def load_baseline_parser() -> Callable[[bytes], Any]:
    """``parse_message`` of :data:`BASELINE_COMMIT`'s ``mien/server/protocol.py``, as module ``protocol_before``."""
    text = subprocess.run(
        ["git", "show", f"{BASELINE_COMMIT}:src/mien/server/protocol.py"],
        cwd=REPO, check=True, capture_output=True, text=True,
    ).stdout  # fmt: skip
    path = Path(tempfile.mkdtemp(prefix="mien_before_")) / "protocol_before.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("protocol_before", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["protocol_before"] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module.parse_message  # type: ignore[no-any-return]


def build(registry: Registry) -> tuple[Clock, Hub]:
    for i in range(N_CHARACTERS):
        registry.add(CharacterSpec(f"c{i:03d}", head="builtin", seed=i, idle=True))
    clock = Clock(registry, TICK_HZ)
    hub = Hub(registry)
    clock.listeners.append(hub.on_tick)
    for v in range(N_VIEWERS):
        hub.viewers.add(Viewer(f"c{v * 7 % N_CHARACTERS:03d}"))
    return clock, hub


def one_tick(
    clock: Clock, hub: Hub, parse: Callable[[bytes], Any], datagrams: list[bytes], tick: int
) -> tuple[float, float]:
    """(wall, thread CPU) seconds of one tick: parse and queue the datagrams, run the tick, the viewers take
    their frame."""
    begin, cpu = time.perf_counter(), time.thread_time()
    for data in datagrams:
        clock.registry.submit(parse(data))
    clock.run_tick(tick, tick / TICK_HZ)
    for viewer in hub.viewers:
        viewer.latest = None
        viewer.ready.clear()
    return time.perf_counter() - begin, time.thread_time() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=2000, help="ticks per run (default 2000)")
    args = parser.parse_args()
    rng = np.random.default_rng(27)
    pool = [
        openfacs_message(
            {f"AU{code}": int(v) for code, v in zip(OPENFACS_AUS, rng.integers(0, 6, len(OPENFACS_AUS)), strict=True)},
            0.05,
            character=f"c{int(rng.integers(N_CHARACTERS)):03d}",
        )
        for _ in range(997)
    ]
    new_clock, new_hub = build(Registry())
    old_clock, old_hub = build(PerAuRegistry())
    old_parse = load_baseline_parser()
    runs: dict[str, list[np.ndarray]] = {"new": [], "old": [], "new_cpu": [], "old_cpu": []}
    identical = True
    tick = 0
    for _ in range(3):
        new_s, old_s = np.empty((args.ticks, 2)), np.empty((args.ticks, 2))
        for k in range(args.ticks):
            datagrams = [pool[(tick * N_MESSAGES + j) % len(pool)] for j in range(N_MESSAGES)]
            if tick % 2:
                old_s[k] = one_tick(old_clock, old_hub, old_parse, datagrams, tick)
                new_s[k] = one_tick(new_clock, new_hub, parse_message, datagrams, tick)
            else:
                new_s[k] = one_tick(new_clock, new_hub, parse_message, datagrams, tick)
                old_s[k] = one_tick(old_clock, old_hub, old_parse, datagrams, tick)
            identical = identical and np.array_equal(new_clock.registry.frames, old_clock.registry.frames)
            tick += 1
        for key, values in (("new", new_s), ("old", old_s)):
            runs[key].append(values[:, 0] * 1e3)
            runs[f"{key}_cpu"].append(values[:, 1] * 1e3)
    print(
        f"{N_CHARACTERS} characters (idle on), {N_MESSAGES} OpenFACS messages of 18 AUs a tick, {N_VIEWERS} viewers, "
        f"{TICK_HZ:g} Hz, 3 interleaved runs of {args.ticks} ticks"
    )
    rows = (
        ("new", "new: one write per tick, wall"),
        ("old", "baseline: before (per-AU), wall"),
        ("new_cpu", "new: one write per tick, thread CPU"),
        ("old_cpu", "baseline: before (per-AU), thread CPU"),
    )
    median, p999 = {}, {}
    for key, name in rows:
        ms = np.concatenate(runs[key])
        p = {q: float(np.percentile(ms, q)) for q in (50, 99, 99.9)}
        spread = [float(np.percentile(r, 99.9)) for r in runs[key]]
        median[key], p999[key] = p[50], p[99.9]
        print(
            f"  {name:38s} median {p[50]:6.3f} ms  p99 {p[99]:6.3f} ms  p99.9 {p[99.9]:6.3f} ms "
            f"(runs {min(spread):.3f}..{max(spread):.3f})  max {ms.max():6.3f} ms"
        )
    for kind, new, old in (("wall", "new", "old"), ("thread CPU", "new_cpu", "old_cpu")):
        verdict = "met" if p999[new] <= TARGET_MS else "NOT met"
        print(
            f"baseline / new, {kind}: median {median[old] / median[new]:.2f}x, p99.9 {p999[old] / p999[new]:.2f}x; "
            f"new p99.9 {p999[new]:.3f} ms vs target {TARGET_MS:.1f} ms: {verdict}"
        )
    print(f"frames identical to the baseline on every tick: {identical}")
    print(f"load average now: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (wall includes waiting for a CPU)")


if __name__ == "__main__":
    main()
