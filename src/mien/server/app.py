"""``mien serve``: one asyncio loop running the clock, the OpenFACS UDP endpoint and uvicorn (HTTP + WebSocket).

>>> config = ServeConfig(udp_port=0, http_port=0, characters=(CharacterSpec("a", head="builtin"),))
>>> with ServerThread(config) as server:
...     server.udp_port > 0 and server.http_port > 0
True
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
import socket
import threading
import time
from dataclasses import dataclass
from typing import Any

from mien.errors import InvalidValueError
from mien.extras import require
from mien.server.capture_source import CaptureConfig, CaptureSource
from mien.server.guard import access_policy, is_loopback, origin_of
from mien.server.registry import CharacterSpec, Registry
from mien.server.scheduler import Clock
from mien.server.stats import os_dropped_datagrams
from mien.server.udp import OpenFacsEndpoint, open_udp
from mien.server.websocket import DEFAULT_MAX_VIEWERS, Hub

__all__ = ["LiveServer", "ServeConfig", "ServerThread", "is_loopback", "serve"]

log = logging.getLogger("mien.server")


@dataclass(frozen=True)
class ServeConfig:
    """How to run a server."""

    host: str = "127.0.0.1"
    """Address of every endpoint (beyond loopback an access token is required)."""
    udp_port: int = 5000
    """OpenFACS UDP port (0 = any free port)."""
    http_port: int = 8000
    """HTTP + WebSocket port (0 = any free port)."""
    tick_hz: float = 60.0
    """Clock rate, ticks per second."""
    token: str | None = None
    """Access token; None = none on loopback, a generated one beyond."""
    characters: tuple[CharacterSpec, ...] = (CharacterSpec("default"),)
    """Characters at start (the first is the default target of messages)."""
    allow_origins: tuple[str, ...] = ()
    """Web origins besides the server's own whose pages may use it (``http://localhost:3000``); see
    :mod:`mien.server.guard`."""
    max_viewers: int = DEFAULT_MAX_VIEWERS
    """WebSocket viewers served at once; more are refused (close code 1013) and counted."""
    capture: CaptureConfig | None = None
    """A camera or video file whose performer some characters follow (:mod:`mien.server.capture_source`)."""

    def __post_init__(self) -> None:
        for name in ("udp_port", "http_port"):
            port = getattr(self, name)
            if not isinstance(port, int) or not 0 <= port <= 65535:
                raise InvalidValueError(name, port, "a port 0..65535 (0 = any free port)")
        if self.token is not None and len(self.token) < 8:
            raise InvalidValueError("token", "***", "a token of at least 8 characters")
        for origin in self.allow_origins:
            origin_of(origin)  # raises naming a malformed one
        ids = [spec.id for spec in self.characters]
        if len(set(ids)) != len(ids):
            raise InvalidValueError("characters", ids, "distinct character ids")
        if isinstance(self.max_viewers, bool) or not isinstance(self.max_viewers, int) or self.max_viewers < 0:
            raise InvalidValueError("max_viewers", self.max_viewers, "a number of viewers >= 0")
        if self.capture is not None:
            for character_id in self.capture.characters:
                if character_id not in ids:
                    raise InvalidValueError("capture character", character_id, f"one of the characters {ids}")


class LiveServer:
    """The running parts: registry, clock, WebSocket hub, UDP transport, uvicorn server (a
    :class:`~mien.server.running.RunningServer`)."""

    def __init__(self, config: ServeConfig) -> None:
        self.config = config
        """How it was started."""
        self.registry = Registry()
        """The characters."""
        self.clock = Clock(self.registry, config.tick_hz)
        """The fixed-rate clock."""
        self.hub = Hub(self.registry, config.max_viewers, config.tick_hz)
        """The WebSocket viewers."""
        self.clock.listeners.append(self.hub.on_tick)
        self.capture = CaptureSource(config.capture) if config.capture is not None else None
        """The capture source, or None."""
        if self.capture is not None:
            self.registry.capture = self.capture
            self.clock.listeners.append(self.capture.on_tick)
        self.token: str | None = config.token
        """Access token for HTTP and WebSocket, or None."""
        if self.token is None and not is_loopback(config.host):
            self.token = secrets.token_urlsafe(18)
        self.udp_port = 0
        """Bound UDP port."""
        self.http_port = 0
        """Bound HTTP port."""
        self.started_monotonic = time.monotonic()
        """``time.monotonic()`` at start."""
        self._tasks: list[asyncio.Task[Any]] = []
        self._udp: OpenFacsEndpoint | None = None
        self._uvicorn: Any = None

    async def start(self) -> None:
        """Create the characters, warm up, bind the sockets and start the clock and uvicorn."""
        uvicorn = require("uvicorn", "serve")
        require("fastapi", "serve")
        from mien.server.http_api import create_app  # FastAPI and pydantic load only when a server starts

        for spec in self.config.characters:
            self.registry.add(spec)
        self.registry.warm_up()  # the first laugh is slow: not on the clock
        if self.capture is not None and self.config.characters:
            followers = self.capture.config.characters or (self.config.characters[0].id,)
            for character_id in followers:
                self.registry.follow(self.registry.get(character_id), True)
            self.capture.start()
        host = self.config.host
        self._udp, self.udp_port = await open_udp(self.registry, host, self.config.udp_port)
        sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, self.config.http_port))
        except OSError:
            sock.close()
            self._udp.close()
            raise
        self.http_port = int(sock.getsockname()[1])
        app = create_app(self, access_policy(host, self.config.allow_origins))
        config = uvicorn.Config(
            app, log_level="warning", lifespan="off", ws="websockets-sansio", access_log=False, ws_max_size=65536
        )
        self._uvicorn = uvicorn.Server(config)
        self.started_monotonic = time.monotonic()
        http = asyncio.create_task(self._uvicorn.serve(sockets=[sock]), name="mien-http")
        for _ in range(1000):  # bounded: 10 s
            if self._uvicorn.started or http.done():
                break
            await asyncio.sleep(0.01)
        if http.done():
            http.result()  # raise the start error
        # the clock starts last, so start-up work is not counted as late ticks
        self._tasks = [asyncio.create_task(self.clock.run(), name="mien-clock"), http]
        if not is_loopback(host):
            log.warning(
                "mien serve listens on %s beyond loopback: HTTP and WebSocket need the access token "
                "(Authorization: Bearer TOKEN or ?token=TOKEN); UDP has no authentication",
                host,
            )

    def health_state(self) -> dict[str, Any]:
        """What ``/api/health`` adds to the counters: ``status`` (``"ok"``, or ``"degraded"`` while ticks fail or
        run late (:meth:`Clock.health <mien.server.scheduler.Clock.health>`), a character is quarantined or the
        capture source failed),
        ``degraded`` (the reasons), ``quarantined`` (id -> why), ``datagrams_dropped_by_os`` (None where the system
        does not say), ``viewers_refused``, ``frames_thinned``, ``frame_stride``, ``max_viewers``,
        ``step_failures``."""
        reasons = self.clock.health()
        quarantined = dict(self.registry.quarantined)
        if quarantined:
            reasons.append("quarantined")
        if self.capture is not None and self.capture.state == "failed":
            reasons.append("capture_failed")
        counters = self.registry.counters
        return {
            "status": "degraded" if reasons else "ok",
            "degraded": reasons,
            "quarantined": quarantined,
            "datagrams_dropped_by_os": os_dropped_datagrams(self._udp.sock) if self._udp is not None else None,
            "viewers_refused": counters.viewers_refused,
            "frames_thinned": counters.frames_thinned,
            "frame_stride": self.hub.stride,
            "max_viewers": self.hub.max_viewers,
            "step_failures": counters.step_failures,
        }

    async def stop(self) -> None:
        """Stop uvicorn, the clock and the UDP endpoint."""
        if self._uvicorn is not None:
            self._uvicorn.should_exit = True
        if self._udp is not None:
            self._udp.close()
            self._udp = None
        if self.capture is not None:
            await asyncio.to_thread(self.capture.stop)
        await asyncio.to_thread(self.registry.speech.close)
        if self._tasks:
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(asyncio.shield(self._tasks[1]), 5.0)
            for task in self._tasks:
                task.cancel()
            await asyncio.gather(*self._tasks, return_exceptions=True)

    async def run_forever(self) -> None:
        """Start, then wait until cancelled (Ctrl-C), then stop."""
        await self.start()
        try:
            await asyncio.gather(*self._tasks)
        finally:
            await self.stop()


def serve(config: ServeConfig) -> None:
    """Run a server in this thread until Ctrl-C."""
    asyncio.run(LiveServer(config).run_forever())


class ServerThread:
    """A :class:`LiveServer` on its own event loop in a background thread (for tests, benchmarks, notebooks).

    Use as a context manager; :attr:`udp_port`, :attr:`http_port` and :attr:`server` are set once entered.
    :meth:`call` runs a function on the server's loop. Changes through the registry (``add``, ``remove``,
    ``submit``) may come from any thread (they hold ``Registry.lock`` and land between ticks); read its state
    through :meth:`call`.
    """

    def __init__(self, config: ServeConfig) -> None:
        self.config = config
        self.server = LiveServer(config)
        """The server (touch it only through :meth:`call`)."""
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, name="mien-server", daemon=True)

    @property
    def udp_port(self) -> int:
        """Bound UDP port."""
        return self.server.udp_port

    @property
    def http_port(self) -> int:
        """Bound HTTP port."""
        return self.server.http_port

    @property
    def base_url(self) -> str:
        """``http://host:port``."""
        return f"http://{self.config.host}:{self.http_port}"

    def call(self, function: Any, *args: Any) -> Any:
        """Run ``function(*args)`` on the server's loop and return its result (5 s limit)."""

        async def run() -> Any:
            return function(*args)

        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(5.0)

    def __enter__(self) -> ServerThread:
        self._thread.start()
        try:
            asyncio.run_coroutine_threadsafe(self.server.start(), self.loop).result(30.0)
        except BaseException:
            self._shutdown()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        with contextlib.suppress(Exception):
            asyncio.run_coroutine_threadsafe(self.server.stop(), self.loop).result(10.0)
        self._shutdown()

    def _shutdown(self) -> None:
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5.0)
        if not self._thread.is_alive():
            self.loop.close()
