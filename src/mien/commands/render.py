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

DEFAULT_FOLDER = "mien-output"
"""Where outputs go without -o, named after what is rendered."""

MAX_CLIP_VIDEO_FPS = 120.0
"""A clip file above this rate (frames per second) renders at VIDEO_FPS unless --fps says otherwise."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "render",
        help="render an emotion, AUs, a laugh or a clip file to MP4 / PNG",
        description="Render a face: WHAT is an emotion or blend (joy, evil...), one or more AUs (AU6C AU12C), "
        "a laugh type (laughter, stifled_smile...; also `laughter TYPE`), or a clip file of any format mien "
        "reads (.csv curves, Live Link Face or OpenFace CSV, .json, .jsonl, .npz, .anim, .glb), with face "
        "channels, ARKit weights or laughter-controller curves (`mien laugh -o x.anim`). The output is an MP4, a "
        "PNG still (the expression's peak) or, for a path without suffix, a folder of PNG frames; without -o it "
        "is named after WHAT in mien-output/ and an existing file there is kept unless --force. A clip file "
        "renders at its own rate, resampled with --fps; a clip above "
        f"{MAX_CLIP_VIDEO_FPS:g} fps (a 1000 fps OpenFace file) renders at {VIDEO_FPS:g} fps unless --fps says "
        "otherwise.",
    )
    parser.add_argument("what", nargs="+", help="emotion name, AU codes, laugh type, or a clip file")
    add_output(
        parser,
        type=output_target,
        help="an .mp4, a .png still, or a folder of PNG frames (a path without suffix); folders are made "
        f"(default {DEFAULT_FOLDER}/WHAT.mp4, e.g. {DEFAULT_FOLDER}/joy.mp4, {DEFAULT_FOLDER}/take.mp4 for take.csv)",
    )
    parser.add_argument(
        "--force", action="store_true", help=f"replace an existing output in {DEFAULT_FOLDER}/ when -o is not given"
    )
    parser.add_argument(
        "--intensity", type=float, help="emotion intensity (default 1.2) or laugh gain (default 1); not for a clip file"
    )
    parser.add_argument("--duration", type=positive_seconds, help="seconds (default 2.5; not for a clip file)")
    parser.add_argument(
        "--fps",
        type=positive_fps,
        help=f"frames per second (default {VIDEO_FPS:g}; a clip file: its own rate, resampled to this one)",
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
    from mien.commands._clips import read_input_clip
    from mien.errors import MienError, UnknownNameError
    from mien.exchange import READERS
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.facs.intensity import parse_au

    first = args.what[0]
    if len(args.what) == 1 and (Path(first).suffix.lower() in READERS or "/" in first):
        if not Path(first).is_file():  # a typo'd file name, not an unknown emotion
            raise MienError(missing_file_message(Path(first), "clip file"))
        if args.duration is not None:
            refuse_option("--duration", args.duration, "a clip file carries its own length")
        for option, value in (("--intensity", args.intensity), ("--seed", args.seed)):
            if value is not None:
                refuse_option(option, value, "a clip file is rendered as it is")
        if args.no_idle:
            refuse_option("--no-idle", True, "a clip file has no idle behaviour added")
        clip, messages = read_input_clip(Path(first), None, "render")
        for message in messages:
            print(f"mien render: warning: {message}")
        still = args.output is not None and args.output.suffix.lower() == ".png"
        clip = _clip_rate(clip, args.fps, first, still)
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


def _clip_rate(clip: Clip, fps: float | None, name: str, still: bool = False) -> Clip:
    """``clip`` resampled to ``fps`` when given, else, for a video (not a ``still``), to VIDEO_FPS above
    MAX_CLIP_VIDEO_FPS; said on stdout."""
    from mien.exchange.timing import resample

    if fps is None and clip.fps > MAX_CLIP_VIDEO_FPS and not still:
        fps = VIDEO_FPS
        print(
            f"{name} runs at {clip.fps:g} fps: rendering at {fps:g} fps (over {MAX_CLIP_VIDEO_FPS:g} fps a video "
            "gains nothing; --fps chooses)"
        )
    if fps is None or fps == clip.fps:
        return clip
    resampled = resample(clip, fps, cover_end=True)  # the last frame held: no part of the clip is lost
    print(f"{name}: {clip.n_frames} frames at {clip.fps:g} fps resampled to {resampled.n_frames} at {fps:g} fps")
    return resampled


def _default_output(what: list[str], force: bool) -> Path:
    """``mien-output/<WHAT>.mp4`` (a clip file's stem, or the words joined by ``_``); an existing one is refused
    without ``force``."""
    import re

    from mien.errors import InvalidValueError

    first = Path(what[0])
    is_file = len(what) == 1 and first.suffix != "" and first.is_file()
    stem = first.stem if is_file else "_".join(what)
    stem = re.sub(r"[^A-Za-z0-9_.+-]+", "_", stem).strip("._") or "render"
    out = Path(DEFAULT_FOLDER) / f"{stem}.mp4"
    if out.exists() and not force:
        raise InvalidValueError(
            "output", str(out), "a new file: it exists already; give --force to replace it, or -o another path"
        )
    return out


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
    import warnings

    from mien.commands._clips import refuse_foreign_channels
    from mien.render.clip_render import render_clip, render_still
    from mien.render.video import write_png
    from mien.rig.face_weights import clip_to_rig, is_controller_clip

    out: Path = args.output if args.output is not None else _default_output(args.what, args.force)
    clip, features, peak = _face_clip(args)
    rig, camera, size = scene_from_args(args)
    refuse_foreign_channels(clip, Path(args.what[0]), rig.target_names)
    if is_controller_clip(clip) and not any(c in rig.target_names for c in clip.channels):
        print("laughter controller curves: rendered through the controllers' ARKit mapping")
    if features is not None:
        from mien.rig.animate import face_to_rig

        weights, poses = face_to_rig(rig, clip, features)
    else:  # face channels through the AU mapping, or the head's own target names (ARKit weights) as they are
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            weights, poses = clip_to_rig(clip, rig)
        for warning in caught:
            print(f"mien render: warning: {warning.message}")
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.suffix.lower() == ".png":
        write_png(render_still(rig, weights[peak], camera, size, poses[peak]), out)
    else:
        render_clip(rig, weights, out, clip.fps, camera, size, poses, progress=not args.quiet)
    print(f"rendered {rig.name} head: {out}")
    return 0
