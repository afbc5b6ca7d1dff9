"""What a viewer loads for a character's head, and the morph weights its frames carry.

A head mien builds (built-in, ICT-FaceKit, an OBJ folder) is shown as mien's own glTF of the rig
(:func:`mien.exchange.glb.head_glb_bytes`); its frames carry the rig's weights in the rig's target order.

A head read from a user's glTF file (``.glb``, ``.gltf``, ``.vrm``; a :class:`mien.rig.files.head.FileRig`) is
shown as the file itself, with its textures, hair, skin and skeleton. Its frames carry the weights of the FILE's
own morph targets, named by :attr:`HeadView.frame_names` (the viewer sets every morph mesh's target of that name,
so a shape on the head and the teeth moves both). The rig's weights (mien's ARKit names) become the file's by one
matrix built once from the rows each rig target was made of (``info.source_names``: file shape, weight, side)::

    file weight = clip(sum over rows of rig weight * row weight * (1/2 for a one-side row), 0, MAX_GAIN)

The rows carry the gains :mod:`mien.heads.amplitude` put on a timid shape, so a file weight may pass 1 (up to
:data:`~mien.heads.amplitude.MAX_GAIN`): three.js extrapolates a morph target past 1 as mien's renderer does.

A row with a side is one half of a both-sided file shape split at the midline; half of each side's weight is the
least-squares single weight of the whole shape (both sides at 1 give 1). A VRM expression (``happy``, ``aa``) the
rig was built from is expanded into the morph targets it binds. :attr:`HeadView.file_to_rig` maps the file's world
coordinates onto mien's frame (metres, origin between the eyes, +z forward), fitted to the rig's vertices, so the
viewer's camera presets frame any head. A file head that has targets the file cannot show (the feature-point
basis adds 54) is shown as mien's glTF of the rig instead, and :attr:`HeadView.note` says why.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from mien.heads.amplitude import MAX_GAIN, reference_moves
from mien.rig.files.gltf import read_gltf
from mien.rig.files.head import _vrm_expressions
from mien.rig.model import Rig

__all__ = ["HeadView", "frame_weights", "head_view", "referenced_files"]

log = logging.getLogger("mien.server")

FIT_POINTS_PER_PRIMITIVE = 2000
"""Vertices per drawn primitive used to fit :attr:`HeadView.file_to_rig` (a stride through the primitive)."""

FIT_WARN_M = 0.001
"""A fit whose RMS residual exceeds this (metres) is logged: the viewer may place the file head off-centre."""

MEDIA_TYPES: dict[str, str] = {
    ".glb": "model/gltf-binary",
    ".vrm": "model/gltf-binary",
    ".gltf": "model/gltf+json",
    ".bin": "application/octet-stream",
    ".png": "image/png",
    ".jpg": "image/jpeg",
    ".jpeg": "image/jpeg",
    ".webp": "image/webp",
    ".ktx2": "image/ktx2",
}
"""Media type of a head file, and of the files a ``.gltf`` points at, by suffix."""


@dataclass(frozen=True, eq=False)
class HeadView:
    """How a viewer shows one head."""

    frame_names: tuple[str, ...]
    """Names of the frame's weights, in order: the rig's targets, or the file's own morph-target names."""
    matrix: np.ndarray | None
    """(n_frame_names, n_rig_targets) float32: rig weights -> frame weights (clipped 0..MAX_GAIN); None: the rig's."""
    source: Path | None
    """The user's file served as is, or None (mien's glTF of the rig is served)."""
    file_to_rig: np.ndarray | None
    """(4, 4) float64 similarity (column vectors): the file's world coordinates -> mien's frame, metres."""
    fit_rms_m: float = 0.0
    """RMS distance of the fitted file vertices from the rig's, metres."""
    note: str = ""
    """Why a file head is shown as mien's glTF, or which synthesized shapes its file view leaves out (empty when
    neither, or for no file head)."""

    @property
    def media_type(self) -> str:
        """The served head's media type (``model/gltf-binary`` or ``model/gltf+json``)."""
        return MEDIA_TYPES[self.source.suffix.lower()] if self.source is not None else "model/gltf-binary"


def frame_weights(view: HeadView, weights: np.ndarray) -> np.ndarray:
    """(n_frame_names,) float32 frame weights of the rig's (n_targets,) weights 0..1."""
    if view.matrix is None:
        return weights
    out = view.matrix @ weights
    np.clip(out, 0.0, MAX_GAIN, out=out)
    return out


def head_view(rig: Rig) -> HeadView:
    """How a viewer shows ``rig`` (reads a file head's glTF once more, about 0.2 s, to fit its placement)."""
    info = getattr(rig, "info", None)
    names = tuple(rig.target_names)
    if info is None:
        return HeadView(names, None, None, None)
    source = Path(info.path)
    if info.format == "obj-folder" or source.suffix.lower() not in (".glb", ".gltf", ".vrm"):
        return HeadView(names, None, None, None, note=f"{source.name}: an OBJ folder is shown as mien's glTF")
    unsourced = [name for name in names if not info.source_names.get(name)]
    made = set(reference_moves())  # shapes mien synthesized for what the file lacks (mien.heads.synthesize)
    lacking = [name for name in unsourced if name not in made]
    if lacking:
        note = (f"{source.name}: shown as mien's glTF of the rig: the file has no shapes for {len(lacking)} "
                f"of its targets ({', '.join(lacking[:3])}...)")  # fmt: skip
        return HeadView(names, None, None, None, note=note)

    scene = read_gltf(source)
    expansions = _vrm_binds(scene.gltf) if info.format in ("vrm0", "vrm1") else {}
    frame_names, matrix = _weight_matrix(names, info.source_names, expansions)
    file_to_rig, rms = _fit(scene.primitives, info.materials, rig.neutral)
    if rms > FIT_WARN_M:
        log.warning("%s: the file's vertices lie %.1f mm (RMS) from the rig's after placing", source.name, rms * 1e3)
    note = ""
    if unsourced:
        note = (f"{source.name}: shown as its file, without the {len(unsourced)} shapes mien synthesized for it "
                f"({', '.join(unsourced[:3])}...: they show in mien's renders)")  # fmt: skip
    return HeadView(frame_names, matrix, source, file_to_rig, rms, note=note)


def _weight_matrix(
    names: tuple[str, ...],
    source_names: dict[str, tuple[tuple[str, float, str], ...]],
    expansions: dict[str, list[tuple[str, float]]],
) -> tuple[tuple[str, ...], np.ndarray]:
    """Frame names (file shapes in order of first use) and the (n_shapes, n_targets) matrix of the rows."""
    entries: dict[tuple[str, int], float] = {}
    for column, target in enumerate(names):
        for shape, weight, side in source_names.get(target, ()):  # a synthesized target: a zero column
            factor = weight * (0.5 if side else 1.0)
            for file_shape, bind in expansions.get(shape, [(shape, 1.0)]):
                key = (file_shape, column)
                entries[key] = entries.get(key, 0.0) + factor * bind
    frame_names = tuple(dict.fromkeys(shape for shape, _ in entries))
    row_of = {shape: i for i, shape in enumerate(frame_names)}
    matrix = np.zeros((len(frame_names), len(names)), np.float32)
    for (shape, column), value in entries.items():
        matrix[row_of[shape], column] += value
    return frame_names, matrix


def _vrm_binds(gltf: Any) -> dict[str, list[tuple[str, float]]]:
    """VRM expression name -> [(morph-target name, weight 0..1)], the names three.js gives them (the mesh's
    ``extras.targetNames``, else the index)."""

    _, expressions = _vrm_expressions(gltf, [])
    out: dict[str, list[tuple[str, float]]] = {}
    for expression, binds in expressions.items():
        rows = []
        for mesh_id, morph, weight in binds:
            extras = gltf.meshes[mesh_id].extras
            target_names = list(extras.get("targetNames") or []) if isinstance(extras, dict) else []
            rows.append((target_names[morph] if morph < len(target_names) else str(morph), weight))
        out[expression] = rows
    return out


def _fit(primitives: Any, materials: Any, neutral: np.ndarray) -> tuple[np.ndarray | None, float]:
    """The similarity (Umeyama 1991) taking the primitives' file positions onto their rig vertices, and its RMS
    residual in metres; (None, inf) when the file and the rig do not line up primitive by primitive."""
    sources, targets = [], []
    for primitive, material in zip(primitives, materials, strict=False):
        if len(primitive.positions) != len(material.vertex_ids):
            return None, float("inf")
        step = max(1, len(primitive.positions) // FIT_POINTS_PER_PRIMITIVE)
        sources.append(np.asarray(primitive.positions[::step], np.float64))
        targets.append(np.asarray(neutral[material.vertex_ids[::step]], np.float64))
    if len(primitives) != len(materials) or not sources:
        return None, float("inf")
    source, target = np.concatenate(sources), np.concatenate(targets)
    mean_s, mean_t = source.mean(axis=0), target.mean(axis=0)
    xs, xt = source - mean_s, target - mean_t
    u, s, vt = np.linalg.svd(xt.T @ xs / len(source))
    d = np.diag([1.0, 1.0, float(np.sign(np.linalg.det(u) * np.linalg.det(vt)) or 1.0)])
    rotation = u @ d @ vt
    variance = float((xs**2).sum() / len(source))
    scale = float(np.trace(np.diag(s) @ d)) / variance if variance > 0 else 1.0
    matrix = np.eye(4)
    matrix[:3, :3] = scale * rotation
    matrix[:3, 3] = mean_t - scale * rotation @ mean_s
    residual = source @ matrix[:3, :3].T + matrix[:3, 3] - target
    return matrix, float(np.sqrt((residual**2).sum(axis=1).mean()))


def referenced_files(path: Path) -> dict[str, Path]:
    """The files a ``.gltf`` points at (buffers and images by relative URI) that exist inside its folder:
    URI (percent-decoded, as a request path arrives) -> path. Data URIs and anything outside the folder are left
    out."""
    import json

    folder = path.parent.resolve()
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    out: dict[str, Path] = {}
    for item in [*(document.get("buffers") or []), *(document.get("images") or [])]:
        uri = item.get("uri") if isinstance(item, dict) else None
        if not isinstance(uri, str) or uri.startswith("data:") or ":" in uri.split("/", 1)[0]:
            continue
        file = (folder / unquote(uri)).resolve()
        if file.is_file() and file.is_relative_to(folder):
            out[unquote(uri)] = file
    return out
