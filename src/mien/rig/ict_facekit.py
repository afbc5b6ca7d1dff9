"""Load the ICT-FaceKit realistic head (MIT, USC Institute for Creative Technologies) as a mien :class:`Rig`.

The asset is never bundled: point ``MIEN_ICT_FACEKIT`` (or the config file's ``[assets] ict_facekit``, or the
``path`` argument) at the folder that holds ``FaceXModel/``. That folder must contain:

- ``generic_neutral_mesh.obj``: 26,719 vertices, quads (split into triangles here);
- 53 expression shapes named like ARKit with ``_L``/``_R`` suffixes (``eyeBlink_L.obj``...), plus
  ``cheekRaiser_L/R`` and ``PupilDilate_L/R``: full meshes in the same topology (delta = shape - neutral);
- ``identity000..015.obj``: the first 16 identity components of ICT's morphable model (delta = shape - neutral);
- ``vertex_indices.json``: expression names and the 68 iBUG landmark vertex ids (``idx_to_landmark_verts``).

Facts checked on the mesh (and tested):

- Units are centimetres (eyeball centres 6.4 cm apart, head 25 cm wide): scaled by 0.01 to metres.
- Axes already match the mien frame: +y up, +z out of the face, and the parts ICT calls "left" (eyeball,
  eye socket) sit at +x, which is the character's left. So no axis flip, only a translation that puts the
  origin midway between the eyeball centres (recomputed for each identity).
- ``_L`` shapes move the +x side (``eyeBlink_L`` closes the +x eye): ``_L`` is the character's left, which is
  ARKit's ``Left``. ``eyeBlink_L.obj`` becomes ``eyeBlinkLeft``.
- ARKit's single ``browInnerUp`` and ``cheekPuff`` are the sums of ICT's ``_L`` and ``_R`` shapes; the
  one-sided shapes are kept as extra targets (``browInnerUpLeft``...), as are ``cheekRaiserLeft/Right`` and
  ``pupilDilateLeft/Right``. ICT has no tongue shape: ``tongueOut`` is an empty target (it moves nothing), so
  the rig carries all 52 ARKit names in ARKit order.
- Shapes are stored sparsely, keeping vertices that move more than 0.01 mm (the OBJ files carry about 1e-5 cm
  of rounding noise everywhere).

Vertex ranges of the mesh parts come from the ICT-FaceKit README ("Face Model Topology" and "Eyeball
Details" tables, https://github.com/ICT-VGL/ICT-FaceKit); ``vertex_indices.json`` does not list them.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np

from mien.errors import InvalidValueError, MissingAssetError
from mien.facs.arkit import ARKIT_NAMES
from mien.fileio.container import load_container, save_container
from mien.fileio.hashing import key_sha256
from mien.paths import cache_dir, require_asset
from mien.progress import progress
from mien.rig.model import MorphTarget, Rig
from mien.rig.obj import read_obj, read_obj_vertices
from mien.rig.polygon import lip_vertices

__all__ = [
    "ICT_EXTRA_TARGETS",
    "ICT_N_IDENTITY",
    "ICT_N_VERTICES",
    "ICT_PARTS",
    "ICT_TARGET_GAINS",
    "ict_cache_file",
    "ict_identity_presets",
    "ict_missing_files",
    "load_ict_facekit",
]

ICT_N_VERTICES = 26719
"""Vertices of ICT-FaceKit's generic neutral mesh."""

ICT_N_IDENTITY = 16
"""Identity components shipped as ``identity000..015.obj``."""

CM_TO_M = 0.01
"""ICT-FaceKit is modelled in centimetres."""

SPARSE_TOLERANCE_M = 1e-5
"""Vertices moving less than this (0.01 mm) at weight 1 are dropped from a sparse target."""

_CACHE_VERSION = "ict-1"
_CACHE_FORMAT = "mien-ict-cache"
"""Container kind of the parsed-model cache (:mod:`mien.fileio.container`; written atomically)."""
_CACHE_FORMAT_VERSION = 1

ICT_PARTS: dict[str, tuple[int, int]] = {
    "face": (0, 9408),
    "head_neck": (9409, 11247),
    "mouth_socket": (11248, 13293),
    "eye_socket_L": (13294, 13677),
    "eye_socket_R": (13678, 14061),
    "gums_tongue": (14062, 17038),
    "teeth": (17039, 21450),
    "eye_L": (21451, 23020),
    "eye_R": (23021, 24590),
    "lacrimal_fluid_L": (24591, 24794),
    "lacrimal_fluid_R": (24795, 24998),
    "eye_blend_L": (24999, 25022),
    "eye_blend_R": (25023, 25046),
    "eye_occlusion_L": (25047, 25198),
    "eye_occlusion_R": (25199, 25350),
    "eyelashes_L": (25351, 26034),
    "eyelashes_R": (26035, 26718),
    "sclera_L": (21451, 22220),
    "iris_L": (22221, 23020),
    "sclera_R": (23021, 23790),
    "iris_R": (23791, 24590),
}
"""ICT mesh parts as inclusive vertex-id ranges (ICT-FaceKit README). ``_L`` is the character's left (+x)."""

ICT_EXTRA_TARGETS: tuple[str, ...] = (
    "browInnerUpLeft",
    "browInnerUpRight",
    "cheekPuffLeft",
    "cheekPuffRight",
    "cheekRaiserLeft",
    "cheekRaiserRight",
    "pupilDilateLeft",
    "pupilDilateRight",
)
"""Targets the ICT rig has after the 52 ARKit ones, in this order."""

_EXTRA_SOURCES: dict[str, tuple[str, ...]] = {
    "browInnerUp": ("browInnerUp_L", "browInnerUp_R"),
    "cheekPuff": ("cheekPuff_L", "cheekPuff_R"),
    "tongueOut": (),
    "jawLeft": ("jawLeft",),  # whole-jaw / whole-mouth shifts: "Left" is a direction, not a side
    "jawRight": ("jawRight",),
    "mouthLeft": ("mouthLeft",),
    "mouthRight": ("mouthRight",),
    "browInnerUpLeft": ("browInnerUp_L",),
    "browInnerUpRight": ("browInnerUp_R",),
    "cheekPuffLeft": ("cheekPuff_L",),
    "cheekPuffRight": ("cheekPuff_R",),
    "cheekRaiserLeft": ("cheekRaiser_L",),
    "cheekRaiserRight": ("cheekRaiser_R",),
    "pupilDilateLeft": ("PupilDilate_L",),
    "pupilDilateRight": ("PupilDilate_R",),
}

ICT_TARGET_GAINS: dict[str, float] = {"browDownLeft": 2.0, "browDownRight": 2.0}
"""Factors on ICT's own shapes, applied when a rig is built (the cached arrays keep the shapes as shipped).

``browDown``: ICT's shape lowers the brow 3.4 mm at weight 1 (mean of its 50 most-moved vertices; 6.5 mm at
most, mostly inward and forward), where Broekens et al.'s Table 1 lowers the angry inner brow 12 mm and draws it
13 mm in at intensity 1. MediaPipe reads ICT's browDown at weight 1 as 0.03 (the built-in head's as 0.41), so
AU4 at E hardly showed: in `mien validate rig` its slope was 0.03, and at 45 degrees anger with or without AU4
read the same. At 2.0 the brow comes 6.8 mm down and MediaPipe reads 0.15-0.18 (docs/VALIDATION.md, eighth
pass)."""

# First 16 of the identity coefficients in ICT-FaceKit's sample_identity_coeffs.json (MIT).
_SAMPLE_IDENTITY = (
    -0.9202722907066345, -1.2585458755493164, -0.24934729933738708, -0.9247258901596069,
    -0.8216460943222046, -0.052826594561338425, 0.8031851649284363, -0.2329656183719635,
    -0.32379522919654846, -0.5188148021697998, -0.06267508119344711, -0.685829222202301,
    -0.16170993447303772, -0.08769584447145462, 1.5452380180358887, -0.19848349690437317,
)  # fmt: skip


def _sources(target: str) -> tuple[str, ...]:
    """ICT shape files (without ``.obj``) summed to make ``target``."""
    if target in _EXTRA_SOURCES:
        return _EXTRA_SOURCES[target]
    for suffix, ict in (("Left", "_L"), ("Right", "_R")):
        if target.endswith(suffix):
            return (target[: -len(suffix)] + ict,)
    return (target,)


_TARGET_NAMES: tuple[str, ...] = ARKIT_NAMES + ICT_EXTRA_TARGETS
_SHAPE_FILES: tuple[str, ...] = tuple(sorted({s for name in _TARGET_NAMES for s in _sources(name)}))
_IDENTITY_FILES: tuple[str, ...] = tuple(f"identity{i:03d}" for i in range(ICT_N_IDENTITY))
_REQUIRED_FILES: tuple[str, ...] = (
    "generic_neutral_mesh.obj",
    "vertex_indices.json",
    *(f"{s}.obj" for s in _SHAPE_FILES),
    *(f"{s}.obj" for s in _IDENTITY_FILES),
)


def ict_identity_presets() -> dict[str, np.ndarray]:
    """Named (16,) float64 identity coefficient vectors for :func:`load_ict_facekit`.

    ``"mean"`` is ICT's generic face; ``"a"`` is ICT-FaceKit's ``sample_identity_coeffs.json`` (its first 16
    coefficients); ``"b"`` is its mirror image in identity space (all coefficients negated), a clearly
    different face at the same distance from the mean.
    """
    sample = np.array(_SAMPLE_IDENTITY, dtype=np.float64)
    return {"mean": np.zeros(ICT_N_IDENTITY), "a": sample, "b": -sample}


def ict_missing_files(path: str | os.PathLike[str] | None = None) -> list[str]:
    """Files that a complete ICT-FaceKit folder needs and ``path`` (resolved as in :func:`load_ict_facekit`)
    lacks, as paths relative to it (``FaceXModel/eyeBlink_L.obj``...); empty when complete.

    Raises :class:`MissingAssetError` when the folder itself is not configured or does not exist.
    """
    folder = require_asset("ict_facekit", path)
    model = folder / "FaceXModel"
    if not model.is_dir():
        return ["FaceXModel/"]
    return [f"FaceXModel/{name}" for name in _REQUIRED_FILES if not (model / name).is_file()]


def _check_folder(folder: Path) -> Path:
    missing = ict_missing_files(folder)
    if missing:
        shown = ", ".join(missing)
        raise MissingAssetError(
            f"ICT-FaceKit folder {folder} is incomplete: missing {len(missing)} of {len(_REQUIRED_FILES)} files "
            f"({shown}). Point MIEN_ICT_FACEKIT at a full checkout of https://github.com/ICT-VGL/ICT-FaceKit "
            "(the folder that holds FaceXModel/)."
        )
    return folder / "FaceXModel"


def ict_cache_file(path: str | os.PathLike[str] | None = None) -> Path:
    """Where the parsed form of the ICT folder at ``path`` is (or would be) cached.

    The name hashes the resolved folder path and the size and modification time of every file read, so an
    edited or replaced asset gets a fresh cache. Raises :class:`MissingAssetError` on an incomplete folder.
    """
    model = _check_folder(require_asset("ict_facekit", path))
    parts = [_CACHE_VERSION, str(model.resolve())]
    for name in _REQUIRED_FILES:
        stat = (model / name).stat()
        parts.append(f"{name}:{stat.st_size}:{stat.st_mtime_ns}")
    key = key_sha256(parts, 20)
    return cache_dir("ict-facekit") / f"{key}.npz"


def _parse(model: Path) -> dict[str, np.ndarray]:
    """Parse the OBJ folder into arrays in metres (ICT origin, mien axes): see :func:`_build`."""
    neutral_cm, faces = read_obj(model / "generic_neutral_mesh.obj")
    n = len(neutral_cm)
    if n != ICT_N_VERTICES:
        raise InvalidValueError("generic_neutral_mesh.obj vertex count", n, f"{ICT_N_VERTICES} vertices")
    try:
        with (model / "vertex_indices.json").open(encoding="utf-8") as handle:
            landmarks = np.asarray(json.load(handle)["idx_to_landmark_verts"], dtype=np.int64)
    except (KeyError, TypeError, ValueError) as exc:
        raise InvalidValueError(
            f"{model / 'vertex_indices.json'} idx_to_landmark_verts", repr(exc), "a list of 68 vertex ids"
        ) from None
    if landmarks.shape != (68,) or landmarks.min() < 0 or landmarks.max() >= n:
        raise InvalidValueError(
            f"{model / 'vertex_indices.json'} idx_to_landmark_verts", landmarks.shape, "68 ids of existing vertices"
        )

    def delta_m(stem: str) -> np.ndarray:
        vertices = read_obj_vertices(model / f"{stem}.obj")
        if len(vertices) != n:
            raise InvalidValueError(
                f"{model / (stem + '.obj')} vertex count",
                len(vertices),
                f"{n} vertices, as in generic_neutral_mesh.obj (same topology)",
            )
        return ((vertices - neutral_cm) * CM_TO_M).astype(np.float32)

    stems = _SHAPE_FILES + _IDENTITY_FILES
    shapes = {
        stem: delta_m(stem)
        for stem in progress(stems, total=len(stems), desc="ICT-FaceKit OBJ", enabled=sys.stderr.isatty())
    }
    ids_list, deltas_list, offsets = [], [], [0]
    for name in _TARGET_NAMES:
        dense = np.zeros((n, 3), np.float32)
        for stem in _sources(name):
            dense += shapes[stem]
        target = MorphTarget.from_dense(name, dense, tolerance_m=SPARSE_TOLERANCE_M)
        ids_list.append(target.vertex_ids)
        deltas_list.append(target.deltas)
        offsets.append(offsets[-1] + len(target.vertex_ids))
    return {
        "neutral": (neutral_cm * CM_TO_M).astype(np.float32),
        "faces": faces,
        "landmarks": landmarks.astype(np.int32),
        "target_names": np.array(_TARGET_NAMES),
        "target_offsets": np.array(offsets, dtype=np.int64),
        "target_ids": np.concatenate(ids_list).astype(np.int32),
        "target_deltas": np.concatenate(deltas_list).astype(np.float32),
        "identity_deltas": np.stack([shapes[s] for s in _IDENTITY_FILES]),
    }


def _sphere_center(points: np.ndarray) -> np.ndarray:
    """Least-squares sphere centre of (k, 3) points: |p|^2 = 2 c.p + (r^2 - |c|^2)."""
    p = points.astype(np.float64)
    a = np.column_stack([2.0 * p, np.ones(len(p))])
    solution, *_ = np.linalg.lstsq(a, (p * p).sum(axis=1), rcond=None)
    return np.asarray(solution[:3])


def _regions(neutral: np.ndarray, landmarks: np.ndarray) -> dict[str, np.ndarray]:
    regions = {name: np.arange(lo, hi + 1, dtype=np.int32) for name, (lo, hi) in ICT_PARTS.items()}
    n = len(neutral)
    regions["head"] = np.arange(n, dtype=np.int32)
    regions["skin"] = np.arange(0, ICT_PARTS["head_neck"][1] + 1, dtype=np.int32)
    # Lips: face vertices inside the outer lip contour (iBUG 48..59) seen from the front, on the lips' surface.
    regions["lips"] = lip_vertices(neutral, regions["face"], neutral[landmarks[48:60]]).astype(np.int32)
    return regions


def _build(arrays: dict[str, np.ndarray], identity: np.ndarray | None, name: str) -> Rig:
    neutral = arrays["neutral"].astype(np.float32)
    if identity is not None:
        neutral = neutral + np.tensordot(identity.astype(np.float32), arrays["identity_deltas"], axes=1)
    (l0, l1), (r0, r1) = ICT_PARTS["sclera_L"], ICT_PARTS["sclera_R"]
    eye_centers = np.stack([_sphere_center(neutral[l0 : l1 + 1]), _sphere_center(neutral[r0 : r1 + 1])])
    origin = eye_centers.mean(axis=0)
    neutral = (neutral - origin).astype(np.float32)
    eye_centers = (eye_centers - origin).astype(np.float32)
    landmarks = arrays["landmarks"]
    # Head pivot near the atlanto-occipital joint: midline, about 45% of the way from eye level down to the
    # chin, halfway between the eyes' depth and the back of the skull.
    chin_y = float(neutral[landmarks[8], 1])
    back_z = float(neutral[: ICT_PARTS["head_neck"][1] + 1, 2].min())
    neck_pivot = np.array([0.0, 0.45 * chin_y, 0.5 * back_z], dtype=np.float32)
    offsets = arrays["target_offsets"]
    ids, deltas = arrays["target_ids"], arrays["target_deltas"]
    targets = tuple(
        MorphTarget(
            str(t),
            ids[offsets[i] : offsets[i + 1]],
            deltas[offsets[i] : offsets[i + 1]] * ICT_TARGET_GAINS.get(str(t), 1.0),
        )
        for i, t in enumerate(arrays["target_names"])
    )
    return Rig(
        name=name,
        neutral=neutral,
        faces=arrays["faces"],
        targets=targets,
        landmarks=landmarks,
        regions=_regions(neutral, landmarks),
        eye_centers=eye_centers,
        neck_pivot=neck_pivot,
        shape_gains=dict(ICT_TARGET_GAINS),
    )


def _check_identity(identity: object) -> np.ndarray | None:
    if identity is None:
        return None
    coeffs = np.asarray(identity, dtype=np.float64)
    if coeffs.shape != (ICT_N_IDENTITY,) or not np.all(np.isfinite(coeffs)):
        raise InvalidValueError(
            "identity", identity, f"({ICT_N_IDENTITY},) finite coefficients (see ict_identity_presets())"
        )
    return coeffs


def load_ict_facekit(
    path: str | os.PathLike[str] | None = None,
    identity: np.ndarray | None = None,
    cache: bool = True,
) -> Rig:
    """Load ICT-FaceKit as a :class:`Rig` in the mien frame (metres, +x character's left, origin between eyes).

    ``path``: the folder holding ``FaceXModel/`` (default: ``MIEN_ICT_FACEKIT`` or the config file).
    ``identity``: (16,) identity coefficients (``None`` = ICT's mean face; see :func:`ict_identity_presets`).
    ``cache``: reuse / write a parsed ``.npz`` under ``mien.paths.cache_dir("ict-facekit")`` (first load parses
    76 OBJ files, a few seconds; a cached load takes well under a second).

    The rig has 26,719 vertices, the 52 ARKit targets in ARKit order then :data:`ICT_EXTRA_TARGETS`, the 68
    iBUG landmarks, regions :data:`ICT_PARTS` plus ``head`` (all), ``skin`` (face, head and neck) and ``lips``.
    Raises :class:`MissingAssetError` (missing or incomplete folder, naming the missing files) or
    :class:`InvalidValueError` (a shape with another vertex count, bad ``identity``).
    """
    coeffs = _check_identity(identity)
    folder = require_asset("ict_facekit", path)
    model = _check_folder(folder)
    arrays: dict[str, np.ndarray] | None = None
    cache_file = ict_cache_file(folder) if cache else None
    if cache_file is not None and cache_file.is_file():
        try:
            arrays = load_container(cache_file, _CACHE_FORMAT, _CACHE_FORMAT_VERSION).arrays
        except InvalidValueError:
            arrays = None  # a damaged cache is rebuilt
    if arrays is None:
        arrays = _parse(model)
        if cache_file is not None:
            save_container(cache_file, _CACHE_FORMAT, _CACHE_FORMAT_VERSION, {"model": str(model)}, arrays, False)
    return _build(arrays, coeffs, "ict-facekit")
