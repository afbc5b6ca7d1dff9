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
        "with --au (a non-negative least-squares solve of the AU -> ARKit mapping). Skipped columns, keys and "
        "untracked rows are reported as warnings.",
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
    parser.add_argument("--au", action="store_true", help="turn ARKit weights into AU intensities (0..5)")
    parser.add_argument("--input-format", help="input format when its suffix and header do not tell")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import warnings

    from mien.commands._checks import refuse_option
    from mien.errors import InvalidValueError
    from mien.exchange import reader_for, writer_for
    from mien.facs.arkit import ARKIT_NAMES
    from mien.facs.catalogue import FACE_CHANNELS

    if args.output.suffix.lower() not in CLIP_SUFFIXES:
        raise InvalidValueError("output", str(args.output), "a mien clip path ending in .npz or .json")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        clip = reader_for(args.input, args.input_format)(args.input)
    for warning in caught:
        print(f"mien import: warning: {warning.message}")
    if clip.n_frames == 0:
        raise InvalidValueError(str(args.input), "no frames", "a recording with at least one frame")
    if args.au:
        if not any(c in ARKIT_NAMES for c in clip.channels):
            refuse_option("--au", True, f"{args.input.name} holds AU channels already, not ARKit weights")
        from mien.rig.face_weights import weights_to_au

        clip = weights_to_au(clip)
    writer_for(args.output)(clip, args.output)
    kind = "AU" if all(c in FACE_CHANNELS for c in clip.channels) else "weight"
    shape = f"{clip.n_frames} frames at {clip.fps:g} fps ({kind} clip, {len(clip.channels)} channels)"
    print(f"imported {shape}: {args.output}")
    return 0
