"""Figures of a study's analysis (matplotlib on Agg, imported when a figure is drawn).

Each function takes a :class:`~mien.study.analysis.StudyAnalysis` and a PNG path, draws one figure, writes it
under a temporary name renamed when complete, and returns the path:

* :func:`plot_profile`: the rating profile, expression x label mean rating 1..5 (the paper's Figure 7);
* :func:`plot_quality`: quality per expression, overall and per level of each condition, with Broekens'
  Table 4 beside it;
* :func:`plot_naturalness`: naturalness per expression with 95% intervals (the paper's Figure 5);
* :func:`plot_interactions`: mean of one measure per level of one factor, a line per level of another, for
  every pair of the ANOVA's factors;
* :func:`plot_mascaro`: the two questions' means per laughter type with 95% intervals, the paper's values
  where its text gives them.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mien.fileio.streams import atomic_path
from mien.plot import pyplot
from mien.study.quality import paper_table4, table_frame

if TYPE_CHECKING:
    from mien.study.analysis import StudyAnalysis

__all__ = ["plot_interactions", "plot_mascaro", "plot_naturalness", "plot_profile", "plot_quality"]


def _save(figure: Any, path: str | os.PathLike[str]) -> Path:

    target = Path(path)
    figure.tight_layout()
    with atomic_path(target) as temporary:
        figure.savefig(temporary, dpi=100, format="png")
    pyplot().close(figure)
    return target


def _short(question: str) -> str:
    return question.removeprefix("label:")


def plot_profile(analysis: StudyAnalysis, path: str | os.PathLike[str]) -> Path:
    """Heatmap of the mean rating (1..5) of every label (columns) for every expression (rows)."""

    if analysis.profile is None:
        raise ValueError("plot_profile needs a Broekens analysis (rating profile)")
    plt = pyplot()
    profile = analysis.profile
    values = profile.to_numpy(np.float64)
    figure, axes = plt.subplots(figsize=(1.0 + 0.62 * values.shape[1], 1.4 + 0.42 * values.shape[0]))
    image = axes.imshow(values, cmap="Reds", vmin=1, vmax=5, aspect="auto")
    axes.set_xticks(range(values.shape[1]), [_short(c) for c in profile.columns], rotation=35, ha="right")
    axes.set_yticks(range(values.shape[0]), list(profile.index))
    for r, c in itertools.product(range(values.shape[0]), range(values.shape[1])):
        axes.text(
            c,
            r,
            f"{values[r, c]:.1f}",
            ha="center",
            va="center",
            fontsize=8,
            color="white" if values[r, c] > 3.6 else "black",
        )
    axes.set_xlabel("label rated")
    axes.set_ylabel("expression shown")
    axes.set_title(f"Rating profiles: mean rating 1..5 (n = {analysis.n_participants})", fontsize=10)
    figure.colorbar(image, ax=axes, fraction=0.04)
    return _save(figure, path)


def plot_quality(analysis: StudyAnalysis, path: str | os.PathLike[str]) -> Path:
    """Bars of quality per expression: one panel for all conditions (the paper's Table 4 beside), one per factor."""

    if analysis.quality is None:
        raise ValueError("plot_quality needs a Broekens analysis (quality table)")
    plt = pyplot()
    quality = analysis.quality
    panels = ["all", *[f for f in dict.fromkeys(quality["factor"]) if f != "all"]]
    expressions = list(dict.fromkeys(quality.loc[quality["factor"] == "all", "expression"]))
    paper = paper_table4().set_index("expression")["quality"]
    figure, axes_list = plt.subplots(
        len(panels),
        1,
        figsize=(max(7.0, 1.6 + 0.75 * len(expressions)), 2.4 * len(panels) + 0.4),
        squeeze=False,
        sharex=True,
    )
    x = np.arange(len(expressions))
    for axes, factor in zip(axes_list[:, 0], panels, strict=True):
        part = quality[quality["factor"] == factor]
        levels = list(dict.fromkeys(part["level"]))
        series = [(lvl, part[part["level"] == lvl].set_index("expression")["quality"]) for lvl in levels]
        if factor == "all":
            series = [("this study", series[0][1]), ("Broekens et al. Table 4", paper)]
        width = 0.8 / len(series)
        for i, (name, values) in enumerate(series):
            heights = [float(values.get(e, np.nan)) for e in expressions]
            colour = "0.65" if name.startswith("Broekens") else None
            axes.bar(x - 0.4 + width * (i + 0.5), heights, width, label=str(name) or "all", color=colour)
        axes.set_ylabel("quality")
        axes.set_ylim(0, 1)
        axes.axhline(0.1, color="0.5", linestyle=":", linewidth=0.8)  # equal ratings on all ten labels
        axes.set_title("all conditions" if factor == "all" else f"by {factor}", fontsize=9)
        axes.legend(fontsize=7, ncol=len(series), loc="upper right")
    axes_list[-1, 0].set_xticks(x, expressions, rotation=30, ha="right")
    figure.suptitle("Quality = target / (mean over labels x labels); dotted line: no preference", fontsize=10)
    return _save(figure, path)


def plot_naturalness(analysis: StudyAnalysis, path: str | os.PathLike[str]) -> Path:
    """Mean naturalness (1..5) per expression with t-based 95% intervals over participants."""

    if analysis.naturalness is None:
        raise ValueError("plot_naturalness needs a Broekens analysis")
    plt = pyplot()
    table = analysis.naturalness
    figure, axes = plt.subplots(figsize=(max(5.0, 1.6 + 0.7 * len(table)), 3.2))
    x = np.arange(len(table))
    means = table["mean"].to_numpy(np.float64)
    errors = np.vstack([means - table["ci_low"].to_numpy(np.float64), table["ci_high"].to_numpy(np.float64) - means])
    axes.bar(x, means, 0.6, yerr=np.nan_to_num(errors), capsize=3, color="#6a9fcf")
    axes.set_xticks(x, list(table["expression"]), rotation=30, ha="right")
    axes.set_ylim(1, 5)
    axes.set_ylabel("naturalness (1..5)")
    axes.set_title("Perceived naturalness, mean and 95% CI over participants", fontsize=10)
    return _save(figure, path)


def plot_interactions(analysis: StudyAnalysis, measure: str, path: str | os.PathLike[str]) -> Path:
    """Interaction plots of ``measure``: for each pair of the ANOVA's factors, its mean over participants per
    level of the first (x) with one line per level of the second (one factor: a single line)."""

    if analysis.trials is None or measure not in analysis.trials.columns:
        raise ValueError(f"no measure {measure!r} in the analysis")
    plt = pyplot()
    factors = list(analysis.factors)
    pairs: list[tuple[str, str | None]] = list(itertools.combinations(factors, 2)) or [(f, None) for f in factors]
    columns = min(3, len(pairs))
    rows = int(np.ceil(len(pairs) / columns))
    figure, axes_grid = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.2 * rows), squeeze=False)
    trials = analysis.trials
    for axes, (first, second) in zip(axes_grid.flat, pairs, strict=False):
        keys = [first] if second is None else [first, second]
        per_participant = trials.groupby([*keys, "participant"], observed=True)[measure].mean()
        means = per_participant.groupby(level=list(range(len(keys))), observed=True).mean()
        x_levels = list(dict.fromkeys(trials[first].astype(str)))
        if second is None:
            axes.plot(range(len(x_levels)), [means.get(lvl, np.nan) for lvl in x_levels], marker="o")
        else:
            for level in dict.fromkeys(trials[second].astype(str)):
                axes.plot(
                    range(len(x_levels)),
                    [means.get((x, level), np.nan) for x in x_levels],
                    marker="o",
                    label=f"{second} = {level}",
                )
            axes.legend(fontsize=7)
        axes.set_xticks(range(len(x_levels)), x_levels)
        axes.set_xlabel(first)
        axes.set_ylabel(_short(measure))
    for axes in list(axes_grid.flat)[len(pairs) :]:
        axes.set_visible(False)
    figure.suptitle(f"{_short(measure)}: means over participants", fontsize=10)
    return _save(figure, path)


def _paper_mascaro() -> Any:

    return table_frame("mien.study", "data/mascaro_fig10.csv")


def plot_mascaro(analysis: StudyAnalysis, path: str | os.PathLike[str]) -> Path:
    """Bars of the two questions' means (0..5) per laughter type with 95% intervals; the paper's means as
    black diamonds where its text gives them (``data/mascaro_fig10.csv``)."""

    if analysis.mascaro is None:
        raise ValueError("plot_mascaro needs a Mascaro analysis")
    plt = pyplot()
    table = analysis.mascaro
    kinds = list(dict.fromkeys(table["expression"]))
    questions = list(dict.fromkeys(table["question"]))
    paper = _paper_mascaro().set_index(["laughter_type", "question"])["mean"]
    figure, axes = plt.subplots(figsize=(max(6.0, 1.8 + 0.9 * len(kinds)), 3.6))
    x = np.arange(len(kinds))
    width = 0.8 / max(len(questions), 1)
    for i, question in enumerate(questions):
        part = table[table["question"] == question].set_index("expression")
        means = np.array([float(part["mean"].get(k, np.nan)) for k in kinds])
        low = np.array([float(part["ci_low"].get(k, np.nan)) for k in kinds])
        high = np.array([float(part["ci_high"].get(k, np.nan)) for k in kinds])
        offset = x - 0.4 + width * (i + 0.5)
        axes.bar(
            offset,
            means,
            width,
            yerr=np.nan_to_num(np.vstack([means - low, high - means])),
            capsize=3,
            label=question.replace("_", " "),
        )
        cited = [float(paper.get((k, question), np.nan)) for k in kinds]
        axes.plot(offset, cited, "kD", markersize=5, label="Mascaró et al. (text)" if i == 0 else None)
    axes.set_xticks(x, kinds, rotation=30, ha="right")
    axes.set_ylim(0, 5)
    axes.set_ylabel("answer (0..5)")
    axes.set_title(f"Mascaró questions, mean and 95% CI (n = {analysis.n_participants})", fontsize=10)
    axes.legend(fontsize=7)
    return _save(figure, path)
