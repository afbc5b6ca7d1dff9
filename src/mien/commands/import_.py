"""``mien import INPUT -o OUTPUT``: an external recording (Live Link Face, OpenFace, OpenFACS, glTF...) -> a mien
clip (.npz or .json)."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, output_file
from mien.commands._vocabulary import add_output

CLIP_SUFFIXES = (".npz", ".json")
"""Suffixes of the mien clip files ``import`` writes."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "import",
        help="import a recording (Live Link Face / OpenFace CSV, OpenFACS .jsonl, .glb, .anim) as a mien clip",
        description="Read INPUT in any format mien reads and save it as a mien clip (-o, .npz or .json). OpenFace "
        "and OpenFACS files become AU clips; Live Link Face CSV and .glb become ARKit weight clips, or AU clips "
        "with --au (a non-negative least-squares solve of the AU -> ARKit mapping; a head's targets beyond "
        "ARKit's 52 are skipped with a warning); laughter-controller .anim curves stay controller curves, or "
        "become AU clips with --au through the controllers' ARKit mapping. Skipped columns, keys and untracked "
        "rows are reported as warnings.",
    )
    parser.add_argument("input", type=input_file, help="file to import")
    add_output(
        parser,
        type=output_file,
        metavar="FILE",
        required=True,
        positional=True,
        help="mien clip to write: .npz or .json",
    )
    parser.add_argument(
        "--au", action="store_true", help="turn ARKit weights or laughter controllers into AU intensities (0..5)"
    )
    parser.add_argument("--input-format", help="input format when its suffix and header do not tell")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import warnings

    from mien.commands._checks import refuse_option
    from mien.commands._clips import clip_vocabulary, read_input_clip
    from mien.errors import InvalidValueError
    from mien.exchange import writer_for
    from mien.facs.catalogue import FACE_CHANNELS

    if args.output.suffix.lower() not in CLIP_SUFFIXES:
        raise InvalidValueError("output", str(args.output), "a mien clip path ending in .npz or .json")
    clip, messages = read_input_clip(args.input, args.input_format, "import")
    if args.au:
        vocabulary = clip_vocabulary(clip)
        if vocabulary == "face":
            refuse_option("--au", True, f"{args.input.name} holds AU channels already, not ARKit weights")
        if vocabulary == "other":
            shown = ", ".join(clip.channels[:3])
            refuse_option("--au", True, f"{args.input.name} holds no ARKit weights or laughter controllers ({shown})")
        from mien.rig.face_weights import weights_to_au

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            clip = weights_to_au(clip)
        messages += [str(w.message) for w in caught]
    for message in messages:
        print(f"mien import: warning: {message}")
    writer_for(args.output)(clip, args.output)
    kind = "AU" if all(c in FACE_CHANNELS for c in clip.channels) else "weight"
    shape = f"{clip.n_frames} frames at {clip.fps:g} fps ({kind} clip, {len(clip.channels)} channels)"
    print(f"imported {shape}: {args.output}")
    return 0
