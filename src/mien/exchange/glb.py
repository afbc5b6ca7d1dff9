"""glTF 2.0 binary (``.glb``): the head mesh with its morph targets, and a clip as animations of both.

What a written file holds (Khronos glTF 2.0 specification; checked by the Khronos ``gltf-validator`` in the
tests with zero errors and zero warnings):

- one mesh, one triangle primitive: ``POSITION`` (metres, the mien frame, which is glTF's: +y up, +z out of the
  face, +x the character's left), smooth ``NORMAL``, ``COLOR_0`` (linear RGB albedo of
  :func:`mien.render.appearance.rig_vertex_colors`) and, where the head gets face paint (brows, lash lines,
  lips; :mod:`mien.render.face_paint`), ``TEXCOORD_0`` and a PNG ``baseColorTexture`` that multiplies the
  vertex colour, and ``_PAINT`` (an application attribute: each vertex's own paint texcoords and strength, which
  mien's viewer uses to fade the paint as the renderer does); triangles the renderer hides (see-through helper
  meshes) are left out of the indices;
- every rig target as a morph target (``POSITION`` deltas, metres), as a *sparse* accessor when the target moves
  few enough vertices that the sparse form is smaller; the target names in ``mesh.extras.targetNames``
  (the convention three.js and Blender read);
- two nodes: ``head`` at the neck pivot, which carries the head rotation, and its child ``face`` with the mesh;
- with a clip, one animation ``clip`` with linear channels for the morph weights of ``face`` and the rotation
  of ``head`` (quaternions from the clip's yaw/pitch/roll, :mod:`mien.rig.pose` conventions), sampled at the
  clip's frames.

Gaze is not animated (the eyes are part of the one mesh; ARKit eye-look targets move the lids only), and the
whole mesh turns with the head, also vertices outside the rig's ``head`` region.

The reader returns the animation as a weight clip: one channel per target name (weights 0..1) and the head
pose channels when the file rotates a node, resampled to a uniform frame rate estimated from the key times. A
user's character file that mien animated (:mod:`mien.exchange.glb_user`) gives back the head's target weights
(ARKit names, and the file's other shapes under their own names) rather than its own shapes' weights.
:func:`mien.rig.face_weights.weights_to_au` turns ARKit weights into AU intensities.
"""

from __future__ import annotations

import struct
import weakref
import zlib
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.glb_user import carries_file, head_turns, target_clip
from mien.exchange.glb_user import write as write_user_file
from mien.exchange.quaternions import matrix_quaternions
from mien.exchange.timing import uniform_clip
from mien.facs.catalogue import POSE_CHANNELS
from mien.facs.clip import Clip
from mien.fileio.glb import COMPONENT_DTYPES, dequantize, pack_glb, read_accessor, unpack_glb
from mien.fileio.streams import Source, TargetT, read_bytes, source_name, write_bytes
from mien.render.appearance import SKIN_ALBEDO, rig_vertex_colors, visible_faces
from mien.render.face_paint import face_paint
from mien.render.offscreen import vertex_normals
from mien.rig.face_weights import clip_to_rig
from mien.rig.heads import open_head
from mien.rig.model import Rig
from mien.rig.pose import _rotations

__all__ = [
    "SUFFIXES",
    "document_of",
    "head_glb_bytes",
    "matrix_quaternions",
    "pack_glb",
    "read",
    "split_glb",
    "write",
]

SUFFIXES: tuple[str, ...] = (".glb",)
"""File suffixes of this format."""

_FLOAT, _UINT32, _UINT16, _UINT8 = 5126, 5125, 5123, 5121
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963

_HEAD_CACHE: weakref.WeakKeyDictionary[Rig, bytes] = weakref.WeakKeyDictionary()


# ---------------------------------------------------------------------------------------------------------------
# Writing


class _Builder:
    """Collects binary data, buffer views and accessors of one GLB."""

    def __init__(self) -> None:
        self.chunks: list[bytes] = []
        self.length = 0
        self.views: list[dict[str, Any]] = []
        self.accessors: list[dict[str, Any]] = []

    def view(self, data: bytes, target: int | None = None) -> int:
        padding = (-self.length) % 4
        if padding:
            self.chunks.append(b"\0" * padding)
            self.length += padding
        view: dict[str, Any] = {"buffer": 0, "byteOffset": self.length, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.chunks.append(data)
        self.length += len(data)
        self.views.append(view)
        return len(self.views) - 1

    def accessor(
        self, array: np.ndarray, kind: str, component: int = _FLOAT, target: int | None = None, bounds: bool = False
    ) -> int:
        data = np.ascontiguousarray(array, dtype=COMPONENT_DTYPES[component])
        accessor: dict[str, Any] = {
            "bufferView": self.view(data.tobytes(), target),
            "componentType": component,
            "count": int(data.shape[0]),
            "type": kind,
        }
        if bounds:
            flat = data.reshape(data.shape[0], -1)
            accessor["min"] = [_number(v) for v in flat.min(axis=0)]
            accessor["max"] = [_number(v) for v in flat.max(axis=0)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def sparse_vec3(self, count: int, ids: np.ndarray, values: np.ndarray) -> int:
        """A VEC3 float accessor of ``count`` zeros except ``values`` (k, 3) at ``ids`` (k,), with bounds."""
        values = np.ascontiguousarray(values, dtype=np.float32)
        low = np.minimum(values.min(axis=0), 0.0) if len(values) else np.zeros(3, np.float32)
        high = np.maximum(values.max(axis=0), 0.0) if len(values) else np.zeros(3, np.float32)
        if len(values) == count:  # every vertex moves: a sparse block would cover all of them
            low, high = values.min(axis=0), values.max(axis=0)
        accessor: dict[str, Any] = {
            "componentType": _FLOAT,
            "count": count,
            "type": "VEC3",
            "min": [_number(v) for v in low],
            "max": [_number(v) for v in high],
        }
        if len(ids):
            accessor["sparse"] = {
                "count": len(ids),
                "indices": {"bufferView": self.view(np.asarray(ids, np.uint32).tobytes()), "componentType": _UINT32},
                "values": {"bufferView": self.view(values.tobytes())},
            }
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def binary(self) -> bytes:
        data = b"".join(self.chunks)
        return data + b"\0" * ((-len(data)) % 4)


def _number(value: Any) -> float | int:
    number = value.item() if hasattr(value, "item") else value
    return int(number) if isinstance(number, (int, np.integer)) else float(number)


def _png(rgba: np.ndarray) -> bytes:
    """PNG bytes of an (h, w, 4) uint8 image (zlib only: the format needs no imaging library)."""
    height, width = rgba.shape[:2]
    raw = b"".join(b"\0" + rgba[row].tobytes() for row in range(height))

    def chunk(kind: bytes, payload: bytes) -> bytes:
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b"")


def _srgb(linear: np.ndarray) -> np.ndarray:
    """Linear 0..1 -> sRGB-encoded 0..255 uint8."""
    c = np.clip(linear, 0.0, 1.0)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.asarray(np.round(encoded * 255.0), np.uint8)


def _appearance(rig: Rig) -> tuple[np.ndarray, np.ndarray | None, bytes | None]:
    """(colours (n, 3) linear, texcoords (n, 2) or None, PNG of the paint as a colour multiplier or None)."""

    colors = rig_vertex_colors(rig).copy()
    paint = face_paint(rig)
    if paint is None:
        return colors, None, None
    texture = np.asarray(paint.texture, np.float64)  # premultiplied rgb, alpha; row 0 is v = 0
    skin = np.asarray(SKIN_ALBEDO)
    # Paint over skin, as a factor on the skin colour: the vertex colour under painted texels is skin.
    factor = (texture[..., :3] + (1.0 - texture[..., 3:4]) * skin) / skin
    rgba = np.concatenate([_srgb(factor), np.full((*factor.shape[:2], 1), 255, np.uint8)], axis=2)
    uv = np.array(paint.texcoords[:, :2], np.float32)
    strength = paint.texcoords[:, 2]
    height, width = texture.shape[:2]
    painted = strength > 0
    # Vertices under opaque paint (the lips' vermilion) take skin colour; the texture carries their colour.
    column = np.clip((uv[:, 0] * width).astype(np.int64), 0, width - 1)
    row = np.clip((uv[:, 1] * height).astype(np.int64), 0, height - 1)
    covered = painted & (texture[row, column, 3] > 0.5)
    colors[covered] = skin
    uv[~painted] = -0.01  # clamped onto the transparent border: factor 1
    return colors, uv, _png(rgba)


def _quaternions(poses_deg: np.ndarray) -> np.ndarray:
    """(n, 4) float32 unit quaternions (x, y, z, w) of the head rotations of (n, 5) pose degrees."""

    return matrix_quaternions(_rotations(poses_deg[:, 0], poses_deg[:, 1], poses_deg[:, 2]))


def _angles(quaternions: np.ndarray) -> np.ndarray:
    """(n, 3) yaw, pitch, roll degrees of (n, 4) quaternions (x, y, z, w): the inverse of :func:`_quaternions`."""
    q = np.asarray(quaternions, np.float64)
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    x, y, z, w = q.T
    r02 = 2 * (x * z + w * y)
    r22 = 1 - 2 * (x * x + y * y)
    r12 = 2 * (y * z - w * x)
    r10 = 2 * (x * y + w * z)
    r11 = 1 - 2 * (x * x + z * z)
    yaw = np.arctan2(r02, r22)
    b = np.arcsin(np.clip(-r12, -1.0, 1.0))  # R = Ry(yaw) Rx(b) Rz(c) with b = -pitch, c = -roll
    c = np.arctan2(r10, r11)
    return np.degrees(np.stack([yaw, -b, -c], axis=1))


def _document(rig: Rig, weights: np.ndarray | None, poses: np.ndarray | None, fps: float) -> bytes:
    return pack_glb(*document_of(rig, weights, poses, fps))


def document_of(
    rig: Rig, weights: np.ndarray | None, poses: np.ndarray | None, fps: float
) -> tuple[dict[str, Any], bytes]:
    """The glTF JSON (a dict) and binary chunk of ``rig`` animated by (n, n_targets) ``weights`` and (n, 5)
    ``poses`` at ``fps`` (both None: the still head). Node 0 is ``head``, node 1 ``face`` (the mesh)."""

    built = _Builder()
    faces = visible_faces(rig)
    neutral = rig.neutral
    normals = vertex_normals(neutral, faces)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    normals = np.where(length > 0.5, normals / np.maximum(length, 1e-12), np.array([0.0, 0.0, 1.0], np.float32)).astype(
        np.float32
    )
    colors, uv, png = _appearance(rig)
    attributes = {
        "POSITION": built.accessor(neutral, "VEC3", target=_ARRAY_BUFFER, bounds=True),
        "NORMAL": built.accessor(normals, "VEC3", target=_ARRAY_BUFFER),
        "COLOR_0": built.accessor(np.clip(colors, 0.0, 1.0), "VEC3", target=_ARRAY_BUFFER),
    }
    material: dict[str, Any] = {
        "name": "skin",
        "pbrMetallicRoughness": {"metallicFactor": 0.0, "roughnessFactor": 0.6},
    }
    gltf: dict[str, Any] = {"asset": {"version": "2.0", "generator": "mien"}}
    if uv is not None and png is not None:
        attributes["TEXCOORD_0"] = built.accessor(uv, "VEC2", target=_ARRAY_BUFFER)
        gltf["images"] = [{"bufferView": built.view(png), "mimeType": "image/png"}]
        gltf["samplers"] = [{"magFilter": 9729, "minFilter": 9987, "wrapS": 33071, "wrapT": 33071}]
        gltf["textures"] = [{"sampler": 0, "source": 0}]
        material["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
        # Every vertex's own texcoords and paint strength (FacePaint.texcoords: u, v, strength), for mien's viewer,
        # which fades the paint by the strength as the renderer does. TEXCOORD_0 parks unpainted vertices on the
        # border, so a triangle from a painted vertex to a parked one spans the texture and samples its coarsest
        # mipmap: thin red lines along the paint's edge (ICT's neck and chest) in a viewer that reads only it.
        paint_texcoords = np.asarray(face_paint(rig).texcoords, np.float32)  # type: ignore[union-attr]  # uv: painted
        attributes["_PAINT"] = built.accessor(paint_texcoords, "VEC3", target=_ARRAY_BUFFER)
    primitive: dict[str, Any] = {
        "attributes": attributes,
        "indices": built.accessor(faces.reshape(-1), "SCALAR", _UINT32, target=_ELEMENT_ARRAY_BUFFER),
        "material": 0,
        "mode": 4,
    }
    n = rig.n_vertices
    targets = []
    for target in rig.targets:
        if len(target.vertex_ids) * 16 < n * 12:
            targets.append({"POSITION": built.sparse_vec3(n, target.vertex_ids, target.deltas)})
        else:
            targets.append({"POSITION": built.accessor(target.dense(n), "VEC3", bounds=True)})
    mesh: dict[str, Any] = {"name": rig.name, "primitives": [primitive]}
    if targets:
        primitive["targets"] = targets
        mesh["weights"] = [0.0] * len(targets)
        mesh["extras"] = {"targetNames": list(rig.target_names)}
    pivot = [float(v) for v in rig.neck_pivot]
    gltf.update(
        scene=0,
        scenes=[{"name": "mien", "nodes": [0]}],
        nodes=[
            {"name": "head", "translation": pivot, "children": [1]},
            {"name": "face", "mesh": 0, "translation": [-v for v in pivot]},
        ],
        meshes=[mesh],
        materials=[material],
    )
    if weights is not None and poses is not None and len(weights):
        times = (np.arange(len(weights)) / fps).astype(np.float32)
        time_accessor = built.accessor(times, "SCALAR", bounds=True)
        samplers = []
        channels = []
        if targets:
            samplers.append({"input": time_accessor, "output": built.accessor(weights.reshape(-1), "SCALAR")})
            channels.append({"sampler": 0, "target": {"node": 1, "path": "weights"}})
        samplers.append({"input": time_accessor, "output": built.accessor(_quaternions(poses), "VEC4")})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": 0, "path": "rotation"}})
        gltf["animations"] = [{"name": "clip", "samplers": samplers, "channels": channels}]
    binary = built.binary()
    gltf["buffers"] = [{"byteLength": len(binary)}]
    gltf["bufferViews"] = built.views
    gltf["accessors"] = built.accessors
    return gltf, binary


def head_glb_bytes(rig: Rig) -> bytes:
    """The head alone as GLB bytes: mesh, appearance and named morph targets, no animation.

    Cached per rig (rigs are immutable); this is what the live viewer loads before streaming weights.
    """
    cached = _HEAD_CACHE.get(rig)
    if cached is None:
        cached = _HEAD_CACHE[rig] = _document(rig, None, None, 30.0)
    return cached


def write(clip: Clip, target: TargetT, rig: Rig | None = None) -> TargetT:
    """Write ``rig`` (default: :func:`mien.rig.heads.open_head`) animated by ``clip`` as GLB to ``target``.

    A head read from the user's own glTF / GLB / VRM file (a :class:`~mien.rig.files.head.FileRig`) is written
    as that file with the animation added (:mod:`mien.exchange.glb_user`); any other head as the document the
    module doc describes.

    ``clip``: face channels (AU intensities, pose degrees) or the rig's target names (weights 0..1) plus
    optional pose channels (see :func:`mien.rig.face_weights.clip_to_rig`). Returns ``target``.
    """

    if rig is None:
        rig = open_head()
    if clip.n_frames == 0:
        raise InvalidValueError("clip", "0 frames", "a clip with at least one frame to animate")

    if carries_file(rig):  # a head read from the user's glTF file: that file, animated
        return write_user_file(clip, target, rig)
    weights, poses = clip_to_rig(clip, rig)
    write_bytes(_document(rig, weights, poses, clip.fps), target)
    return target


# ---------------------------------------------------------------------------------------------------------------
# Reading


def split_glb(data: bytes, name: str) -> tuple[dict[str, Any], bytes]:
    """The JSON document (a dict) and the binary chunk (``b""`` when none) of GLB ``data``; ``name`` names the
    file in errors (truncated or corrupt data raises :class:`~mien.fileio.glb.GlbError`, an
    :class:`~mien.errors.InvalidValueError`). The container is :mod:`mien.fileio.glb`'s."""
    document, binary = unpack_glb(data, name)
    return document, binary or b""


def _read_accessor(document: dict[str, Any], binary: bytes, index: int, name: str) -> np.ndarray:
    """(count, width) float64 values of accessor ``index`` (buffer 0 only: mien's own files have no other)."""
    views = document.get("bufferViews") or []

    def view_bytes(view_index: int) -> bytes:
        view = views[view_index]
        start = int(view.get("byteOffset", 0))
        data = binary[start : start + int(view["byteLength"])]
        if len(data) != int(view["byteLength"]):
            raise InvalidValueError(f"{name} bufferView {view_index}", "past the end of the buffer", "a complete file")
        return data

    try:
        values = read_accessor(document, index, view_bytes, name)
        return dequantize(values, document["accessors"][index]).astype(np.float64)
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        if isinstance(exc, InvalidValueError):
            raise
        raise InvalidValueError(f"{name} accessor {index}", repr(exc), "a valid glTF accessor") from None


def read(source: Source) -> Clip:
    """The first animation of a GLB as a weight clip (target names, plus pose channels if a node rotates).

    Keys are resampled (linearly) to a uniform rate: ``(n_keys - 1) / duration``. A file without a mesh that
    has morph targets, or without an animation of them, raises naming the file.
    """
    name = source_name(source)
    document, binary = split_glb(read_bytes(source), name)
    meshes = document.get("meshes", [])
    nodes = document.get("nodes", [])
    mesh_index = next((i for i, m in enumerate(meshes) if any("targets" in p for p in m.get("primitives", []))), None)
    if mesh_index is None:
        raise InvalidValueError(f"{name} meshes", len(meshes), "a mesh with morph targets")
    n_targets = len(meshes[mesh_index]["primitives"][0]["targets"])
    names = list(meshes[mesh_index].get("extras", {}).get("targetNames", []))
    if len(names) != n_targets:
        names = [f"target_{i}" for i in range(n_targets)]
    animations = document.get("animations", [])
    if not animations:
        raise InvalidValueError(f"{name} animations", 0, "an animation (this file holds a still head)")
    animation = animations[0]
    extras = animation.get("extras")
    mesh_nodes = {i for i, node in enumerate(nodes) if node.get("mesh") == mesh_index}
    tracks: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for channel in animation.get("channels", []):
        path = channel.get("target", {}).get("path")
        sampler = animation["samplers"][channel["sampler"]]
        times = _read_accessor(document, binary, sampler["input"], name)[:, 0]
        output = _read_accessor(document, binary, sampler["output"], name)
        if sampler.get("interpolation") == "CUBICSPLINE":
            output = output.reshape(len(times), 3, -1)[:, 1].reshape(-1, output.shape[1])
        if path == "weights" and channel["target"].get("node") in mesh_nodes and "weights" not in tracks:
            tracks["weights"] = (times, output.reshape(len(times), n_targets))
        elif path == "rotation":
            turns = head_turns(channel["target"].get("node"), output, extras)
            if turns is not None:  # the head of a user's file that mien animated: its own rest frame undone
                tracks["rotation"] = (times, _angles(matrix_quaternions(turns)))
            elif "rotation" not in tracks:
                tracks["rotation"] = (times, _angles(output))
    if "weights" not in tracks:
        raise InvalidValueError(f"{name} animation 0", "no morph-weight channel", "an animation of the morph weights")
    times, weights = tracks["weights"]
    if len(times) > 1 and np.any(np.diff(times) <= 0):
        index = int(np.argmax(np.diff(times) <= 0)) + 1
        raise InvalidValueError(f"{name} key time {index}", float(times[index]), "increasing key times")
    columns = [weights[:, j] for j in range(n_targets)]
    channel_names = list(names)
    if "rotation" in tracks:
        rotation_times, angles = tracks["rotation"]
        columns += [np.interp(times, rotation_times, angles[:, j]) for j in range(3)]
        channel_names += list(POSE_CHANNELS[:3])
    clip = uniform_clip(times, np.stack(columns, axis=1), channel_names)
    targets = target_clip(clip, extras)
    return clip if targets is None else targets
