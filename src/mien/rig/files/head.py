"""A head from a user's file: glTF / GLB / VRM or an OBJ folder -> a :class:`FileRig` in mien's frame.

Steps, each reported in :class:`HeadFileInfo`:

1. Read the meshes (:mod:`mien.rig.files.gltf`, or an OBJ folder: a neutral ``.obj`` plus one ``.obj`` per shape
   in the same topology). VRM expressions (1.0 ``VRMC_vrm.expressions``, 0.x ``blendShapeMaster`` groups) become
   targets named by their preset, built from their morph-target binds.
2. Weld each mesh's vertices that sit at the same place and move alike (glTF splits vertices at UV seams).
3. Find the eyes: meshes named like eyes (sphere centre of their vertices), else eye joints / nodes, else two
   eyeball-like closed parts of the mesh (sphere fits), else an estimate from the region the shapes move.
4. Units: the power of ten (or inch) that puts the eyeball centres 63 mm apart (glTF says metres, but a
   centimetre head exported as is, like ICT-FaceKit through Blender, keeps its numbers). Axes: glTF's (+y up, +z
   out of the face, +x the character's left) unless the eye named left sits at -x (a model facing -z, as VRM 0.x
   does), which is turned 180 degrees about +y.
5. Names: :func:`mien.rig.conventions.match_names`: the rig's targets get mien's ARKit names (several shapes on
   several meshes combined into one target), unmatched shapes keep their own names.
"""

from __future__ import annotations

import io
import math
import os
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import available
from mien.rig.conventions import NameMatch, Overrides, match_names, read_overrides
from mien.rig.files.errors import HeadFileError, HeadFileWarning, NoMorphTargetsError
from mien.rig.model import MorphTarget, Rig
from mien.rig.obj import read_obj, read_obj_vertices
from mien.rig.topology import vertex_components

__all__ = ["FILE_SUFFIXES", "FileRig", "HeadFileInfo", "PrimitiveMaterial", "is_head_file", "load_head_file"]

FILE_SUFFIXES: tuple[str, ...] = (".glb", ".gltf", ".vrm")
"""File suffixes read as glTF; a folder is read as an OBJ folder."""

EYE_DISTANCE_M = 0.063
"""Typical adult distance between the eyeball centres (about the interpupillary distance), metres."""

SPARSE_TOLERANCE_M = 1e-6
"""Vertices moving less than this at weight 1 are dropped from a target (0.001 mm)."""


@dataclass(frozen=True, eq=False)
class PrimitiveMaterial:
    """What a later textured renderer needs of one drawn part: its vertices, UVs and base colour."""

    mesh_name: str
    """The file's mesh name."""
    vertex_ids: np.ndarray
    """(n,) int32 rig vertex of each of the part's own (unwelded) vertices, in the file's order."""
    triangles: np.ndarray
    """(m, 3) int32 triangles over the part's own vertices (index :attr:`vertex_ids` for rig vertices)."""
    uvs: np.ndarray | None
    """(n, 2) float32 ``TEXCOORD_0`` of the part's own vertices (glTF: origin top-left), or None."""
    base_color_factor: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    """Linear RGBA factor on the base colour."""
    base_color_image: bytes | None = None
    """Encoded image (PNG, JPEG, WebP) of the base-colour texture, or None."""
    base_color_mime: str = ""
    """Its MIME type (``image/webp``...)."""
    alpha_mode: str = "OPAQUE"
    """``OPAQUE``, ``MASK`` (alpha-tested at :attr:`alpha_cutoff`) or ``BLEND``."""
    alpha_cutoff: float = 0.5
    """Alpha threshold of ``MASK``."""
    double_sided: bool = False
    """Whether back faces are drawn."""


@dataclass(frozen=True, eq=False)
class HeadFileInfo:
    """Where a file head came from and what mien decided while loading it."""

    path: str
    """The file or folder read."""
    format: str
    """``"gltf"``, ``"vrm0"``, ``"vrm1"`` or ``"obj-folder"``."""
    eyes: str
    """How the eye centres were found (``"eye meshes h_L_eye, h_R_eye"``, ``"eye joints ..."``, ``"eyeball-like
    parts"``, ``"estimated ..."``)."""
    unit_m: float
    """Metres per file unit applied (1.0, 0.01...)."""
    unit_reason: str
    """Why that unit (the eye distance it gives)."""
    axes: str
    """How the file's axes were turned into mien's."""
    names: NameMatch
    """The naming convention and what the rig cannot show."""
    source_names: dict[str, tuple[tuple[str, float, str], ...]]
    """Rig target -> ``(file shape, weight, side)`` rows it was built from (to write the file's names back)."""
    meshes: dict[str, tuple[int, int]]
    """File mesh name -> rig vertex range ``[start, stop)``."""
    materials: tuple[PrimitiveMaterial, ...]
    """One entry per drawn part."""
    skin: str = ""
    """Skinned meshes: whether the file's joint pose is its bind pose."""
    notes: tuple[str, ...] = ()
    """Warnings raised while loading (undecodable textures...)."""

    def report(self) -> str:
        """Lines for people: file, eyes, unit, axes, then the naming report."""
        lines = [f"head file: {self.path} ({self.format})", f"eyes: {self.eyes}", f"unit: {self.unit_reason}",
                 f"axes: {self.axes}"]  # fmt: skip
        if self.skin:
            lines.append(f"skin: {self.skin}")
        lines.append("landmarks: none yet (found by instrumenting the head)")
        return "\n".join([*lines, self.names.report(), *self.notes])


@dataclass(frozen=True, eq=False)
class FileRig(Rig):
    """A :class:`Rig` loaded from a user's file, with :class:`HeadFileInfo` beside it."""

    info: HeadFileInfo | None = None
    """How the file was read (None only on a rig built by hand)."""

    def with_targets(self, extra: tuple[MorphTarget, ...]) -> FileRig:
        rig = super().with_targets(extra)
        return FileRig(**{name: getattr(rig, name) for name in Rig.__dataclass_fields__}, info=self.info)


@dataclass(eq=False)
class _Part:
    """One mesh part in file units while the head is being built."""

    name: str
    positions: np.ndarray
    triangles: np.ndarray
    targets: dict[str, np.ndarray]
    uvs: np.ndarray | None = None
    material: int | None = None
    head_weight: np.ndarray | None = None
    eye_joint_weight: dict[str, np.ndarray] = field(default_factory=dict)


def is_head_file(spec: str | os.PathLike[str]) -> bool:
    """True when ``spec`` is an existing ``.glb``/``.gltf``/``.vrm`` file or a folder of ``.obj`` files."""
    path = Path(spec)
    try:
        if path.is_file():
            return path.suffix.lower() in FILE_SUFFIXES
        return path.is_dir() and any(path.glob("*.obj"))
    except OSError:
        return False


_TOKEN = re.compile(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])|\d+")


def _tokens(name: str) -> list[str]:
    return [token.lower() for token in _TOKEN.findall(name)]


def _side(name: str) -> str:
    tokens = _tokens(name)
    if "l" in tokens or "left" in tokens:
        return "L"
    if "r" in tokens or "right" in tokens:
        return "R"
    return ""


def _is_eye(name: str) -> bool:
    tokens = _tokens(name)
    skip = {"lash", "lashes", "brow", "brows", "lid", "lids", "occlusion", "shadow", "gland", "end", "white", "blend",
            "socket", "tear", "wet", "highlight", "line", "lacrimal"}  # fmt: skip
    return any(t in ("eye", "eyeball", "eyes") for t in tokens) and not skip & set(tokens)


def _sphere(points: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Least-squares sphere of (k, 3) points: centre, radius, rms residual."""
    p = points.astype(np.float64)
    a = np.column_stack([2.0 * p, np.ones(len(p))])
    solution, *_ = np.linalg.lstsq(a, (p * p).sum(axis=1), rcond=None)
    centre = solution[:3]
    radius = math.sqrt(max(float(solution[3] + centre @ centre), 0.0))
    residual = float(np.sqrt(np.mean((np.linalg.norm(p - centre, axis=1) - radius) ** 2)))
    return centre, radius, residual


def _eyeball_parts(positions: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """Two mirror-image eyeballs among the closed parts of one mesh: (2, 3) centres (+x first) and their vertex ids.

    A part is eyeball-like when a sphere fits it (rms residual under 6% of the radius: a cornea bulges) and it
    spans about a diameter along every axis; concentric parts (sclera and iris shells) join one eye.
    """
    labels = vertex_components(len(positions), triangles)
    spheres: list[tuple[np.ndarray, float, np.ndarray]] = []
    for label in np.unique(labels):
        ids = np.flatnonzero(labels == label)
        if len(ids) < 40:
            continue
        centre, radius, residual = _sphere(positions[ids])
        extent = np.ptp(positions[ids], axis=0)
        if radius > 0 and residual < 0.06 * radius and np.all(extent > 1.5 * radius):
            spheres.append((centre, radius, ids))
    eyes: list[tuple[np.ndarray, float, np.ndarray]] = []
    for centre, radius, ids in sorted(spheres, key=lambda s: -len(s[2])):
        for k, (c, r, group) in enumerate(eyes):
            if np.linalg.norm(centre - c) < 0.3 * r and abs(radius - r) < 0.3 * r:
                eyes[k] = (c, r, np.concatenate([group, ids]))
                break
        else:
            eyes.append((centre, radius, ids))
    best = None
    for i, (c_a, r_a, ids_a) in enumerate(eyes):
        for c_b, r_b, ids_b in eyes[i + 1 :]:
            d = float(np.linalg.norm(c_a - c_b))
            mirrored = abs(c_a[1] - c_b[1]) < 0.2 * r_a and abs(c_a[2] - c_b[2]) < 0.2 * r_a
            if abs(r_a - r_b) < 0.15 * r_a and mirrored and 3.0 < d / r_a < 7.0:
                score = len(ids_a) + len(ids_b)
                if best is None or score > best[0]:
                    best = (score, ids_a, ids_b)
    if best is None:
        return None
    _, ids_a, ids_b = best
    centres = [_sphere(positions[ids])[0] for ids in (ids_a, ids_b)]
    if centres[0][0] < centres[1][0]:
        centres, ids_a, ids_b = centres[::-1], ids_b, ids_a
    return np.stack(centres), [np.sort(ids_a), np.sort(ids_b)]


EYE_SHELL_REACH = 2.2
"""A part is an eye shell when every vertex lies within this many eyeball radii of one eye centre."""


def _eye_shells(
    positions: np.ndarray, faces: np.ndarray, centres: np.ndarray, eye_ids: Sequence[np.ndarray]
) -> dict[str, np.ndarray]:
    """``{"eye_shell_L": ids, "eye_shell_R": ids}``: small parts hugging an eyeball that are not the eyeball.

    Heads sculpted for real-time engines wrap each eye in see-through geometry (ICT's and Character Creator's
    eye occlusion and tear line, MetaHuman's eye shell) that their engine draws transparent or as a shadow. In
    a file exported without those materials they are opaque skin-coloured shells over the eyes; these regions
    let the untextured renderer leave them out (:data:`mien.render.appearance.HIDDEN_REGIONS`). Empty without
    eyeball vertices.
    """
    if any(len(ids) == 0 for ids in eye_ids):
        return {}
    n = len(positions)
    near = np.zeros((2, n), bool)
    for k, ids in enumerate(eye_ids):
        distance = np.linalg.norm(positions - centres[k], axis=1)
        near[k] = distance <= EYE_SHELL_REACH * float(np.median(distance[ids]))
    close = near[0] | near[1]
    inside = close[faces].all(axis=1)
    spoiled = np.zeros(n, bool)  # in the eyeballs, or joined by a face to a vertex beyond reach
    spoiled[faces[~inside].ravel()] = True
    for ids in eye_ids:
        spoiled[ids] = True
    candidates = np.flatnonzero(close)
    index = np.full(n, -1, np.int64)
    index[candidates] = np.arange(len(candidates))
    labels = vertex_components(len(candidates), index[faces[inside]])  # only the parts round the eyes
    _, part = np.unique(labels, return_inverse=True)
    part = part.ravel()
    bad = np.bincount(part, weights=spoiled[candidates]) > 0
    out = {}
    for k, side in enumerate(("L", "R")):
        whole = np.bincount(part, weights=near[k][candidates]) == np.bincount(part)
        keep = whole[part] & ~bad[part]
        if keep.any():
            out[f"eye_shell_{side}"] = candidates[keep].astype(np.int32)
    return out


def _weld(part: _Part) -> tuple[_Part, np.ndarray]:
    """Merge vertices with equal position and equal deltas; returns the welded part and old -> new ids.

    Deltas are compared through four fixed random projections of all of them (cheap; two vertices that move
    differently agree on all four only by accident).
    """
    projection = np.zeros((len(part.positions), 4), np.float64)
    rng = np.random.default_rng(0)
    for delta in part.targets.values():
        projection += delta.astype(np.float64) @ rng.standard_normal((3, 4))
    key = np.ascontiguousarray(np.concatenate([part.positions.astype(np.float32), projection.astype(np.float32)], 1))
    row = key.view(np.dtype((np.void, key.dtype.itemsize * key.shape[1]))).ravel()
    _, first, inverse = np.unique(row, return_index=True, return_inverse=True)
    order = np.argsort(first)  # keep the file's vertex order
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    keep, remap = first[order], rank[inverse.ravel()]
    if len(keep) == len(part.positions):
        return part, np.arange(len(keep))
    welded = _Part(
        name=part.name,
        positions=part.positions[keep],
        triangles=remap[part.triangles],
        targets={name: np.take(d, keep, axis=0) for name, d in part.targets.items()},  # 4x faster than d[keep]
        material=part.material,
        head_weight=None if part.head_weight is None else part.head_weight[keep],
        eye_joint_weight={k: v[keep] for k, v in part.eye_joint_weight.items()},
    )
    return welded, remap


def _moved(delta: np.ndarray, tolerance: float) -> np.ndarray:
    """Ascending ids of the rows of (n, 3) ``delta`` with a component above ``tolerance`` (1-D scan: fast)."""
    flat = np.flatnonzero(np.abs(delta.reshape(-1)) > tolerance) // 3
    return flat[np.r_[True, flat[1:] != flat[:-1]]] if flat.size else flat


def _vrm_expressions(
    gltf: Any, scene_parts: list[tuple[Any, _Part]]
) -> tuple[str, dict[str, list[tuple[int, int, float]]]]:
    """VRM version and preset/custom expression name -> [(mesh index, morph index, weight 0..1)]."""
    extensions = gltf.extensions or {}
    out: dict[str, list[tuple[int, int, float]]] = {}
    if "VRMC_vrm" in extensions:
        expressions = extensions["VRMC_vrm"].get("expressions", {})
        for group in ("preset", "custom"):
            for name, expression in (expressions.get(group) or {}).items():
                binds = []
                for bind in expression.get("morphTargetBinds") or []:
                    node = gltf.nodes[int(bind["node"])]
                    if node.mesh is not None:
                        binds.append((int(node.mesh), int(bind["index"]), float(bind.get("weight", 1.0))))
                out[name] = binds
        return "vrm1", out
    if "VRM" in extensions:
        groups = (extensions["VRM"].get("blendShapeMaster") or {}).get("blendShapeGroups") or []
        for group in groups:
            preset = group.get("presetName") or "unknown"
            name = group.get("name", "") if preset == "unknown" else preset
            out[name] = [(int(b["mesh"]), int(b["index"]), float(b.get("weight", 100.0)) / 100.0)
                         for b in group.get("binds") or []]  # fmt: skip
        return "vrm0", out
    return "gltf", out


def _texture_of(gltf: Any, texture: int | None) -> int | None:
    if texture is None or texture >= len(gltf.textures or []):
        return None
    tex = gltf.textures[texture]
    for name in ("EXT_texture_webp", "KHR_texture_basisu"):
        ext = (tex.extensions or {}).get(name)
        if ext is not None and "source" in ext:
            return int(ext["source"])
    return tex.source


def _material(gltf: Any, index: int | None, images: dict[int, tuple[bytes, str]], path: Path,
              checked: dict[int, bool], notes: list[str]) -> dict[str, Any]:  # fmt: skip
    if index is None or index >= len(gltf.materials or []):
        return {}
    material = gltf.materials[index]
    pbr = material.pbrMetallicRoughness
    fields: dict[str, Any] = {
        "alpha_mode": material.alphaMode or "OPAQUE",
        "alpha_cutoff": float(material.alphaCutoff if material.alphaCutoff is not None else 0.5),
        "double_sided": bool(material.doubleSided),
    }
    if pbr is not None and pbr.baseColorFactor is not None:
        fields["base_color_factor"] = tuple(float(v) for v in pbr.baseColorFactor)
    image = _texture_of(gltf, pbr.baseColorTexture.index) if pbr is not None and pbr.baseColorTexture else None
    if image is None:
        return fields
    if image not in checked:
        checked[image] = image in images and _decodes(images[image][0])
        if not checked[image]:
            note = (
                f"head file {path}: base-colour image {image} of material {material.name or index!r} "
                + ("is missing" if image not in images else "cannot be decoded")
                + "; the mesh loads untextured"
            )
            notes.append(note)
            warnings.warn(note, HeadFileWarning, stacklevel=4)
    if checked[image]:
        fields["base_color_image"], fields["base_color_mime"] = images[image]
    return fields


def _decodes(data: bytes) -> bool:
    if not available("PIL"):
        return True  # nothing to check with: a renderer will say so when it needs Pillow
    from PIL import Image

    try:
        with Image.open(io.BytesIO(data)) as image:
            image.verify()
        return True
    except Exception:  # Pillow raises many kinds for a bad image
        return False


def _gltf_parts(path: Path) -> tuple[str, list[_Part], Any, dict[str, np.ndarray], str, list[PrimitiveMaterial],
                                     list[tuple[str, dict[str, Any]]]]:  # fmt: skip
    from mien.rig.files.gltf import read_gltf

    scene = read_gltf(path)
    gltf = scene.gltf
    nodes = scene.nodes
    head_nodes = [i for i, node in enumerate(nodes) if "head" in _tokens(node.name) and "end" not in _tokens(node.name)
                  and "top" not in _tokens(node.name)]  # fmt: skip
    humanoid = _humanoid_bones(gltf)
    if "head" in humanoid:
        head_nodes = [humanoid["head"]]
    subtree = set()
    if head_nodes:
        stack = [head_nodes[0]]
        while stack:
            i = stack.pop()
            subtree.add(i)
            stack.extend(j for j, node in enumerate(nodes) if node.parent == i)
    eye_nodes = {
        side: i for side, i in (("L", humanoid.get("leftEye")), ("R", humanoid.get("rightEye"))) if i is not None
    }
    for i, node in enumerate(nodes):
        side = _side(node.name)
        if _is_eye(node.name) and side and side not in eye_nodes and gltf.nodes[i].mesh is None:
            eye_nodes[side] = i
    version, expressions = _vrm_expressions(gltf, [])
    parts: list[_Part] = []
    extras: list[tuple[str, dict[str, Any]]] = []
    skin_spread = 0.0
    mesh_index_of = {id(p): gltf.nodes[p.node].mesh for p in scene.primitives}
    for primitive in scene.primitives:
        targets = dict(primitive.targets)
        mesh = gltf.meshes[mesh_index_of[id(primitive)]]
        names = list((mesh.extras or {}).get("targetNames") or []) if isinstance(mesh.extras, dict) else []
        for expression, binds in expressions.items():
            delta = None
            for mesh_id, morph, weight in binds:
                if mesh_id != mesh_index_of[id(primitive)]:
                    continue
                source = names[morph] if morph < len(names) else f"{primitive.mesh_name}.target{morph}"
                if source in primitive.targets:
                    add = primitive.targets[source] * np.float32(weight)
                    delta = add if delta is None else delta + add
            if delta is not None:
                targets[expression] = delta
        head_weight = None
        eye_weights: dict[str, np.ndarray] = {}
        if primitive.joint_weights:
            head_weight = sum((w for j, w in primitive.joint_weights.items() if j in subtree),
                              np.zeros(len(primitive.positions), np.float32))  # fmt: skip
            for side, eye_node in eye_nodes.items():
                if eye_node in primitive.joint_weights:
                    eye_weights[side] = primitive.joint_weights[eye_node]
        parts.append(_Part(primitive.mesh_name, primitive.positions, primitive.triangles, targets, primitive.uvs,
                           primitive.material, head_weight, eye_weights))  # fmt: skip
    eye_points = {side: nodes[i].world[:3, 3] for side, i in eye_nodes.items()}
    eye_names = {side: nodes[i].name for side, i in eye_nodes.items()}
    head_point = nodes[head_nodes[0]].world[:3, 3] if head_nodes else None
    skin = _skin_pose(gltf, scene)
    del skin_spread, extras
    points = {f"eye_{s}": p for s, p in eye_points.items()}
    if head_point is not None:
        points["head"] = head_point
    joint_names = ", ".join(f"{eye_names[s]}" for s in sorted(eye_names))
    return version, parts, scene, points, joint_names, [], [("skin", {"skin": skin})]


def _humanoid_bones(gltf: Any) -> dict[str, int]:
    extensions = gltf.extensions or {}
    if "VRMC_vrm" in extensions:
        bones = (extensions["VRMC_vrm"].get("humanoid") or {}).get("humanBones") or {}
        return {name: int(bone["node"]) for name, bone in bones.items() if "node" in bone}
    if "VRM" in extensions:
        bones = (extensions["VRM"].get("humanoid") or {}).get("humanBones") or []
        return {bone["bone"]: int(bone["node"]) for bone in bones if "bone" in bone and "node" in bone}
    return {}


def _skin_pose(gltf: Any, scene: Any) -> str:
    if not gltf.skins:
        return ""
    return "skinned meshes placed by the file's joint pose (linear blend skinning with its inverse bind matrices)"


def _obj_parts(folder: Path, neutral: str | None) -> list[_Part]:

    files = sorted(folder.glob("*.obj"))
    if not files:
        raise HeadFileError(folder, "an OBJ folder needs a neutral .obj and one .obj per shape; it has no .obj")
    if neutral is None:
        named = [f for f in files if "neutral" in f.stem.lower() or f.stem.lower() in ("base", "basis", "head")]
        if not named:
            raise HeadFileError(folder, "no neutral mesh: name it *neutral*.obj (or base.obj), or pass neutral=")
        base = named[0]
    else:
        base = folder / neutral
        if not base.is_file():
            raise HeadFileError(folder, f"the neutral mesh {neutral} is not in the folder")
    try:
        vertices, triangles = read_obj(base)
    except (InvalidValueError, ValueError) as exc:
        raise HeadFileError(base, f"unreadable neutral OBJ ({exc})") from None
    targets: dict[str, np.ndarray] = {}
    for file in files:
        if file == base:
            continue
        try:
            shape = read_obj_vertices(file)
        except (InvalidValueError, ValueError) as exc:
            warnings.warn(f"head folder {folder}: {file.name} skipped ({exc})", HeadFileWarning, stacklevel=3)
            continue
        if shape.shape != vertices.shape:
            problem = f"{file.name} has {len(shape)} vertices, the neutral {len(vertices)}"
            warnings.warn(f"head folder {folder}: {problem}: skipped (a shape must share the neutral's topology)",
                          HeadFileWarning, stacklevel=3)  # fmt: skip
            continue
        targets[file.stem] = (shape - vertices).astype(np.float32)
    return [_Part(base.stem, vertices, triangles.astype(np.int64), targets)]


def _unit(distance: float) -> tuple[float, str]:
    candidates = {1.0: "metres", 0.01: "centimetres", 0.001: "millimetres", 0.0254: "inches", 0.1: "decimetres"}
    scale = min(candidates, key=lambda s: abs(math.log(max(distance, 1e-12) * s / EYE_DISTANCE_M)))
    return scale, f"{candidates[scale]} (eye centres {distance:.4g} file units apart = {distance * scale * 1e3:.1f} mm)"


def load_head_file(
    path: str | os.PathLike[str],
    convention: str | None = None,
    overrides: str | os.PathLike[str] | Overrides | None = None,
    neutral: str | None = None,
) -> FileRig:
    """Load a head from a ``.glb``/``.gltf``/``.vrm`` file or an OBJ folder as a :class:`FileRig`.

    ``convention`` forces a naming convention (:data:`mien.rig.conventions.CONVENTION_NAMES`), ``overrides`` is a
    TOML file (or parsed :class:`~mien.rig.conventions.Overrides`) of naming rows, ``neutral`` names the OBJ
    folder's neutral file. The rig's targets: the ARKit targets the file can feed, in ARKit order, then the
    file's unmatched shapes under their own names. Raises :class:`HeadFileError` (bad file),
    :class:`NoMorphTargetsError` (nothing to animate), :class:`~mien.errors.MissingExtraError` (``mien[heads]``).
    """
    source = Path(path)
    if isinstance(overrides, str | os.PathLike):
        overrides = read_overrides(overrides)
    notes: list[str] = []
    points: dict[str, np.ndarray] = {}
    joint_names = ""
    materials_raw: list[dict[str, Any]] = []
    skin = ""
    if source.is_dir():
        fmt, parts = "obj-folder", _obj_parts(source, neutral)
        materials_raw = [{} for _ in parts]
    elif source.suffix.lower() in FILE_SUFFIXES or source.is_file():
        if source.suffix.lower() not in FILE_SUFFIXES:
            raise HeadFileError(source, f"unsupported file type {source.suffix!r}: use {', '.join(FILE_SUFFIXES)} "
                                "or an OBJ folder")  # fmt: skip
        fmt, parts, scene, points, joint_names, _, extra = _gltf_parts(source)
        skin = extra[0][1]["skin"]
        checked: dict[int, bool] = {}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", HeadFileWarning)  # collected in notes, re-raised once below
            materials_raw = [
                _material(scene.gltf, part.material, scene.images, source, checked, notes) for part in parts
            ]
        for note in notes:
            warnings.warn(note, HeadFileWarning, stacklevel=2)
    else:
        raise HeadFileError(source, "no such file or folder")
    if not parts:
        raise HeadFileError(source, "no triangle meshes in the default scene")
    if not any(part.targets for part in parts):
        raise NoMorphTargetsError(source)

    # Weld, then lay the parts end to end.
    welded, remaps = zip(*(_weld(part) for part in parts), strict=True)
    offsets = np.cumsum([0] + [len(p.positions) for p in welded])
    positions = np.concatenate([p.positions for p in welded])
    faces = np.concatenate([p.triangles + offsets[i] for i, p in enumerate(welded)])

    # Eyes.
    eye_centres, eye_ids, eyes = None, [np.zeros(0, np.int64), np.zeros(0, np.int64)], ""
    eye_meshes = {}
    for i, part in enumerate(welded):
        side = _side(part.name)
        if _is_eye(part.name) and side and side not in eye_meshes:
            eye_meshes[side] = i
    if len(eye_meshes) == 2:
        found = [_sphere(welded[eye_meshes[s]].positions)[0] for s in ("L", "R")]
        eye_centres = np.stack(found)
        eye_ids = [np.arange(offsets[eye_meshes[s]], offsets[eye_meshes[s] + 1]) for s in ("L", "R")]
        eyes = f"eye meshes {welded[eye_meshes['L']].name}, {welded[eye_meshes['R']].name} (sphere centres)"
    elif "eye_L" in points and "eye_R" in points:
        eye_centres = np.stack([points["eye_L"], points["eye_R"]])
        eyes = f"eye joints {joint_names} (their positions)"
        eye_ids = [np.flatnonzero(np.concatenate([p.eye_joint_weight.get(s, np.zeros(len(p.positions)))
                                                  for p in welded]) > 0.5) for s in ("L", "R")]  # fmt: skip
    else:
        for i, part in enumerate(welded):
            found_parts = _eyeball_parts(part.positions, part.triangles)
            if found_parts is not None:
                eye_centres = found_parts[0]
                eye_ids = [np.asarray(found_parts[1][k], np.int64) + offsets[i] for k in range(2)]
                eyes = f"eyeball-like parts of mesh {part.name} (sphere fits: no eye mesh or joint is named)"
                break
    if eye_centres is None:
        moved = np.zeros(len(positions), bool)
        for i, part in enumerate(welded):
            for delta in part.targets.values():
                moved[offsets[i] : offsets[i + 1]] |= np.abs(delta).max(axis=1) > 1e-9
        face = positions[moved] if moved.any() else positions
        lo, hi = face.min(axis=0), face.max(axis=0)
        width = float(hi[0] - lo[0])
        centre = np.array([(lo[0] + hi[0]) / 2, hi[1] - 0.3 * (hi[1] - lo[1]), hi[2] - 0.35 * width])
        half = 0.22 * width
        step = np.array([half, 0.0, 0.0])
        eye_centres = np.stack([centre + step, centre - step])
        eyes = ("estimated from the region the shapes move (no eye mesh, joint or eyeball found): 30% down from "
                "its top, eyes 44% of its width apart")  # fmt: skip

    # Axes: a model whose left eye (by name) sits at -x faces -z.
    axes = (
        "glTF axes kept (+y up, +z out of the face, +x the character's left)"
        if fmt != "obj-folder"
        else ("OBJ axes read as +y up, +z out of the face, +x the character's left")
    )
    turn = fmt == "vrm0" or (bool(eye_meshes or joint_names) and eye_centres[0, 0] < eye_centres[1, 0])
    if turn:
        flip = np.diag([-1.0, 1.0, -1.0])
        positions = positions @ flip
        eye_centres = eye_centres @ flip
        points = {k: v @ flip for k, v in points.items()}
        for part in welded:
            for name in part.targets:
                part.targets[name] = (part.targets[name] @ flip.astype(np.float32)).astype(np.float32)
        axes = ("turned 180 degrees about +y: the model faces -z (" + ("VRM 0.x" if fmt == "vrm0" else
                "its left eye sits at -x") + ")")  # fmt: skip
    if eye_centres[0, 0] < eye_centres[1, 0] and not (eye_meshes or joint_names):
        eye_centres = eye_centres[::-1].copy()
        eye_ids = eye_ids[::-1]

    distance = float(np.linalg.norm(eye_centres[0] - eye_centres[1]))
    unit, unit_reason = _unit(distance)
    origin = eye_centres.mean(axis=0)
    neutral_m = ((positions - origin) * unit).astype(np.float32)
    eyes_m = ((eye_centres - origin) * unit).astype(np.float32)
    if "head" in points:
        neck = ((points["head"] - origin) * unit).astype(np.float32)
        neck[0] = 0.0
    else:
        neck = np.array([0.0, -0.055, -0.045], np.float32)

    # Names -> targets.
    shape_names = list(dict.fromkeys(name for part in welded for name in part.targets))
    match = match_names(shape_names, convention, overrides if isinstance(overrides, Overrides) else None)
    n = len(neutral_m)
    x = neutral_m[:, 0]
    # Splitting a both-sided shape: a 1 cm wide linear blend across the midline, so the halves sum to the whole.
    halves: dict[str, np.ndarray | None] = {
        "": None, "L": np.clip(0.5 + x / 0.01, 0.0, 1.0), "R": np.clip(0.5 - x / 0.01, 0.0, 1.0),
    }  # fmt: skip

    tolerance = SPARSE_TOLERANCE_M / unit
    sparse: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for i, part in enumerate(welded):
        for name, delta in part.targets.items():
            ids = _moved(delta, tolerance)
            sparse.setdefault(name, []).append((ids + offsets[i], delta[ids] * np.float32(unit)))

    def combine(name: str, pieces: list[tuple[np.ndarray, np.ndarray]]) -> MorphTarget:
        pieces = [p for p in pieces if len(p[0])]
        if not pieces:
            return MorphTarget(name, np.zeros(0, np.int32), np.zeros((0, 3), np.float32))
        if len(pieces) == 1:
            return MorphTarget(name, *pieces[0])
        ids = np.concatenate([p[0] for p in pieces])
        unique, inverse = np.unique(ids, return_inverse=True)
        deltas = np.zeros((len(unique), 3), np.float32)
        np.add.at(deltas, inverse.ravel(), np.concatenate([p[1] for p in pieces]))
        return MorphTarget(name, unique, deltas)

    targets: list[MorphTarget] = []
    source_names: dict[str, tuple[tuple[str, float, str], ...]] = {}
    for arkit in match.arkit_targets:
        rows = [row for row in match.rows if row.arkit == arkit]
        pieces = []
        for row in rows:
            for ids, delta in sparse.get(row.source, []):
                side_mask = halves[row.side]
                factor = np.float32(row.weight) * (1.0 if side_mask is None else side_mask[ids, None])
                pieces.append((ids, (delta * factor).astype(np.float32)))
        targets.append(combine(arkit, pieces))
        source_names[arkit] = tuple((row.source, row.weight, row.side) for row in rows)
    taken = set(match.arkit_targets)
    for name in match.unmatched:
        own = name if name not in taken else f"{name}.file"
        targets.append(combine(own, sparse.get(name, [])))
        source_names[own] = ((name, 1.0, ""),)

    # Regions.
    regions: dict[str, np.ndarray] = {
        "eye_L": np.asarray(eye_ids[0], np.int32),
        "eye_R": np.asarray(eye_ids[1], np.int32),
    }
    if any(p.head_weight is not None for p in welded):
        head_weight = np.concatenate([p.head_weight if p.head_weight is not None else np.zeros(len(p.positions))
                                      for p in welded])  # fmt: skip
        regions["head"] = np.flatnonzero(head_weight >= 0.5).astype(np.int32)
    else:
        regions["head"] = np.arange(n, dtype=np.int32)
    teeth = [np.arange(offsets[i], offsets[i + 1]) for i, p in enumerate(welded) if "teeth" in p.name.lower()
             or "tooth" in p.name.lower()]  # fmt: skip
    if teeth:
        regions["teeth"] = np.concatenate(teeth).astype(np.int32)
    skin_parts = [np.arange(offsets[i], offsets[i + 1]) for i, p in enumerate(welded)
                  if i not in eye_meshes.values() and "teeth" not in p.name.lower()]  # fmt: skip
    if skin_parts:
        regions["skin"] = np.concatenate(skin_parts).astype(np.int32)
    regions.update(_eye_shells(neutral_m, faces, eyes_m, eye_ids))

    materials = tuple(
        PrimitiveMaterial(
            mesh_name=part.name,
            vertex_ids=(remaps[i] + offsets[i]).astype(np.int32),
            triangles=part.triangles.astype(np.int32),
            uvs=part.uvs,
            **materials_raw[i],
        )
        for i, part in enumerate(parts)
    )
    meshes: dict[str, tuple[int, int]] = {}
    for i, part in enumerate(welded):
        start, _stop = meshes.get(part.name, (int(offsets[i]), int(offsets[i])))
        meshes[part.name] = (min(start, int(offsets[i])), int(offsets[i + 1]))
    info = HeadFileInfo(
        path=str(source), format=fmt, eyes=eyes, unit_m=unit, unit_reason=unit_reason, axes=axes, names=match,
        source_names=source_names, meshes=meshes, materials=materials, skin=skin, notes=tuple(notes),
    )  # fmt: skip
    return FileRig(
        name=source.stem,
        neutral=neutral_m,
        faces=faces.astype(np.int32),
        targets=tuple(targets),
        landmarks=np.zeros(0, np.int32),
        regions=regions,
        eye_centers=eyes_m,
        neck_pivot=neck,
        info=info,
    )
