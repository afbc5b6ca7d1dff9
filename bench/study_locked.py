"""A study server whose SQLite database another program holds locked: how long a request waits before its
first answer, against the named baseline ``bound`` (the server's ``--busy-timeout``), what the health says,
and that every answer is stored once the lock is gone (answers lost must be 0).

Run: .venv/bin/python bench/study_locked.py [--participants 20] [--hold 12] [--busy-timeout 3]

Each participant opens a session, gives consent and plays its first stimulus; then another process takes the
database's write lock (``BEGIN EXCLUSIVE``) for ``--hold`` seconds while every participant posts its first
answer at once and retries it after each 503 as the page does (after ``Retry-After``) until it is stored. A
read-only page (``POST /api/session`` of a known participant) and ``GET /api/health`` are timed during the
lock. Prints the longest wait for a first reply and its ratio to the bound (1.0 = the bound held), the
statuses seen, and the answers stored against those given. A server without ``--busy-timeout`` (an older
mien) is started without it.
"""

from __future__ import annotations

import argparse
import asyncio
import signal
import sqlite3
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DESIGN = """
[study]
name = "locked"
protocol = "broekens"
[stimuli]
expressions = ["joy", "anger"]
heads = ["builtin"]
duration_s = 0.4
fps = 5
size = 32
"""


def start_server(design: Path, db: Path, busy_timeout_s: float) -> tuple[subprocess.Popen[bytes], str]:
    import httpx

    from mien.ports import free_port

    port = free_port()
    command = [sys.executable, "-m", "mien.cli", "study", "serve", str(design), "--db", str(db),
               "--http-port", str(port)]  # fmt: skip
    help_text = subprocess.run([*command[:4], "--help"], capture_output=True, text=True).stdout
    if "--busy-timeout" in help_text:
        command += ["--busy-timeout", str(busy_timeout_s)]
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


async def run(url: str, db: Path, n: int, hold_s: float) -> dict[str, object]:
    import httpx

    limits = httpx.Limits(max_connections=n + 4, max_keepalive_connections=n + 4)
    async with httpx.AsyncClient(base_url=url, limits=limits, timeout=300.0) as client:
        bodies = []
        for k in range(n):
            session = (await client.post("/api/session", json={"participant": f"L{k}"})).json()
            await client.post("/api/consent", json={"participant": f"L{k}"})
            first = session["sequence"][0]["stimulus"]
            await client.post("/api/show", json={"participant": f"L{k}", "stimulus": first, "nr_shows": 1})
            ratings = {q["key"]: 3 for q in session["questions"]}
            bodies.append({"participant": f"L{k}", "stimulus": first, "position": 0, "ratings": ratings,
                           "nr_shows": 1})  # fmt: skip
        first_reply: list[float] = []
        statuses: dict[int, int] = {}
        stored = 0

        async def answer(body: dict) -> None:
            nonlocal stored
            start, timed = time.perf_counter(), False
            while True:
                reply = await client.post("/api/answer", json=body)
                if not timed:
                    first_reply.append(time.perf_counter() - start)
                    timed = True
                statuses[reply.status_code] = statuses.get(reply.status_code, 0) + 1
                if reply.status_code == 200:
                    stored += reply.json()["stored"]
                    return
                await asyncio.sleep(float(reply.headers.get("Retry-After", "1")))

        async def probe(path: str, json: dict | None = None) -> tuple[float, int, dict]:
            start = time.perf_counter()
            reply = await (client.post(path, json=json) if json is not None else client.get(path))
            return time.perf_counter() - start, reply.status_code, reply.json()

        blocker = sqlite3.connect(db, timeout=5)
        blocker.execute("BEGIN EXCLUSIVE")
        locked_at = time.perf_counter()
        answers = [asyncio.create_task(answer(b)) for b in bodies]
        await asyncio.sleep(min(1.0, hold_s / 4))
        page = asyncio.create_task(probe("/api/session", {"participant": "L0"}))  # the lock ends on time anyway
        await asyncio.sleep(max(0.0, min(hold_s, 4.0) - (time.perf_counter() - locked_at)))
        health = asyncio.create_task(probe("/api/health"))
        await asyncio.sleep(max(0.0, hold_s - (time.perf_counter() - locked_at)))
        blocker.rollback()
        blocker.close()
        await asyncio.gather(*answers)
        page_result, health_result = await page, await health
        after = await probe("/api/health")
        return {"first_reply": first_reply, "statuses": statuses, "stored": stored, "page": page_result,
                "health": health_result, "after": after}  # fmt: skip


def main() -> None:
    from mien.study.design import load_design
    from mien.study.stimuli import make_stimuli
    from mien.study.storage import Store, database_url

    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--participants", type=int, default=20)
    parser.add_argument("--hold", type=float, default=12.0, help="seconds the lock is held")
    parser.add_argument("--busy-timeout", type=float, default=3.0, help="the server's bound, seconds")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mien-bench-locked-") as tmp:
        folder = Path(tmp)
        design_path = folder / "design.toml"
        design_path.write_text(DESIGN)
        make_stimuli(load_design(design_path), progress=False)
        db = folder / "locked.sqlite"
        process, url = start_server(design_path, db, args.busy_timeout)
        try:
            result = asyncio.run(run(url, db, args.participants, args.hold))
        finally:
            process.send_signal(signal.SIGTERM)
            process.wait(timeout=30)
            if process.stderr is not None:
                process.stderr.close()
        with Store(database_url(db, db)) as store:
            in_db = store.count_answers("locked")
    first = result["first_reply"]
    assert isinstance(first, list)
    expected = args.participants * 11
    page_s, page_status, _ = result["page"]  # type: ignore[misc]
    health_s, _, health = result["health"]  # type: ignore[misc]
    _, _, after = result["after"]  # type: ignore[misc]
    print(f"SQLite locked by another process for {args.hold:g} s; {args.participants} participants answer during it; "
          f"baseline 'bound' = --busy-timeout {args.busy_timeout:g} s")  # fmt: skip
    print(f"  first reply to an answer: max {max(first):.2f} s, median {sorted(first)[len(first) // 2]:.2f} s "
          f"-> ratio max / bound {max(first) / args.busy_timeout:.2f}")  # fmt: skip
    print(f"  replies: {dict(sorted(result['statuses'].items()))} (503 = refused with Retry-After, retried)")  # type: ignore[attr-defined]
    print(f"  read-only page during the lock: {page_status} in {page_s:.2f} s")
    status, database = health.get("status", "(none)"), health.get("database", "(not reported)")
    print(f"  health during the lock ({health_s * 1000:.1f} ms): status {status!r}, database {database!r}; "
          f"after: {after.get('status', '(none)')!r}")  # fmt: skip
    print(f"  answers stored {in_db}/{expected}; lost {expected - in_db}")
    print("  first replies, s:", " ".join(f"{t:.2f}" for t in sorted(first)))


if __name__ == "__main__":
    main()
