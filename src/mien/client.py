"""Clients of ``mien serve``: drive a face from an experiment script in two lines.

>>> from mien.client import openfacs_message
>>> openfacs_message({"AU12": 3}, speed=0.1)[:40]
b'{"AU1": 0, "AU2": 0, "AU4": 0, "AU5": 0,'

``UdpClient("127.0.0.1", 5000).send({"AU12": 3}, speed=0.1)`` sends the exact OpenFACS dict (the 18 AUs in
its order, then ``Speed``), so the original server would read it too; extensions (left/right AUs, emotion,
laughter, PAD, a character id) follow. UDP has no reply: nothing tells the sender that a datagram arrived or
was refused; :class:`HttpClient` asks the server (its characters, its counters of accepted and refused
messages). :class:`WebSocketClient` receives decoded frames and sends commands.
"""

from __future__ import annotations

import json
import socket
import urllib.error
import urllib.request
from collections.abc import Mapping
from contextlib import ExitStack
from typing import Any
from urllib.parse import quote, urlencode

from mien.errors import InvalidValueError, MienError
from mien.extras import require
from mien.server.protocol import OPENFACS_KEYS, Frame, decode_frame

__all__ = ["AsyncWebSocketClient", "HttpClient", "UdpClient", "WebSocketClient", "openfacs_message"]


def openfacs_message(aus: Mapping[str, float], speed: float = 0.05, **extensions: Any) -> bytes:
    """The OpenFACS datagram for ``aus`` (missing AUs are 0; integers stay integers) plus ``extensions``.

    AUs outside OpenFACS's 18 (``AU12L``, ``AU43``...) go after ``Speed``; ``extensions`` with value None are
    left out.
    """
    message: dict[str, Any] = {key: 0 for key in OPENFACS_KEYS[:-1]}
    extra: dict[str, Any] = {}
    for key, value in aus.items():
        (message if key in message else extra)[key] = value
    message["Speed"] = speed
    message.update(extra)
    message.update({key: value for key, value in extensions.items() if value is not None})
    return json.dumps(message).encode()


class UdpClient:
    """Send OpenFACS (and extended) messages to ``host:port`` over UDP (no reply, like OpenFACS)."""

    def __init__(self, host: str = "127.0.0.1", port: int = 5000) -> None:
        self.address = (host, int(port))
        """(host, port) of the server."""
        self._sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_DGRAM)

    def send(self, aus: Mapping[str, float], speed: float = 0.05, character: str | None = None) -> None:
        """Set the full AU state (intensities 0..5; missing AUs are 0) moving at OpenFACS ``speed`` per tick."""
        self.send_raw(openfacs_message(aus, speed, character=character))

    def emote(self, emotion: str, intensity: float = 1.0, character: str | None = None) -> None:
        """Trigger an emotion or blend event (intensity 0..5)."""
        self.send_json({"emotion": emotion, "intensity": intensity, "character": character})

    def laugh(self, laugh_type: str, intensity: float = 1.0, character: str | None = None) -> None:
        """Play a laugh or smile type."""
        self.send_json({"laugh": laugh_type, "intensity": intensity, "character": character})

    def pad(self, pleasure: float, arousal: float, dominance: float, character: str | None = None) -> None:
        """Move the PAD state (each -1..1)."""
        self.send_json({"pad": [pleasure, arousal, dominance], "character": character})

    def say(self, text: str, language: str = "en", rate_wpm: int = 175, character: str | None = None) -> None:
        """Make the character speak ``text`` (espeak-ng on the server; at most 400 characters, see docs/SERVER.md)."""
        self.send_json({"say": {"text": text, "language": language, "rate_wpm": rate_wpm}, "character": character})

    def send_json(self, message: Mapping[str, Any]) -> None:
        """Send any message (keys with value None are left out)."""
        self.send_raw(json.dumps({k: v for k, v in message.items() if v is not None}).encode())

    def send_raw(self, data: bytes) -> None:
        """Send one datagram as is."""
        self._sock.sendto(data, self.address)

    def close(self) -> None:
        """Close the socket."""
        self._sock.close()

    def __enter__(self) -> UdpClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class HttpClient:
    """Read a running server's state over its HTTP API (standard library only): ``health()``, ``characters()``.

    ``base_url`` is like ``http://127.0.0.1:8000``; ``token`` is the server's access token, if it has one.
    """

    def __init__(self, base_url: str = "http://127.0.0.1:8000", token: str | None = None, timeout_s: float = 5.0):
        if not base_url.startswith(("http://", "https://")):
            raise InvalidValueError("url", base_url, "an http:// URL such as http://127.0.0.1:8000")
        self.base_url = base_url.rstrip("/")
        """``http://host:port`` of the server."""
        self._token = token
        self._timeout_s = timeout_s

    def get(self, path: str) -> Any:
        """The JSON answer of ``GET path``; raises :class:`~mien.errors.MienError` saying what went wrong."""
        request = urllib.request.Request(f"{self.base_url}{path}", headers={"Accept": "application/json"})
        if self._token is not None:
            request.add_header("Authorization", f"Bearer {self._token}")
        try:
            with urllib.request.urlopen(request, timeout=self._timeout_s) as response:
                return json.loads(response.read())
        except urllib.error.HTTPError as exc:
            detail = exc.read().decode(errors="replace")[:200]
            exc.close()
            hint = "; give the server's --token" if exc.code == 401 else ""
            raise MienError(f"{self.base_url}{path} answered {exc.code}: {detail}{hint}") from None
        except (OSError, ValueError) as exc:
            reason = getattr(exc, "reason", exc)
            raise MienError(
                f"cannot reach {self.base_url} ({reason}); is `mien serve` running there (its --http-port)?"
            ) from None

    def health(self) -> dict[str, Any]:
        """``/api/health``: uptime, clock and message counters, rejections per reason."""
        return dict(self.get("/api/health"))

    def characters(self) -> list[str]:
        """The server's character ids, in creation order (the first is the default target)."""
        return [str(item["id"]) for item in self.get("/api/characters")]

    def character(self, character_id: str) -> dict[str, Any]:
        """The character's face at the last tick (``aus``, ``pose_deg``, ``weights``)."""
        return dict(self.get(f"/api/characters/{quote(character_id)}"))


def _ws_url(url: str, character: str | None, token: str | None) -> str:
    if not url.startswith(("ws://", "wss://")):
        raise InvalidValueError("url", url, "a ws:// or wss:// URL such as ws://127.0.0.1:8000/ws")
    query = urlencode({k: v for k, v in (("character", character), ("token", token)) if v is not None})
    return f"{url}{'&' if '?' in url else '?'}{query}" if query else url


class WebSocketClient:
    """Synchronous WebSocket client: ``recv_frame()`` returns decoded frames, ``send(...)`` sends commands.

    ``url`` is like ``ws://127.0.0.1:8000/ws``; ``character`` picks the stream (default: the first).
    """

    def __init__(
        self, url: str, character: str | None = None, token: str | None = None, open_timeout_s: float = 5.0
    ) -> None:
        connect = require("websockets.sync.client", "serve").connect  # MissingExtraError without the extra
        invalid_handshake = require("websockets.exceptions", "serve").InvalidHandshake
        self._stack = ExitStack()
        try:
            self._ws = self._stack.enter_context(
                connect(_ws_url(url, character, token), open_timeout=open_timeout_s, max_size=2**20)
            )
        except (OSError, invalid_handshake) as exc:
            raise MienError(
                f"cannot connect to {url}: {exc}; is `mien serve` running, and are the character and token right?"
            ) from None

    def recv_frame(self, timeout_s: float = 5.0) -> Frame:
        """The next frame (skips text messages); raises TimeoutError after ``timeout_s``."""
        while True:
            data = self._ws.recv(timeout=timeout_s)
            if isinstance(data, bytes):
                return decode_frame(data)

    def send(self, command: Mapping[str, Any]) -> None:
        """Send a JSON command (same keys as the extended UDP messages; ``watch`` switches the stream)."""
        self._ws.send(json.dumps(dict(command)))

    def close(self) -> None:
        """Close the connection."""
        self._stack.close()

    def __enter__(self) -> WebSocketClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class AsyncWebSocketClient:
    """asyncio WebSocket client: ``await AsyncWebSocketClient.connect(url)``, then ``recv_frame``/``send``."""

    def __init__(self, ws: Any) -> None:
        self._ws = ws

    @classmethod
    async def connect(
        cls, url: str, character: str | None = None, token: str | None = None, open_timeout_s: float = 5.0
    ) -> AsyncWebSocketClient:
        """Open a connection (raises :class:`~mien.errors.MissingExtraError` without the serve extra)."""
        connect = require("websockets.asyncio.client", "serve").connect
        return cls(await connect(_ws_url(url, character, token), open_timeout=open_timeout_s, max_size=2**20))

    async def recv_frame(self) -> Frame:
        """The next frame (skips text messages)."""
        while True:
            data = await self._ws.recv()
            if isinstance(data, bytes):
                return decode_frame(data)

    async def send(self, command: Mapping[str, Any]) -> None:
        """Send a JSON command."""
        await self._ws.send(json.dumps(dict(command)))

    async def close(self) -> None:
        """Close the connection."""
        await self._ws.close()
