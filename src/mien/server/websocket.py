"""The WebSocket stream: one binary frame per tick to each viewer (see :mod:`mien.server.protocol` for the
format), JSON commands from viewers. A slow viewer never blocks the clock: each viewer has a one-frame slot
that keeps only the newest frame."""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import Any

from mien.server.protocol import MessageRejected, Rejection, encode_frame, parse_message
from mien.server.registry import Registry

__all__ = ["Hub", "Viewer"]

log = logging.getLogger("mien.server")


class Viewer:
    """One connected viewer: the character it watches and its newest unsent frame."""

    def __init__(self, watching: str | None) -> None:
        self.watching = watching
        """Id of the watched character."""
        self.latest: bytes | None = None
        """Newest frame not yet sent."""
        self.ready = asyncio.Event()
        """Set when :attr:`latest` holds a frame."""


class Hub:
    """Viewers and the per-tick fan-out (register :meth:`on_tick` with the clock)."""

    def __init__(self, registry: Registry) -> None:
        self.registry = registry
        self.viewers: set[Viewer] = set()
        """Connected viewers."""

    def on_tick(self, tick: int, t_s: float) -> None:
        """Encode one frame per watched character and hand it to its viewers (drops their older frame)."""
        if not self.viewers:
            return
        counters = self.registry.counters
        frames: dict[str, bytes | None] = {}
        for viewer in self.viewers:
            watching = viewer.watching or self.registry.default_id
            if watching is None:
                continue
            if watching not in frames:
                entry = self.registry.entries.get(watching)
                if entry is None:
                    frames[watching] = None
                else:
                    weights, pose = self.registry.frame_output(entry)
                    frames[watching] = encode_frame(tick, entry.row, t_s, pose, weights)
            data = frames[watching]
            if data is None:
                continue
            if viewer.latest is not None:
                counters.frames_dropped += 1
            viewer.latest = data
            counters.frames_sent += 1
            viewer.ready.set()

    async def serve(self, websocket: Any, watching: str | None) -> None:
        """Run one viewer connection (a Starlette ``WebSocket``, already accepted) until it closes."""
        viewer = Viewer(watching)
        self.viewers.add(viewer)
        sender = asyncio.create_task(self._send(websocket, viewer))
        try:
            await self._receive(websocket, viewer)
        finally:
            self.viewers.discard(viewer)
            sender.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await sender

    async def _send(self, websocket: Any, viewer: Viewer) -> None:
        try:
            while True:
                await viewer.ready.wait()
                viewer.ready.clear()
                data, viewer.latest = viewer.latest, None
                if data is not None:
                    await websocket.send_bytes(data)
        except asyncio.CancelledError:
            raise
        except Exception as exc:  # the viewer went away; the receiver notices and cleans up
            log.info("viewer send failed: %s", exc)
            with contextlib.suppress(Exception):
                await websocket.close()

    async def _receive(self, websocket: Any, viewer: Viewer) -> None:
        from starlette.websockets import WebSocketDisconnect

        counters = self.registry.counters
        while True:
            try:
                event = await websocket.receive()
            except (WebSocketDisconnect, RuntimeError):
                return
            if event["type"] == "websocket.disconnect":
                return
            data = event.get("text")
            if data is None:
                data = event.get("bytes") or b""
            try:
                message = parse_message(data)
                if message.watch is not None:
                    if message.watch not in self.registry.entries:
                        raise MessageRejected(Rejection.UNKNOWN_CHARACTER, f"watch={message.watch!r} does not exist")
                    viewer.watching = message.watch
                if message.aus is not None or message.has_events:
                    self.registry.submit(message, default=viewer.watching)
            except MessageRejected as exc:
                self.registry.reject(exc)
                continue
            except Exception as exc:  # a bug must cost one message, not the connection
                log.exception("WebSocket command failed")
                self.registry.reject(MessageRejected(Rejection.INTERNAL_ERROR, f"{type(exc).__name__}: {exc}"))
                continue
            counters.ws_commands_accepted += 1
