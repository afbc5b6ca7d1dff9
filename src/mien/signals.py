"""Termination signals as Ctrl-C: SIGTERM and SIGHUP (a ``kill``, a closed terminal) raise :class:`Terminated`, a
``KeyboardInterrupt``, so ``with`` blocks and ``finally`` clauses clean up as they do for Ctrl-C (an MP4 writer
keeps ``.partial.mp4`` and removes its temporary file; an atomic write leaves no temporary file). ``mien``'s
entry point runs every command inside :func:`termination_as_interrupt`.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

__all__ = ["TERMINATING_SIGNALS", "Terminated", "termination_as_interrupt"]


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP arrived while :func:`termination_as_interrupt` was active (a ``KeyboardInterrupt``, so
    every writer cleans up as for Ctrl-C)."""

    def __init__(self, signal_number: int) -> None:
        self.signal_number = signal_number
        super().__init__(f"terminated by {signal.Signals(signal_number).name}")


TERMINATING_SIGNALS: tuple[str, ...] = ("SIGTERM", "SIGHUP")
"""Signals :func:`termination_as_interrupt` turns into :class:`Terminated` (those this platform has)."""


@contextlib.contextmanager
def termination_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread instead of killing the
    process at once, so ``with`` blocks and ``finally`` clauses run (an MP4 writer keeps ``.partial.mp4`` and
    removes its temporary file). Only signals still at their default action are taken over, and only from the
    main thread (elsewhere the block runs unchanged); the previous handlers come back on exit."""
    taken: dict[int, object] = {}
    if threading.current_thread() is threading.main_thread():
        for name in TERMINATING_SIGNALS:
            number = getattr(signal, name, None)
            if number is not None and signal.getsignal(number) is signal.SIG_DFL:
                taken[number] = signal.signal(number, _raise_terminated)
    try:
        yield
    finally:
        for number, previous in taken.items():
            signal.signal(number, previous)  # type: ignore[arg-type]


def _raise_terminated(signal_number: int, frame: object) -> None:
    raise Terminated(signal_number)
