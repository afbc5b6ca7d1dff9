"""A spoken clip with its sound side by side: ``out.glb`` (or any clip format) and ``out.wav``.

No clip format mien writes carries sound (glTF has no ratified audio extension; Maya ``.anim`` and the CSV and
JSON formats have none), so a talking face is exported as two files with one stem: the clip in the format
its suffix names, and its sound as 16-bit PCM mono WAV beside it, both starting at t = 0 (the clip's first
frame is the sound's first sample). ``mien say TEXT -o out.glb`` and ``mien export clip.json out.glb --audio
sound.mp3`` write them.

>>> import numpy as np, tempfile, pathlib
>>> from mien.facs.clip import Clip
>>> from mien.speech.track import Audio
>>> clip = Clip(np.zeros((31, 1)), 30.0, ("AU26",))
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> [p.name for p in write_spoken(clip, Audio(np.zeros(22050, np.float32), 22050), folder / "hi.json")]
['hi.json', 'hi.wav']
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from mien.errors import InvalidValueError
from mien.exchange import format_for, format_module
from mien.facs.clip import Clip
from mien.speech.track import Audio

__all__ = ["HEAD_FORMATS", "sound_path", "write_spoken"]

HEAD_FORMATS = ("glb", "vrm")
"""Formats that carry the head with the clip (they need a rig)."""


def sound_path(path: str | os.PathLike[str]) -> Path:
    """Where the sound of the clip at ``path`` goes: the same stem, ``.wav``.

    >>> sound_path("out/hello.glb").as_posix()
    'out/hello.wav'
    """
    target = Path(path)
    if target.suffix.lower() == ".wav":
        raise InvalidValueError("output", str(path), "a clip file (.glb, .anim, .csv...): its sound goes beside it")
    return target.with_suffix(".wav")


def write_spoken(
    clip: Clip, audio: Audio, path: str | os.PathLike[str], *, rig: Any = None, format: str | None = None
) -> tuple[Path, Path]:
    """Write ``clip`` to ``path`` in its suffix's format (``format`` forces one; ``.glb``/``.vrm`` need
    ``rig``, the head it animates) and ``audio`` beside it (:func:`sound_path`). Returns both paths."""
    target = Path(path)
    wav = sound_path(target)
    name = format_for(target, "write", format)
    write = format_module(name).write
    if name in HEAD_FORMATS:
        if rig is None:
            raise InvalidValueError("rig", None, f"the head a {target.suffix} file carries (mien.heads.load_head)")
        write(clip, target, rig=rig)
    else:
        write(clip, target)
    audio.write_wav(wav)
    return target, wav
