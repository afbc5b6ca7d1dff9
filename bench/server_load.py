"""Server tick cost: 100 characters at 60 Hz with 10 viewers, ten minutes of simulated time.

Target (issue 8): no tick over its budget (1/60 s) at the 99.9th percentile. The server's own tick
(:meth:`mien.server.scheduler.Clock.run_tick`: apply queued commands, step the one batch, encode a frame per
watched character and hand it to each viewer) runs 36,000 times back to back with simulated time; every tick
also parses and queues 20 OpenFACS datagrams (1,200 a second) and an emotion event, like a busy experiment.
Baseline in the same run: the engine step alone (``registry.step``), to show what the server adds.
Wall time includes time spent waiting for a CPU on a shared machine; thread CPU time is the tick's own work.
Repeats: 3 interleaved runs of 12,000 ticks (3 x 200 s = 10 minutes simulated); percentiles over all ticks,
spread = the runs' range. Run: ``python bench/server_load.py`` (``--minutes 1`` for a quick look).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from mien.client import openfacs_message
from mien.server.protocol import parse_message
from mien.server.registry import CharacterSpec, Registry
from mien.server.scheduler import Clock
from mien.server.websocket import Hub, Viewer

N_CHARACTERS = 100
N_VIEWERS = 10
TICK_HZ = 60.0
BUDGET_MS = 1000.0 / TICK_HZ


def build() -> tuple[Clock, Hub, list[str]]:
    registry = Registry()
    ids = [f"c{i:03d}" for i in range(N_CHARACTERS)]
    for i, character_id in enumerate(ids):
        registry.add(CharacterSpec(character_id, head="builtin", seed=i, idle=True))
    clock = Clock(registry, TICK_HZ)
    hub = Hub(registry)
    clock.listeners.append(hub.on_tick)
    for v in range(N_VIEWERS):
        hub.viewers.add(Viewer(ids[v * 7 % N_CHARACTERS]))
    return clock, hub, ids


def run(clock: Clock, hub: Hub, ids: list[str], n_ticks: int, engine_only: bool) -> tuple[np.ndarray, np.ndarray]:
    """(wall ms, thread CPU ms) per tick."""
    rng = np.random.default_rng(len(ids))
    datagrams = [
        openfacs_message({"AU12": int(rng.integers(0, 6)), "AU4": float(rng.integers(0, 50)) / 10}, 0.05, character=c)
        for c in ids
    ]
    costs = np.empty(n_ticks)
    cpu = np.empty(n_ticks)
    start_tick = clock.tick
    for k in range(n_ticks):
        tick = start_tick + k
        t_s = tick / TICK_HZ
        begin = time.perf_counter()
        cpu_begin = time.thread_time()
        for j in range(20):  # what the UDP handler does for 20 datagrams
            clock.registry.submit(parse_message(datagrams[(tick * 20 + j) % len(datagrams)]))
        if k % 60 == 0:
            clock.registry.submit(parse_message(b'{"emotion": "joy", "intensity": 1.2, "character": "c001"}'))
        if engine_only:
            clock.registry.step(t_s)
        else:
            clock.run_tick(tick, t_s)
            for viewer in hub.viewers:  # the viewers' send tasks take the frame
                viewer.latest = None
                viewer.ready.clear()
        costs[k] = time.perf_counter() - begin
        cpu[k] = time.thread_time() - cpu_begin
    clock.tick = start_tick + n_ticks
    return costs * 1e3, cpu * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="simulated minutes (default 10)")
    args = parser.parse_args()
    n_ticks = int(args.minutes * 60 * TICK_HZ / 3)
    clock, hub, ids = build()
    engine_clock, engine_hub, engine_ids = build()
    server_runs, engine_runs, server_cpu_runs, engine_cpu_runs = [], [], [], []
    for _ in range(3):
        wall, cpu = run(clock, hub, ids, n_ticks, engine_only=False)
        server_runs.append(wall)
        server_cpu_runs.append(cpu)
        wall, cpu = run(engine_clock, engine_hub, engine_ids, n_ticks, engine_only=True)
        engine_runs.append(wall)
        engine_cpu_runs.append(cpu)
    server, engine = np.concatenate(server_runs), np.concatenate(engine_runs)
    server_cpu, engine_cpu = np.concatenate(server_cpu_runs), np.concatenate(engine_cpu_runs)
    print(f"{N_CHARACTERS} characters, {N_VIEWERS} viewers, {TICK_HZ:g} Hz, {len(server)} ticks "
          f"({len(server) / TICK_HZ / 60:.1f} simulated minutes), budget {BUDGET_MS:.2f} ms per tick")  # fmt: skip
    rows = (
        ("server tick, wall", server, server_runs),
        ("server tick, thread CPU", server_cpu, server_cpu_runs),
        ("engine step alone, wall", engine, engine_runs),
        ("engine step alone, thread CPU", engine_cpu, engine_cpu_runs),
    )
    for name, costs, runs in rows:
        p = {q: float(np.percentile(costs, q)) for q in (50, 99, 99.9)}
        spread = [float(np.percentile(r, 99.9)) for r in runs]
        print(
            f"{name:30s} p50 {p[50]:6.3f} ms  p99 {p[99]:6.3f} ms  p99.9 {p[99.9]:6.3f} ms "
            f"(runs {min(spread):.3f}..{max(spread):.3f})  max {costs.max():6.3f} ms  "
            f"over budget: {int((costs > BUDGET_MS).sum())}"
        )
    p999 = float(np.percentile(server, 99.9))
    p999_cpu = float(np.percentile(server_cpu, 99.9))
    print(f"p99.9 tick / budget: wall {p999 / BUDGET_MS:.3f}, thread CPU {p999_cpu / BUDGET_MS:.3f} (target < 1)")
    print(f"load average now: {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (wall includes waiting for a CPU)")
    print(f"server tick / engine step (median): {statistics.median(server) / statistics.median(engine):.2f}x")


if __name__ == "__main__":
    main()
