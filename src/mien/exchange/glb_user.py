"""A clip on the user's own character: their glTF / GLB / VRM file as it is, with one animation added, as GLB.

What the written file holds: everything of the file read (meshes, compressed buffers, textures, skins, materials,
extensions, VRM data, its own animations), and one more animation, ``mien``, with linear channels sampled at the
clip's frames:

- the morph weights of every node that draws a mesh with a shape the clip moves: the file's own shapes, at the
  weights :mod:`mien.exchange.file_shapes` gives from the rig's (ARKit) weights, so same-named shapes on several
  meshes (a head and its teeth) move together; a VRM expression (``happy``) drives the morph targets it binds, at
  their bind weights; shapes the clip does not move keep the file's default weights;
- in the animation's ``extras.mien.targets``, the rows that made each shape weight (rig target -> ``[shape,
  weight, side]`` rows, :mod:`mien.exchange.file_shapes`), so :func:`target_clip` (used by the ``.glb`` reader)
  gives the rig's target weights back (ARKit names, with the file's unmatched shapes under their own names),
  and, with a head turn, ``extras.mien.head``: the head node and the rest rotations around the turn (``local =
  left @ turn @ right``), so :func:`head_turns` reads mien's yaw, pitch and roll back, not the bone's;
- with head pose channels in the clip, the rotation of the head bone or node (the VRM humanoid ``head``, else a
  node named ``Head``), and with gaze channels, of the eye bones or nodes (``leftEye`` / ``rightEye``, else nodes
  named ``LeftEye``...), each turned in mien's frame (:mod:`mien.rig.pose` signs) about its own origin, the eyes
  within the head.

Buffers: a GLB's binary chunk stays buffer 0 and the animation data is appended to it; a ``.gltf``'s external
or data-URI buffers and external images are copied into that chunk (views re-pointed), so the file stands alone;
buffers without data (``EXT_meshopt_compression`` fallback buffers) are kept as they are. Nothing is re-encoded.

A head whose axes mien turned on reading (a VRM 0.x model faces -z) gets its rotations turned back; a head mien
placed by its landmarks alone (no eyes it could name) keeps the file's axes, which may then differ from mien's.
"""

from __future__ import annotations

import base64
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.file_shapes import SourceRows, rig_shape_weights, shape_weights, source_rows
from mien.exchange.quaternions import matrix_quaternions
from mien.facs.catalogue import POSE_CHANNELS
from mien.facs.clip import Clip
from mien.fileio.glb import MAGIC, pack_glb, parse_json, unpack_glb
from mien.fileio.streams import TargetT, write_bytes
from mien.rig.face_weights import clip_to_rig
from mien.rig.model import Rig
from mien.rig.pose import _rotations

__all__ = [
    "ANIMATION_NAME",
    "FILE_FORMATS",
    "carries_file",
    "head_turns",
    "target_clip",
    "user_file_bytes",
    "write",
]

FILE_FORMATS: tuple[str, ...] = ("gltf", "vrm0", "vrm1")
"""``HeadFileInfo.format`` values of heads read from a glTF file (an OBJ folder has no file to carry)."""

ANIMATION_NAME = "mien"
"""Name of the animation added to the file."""

MAX_EXTRAS_ROWS = 4096
"""Most target -> shape rows :func:`target_clip` trusts in a file's ``extras`` (mien writes one or two per
target: about 100 for a VALID avatar)."""

_FLOAT = 5126
_MIME = {".png": "image/png", ".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".webp": "image/webp", ".ktx2": "image/ktx2"}
_TOKEN = re.compile(r"[A-Z]?[a-z]+|[A-Z]+(?![a-z])|\d+")


def carries_file(rig: object) -> bool:
    """True when ``rig`` was read from a glTF / GLB / VRM file that a writer can carry."""
    info = getattr(rig, "info", None)
    return info is not None and getattr(info, "format", "") in FILE_FORMATS


def write(clip: Clip, target: TargetT, rig: Rig) -> TargetT:
    """Write the file ``rig`` was read from, animated by ``clip``, as GLB to ``target`` (see the module doc).

    ``clip``: face channels (AU intensities, pose degrees) or the rig's target names (weights 0..1) plus pose
    channels. Warns when nothing of the file moves or a pose channel has no bone to turn. Returns ``target``.
    """
    write_bytes(user_file_bytes(clip, rig), target)
    return target


def user_file_bytes(clip: Clip, rig: Rig) -> bytes:
    """GLB bytes of the file ``rig`` was read from with ``clip`` as an animation (see :func:`write`)."""

    if not carries_file(rig):
        raise InvalidValueError("head", rig.name, "a head read from a .glb, .gltf or .vrm file")
    if clip.n_frames == 0:
        raise InvalidValueError("clip", "0 frames", "a clip with at least one frame to animate")
    info = getattr(rig, "info")  # noqa: B009 (carries_file checked it)
    source = Path(info.path)
    document, blob = _standalone(source)
    weights, poses = clip_to_rig(clip, rig)
    shapes = rig_shape_weights(weights, rig)
    appender = _Appender(document, blob)
    n = clip.n_frames
    times = (np.arange(n) / clip.fps).astype(np.float32)
    time_accessor = appender.accessor(times[:, None], "SCALAR", bounds=True)
    samplers: list[dict[str, Any]] = []
    channels: list[dict[str, Any]] = []

    def channel(node: int, path: str, values: np.ndarray, kind: str) -> None:
        output = appender.accessor(values, kind)
        samplers.append({"input": time_accessor, "output": output, "interpolation": "LINEAR"})
        channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})

    node_weights, missing = _node_weights(document, shapes, n)
    moved = [name for name, column in shapes.items() if np.any(column != 0.0)]
    if missing:
        shown = ", ".join(missing[:6]) + (", ..." if len(missing) > 6 else "")
        warnings.warn(f"{source.name}: shapes not found in the file, not animated: {shown}", stacklevel=3)
    if moved and not node_weights:
        warnings.warn(f"{source.name}: none of the clip's shapes is on a mesh of the file", stacklevel=3)
    for node, values in node_weights.items():
        channel(node, "weights", values.reshape(-1, 1), "SCALAR")

    flip = np.diag([-1.0, 1.0, -1.0]) if str(info.axes).startswith("turned") else np.eye(3)
    head_node, eye_nodes = _pose_nodes(document)
    head: dict[str, Any] | None = None
    has_head = any(c in clip.channels for c in POSE_CHANNELS[:3])
    has_gaze = any(c in clip.channels for c in POSE_CHANNELS[3:])

    if has_head:
        if head_node is None:
            warnings.warn(
                f"{source.name}: no head bone or node named head: the head turn is not animated", stacklevel=3
            )
        else:
            turn = flip @ _rotations(poses[:, 0], poses[:, 1], poses[:, 2]) @ flip
            channel(head_node, "rotation", _turned_locals(document, head_node, turn), "VEC4")
            parent, rest = _rest_frames(document, head_node)
            head = {"node": head_node, "left": (parent.T @ flip).tolist(), "right": (flip @ parent @ rest).tolist()}
    if has_gaze:
        if not eye_nodes:
            warnings.warn(f"{source.name}: no eye bones or nodes: the gaze is not animated", stacklevel=3)
        gaze = flip @ _rotations(poses[:, 3], poses[:, 4], np.zeros(n)) @ flip
        for eye in eye_nodes:
            channel(eye, "rotation", _turned_locals(document, eye, gaze), "VEC4")
    if channels:
        rows = {target: [list(row) for row in shape_rows] for target, shape_rows in source_rows(rig).items()}
        extras: dict[str, Any] = {"mien": {"targets": rows, **({"head": head} if head else {})}}
        animation = {"name": ANIMATION_NAME, "samplers": samplers, "channels": channels, "extras": extras}
        document.setdefault("animations", []).append(animation)
    asset = document.setdefault("asset", {"version": "2.0"})
    generator = asset.get("generator")
    asset["generator"] = f"{generator}; animated by mien" if generator else "mien"
    return pack_glb(document, appender.binary())


def target_clip(shapes: Clip, extras: Any) -> Clip | None:
    """The rig's target weights (0..1) of a clip of file ``shapes`` weights (pose channels kept) that
    :func:`user_file_bytes` wrote, from the rows it left in the animation's ``extras``; None without them.

    The shape weights are linear in the target weights (:func:`~mien.exchange.file_shapes.shape_weights`), so
    the targets are their least-squares solution (the smallest one where targets share a shape), over the
    shapes ``shapes`` holds (a file's shapes on other meshes, such as the teeth, are not needed). Targets with
    no shape in ``shapes`` are left out. Rows that are malformed, not finite or more than
    :data:`MAX_EXTRAS_ROWS` are not trusted: the file's own shapes are read as they are.
    """
    table = _mien_extras(extras).get("targets")
    if not isinstance(table, dict) or not table:
        return None
    present_names = set(shapes.channels)
    try:
        rows: SourceRows = {
            str(target): tuple((str(shape), float(weight), str(side)) for shape, weight, side in table_rows)
            for target, table_rows in table.items()
        }
    except (TypeError, ValueError):
        return None
    if sum(len(r) for r in rows.values()) > MAX_EXTRAS_ROWS or not all(
        math.isfinite(weight) for r in rows.values() for _shape, weight, _side in r
    ):
        return None
    rows = {target: r for target, r in rows.items() if any(shape in present_names for shape, _w, _s in r)}
    if not rows:
        return None
    targets = tuple(rows)
    unit = shape_weights(np.eye(len(targets), dtype=np.float32), targets, rows)  # shape -> its column of M
    present = [name for name in shapes.channels if name in unit]
    matrix = np.stack([unit[name] for name in present]).astype(np.float64)  # (shapes, targets)
    used = np.flatnonzero(np.abs(matrix).sum(axis=0) > 0)
    if used.size == 0:
        return None
    values = np.stack([shapes.channel(name) for name in present], axis=1)
    solved = values @ np.linalg.pinv(matrix[:, used]).T
    poses = [name for name in shapes.channels if name in POSE_CHANNELS]
    columns = [np.clip(solved, 0.0, 1.0), *(shapes.channel(name)[:, None] for name in poses)]
    return Clip(np.hstack(columns), shapes.fps, (*(targets[j] for j in used), *poses))


def head_turns(node: int, quaternions: np.ndarray, extras: Any) -> np.ndarray | None:
    """(n, 3, 3) head turns in mien's frame (:mod:`mien.rig.pose`) of node ``node``'s animated (n, 4) local
    rotations (x, y, z, w), when :func:`user_file_bytes` wrote them for the head and left its rest frames in the
    animation's ``extras``; None otherwise."""
    head = _mien_extras(extras).get("head")
    if not isinstance(head, dict) or head.get("node") != node:
        return None
    try:
        left, right = np.asarray(head["left"], np.float64), np.asarray(head["right"], np.float64)
    except (KeyError, TypeError, ValueError):
        return None
    if left.shape != (3, 3) or right.shape != (3, 3) or not (np.isfinite(left).all() and np.isfinite(right).all()):
        return None
    q = np.asarray(quaternions, np.float64)
    if q.ndim != 2 or q.shape[1] != 4:
        return None
    turns: np.ndarray = left.T @ _quaternion_matrix(q) @ right.T  # both are rotations: their transposes undo them
    return turns


def _mien_extras(extras: Any) -> dict[str, Any]:
    """The ``mien`` object of an animation's ``extras`` (empty when there is none, or it is not an object)."""
    found = extras.get("mien") if isinstance(extras, dict) else None
    return found if isinstance(found, dict) else {}


# ---------------------------------------------------------------------------------------------------------------
# One standalone document


def _standalone(source: Path) -> tuple[dict[str, Any], bytearray]:
    """The file's JSON and one binary blob (buffer 0) holding every buffer and external image that has data."""
    if not source.is_file():
        raise InvalidValueError("head file", str(source), "the character file the head was read from (moved?)")
    data = source.read_bytes()
    is_glb = data[:4] == MAGIC
    document, found = unpack_glb(data, str(source)) if is_glb else (parse_json(data, str(source)), None)
    chunk = found or b""
    blob = bytearray()
    buffers = document.get("buffers") or []
    new_buffers: list[dict[str, Any]] = [{}]
    offsets: dict[int, int] = {}
    remap: dict[int, int] = {}
    for k, buffer in enumerate(buffers):
        uri = buffer.get("uri")
        if uri is None and not (k == 0 and is_glb):  # no data: a compression extension's fallback buffer
            remap[k] = len(new_buffers)
            new_buffers.append(buffer)
            continue
        content = chunk[: int(buffer.get("byteLength", len(chunk)))] if uri is None else _uri_bytes(uri, source)
        blob.extend(b"\0" * ((-len(blob)) % 16))
        offsets[k], remap[k] = len(blob), 0
        blob.extend(content)
        if k == 0 or "name" not in new_buffers[0]:
            new_buffers[0].update({key: v for key, v in buffer.items() if key not in ("uri", "byteLength")})
    for view in document.get("bufferViews") or []:
        for holder in (view, (view.get("extensions") or {}).get("EXT_meshopt_compression")):
            if holder is None:
                continue
            k = int(holder["buffer"])
            if k not in remap:
                raise InvalidValueError(f"{source} bufferView", k, f"a buffer index below {len(buffers)}")
            if k in offsets:
                holder["byteOffset"] = int(holder.get("byteOffset", 0)) + offsets[k]
            holder["buffer"] = remap[k]
    document["buffers"] = new_buffers
    views = document.setdefault("bufferViews", [])
    for image in document.get("images") or []:
        uri = image.get("uri")
        if uri is None or uri.startswith("data:"):
            continue
        content = _uri_bytes(uri, source)
        blob.extend(b"\0" * ((-len(blob)) % 16))
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(content)})
        blob.extend(content)
        mime = image.get("mimeType") or _MIME.get(Path(uri).suffix.lower(), "image/png")
        del image["uri"]
        image.update(bufferView=len(views) - 1, mimeType=mime)
    return document, blob


def _uri_bytes(uri: str, source: Path) -> bytes:
    if uri.startswith("data:"):
        try:
            return base64.b64decode(uri.split(",", 1)[1])
        except (IndexError, ValueError):
            raise InvalidValueError(f"{source} data URI", uri[:40], "base64 data") from None
    from urllib.parse import unquote

    file = source.parent / unquote(uri)
    if not file.is_file():
        raise InvalidValueError(f"{source} resource", uri, f"a file beside it ({file} does not exist)")
    return file.read_bytes()


class _Appender:
    """Appends float accessors (in their own 4-byte aligned views of buffer 0) to a document."""

    def __init__(self, document: dict[str, Any], blob: bytearray) -> None:
        self.document, self.blob = document, blob

    def accessor(self, values: np.ndarray, kind: str, bounds: bool = False) -> int:
        data = np.ascontiguousarray(values, np.float32)
        self.blob.extend(b"\0" * ((-len(self.blob)) % 4))
        views = self.document.setdefault("bufferViews", [])
        views.append({"buffer": 0, "byteOffset": len(self.blob), "byteLength": data.nbytes})
        self.blob.extend(data.tobytes())
        accessor: dict[str, Any] = {"bufferView": len(views) - 1, "componentType": _FLOAT, "count": len(data),
                                    "type": kind}  # fmt: skip
        if bounds:
            accessor["min"] = [float(v) for v in data.min(axis=0)]
            accessor["max"] = [float(v) for v in data.max(axis=0)]
        accessors = self.document.setdefault("accessors", [])
        accessors.append(accessor)
        return len(accessors) - 1

    def binary(self) -> bytes:
        self.blob.extend(b"\0" * ((-len(self.blob)) % 4))
        self.document["buffers"][0]["byteLength"] = len(self.blob)
        return bytes(self.blob)


# ---------------------------------------------------------------------------------------------------------------
# Morph weights per node


def _vrm_binds(document: dict[str, Any]) -> dict[str, list[tuple[int, int, float]]]:
    """VRM expression (1.0 preset / custom, 0.x group) -> [(mesh, morph target, weight 0..1)]."""
    extensions = document.get("extensions") or {}
    nodes = document.get("nodes") or []
    out: dict[str, list[tuple[int, int, float]]] = {}
    if "VRMC_vrm" in extensions:
        expressions = extensions["VRMC_vrm"].get("expressions") or {}
        for group in ("preset", "custom"):
            for name, expression in (expressions.get(group) or {}).items():
                binds = []
                for bind in expression.get("morphTargetBinds") or []:
                    mesh = nodes[int(bind["node"])].get("mesh")
                    if mesh is not None:
                        binds.append((int(mesh), int(bind["index"]), float(bind.get("weight", 1.0))))
                out[name] = binds
    elif "VRM" in extensions:
        for group in (extensions["VRM"].get("blendShapeMaster") or {}).get("blendShapeGroups") or []:
            preset = group.get("presetName") or "unknown"
            name = group.get("name", "") if preset == "unknown" else preset
            out[name] = [(int(b["mesh"]), int(b["index"]), float(b.get("weight", 100.0)) / 100.0)
                         for b in group.get("binds") or []]  # fmt: skip
    return out


def _node_weights(
    document: dict[str, Any], shapes: dict[str, np.ndarray], n: int
) -> tuple[dict[int, np.ndarray], list[str]]:
    """Node -> (n, n_morph) weights of the nodes whose mesh has a shape in ``shapes``; names found nowhere."""
    meshes = document.get("meshes") or []
    nodes = document.get("nodes") or []
    counts = {}
    for m, mesh in enumerate(meshes):
        primitives = mesh.get("primitives") or [{}]
        counts[m] = len(primitives[0].get("targets") or [])
    drawers: dict[int, list[int]] = {}
    where: dict[str, list[tuple[int, int]]] = {}  # shape name -> (node, morph)
    for i, node in enumerate(nodes):
        m = node.get("mesh")
        if m is None or not counts.get(m):
            continue
        drawers.setdefault(int(m), []).append(i)
        mesh = meshes[m]
        names = (
            list((mesh.get("extras") or {}).get("targetNames") or []) if isinstance(mesh.get("extras"), dict) else []
        )
        label = mesh.get("name") or node.get("name") or f"mesh{m}"
        for k in range(counts[m]):
            name = str(names[k]) if k < len(names) else f"{label}.target{k}"
            where.setdefault(name, []).append((i, k))
    binds = _vrm_binds(document)
    out: dict[int, np.ndarray] = {}
    touched: set[tuple[int, int]] = set()
    missing = []

    def add(node: int, morph: int, values: np.ndarray) -> None:
        if node not in out:
            mesh = meshes[nodes[node]["mesh"]]
            default = nodes[node].get("weights") or mesh.get("weights") or [0.0] * counts[nodes[node]["mesh"]]
            out[node] = np.tile(np.asarray(default, np.float32), (n, 1))
        if (node, morph) not in touched:
            touched.add((node, morph))
            out[node][:, morph] = 0.0
        out[node][:, morph] += values

    for name, values in shapes.items():
        if name in binds:  # a VRM expression, as the reader built it, wins over a morph of the same name
            for mesh, morph, weight in binds[name]:
                for node in drawers.get(mesh, []):
                    if morph < counts[mesh]:
                        add(node, morph, values * np.float32(weight))
        elif name in where:
            for node, morph in where[name]:
                add(node, morph, values)
        else:
            missing.append(name)
    return out, missing


# ---------------------------------------------------------------------------------------------------------------
# Head and eye rotations


def _tokens(name: str) -> set[str]:
    return {token.lower() for token in _TOKEN.findall(name or "")}


def _pose_nodes(document: dict[str, Any]) -> tuple[int | None, list[int]]:
    """(head node or None, eye nodes) of the file: VRM humanoid bones, else nodes named so (not meshes)."""
    extensions = document.get("extensions") or {}
    bones: dict[str, int] = {}
    if "VRMC_vrm" in extensions:
        human = (extensions["VRMC_vrm"].get("humanoid") or {}).get("humanBones") or {}
        bones = {name: int(bone["node"]) for name, bone in human.items() if "node" in bone}
    elif "VRM" in extensions:
        human_list = (extensions["VRM"].get("humanoid") or {}).get("humanBones") or []
        bones = {bone["bone"]: int(bone["node"]) for bone in human_list if "bone" in bone and "node" in bone}
    nodes = document.get("nodes") or []
    head = bones.get("head")
    if head is None:
        head = next((i for i, node in enumerate(nodes) if "head" in _tokens(node.get("name", ""))
                     and not {"end", "top"} & _tokens(node.get("name", "")) and "mesh" not in node), None)  # fmt: skip
    eyes = [bones[side] for side in ("leftEye", "rightEye") if side in bones]
    if not eyes:
        for side in ("left", "right"):
            found = next((i for i, node in enumerate(nodes) if "mesh" not in node
                          and _eye_side(node.get("name", "")) == side), None)  # fmt: skip
            if found is not None:
                eyes.append(found)
    return head, eyes


_NOT_EYE = frozenset({"end", "lash", "lashes", "brow", "lid", "lids", "gland", "socket", "tear", "highlight", "target"})


def _eye_side(name: str) -> str:
    """``"left"`` / ``"right"`` for an eye bone's name (``LeftEye``, ``Eye_L``, ``eyeball.R``), else ``""``."""
    tokens = _tokens(name)
    if not {"eye", "eyeball"} & tokens or _NOT_EYE & tokens:
        return ""
    if {"left", "l"} & tokens:
        return "left"
    return "right" if {"right", "r"} & tokens else ""


def _local(node: dict[str, Any]) -> np.ndarray:
    """(4, 4) local matrix of a node (column vectors)."""
    if "matrix" in node:
        return np.asarray(node["matrix"], np.float64).reshape(4, 4).T
    m = np.eye(4)
    m[:3, :3] = _quaternion_matrix(node.get("rotation", [0.0, 0.0, 0.0, 1.0])) * np.asarray(
        node.get("scale", [1.0, 1.0, 1.0]), np.float64
    )
    m[:3, 3] = node.get("translation", [0.0, 0.0, 0.0])
    return m


def _quaternion_matrix(q: Any) -> np.ndarray:
    """(..., 3, 3) rotation matrices of (..., 4) quaternions (x, y, z, w), normalised first."""
    q = np.asarray(q, np.float64)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    x, y, z, w = np.moveaxis(q / np.where(norm > 0, norm, 1.0), -1, 0)
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], -2)  # fmt: skip


def _rotation_part(m: np.ndarray) -> np.ndarray:
    """The nearest rotation to a 3x3 linear map (polar decomposition: scale and mirroring removed)."""
    u, _, vt = np.linalg.svd(m)
    r = u @ vt
    if np.linalg.det(r) < 0:
        u[:, -1] *= -1
        r = u @ vt
    return r


def _turned_locals(document: dict[str, Any], index: int, turns: np.ndarray) -> np.ndarray:
    """(n, 4) local rotations of node ``index`` that turn it by (n, 3, 3) world rotations about its origin.

    With ``P`` the parent's rest world rotation and ``L`` the node's rest rotation, the local rotation
    ``P^-1 T P L`` turns the node's world frame by ``T``. A node given by a matrix is rewritten as TRS (a node
    whose rotation is animated may not have a matrix).
    """
    parent, rest = _rest_frames(document, index)
    return matrix_quaternions(parent.T @ turns @ parent @ rest)


def _rest_frames(document: dict[str, Any], index: int) -> tuple[np.ndarray, np.ndarray]:
    """``(P, L)``: node ``index``'s parent's rest world rotation and its own rest rotation, (3, 3) each. A node
    given by a matrix is rewritten as TRS (a node whose rotation is animated may not have a matrix)."""
    nodes = document["nodes"]
    parent_of = {child: i for i, node in enumerate(nodes) for child in node.get("children") or []}
    world = np.eye(4)
    j = parent_of.get(index)
    while j is not None:
        world = _local(nodes[j]) @ world
        j = parent_of.get(j)
    node = nodes[index]
    if "matrix" in node:
        m = np.asarray(node.pop("matrix"), np.float64).reshape(4, 4).T
        rest = _rotation_part(m[:3, :3])
        node["translation"] = [float(v) for v in m[:3, 3]]
        node["rotation"] = [float(v) for v in matrix_quaternions(rest[None])[0]]
        node["scale"] = [float(v) for v in np.diag(rest.T @ m[:3, :3])]
    rest = _quaternion_matrix(node.get("rotation", [0.0, 0.0, 0.0, 1.0]))
    return _rotation_part(world[:3, :3]), rest
