"""200 simulated participants answering at once against one ``mien study serve`` process: every answer stored,
the 99th-percentile answer latency (target < 100 ms), against a named baseline measured in the same run.

Run: .venv/bin/python bench/study_server.py [--participants 200] [--no-postgres]

Each participant (an asyncio task sharing one httpx client) opens a session, gives consent, then for each
stimulus posts a play (``/api/show``) and, after a think time of 2-6 s (:data:`THINK_S`), its 11 ratings
(``/api/answer``, one committed transaction). Baseline ``health``: the bare FastAPI endpoint ``GET
/api/health`` (no database), requested by the same participants right before each answer, so both see the
same load. Prints p50/p99/max latency of both and their ratio, the answer handler's own time (its
``Server-Timing`` header: validation, commit and progress read, without queueing), the machine's load
average, and checks the database holds exactly every answer. Runs on SQLite, then on a PostgreSQL server
started in a temporary folder (when Debian's binaries are installed).
"""

from __future__ import annotations

import argparse
import asyncio
import os
import random
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DESIGN = """
[study]
name = "bench"
protocol = "broekens"
[stimuli]
expressions = ["joy", "sadness", "anger", "fear", "surprise", "disgust",
               "evil", "furious", "enthusiastic", "frustrated"]
heads = ["builtin"]
duration_s = 0.5
fps = 10
size = 32
"""


ARRIVAL_S = 10.0
"""Participants arrive at uniform random times over the first 10 s."""

THINK_S = (2.0, 6.0)
"""Seconds between a stimulus's play and its answer (uniform). People in the Broekens study took 15-30
minutes for 60 stimuli (15-30 s each); 2-6 s is 5x faster than that, so the load is pessimistic."""


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(q / 100 * (len(ordered) - 1)))]


async def participant(client, index: int, latencies: dict[str, list[float]], rng: random.Random) -> int:  # type: ignore[no-untyped-def]
    await asyncio.sleep(rng.uniform(0.0, ARRIVAL_S))
    session = (await client.post("/api/session", json={"participant": f"bench-{index}"})).json()
    await client.post("/api/consent", json={"participant": session["participant"]})
    ratings = {q["key"]: rng.randint(q["low"], q["high"]) for q in session["questions"]}
    stored = 0
    for item in session["sequence"]:
        await client.post(
            "/api/show", json={"participant": session["participant"], "stimulus": item["stimulus"], "nr_shows": 1}
        )
        await asyncio.sleep(rng.uniform(*THINK_S))
        start = time.perf_counter()
        reply = await client.get("/api/health")
        latencies["health"].append(time.perf_counter() - start)
        assert reply.status_code == 200
        body = {
            "participant": session["participant"],
            "stimulus": item["stimulus"],
            "position": item["position"],
            "ratings": ratings,
            "nr_shows": 1,
        }
        start = time.perf_counter()
        reply = await client.post("/api/answer", json=body)
        latencies["answer"].append(time.perf_counter() - start)
        assert reply.status_code == 200, reply.text
        latencies["server"].append(float(reply.headers["server-timing"].split("dur=")[1]) / 1000)
        stored += reply.json()["stored"]
    return stored


async def run_participants(url: str, n: int) -> tuple[dict[str, list[float]], int, float]:
    import httpx

    latencies: dict[str, list[float]] = {"health": [], "answer": [], "server": []}
    limits = httpx.Limits(max_connections=n, max_keepalive_connections=n)
    async with httpx.AsyncClient(base_url=url, limits=limits, timeout=30.0) as client:
        start = time.perf_counter()
        stored = await asyncio.gather(*(participant(client, k, latencies, random.Random(k)) for k in range(n)))
        return latencies, sum(stored), time.perf_counter() - start


def start_server(design: Path, db: str) -> tuple[subprocess.Popen[bytes], str]:
    import httpx

    from mien.ports import free_port

    port = free_port()
    command = [sys.executable, "-m", "mien.cli", "study", "serve", str(design), "--db", db, "--http-port", str(port)]
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise SystemExit(f"server failed: {process.stderr.read().decode() if process.stderr else ''}")
        try:
            if httpx.get(f"{url}/api/health", timeout=1).status_code == 200:
                return process, url
        except httpx.HTTPError:
            time.sleep(0.1)
    raise SystemExit("server did not start in 60 s")


def measure(name: str, design: Path, db: str, n: int, n_stimuli: int) -> None:
    from mien.study.storage import Store

    load = os.getloadavg()[0]
    process, url = start_server(design, db)
    try:
        latencies, stored, wall = asyncio.run(run_participants(url, n))
    finally:
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=30)
    with Store(db) as store:
        in_db = store.count_answers("bench")
    expected = n * n_stimuli * 11
    ms = {k: [v * 1000 for v in values] for k, values in latencies.items()}
    print(f"{name}: {n} participants x {n_stimuli} stimuli in {wall:.1f} s; answers stored {in_db}/{expected} "
          f"({'all' if in_db == expected == stored else 'MISSING'}); machine load average {load:.1f} -> "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")  # fmt: skip
    rows = (
        ("answer", "POST /api/answer (DB commit)"),
        ("health", "baseline GET /api/health (no DB)"),
        ("server", "answer handler alone (Server-Timing)"),
    )
    for key, label in rows:
        values = ms[key]
        print(f"  {label:34s} p50 {statistics.median(values):6.1f} ms  p99 {percentile(values, 99):6.1f} ms  "
              f"max {max(values):6.1f} ms  (n={len(values)})")  # fmt: skip
    p99 = percentile(ms["answer"], 99)
    print(f"  ratio p99 answer / p99 baseline: {p99 / percentile(ms['health'], 99):.2f}x; "
          f"p99 answer {'<' if p99 < 100 else '>='} 100 ms target")  # fmt: skip


def main() -> None:
    from mien.study._postgres import postgres_available, temporary_postgres
    from mien.study.design import load_design
    from mien.study.stimuli import make_stimuli

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--participants", type=int, default=200)
    parser.add_argument("--no-postgres", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mien-bench-server-") as tmp:
        folder = Path(tmp)
        design_path = folder / "design.toml"
        design_path.write_text(DESIGN)
        design = load_design(design_path)
        make_stimuli(design, progress=False)
        n_stimuli = len(design.stimuli)
        measure("SQLite", design_path, f"sqlite:///{folder / 'bench.sqlite'}", args.participants, n_stimuli)
        if args.no_postgres:
            return
        if not postgres_available():
            print("PostgreSQL: server binaries not found, skipped")
            return
        with temporary_postgres(prefix="mien-bench-pg-", max_connections=200) as url:
            measure("PostgreSQL", design_path, url, args.participants, n_stimuli)


if __name__ == "__main__":
    main()
