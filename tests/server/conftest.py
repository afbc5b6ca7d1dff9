"""Fixtures of the server tests: a real server on loopback (ephemeral ports) in a background thread."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

pytest.importorskip("fastapi", reason="the serve extra (pip install 'mien[serve]') is not installed")
pytest.importorskip("uvicorn", reason="the serve extra (pip install 'mien[serve]') is not installed")

from mien.server.app import ServeConfig, ServerThread
from mien.server.registry import CharacterSpec

OPENFACS_ORDER = (1, 2, 4, 5, 6, 7, 9, 10, 12, 14, 15, 17, 20, 23, 25, 26, 28, 45)
"""The AUs of the original client, in its key order."""


def make_server(**overrides: Any) -> ServerThread:
    """A server on 127.0.0.1 with characters ``a`` and ``b`` (built-in head, no idle) unless overridden."""
    characters = (CharacterSpec("a", head="builtin", idle=False), CharacterSpec("b", head="builtin", idle=False))
    options: dict[str, Any] = {"udp_port": 0, "http_port": 0, "characters": characters}
    options.update(overrides)
    return ServerThread(ServeConfig(**options))


def assert_unharmed(server: ServerThread) -> None:
    """The server answers its health check and no tick failed and no character was quarantined. Late ticks may
    mark it ``degraded`` on a loaded shared machine: that is the clock's timing, not harm done by a request."""
    import httpx

    health = httpx.get(f"{server.base_url}/api/health").json()
    assert not {"tick_errors", "quarantined"} & set(health["degraded"]), health


@pytest.fixture
def live() -> Iterator[ServerThread]:
    """A running server (60 Hz) with characters ``a`` and ``b``."""
    with make_server() as server:
        yield server


def wait_for(predicate: Callable[[], Any], timeout_s: float = 3.0, what: str = "condition") -> Any:
    """Poll ``predicate`` every 10 ms for at most ``timeout_s`` seconds; return its truthy value or fail."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.01)
    pytest.fail(f"{what} not reached in {timeout_s} s")


@pytest.fixture
def wait_until() -> Callable[..., Any]:
    """``wait_until(predicate, timeout_s=3.0, what=...)``: :func:`wait_for` as a fixture."""
    return wait_for


@pytest.fixture
def au_value() -> Callable[[ServerThread, str, str], float]:
    """``au_value(server, character, channel)``: the channel's value at the server's last tick."""

    def value(server: ServerThread, character: str, channel: str) -> float:
        registry = server.server.registry
        return float(server.call(lambda: registry.state(registry.get(character))[channel]))

    return value


@pytest.fixture
def server_factory() -> Callable[..., ServerThread]:
    """:func:`make_server` (use it as a context manager)."""
    return make_server


@pytest.fixture
def openfacs_datagram() -> Callable[..., bytes]:
    """``openfacs_datagram({12: 5}, speed=0.05)``: built exactly like the original client (key order, ints)."""
    import json

    def build(aus: dict[int, int | float], speed: float = 0.05) -> bytes:
        message: dict[str, Any] = {f"AU{code}": aus.get(code, 0) for code in OPENFACS_ORDER}
        message["Speed"] = speed
        return json.dumps(message).encode()

    return build
