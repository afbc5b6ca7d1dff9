"""Building blocks of mien's self-contained HTML reports (``mien validate report``, ``mien study analyze``).

One page, no external file: figures are embedded as base64 PNG, numbers are formatted one way, cells are
given as HTML fragments (escape text with :func:`html.escape` before passing it).
"""

from __future__ import annotations

import base64
import html
import importlib.metadata
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np

__all__ = ["STYLE", "img", "library_versions", "num", "pct", "table"]

STYLE = """
body{font-family:system-ui,sans-serif;margin:2em auto;max-width:1200px;color:#222}
table{border-collapse:collapse;margin:1em 0;font-size:13px}td,th{border:1px solid #ccc;padding:3px 6px;text-align:right}
th{background:#f0f0f0}td:first-child{text-align:left}.low{color:#b00;font-weight:bold}code{font-size:12px}
img{display:inline-block;margin:4px;border:1px solid #ddd}pre{background:#f7f7f7;padding:8px;font-size:12px}
"""
"""The reports' CSS."""


def img(path: str | Path, alt: str, width: str = "100%") -> str:
    """An ``<img>`` holding the PNG at ``path`` as a base64 data URL, at most ``width`` wide (CSS)."""
    data = base64.b64encode(Path(path).read_bytes()).decode("ascii")
    return f'<img alt="{html.escape(alt)}" style="max-width:{width}" src="data:image/png;base64,{data}">'


def pct(value: float | None) -> str:
    """A share 0..1 as a whole percentage; a dash for NaN or None.

    >>> pct(0.576), pct(float("nan"))
    ('58%', '–')
    """
    return "–" if value is None or not np.isfinite(value) else f"{value:.0%}"


def num(value: float | None, digits: int = 2) -> str:
    """A number with ``digits`` decimals; a dash for NaN or None.

    >>> num(0.5764, 3), num(None)
    ('0.576', '–')
    """
    return "–" if value is None or not np.isfinite(value) else f"{value:.{digits}f}"


def table(header: Sequence[str], rows: Iterable[Sequence[str]]) -> str:
    """A ``<table>``: ``header`` is plain text (escaped here), ``rows`` are HTML fragments (escaped by the caller)."""
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{cell}</td>" for cell in row) + "</tr>" for row in rows)
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def library_versions(names: Iterable[str]) -> dict[str, str]:
    """Distribution name -> installed version (``"not installed"`` when absent)."""
    versions = {}
    for name in names:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    return versions
