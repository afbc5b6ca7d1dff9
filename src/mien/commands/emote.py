"""``mien emote``: an emotion or blend event -> AU curves (Broekens envelopes on EMFACS prototypes)."""

from __future__ import annotations

import argparse

from mien.commands._checks import check_curve_request, non_negative_seconds
from mien.commands._curves import add_curve_options, emit_curves


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "emote",
        help="express an emotion or blend and output the AU curves",
        description="Trigger an emotion event (joy, sadness, anger, surprise, disgust, fear, or a blend: "
        "enthusiastic, furious, frustrated, evil) and output the face's AU curves.",
    )
    parser.add_argument("emotion", help="emotion or blend name (aliases such as happy, sad, angry work)")
    parser.add_argument("--intensity", type=float, default=1.0, help="0..5; 1 = the prototype (study: 1.2, 2.4)")
    parser.add_argument("--onset", type=non_negative_seconds, default=0.4, help="onset seconds (default %(default)s)")
    parser.add_argument("--hold", type=non_negative_seconds, default=0.3, help="hold seconds (default %(default)s)")
    parser.add_argument("--decay", type=non_negative_seconds, default=0.3, help="decay seconds (default %(default)s)")
    parser.add_argument(
        "--start", type=non_negative_seconds, default=0.2, help="event time in seconds (default %(default)s)"
    )
    add_curve_options(parser)
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    from mien.affect.emotions import resolve_emotion
    from mien.character import Character
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.envelope import Envelope

    name = resolve_emotion(args.emotion)
    check_curve_request(args.duration, args.fps, len(FACE_CHANNELS))
    character = Character(seed=args.seed, idle=not args.no_idle)
    envelope = Envelope(onset_s=args.onset, hold_s=args.hold, decay_s=args.decay)
    character.emote(name, args.intensity, start_s=args.start, envelope=envelope)
    clip = character.run(args.duration, args.fps)
    emit_curves(clip, args, f"{name} at intensity {args.intensity:g}", events=[(args.start, name)])
    return 0
