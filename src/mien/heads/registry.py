"""Loading any head for any mien job: a named head, or a user's file instrumented on first use.

:func:`load_head` is the one door every job (render, demo, export, serve, validate, study) goes through. A named
head (``builtin``, ``ict``, ``default``, with ``:IDENTITY``) comes from :mod:`mien.rig.heads` as it is. A head
file (``face.glb``, ``file:PATH``, an OBJ folder) is read by :mod:`mien.rig.files`, then instrumented
(:mod:`mien.heads.instrument`: its landmarks found on its own textured render, cached per file hash) and placed
in mien's frame (:func:`mien.heads.placement.place_rig`), so the feature-point rig, the study cameras and the
validation crops work on it like on mien's own heads.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError
from mien.fileio.hashing import file_sha256, key_sha256
from mien.heads.amplitude import calibrate_amplitudes
from mien.heads.instrument import Instrumentation, instrument_cached
from mien.heads.mouth import mouth_regions
from mien.heads.placement import place_rig
from mien.heads.synthesize import synthesize_cached
from mien.render.camera import Camera
from mien.render.clip_render import FrameRenderer, make_renderer
from mien.rig.feature_points import FeaturePointRig
from mien.rig.files.head import FileRig
from mien.rig.fp_correctives import corrective_targets
from mien.rig.heads import open_head
from mien.rig.model import Rig

__all__ = ["file_fingerprint", "instrument_head", "load_head"]


def file_fingerprint(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a head file, or of an OBJ folder's files (names and contents), for the instrumenting cache."""
    source = Path(path)
    if source.is_dir():
        files = sorted(p for p in source.rglob("*") if p.is_file())
        return key_sha256([(str(p.relative_to(source)), file_sha256(p)) for p in files])
    return file_sha256(source)


def instrument_head(
    rig: FileRig, landmarker_model: str | os.PathLike[str] | None = None
) -> tuple[Rig, Instrumentation]:
    """``rig`` (as its file was read) with the landmarks, axes and pivots its instrumenting found, and what it
    found. The landmarks are looked for on the head's own textured render (brows, eyes and lips as drawn); the
    inside of the mouth is then found behind the lips (:func:`mien.heads.mouth.mouth_regions`)."""
    if rig.info is None:
        raise InvalidValueError("head", rig.name, "a head read from a file (mien.rig.files.load_head_file)")

    def draw(camera: Camera, size: int) -> FrameRenderer:
        return make_renderer(rig, camera, (size, size))

    found = instrument_cached(
        rig.neutral, rig.faces, file_fingerprint(rig.info.path), landmarker_model, name=Path(rig.info.path).name,
        renderer=draw, eyes=rig.eye_centers.astype(np.float64),
    )  # fmt: skip
    if found.unit != "m" or found.up != (0.0, 1.0, 0.0) or found.forward != (0.0, 0.0, 1.0):
        # the reader could not tell the file's axes or unit (no eyes it could name): the face itself tells them
        placed = place_rig(rig, found)
    else:
        placed = replace(rig, landmarks=found.ibug68_vertices)
    mouth = mouth_regions(placed.neutral, placed.faces, placed.landmarks, placed.regions)
    return (replace(placed, regions={**placed.regions, **mouth}) if mouth else placed), found


def load_head(
    name: str = "default",
    identity: str | None = None,
    feature_points: bool = False,
    landmarker_model: str | os.PathLike[str] | None = None,
    calibrate: bool = True,
) -> Rig:
    """The head ``name`` (a named head, ``HEAD:IDENTITY``, or a head file's path) ready for every mien job.

    ``identity`` is a preset of a named head (see :func:`mien.rig.heads.open_head`). A head file is
    instrumented on first use (about 5 s; then cached per file hash), which needs MediaPipe
    (``pip install 'mien[track]'``) and its ``face_landmarker.task`` (``landmarker_model`` or the configured
    asset), its timid shapes are driven as far as the reference head's (``calibrate``;
    :mod:`mien.heads.amplitude`), and the ARKit shapes it lacks are made through the feature-point fields
    (:mod:`mien.heads.synthesize`: a Rocketbox head's lip stretcher; about 2 s, then cached). With
    ``feature_points`` the Broekens feature-point rig is compiled onto the head (54 extra targets
    ``fp_<Feature>_<axis>``) with its skin-detail correctives (``fpc_<shape>``, :mod:`mien.rig.fp_correctives`).
    """
    rig = open_head(name, identity)
    if isinstance(rig, FileRig) and rig.info is not None:
        path = rig.info.path
        rig, _ = instrument_head(rig, landmarker_model)
        if calibrate:
            rig, _ = calibrate_amplitudes(rig)
        rig, _ = synthesize_cached(rig, file_fingerprint(path))
    if feature_points:
        fp = FeaturePointRig.build(rig)
        rig = rig.with_targets(fp.compile())
        rig = rig.with_targets(corrective_targets(fp, rig))
    return rig
