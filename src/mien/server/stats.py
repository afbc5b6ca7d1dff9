"""Server counters (shown by ``GET /api/health``) and a rate-limited log of dropped input."""

from __future__ import annotations

import logging
import os
import socket
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Counters", "RateLimitedLog", "os_dropped_datagrams"]

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
    frames_thinned: int = 0
    """Frames not handed to viewers because the clock ran late (see :attr:`mien.server.websocket.Hub.stride`)."""
    viewers_refused: int = 0
    """WebSocket viewers refused because the server had its maximum of viewers."""
    step_failures: int = 0
    """Ticks whose step of the batch raised (the failing character is then quarantined)."""
    quarantined: int = 0
    """Characters quarantined because stepping them failed."""
    rebuilds: int = 0
    """Batches rebuilt because no single character explained a failed step."""


class RateLimitedLog:
    """Log a warning per reason at most once every ``interval_s``, with the count of suppressed ones (a fault
    that repeats every tick costs one line, and one traceback, per interval, not 60 a second)."""

    def __init__(self, interval_s: float = 5.0, prefix: str = "dropped message") -> None:
        self.interval_s = interval_s
        """Seconds between two log lines of the same reason."""
        self.prefix = prefix
        """Start of each line (``"dropped message"``, ``"tick failed"``...)."""
        self._last: dict[str, float] = {}
        self._suppressed: Counter[str] = Counter()

    def warn(self, reason: str, detail: str, error: BaseException | None = None) -> bool:
        """Log ``detail`` for ``reason`` (with ``error``'s traceback) unless one was logged within
        ``interval_s``; True when logged."""
        now = time.monotonic()
        if now - self._last.get(reason, -1e9) < self.interval_s:
            self._suppressed[reason] += 1
            return False
        suppressed = self._suppressed.pop(reason, 0)
        extra = f" ({suppressed} more since the last report)" if suppressed else ""
        log.warning("%s (%s): %s%s", self.prefix, reason, detail, extra, exc_info=error)
        self._last[reason] = now
        return True


def os_dropped_datagrams(sock: socket.socket) -> int | None:
    """Datagrams the kernel dropped for ``sock`` because its receive queue was full (the ``drops`` column of
    ``/proc/net/udp`` or ``udp6`` on the row of the socket's inode); None where the system does not say."""
    try:
        inode = str(os.fstat(sock.fileno()).st_ino)
    except (OSError, ValueError):  # closed socket
        return None
    for table in ("/proc/net/udp", "/proc/net/udp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except OSError:  # not Linux, or no /proc
            continue
        for line in lines:
            fields = line.split()  # sl local rem st tx:rx tr:tm retrnsmt uid timeout inode ref pointer drops
            if len(fields) >= 13 and fields[9] == inode:
                return int(fields[12])
    return None
