"""Server counters (shown by ``GET /api/health``) and a rate-limited log of dropped input."""

from __future__ import annotations

import logging
import time
from collections import Counter
from dataclasses import dataclass, field

__all__ = ["Counters", "RateLimitedLog"]

log = logging.getLogger("mien.server")


@dataclass
class Counters:
    """Mutable counters of one server (only the event loop's thread writes them)."""

    datagrams_received: int = 0
    """UDP datagrams received."""
    datagrams_accepted: int = 0
    """UDP datagrams parsed and queued."""
    ws_commands_accepted: int = 0
    """WebSocket commands parsed and queued."""
    http_commands: int = 0
    """Commands received over HTTP."""
    coalesced: int = 0
    """State messages replaced by a newer one before the tick applied them (full state: nothing is lost)."""
    rejections: Counter[str] = field(default_factory=Counter)
    """Dropped messages per :class:`~mien.server.protocol.Rejection` reason."""
    frames_sent: int = 0
    """WebSocket frames handed to viewers."""
    frames_dropped: int = 0
    """Frames replaced by a newer one before a slow viewer read them."""


class RateLimitedLog:
    """Log a warning per reason at most once every ``interval_s``, with the count of suppressed ones."""

    def __init__(self, interval_s: float = 5.0) -> None:
        self.interval_s = interval_s
        """Seconds between two log lines of the same reason."""
        self._last: dict[str, float] = {}
        self._suppressed: Counter[str] = Counter()

    def warn(self, reason: str, detail: str) -> bool:
        """Log ``detail`` for ``reason`` unless one was logged within ``interval_s``; True when logged."""
        now = time.monotonic()
        if now - self._last.get(reason, -1e9) < self.interval_s:
            self._suppressed[reason] += 1
            return False
        suppressed = self._suppressed.pop(reason, 0)
        extra = f" ({suppressed} more since the last report)" if suppressed else ""
        log.warning("dropped message (%s): %s%s", reason, detail, extra)
        self._last[reason] = now
        return True
