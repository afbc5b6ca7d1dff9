"""Figures of the validation reports: recognition (confusion, quality next to the study's people), rig fidelity
(commanded vs detected, cross-talk) and the human-video comparison (activation maps side by side).

Each figure takes the result it draws and a path, and writes one PNG; matplotlib loads only when one is drawn
(:func:`mien.plot.pyplot`). The rig and comparison figures read their results through the small protocols below,
so that the results, which draw themselves when written, need not be imported here.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Protocol

import numpy as np

from mien.plot import pyplot
from mien.validate.detector import EMOTION_LABELS
from mien.validate.expressions import EXPRESSIONS, HUMAN_QUALITY, LABEL_OF
from mien.validate.scores import RecognitionResult

__all__ = [
    "FidelityFigure",
    "MapsFigure",
    "plot_comparison",
    "plot_confusion",
    "plot_crosstalk",
    "plot_quality",
    "plot_scatter",
]


class FidelityFigure(Protocol):
    """What the rig figures read of a :class:`~mien.validate.rig_fidelity.HeadFidelity`."""

    @property
    def label(self) -> str:
        """``head`` or ``head:identity``."""

    @property
    def aus(self) -> tuple[int, ...]:
        """Commanded AU numbers (rows)."""

    @property
    def detected_aus(self) -> tuple[int, ...]:
        """Detected AU numbers (columns)."""

    @property
    def intensities(self) -> tuple[float, ...]:
        """Commanded intensities 1..5."""

    @property
    def neutral(self) -> np.ndarray:
        """(n_det,) detected AU intensities 0..5 of the neutral face."""

    @property
    def detected(self) -> np.ndarray:
        """(n_cmd, n_int, n_det) detected AU intensities 0..5."""

    @property
    def r(self) -> np.ndarray:
        """(n_cmd,) Pearson r of commanded vs detected."""

    @property
    def slope(self) -> np.ndarray:
        """(n_cmd,) detected per commanded unit."""

    @property
    def crosstalk(self) -> np.ndarray:
        """(n_cmd, n_det) slope of every detected AU on the commanded AU's intensity."""

    def leaks(self, threshold: float = 0.2) -> list[list[tuple[int, float]]]:
        """Per commanded AU, the other detected AUs with a cross-talk slope >= ``threshold``, largest first."""
        ...


class MapsFigure(Protocol):
    """What the comparison figure reads of a :class:`~mien.validate.compare.MapComparison`."""

    @property
    def name(self) -> str:
        """What was compared."""

    @property
    def aus(self) -> tuple[int, ...]:
        """AU numbers, one per map row."""

    @property
    def human(self) -> np.ndarray:
        """(n_aus, length) the human's map."""

    @property
    def character(self) -> np.ndarray:
        """(n_aus, length) the character's map."""

    @property
    def r(self) -> float:
        """2D correlation coefficient of the two maps."""

    @property
    def row_r(self) -> np.ndarray:
        """(n_aus,) correlation of each AU's row."""


def _fmt(value: float) -> str:
    return "-" if math.isnan(float(value)) else f"{float(value):.2f}"


def plot_confusion(result: RecognitionResult, path: str | os.PathLike[str]) -> Path:
    """Heatmap of expression (rows) x top label (columns), each row as shares of its renders."""
    plt = pyplot()
    rows, counts = result.confusion()
    shares = counts / np.maximum(counts.sum(axis=1, keepdims=True), 1)
    figure, axes = plt.subplots(figsize=(7.5, 0.42 * len(rows) + 1.6))
    image = axes.imshow(shares, cmap="Blues", vmin=0, vmax=1, aspect="auto")
    axes.set_xticks(range(len(EMOTION_LABELS)), EMOTION_LABELS, rotation=30)
    axes.set_yticks(range(len(rows)), rows)
    for r in range(len(rows)):
        for c in range(len(EMOTION_LABELS)):
            if counts[r, c]:
                axes.text(c, r, f"{shares[r, c]:.0%}", ha="center", va="center", fontsize=8,
                          color="white" if shares[r, c] > 0.6 else "black")  # fmt: skip
    axes.set_xlabel("classifier's top label")
    axes.set_title(f"Recognition of rendered expressions ({result.detector})", fontsize=10)
    figure.colorbar(image, ax=axes, fraction=0.04)
    figure.tight_layout()
    figure.savefig(path, dpi=110, format="png")
    plt.close(figure)
    return Path(path)


def plot_quality(result: RecognitionResult, path: str | os.PathLike[str]) -> Path:
    """Bars: machine quality (mean target probability) per basic emotion beside Broekens' human Table 4."""
    plt = pyplot()
    names = [e for e in EXPRESSIONS if e in LABEL_OF]
    machine = [result.quality(e) for e in names]
    human = [HUMAN_QUALITY[e] for e in names]
    x = np.arange(len(names))
    figure, axes = plt.subplots(figsize=(7.5, 3.2))
    axes.bar(x - 0.2, human, 0.4, label="people (Broekens et al., Table 4)", color="#999999")
    axes.bar(x + 0.2, machine, 0.4, label="classifier on mien's renders", color="#3b75af")
    axes.set_xticks(x, names)
    axes.set_ylim(0, 1)
    axes.set_ylabel("quality")
    axes.legend(fontsize=8, loc="upper right")
    axes.set_title("Recognition quality: target / (mean over labels x labels)", fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=110, format="png")
    plt.close(figure)
    return Path(path)


def plot_scatter(head: FidelityFigure, path: str | os.PathLike[str]) -> Path:
    """A grid of commanded vs detected intensity per commanded AU (its own AU, and its largest leak)."""
    plt = pyplot()
    n = len(head.aus)
    columns = min(6, n)
    rows = math.ceil(n / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(2.3 * columns, 2.3 * rows + 0.6), squeeze=False)
    levels = np.array([0.0, *head.intensities])
    leaks = head.leaks(threshold=0.0)
    r, slope = head.r, head.slope
    try:
        for i, axis in enumerate(axes.flat):
            if i >= n:
                axis.axis("off")
                continue
            code = head.aus[i]
            own = head.detected_aus.index(code)
            axis.plot([0, 5], [0, 5], color="0.75", linestyle="--", linewidth=0.8)
            own_y = np.concatenate([[head.neutral[own]], head.detected[i, :, own]])
            axis.plot(levels, own_y, "o-", color="tab:blue", markersize=4, linewidth=1.2, label=f"AU{code}")
            if leaks[i]:
                other = head.detected_aus.index(leaks[i][0][0])
                other_y = np.concatenate([[head.neutral[other]], head.detected[i, :, other]])
                axis.plot(
                    levels, other_y, "s:", color="tab:red", markersize=3, linewidth=1.0, label=f"AU{leaks[i][0][0]}"
                )
            axis.set_xlim(-0.3, 5.3)
            axis.set_ylim(-0.3, 5.3)
            axis.set_title(f"AU{code}  r {_fmt(r[i])}  s {_fmt(slope[i])}", fontsize=9)
            axis.tick_params(labelsize=7)
            axis.legend(fontsize=6, loc="upper left", frameon=False)
            if i % columns == 0:
                axis.set_ylabel("detected", fontsize=8)
            if i // columns == rows - 1:
                axis.set_xlabel("commanded (0..5)", fontsize=8)
        fig.suptitle(
            f"{head.label}: commanded vs detected AU intensity (blue: own AU, red: largest other AU)", fontsize=10
        )
        fig.tight_layout()
        out = Path(path)
        fig.savefig(out, format="png", dpi=100)
    finally:
        plt.close(fig)
    return out


def plot_crosstalk(head: FidelityFigure, path: str | os.PathLike[str]) -> Path:
    """Heatmap of the cross-talk slopes (rows: commanded AU; columns: detected AU; values annotated >= 0.1)."""
    plt = pyplot()
    matrix = head.crosstalk
    fig, axis = plt.subplots(figsize=(1.2 + 0.42 * len(head.detected_aus), 1.4 + 0.36 * len(head.aus)))
    try:
        image = axis.imshow(matrix, cmap="RdBu_r", vmin=-1.2, vmax=1.2, aspect="auto", interpolation="nearest")
        axis.set_xticks(range(len(head.detected_aus)), [f"{c}" for c in head.detected_aus], fontsize=8)
        axis.set_yticks(range(len(head.aus)), [f"AU{c}" for c in head.aus], fontsize=8)
        axis.set_xlabel("detected AU")
        axis.set_ylabel("commanded AU")
        for (row, column), value in np.ndenumerate(matrix):
            if np.isfinite(value) and abs(value) >= 0.1:
                colour = "white" if abs(value) > 0.8 else "black"
                axis.text(column, row, f"{value:.1f}", ha="center", va="center", fontsize=6, color=colour)
        fig.colorbar(image, ax=axis, label="slope (detected per commanded unit)", shrink=0.8)
        axis.set_title(f"{head.label}: cross-talk (least-squares slope)", fontsize=10)
        fig.tight_layout()
        out = Path(path)
        fig.savefig(out, format="png", dpi=110)
    finally:
        plt.close(fig)
    return out


def plot_comparison(comparison: MapsFigure, path: str | os.PathLike[str]) -> Path:
    """A Fig. 5-style PNG: the human's and the character's activation maps side by side, r in the title."""
    plt = pyplot()
    labels = [f"AU{code}" for code in comparison.aus]
    row_r = comparison.row_r
    r = comparison.r
    height = 1.6 + 0.22 * len(labels)
    fig, axes = plt.subplots(1, 2, figsize=(9.0, height), sharey=True, constrained_layout=True)
    try:
        image = None
        for axis, values, title in zip(
            axes, (comparison.human, comparison.character), ("human", "character"), strict=True
        ):
            image = axis.imshow(values, aspect="auto", cmap="inferno", vmin=0.0, vmax=5.0, interpolation="nearest")
            axis.set_title(title)
            axis.set_xlabel("time (% of clip)")
            n = values.shape[1]
            axis.set_xticks(np.linspace(0, n - 1, 5), [f"{p:.0f}" for p in np.linspace(0, 100, 5)])
        axes[0].set_yticks(range(len(labels)), labels)
        right = axes[1].secondary_yaxis("right")
        right.set_yticks(range(len(labels)), ["" if math.isnan(v) else f"{v:+.2f}" for v in row_r], fontsize=7)
        right.set_ylabel("r per AU")
        fig.colorbar(image, ax=axes, shrink=0.8, label="intensity (0..5)", pad=0.02)
        r_text = "undefined" if math.isnan(r) else f"{r:.2f}"
        fig.suptitle(f"{comparison.name}  (r = {r_text})")
        out = Path(path)
        fig.savefig(out, format="png", dpi=110)
    finally:
        plt.close(fig)
    return out
