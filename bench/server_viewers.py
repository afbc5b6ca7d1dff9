"""Clock rate while 1,000 WebSocket clients connect and never read (issue 29 case 6).

A ``mien serve`` child process (built-in head, 60 Hz) is measured twice in the same run: the baseline with one
reading viewer, then with ``--clients`` more that complete the handshake and never read a byte. The tick rate
comes from ``/api/health`` (ticks over wall time); the reading viewer's frame rate shows whether a real viewer
is still served. Target: the clock keeps >= 0.95 of its baseline rate (before the viewer cap: 52 of 60 ticks/s
reported in the issue). Run: ``python bench/server_viewers.py`` (``--clients 1000 --seconds 10``; extra options
after ``--`` go to ``mien serve``, e.g. ``-- --max-viewers 1000`` to see the clock without the cap).
"""

from __future__ import annotations

import argparse
import base64
import os
import socket
import threading
import time

from _live_server import health, live_server

from mien.client import WebSocketClient


def raw_viewer(port: int) -> socket.socket:
    """A WebSocket client that completes the handshake and then never reads."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10.0)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        ).encode()
    )
    sock.recv(256)  # the 101 (and maybe the start of a frame); nothing is read after this
    return sock


class Reader:
    """One viewer that reads every frame, in a thread; counts frames per window."""

    def __init__(self, port: int) -> None:
        self.client = WebSocketClient(f"ws://127.0.0.1:{port}/ws")
        self.frames = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.client.recv_frame(1.0)
                self.frames += 1
            except Exception:
                if self._stop.is_set():
                    return

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5.0)
        self.client.close()


def window(http_port: int, reader: Reader, seconds: float) -> dict[str, float]:
    """Tick rate, late/skipped ticks and the reader's frame rate over ``seconds``."""
    before, frames, begin = health(http_port), reader.frames, time.monotonic()
    time.sleep(seconds)
    after, elapsed = health(http_port), time.monotonic() - begin
    return {
        "ticks_per_s": (after["ticks"] - before["ticks"]) / elapsed,
        "late": after["late_ticks"] - before["late_ticks"],
        "skipped": after["skipped_ticks"] - before["skipped_ticks"],
        "reader_fps": (reader.frames - frames) / elapsed,
        "viewers": after["viewers"],
        "refused": after.get("viewers_refused", 0),
        "status": after["status"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clients", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("serve_options", nargs="*", help="options for mien serve (after --)")
    args = parser.parse_args()
    with live_server("--head", "builtin", *args.serve_options) as (_, http_port):
        reader = Reader(http_port)
        try:
            base = window(http_port, reader, args.seconds)
            begin = time.monotonic()
            clients = [raw_viewer(http_port) for _ in range(args.clients)]
            connect_s = time.monotonic() - begin
            try:
                attack = window(http_port, reader, args.seconds)
            finally:
                for sock in clients:
                    sock.close()
        finally:
            reader.close()
    print(f"{args.clients} never-reading clients connected in {connect_s:.1f} s; {args.seconds:g} s windows")
    for name, row in (("baseline (1 reading viewer)", base), (f"+{args.clients} never reading", attack)):
        print(
            f"{name:>30}: {row['ticks_per_s']:5.1f} ticks/s, late {row['late']:4.0f}, skipped {row['skipped']:4.0f}, "
            f"reader {row['reader_fps']:5.1f} frames/s, viewers {row['viewers']:.0f}, refused {row['refused']:.0f}, "
            f"status {row['status']}"
        )
    print(f"ratio (attack / baseline tick rate): {attack['ticks_per_s'] / base['ticks_per_s']:.3f} (target >= 0.95)")


if __name__ == "__main__":
    main()
