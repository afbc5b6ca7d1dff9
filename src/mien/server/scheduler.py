"""The fixed-rate clock: tick k runs at ``start + k / tick_hz`` (no drift), steps the registry, then calls
the listeners (the WebSocket hub). Motion is a function of time (time constants), so any rate shows the same
face; a late tick is counted and the clock skips the ticks it missed instead of bunching them up."""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

from mien.errors import InvalidValueError
from mien.server.registry import Registry

__all__ = ["Clock", "ClockStats"]

log = logging.getLogger("mien.server")

TickListener = Callable[[int, float], None]
"""Called after each step with (tick, time_s)."""


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

    def now_s(self) -> float:
        """Server time now, seconds."""
        return time.perf_counter() - self.started_at

    def run_tick(self, tick: int, t_s: float) -> None:
        """Step the characters to ``t_s`` and notify the listeners (errors are logged, not raised)."""
        try:
            self.registry.step(t_s)
            for listener in self.listeners:
                listener(tick, t_s)
        except Exception:  # a bug in one tick must not stop the face of every character
            self.stats.tick_errors += 1
            log.exception("tick %d failed", tick)
        self.stats.ticks += 1

    async def run(self) -> None:
        """Tick until cancelled."""
        self.started_at = time.perf_counter()
        while True:
            t_s = self.tick * self.period_s
            delay = t_s - self.now_s()
            if delay > 0:
                await asyncio.sleep(delay)
            begin = time.perf_counter()
            self.run_tick(self.tick, t_s)
            cost = time.perf_counter() - begin
            self.stats.last_tick_cost_s = cost
            self.stats.max_tick_cost_s = max(self.stats.max_tick_cost_s, cost)
            self.tick += 1
            behind = self.now_s() - self.tick * self.period_s
            if behind > 0:
                self.stats.late_ticks += 1
                if behind > self.period_s:
                    missed = int(behind // self.period_s)
                    self.stats.skipped_ticks += missed
                    self.tick += missed
            if delay <= 0:
                await asyncio.sleep(0)  # let the transports run even when behind
