"""The clip file a command is given (``render``, ``export``, ``import``): read in any format mien reads, with
warnings kept for the command to print, a face track captured into a face clip (:mod:`mien.capture`), and
channels no output understands refused with what to do."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from mien.errors import InvalidValueError, MienError

if TYPE_CHECKING:
    from mien.facs.clip import Clip
    from mien.tracking.track import Track

__all__ = ["clip_vocabulary", "read_input_clip", "refuse_foreign_channels"]


def read_input_clip(path: Path, input_format: str | None, verb: str) -> tuple[Clip, list[str]]:
    """``(clip, warning messages)`` of the clip file ``path``; ``verb`` (``"render"``) words the refusals.

    A file with no frames is refused. A face track (``mien track``'s ``.npz`` / ``.json``) is captured as
    ``mien capture`` does with its defaults (:func:`mien.capture.capture_track`: the AU route, neutral from
    the first face seconds, jitter filtered, faceless frames held then eased), and a message says so; a
    captured clip's ``face_found`` mask channel is dropped (a message counts its faceless frames).
    """
    from mien.capture import capture_track, strip_face_mask
    from mien.exchange import reader_for

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            clip = reader_for(path, input_format)(path)
        except InvalidValueError:
            track = _track(path) if input_format is None else None
            if track is None:
                raise
            capture = capture_track(track)
            if not capture.face_found.any():
                raise InvalidValueError(
                    str(path), "a face track without a face", "a track of a video that shows a face"
                ) from None
            clip = capture.clip("au")
            warnings.warn(
                f"{path.name} is a face track: captured as `mien capture` does with its defaults ({capture.report()})",
                stacklevel=1,
            )
    clip, mask = strip_face_mask(clip)
    messages = [str(w.message) for w in caught]
    if mask is not None and not mask.all():
        messages.append(
            f"{path.name}: {int((~mask).sum())} of {len(mask)} frames had no face in the recording (held, then "
            "eased to neutral)"
        )
    if clip.n_frames == 0:
        raise InvalidValueError(str(path), "no frames", "a clip file with at least one row of values")
    return clip, messages


def _track(path: Path) -> Track | None:
    """The face track in ``path``, or None when it is not one."""
    if path.suffix.lower() not in (".npz", ".json"):
        return None
    from mien.tracking.track import load_track

    try:
        return load_track(path)
    except (MienError, OSError, ValueError, KeyError, TypeError):
        return None


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
