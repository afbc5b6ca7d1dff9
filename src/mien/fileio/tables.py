"""mien's data tables: commented CSV files shipped inside the package, read one way.

A table is a CSV file with a header row; lines starting with ``#`` are comments (sources, versions, notes)
and may appear anywhere. Tables are read once per process and cached.

>>> rows = read_table("mien.laughter", "data/taxonomy.csv")
>>> rows[0]["type"], rows[0]["family"]
('uproarious_laughter', 'laugh')
"""

from __future__ import annotations

import csv
from functools import cache
from importlib import resources

__all__ = ["read_table", "table_comments", "table_version"]


@cache
def _text(package: str, name: str) -> str:
    return resources.files(package).joinpath(name).read_text(encoding="utf-8")


@cache
def _rows(package: str, name: str) -> tuple[dict[str, str], ...]:
    lines = (line for line in _text(package, name).splitlines() if not line.startswith("#"))
    return tuple(csv.DictReader(lines))


def read_table(package: str, name: str) -> list[dict[str, str]]:
    """The rows of the table ``name`` (a path inside ``package``, e.g. ``"data/taxonomy.csv"``), each a
    ``{column: text}`` dict, in file order; comment lines are skipped. The list and dicts are the caller's."""
    return [dict(row) for row in _rows(package, name)]


def table_comments(package: str, name: str) -> list[str]:
    """The comment lines of the table ``name`` of ``package``, without the leading ``#`` and surrounding
    spaces (where a table records its source and version)."""
    return [line[1:].strip() for line in _text(package, name).splitlines() if line.startswith("#")]


def table_version(package: str, name: str) -> str:
    """The value of the table's ``# version: ...`` comment line (``""`` when it has none).

    >>> table_version("mien.facs", "data/emfacs_prototypes.csv")
    '3'
    """
    for comment in table_comments(package, name):
        key, _, value = comment.partition(":")
        if key.strip().lower() == "version":
            return value.strip()
    return ""
