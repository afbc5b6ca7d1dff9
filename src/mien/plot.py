"""Plots of curves (matplotlib, from the ``plot`` extra; imported only when a plot is made)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from mien.extras import require
from mien.facs.clip import Clip

__all__ = ["plot_clip", "pyplot"]


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the headless Agg backend, or :class:`MissingExtraError` naming ``mien[plot]``."""
    require("matplotlib", "plot").use("Agg")
    return require("matplotlib.pyplot", "plot")


def plot_clip(
    clip: Clip,
    path: str | Path,
    title: str = "",
    channels: Sequence[str] | None = None,
    threshold: float = 0.05,
    events: Sequence[tuple[float, str]] = (),
    ylabel: str = "intensity (0..5, A..E)",
) -> Path:
    """Save a PNG of ``clip``'s curves over time.

    Plots ``channels`` (default: every channel whose peak exceeds ``threshold``; left/right pairs with equal
    curves are drawn once, named without the side). Pose channels (``*_deg``) go on a second axis below.
    ``events`` are ``(time_s, label)`` marks drawn as vertical lines.
    """
    plt = pyplot()
    names = list(channels) if channels is not None else list(clip.active_channels(threshold))
    shown: list[tuple[str, str]] = []
    for name in names:
        twin = name[:-1] + ("R" if name.endswith("L") else "L")
        same = name[-1] in "LR" and twin in names and bool((clip.channel(name) == clip.channel(twin)).all())
        if same and name.endswith("R"):
            continue  # drawn once with its left twin
        shown.append((name, name[:-1] if same else name))
    face = [(n, lab) for n, lab in shown if not n.endswith("_deg")]
    pose = [(n, lab) for n, lab in shown if n.endswith("_deg")]
    panels = [(group, unit) for group, unit in ((face, ylabel), (pose, "degrees")) if group] or [([], ylabel)]
    fig, axes = plt.subplots(len(panels), 1, figsize=(10, 3.2 + 2.6 * len(panels)), sharex=True, squeeze=False)
    times = clip.times_s
    for ax, (group, unit) in zip(axes[:, 0], panels, strict=True):
        for name, label in group:
            ax.plot(times, clip.channel(name), label=label, linewidth=1.6)
        for time_s, text in events:
            ax.axvline(time_s, color="0.6", linestyle="--", linewidth=0.8)
            ax.text(time_s, ax.get_ylim()[1], f" {text}", va="top", fontsize=8, color="0.3")
        ax.set_ylabel(unit)
        ax.grid(alpha=0.3)
        if group:
            ax.legend(loc="upper right", fontsize=8, ncol=len(group) // 8 + 1)
    axes[-1, 0].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
