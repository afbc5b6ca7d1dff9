"""``mien au``: FACS action units -> AU curves, with time-based or OpenFACS Speed dynamics."""

from __future__ import annotations

import argparse

from mien.commands._checks import check_curve_request, non_negative_seconds, positive_seconds
from mien.commands._curves import add_curve_options, emit_curves


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "au",
        help="drive action units (e.g. AU6C AU12C) and output the AU curves",
        description="Hold (or play once) FACS action units and output the face's AU curves. AUs are written "
        "AU12, 12C, AU12C, AU12L, L12C...; a missing letter means C (3).",
    )
    parser.add_argument("aus", nargs="+", metavar="AU", help="action units with optional side and A..E letter")
    dynamics = parser.add_mutually_exclusive_group()
    dynamics.add_argument("--tau", type=positive_seconds, help="time constant in seconds for the held AUs")
    dynamics.add_argument("--speed", type=float, help="OpenFACS Speed 0..1 per tick at 60 Hz")
    parser.add_argument(
        "--play",
        nargs=3,
        type=non_negative_seconds,
        metavar=("ONSET", "APEX", "OFFSET"),
        help="play the AUs once with these onset/apex/offset seconds instead of holding them",
    )
    parser.add_argument(
        "--start", type=non_negative_seconds, default=0.2, help="when the AUs start, seconds (default %(default)s)"
    )
    add_curve_options(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from mien.character import Character
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.intensity import parse_au

    specs = [parse_au(text) for text in args.aus]  # all validated before anything runs
    check_curve_request(args.duration, args.fps, len(FACE_CHANNELS))
    character = Character(seed=args.seed, idle=not args.no_idle)
    fps = args.fps
    n_before = max(0, round(args.start * fps))
    if args.play:
        onset, apex, offset = args.play
        for spec in specs:
            character.play_au(spec, None, onset_s=onset, apex_s=apex, offset_s=offset, start_s=args.start)
        clip = character.run(args.duration, fps)
    else:
        head = character.run(n_before / fps, fps).values if n_before else None
        if args.speed is not None:
            character.set_aus({spec.label: spec.intensity or 3.0 for spec in specs}, speed=args.speed)
        else:
            for spec in specs:
                character.set_au(spec, None, tau_s=args.tau)
        tail = character.run(max(args.duration - n_before / fps, 1 / fps), fps)
        import numpy as np

        from mien.facs.clip import Clip

        clip = tail if head is None else Clip(np.vstack([head, tail.values]), fps, tail.channels)
    emit_curves(clip, args, " ".join(spec.label for spec in specs), events=[(args.start, "start")])
    return 0
