"""The OpenFACS UDP endpoint: one JSON object per datagram, no reply. The handler only parses and stores the
newest message per character; the clock applies it (so tens of thousands of datagrams a second fit)."""

from __future__ import annotations

import asyncio
import socket
from typing import Any

from mien.server.protocol import MAX_MESSAGE_BYTES, MessageRejected, Rejection, parse_message
from mien.server.registry import Registry

__all__ = ["RECEIVE_BUFFER_BYTES", "OpenFacsProtocol", "open_udp"]

RECEIVE_BUFFER_BYTES = 4 * 1024 * 1024
"""SO_RCVBUF asked for (the kernel may cap it at net.core.rmem_max), so bursts wait in the kernel."""


class OpenFacsProtocol(asyncio.DatagramProtocol):
    """Parse each datagram with :func:`parse_message` and queue it in the registry; count and drop bad ones."""

    def __init__(self, registry: Registry) -> None:
        self.registry = registry
        self.counters = registry.counters

    def datagram_received(self, data: bytes, addr: Any) -> None:
        """Handle one datagram (never raises)."""
        counters = self.counters
        counters.datagrams_received += 1
        try:
            if len(data) > MAX_MESSAGE_BYTES:
                raise MessageRejected(Rejection.OVERSIZED, f"{len(data)} bytes from {addr} > {MAX_MESSAGE_BYTES}")
            self.registry.submit(parse_message(data))
        except MessageRejected as exc:
            self.registry.reject(exc)
            return
        counters.datagrams_accepted += 1

    def error_received(self, exc: Exception) -> None:
        """ICMP errors and the like: nothing to do for a receive-only endpoint."""


async def open_udp(registry: Registry, host: str, port: int) -> tuple[asyncio.DatagramTransport, int]:
    """Listen on ``host:port`` (0 = any free port); returns the transport and the bound port."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER_BYTES)
        sock.bind((host, port))  # no SO_REUSEADDR: a second server on the port must fail, not share it
    except OSError:
        sock.close()
        raise
    sock.setblocking(False)
    loop = asyncio.get_running_loop()
    transport, _ = await loop.create_datagram_endpoint(lambda: OpenFacsProtocol(registry), sock=sock)
    return transport, int(sock.getsockname()[1])
