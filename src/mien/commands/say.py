"""``mien say``: a talking face -> an MP4 with its sound in sync (espeak-ng text, a timing file, or audio)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import TYPE_CHECKING

from mien.commands._checks import input_file, output_file, positive_fps
from mien.commands._scene import add_scene_options, scene_from_args
from mien.commands._vocabulary import VIDEO_FPS, add_output, add_quiet

if TYPE_CHECKING:
    from mien.speech.track import Utterance

TAIL_S = 0.4
"""Seconds of video after the utterance ends (the mouth comes to rest)."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "say",
        help="make the face speak (espeak-ng, a timing file, or audio) and render an MP4 with the sound",
        description="Make the face say TEXT (spoken by espeak-ng through libespeak-ng, which gives each phoneme's "
        "timing), or follow a phoneme/viseme timing file (--timing: mien's JSON or CSV, or OpenFaceFX's "
        "track.json) with its audio (--audio), or audio alone (--audio: the jaw follows the sound's energy). "
        "Speech owns the lips' opening and rounding and the jaw; --emotion keeps the brows, lids, cheeks and lip "
        "corners. The MP4 carries the sound, in sync; the sound is also kept as a WAV next to it.",
    )
    parser.add_argument("text", nargs="?", help="what to say (spoken by espeak-ng)")
    add_output(parser, type=output_file, required=True, help="the .mp4 to write (its .wav is kept next to it), or "
               "a clip file (.glb with the head, .anim, .csv, .json...) with its sound beside it as .wav")  # fmt: skip
    parser.add_argument("--language", default="en", help="espeak-ng voice for TEXT (default %(default)s)")
    parser.add_argument("--rate", type=int, default=175, help="speaking rate, words per minute (default %(default)s)")
    parser.add_argument("--timing", type=input_file, help="phoneme/viseme timing (.json, .csv) or OpenFaceFX track")
    parser.add_argument("--audio", type=input_file, help="the sound (WAV, MP3...): with --timing, or alone")
    parser.add_argument("--emotion", help="an emotion or blend held while speaking (joy, sadness, evil...)")
    parser.add_argument("--intensity", type=float, default=1.0, help="emotion intensity 0..5 (default %(default)s)")
    parser.add_argument("--fps", type=positive_fps, default=VIDEO_FPS, help="frames per second (default %(default)s)")
    parser.add_argument("--seed", type=int, default=0, help="idle-behaviour seed (default %(default)s)")
    parser.add_argument("--no-idle", action="store_true", help="no blinks, micro-motion, gaze or wobble")
    add_scene_options(parser)
    add_quiet(parser)
    parser.set_defaults(handler=run)


def utterance_from_args(args: argparse.Namespace) -> Utterance:
    """The utterance TEXT, ``--timing`` and ``--audio`` name (one documented combination each)."""
    from mien.commands._checks import refuse_option
    from mien.errors import InvalidValueError

    if args.text is not None and (args.timing is not None or args.audio is not None):
        option, value = ("--timing", args.timing) if args.timing is not None else ("--audio", args.audio)
        refuse_option(option, value, "TEXT is spoken by espeak-ng with its own timing and sound; give one of them")
    if args.text is not None:
        from mien.speech.espeak import speak

        return speak(args.text, args.language, args.rate)
    if args.timing is not None:
        if _is_openfacefx(args.timing):
            from mien.speech.openfacefx import read_openfacefx

            return read_openfacefx(args.timing, args.audio)
        from mien.speech.timing_file import read_timing

        return read_timing(args.timing, args.audio)
    if args.audio is not None:
        from mien.speech.audio import utterance_from_audio

        return utterance_from_audio(args.audio)
    raise InvalidValueError("text", "", "TEXT to say, a --timing file, or --audio")


def _is_openfacefx(path: Path) -> bool:
    if path.suffix.lower() != ".json":
        return False
    try:
        return json.loads(path.read_text(encoding="utf-8")).get("format") == "openfacefx.track"
    except (OSError, UnicodeDecodeError, ValueError, AttributeError):
        return False


def run(args: argparse.Namespace) -> int:
    import tempfile

    from mien.character import Character
    from mien.commands._checks import check_curve_request
    from mien.errors import InvalidValueError
    from mien.facs.envelope import Envelope
    from mien.render.clip_render import render_clip
    from mien.rig.animate import face_to_rig
    from mien.speech.audio import mux_audio

    out: Path = args.output
    spoken_clip = out.suffix.lower() != ".mp4"  # a clip file (.glb, .anim, .csv...) with its sound beside it
    if spoken_clip:
        from mien.commands._spoken import check_clip_output, export_spoken

        check_clip_output(out)
    if isinstance(args.text, str) and not args.text.strip():
        raise InvalidValueError("text", args.text, "some text to say (it is empty)")
    emotion = None
    if args.emotion is not None:
        from mien.affect.emotions import resolve_emotion

        emotion = resolve_emotion(args.emotion)
    utterance = utterance_from_args(args)
    duration = utterance.duration_s + TAIL_S
    check_curve_request(duration, args.fps, 62 + 128)
    character = Character(seed=args.seed, idle=not args.no_idle, expression_basis=args.basis)
    if emotion is not None:
        character.emote(emotion, args.intensity, start_s=0.0, envelope=Envelope(0.3, duration, 0.3))
    character.say(utterance, start_s=0.0)
    clip = character.run(duration, args.fps)
    if spoken_clip:
        return export_spoken(args, clip, utterance)
    rig, camera, size = scene_from_args(args)
    weights, poses = face_to_rig(rig, clip, character.last_feature_weights, visemes=character.last_viseme_weights)
    out.parent.mkdir(parents=True, exist_ok=True)
    if utterance.audio is None:
        render_clip(rig, weights, out, clip.fps, camera, size, poses, progress=not args.quiet)
        print(f"{utterance.source}: {len(utterance.segments)} segments, no sound; rendered {rig.name} head: {out}")
        return 0
    with tempfile.TemporaryDirectory(prefix="mien-say-", dir=out.parent) as folder:
        silent = render_clip(rig, weights, Path(folder) / "silent.mp4", clip.fps, camera, size, poses,
                             progress=not args.quiet)  # fmt: skip
        mux_audio(silent, utterance.audio, out)
    wav = utterance.audio.write_wav(out.with_suffix(".wav"))
    print(
        f"{utterance.source}: {len(utterance.segments)} segments, {utterance.duration_s:.2f} s; "
        f"rendered {rig.name} head with its sound: {out} (sound: {wav})"
    )
    return 0
