"""``mien laugh``: generate a laugh or smile of one of the 13 types and export it or print a summary."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, output_file, positive_fps, positive_seconds
from mien.commands._vocabulary import ANIMATION_FPS, add_output

__all__ = ["register", "run"]


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``laugh`` subcommand."""
    parser = subparsers.add_parser(
        "laugh",
        help="generate a laugh or smile (13 types) as controller curves and a face clip",
        description="Generate a laugh or smile from the laugh library (built-in unless --library) and the "
        "taxonomy. Writes the face clip (AU intensities + head pose) to .csv/.json/.npz, the rig controller "
        "curves to .anim (Maya, as in Mascaro et al. 2021), or prints a summary.",
    )
    parser.add_argument("type", nargs="?", help="laugh type id (see --list), e.g. sly_smile")
    parser.add_argument("--intensity", type=float, default=1.0, help="gain 0..5, 1 = typical (default 1)")
    parser.add_argument("--duration", type=positive_seconds, default=None, help="length in seconds (default: typical)")
    parser.add_argument("--seed", type=int, default=0, help="random seed for natural variation (default 0)")
    parser.add_argument(
        "--fps", type=positive_fps, default=ANIMATION_FPS, help="frames per second (default %(default)s)"
    )
    parser.add_argument("--library", default=None, type=input_file, help="a learned library .npz (default: built-in)")
    add_output(parser, type=output_file, metavar="FILE", help="output file: .csv, .json, .npz or .anim")
    parser.add_argument(
        "--curves",
        choices=("auto", "face", "controllers"),
        default="auto",
        help="which curves to write: face AUs, rig controllers, or auto (controllers for .anim, else face)",
    )
    parser.add_argument("--plot", default=None, type=output_file, help="also plot the curves to this PNG")
    parser.add_argument("--list", action="store_true", help="list the 13 types and exit")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    """Handle ``mien laugh``; returns the exit code."""
    from pathlib import Path

    from mien.errors import InvalidValueError
    from mien.laughter.taxonomy import TAXONOMY

    if args.list and args.type:
        raise InvalidValueError("type", args.type, "no laugh type with --list (it lists them all)")
    if args.curves != "auto" and not args.output:
        raise InvalidValueError("--curves", args.curves, "-o FILE as well (--curves chooses what that file holds)")
    if args.list:
        for name, r in TAXONOMY.items():
            aus = " ".join(f"AU{code}{side or ''}={value:g}" for code, side, value in r.aus)
            print(f"{name:22s} {r.label:28s} {aus}")
        return 0
    if not args.type:
        raise InvalidValueError("type", None, "a laugh type (mien laugh --list shows them)")

    from mien.commands._checks import check_curve_request
    from mien.exchange import writer_for
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.laughter.generator import generate
    from mien.laughter.library import load_library
    from mien.laughter.names import CONTROLLER_NAMES

    if args.duration is not None:
        check_curve_request(args.duration, args.fps, 2 * (len(FACE_CHANNELS) + len(CONTROLLER_NAMES)))
    library = load_library(args.library) if args.library else None
    result = generate(args.type, args.intensity, args.duration, args.seed, args.fps, library)
    if args.output:
        curves = args.curves
        if curves == "auto":
            curves = "controllers" if Path(args.output).suffix.lower() == ".anim" else "face"
        clip = result.controllers if curves == "controllers" else result.face_clip
        writer_for(args.output)(clip, args.output)
        print(f"wrote {curves.rstrip('s')} curves ({clip.n_frames} frames at {clip.fps:g} fps) to {args.output}")
    if args.plot:
        from mien.laughter.generator import plot_result

        plot_result(result, args.plot)
        print(f"wrote plot to {args.plot}")
    if not args.output and not args.plot:
        print(summary(result))
    return 0


def summary(result: object) -> str:
    """Text summary of a :class:`~mien.laughter.generator.LaughResult`: duration, pulses, AU peaks."""
    import numpy as np

    from mien.laughter.generator import LaughResult

    assert isinstance(result, LaughResult)
    face = result.face_clip
    lines = [
        f"{result.type}: {result.duration_s:.2f} s at {face.fps:g} fps, intensity {result.intensity:g}, "
        f"seed {result.seed}, {len(result.pulse_times_s)} laughter pulses"
    ]
    peaks = np.abs(face.values).max(axis=0)
    active = [(name, peaks[i]) for i, name in enumerate(face.channels) if peaks[i] > 0.05]
    lines.append("peaks: " + ", ".join(f"{name} {value:.2f}" for name, value in active))
    return "\n".join(lines)
