"""The WebSocket stream: decoded frames, commands, watching, slow and vanishing viewers."""

from __future__ import annotations

import asyncio
import base64
import os
import socket
import time

import httpx
import numpy as np
import pytest
from tests.server.conftest import assert_unharmed

from mien.client import AsyncWebSocketClient, UdpClient, WebSocketClient
from mien.errors import MienError
from mien.server.protocol import frame_bytes


def _smile_index(live) -> int:
    return list(live.server.registry.get("a").rig.target_names).index("mouthSmileLeft")


def test_frames_decode_and_show_udp_state(live) -> None:
    url = f"ws://127.0.0.1:{live.http_port}/ws"
    smile = _smile_index(live)
    with WebSocketClient(url) as viewer, UdpClient("127.0.0.1", live.udp_port) as udp:
        first = viewer.recv_frame()
        assert first.weights.shape == (52,) and first.row == 0 and first.weights[smile] == 0.0
        udp.send({"AU12": 5}, speed=1.0)
        frames = [viewer.recv_frame() for _ in range(30)]
        assert frames[-1].weights[smile] == 1.0  # AU12 at 5 -> mouthSmileLeft 1 (float16 exact)
        ticks = [f.tick for f in frames]
        assert ticks == sorted(ticks) and len(set(ticks)) == len(ticks)
        times = np.array([f.time_s for f in frames])
        assert np.allclose(np.diff(times) * 60, np.round(np.diff(times) * 60))  # on the 60 Hz grid
    assert frame_bytes(52) == 148


def test_commands_and_watch(live, wait_until) -> None:
    url = f"ws://127.0.0.1:{live.http_port}/ws"
    smile = _smile_index(live)
    with WebSocketClient(url, character="b") as viewer:
        assert viewer.recv_frame().row == 1
        viewer.send({"AU12": 5, "Speed": 1})  # commands go to the watched character
        frame = wait_until(lambda: (f := viewer.recv_frame()).weights[smile] == 1.0 and f, what="smile on b")
        assert frame.row == 1
        assert httpx.get(f"{live.base_url}/api/characters/a").json()["aus"]["AU12L"] == 0.0
        viewer.send({"watch": "a"})
        wait_until(lambda: viewer.recv_frame().row == 0, what="watching a")
        viewer.send({"watch": "nobody"})
        viewer.send({"AU12": 77})
        health = wait_until(
            lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"].get("out_of_range") and h
        )
        assert health["rejections"] == {"unknown_character": 1, "out_of_range": 1}
        assert health["ws_commands_accepted"] == 2
        assert viewer.recv_frame().row == 0  # still streaming


def test_unknown_character_is_refused(live) -> None:
    with pytest.raises(MienError, match="cannot connect"):
        WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws?character=nobody")


def test_async_client(live) -> None:
    async def run() -> tuple[int, int]:
        client = await AsyncWebSocketClient.connect(f"ws://127.0.0.1:{live.http_port}/ws", character="b")
        try:
            frame = await asyncio.wait_for(client.recv_frame(), 5.0)
            await client.send({"emotion": "joy"})
            return frame.row, frame.weights.shape[0]
        finally:
            await client.close()

    assert asyncio.run(run()) == (1, 52)


def _raw_viewer(port: int) -> socket.socket:
    """A WebSocket client that completes the handshake and then never reads."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        ).encode()
    )
    assert b"101" in sock.recv(1024).split(b"\r\n")[0]
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
    return sock


def test_slow_and_vanishing_viewers_do_not_block_the_clock(live, wait_until) -> None:
    stalled = [_raw_viewer(live.http_port) for _ in range(3)]
    try:
        with WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws", character="b") as good:
            start_tick = good.recv_frame().tick
            begin = time.monotonic()
            received = [good.recv_frame() for _ in range(60)]
            elapsed = time.monotonic() - begin
            assert received[-1].tick - start_tick >= 60 and elapsed < 10.0  # the good viewer keeps receiving
            # (the newest-frame slot itself is checked without sockets in test_registry.py)
            health = httpx.get(f"{live.base_url}/api/health").json()
            assert health["viewers"] == 4 and health["tick_errors"] == 0
            assert health["frames_sent"] >= 4 * 60 * 0.5  # the stalled viewers were handed frames too
            for sock in stalled[:2]:  # vanish without a close frame
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
                sock.close()
            wait_until(lambda: httpx.get(f"{live.base_url}/api/health").json()["viewers"] == 2, what="2 viewers left")
            assert good.recv_frame().tick > received[-1].tick
    finally:
        for sock in stalled:
            sock.close()
    wait_until(lambda: httpx.get(f"{live.base_url}/api/health").json()["viewers"] == 0, what="no viewers")


def test_garbage_on_the_sockets_is_dropped_and_counted(live, wait_until) -> None:
    with WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws") as viewer:
        viewer._ws.send(os.urandom(200).replace(b"{", b"x"))  # binary garbage as a command
        viewer._ws.send("x" * 5000)  # an oversized text command
        health = wait_until(
            lambda: (h := httpx.get(f"{live.base_url}/api/health").json())["rejections"].get("oversized") and h
        )
        assert health["rejections"] == {"malformed_json": 1, "oversized": 1}
        assert viewer.recv_frame().weights.shape == (52,)  # the connection lives on
    with socket.create_connection(("127.0.0.1", live.http_port), timeout=5.0) as raw:  # not HTTP at all
        raw.sendall(os.urandom(512) + b"\r\n\r\n")
        raw.recv(1024)
    assert_unharmed(live)
