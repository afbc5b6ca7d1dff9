"""Read the meshes of a glTF 2.0 file (``.glb``, ``.gltf``, ``.vrm``) into plain arrays, in the file's world frame.

The JSON is read directly (a thin attribute view with pygltflib's field names, :class:`_View`: pygltflib's own
document model takes 0.16 s per VALID avatar, 0.8 s on its first call, against 1 ms here); the decoders come
with the extra ``mien[heads]``. This module decodes what real avatars hold:

- ``EXT_meshopt_compression`` buffer views (PyPI ``meshopt``, meshoptimizer's decoder, with its filters);
- ``KHR_mesh_quantization``: normalized and unnormalized integer accessors (glTF 2.0 section 3.11 formulas);
- ``KHR_draco_mesh_compression`` primitives (PyPI ``DracoPy``);
- sparse accessors, interleaved (strided) views, data URIs and external ``.bin`` files beside a ``.gltf``;
- every mesh instance in the default scene, placed by its node's world matrix, or, when skinned, by linear blend
  skinning with the file's joint pose (``J_j @ IBM_j`` per joint: the skinned mesh's own node transform is
  ignored, as the spec says). Morph deltas get the same linear part, so a target moves the placed mesh.
- ``EXT_texture_webp`` and plain base-colour textures: the image bytes are kept (not decoded here).

Names of morph targets come from ``mesh.extras.targetNames`` (what Blender, glTF-Transform and three.js use).
Every failure raises :class:`~mien.rig.files.errors.HeadFileError` naming the file.
"""

from __future__ import annotations

import base64
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mien.extras import require
from mien.fileio.glb import MAGIC, GlbError, dequantize, parse_json, read_accessor, unpack_glb
from mien.rig.files.errors import HeadFileError

__all__ = ["SUPPORTED_EXTENSIONS", "GltfNode", "GltfPrimitive", "GltfScene", "read_gltf"]

SUPPORTED_EXTENSIONS: frozenset[str] = frozenset(
    {
        "EXT_meshopt_compression",
        "KHR_mesh_quantization",
        "KHR_draco_mesh_compression",
        "EXT_texture_webp",
        "KHR_materials_emissive_strength",
        "KHR_materials_unlit",
        "KHR_texture_transform",
        "KHR_materials_specular",
        "KHR_materials_ior",
        "KHR_materials_clearcoat",
        "KHR_materials_sheen",
        "KHR_materials_transmission",
        "KHR_materials_volume",
        "KHR_texture_basisu",
        "VRM",
        "VRMC_vrm",
        "VRMC_springBone",
        "VRMC_materials_mtoon",
        "VRMC_node_constraint",
    }
)
"""Extensions a file may *require* and still load (material-only ones only change looks, which mien ignores)."""


@dataclass(frozen=True, eq=False)
class GltfNode:
    """One node: its name, world matrix and parent."""

    name: str
    """The node's name (``node<i>`` when it has none)."""
    world: np.ndarray
    """(4, 4) float64 world matrix (column vectors), file units."""
    parent: int | None
    """Index of the parent node, None at a root."""


@dataclass(frozen=True, eq=False)
class GltfPrimitive:
    """One drawn primitive, placed in the file's world frame."""

    mesh_name: str
    """Name of its mesh (``mesh<i>`` when it has none)."""
    node: int
    """Index of the node that draws it."""
    positions: np.ndarray
    """(n, 3) float64 world positions, file units."""
    triangles: np.ndarray
    """(m, 3) int64 vertex ids into :attr:`positions`."""
    targets: dict[str, np.ndarray]
    """Morph-target name -> (n, 3) float32 world delta at weight 1, file units."""
    uvs: np.ndarray | None
    """(n, 2) float32 ``TEXCOORD_0``, or None."""
    material: int | None
    """Index of its material in the file, or None."""
    joint_weights: dict[int, np.ndarray] = field(default_factory=dict)
    """Skinned primitives: node index of a joint -> (n,) float32 weight of that joint on each vertex."""


@dataclass(frozen=True, eq=False)
class GltfScene:
    """What mien takes from a glTF file."""

    path: Path
    """The file read."""
    gltf: Any
    """The glTF document as an attribute view (materials, extensions, VRM data; pygltflib's field names)."""
    nodes: tuple[GltfNode, ...]
    """Every node of the file, in file order."""
    primitives: tuple[GltfPrimitive, ...]
    """Every triangle primitive drawn by the default scene."""
    images: dict[int, tuple[bytes, str]]
    """Image index -> (encoded bytes, MIME type) for images the file carries or points at."""


def _trs(node: Any) -> np.ndarray:
    if node.matrix is not None:
        return np.asarray(node.matrix, np.float64).reshape(4, 4).T
    m = np.eye(4)
    if node.rotation is not None:
        x, y, z, w = (float(v) for v in node.rotation)
        m[:3, :3] = [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    if node.scale is not None:
        m[:3, :3] = m[:3, :3] * np.asarray(node.scale, np.float64)[None, :]
    if node.translation is not None:
        m[:3, 3] = node.translation
    return m


class _Reader:
    """Buffers, views and accessors of one document, decoded once each."""

    def __init__(self, gltf: Any, path: Path, blob: bytes | None) -> None:
        self.gltf, self.path, self.blob = gltf, path, blob
        self._buffers: dict[int, bytes] = {}
        self._views: dict[int, memoryview] = {}  # zero-copy slices of the buffers, or decoded data

    def fail(self, problem: str) -> HeadFileError:
        return HeadFileError(self.path, problem)

    def buffer(self, index: int) -> bytes:
        if index in self._buffers:
            return self._buffers[index]
        try:
            buffer = self.gltf.buffers[index]
        except (IndexError, TypeError):
            raise self.fail(f"buffer {index} does not exist") from None
        uri = buffer.uri
        if uri is None:
            if self.blob is None:
                raise self.fail(f"buffer {index} has no data (no binary chunk, no uri)")
            data = self.blob
        elif uri.startswith("data:"):
            try:
                data = base64.b64decode(uri.split(",", 1)[1])
            except (IndexError, ValueError):
                raise self.fail(f"buffer {index} has an undecodable data URI") from None
        else:
            file = self.path.parent / uri
            if not file.is_file():
                raise self.fail(f"buffer {index} points at {file}, which does not exist")
            data = file.read_bytes()
        if len(data) < int(buffer.byteLength or 0):
            raise self.fail(f"buffer {index} is truncated: {len(data)} of {buffer.byteLength} bytes")
        self._buffers[index] = data
        return data

    def view(self, index: int) -> memoryview:
        if index in self._views:
            return self._views[index]
        try:
            view = self.gltf.bufferViews[index]
        except (IndexError, TypeError):
            raise self.fail(f"bufferView {index} does not exist") from None
        meshopt_ext = (view.extensions or {}).get("EXT_meshopt_compression")
        if meshopt_ext is not None:
            meshopt = require("meshopt", "heads")
            source = self.buffer(int(meshopt_ext["buffer"]))
            start = int(meshopt_ext.get("byteOffset", 0))
            packed = memoryview(source)[start : start + int(meshopt_ext["byteLength"])]
            count, stride = int(meshopt_ext["count"]), int(meshopt_ext["byteStride"])
            try:
                decoded = meshopt.decode_gltf_buffer(
                    packed, count, stride, meshopt_ext["mode"], meshopt_ext.get("filter", "NONE")
                )
            except Exception as exc:  # the decoder's own errors: corrupt or truncated stream
                raise self.fail(f"bufferView {index}: EXT_meshopt_compression data does not decode ({exc})") from None
            data = np.ascontiguousarray(decoded).data.cast("B")
        else:
            source = self.buffer(int(view.buffer))
            start = int(view.byteOffset or 0)
            data = memoryview(source)[start : start + int(view.byteLength)]
            if len(data) != int(view.byteLength):
                raise self.fail(f"bufferView {index} runs past the end of buffer {view.buffer} (truncated file?)")
        self._views[index] = data
        return data

    def _stride(self, view_index: int) -> int:
        view = self.gltf.bufferViews[view_index]
        meshopt_ext = (view.extensions or {}).get("EXT_meshopt_compression")
        return int(meshopt_ext["byteStride"]) if meshopt_ext is not None else int(view.byteStride or 0)

    def accessor(self, index: int, as_float: bool = True) -> np.ndarray:
        """(count, width) array of accessor ``index``: floats (dequantized) or raw integers."""
        try:
            values = read_accessor(self.gltf.document, index, self.view, str(self.path), self._stride)
        except GlbError as exc:
            raise self.fail(exc.problem) from None
        return dequantize(values, self.gltf.document["accessors"][index]) if as_float else values


class _View:
    """Attribute access over a glTF JSON object (pygltflib's field names; absent fields read as None).

    ``extras``, ``extensions`` and morph ``targets`` stay plain dicts. pygltflib's own document model decodes
    the same JSON through dataclasses_json in 0.16 s for a VALID avatar (61 kB of JSON; 0.8 s on its first
    call), most of a whole mien load; this view reads it in about 1 ms (bench/head_load.py times both).
    """

    __slots__ = ("_cache", "_data")

    def __init__(self, data: dict[str, Any]) -> None:
        self._data = data
        self._cache: dict[str, Any] = {}

    @property
    def document(self) -> dict[str, Any]:
        """The JSON object this view reads."""
        return self._data

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        if name not in self._cache:
            value = self._data.get(name)
            keep = name in ("extras", "extensions", "targets") or value is None
            self._cache[name] = value if keep else _wrap(value)
        return self._cache[name]


def _wrap(value: Any) -> Any:
    if isinstance(value, dict):
        return _View(value)
    if isinstance(value, list):
        return [_wrap(item) for item in value]
    return value


def _load_document(path: Path) -> tuple[Any, bytes | None]:
    """The glTF JSON (as a :class:`_View`) and the GLB binary chunk (None for a ``.gltf``)."""
    if not path.is_file():
        raise HeadFileError(path, "no such file")
    data = path.read_bytes()
    try:
        document, blob = unpack_glb(data, str(path)) if data[:4] == MAGIC else (parse_json(data, str(path)), None)
    except GlbError as exc:
        raise HeadFileError(path, exc.problem) from None
    if not str((document.get("asset") or {}).get("version", "")).startswith("2"):
        raise HeadFileError(path, "not a glTF 2.0 file (asset.version is not 2.x)")
    return _View(document), blob


def _world_matrices(gltf: Any) -> tuple[list[np.ndarray], list[int | None]]:
    n = len(gltf.nodes or [])
    parent: list[int | None] = [None] * n
    for i, node in enumerate(gltf.nodes or []):
        for child in node.children or []:
            parent[child] = i
    world: list[np.ndarray | None] = [None] * n

    def compute(i: int) -> np.ndarray:
        chain = []
        j: int | None = i
        while j is not None and world[j] is None:
            chain.append(j)
            j = parent[j]
        base = np.eye(4) if j is None else world[j]
        for k in reversed(chain):
            base = base @ _trs(gltf.nodes[k])
            world[k] = base
        return world[i]  # type: ignore[return-value]

    return [compute(i) for i in range(n)], parent


def _scene_nodes(gltf: Any) -> list[int]:
    """Nodes drawn by the default scene (every root's subtree); all nodes when the file has no scene."""
    if not gltf.scenes:
        return list(range(len(gltf.nodes or [])))
    scene = gltf.scenes[gltf.scene or 0]
    out, stack = [], list(scene.nodes or [])
    while stack:
        i = stack.pop()
        out.append(i)
        stack.extend(gltf.nodes[i].children or [])
    return sorted(out)


def _draco(reader: _Reader, primitive: Any, ext: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    dracopy = require("DracoPy", "heads")
    try:
        mesh = dracopy.decode(bytes(reader.view(int(ext["bufferView"]))))
    except Exception as exc:  # DracoPy raises its own failure types
        raise reader.fail(f"KHR_draco_mesh_compression data does not decode ({exc})") from None
    attributes = ext.get("attributes", {})

    def attribute(name: str) -> np.ndarray | None:
        if name not in attributes:
            return None
        found = mesh.get_attribute_by_unique_id(int(attributes[name]))
        return None if found is None else np.asarray(found["data"], np.float32)

    positions = attribute("POSITION")
    if positions is None:
        positions = np.asarray(mesh.points, np.float32)
    return positions, np.asarray(mesh.faces, np.int64).reshape(-1, 3), attribute("TEXCOORD_0")


def _triangles(mode: int, ids: np.ndarray) -> np.ndarray | None:
    if mode == 4:
        return ids.reshape(-1, 3)
    if mode == 5:  # strip: alternate the winding
        tri = np.stack([ids[:-2], ids[1:-1], ids[2:]], axis=1)
        tri[1::2] = tri[1::2][:, [1, 0, 2]]
        return tri
    if mode == 6:  # fan
        return np.stack([np.full(len(ids) - 2, ids[0]), ids[1:-1], ids[2:]], axis=1)
    return None  # points and lines carry no surface


def _primitive(
    reader: _Reader, mesh: Any, mesh_name: str, node_index: int, primitive: Any, place: np.ndarray | None,
    skin_matrices: np.ndarray | None, joints_of_skin: list[int],
) -> GltfPrimitive | None:  # fmt: skip
    attributes = primitive.attributes
    draco = (primitive.extensions or {}).get("KHR_draco_mesh_compression")
    if draco is not None:
        positions, triangles, uvs = _draco(reader, primitive, draco)
    else:
        if attributes.POSITION is None:
            return None
        positions = reader.accessor(attributes.POSITION)
        n = len(positions)
        ids = (
            reader.accessor(primitive.indices, as_float=False)[:, 0].astype(np.int64)
            if primitive.indices is not None
            else np.arange(n, dtype=np.int64)
        )
        found = _triangles(primitive.mode if primitive.mode is not None else 4, ids)
        if found is None:
            return None
        triangles = found
        uvs = reader.accessor(attributes.TEXCOORD_0) if attributes.TEXCOORD_0 is not None else None
    n = len(positions)
    if triangles.size and (triangles.min() < 0 or triangles.max() >= n):
        raise reader.fail(f"mesh {mesh_name!r}: triangle indices outside its {n} vertices")
    names = list((mesh.extras or {}).get("targetNames") or []) if isinstance(mesh.extras, dict) else []
    targets: dict[str, np.ndarray] = {}
    for k, target in enumerate(primitive.targets or []):
        name = str(names[k]) if k < len(names) else f"{mesh_name}.target{k}"
        if "POSITION" not in target or target["POSITION"] is None:
            continue
        delta = reader.accessor(target["POSITION"])
        if delta.shape != (n, 3):
            raise reader.fail(f"mesh {mesh_name!r} morph target {name!r}: {delta.shape} deltas for {n} vertices")
        targets[name] = delta
    joint_weights: dict[int, np.ndarray] = {}
    pos64 = positions.astype(np.float64)
    if skin_matrices is not None and attributes.JOINTS_0 is not None and attributes.WEIGHTS_0 is not None:
        joints = np.concatenate(
            [reader.accessor(getattr(attributes, f"JOINTS_{s}"), as_float=False) for s in range(8)
             if getattr(attributes, f"JOINTS_{s}", None) is not None], axis=1,
        ).astype(np.int64)  # fmt: skip
        weights = np.concatenate(
            [reader.accessor(getattr(attributes, f"WEIGHTS_{s}")) for s in range(8)
             if getattr(attributes, f"WEIGHTS_{s}", None) is not None], axis=1,
        ).astype(np.float64)  # fmt: skip
        if joints.shape != weights.shape or len(joints) != n or (joints.size and joints.max() >= len(skin_matrices)):
            raise reader.fail(f"mesh {mesh_name!r}: JOINTS/WEIGHTS do not match its skin")
        total = weights.sum(axis=1, keepdims=True)
        weights = np.divide(weights, total, out=np.zeros_like(weights), where=total > 0)
        # Per-vertex blended matrix, its top 3x4 rows only: (n, 3, 4), a sum over the few influences per vertex.
        top = skin_matrices[:, :3, :]
        blend = np.zeros((n, 3, 4))
        for k in range(joints.shape[1]):
            blend += weights[:, k, None, None] * top[joints[:, k]]
        columns = [np.ascontiguousarray(blend[:, :, j]) for j in range(4)]  # (n, 3) each: x, y, z columns, shift
        pos64 = pos64[:, 0:1] * columns[0] + pos64[:, 1:2] * columns[1] + pos64[:, 2:3] * columns[2] + columns[3]
        for name, delta in targets.items():  # only the rows a target moves (most are zero): R @ 0 = 0
            moved = delta.reshape(-1) != 0
            rows = np.flatnonzero(moved[0::3] | moved[1::3] | moved[2::3])
            d = delta[rows].astype(np.float64)
            turned = np.zeros_like(delta)
            turned[rows] = d[:, 0:1] * columns[0][rows] + d[:, 1:2] * columns[1][rows] + d[:, 2:3] * columns[2][rows]
            targets[name] = turned
        # Weight of each joint on each vertex: one bincount over (vertex, joint) pairs.
        n_joints = len(skin_matrices)
        pairs = np.bincount(
            (np.arange(n)[:, None] * n_joints + joints).reshape(-1), weights.reshape(-1), minlength=n * n_joints
        ).reshape(n, n_joints)
        for joint in np.unique(joints[weights > 0]):
            joint_weights[joints_of_skin[int(joint)]] = pairs[:, joint].astype(np.float32)
    elif place is not None:
        pos64 = pos64 @ place[:3, :3].T + place[:3, 3]
        for name in targets:
            targets[name] = (targets[name].astype(np.float64) @ place[:3, :3].T).astype(np.float32)
    return GltfPrimitive(
        mesh_name=mesh_name,
        node=node_index,
        positions=pos64,
        triangles=triangles.astype(np.int64),
        targets=targets,
        uvs=None if uvs is None else np.asarray(uvs, np.float32)[:, :2],
        material=primitive.material,
        joint_weights=joint_weights,
    )


def _images(reader: _Reader) -> dict[int, tuple[bytes, str]]:
    out: dict[int, tuple[bytes, str]] = {}
    for i, image in enumerate(reader.gltf.images or []):
        try:
            if image.bufferView is not None:
                out[i] = (bytes(reader.view(image.bufferView)), image.mimeType or "")
            elif image.uri and image.uri.startswith("data:"):
                head, _, payload = image.uri.partition(",")
                out[i] = (base64.b64decode(payload), head[5:].split(";")[0])
            elif image.uri:
                file = reader.path.parent / image.uri
                if file.is_file():
                    out[i] = (file.read_bytes(), image.mimeType or "")
        except (HeadFileError, ValueError):
            continue  # a missing image is reported by the texture check, not fatal
    return out


def read_gltf(path: str | os.PathLike[str]) -> GltfScene:
    """Read every triangle primitive of ``path``'s default scene, placed in world coordinates (file units).

    Raises :class:`HeadFileError` for a missing, truncated or corrupt file, an extension it requires that mien
    cannot decode, or inconsistent accessors; :class:`~mien.errors.MissingExtraError` when ``mien[heads]`` is
    not installed.
    """
    file = Path(path)
    gltf, blob = _load_document(file)
    unsupported = sorted(set(gltf.extensionsRequired or []) - SUPPORTED_EXTENSIONS)
    if unsupported:
        raise HeadFileError(file, f"requires extension(s) mien cannot decode: {', '.join(unsupported)}")
    reader = _Reader(gltf, file, blob)
    world, parent = _world_matrices(gltf)
    nodes = tuple(
        GltfNode(name=node.name or f"node{i}", world=world[i], parent=parent[i])
        for i, node in enumerate(gltf.nodes or [])
    )
    primitives: list[GltfPrimitive] = []
    for i in _scene_nodes(gltf):
        node = gltf.nodes[i]
        if node.mesh is None:
            continue
        if node.mesh >= len(gltf.meshes or []):
            raise reader.fail(f"node {i} draws mesh {node.mesh}, which does not exist")
        mesh = gltf.meshes[node.mesh]
        mesh_name = mesh.name or node.name or f"mesh{node.mesh}"
        skin_matrices, joints_of_skin = None, []
        if node.skin is not None:
            skin = gltf.skins[node.skin]
            joints_of_skin = list(skin.joints)
            if skin.inverseBindMatrices is not None:
                ibm = reader.accessor(skin.inverseBindMatrices).astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
            else:
                ibm = np.tile(np.eye(4), (len(joints_of_skin), 1, 1))
            if len(ibm) != len(joints_of_skin):
                raise reader.fail(
                    f"skin {node.skin}: {len(ibm)} inverse bind matrices for {len(joints_of_skin)} joints"
                )
            skin_matrices = np.stack([world[j] for j in joints_of_skin]) @ ibm
        for primitive in mesh.primitives:
            found = _primitive(reader, mesh, mesh_name, i, primitive, world[i], skin_matrices, joints_of_skin)
            if found is not None and len(found.triangles):
                primitives.append(found)
    return GltfScene(path=file, gltf=gltf, nodes=nodes, primitives=tuple(primitives), images=_images(reader))
