"""The OpenFACS UDP endpoint: one JSON object per datagram, no reply. The handler only parses and stores the
newest message per character; the clock applies it (so tens of thousands of datagrams a second fit)."""

from __future__ import annotations

import asyncio
import logging
import socket

from mien.server.protocol import MAX_MESSAGE_BYTES, MessageRejected, Rejection, parse_message
from mien.server.registry import Registry
from mien.server.stats import RateLimitedLog

__all__ = ["MAX_DATAGRAMS_PER_WAKEUP", "RECEIVE_BUFFER_BYTES", "OpenFacsEndpoint", "open_udp"]

log = logging.getLogger("mien.server")

MAX_DATAGRAMS_PER_WAKEUP = 256
"""Datagrams handled per event-loop wake-up before other work (the clock, HTTP) gets a turn."""

RECEIVE_BUFFER_BYTES = 4 * 1024 * 1024
"""SO_RCVBUF asked for (the kernel may cap it at net.core.rmem_max), so bursts wait in the kernel."""


class OpenFacsEndpoint:
    """Drain the socket on each readiness event (up to :data:`MAX_DATAGRAMS_PER_WAKEUP` datagrams, so the clock
    is never starved), parse each with :func:`parse_message` and queue it in the registry; count and drop bad
    ones. One wake-up per burst instead of one per datagram keeps the cost per datagram low."""

    def __init__(self, registry: Registry, sock: socket.socket) -> None:
        self.registry = registry
        self.sock = sock
        """The bound, non-blocking socket."""
        self.counters = registry.counters
        self._faults = RateLimitedLog(prefix="datagram handling failed")
        """A bug hit by every datagram of a flood logs one line (and traceback) per interval, not one each."""

    def on_readable(self) -> None:
        """Read and handle the waiting datagrams (never raises)."""
        counters = self.counters
        registry = self.registry
        recv = self.sock.recvfrom
        for _ in range(MAX_DATAGRAMS_PER_WAKEUP):
            try:
                data, addr = recv(MAX_MESSAGE_BYTES + 1)  # one byte more than allowed tells "oversized"
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. ICMP port unreachable reported on the socket: nothing to read
                continue
            counters.datagrams_received += 1
            try:
                if len(data) > MAX_MESSAGE_BYTES:
                    raise MessageRejected(Rejection.OVERSIZED, f"datagram from {addr} over {MAX_MESSAGE_BYTES} bytes")
                registry.submit(parse_message(data))
            except MessageRejected as exc:
                registry.reject(exc)
                continue
            except Exception as exc:  # a bug must cost one datagram, not the endpoint
                self._faults.warn(type(exc).__name__, f"datagram from {addr}: {exc}", exc)
                registry.reject(MessageRejected(Rejection.INTERNAL_ERROR, f"{type(exc).__name__}: {exc}"))
                continue
            counters.datagrams_accepted += 1

    def close(self) -> None:
        """Stop reading and close the socket."""
        asyncio.get_running_loop().remove_reader(self.sock.fileno())
        self.sock.close()


async def open_udp(registry: Registry, host: str, port: int) -> tuple[OpenFacsEndpoint, int]:
    """Listen on ``host:port`` (0 = any free port); returns the endpoint and the bound port."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
        sock.bind((host, port))  # no SO_REUSEADDR: a second server on the port must fail, not share it
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    endpoint = OpenFacsEndpoint(registry, sock)
    asyncio.get_running_loop().add_reader(sock.fileno(), endpoint.on_readable)
    return endpoint, int(sock.getsockname()[1])
