"""The fixed-rate clock: tick k runs at ``start + k / tick_hz`` (no drift), steps the registry, then calls
the listeners (the WebSocket hub). Motion is a function of time (time constants), so any rate shows the same
face; a late tick is counted and the clock skips the ticks it missed instead of bunching them up. Each tick
holds :attr:`Registry.lock <mien.server.registry.Registry.lock>`, so changes from other threads land between
ticks. :meth:`Clock.health` says ``"degraded"`` while ticks fail or run late."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from mien.errors import InvalidValueError
from mien.server.registry import Registry
from mien.server.stats import RateLimitedLog

__all__ = ["HEALTH_WINDOW_S", "LATE_SHARE_DEGRADED", "Clock", "ClockStats"]

log = logging.getLogger("mien.server")

TickListener = Callable[[int, float], None]
"""Called after each step with (tick, time_s)."""

HEALTH_WINDOW_S = 10.0
"""Seconds of recent ticks :meth:`Clock.health` judges."""

LATE_SHARE_DEGRADED = 0.1
"""Share of the recent ticks late or skipped above which the clock is ``degraded``."""

_OK, _LATE, _FAILED = 0, 1, 2  # what became of a tick, in Clock._recent


@dataclass
class ClockStats:
    """Counters of the clock."""

    ticks: int = 0
    """Ticks run."""
    late_ticks: int = 0
    """Ticks whose work ended after the next tick's start (over budget)."""
    skipped_ticks: int = 0
    """Ticks not run because the clock fell more than one period behind."""
    tick_errors: int = 0
    """Ticks that raised (logged; the clock goes on)."""
    last_tick_cost_s: float = 0.0
    """Work time of the last tick, seconds."""
    max_tick_cost_s: float = 0.0
    """Largest work time of a tick, seconds."""


class Clock:
    """Steps ``registry`` at ``tick_hz`` ticks per second of server time (seconds since :meth:`run` began)."""

    def __init__(self, registry: Registry, tick_hz: float = 60.0) -> None:
        if not (isinstance(tick_hz, int | float) and math.isfinite(tick_hz) and 1.0 <= tick_hz <= 1000.0):
            raise InvalidValueError("tick_hz", tick_hz, "a tick rate between 1 and 1000 Hz")
        self.registry = registry
        """The characters it steps."""
        self.tick_hz = float(tick_hz)
        """Ticks per second."""
        self.period_s = 1.0 / self.tick_hz
        """Seconds between ticks."""
        self.stats = ClockStats()
        """Counters."""
        self.listeners: list[TickListener] = []
        """Called after each tick with (tick, time_s)."""
        self.tick = 0
        """Number of the next tick."""
        self.started_at = 0.0
        """``time.perf_counter()`` at tick 0."""
        self._recent: deque[tuple[float, int]] = deque()  # (server time s, _OK/_LATE/_FAILED) of recent ticks
        self._log = RateLimitedLog(prefix="tick failed")

    def now_s(self) -> float:
        """Server time now, seconds."""
        return time.perf_counter() - self.started_at

    def run_tick(self, tick: int, t_s: float) -> bool:
        """Step the characters to ``t_s`` and notify the listeners, holding the registry's lock (errors are
        counted and logged at most every few seconds, not raised); True when the tick went through."""
        ok = True
        with self.registry.lock:
            try:
                self.registry.step(t_s)
                for listener in self.listeners:
                    listener(tick, t_s)
            except Exception as exc:  # a bug in one tick must not stop the face of every character
                ok = False
                self.stats.tick_errors += 1
                self._log.warn("tick", f"tick {tick} at t={t_s:.3f} s: {type(exc).__name__}: {exc}", exc)
        self.stats.ticks += 1
        return ok

    def _record(self, t_s: float, outcome: int, skipped: int = 0) -> None:
        recent = self._recent
        recent.append((t_s, outcome))
        for _ in range(min(skipped, int(HEALTH_WINDOW_S * self.tick_hz))):
            recent.append((t_s, _LATE))  # a skipped tick counts as a late one
        while recent and recent[0][0] < t_s - HEALTH_WINDOW_S:
            recent.popleft()

    def health(self) -> list[str]:
        """Why the clock is degraded now (empty: healthy): ``"tick_errors"`` when a tick of the last
        :data:`HEALTH_WINDOW_S` seconds failed, ``"late_ticks"`` when more than :data:`LATE_SHARE_DEGRADED` of
        them ran late or were skipped, ``"stalled"`` when no tick ran for a second while the clock runs."""
        reasons: list[str] = []
        recent = list(self._recent)
        if any(outcome == _FAILED for _, outcome in recent):
            reasons.append("tick_errors")
        late = sum(outcome == _LATE for _, outcome in recent)
        if recent and late > LATE_SHARE_DEGRADED * len(recent):
            reasons.append("late_ticks")
        if self.started_at and recent and self.now_s() - recent[-1][0] > 1.0:
            reasons.append("stalled")
        return reasons

    async def run(self) -> None:
        """Tick until cancelled."""
        self.started_at = time.perf_counter()
        while True:
            t_s = self.tick * self.period_s
            delay = t_s - self.now_s()
            if delay > 0:
                await asyncio.sleep(delay)
            begin = time.perf_counter()
            ok = self.run_tick(self.tick, t_s)
            cost = time.perf_counter() - begin
            self.stats.last_tick_cost_s = cost
            self.stats.max_tick_cost_s = max(self.stats.max_tick_cost_s, cost)
            self.tick += 1
            behind = self.now_s() - self.tick * self.period_s
            missed = 0
            if behind > 0:
                self.stats.late_ticks += 1
                if behind > self.period_s:
                    missed = int(behind // self.period_s)
                    self.stats.skipped_ticks += missed
                    self.tick += missed
            self._record(t_s, _FAILED if not ok else _LATE if behind > 0 else _OK, missed)
            if delay <= 0:
                await asyncio.sleep(0)  # let the transports run even when behind
