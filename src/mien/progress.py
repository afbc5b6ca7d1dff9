"""Progress bars for long work: tqdm when installed, a plain line on stderr otherwise."""

from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

from mien.extras import available

__all__ = ["progress"]

T = TypeVar("T")


def progress(items: Iterable[T], total: int | None = None, desc: str = "", enabled: bool = True) -> Iterator[T]:
    """Yield ``items`` while showing a progress bar on stderr (silent when ``enabled`` is False or stderr is not a
    terminal, so logs and pipes get no bar noise)."""
    if not enabled or not sys.stderr.isatty():
        yield from items
        return
    if not available("tqdm"):
        count = 0
        for count, item in enumerate(items, 1):
            yield item
            print(f"\r{desc} {count}/{total or '?'}", end="", file=sys.stderr, flush=True)
        print(file=sys.stderr)
        return
    from tqdm import tqdm

    yield from tqdm(items, total=total, desc=desc, file=sys.stderr, dynamic_ncols=True)
