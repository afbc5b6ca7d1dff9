"""Start ``mien serve`` in a child process for the server benchmarks (so client and server do not share a GIL)."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager

import httpx


@contextmanager
def live_server(*options: str) -> Iterator[tuple[int, int]]:
    """Run ``mien serve --udp-port 0 --http-port 0 *options``; yields (udp_port, http_port)."""
    command = [sys.executable, "-m", "mien.cli", "serve", "--udp-port", "0", "--http-port", "0", *options]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        udp = http = 0
        deadline = time.monotonic() + 60
        assert process.stdout is not None
        while (not udp or not http) and time.monotonic() < deadline:
            line = process.stdout.readline()
            if not line:
                raise RuntimeError("mien serve exited before printing its ports")
            if match := re.search(r"UDP on [^:]+:(\d+)", line):
                udp = int(match.group(1))
            if match := re.search(r"HTTP on http://[^:]+:(\d+)", line):
                http = int(match.group(1))
        yield udp, http
    finally:
        process.terminate()
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()


def health(http_port: int) -> dict:
    """The server's /api/health."""
    return httpx.get(f"http://127.0.0.1:{http_port}/api/health", timeout=10).json()
