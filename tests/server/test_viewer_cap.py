"""Issue 29 case 6: a cap on WebSocket viewers (refusals counted, close code 1013), and viewers that cost the clock
its rate get every 2nd, 4th... frame instead (bench/server_viewers.py measures the clock with 1,000 never-reading
clients)."""

from __future__ import annotations

import base64
import os
import socket
import types

import httpx
import pytest

from mien.client import WebSocketClient
from mien.errors import InvalidValueError
from mien.server.app import ServeConfig
from mien.server.registry import CharacterSpec, Registry
from mien.server.websocket import MAX_FRAME_STRIDE, TRY_AGAIN_LATER, Hub, Viewer


def _raw_viewer(port: int) -> tuple[socket.socket, bytes]:
    """A WebSocket client that completes the handshake, reads its response, and then never reads."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
    key = base64.b64encode(os.urandom(16)).decode()
    sock.sendall(
        (
            f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
        ).encode()
    )
    return sock, sock.recv(4096)


def test_viewers_past_the_cap_are_refused_with_1013_and_counted(server_factory, wait_until) -> None:
    from websockets.exceptions import ConnectionClosed
    from websockets.sync.client import connect

    with server_factory(max_viewers=2) as live:
        url = f"ws://127.0.0.1:{live.http_port}/ws"
        health = f"{live.base_url}/api/health"
        with WebSocketClient(url, character="a") as first, WebSocketClient(url, character="b") as second:
            first.recv_frame()
            second.recv_frame()
            with connect(url, open_timeout=5.0) as third, pytest.raises(ConnectionClosed) as closed:
                third.recv(timeout=5.0)
            assert closed.value.rcvd is not None and closed.value.rcvd.code == TRY_AGAIN_LATER
            body = httpx.get(health).json()
            assert body["viewers"] == 2 and body["viewers_refused"] == 1 and body["max_viewers"] == 2
            assert first.recv_frame().row == 0  # the admitted viewers keep their frames
        wait_until(lambda: httpx.get(health).json()["viewers"] == 0, what="both viewers gone")
        with WebSocketClient(url, character="b") as later:  # a freed place is taken again
            assert later.recv_frame().row == 1


def test_never_reading_clients_past_the_cap_cost_the_clock_nothing(server_factory, wait_until) -> None:
    with server_factory(max_viewers=3) as live:
        health = f"{live.base_url}/api/health"
        with WebSocketClient(f"ws://127.0.0.1:{live.http_port}/ws", character="a") as good:
            clients = [_raw_viewer(live.http_port) for _ in range(40)]
            try:
                wait_until(lambda: httpx.get(health).json()["viewers_refused"] == 38, what="38 refusals counted")
                body = httpx.get(health).json()
                assert body["viewers"] == 3 and all(b" 101 " in head for _, head in clients)
                assert body["tick_errors"] == 0 and "tick_errors" not in body["degraded"]
                start = good.recv_frame().tick
                assert good.recv_frame().tick > start  # the good viewer is still served
            finally:
                for sock, _ in clients:
                    sock.close()


def test_the_cap_is_checked() -> None:
    with pytest.raises(InvalidValueError, match="max_viewers"):
        ServeConfig(max_viewers=-1)
    with pytest.raises(InvalidValueError, match="max_viewers"):
        Hub(Registry(), max_viewers=True)


def test_frames_thin_out_only_while_sending_them_makes_the_clock_late(monkeypatch) -> None:
    registry = Registry()
    registry.add(CharacterSpec("a", head="builtin", idle=False))
    registry.step(0.0)
    hub = Hub(registry, tick_hz=60.0)
    viewers = [Viewer("a", slot) for slot in range(8)]
    hub.viewers.update(viewers)
    now = [100.0]
    monkeypatch.setattr("mien.server.websocket.time", types.SimpleNamespace(perf_counter=lambda: now[0]))

    def run(ticks: range, late_s: float, send_share: float) -> int:
        """Hand ``ticks`` to the hub, each ``late_s`` late, sends taking ``send_share`` of the loop; frames out."""
        sent = registry.counters.frames_sent
        for tick in ticks:
            hub._send_s = send_share / 60.0  # what the viewers' senders measured since the last tick
            now[0] = 100.0 + tick / 60.0 + late_s
            hub.on_tick(tick, tick / 60.0)
        return registry.counters.frames_sent - sent

    assert run(range(0, 120), 0.0, 0.05) == 8 * 120 and hub.stride == 1  # on time: every frame to every viewer
    assert run(range(120, 240), 0.012, 0.05) == 8 * 120 and hub.stride == 1  # late, cheap sends: a busy machine
    run(range(240, 360), 0.012, 0.5)  # late while sends take half the loop: thin out
    assert hub.stride == MAX_FRAME_STRIDE
    assert run(range(360, 480), 0.012, 0.5) == 120  # 8 viewers, each every 8th tick, in turns: 1 frame a tick
    assert registry.counters.frames_thinned >= 7 * 120
    run(range(480, 480 + 6 * 60 + 60), 0.0, 0.05)  # on time again: halved every 2 s
    assert hub.stride == 1
