"""``mien track VIDEO``: track the face through a video (landmarks, blendshapes, head pose) and save it."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, non_negative_seconds, output_file
from mien.commands._vocabulary import add_landmarker, add_output, add_quiet, add_workers

__all__ = ["TRACK_WORKERS_HELP", "register", "run"]

TRACK_WORKERS_HELP = (
    "processes tracking segments of the video at once (default: one per CPU for a video of 10 s or more, else 1)"
)


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``track`` subcommand."""
    parser = subparsers.add_parser(
        "track",
        help="track a face through a video (MediaPipe landmarks, ARKit blendshapes, head pose)",
        description=(
            "Track the face through VIDEO with MediaPipe Face Landmarker: 478 landmarks, 52 ARKit blendshape "
            "scores and head pose per frame. Frames without a face are marked; gaps up to --max-gap-s are "
            "interpolated, longer ones split the video into takes. Results are cached per video."
        ),
    )
    parser.add_argument("video", type=input_file, help="video file (mp4, mov, avi, mkv, webm...)")
    add_output(
        parser, type=output_file, metavar="FILE", help="write the track to this .npz or .json file (folders are made)"
    )
    add_landmarker(parser, type=input_file, old=("--model",))
    parser.add_argument("--no-cache", action="store_true", help="track again even when a cached result exists")
    parser.add_argument(
        "--max-gap-s",
        type=non_negative_seconds,
        default=0.2,
        help="longest gap (seconds) filled by interpolation (default 0.2)",
    )
    add_workers(parser, help=TRACK_WORKERS_HELP)
    add_quiet(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Track ``args.video``, print a report, and save to ``args.output`` when given."""
    from mien.errors import InvalidValueError
    from mien.tracking.track import track_video

    if args.output and not str(args.output).endswith((".npz", ".json")):
        raise InvalidValueError("output", args.output, "a path ending in .npz or .json")
    track = track_video(
        args.video,
        args.landmarker,
        max_gap_s=args.max_gap_s,
        use_cache=not args.no_cache,
        show_progress=not args.quiet,
        workers=args.workers,
    )
    print(track.report())
    if args.output:
        print(f"wrote {track.save(args.output)}")
    return 0
