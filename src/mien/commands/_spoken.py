"""``mien say TEXT -o out.glb``: a spoken clip in any clip format with its sound beside it (out.wav).

:func:`check_clip_output` runs before the speech is made (a wrong suffix fails first); :func:`export_spoken`
writes the clip and the sound with :func:`mien.exchange.spoken.write_spoken`.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mien.facs.clip import Clip
    from mien.speech.track import Utterance


def check_clip_output(out: Path) -> None:
    """Refuse (typed error naming it) an output that is neither .mp4 nor a clip format mien writes."""
    from mien.errors import InvalidValueError, UnknownNameError
    from mien.exchange import format_for, writable_suffixes
    from mien.exchange.spoken import sound_path

    try:
        format_for(out, "write")
    except UnknownNameError:
        known = ", ".join(sorted(writable_suffixes()))
        raise InvalidValueError("output", str(out), f"an .mp4 video, or a clip file ({known}) with its .wav") from None
    sound_path(out)


def export_spoken(args: argparse.Namespace, clip: Clip, utterance: Utterance) -> int:
    """Write ``clip`` to ``args.output`` (a .glb/.vrm on the ``--head``) and the utterance's sound beside it."""
    from mien.exchange import format_for, format_module
    from mien.exchange.spoken import HEAD_FORMATS, write_spoken

    out: Path = args.output
    out.parent.mkdir(parents=True, exist_ok=True)
    name = format_for(out, "write")
    rig = None
    if name in HEAD_FORMATS:
        from mien.commands._scene import scene_from_args

        rig = scene_from_args(args)[0]
    what = f"{utterance.source}: {len(utterance.segments)} segments, {clip.n_frames} frames at {clip.fps:g} fps"
    if utterance.audio is None:
        format_module(name).write(clip, out, **({"rig": rig} if rig is not None else {}))
        print(f"{what}, no sound: {out}")
        return 0
    target, wav = write_spoken(clip, utterance.audio, out, rig=rig)
    print(f"{what}: {target} (sound: {wav})")
    return 0
