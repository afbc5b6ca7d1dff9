"""Keep MediaPipe's and TensorFlow Lite's routine C++ log lines off the terminal, and let their errors through.

Creating a MediaPipe Face Landmarker or a LiteRT interpreter writes, from C++ straight to file descriptor 2
(so neither :mod:`logging` nor :data:`sys.stderr` can catch it), lines such as::

    WARNING: Logging before InitGoogle() is written to STDERR
    W0000 00:00:1795735387.504442   11782 face_landmarker_graph.cc:181] Sets FaceBlendshapesGraph acceleration ...
    INFO: Created TensorFlow Lite XNNPACK delegate for CPU.

on every ``mien track``, ``learn`` and ``validate`` run. MediaPipe 0.10.30 logs through absl, which reads
neither ``GLOG_minloglevel`` nor ``TF_CPP_MIN_LOG_LEVEL`` (measured: both set, the lines still come), so
:func:`quiet_native_logs` also points descriptor 2 at a temporary file while the model is made, then writes
back every line that is not an absl/glog ``I``/``W`` line or a TFLite ``INFO:`` line: errors (``E``/``F``
lines), Python warnings and anything else still reach the terminal, after the block.

>>> with quiet_native_logs():
...     _ = os.write(2, b"W0000 00:00:1.0   11 graph.cc:181] routine\\n")
>>> kept_lines(b"INFO: Created TensorFlow Lite XNNPACK delegate for CPU.\\nE0000 00:00:1.0   11 graph.cc:9] broken\\n")
b'E0000 00:00:1.0   11 graph.cc:9] broken\\n'
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
import threading
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["NATIVE_LOG_LEVELS", "kept_lines", "quiet_native_logs"]

NATIVE_LOG_LEVELS = {"GLOG_minloglevel": "2", "TF_CPP_MIN_LOG_LEVEL": "2"}
"""Environment the C++ loggers of other MediaPipe / TensorFlow builds read at import (2: errors and worse);
set with ``setdefault``, so a value the user chose wins."""

_ROUTINE = re.compile(
    rb"[IW]\d{4} \d\d:\d\d:[\d.]+ +\d+ [^\]]*\] "  # absl / glog info and warning: "W0000 00:00:17.5  11 x.cc:1] "
    rb"|INFO: "  # TFLite's minimal logger
    rb"|WARNING: Logging before InitGoogle\(\) is written to STDERR"
)
_lock = threading.RLock()
_depth = 0


def kept_lines(captured: bytes) -> bytes:
    """The lines of ``captured`` that are not routine C++ info/warning lines (errors, Python output...)."""
    return b"".join(line for line in captured.splitlines(keepends=True) if not _ROUTINE.match(line))


@contextmanager
def quiet_native_logs() -> Iterator[None]:
    """Hold descriptor 2 while the block runs (making a MediaPipe task, a LiteRT interpreter); then write what
    :func:`kept_lines` keeps of it back to descriptor 2. Thread-safe and re-entrant (the outermost block
    redirects); without a usable descriptor 2 the block just runs."""
    global _depth
    for name, value in NATIVE_LOG_LEVELS.items():
        os.environ.setdefault(name, value)
    with _lock:
        _depth += 1
        try:
            if _depth > 1:
                yield
                return
            try:
                saved = os.dup(2)
            except OSError:
                yield
                return
            with tempfile.TemporaryFile() as held:
                _flush_stderr()
                os.dup2(held.fileno(), 2)
                try:
                    yield
                finally:
                    _flush_stderr()
                    os.dup2(saved, 2)
                    os.close(saved)
                    held.seek(0)
                    kept = memoryview(kept_lines(held.read()))
                    while kept:
                        kept = kept[os.write(2, kept) :]
        finally:
            _depth -= 1


def _flush_stderr() -> None:
    """Python's buffered stderr goes out on the descriptor it was written for."""
    if sys.stderr is not None:
        with contextlib.suppress(OSError, ValueError):
            sys.stderr.flush()
