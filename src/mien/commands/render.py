"""``mien render``: an emotion, AUs, a laugh type or a clip file -> MP4 video, PNG frames or a PNG still."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from mien.commands._checks import output_target, positive_fps, positive_seconds
from mien.commands._scene import add_scene_options, scene_from_args
from mien.commands._vocabulary import VIDEO_FPS, add_output, add_quiet

if TYPE_CHECKING:
    import numpy as np

    from mien.facs.clip import Clip


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "render",
        help="render an emotion, AUs, a laugh or a clip file to MP4 / PNG",
        description="Render a face: WHAT is an emotion or blend (joy, evil...), one or more AUs (AU6C AU12C), "
        "a laugh type (laughter, stifled_smile...; also `laughter TYPE`), or a clip file of any format mien "
        "reads (.csv curves, Live Link Face or OpenFace CSV, .json, .jsonl, .npz, .anim, .glb), with face "
        "channels or ARKit weights. The output is an MP4, a PNG still (the expression's peak) or, for a path "
        "without suffix, a folder of PNG frames.",
    )
    parser.add_argument("what", nargs="+", help="emotion name, AU codes, laugh type, or a clip file")
    add_output(
        parser,
        type=output_target,
        default=Path("mien-output/render.mp4"),
        help="an .mp4, a .png still, or a folder of PNG frames (a path without suffix); folders are made "
        "(default %(default)s)",
    )
    parser.add_argument(
        "--intensity", type=float, help="emotion intensity (default 1.2) or laugh gain (default 1); not for a clip file"
    )
    parser.add_argument("--duration", type=positive_seconds, help="seconds (default 2.5; not for a clip file)")
    parser.add_argument(
        "--fps", type=positive_fps, help=f"frames per second (default {VIDEO_FPS:g}; not for a clip file)"
    )
    parser.add_argument("--seed", type=int, help="idle-behaviour or laugh seed (default 0; not for a clip file)")
    parser.add_argument("--no-idle", action="store_true", help="no blinks, micro-motion, gaze or wobble")
    add_scene_options(parser)
    add_quiet(parser)
    parser.set_defaults(handler=run)


def _face_clip(args: argparse.Namespace) -> tuple[Clip, np.ndarray | None, int]:
    """(face clip, feature weights or None, frame index of the peak)."""
    from mien.character import Character
    from mien.commands._checks import check_curve_request, missing_file_message, refuse_option
    from mien.errors import InvalidValueError, MienError, UnknownNameError
    from mien.exchange import READERS, reader_for
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.intensity import parse_au

    first = args.what[0]
    if len(args.what) == 1 and (Path(first).suffix.lower() in READERS or "/" in first):
        if not Path(first).is_file():  # a typo'd file name, not an unknown emotion
            raise MienError(missing_file_message(Path(first), "clip file"))
        for option, value in (("--fps", args.fps), ("--duration", args.duration)):
            if value is not None:
                refuse_option(option, value, "a clip file carries its own frame rate and length")
        for option, value in (("--intensity", args.intensity), ("--seed", args.seed)):
            if value is not None:
                refuse_option(option, value, "a clip file is rendered as it is")
        if args.no_idle:
            refuse_option("--no-idle", True, "a clip file has no idle behaviour added")
        clip = reader_for(first)(first)
        if clip.n_frames == 0:
            raise InvalidValueError(first, "no frames", "a clip file with at least one row of values")
        face = [j for j, name in enumerate(clip.channels) if not name.endswith("_deg")]
        return clip, None, int(abs(clip.values[:, face]).sum(axis=1).argmax()) if face else 0
    laugh = _laugh_type(args.what)
    if laugh is not None:
        return _laugh_clip(args, laugh)
    args.fps = VIDEO_FPS if args.fps is None else args.fps
    args.seed = 0 if args.seed is None else args.seed
    args.intensity = 1.2 if args.intensity is None else args.intensity
    args.duration = 2.5 if args.duration is None else args.duration
    check_curve_request(args.duration, args.fps, len(FACE_CHANNELS) + 128)  # curves + rig weights per frame
    character = Character(seed=args.seed, idle=not args.no_idle, expression_basis=args.basis)
    try:
        specs = [parse_au(text) for text in args.what]
    except UnknownNameError:
        specs = []
    if specs:
        for spec in specs:
            character.play_au(spec, None, onset_s=0.4, apex_s=max(0.1, args.duration - 1.2), offset_s=0.5, start_s=0.2)
        peak_s = 0.2 + 0.4 + 0.5 * max(0.1, args.duration - 1.2)
    else:
        from mien.affect.emotions import resolve_emotion
        from mien.facs.envelope import Envelope

        hold = max(0.3, args.duration - 1.5)
        character.emote(
            resolve_emotion(" ".join(args.what)), args.intensity, start_s=0.2, envelope=Envelope(0.4, hold, 0.5)
        )
        peak_s = 0.2 + 0.4 + 0.5 * hold
    clip = character.run(args.duration, args.fps)
    return clip, getattr(character, "last_feature_weights", None), min(clip.n_frames - 1, int(peak_s * args.fps))


def _laugh_type(what: list[str]) -> str | None:
    """The laugh type named by ``what`` (``laughter``, ``stifled_smile``, or ``laughter TYPE``), else None."""
    from mien.laughter.names import LAUGH_TYPES

    if len(what) == 1 and what[0] in LAUGH_TYPES:
        return what[0]
    if len(what) == 2 and what[0] in ("laughter", "laugh") and what[1] in LAUGH_TYPES:
        return what[1]
    return None


def _laugh_clip(args: argparse.Namespace, laugh: str) -> tuple[Clip, np.ndarray | None, int]:
    """(face clip of a generated laugh, None, frame index of its strongest frame)."""
    import numpy as np

    from mien.commands._checks import check_curve_request, refuse_option
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.laughter.generator import generate

    if args.no_idle:
        refuse_option("--no-idle", True, "a generated laugh has no idle behaviour")
    if args.basis != "facs":
        refuse_option("--basis", args.basis, "a laugh drives AUs (the facs basis)")
    fps = VIDEO_FPS if args.fps is None else args.fps
    if args.duration is not None:
        check_curve_request(args.duration, fps, len(FACE_CHANNELS) + 128)
    intensity = 1.0 if args.intensity is None else args.intensity
    result = generate(laugh, intensity, args.duration, args.seed or 0, fps)
    clip = result.face_clip
    face = [j for j, name in enumerate(clip.channels) if not name.endswith("_deg")]
    return clip, None, int(np.abs(clip.values[:, face]).sum(axis=1).argmax())


def run(args: argparse.Namespace) -> int:
    from mien.render.clip_render import render_clip, render_still
    from mien.render.video import write_png
    from mien.rig.face_weights import clip_to_rig

    clip, features, peak = _face_clip(args)
    rig, camera, size = scene_from_args(args)
    if features is not None:
        from mien.rig.animate import face_to_rig

        weights, poses = face_to_rig(rig, clip, features)
    else:  # face channels through the AU mapping, or the head's own target names (ARKit weights) as they are
        weights, poses = clip_to_rig(clip, rig)
    out: Path = args.output
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.suffix.lower() == ".png":
        write_png(render_still(rig, weights[peak], camera, size, poses[peak]), out)
    else:
        render_clip(rig, weights, out, clip.fps, camera, size, poses, progress=not args.quiet)
    print(f"rendered {rig.name} head: {out}")
    return 0
