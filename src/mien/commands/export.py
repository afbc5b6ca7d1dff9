"""``mien export INPUT -o OUTPUT``: any clip file mien reads -> any format it writes (.glb with the head)."""

from __future__ import annotations

import argparse

from mien.commands._checks import input_file, output_file, positive_fps
from mien.commands._vocabulary import add_head, add_output


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "export",
        help="convert a clip file to another format (.glb, .anim, Live Link CSV, .jsonl...)",
        description="Read INPUT (any format mien reads: .csv curves, Live Link Face or OpenFace CSV, .json, "
        ".jsonl, .npz, .anim, .glb) and write -o OUTPUT in the format its suffix names: .glb (the head with the "
        "clip as animations of its morph weights and head rotation; with --head face.glb, the user's own file, "
        "textures and skin kept, its own shapes and head/eye bones animated), .vrm (VRM 1.0: the head with the "
        "VRM expression presets made from mien's emotion prototypes), .anim (Maya curves), .csv (time_s curves; "
        "--format arkit_csv for Live Link Face, --names file for the head file's own shape names), .json, .jsonl "
        "(OpenFACS; ARKit weights and laughter controllers become AU intensities by the NNLS solve of `mien "
        "import --au`), .npz. Laughter-controller curves (`mien laugh -o x.anim`) reach a head through the "
        "controllers' ARKit mapping; a head's targets beyond ARKit's 52 are skipped with a warning where the output "
        "has no place for them. Formats are in docs/FORMATS.md.",
    )
    parser.add_argument("input", type=input_file, help="clip file to read")
    add_output(
        parser,
        type=output_file,
        metavar="FILE",
        required=True,
        positional=True,
        help="file to write; its suffix picks the format",
    )
    add_head(
        parser,
        default=None,
        help="head for .glb and .vrm: default, builtin or ict, with an optional identity (builtin:b, ict:a), or "
        "a character file (face.glb, avatar.vrm, file:PATH); with --names file, the head whose shape names a "
        "Live Link CSV takes",
    )
    parser.add_argument(
        "--names",
        choices=("arkit", "file"),
        default="arkit",
        help="Live Link CSV columns: ARKit's names (default) or the own shape names of the --head character file",
    )
    parser.add_argument("--fps", type=positive_fps, help="resample the clip to this frame rate before writing")
    parser.add_argument("--format", help="output format when several share a suffix (arkit_csv for .csv)")
    parser.add_argument("--input-format", help="input format when its suffix and header do not tell")
    parser.add_argument(
        "--audio",
        type=input_file,
        help="the clip's sound (WAV, MP3, OGG...): written beside OUTPUT as a WAV of the same stem (out.glb + "
        "out.wav; no clip format carries sound), starting with the clip's first frame",
    )
    parser.set_defaults(handler=run)


AU_ONLY_FORMATS = ("openfacs_jsonl",)
"""Output formats that carry AU intensities only (OpenFACS messages): weight and controller clips are solved
into AUs for them."""

ANY_CHANNEL_FORMATS = ("curves_csv", "clip_json", "clip_npz")
"""Output formats that carry channels of any name."""


def run(args: argparse.Namespace) -> int:
    import warnings

    from mien.commands._checks import refuse_option
    from mien.commands._clips import clip_vocabulary, read_input_clip, refuse_foreign_channels
    from mien.exchange import format_for, format_module

    output_format = format_for(args.output, "write", args.format)
    carries_head = output_format in ("glb", "vrm")
    head_spec = ":".join(part for part in (args.head or "default", args.identity) if part)
    file_names = args.names == "file"
    if file_names:
        if output_format != "arkit_csv":
            refuse_option("--names", args.names, f"only Live Link CSV (--format arkit_csv) has columns to name, "
                          f"not {output_format}")  # fmt: skip
        if args.head is None:
            refuse_option("--names", args.names, "give the character file with --head face.glb")
    elif not carries_head and (args.head is not None or args.identity is not None):
        refuse_option("--head", head_spec, f"{args.output.suffix} carries no head (only .glb and .vrm do)")
    audio = None
    if args.audio is not None:  # read before anything is written: a sound that does not decode fails first
        from mien.exchange.spoken import sound_path
        from mien.speech.audio import read_audio

        wav_path = sound_path(args.output)
        audio = read_audio(args.audio)
    clip, messages = read_input_clip(args.input, args.input_format, "export")
    notes = []
    if output_format not in ANY_CHANNEL_FORMATS and not carries_head:
        refuse_foreign_channels(clip, args.input)
    if output_format in AU_ONLY_FORMATS and clip_vocabulary(clip) in ("arkit", "controllers"):
        from mien.rig.face_weights import weights_to_au

        notes.append(f"{clip_vocabulary(clip)} curves -> AU intensities (NNLS solve, as `mien import --au`)")
        with warnings.catch_warnings(record=True) as solved:
            warnings.simplefilter("always")
            clip = weights_to_au(clip)
        messages += [str(w.message) for w in solved]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if args.fps is not None:
            from mien.exchange.timing import resample

            clip = resample(clip, args.fps)
        write = format_module(output_format).write
        if carries_head or file_names:
            from mien.heads import load_head

            rig = load_head(args.head or "default", args.identity)
            refuse_foreign_channels(clip, args.input, rig.target_names)
            if file_names:
                write(clip, args.output, rig=rig, names="file")
                done = f"with the shape names of {rig.name}"
            else:
                write(clip, args.output, rig=rig)
                done = f"on the {rig.name} head"
        else:
            write(clip, args.output)
            done = f"({output_format})"
    if audio is not None:
        audio.write_wav(wav_path)
        clip_end_s = (clip.n_frames - 1) / clip.fps
        if audio.duration_s > clip_end_s + 1.0 / clip.fps:
            messages.append(f"the sound lasts {audio.duration_s:.2f} s, the clip {clip_end_s:.2f} s: the face stops")
        notes.append(f"sound beside it: {wav_path}")
    for message in [*messages, *(str(w.message) for w in caught)]:
        print(f"mien export: warning: {message}")
    for note in notes:
        print(f"mien export: {note}")
    print(f"exported {clip.n_frames} frames at {clip.fps:g} fps {done}: {args.output}")
    return 0
