"""OpenFACS UDP ingest: datagrams per second into ``mien serve`` from one client, and parse cost per datagram.

Targets (issue 8): at least 20,000 OpenFACS datagrams per second from one client with no valid datagram lost;
parse cost per datagram against ``json.loads`` alone (baseline, same run). The server runs in a child process
(``mien serve``); the client sends exact OpenFACS datagrams (the 18 AUs, integers, Speed) paced at a target
rate, and the server's /api/health counts what it accepted. Repeats: 3 interleaved runs per rate; medians
with the range. Run: ``python bench/server_udp.py``.
"""

from __future__ import annotations

import json
import socket
import statistics
import sys
import time
from pathlib import Path

import orjson

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _live_server import health, live_server

from mien.client import openfacs_message
from mien.server.protocol import parse_message

N_DATAGRAMS = 60_000
RATES = (20_000, 30_000, 50_000)


def datagrams(n: int) -> list[bytes]:
    return [openfacs_message({"AU4": i % 6, "AU12": (i // 6) % 6, "AU26": i % 3}, 0.05) for i in range(n)]


def parse_costs_us(repeats: int = 5, n: int = 20_000) -> dict[str, list[float]]:
    data = datagrams(n)
    out: dict[str, list[float]] = {"json.loads": [], "orjson.loads": [], "parse_message": []}
    functions = {"json.loads": json.loads, "orjson.loads": orjson.loads, "parse_message": parse_message}
    for _ in range(repeats):
        for name, function in functions.items():
            begin = time.perf_counter()
            for d in data:
                function(d)
            out[name].append((time.perf_counter() - begin) / n * 1e6)
    return out


def send_paced(port: int, data: list[bytes], rate: float) -> float:
    """Send every datagram at ``rate`` per second (bursts of 1 ms); returns the achieved rate."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    address = ("127.0.0.1", port)
    per_ms = max(1, int(rate / 1000))
    begin = time.perf_counter()
    for start in range(0, len(data), per_ms):
        for d in data[start : start + per_ms]:
            sock.sendto(d, address)
        due = begin + (start + per_ms) / rate
        while time.perf_counter() < due:
            pass
    elapsed = time.perf_counter() - begin
    sock.close()
    return len(data) / elapsed


def ingest(udp: int, http: int, rate: float) -> tuple[float, int, int]:
    """(achieved send rate, accepted, lost) for one paced run."""
    data = datagrams(N_DATAGRAMS)
    before = health(http)
    achieved = send_paced(udp, data, rate)
    deadline = time.monotonic() + 10
    after = health(http)
    while after["datagrams_received"] - before["datagrams_received"] < N_DATAGRAMS and time.monotonic() < deadline:
        time.sleep(0.2)
        after = health(http)
    accepted = after["datagrams_accepted"] - before["datagrams_accepted"]
    return achieved, accepted, N_DATAGRAMS - accepted


def main() -> None:
    costs = parse_costs_us()
    base = statistics.median(costs["json.loads"])
    for name, values in costs.items():
        median = statistics.median(values)
        print(
            f"{name:14s} {median:6.2f} us per datagram (range {min(values):.2f}..{max(values):.2f}), "
            f"{median / base:5.2f}x json.loads"
        )
    with live_server("--head", "builtin", "--no-idle") as (udp, http):
        results: dict[int, list[tuple[float, int, int]]] = {rate: [] for rate in RATES}
        for _ in range(3):
            for rate in RATES:
                results[rate].append(ingest(udp, http, rate))
        final = health(http)
    for rate, runs in results.items():
        achieved = [r[0] for r in runs]
        lost = [r[2] for r in runs]
        print(
            f"paced at {rate:6d}/s: sent {statistics.median(achieved):8.0f}/s (range {min(achieved):.0f}.."
            f"{max(achieved):.0f}), {N_DATAGRAMS} per run, lost {statistics.median(lost):.0f} (max {max(lost)}) "
            f"-> {statistics.median(achieved) / 20_000:.2f}x the 20,000/s target"
        )
    print(f"server after the runs: ticks {final['ticks']}, late ticks {final['late_ticks']}, rejections "
          f"{final['rejections']}")  # fmt: skip


if __name__ == "__main__":
    main()
