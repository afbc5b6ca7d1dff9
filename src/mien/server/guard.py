"""What every HTTP request and WebSocket handshake must pass before a handler sees it (an ASGI middleware).

A web page the user happens to open may not drive a local server: browsers let any page send requests to
``127.0.0.1``, and a DNS name an attacker controls may point at it (DNS rebinding). So, before any handler:

- ``Host`` must name the server: on a loopback address, ``localhost`` or a loopback IP (or a host of an allowed
  origin). A server bound beyond loopback checks no ``Host`` (it cannot know its names) but needs its token.
- ``Origin``, when a browser sends one, must be the page's own origin (``http://`` + the ``Host`` asked for) or
  one allowed with ``mien serve --allow-origin``; anything else (``http://evil.example``, ``null``) gets 403,
  WebSocket handshakes included. Clients that are not browsers send no ``Origin`` and pass.
- A body needs its content type: ``application/json`` on the JSON endpoints, ``application/octet-stream`` on
  the clip upload (415 otherwise). Neither is a type a page may send across sites without asking first, so a
  cross-site form or ``text/plain`` POST never reaches a handler.
- A body has a size limit, enforced while it streams (413 at once for a ``Content-Length`` over it, 413 as soon
  as a chunked body passes it), and a time limit (408): a JSON body is read here, whole, before the handler;
  the clip upload reads its own (see :mod:`mien.server.uploads`).
"""

from __future__ import annotations

import asyncio
import ipaddress
import json
import re
import time
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit

from mien.errors import InvalidValueError

__all__ = [
    "BODY_TIMEOUT_S",
    "MAX_JSON_BYTES",
    "AccessPolicy",
    "BodyTooLarge",
    "BodyTooSlow",
    "Guard",
    "access_policy",
    "is_loopback",
    "origin_of",
    "read_body",
]

MAX_JSON_BYTES = 64 * 1024
"""Largest JSON request body, bytes (the largest command, every AU with a speed and a time constant, is ~6 KB)."""

BODY_TIMEOUT_S = 10.0
"""Seconds a client has to send a whole request body."""

CLIP_PATH = re.compile(r"^/api/characters/[^/]+/clip$")
"""The one route whose body is a file, not JSON."""

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
App = Callable[[Scope, Receive, Send], Awaitable[None]]


def is_loopback(host: str) -> bool:
    """True for ``localhost`` and loopback addresses (127.0.0.0/8, ::1).

    >>> is_loopback("127.0.0.1"), is_loopback("localhost"), is_loopback("0.0.0.0")
    (True, True, False)
    """
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def origin_of(url: str) -> str:
    """The origin ``scheme://host[:port]`` of ``url``, lower case (``http://Lab.example:8080/x`` ->
    ``http://lab.example:8080``); raises :class:`~mien.errors.InvalidValueError` for anything else.

    >>> origin_of("http://Lab.example:8080/viewer")
    'http://lab.example:8080'
    """
    parts = urlsplit(url.strip())
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise InvalidValueError("origin", url, "an origin such as http://localhost:3000 (http or https, a host)")
    try:
        port = parts.port
    except ValueError:
        raise InvalidValueError("origin", url, "an origin with a port 0..65535") from None
    host = f"[{parts.hostname}]" if ":" in parts.hostname else parts.hostname
    return f"{parts.scheme}://{host}" + (f":{port}" if port is not None else "")


def _host_name(host_header: str) -> str:
    """The name in a ``Host`` header, without its port, lower case (``[::1]:8000`` -> ``::1``)."""
    host = host_header.strip().lower()
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


@dataclass(frozen=True)
class AccessPolicy:
    """Which ``Host`` and ``Origin`` headers a server answers."""

    loopback_only: bool
    """The server is bound to a loopback address: only loopback names (and allowed origins' hosts) in ``Host``."""
    origins: frozenset[str]
    """Origins allowed besides the page's own (``http://localhost:3000``), lower case."""

    def refusal(self, headers: dict[str, str]) -> str | None:
        """Why a request with these (lower-case) headers is refused, or None when it passes."""
        host_header = headers.get("host", "")
        host = _host_name(host_header)
        # no Host at all (an HTTP/1.0 tool) is no browser, and so no rebinding: only a wrong one is refused
        if self.loopback_only and host_header and not is_loopback(host) and host not in self._origin_hosts:
            return (
                f"Host {host_header!r} is not an address of this server (a loopback server answers localhost and "
                "loopback IPs; allow another name with mien serve --allow-origin)"
            )
        origin = headers.get("origin")
        if origin is None:
            return None
        own = {f"{kind}://{host_header.strip().lower()}" for kind in ("http", "https")}
        if origin.lower() in own or origin.lower() in self.origins:
            return None
        return f"Origin {origin!r} may not use this server (allow it with mien serve --allow-origin {origin})"

    @property
    def _origin_hosts(self) -> set[str]:
        return {_host_name(urlsplit(origin).netloc) for origin in self.origins}


def access_policy(bind_host: str, allow_origins: Iterable[str] = ()) -> AccessPolicy:
    """The policy of a server bound to ``bind_host`` that also answers pages from ``allow_origins``."""
    return AccessPolicy(is_loopback(bind_host), frozenset(origin_of(origin) for origin in allow_origins))


class BodyTooLarge(Exception):
    """A request body passed its limit (413)."""


class BodyTooSlow(Exception):
    """A request body did not arrive in time (408)."""


async def read_body(receive: Receive, limit: int, timeout_s: float, declared: int | None = None) -> bytes:
    """The whole body from ASGI ``receive``: :class:`BodyTooLarge` as soon as it passes ``limit`` bytes (before
    reading, when the ``declared`` length is already over), :class:`BodyTooSlow` after ``timeout_s`` seconds."""
    if declared is not None and declared > limit:
        raise BodyTooLarge(f"a body of {declared} bytes is over the limit of {limit}")
    parts: list[bytes] = []
    size = 0
    deadline = time.monotonic() + timeout_s
    while True:
        left = deadline - time.monotonic()
        try:
            message = await asyncio.wait_for(receive(), max(left, 0.0))
        except TimeoutError:
            raise BodyTooSlow(f"the body did not arrive in {timeout_s:g} s") from None
        if message["type"] == "http.disconnect":
            raise BodyTooSlow("the client went away before sending the whole body")
        chunk = message.get("body", b"")
        size += len(chunk)
        if size > limit:
            raise BodyTooLarge(f"a body of more than {limit} bytes is over the limit")
        parts.append(chunk)
        if not message.get("more_body", False):
            return b"".join(parts)


def _media_type(headers: dict[str, str]) -> str:
    return headers.get("content-type", "").split(";", 1)[0].strip().lower()


class Guard:
    """The ASGI middleware: ``Host`` and ``Origin`` (HTTP and WebSocket), content types, body limits and time."""

    def __init__(self, app: App, policy: AccessPolicy, json_limit: int = MAX_JSON_BYTES,
                 timeout_s: float = BODY_TIMEOUT_S) -> None:  # fmt: skip
        self.app = app
        self.policy = policy
        """Which hosts and origins pass."""
        self.json_limit = json_limit
        """Largest JSON body, bytes."""
        self.timeout_s = timeout_s
        """Seconds to send a body."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {key.decode("latin-1").lower(): value.decode("latin-1") for key, value in scope["headers"]}
        refusal = self.policy.refusal(headers)
        if refusal is not None:
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008, "reason": refusal[:120]})
            else:
                await _answer(send, 403, refusal)
            return
        if scope["type"] == "websocket" or scope["method"] not in ("POST", "PUT", "PATCH", "DELETE"):
            await self.app(scope, receive, send)
            return
        has_body = "transfer-encoding" in headers or headers.get("content-length", "0") not in ("", "0")
        clip = CLIP_PATH.match(scope["path"]) is not None
        wanted = "application/octet-stream" if clip else "application/json"
        if (has_body or scope["method"] != "DELETE") and _media_type(headers) != wanted:
            given = headers.get("content-type") or "none"
            await _answer(send, 415, f"Content-Type {given!r}: this endpoint takes {wanted}")
            return
        if clip:  # the upload streams its own body, with its own limits (mien.server.uploads)
            await self.app(scope, receive, send)
            return
        declared = headers.get("content-length")
        try:
            body = await read_body(
                receive, self.json_limit, self.timeout_s, int(declared) if declared and declared.isdigit() else None
            )
        except BodyTooLarge as exc:
            await _answer(send, 413, str(exc))
            return
        except BodyTooSlow as exc:
            await _answer(send, 408, str(exc))
            return
        await self.app(scope, _replay(body, receive), send)


def _replay(body: bytes, receive: Receive) -> Receive:
    """An ASGI ``receive`` that gives ``body`` once, then waits on the real one (for the disconnect)."""
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replay


async def _answer(send: Send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if status in (408, 413):
        headers.append((b"connection", b"close"))  # the rest of the body is not read
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})
