"""Hostile input against a live ``mien serve`` (issue 29, cases 3, 4, 5, 7): what each attack gets, the clock's
tick rate while it runs, the longest gap between two frames a viewer saw, and the server's memory (RSS).

The server runs in a child process (``mien serve --head builtin``, one character, 60 Hz). The tick rate is the
server's own count (``ticks`` of ``/api/health``) over the attack's window; a WebSocket viewer times its frames
(the longest gap is how long every face stood still). The baseline is the same server at rest, measured in the
same run: each attack prints its tick rate as a ratio to it. The payloads are made before any window opens.
Every attack is bounded (size and time) and stays on 127.0.0.1.

    python bench/server_hostile.py            # every attack
    python bench/server_hostile.py csv npz    # the named ones
    PYTHONPATH=/tmp/old/src python bench/server_hostile.py   # another checkout's server (git archive REV src)
"""

from __future__ import annotations

import functools
import io
import itertools
import json
import re
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import httpx
import numpy as np

WINDOW_S = 1.0
"""Seconds measured at rest (the baseline) and at least this long around each attack."""


@contextmanager
def live_server() -> Iterator[tuple[subprocess.Popen[str], int, int]]:
    """``mien serve`` on free ports in a child process; yields (process, udp_port, http_port)."""
    command = [sys.executable, "-m", "mien.cli", "serve", "--udp-port", "0", "--http-port", "0", "--head", "builtin"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        udp = http = 0
        assert process.stdout is not None
        deadline = time.monotonic() + 60
        while (not udp or not http) and time.monotonic() < deadline:
            line = process.stdout.readline()
            if not line:
                raise RuntimeError("mien serve exited before printing its ports")
            if match := re.search(r"UDP on [^:]+:(\d+)", line):
                udp = int(match.group(1))
            if match := re.search(r"HTTP on http://[^:]+:(\d+)", line):
                http = int(match.group(1))
        yield process, udp, http
    finally:
        process.terminate()
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


def rss_mb(pid: int) -> float:
    """Resident memory of ``pid`` and its children (an upload worker), MB."""
    total = 0.0
    pids = [pid]
    children = Path(f"/proc/{pid}/task/{pid}/children")
    if children.exists():
        pids += [int(p) for p in children.read_text().split()]
    for each in pids:
        try:
            status = Path(f"/proc/{each}/status").read_text()
        except OSError:
            continue
        match = re.search(r"VmRSS:\s+(\d+) kB", status)
        total += int(match.group(1)) / 1024 if match else 0.0
    return total


class Watch:
    """Frame arrival times of one WebSocket viewer and the server's RSS, sampled in background threads."""

    def __init__(self, http_port: int, pid: int) -> None:
        from mien.client import WebSocketClient

        self.pid = pid
        self.times: list[float] = []
        self.rss: list[tuple[float, float]] = []
        self._stop = threading.Event()
        self._client = WebSocketClient(f"ws://127.0.0.1:{http_port}/ws")
        self._threads = [threading.Thread(target=self._frames), threading.Thread(target=self._memory)]
        for thread in self._threads:
            thread.start()

    def _frames(self) -> None:
        while not self._stop.is_set():
            try:
                self._client.recv_frame(timeout_s=0.5)
            except TimeoutError:
                continue
            except Exception:
                return
            self.times.append(time.perf_counter())

    def _memory(self) -> None:
        while not self._stop.is_set():
            self.rss.append((time.perf_counter(), rss_mb(self.pid)))
            time.sleep(0.02)

    def window(self, begin: float, end: float) -> tuple[float, float, float]:
        """(frames per second, longest frame gap in seconds, peak RSS MB) between ``begin`` and ``end``."""
        inside = [t for t in self.times if begin <= t <= end]
        rate = (len(inside) - 1) / (inside[-1] - inside[0]) if len(inside) > 1 else 0.0
        edges = [begin, *inside, end]
        gap = max(b - a for a, b in itertools.pairwise(edges))
        peak = max((m for t, m in self.rss if begin <= t <= end), default=0.0)
        return rate, gap, peak

    def close(self) -> None:
        self._stop.set()
        for thread in self._threads:
            thread.join(5)
        self._client.close()


# ---------------------------------------------------------------------------------------------------------------
# The attacks: each returns what the server answered, in a few words


def _clip_url(port: int) -> str:
    return f"http://127.0.0.1:{port}/api/characters/default/clip"


def _post_clip(port: int, data: bytes | Iterator[bytes], suffix: str) -> str:
    headers = {"content-type": "application/octet-stream"}
    try:
        response = httpx.post(_clip_url(port), params={"suffix": suffix}, content=data, headers=headers, timeout=60)
    except httpx.HTTPError as exc:
        return f"connection ended ({type(exc).__name__})"
    return f"{response.status_code} {response.text[:90]}"


@functools.cache
def big_csv() -> bytes:
    """A 26 MB curves CSV: time_s and the 62 face channels."""
    from mien.facs.catalogue import FACE_CHANNELS

    rows = 26 * 2**20 // (len(FACE_CHANNELS) * 7)
    rng = np.random.default_rng(0)
    values = rng.uniform(0, 5, (rows, len(FACE_CHANNELS))).round(3)
    text = io.StringIO()
    text.write(",".join(("time_s", *FACE_CHANNELS)) + "\n")
    times = np.arange(rows) / 60.0
    np.savetxt(text, np.column_stack([times, values]), fmt=["%.6f"] + ["%.3g"] * len(FACE_CHANNELS), delimiter=",")
    return text.getvalue().encode()


@functools.cache
def npz_bomb() -> bytes:
    """A ~1 MB ``.npz`` clip whose values unpack to 1 GiB (zeros compress 1000:1)."""
    from mien.exchange.clip_npz import write
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.clip import Clip

    frames = 2**30 // (8 * len(FACE_CHANNELS))
    buffer = io.BytesIO()
    write(Clip(np.zeros((frames, len(FACE_CHANNELS))), 60.0, FACE_CHANNELS), buffer)
    return buffer.getvalue()


def glb_bomb() -> bytes:
    """A few hundred bytes of ``.glb`` whose accessors claim 10^8 key times and weights (no buffer at all)."""
    from mien.fileio.glb import pack_glb

    count = 100_000_000
    document = {
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {}, "targets": [{}]}]}],
        "nodes": [{"mesh": 0}],
        "accessors": [
            {"componentType": 5126, "type": "SCALAR", "count": count},
            {"componentType": 5126, "type": "SCALAR", "count": count},
        ],
        "animations": [
            {"channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
             "samplers": [{"input": 0, "output": 1}]}
        ],
    }  # fmt: skip
    return pack_glb(document)


def chunks(total: int, size: int = 2**20, fill: bytes = b"0") -> Iterator[bytes]:
    """``total`` bytes in ``size`` pieces (httpx sends an iterator as a chunked body)."""
    block = fill * size
    for _ in range(total // size):
        yield block


def attack_csv(port: int) -> str:
    return _post_clip(port, big_csv(), ".csv")


def attack_npz(port: int) -> str:
    return _post_clip(port, npz_bomb(), ".npz")


def attack_glb(port: int) -> str:
    data = glb_bomb()
    return f"{len(data)} bytes: {_post_clip(port, data, '.glb')}"


def attack_chunked_clip(port: int) -> str:
    return _post_clip(port, chunks(300 * 2**20), ".csv")


def attack_chunked_json(port: int) -> str:
    def body() -> Iterator[bytes]:
        yield b'{"emotion": "joy", "pad": "'
        yield from chunks(200 * 2**20, fill=b"x")
        yield b'"}'

    url = f"http://127.0.0.1:{port}/api/characters/default/emotion"
    try:
        response = httpx.post(url, content=body(), headers={"content-type": "application/json"}, timeout=60)
    except httpx.HTTPError as exc:
        return f"connection ended ({type(exc).__name__})"
    return f"{response.status_code} {response.text[:90]}"


def _raw(port: int, request: bytes, wait_s: float = 5.0) -> str:
    with socket.create_connection(("127.0.0.1", port), timeout=wait_s) as sock:
        sock.sendall(request)
        try:
            answer = sock.recv(4096)
        except TimeoutError:
            return f"no answer in {wait_s:g} s"
    return answer.split(b"\r\n", 1)[0].decode(errors="replace") if answer else "connection closed, no answer"


def attack_claimed_length(port: int) -> str:
    request = (
        b"POST /api/characters/default/emotion HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        b"Content-Type: application/json\r\nContent-Length: 1000000000000\r\n\r\n{"
    )
    return _raw(port, request)


def attack_unknown_fields(port: int) -> str:
    body = {"emotion": "joy", "junk": "x" * (50 * 2**20)}
    url = f"http://127.0.0.1:{port}/api/characters/default/emotion"
    try:
        response = httpx.post(url, content=json.dumps(body).encode(), headers={"content-type": "application/json"})
    except httpx.HTTPError as exc:
        return f"connection ended ({type(exc).__name__})"
    return f"{response.status_code} {response.text[:90]}"


def attack_nan(port: int) -> str:
    url = f"http://127.0.0.1:{port}/api/characters/default/emotion"
    body = b'{"emotion": "joy", "intensity": NaN}'
    response = httpx.post(url, content=body, headers={"content-type": "application/json"})
    return f"{response.status_code} {response.text[:90]}"


def attack_origin(port: int) -> str:
    from websockets.sync.client import connect

    try:
        with connect(f"ws://127.0.0.1:{port}/ws", origin="http://evil.example", open_timeout=5) as ws:  # type: ignore[arg-type]
            ws.send(json.dumps({"emotion": "anger"}))
            ws.recv(timeout=2)
            return "accepted, frames streamed, command sent"
    except Exception as exc:
        return f"refused ({str(exc)[:60]})"


def attack_host(port: int) -> str:
    return _raw(port, b"GET /api/characters HTTP/1.1\r\nHost: evil.example:8000\r\nConnection: close\r\n\r\n")


def attack_text_plain(port: int) -> str:
    from mien.exchange.clip_json import write
    from mien.facs.clip import Clip

    buffer = io.BytesIO()
    write(Clip(np.full((30, 1), 4.0), 30.0, ("AU12L",)), buffer)
    headers = {"content-type": "text/plain", "origin": "http://evil.example"}
    response = httpx.post(_clip_url(port), params={"suffix": ".json"}, content=buffer.getvalue(), headers=headers)
    return f"{response.status_code} {response.text[:90]}"


def attack_speed_null(udp_port: int, http_port: int) -> str:
    def rejected() -> int:
        health = httpx.get(f"http://127.0.0.1:{http_port}/api/health").json()
        return int(sum(health["rejections"].values()))

    before = rejected()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(b'{"AU12": 3, "Speed": null}', ("127.0.0.1", udp_port))
    time.sleep(0.3)
    return "rejected (counted)" if rejected() > before else "accepted silently"


def attack_send_nobody(udp_port: int) -> str:
    command = [sys.executable, "-m", "mien.cli", "send", "--au", "AU12=3", "--character", "nobody"]
    command += ["--udp-port", str(udp_port)]
    done = subprocess.run(command, capture_output=True, text=True, timeout=60)
    said = (done.stdout + done.stderr).strip().splitlines()
    return f"exit {done.returncode}: {said[-1][:100] if said else ''}"


ATTACKS: dict[str, Callable[[int, int], str]] = {
    "csv": lambda udp, http: attack_csv(http),
    "npz": lambda udp, http: attack_npz(http),
    "glb": lambda udp, http: attack_glb(http),
    "chunked_clip": lambda udp, http: attack_chunked_clip(http),
    "chunked_json": lambda udp, http: attack_chunked_json(http),
    "claimed_length": lambda udp, http: attack_claimed_length(http),
    "unknown_fields": lambda udp, http: attack_unknown_fields(http),
    "nan": lambda udp, http: attack_nan(http),
    "ws_origin": lambda udp, http: attack_origin(http),
    "host": lambda udp, http: attack_host(http),
    "text_plain": lambda udp, http: attack_text_plain(http),
    "speed_null": attack_speed_null,
    "send_nobody": lambda udp, http: attack_send_nobody(udp),
}
"""Attack name -> function(udp_port, http_port) returning what the server answered."""


def _ticks(http: int) -> int:
    return int(httpx.get(f"http://127.0.0.1:{http}/api/health", timeout=60).json()["ticks"])


def main(names: list[str]) -> None:
    chosen = names or list(ATTACKS)
    big_csv(), npz_bomb()  # made before any window opens
    with live_server() as (process, udp, http):
        watch = Watch(http, process.pid)
        try:
            time.sleep(0.5)
            ticks, begin = _ticks(http), time.perf_counter()
            time.sleep(2 * WINDOW_S)
            base_ticks, end = _ticks(http) - ticks, time.perf_counter()
            base_rate = base_ticks / (end - begin)
            _, base_gap, base_rss = watch.window(begin, end)
            print(f"baseline (at rest): {base_rate:.1f} ticks/s, longest frame gap {base_gap * 1e3:.0f} ms, "
                  f"RSS {base_rss:.0f} MB")  # fmt: skip
            print(f"{'attack':<15} {'ticks/s':>7} {'ratio':>6} {'gap ms':>7} {'RSS peak':>8} {'after':>6}  answer")
            for name in chosen:
                ticks, begin = _ticks(http), time.perf_counter()
                answer = ATTACKS[name](udp, http)
                time.sleep(max(0.2, WINDOW_S - (time.perf_counter() - begin)))
                ticked, end = _ticks(http) - ticks, time.perf_counter()
                rate = ticked / (end - begin)
                _, gap, peak = watch.window(begin, end)
                after = rss_mb(process.pid)
                print(f"{name:<15} {rate:7.1f} {rate / base_rate:6.2f} {gap * 1e3:7.0f} {peak:8.0f} {after:6.0f}  "
                      f"{answer}", flush=True)  # fmt: skip
        finally:
            watch.close()


if __name__ == "__main__":
    main(sys.argv[1:])
