"""Printing and plotting DTW distance matrices in the style of Mascaró et al. (2021), Table 3.

The paper's Table 3 is the full symmetric matrix of DTW distances between the 7 performers of one expression
type for one controller, blank diagonal, with a mean and a (sample, n - 1) standard deviation row per column
over the off-diagonal entries, values to two decimals.

>>> import numpy as np
>>> m = np.array([[0.0, 12.85, 12.88], [12.85, 0.0, 42.15], [12.88, 42.15, 0.0]])
>>> print(format_dtw_table(m, ["s01", "s02", "s03"], title="smileFrown"))
smileFrown
        s01    s02    s03
s01          12.85  12.88
s02   12.85         42.15
s03   12.88  42.15
mean  12.87  27.50  27.52
sd     0.02  20.72  20.70
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.plot import pyplot

__all__ = ["column_statistics", "format_dtw_table", "plot_dtw_heatmap"]


def _check(matrix: np.ndarray, labels: Sequence[str]) -> np.ndarray:
    values = np.asarray(matrix, dtype=np.float64)
    if values.ndim != 2 or values.shape[0] != values.shape[1] or values.shape[0] == 0:
        raise InvalidValueError("matrix", f"array of shape {values.shape}", "a square (n, n) matrix, n >= 1")
    if len(labels) != values.shape[0]:
        raise InvalidValueError("labels", f"{len(labels)} labels", f"{values.shape[0]} labels, one per row")
    return values


def column_statistics(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per-column mean and sample standard deviation (ddof 1) of the off-diagonal entries: two (n,) arrays.

    Columns with fewer than two off-diagonal values get a standard deviation of NaN (mean NaN when none).
    """
    values = np.asarray(matrix, dtype=np.float64)
    n = values.shape[0]
    mask = ~np.eye(n, dtype=bool)
    columns = [values[mask[:, j], j] for j in range(n)]
    means = np.array([c.mean() if c.size else np.nan for c in columns])
    sds = np.array([c.std(ddof=1) if c.size > 1 else np.nan for c in columns])
    return means, sds


def format_dtw_table(
    matrix: np.ndarray,
    labels: Sequence[str],
    title: str | None = None,
    *,
    decimals: int = 2,
    lower_only: bool = False,
    statistics: bool = True,
) -> str:
    """A plain-text table of an (n, n) distance matrix with row/column ``labels``.

    The diagonal is left blank; ``lower_only`` blanks the upper triangle too; ``statistics`` adds the
    ``mean`` and ``sd`` rows of :func:`column_statistics`; ``decimals`` digits after the point (the paper
    uses 2).
    """
    values = _check(matrix, labels)
    n = values.shape[0]
    names = [str(label) for label in labels]
    cells: list[list[str]] = []
    for i in range(n):
        row = []
        for j in range(n):
            blank = i == j or (lower_only and j > i)
            row.append("" if blank else f"{values[i, j]:.{decimals}f}")
        cells.append(row)
    row_names = list(names)
    if statistics:
        means, sds = column_statistics(values)
        cells.append([f"{v:.{decimals}f}" if np.isfinite(v) else "" for v in means])
        cells.append([f"{v:.{decimals}f}" if np.isfinite(v) else "" for v in sds])
        row_names += ["mean", "sd"]
    width = max([len(name) for name in names] + [len(c) for row in cells for c in row])
    head_width = max(len(name) for name in row_names)
    lines = [title] if title else []
    lines.append(" " * head_width + "".join(f"  {name:>{width}}" for name in names))
    for name, row in zip(row_names, cells, strict=True):
        lines.append((f"{name:<{head_width}}" + "".join(f"  {c:>{width}}" for c in row)).rstrip())
    return "\n".join(lines)


def plot_dtw_heatmap(
    matrix: np.ndarray,
    labels: Sequence[str],
    path: str | Path,
    title: str | None = None,
    *,
    annotate: bool = True,
    decimals: int = 1,
) -> Path:
    """Save a heat map of an (n, n) distance matrix (PNG, SVG or PDF by suffix) and return its path.

    ``annotate`` writes each value in its cell with ``decimals`` digits. Needs matplotlib (``mien[plot]``).
    """
    values = _check(matrix, labels)

    plt = pyplot()
    n = values.shape[0]
    size = 2.0 + 0.5 * n
    figure, axes = plt.subplots(figsize=(size + 1.0, size))
    try:
        image = axes.imshow(values, cmap="viridis", interpolation="nearest")
        figure.colorbar(image, ax=axes, label="DTW distance")
        axes.set_xticks(range(n), [str(label) for label in labels], rotation=45, ha="right")
        axes.set_yticks(range(n), [str(label) for label in labels])
        if title:
            axes.set_title(title)
        if annotate and n <= 30:
            middle = (np.nanmin(values) + np.nanmax(values)) / 2
            for i in range(n):
                for j in range(n):
                    if i != j:
                        color = "black" if values[i, j] > middle else "white"
                        axes.text(
                            j, i, f"{values[i, j]:.{decimals}f}", ha="center", va="center", color=color, fontsize=8
                        )
        figure.tight_layout()
        target = Path(path)
        figure.savefig(target, dpi=100)
    finally:
        plt.close(figure)
    return target
