"""Options and output shared by the subcommands that produce AU curves (emote, au, demo)."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from mien.commands._checks import output_file, positive_fps, positive_seconds
from mien.commands._vocabulary import ANIMATION_FPS, add_output

if TYPE_CHECKING:
    from mien.facs.clip import Clip

__all__ = ["add_curve_options", "emit_curves"]


def add_curve_options(parser: argparse.ArgumentParser, duration_s: float = 2.0) -> None:
    """Add ``--duration --fps --seed --no-idle -o --plot`` to ``parser``."""
    parser.add_argument(
        "--duration", type=positive_seconds, default=duration_s, help="seconds to generate (default %(default)s)"
    )
    parser.add_argument(
        "--fps", type=positive_fps, default=ANIMATION_FPS, help="frames per second (default %(default)s)"
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the idle behaviour (default %(default)s)")
    parser.add_argument("--no-idle", action="store_true", help="switch blinks, micro-motion, gaze and wobble off")
    add_output(
        parser,
        type=output_file,
        help="save the curves: .csv, .json, .npz, .jsonl, .anim or .glb (docs/FORMATS.md; default: print active "
        "channels as CSV); missing folders are made",
    )
    parser.add_argument("--plot", type=output_file, metavar="PNG", help="also save a plot of the curves")


def emit_curves(clip: Clip, args: argparse.Namespace, title: str, events: Sequence[tuple[float, str]] = ()) -> None:
    """Save or print ``clip`` and plot it, as the options in ``args`` say."""
    from mien.exchange import writer_for

    if args.output is not None:
        writer_for(args.output)(clip, args.output)
        print(f"curves: {args.output} ({clip.n_frames} frames at {clip.fps:g} fps, {len(clip.channels)} channels)")
    else:
        active = clip.select(clip.active_channels(1e-3) or clip.channels[:1])
        print("time_s," + ",".join(active.channels))
        for time_s, row in zip(active.times_s, active.values, strict=True):
            print(f"{time_s:.4f}," + ",".join(f"{v:.4f}" for v in row))
    if args.plot is not None:
        from mien.plot import plot_clip

        plot_clip(clip, args.plot, title=title, events=events)
        print(f"plot: {args.plot}", file=sys.stderr if args.output is None else sys.stdout)
