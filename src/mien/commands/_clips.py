"""The clip file a command is given (``render``, ``export``, ``import``): read in any format mien reads, with
warnings kept for the command to print, a face track named for what it is, and channels no output understands
refused with what to do."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from mien.errors import InvalidValueError, MienError

if TYPE_CHECKING:
    from mien.facs.clip import Clip

__all__ = ["clip_vocabulary", "read_input_clip", "refuse_foreign_channels"]


def read_input_clip(path: Path, input_format: str | None, verb: str) -> tuple[Clip, list[str]]:
    """``(clip, warning messages)`` of the clip file ``path``; ``verb`` (``"render"``) words the refusals.

    A file with no frames is refused; a face track (``mien track``'s ``.npz`` / ``.json``) is refused naming what
    to do with it instead of the clip reader's complaint.
    """
    from mien.exchange import reader_for

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            clip = reader_for(path, input_format)(path)
        except InvalidValueError:
            if _is_track(path):
                raise MienError(
                    f"{path} is a face track (`mien track` output: landmarks and ARKit blendshape scores of a "
                    f"video), not a clip: mien does not {verb} tracks; to see the video's performance on a head "
                    "run `mien validate compare VIDEO`, or read the track in Python with mien.tracking.load_track"
                ) from None
            raise
    if clip.n_frames == 0:
        raise InvalidValueError(str(path), "no frames", "a clip file with at least one row of values")
    return clip, [str(w.message) for w in caught]


def _is_track(path: Path) -> bool:
    if path.suffix.lower() not in (".npz", ".json"):
        return False
    from mien.tracking.track import load_track

    try:
        load_track(path)
    except (MienError, OSError, ValueError, KeyError, TypeError):
        return False
    return True


def clip_vocabulary(clip: Clip) -> str:
    """What ``clip``'s channels are: ``"face"`` (AU intensities), ``"arkit"`` (ARKit weights, perhaps with a
    head's extra targets), ``"controllers"`` (laughter-controller curves) or ``"other"`` (none of these, such as
    a character file's own shape names); pose channels go with any."""
    from mien.facs.arkit import ARKIT_NAMES
    from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
    from mien.rig.face_weights import is_controller_clip

    channels = [c for c in clip.channels if c not in POSE_CHANNELS]
    if channels and all(c in FACE_CHANNELS for c in channels):
        return "face"
    if is_controller_clip(clip):
        return "controllers"
    if any(c in ARKIT_NAMES for c in channels):
        return "arkit"
    return "other"


def refuse_foreign_channels(clip: Clip, path: Path, target_names: tuple[str, ...] = ()) -> None:
    """Refuse a clip whose channels are neither AUs, ARKit weights, laughter controllers nor ``target_names``
    (the head's own targets), naming the channels and what to do."""
    if clip_vocabulary(clip) != "other" or any(c in target_names for c in clip.channels):
        return
    shown = ", ".join(clip.channels[:3]) + (", ..." if len(clip.channels) > 3 else "")
    raise InvalidValueError(
        f"{path.name} channels",
        shown,
        "AU channels, ARKit weights or laughter controllers: these look like a character file's own shape names, "
        "which mien cannot turn back into ARKit weights or AUs; convert the clip that animated that file instead, "
        "or write .csv, .json or .npz, which carry any channel",
    )
