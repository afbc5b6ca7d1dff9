"""A study's stimuli: render them with mien (or take supplied videos), hash them, write ``manifest.json``.

Rendered Broekens stimuli: a :class:`~mien.character.Character` (idle blinks and head motion, seeded) emotes
the expression at the design's intensity with the study envelope (onset 0.4 s, hold 0.3 s, decay 0.3 s),
on the head and identity, in the basis, seen through the ``frontal``/``lateral`` camera preset of
:mod:`mien.render.camera` at the distance. Mascaró stimuli: the character plays the laughter type
(:mod:`mien.laughter`). A design with ``[stimuli] say`` makes every rendered stimulus speak the sentence
while it shows its expression (:mod:`mien.study.spoken`): the MP4 carries the sound and the manifest the text
and its timing source (``speech``). Frames come from mien's renderer (:func:`mien.render.clip_render.iter_frames`) into
H.264 MP4 (:class:`mien.render.video.Mp4Writer`); one renderer serves every stimulus with the same head,
basis and camera.

Each finished video gets a small ``.sNNN.done.json`` record (what was rendered and the file's SHA-256); a
re-run skips stimuli whose record and hash still match, so a late failure keeps the finished videos and the
next run resumes. What was rendered includes the head as resolved here (:func:`rendered_head`: ``default``
is ICT-FaceKit when installed, else the built-in head), its identity and its asset's hash, so installing,
removing or changing a head's asset renders its stimuli again; the manifest records it per stimulus
(``rendered_head``). ``manifest.json`` is written last, atomically, with the design's SHA-256; a manifest
made from another version of the design is refused where it is used (:func:`check_design_sha256`).
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mien.character import Character
from mien.errors import InvalidValueError, MissingAssetError
from mien.extras import require
from mien.fileio.hashing import file_sha256
from mien.fileio.streams import atomic_path, write_text
from mien.heads import load_head
from mien.heads.registry import file_fingerprint
from mien.paths import require_asset
from mien.progress import progress as progress_bar
from mien.render.camera import View
from mien.render.clip_render import iter_frames, make_renderer
from mien.render.video import Mp4Writer
from mien.rig.animate import face_to_rig
from mien.rig.heads import resolve_head_name

if TYPE_CHECKING:
    import numpy as np

    from mien.study.design import Design, StimulusSpec

__all__ = [
    "MANIFEST_NAME",
    "StimuliResult",
    "check_design_sha256",
    "check_video",
    "file_sha256",
    "load_manifest",
    "make_stimuli",
    "rendered_head",
]

MANIFEST_NAME = "manifest.json"
"""File name of the manifest inside the stimuli folder."""


@dataclass(frozen=True)
class StimuliResult:
    """What :func:`make_stimuli` did."""

    manifest_path: Path
    """The written ``manifest.json``."""
    manifest: dict[str, Any]
    """Its content."""
    rendered: int
    """Stimuli rendered or copied in this run."""
    skipped: int
    """Stimuli kept from an earlier run (record and hash matched)."""


def check_video(path: str | os.PathLike[str]) -> tuple[float, float]:
    """``(duration_s, fps)`` of the video at ``path`` after decoding every frame (PyAV).

    Raises :class:`~mien.errors.MissingAssetError` when the file is missing and
    :class:`~mien.errors.InvalidValueError` naming the file when it does not decode.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingAssetError(f"stimulus file {path} not found: fix its path in the design file")
    av = require("av", "track")
    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise InvalidValueError(f"stimulus file {path}", "no video stream", "a video file (MP4, WebM...)")
            stream = container.streams.video[0]
            n_frames = sum(1 for _ in container.decode(stream))
            rate = stream.average_rate or stream.base_rate
            fps = float(rate) if rate else 0.0
    except av.error.FFmpegError as error:
        raise InvalidValueError(
            f"stimulus file {path}", "undecodable", f"a video that decodes (ffmpeg: {error})"
        ) from None
    if n_frames == 0 or fps <= 0:
        raise InvalidValueError(f"stimulus file {path}", f"{n_frames} frames", "a video with frames and a frame rate")
    return n_frames / fps, fps


def rendered_head(head: str, identity: str = "") -> dict[str, str]:
    """What the design's ``head`` / ``identity`` stand for here: ``{"head": the source that renders it
    ("builtin", "ict"), "identity": the preset ("default" / "mean" when none is named), "asset_sha256": the
    hash of the head's asset ('' for the built-in head, which mien's code makes; ICT-FaceKit: the hash of its
    FaceXModel folder's files, :func:`mien.heads.registry.file_fingerprint`)}``.

    Raises :class:`~mien.errors.MissingAssetError` when the head needs an asset that is not installed.
    """
    name = resolve_head_name(head)
    if name == "ict":
        folder = require_asset("ict_facekit") / "FaceXModel"
        if not folder.is_dir():
            raise MissingAssetError(
                f"ICT-FaceKit folder {folder.parent} has no FaceXModel/: point MIEN_ICT_FACEKIT at a full checkout"
            )
        return {"head": name, "identity": identity or "mean", "asset_sha256": file_fingerprint(folder)}
    if name == "file":
        return {"head": name, "identity": identity, "asset_sha256": file_fingerprint(identity)}
    return {"head": name, "identity": identity or "default", "asset_sha256": ""}


def _design_head(design: Design, spec: StimulusSpec) -> tuple[str, str]:
    """(head, identity) the design asks for ``spec`` (Mascaró stimuli: the default head)."""
    if design.protocol == "mascaro":
        return "default", ""
    return str(spec.conditions.get("head", "default")), str(spec.conditions.get("identity", ""))


def _spec_key(design: Design, spec: StimulusSpec, head: dict[str, str] | None = None) -> str:
    """What a finished stimulus must match to be kept (``head``: :func:`rendered_head` of a rendered one)."""
    key: dict[str, Any] = {"expression": spec.expression, "conditions": spec.conditions}
    if spec.file is None:
        key.update(
            duration_s=design.duration_s, onset_s=design.onset_s, fps=design.fps, size=design.size, seed=design.seed
        )
        key["rendered_head"] = head
        if design.say is not None:
            key["say"] = [design.say.text, design.say.language, design.say.rate_wpm]
    else:
        key["source_sha256"] = file_sha256(spec.file)
    return json.dumps(key, sort_keys=True)


def _record_path(out: Path, spec: StimulusSpec) -> Path:
    return out / f".{spec.id}.done.json"


def _finished(out: Path, spec: StimulusSpec, key: str) -> dict[str, Any] | None:
    try:
        record = json.loads(_record_path(out, spec).read_text())
    except (OSError, ValueError):
        return None
    video = out / str(record.get("file", ""))
    if record.get("key") != key or not video.is_file() or file_sha256(video) != record.get("sha256"):
        return None
    return dict(record)


def _speech(design: Design, utterance: Any) -> dict[str, Any]:
    from mien.study.spoken import speech_record

    assert design.say is not None
    return speech_record(design.say, utterance, design.onset_s)


def _write_json_atomic(path: Path, data: Any) -> None:
    write_text(json.dumps(data, indent=2) + "\n", path)


class _Scenes:
    """Rigs, cameras and renderers, reused between stimuli that share them (one open renderer at a time)."""

    def __init__(self, size: int) -> None:
        self.size = (size, size)
        self._rigs: dict[tuple[str, str, str], Any] = {}
        self._key: tuple | None = None
        self._renderer: Any = None

    def rig(self, head: str, identity: str, basis: str) -> Any:

        key = (head, identity, basis)
        if key not in self._rigs:
            self._rigs[key] = load_head(head, identity or None, feature_points=basis == "feature_points")
        return self._rigs[key]

    def renderer(self, rig_key: tuple[str, str, str], view: str, distance_m: float) -> Any:

        key = (*rig_key, view, distance_m)
        if key != self._key:
            self.close()
            camera = View(view, distance_m).camera
            self._renderer = make_renderer(self.rig(*rig_key), camera, self.size, samples=0)
            self._key = key
        return self._renderer

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer, self._key = None, None


def _face_clip(design: Design, spec: StimulusSpec, utterance: Any = None) -> tuple[Any, np.ndarray | None]:
    """(face Clip, feature weights or None) of a rendered stimulus (saying ``utterance`` from the onset)."""

    if design.protocol == "mascaro":
        character = Character(seed=design.seed)
        laugh = character.laugh(spec.expression, start_s=design.onset_s)
        duration = max(design.duration_s, design.onset_s + laugh.duration_s + 0.3)
        return character.run(duration, design.fps), None
    basis = str(spec.conditions["basis"])
    character = Character(seed=design.seed, expression_basis=basis)
    if utterance is not None:
        from mien.study.spoken import clip_duration_s, speaking_envelope

        intensity = float(spec.conditions["intensity"])
        envelope = speaking_envelope(utterance)
        character.emote(spec.expression, intensity, start_s=design.onset_s, envelope=envelope)
        character.say(utterance, start_s=design.onset_s)
        return character.run(clip_duration_s(design, utterance), design.fps), character.last_feature_weights
    character.emote(spec.expression, float(spec.conditions["intensity"]), start_s=design.onset_s)
    clip = character.run(design.duration_s, design.fps)
    return clip, character.last_feature_weights


def _render(
    design: Design, spec: StimulusSpec, scenes: _Scenes, video: Path, head: str = "", utterance: Any = None
) -> tuple[float, float]:
    """Render ``spec`` into ``video``; ``head``: the resolved head (:func:`rendered_head`), default the design's;
    ``utterance``: what it says (the video then carries the sound)."""

    conditions = spec.conditions
    design_head, identity = _design_head(design, spec)
    head = head or design_head  # the source resolved when the key was made, so the record says what was drawn
    basis = str(conditions.get("basis", "facs"))
    view = str(conditions.get("view", "frontal"))
    distance = float(conditions.get("distance_m", 1.0))
    if design.protocol == "mascaro":
        basis, view, distance = "facs", "frontal", 1.0
    rig_key = (head, identity, basis)
    rig = scenes.rig(*rig_key)
    clip, features = _face_clip(design, spec, utterance)
    weights, poses = face_to_rig(rig, clip, features)
    renderer = scenes.renderer(rig_key, view, distance)
    silent = video.with_name(f".{video.stem}.silent.mp4") if utterance is not None else video
    with Mp4Writer(silent, clip.fps) as writer:
        for image in iter_frames(rig, weights, renderer, poses):
            writer.write(image)
    if utterance is not None:
        from mien.speech.audio import mux_audio
        from mien.study.spoken import sound_from_start

        try:
            mux_audio(silent, sound_from_start(utterance, design.onset_s), video)
        finally:
            silent.unlink(missing_ok=True)
    return clip.n_frames / clip.fps, float(clip.fps)


def make_stimuli(
    design: Design,
    out: str | os.PathLike[str] | None = None,
    progress: bool = True,
    on_stimulus: Callable[[str, bool], None] | None = None,
) -> StimuliResult:
    """Render (``source = "render"``) or check and copy (``source = "files"``) every stimulus of ``design``
    into ``out`` (default: ``stimuli/`` next to the design file) and write ``manifest.json`` there.

    Supplied files must exist and decode (else :class:`~mien.errors.MissingAssetError` /
    :class:`~mien.errors.InvalidValueError` naming the file; all are checked before anything is written).
    ``on_stimulus(id, skipped)`` is called after each stimulus.
    """

    folder = Path(out) if out is not None else design.path.parent / "stimuli"
    supplied: dict[str, tuple[float, float]] = {}
    for spec in design.stimuli:
        if spec.file is not None:
            supplied[spec.id] = check_video(spec.file)
    utterance = None
    if design.say is not None and any(spec.file is None for spec in design.stimuli):
        from mien.study.spoken import speak_line

        utterance = speak_line(design.say)  # once, before any video: a voice espeak-ng lacks fails first
    folder.mkdir(parents=True, exist_ok=True)
    scenes = _Scenes(design.size)
    heads: dict[tuple[str, str], dict[str, str]] = {}  # (head, identity) of the design -> rendered_head
    entries, rendered, skipped = [], 0, 0
    try:
        for spec in progress_bar(design.stimuli, total=len(design.stimuli), desc="stimuli", enabled=progress):
            head: dict[str, str] | None = None
            if spec.file is None:
                wanted = _design_head(design, spec)
                if wanted not in heads:
                    heads[wanted] = rendered_head(*wanted)
                head = heads[wanted]
            key = _spec_key(design, spec, head)
            record = _finished(folder, spec, key)
            was_done = record is not None
            if record is None:
                suffix = Path(spec.file).suffix.lower() if spec.file is not None else ".mp4"
                video = folder / f"{spec.id}{suffix}"
                if spec.file is not None:
                    with atomic_path(video) as temporary:
                        shutil.copyfile(spec.file, temporary)
                    duration_s, fps = supplied[spec.id]
                else:
                    assert head is not None
                    duration_s, fps = _render(design, spec, scenes, video, head["head"], utterance)
                record = {
                    "key": key,
                    "file": video.name,
                    "sha256": file_sha256(video),
                    "duration_s": round(duration_s, 6),
                    "fps": fps,
                }
                _write_json_atomic(_record_path(folder, spec), record)
                rendered += 1
            else:
                skipped += 1
            if on_stimulus is not None:
                on_stimulus(spec.id, was_done)
            entries.append(
                {
                    "id": spec.id,
                    "file": record["file"],
                    "sha256": record["sha256"],
                    "expression": spec.expression,
                    "conditions": spec.conditions,
                    "duration_s": record["duration_s"],
                    "fps": record["fps"],
                    **({"rendered_head": head} if head is not None else {}),
                    **({"speech": _speech(design, utterance)} if spec.file is None and utterance is not None else {}),
                }
            )
    finally:
        scenes.close()
    manifest = {
        "study": design.name,
        "protocol": design.protocol,
        "design_sha256": design.sha256,
        "stimuli": entries,
    }
    path = folder / MANIFEST_NAME
    _write_json_atomic(path, manifest)
    return StimuliResult(path, manifest, rendered, skipped)


def check_design_sha256(manifest: dict[str, Any], design: Design, folder: str | os.PathLike[str]) -> None:
    """Refuse (:class:`~mien.errors.InvalidValueError` naming the manifest and the design) a ``manifest`` from
    ``folder`` whose ``design_sha256`` is not the SHA-256 of ``design``'s file: the design changed after its
    stimuli were made, so they may not be the ones it describes."""
    recorded = manifest.get("design_sha256")
    if recorded != design.sha256:
        raise InvalidValueError(
            f"{Path(folder) / MANIFEST_NAME}: design_sha256",
            recorded,
            f"{design.sha256}, the SHA-256 of {design.path}: the design changed after these stimuli were made; "
            f"re-run `mien study stimuli {design.path}` (it makes again only what changed)",
        )


def load_manifest(folder: str | os.PathLike[str], verify: bool = True) -> dict[str, Any]:
    """The manifest in ``folder``; with ``verify`` every stimulus file must exist and match its hash.

    Raises :class:`~mien.errors.MissingAssetError` naming what is missing (run ``mien study stimuli``) and
    :class:`~mien.errors.InvalidValueError` naming a file whose hash changed.
    """
    folder = Path(folder)
    path = folder / MANIFEST_NAME
    try:
        manifest = json.loads(path.read_text())
    except FileNotFoundError:
        raise MissingAssetError(f"{path} not found: run `mien study stimuli DESIGN.toml` first") from None
    except ValueError as error:
        raise InvalidValueError(str(path), "JSON", f"a manifest written by `mien study stimuli` ({error})") from None
    if verify:
        for entry in manifest.get("stimuli", []):
            video = folder / entry["file"]
            if not video.is_file():
                raise MissingAssetError(f"stimulus file {video} not found: re-run `mien study stimuli`")
            if file_sha256(video) != entry["sha256"]:
                raise InvalidValueError(
                    f"stimulus file {video}", "changed", "the file hashed in the manifest (re-run `mien study stimuli`)"
                )
    return dict(manifest)
