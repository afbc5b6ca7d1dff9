"""The WebSocket stream: one binary frame per tick to each viewer (see :mod:`mien.server.protocol` for the
format), JSON commands from viewers. A slow viewer never blocks the clock: each viewer has a one-frame slot
that keeps only the newest frame. At most :attr:`Hub.max_viewers` viewers are served (``mien serve
--max-viewers``): each costs the loop a send per tick, so past the cap a new one is closed with code 1013 ("try
again later") and counted (``viewers_refused``) instead of slowing the clock for everyone. Should the sends still
make the clock run late, viewers get every 2nd, 4th... (up to :data:`MAX_FRAME_STRIDE`) tick's frame until it
is on time again (counted as ``frames_thinned``): the clock's rate comes first."""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import time
from collections import deque
from typing import Any

from mien.errors import InvalidValueError
from mien.server.protocol import MessageRejected, Rejection, encode_frame, parse_message
from mien.server.registry import Registry
from mien.server.stats import RateLimitedLog

__all__ = ["DEFAULT_MAX_VIEWERS", "MAX_FRAME_STRIDE", "TRY_AGAIN_LATER", "Hub", "Viewer"]

log = logging.getLogger("mien.server")

DEFAULT_MAX_VIEWERS = 200
"""Viewers served at once by default (bench/server_viewers.py: the clock keeps its rate with this many viewers
that never read)."""

MAX_FRAME_STRIDE = 8
"""Under load viewers get at least every 8th tick's frame (7.5 frames/s at 60 Hz)."""

TRY_AGAIN_LATER = 1013
"""WebSocket close code of a viewer refused because the server is full (RFC 6455 registry: Try Again Later)."""


class Viewer:
    """One connected viewer: the character it watches and its newest unsent frame."""

    def __init__(self, watching: str | None, slot: int = 0) -> None:
        self.watching = watching
        """Id of the watched character."""
        self.slot = slot
        """Its turn while frames are thinned (:attr:`Hub.stride`)."""
        self.latest: bytes | None = None
        """Newest frame not yet sent."""
        self.ready = asyncio.Event()
        """Set when :attr:`latest` holds a frame."""
        self.texts: deque[str] = deque(maxlen=16)
        """JSON text messages not yet sent (speech announcements: :mod:`mien.server.speech`), sent before frames."""


class Hub:
    """Viewers and the per-tick fan-out (register :meth:`on_tick` with the clock)."""

    def __init__(self, registry: Registry, max_viewers: int = DEFAULT_MAX_VIEWERS, tick_hz: float = 60.0) -> None:
        if isinstance(max_viewers, bool) or not isinstance(max_viewers, int) or max_viewers < 0:
            raise InvalidValueError("max_viewers", max_viewers, "a number of viewers >= 0")
        self.registry = registry
        self.max_viewers = max_viewers
        """Most viewers served at once; more are closed with :data:`TRY_AGAIN_LATER` and counted."""
        self.viewers: set[Viewer] = set()
        """Connected viewers."""
        self.stride = 1
        """Viewers get every ``stride``-th tick's frame: doubled (up to :data:`MAX_FRAME_STRIDE`) while the clock
        runs late, halved after 2 s on time."""
        self._period_s = 1.0 / tick_hz
        self._origin: float | None = None  # least perf_counter() - t_s seen: when a tick on time reaches the hub
        self._last_tick = -1
        self._changed = self._calm_since = self._lateness = 0.0
        self._send_s = 0.0  # loop time spent sending frames since the last tick
        self._send_share = 0.0  # smoothed share of the loop's time spent sending frames
        self._paced_at = 0.0
        self._round = 0  # ticks handed to the hub; a viewer's turn is when (slot + round) % stride == 0
        self._slots = 0
        self._log = RateLimitedLog(prefix="viewer refused")
        registry.speech.listeners.append(self.announce)

    def announce(self, spoken: Any) -> None:
        """Tell the viewers of ``spoken.character`` that it starts an utterance (a JSON text message with the
        sound's URL and its start on the server clock: :meth:`mien.server.speech.Spoken.announcement`)."""
        text: str | None = None
        for viewer in self.viewers:
            if (viewer.watching or self.registry.default_id) == spoken.character:
                text = text or json.dumps(spoken.announcement())
                viewer.texts.append(text)
                viewer.ready.set()

    def _greet(self, viewer: Viewer) -> None:
        """Tell a viewer that starts watching a character what it is saying now, if anything."""
        watching = viewer.watching or self.registry.default_id
        spoken = self.registry.speech.playing(watching, self.registry.time_s) if watching is not None else None
        if spoken is not None:
            viewer.texts.append(json.dumps(spoken.announcement()))
            viewer.ready.set()

    def _pace(self, tick: int, t_s: float) -> None:
        """Adapt :attr:`stride` to how late this tick reached the hub: doubled when ticks keep running late while
        sending frames takes over a fifth of the loop's time, halved after 2 s on time."""
        now = time.perf_counter()
        if self._origin is None or now - t_s < self._origin:
            self._origin = now - t_s
        if self._paced_at:
            share = self._send_s / max(now - self._paced_at, 1e-6)
            self._send_share = 0.9 * self._send_share + 0.1 * min(share, 1.0)
        self._paced_at, self._send_s = now, 0.0
        skipped = max(0, tick - self._last_tick - 1) if self._last_tick >= 0 else 0
        late = skipped > 0 or now - t_s - self._origin > 0.5 * self._period_s
        self._last_tick = tick
        self._lateness = 0.9 * self._lateness + (1 + skipped if late else 0)  # a hiccup is not a load
        if late:
            self._calm_since = now
            sending = self._send_share > 0.2  # late because of the sends, not of the machine
            if sending and self._lateness > 2.5 and self.stride < MAX_FRAME_STRIDE and now - self._changed >= 0.5:
                self.stride *= 2  # (0.5 s: let the last change show first)
                self._changed = now
        elif self.stride > 1 and now - max(self._calm_since, self._changed) >= 2.0:
            self.stride //= 2
            self._changed = now

    def on_tick(self, tick: int, t_s: float) -> None:
        """Encode one frame per watched character and hand it to its viewers (drops their older frame); while the
        clock runs late, each viewer every :attr:`stride`-th tick, in turns, so the sends spread over the ticks."""
        if not self.viewers:
            return
        counters = self.registry.counters
        self._pace(tick, t_s)
        stride, self._round = self.stride, self._round + 1
        frames: dict[str, bytes | None] = {}
        for viewer in self.viewers:
            if stride > 1 and (viewer.slot + self._round) % stride:
                counters.frames_thinned += 1
                continue
            watching = viewer.watching or self.registry.default_id
            if watching is None:
                continue
            if watching not in frames:
                frames[watching] = self._frame(watching, tick, t_s)
            data = frames[watching]
            if data is None:
                continue
            if viewer.latest is not None:
                counters.frames_dropped += 1
            viewer.latest = data
            counters.frames_sent += 1
            viewer.ready.set()

    def _frame(self, character_id: str, tick: int, t_s: float) -> bytes | None:
        """The frame of ``character_id`` at this tick (None: no such character, or its output failed, which
        quarantines it rather than costing every other viewer its frame)."""
        entry = self.registry.entries.get(character_id)
        if entry is None:
            return None
        try:
            weights, pose = self.registry.frame_output(entry)
            return encode_frame(tick, entry.row, t_s, pose, weights)
        except Exception as exc:
            self.registry.quarantine(character_id, f"its frame failed: {type(exc).__name__}: {exc}"[:200])
            return None

    async def serve(self, websocket: Any, watching: str | None) -> None:
        """Run one viewer connection (a Starlette ``WebSocket``, already accepted) until it closes; past
        :attr:`max_viewers`, close it at once with :data:`TRY_AGAIN_LATER` (counted as ``viewers_refused``)."""
        if len(self.viewers) >= self.max_viewers:
            self.registry.counters.viewers_refused += 1
            self._log.warn("full", f"the server serves its maximum of {self.max_viewers} viewers (--max-viewers)")
            with contextlib.suppress(Exception):
                await websocket.close(code=TRY_AGAIN_LATER, reason=f"server full ({self.max_viewers} viewers)")
            return
        viewer = Viewer(watching, self._slots)
        self._slots += 1
        self.viewers.add(viewer)
        self._greet(viewer)
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
                while viewer.texts:
                    await websocket.send_text(viewer.texts.popleft())
                data, viewer.latest = viewer.latest, None
                if data is not None:
                    begin = time.perf_counter()
                    await websocket.send_bytes(data)
                    spent = time.perf_counter() - begin
                    if spent < self._period_s:  # a send that waited for a slow reader cost the loop little
                        self._send_s += spent
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
                    self._greet(viewer)
                if message.aus is not None or message.has_events:
                    self.registry.submit(message, default=viewer.watching)
            except MessageRejected as exc:
                self.registry.reject(exc)
                continue
            except Exception as exc:  # a bug must cost one message, not the connection (logged rate-limited)
                self.registry.reject(MessageRejected(Rejection.INTERNAL_ERROR, f"{type(exc).__name__}: {exc}"), exc)
                continue
            counters.ws_commands_accepted += 1
