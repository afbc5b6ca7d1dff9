"""What the HTTP API needs of a running server, as a :class:`~typing.Protocol`: the HTTP layer is typed against
this small interface instead of :class:`mien.server.app.LiveServer`, which creates it (so the two modules do
not import each other; tests may pass any object with these attributes)."""

from __future__ import annotations

from typing import Any, Protocol

from mien.server.registry import Registry
from mien.server.scheduler import Clock
from mien.server.websocket import Hub

__all__ = ["RunningServer"]


class RunningServer(Protocol):
    """The parts of a live server that its transports read."""

    registry: Registry
    """The characters."""
    clock: Clock
    """The fixed-rate clock (its tick and counters)."""
    hub: Hub
    """The WebSocket viewers."""
    token: str | None
    """Access token for HTTP and WebSocket, or None."""
    started_monotonic: float
    """``time.monotonic()`` at start (the health endpoint's uptime)."""

    def health_state(self) -> dict[str, Any]:
        """``status`` (``"ok"`` or ``"degraded"``), ``degraded`` (reasons), ``quarantined``,
        ``datagrams_dropped_by_os``, ``viewers_refused``, ``frames_thinned``, ``frame_stride``, ``max_viewers``,
        ``step_failures``: see
        :meth:`mien.server.app.LiveServer.health_state`."""
        ...
