"""Reading numeric CSV columns by name, with errors that name the file, line and column.

The CSV formats (plain curves, Live Link Face, OpenFace) all come through :func:`read_columns`: header names are
stripped of surrounding spaces (OpenFace writes ``frame, timestamp, ...``), only the wanted columns are
converted (into one array sized from the line count, checked against :mod:`mien.fileio.limits` first), and
every bad cell (not a number, NaN, infinite), short row (a truncated file) or missing column
raises :class:`~mien.errors.InvalidValueError` with ``FILE line L column C (NAME)``.

>>> import io
>>> table = read_columns(io.BytesIO(b"time_s, a\\n0, 1\\n0.5, 2\\n"), ["a"])
>>> table.values["a"].tolist(), table.lines.tolist()
([1.0, 2.0], [2, 3])
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.limits import check_count, current
from mien.fileio.streams import Source, read_text, source_name

__all__ = ["CsvColumns", "check_increasing", "columns_from_text", "read_columns"]


@dataclass(frozen=True, eq=False)
class CsvColumns:
    """Numeric columns of a CSV file."""

    name: str
    """File name, for messages."""
    header: tuple[str, ...]
    """Every column name, stripped, in file order."""
    values: dict[str, np.ndarray]
    """Wanted column name -> (n_rows,) float64 values."""
    lines: np.ndarray
    """(n_rows,) int64 line number (1-based) of each data row."""

    def where(self, row: int, column: str) -> str:
        """``FILE line L column C (NAME)`` of data row ``row`` and ``column``."""
        return f"{self.name} line {int(self.lines[row])} column {self.header.index(column) + 1} ({column})"


def read_columns(
    source: Source,
    wanted: Sequence[str] | None = None,
    parsers: Mapping[str, Callable[[str], float]] | None = None,
    first_column: str | None = None,
) -> CsvColumns:
    """Read the ``wanted`` columns (None: all) of a comma-separated file with a header line.

    ``parsers``: column -> function from the cell text to a float (default :class:`float`); it raises
    ``ValueError`` on a bad cell. ``first_column``: the name the header must start with (a wrong header raises
    naming line 1). Blank lines are skipped. Cells are split on commas (no quoting: none of these formats quote).
    """
    return columns_from_text(read_text(source), source_name(source), wanted, parsers, first_column)


def columns_from_text(
    text: str,
    name: str,
    wanted: Sequence[str] | None = None,
    parsers: Mapping[str, Callable[[str], float]] | None = None,
    first_column: str | None = None,
) -> CsvColumns:
    """:func:`read_columns` on text already read (``name`` is the file name for messages)."""
    lines = text.splitlines()
    header_line = next((i for i, line in enumerate(lines) if line.strip()), None)
    if header_line is None:
        raise InvalidValueError(f"{name} line 1", "an empty file", "a CSV header line")
    header = tuple(cell.strip() for cell in lines[header_line].split(","))
    if first_column is not None and header[0] != first_column:
        raise InvalidValueError(
            f"{name} line {header_line + 1} column 1", header[0], f"a header starting {first_column}"
        )
    names = list(header) if wanted is None else list(wanted)
    missing = [n for n in names if n not in header]
    if missing:
        shown = ", ".join(missing[:8]) + (", ..." if len(missing) > 8 else "")
        raise InvalidValueError(f"{name} line {header_line + 1}", f"no column {shown}", "those columns in the header")
    positions = [header.index(n) for n in names]
    convert = [(parsers or {}).get(n, float) for n in names]
    most_rows = len(lines) - header_line - 1
    check_count(name, "values (rows x columns)", most_rows * max(len(names), 1), current().clip_values)
    array = np.empty((most_rows, len(names)), dtype=np.float64)  # one row at a time: no list of every cell
    numbers = np.empty(most_rows, dtype=np.int64)
    count = 0
    width = len(header)
    for index in range(header_line + 1, len(lines)):
        line = lines[index]
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != width:
            hint = " (a truncated file?)" if index == len(lines) - 1 and len(cells) < width else ""
            raise InvalidValueError(f"{name} line {index + 1}", f"{len(cells)} cells{hint}", f"{width} as the header")
        row: list[float] = []
        for position, column, parse in zip(positions, names, convert, strict=True):
            cell = cells[position]
            try:
                value = parse(cell)
            except ValueError:
                value = float("nan")
            if not math.isfinite(value):  # math, not numpy: ten times faster per cell
                where = f"{name} line {index + 1} column {position + 1} ({column})"
                raise InvalidValueError(where, cell.strip(), "a finite number")
            row.append(value)
        array[count] = row
        numbers[count] = index + 1
        count += 1
    array = array[:count].copy() if count < most_rows else array
    values = {column: array[:, j] for j, column in enumerate(names)}
    return CsvColumns(name, header, values, numbers[:count].copy())


def check_increasing(table: CsvColumns, column: str) -> None:
    """Raise naming the first row whose ``column`` value does not increase on the row before."""
    times = table.values[column]
    steps = np.diff(times)
    if np.any(steps <= 0):
        row = int(np.argmax(steps <= 0)) + 1
        raise InvalidValueError(table.where(row, column), float(times[row]), f"increasing {column} values")
