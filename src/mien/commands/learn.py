"""``mien learn``: learn a laugh library from a folder of labelled videos (Mascaró et al. 2021)."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, input_folder, output_file, output_folder
from mien.commands._vocabulary import add_landmarker, add_output, add_quiet

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``learn`` subcommand."""
    parser = subparsers.add_parser(
        "learn",
        help="learn a laugh library from labelled videos (tracking, controllers, DTW, clustering)",
        description="Track every labelled video, turn each take into rig-controller curves, compare the takes of "
        "each laugh type by DTW, cluster them and keep the main cluster's representative curve. Per-video "
        "results are checkpointed in LIBRARY's work folder (<library>.work), so a re-run resumes.",
    )
    parser.add_argument("video_dir", metavar="DIR", type=input_folder, help="folder of the videos")
    parser.add_argument("--labels", required=True, type=input_file, help="CSV with columns video,type,performer")
    add_output(parser, type=output_file, required=True, metavar="LIBRARY", help="library file to write (.npz)")
    parser.add_argument("--eps", type=float, default=0.2, help="controller hardness factor (default 0.2)")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: one per CPU; 0: none)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS", help="run on this Dask scheduler instead")
    parser.add_argument("--method", choices=("medoid", "dba"), default="medoid", help="representative curve")
    parser.add_argument(
        "--report-dir", default=None, type=output_folder, help="write summary, DTW tables and plots here"
    )
    parser.add_argument("--seed", type=int, default=0, help="clustering seed (default 0)")
    add_landmarker(parser, type=input_file, old=("--model",))
    add_quiet(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Handle ``mien learn``; returns the exit code."""
    from mien.commands._checks import check_scheduler
    from mien.learning.learn import learn_library

    if args.scheduler is not None:
        if args.workers is not None:
            from mien.commands._checks import refuse_option

            refuse_option("--workers", args.workers, "the Dask scheduler's workers do the work; give one or the other")
        check_scheduler(args.scheduler)  # fail in seconds, naming the address, before tracking anything
    result = learn_library(
        args.video_dir,
        args.labels,
        args.output,
        eps=args.eps,
        workers=args.workers,
        scheduler=args.scheduler,
        method=args.method,
        report_dir=args.report_dir,
        seed=args.seed,
        model=args.landmarker,
        show_progress=not args.quiet,
    )
    print(result.summary)
    return 0
