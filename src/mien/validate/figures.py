"""Figures of the validation reports: recognition confusion matrix and quality next to the study's humans."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mien.validate.detector import EMOTION_LABELS

if TYPE_CHECKING:
    from mien.validate.recognition import RecognitionResult

__all__ = ["plot_confusion", "plot_quality"]


def plot_confusion(result: RecognitionResult, path: str | os.PathLike[str]) -> Path:
    """Heatmap of expression (rows) x top label (columns), each row as shares of its renders."""
    from mien.plot import pyplot

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
    from mien.plot import pyplot
    from mien.validate.recognition import EXPRESSIONS, HUMAN_QUALITY, LABEL_OF

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
