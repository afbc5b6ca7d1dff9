"""``mien demo``: the main job. Six basic emotions and four blends on the default head -> MP4 + contact sheet."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from mien.affect.emotions import STUDY_EXPRESSIONS
from mien.commands._checks import check_curve_request, output_folder, positive_fps
from mien.commands._scene import add_scene_options, scene_from_args
from mien.commands._vocabulary import VIDEO_FPS, add_output, add_quiet

if TYPE_CHECKING:
    import numpy as np

    from mien.facs.clip import Clip

DEMO_SEQUENCE = STUDY_EXPRESSIONS
"""The Broekens study's ten stimuli: six basic emotions, then the four blends."""

SEGMENT_S = 2.0
"""Seconds per expression in the demo video."""


_RIG_VALUES_PER_FRAME = 128
"""Upper bound of the morph-target weights and pose values held per frame (ICT-FaceKit: 57 + 6)."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "demo",
        help="render the six basic emotions and four blends to an MP4 and a contact sheet",
        description="The main job: a face expressing joy, sadness, anger, surprise, disgust, fear and the "
        "blends enthusiastic, furious, frustrated and evil (Broekens et al.), with blinks and idle motion, "
        "rendered on the default head (ICT-FaceKit if installed, else the built-in head).",
    )
    add_output(
        parser,
        type=output_folder,
        default=Path("mien-output"),
        metavar="DIR",
        help="output folder, made if missing (default %(default)s)",
        old=("--out",),
    )
    parser.add_argument(
        "--intensity", type=float, default=1.2, help="emotion intensity, 1.2 as in the study (default %(default)s)"
    )
    parser.add_argument("--fps", type=positive_fps, default=VIDEO_FPS, help="frames per second (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="idle-behaviour seed")
    parser.add_argument("--no-video", action="store_true", help="only the curves, plot and contact sheet")
    add_scene_options(parser)
    add_quiet(parser)
    parser.set_defaults(handler=run)


def demo_clip(
    intensity: float, fps: float, seed: int, basis: str
) -> tuple[Clip, np.ndarray | None, list[tuple[float, str]]]:
    """(face clip, feature weights or None, [(peak time s, label)]) of the demo sequence."""
    from mien.character import Character
    from mien.facs.envelope import Envelope

    character = Character(seed=seed, expression_basis=basis)
    envelope = Envelope(onset_s=0.4, hold_s=0.8, decay_s=0.5)  # 1.7 s: the paper's 1-2 s advice for real use
    peaks = []
    for k, name in enumerate(DEMO_SEQUENCE):
        start = k * SEGMENT_S + 0.2
        character.emote(name, intensity, start_s=start, envelope=envelope)
        peaks.append((start + 0.4 + 0.4, name))
    clip = character.run(SEGMENT_S * len(DEMO_SEQUENCE), fps)
    return clip, getattr(character, "last_feature_weights", None), peaks


def head_line(name: str, n_vertices: int, n_targets: int, camera: str) -> str:
    """The one line saying which head the demo (and so the quick start) used and how to get the realistic one."""
    from mien.assets.fetch import SOURCES
    from mien.paths import asset_path

    line = f"head: {name} ({n_vertices:,} vertices, {n_targets} morph targets); camera: {camera}"
    if name == "ict-facekit":
        return line.replace(" (", " (the realistic head: ", 1)
    if not name.startswith("builtin"):
        return line
    line = line.replace(" (", " (the stylised built-in head: ", 1)
    installed = asset_path("ict_facekit")
    if installed is not None and installed.exists():
        return f"{line}; the realistic head is installed: add --head ict"
    size_mb = SOURCES["ict-facekit"].download_bytes / 1e6
    return f"{line}; for the realistic head run `mien assets fetch ict-facekit` ({size_mb:.0f} MB), then this again"


def run(args: argparse.Namespace) -> int:

    from mien.exchange.curves_csv import write as write_csv
    from mien.facs.catalogue import FACE_CHANNELS
    from mien.plot import plot_clip
    from mien.progress import progress
    from mien.render.clip_render import iter_frames, make_renderer
    from mien.render.contact_sheet import contact_sheet
    from mien.render.video import Mp4Writer, write_png
    from mien.rig.animate import face_to_rig

    out: Path = args.output
    # curves, plus per-frame rig weights and poses (frames themselves are streamed, one at a time)
    check_curve_request(SEGMENT_S * len(DEMO_SEQUENCE), args.fps, len(FACE_CHANNELS) + _RIG_VALUES_PER_FRAME)
    out.mkdir(parents=True, exist_ok=True)
    clip, features, peaks = demo_clip(args.intensity, args.fps, args.seed, args.basis)
    rig, camera, size = scene_from_args(args)
    print(head_line(rig.name, rig.n_vertices, len(rig.targets), args.camera))
    curves = write_csv(clip, out / "demo_curves.csv")
    plot = plot_clip(clip, out / "demo_curves.png", title="mien demo: AU curves", events=[(t, n) for t, n in peaks])
    weights, poses = face_to_rig(rig, clip, features)
    peak_frames = {min(clip.n_frames - 1, round(t * clip.fps)): name for t, name in peaks}
    stills: dict[str, np.ndarray] = {}
    video = out / "demo.mp4"
    with make_renderer(rig, camera, size) as renderer:
        if args.no_video:
            indices = sorted(peak_frames)
            frames = iter_frames(rig, weights[indices], renderer, poses[indices])
            for index, image in zip(indices, frames, strict=True):
                stills[peak_frames[index]] = image
        else:
            with Mp4Writer(video, clip.fps) as writer:
                frames = iter_frames(rig, weights, renderer, poses)
                shown = progress(frames, clip.n_frames, "rendering demo.mp4", enabled=not args.quiet)
                for index, image in enumerate(shown):
                    writer.write(image)
                    if index in peak_frames:
                        stills[peak_frames[index]] = image
    sheet = write_png(
        contact_sheet([stills[name] for name in DEMO_SEQUENCE], list(DEMO_SEQUENCE), columns=5),
        out / "demo_contact_sheet.png",
    )
    print("wrote:")
    if not args.no_video:
        print(f"  video          {video}  ({clip.n_frames} frames, {clip.duration_s:.0f} s at {clip.fps:g} fps)")
    print(f"  contact sheet  {sheet}")
    print(f"  AU curves      {curves}")
    print(f"  curve plot     {plot}")
    return 0
