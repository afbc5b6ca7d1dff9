"""``mien capture RECORDING -o OUT``: a person's recorded face -> a face clip any character plays.

The recording is a video (tracked with MediaPipe), a track file (``mien track``'s ``.npz``/``.json``), a Live
Link Face CSV or an OpenFace CSV; the clip holds AU intensities left and right, head rotation and gaze on the
recording's own time stamps (or, with ``--route arkit``, the ARKit scores passed straight through), and a
``face_found`` mask channel. See docs/CAPTURE.md.
"""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, non_negative_seconds, output_file
from mien.commands._vocabulary import add_landmarker, add_output, add_quiet, add_workers
from mien.commands.track import TRACK_WORKERS_HELP

__all__ = ["neutral_interval", "register", "run"]

_OUTPUT_SUFFIXES = (".csv", ".json", ".npz")


def neutral_interval(text: str) -> tuple[float, float]:
    """argparse type: ``START:END`` seconds (``0:1.5``) of the recording showing the performer's neutral.

    >>> neutral_interval("0.5:2")
    (0.5, 2.0)
    """
    parts = text.split(":")
    try:
        start, end = (float(p) for p in parts) if len(parts) == 2 else (float("nan"), float("nan"))
    except ValueError:
        start = end = float("nan")
    if not (start >= 0 and end > start and end < float("inf")):
        raise argparse.ArgumentTypeError(
            f"bad neutral interval {text!r}: give START:END in seconds with 0 <= START < END (e.g. 0:1.5)"
        )
    return start, end


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``capture`` subcommand."""
    parser = subparsers.add_parser(
        "capture",
        help="turn a video (or track, Live Link or OpenFace file) of a person into a face clip",
        description=(
            "Capture a person's performance from RECORDING (a video, a `mien track` file, a Live Link Face CSV or "
            "an OpenFace CSV) as a face clip: AU intensities left and right (through the reverse AU mapping), head "
            "rotation and gaze on the recording's own time stamps, the performer's neutral subtracted, tracker "
            "jitter filtered (One Euro), frames without a face held then eased to neutral and marked in the "
            "face_found channel. `mien render`, `export` and `import` take the result (and track files directly)."
        ),
    )
    parser.add_argument("recording", type=input_file, help="video, track (.npz/.json), Live Link or OpenFace CSV")
    add_output(
        parser, type=output_file, metavar="FILE", required=True, help="write the clip to this .csv, .json or .npz"
    )
    parser.add_argument(
        "--route",
        choices=("au", "arkit"),
        default="au",
        help="au: AU intensities (any head, layers with emotions); arkit: the ARKit scores straight through, "
        "for a head with the performer's ARKit names (default au)",
    )
    neutral = parser.add_mutually_exclusive_group()
    neutral.add_argument(
        "--neutral-first-s",
        type=non_negative_seconds,
        default=0.5,
        metavar="SECONDS",
        help="the neutral is the median of the first SECONDS of frames with a face (default 0.5; 0: none)",
    )
    neutral.add_argument("--neutral", type=neutral_interval, metavar="START:END", help="the neutral's interval, s")
    neutral.add_argument("--neutral-image", type=input_file, metavar="IMAGE", help="a picture of the neutral face")
    neutral.add_argument("--no-neutral", action="store_true", help="subtract no neutral")
    parser.add_argument(
        "--cutoff-hz",
        type=_positive_hz,
        default=None,
        metavar="HZ",
        help="jitter filter cut-off at rest (One Euro min cut-off, default 1.0 Hz)",
    )
    parser.add_argument("--no-filter", action="store_true", help="no jitter filter (raw tracker scores)")
    parser.add_argument("--no-mask", action="store_true", help="leave out the face_found mask channel")
    add_landmarker(parser, type=input_file)
    parser.add_argument("--no-cache", action="store_true", help="track the video again even when cached")
    add_workers(parser, help=TRACK_WORKERS_HELP)
    add_quiet(parser)
    parser.set_defaults(handler=run)


def _positive_hz(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"bad cut-off {text!r}: give a positive frequency in Hz (e.g. 2)")
    return value


def run(args: argparse.Namespace) -> int:
    """Capture ``args.recording`` and write the clip to ``args.output``."""
    import warnings
    from dataclasses import replace

    from mien.capture import CaptureSettings, capture_file, neutral_from_image
    from mien.commands._checks import refuse_option
    from mien.errors import InvalidValueError
    from mien.exchange import format_for, writer_for

    if args.output.suffix.lower() not in _OUTPUT_SUFFIXES:
        raise InvalidValueError(
            "output", str(args.output), "a .csv, .json or .npz file (they carry every channel and the face_found "
            "mask; convert it afterwards with `mien export CLIP -o OUT`)"
        )  # fmt: skip
    if args.recording.suffix.lower() == ".csv" and format_for(args.recording, "read") == "openface_csv":
        interval = args.neutral and "{:g}:{:g}".format(*args.neutral)
        options = (
            ("--neutral", interval),
            ("--neutral-image", args.neutral_image),
            ("--no-neutral", args.no_neutral),
            ("--cutoff-hz", args.cutoff_hz),
            ("--no-filter", args.no_filter),
            ("--route", "arkit" if args.route == "arkit" else None),
        )
        given = [(option, value) for option, value in options if value]
        if given:
            reason = (
                "an OpenFace CSV holds OpenFace's own AU intensities, kept as read (no scores to calibrate or filter)"
            )
            refuse_option(given[0][0], given[0][1], reason)
    settings = CaptureSettings(neutral_first_s=0.0 if args.no_neutral else args.neutral_first_s, neutral_s=args.neutral)
    if args.cutoff_hz is not None:
        settings = replace(settings, min_cutoff_hz=args.cutoff_hz)
    if args.no_filter:
        settings = replace(settings, filter=False)
    neutral = neutral_from_image(args.neutral_image, args.landmarker) if args.neutral_image else None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        capture = capture_file(
            args.recording,
            settings,
            neutral=neutral,
            model=args.landmarker,
            use_cache=not args.no_cache,
            show_progress=not args.quiet,
            workers=args.workers,
        )
    for warning in caught:
        print(f"mien capture: warning: {warning.message}")
    if not capture.face_found.any():
        raise InvalidValueError(
            "recording", str(args.recording), f"a recording showing a face (none was found on any of its "
            f"{capture.n_frames} frames; a face too small or too dark is not found either)"
        )  # fmt: skip
    clip = capture.clip(args.route, mask=not args.no_mask)
    writer_for(args.output)(clip, args.output)
    print(capture.report())
    print(f"wrote {args.output} ({clip.n_frames} frames at {clip.fps:.2f} fps, {len(clip.channels)} channels)")
    return 0
