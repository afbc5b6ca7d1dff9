"""VRM 1.0 (``.vrm``): a head with its expressions, for VRM apps (three-vrm, UniVRM, VSeeFace...).

A VRM 1.0 file is a GLB with the ``VRMC_vrm`` extension (VRM Consortium, VRM 1.0 specification). What mien writes:

- the head as :mod:`mien.exchange.glb` writes it (mesh, appearance, every rig target as a named morph target,
  the clip as an animation of its morph weights and head rotation), facing +z as VRM 1.0 wants;
- ``humanoid``: the bones VRM 1.0 requires (hips, spine, the arms' upper, lower and hand bones, the legs' upper,
  lower and foot bones) and ``neck`` and ``head``, as plain nodes of a T-posed body below the head (a head alone
  has no body; the bones let VRM apps load it). The mesh hangs from ``head``, so turning it turns the face;
- ``expressions``: the 18 presets (happy, angry, sad, relaxed, surprised, the visemes aa ih ou ee oh, blink,
  blinkLeft/Right, lookUp/Down/Left/Right, neutral) as morph-target binds of mien's own faces on the head's ARKit
  targets (:data:`mien.rig.vrm_presets.PRESETS`: happy = the joy prototype's ARKit weights...), and one custom
  expression per ARKit target the head has, named after it (the "perfect sync" apps drive);
- ``meta``: the name, authors and licence fields, with VRM's own licence (``https://vrm.dev/licenses/1.0/``) and
  restrictive defaults (only the author may use the avatar as an avatar, personal non-profit use, no
  redistribution); ``meta=`` overrides any field. A head from a third party names its source and licence in
  ``copyrightInformation`` / ``otherLicenseUrl`` (ICT-FaceKit: MIT).

A head read from the user's own VRM 1.0 file is written as that file with the animation added
(:mod:`mien.exchange.glb_user`): it already is a VRM. Any other head file (plain glTF, VRM 0.x) is written from
its rig, without its textures and skin (a warning says so).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.exchange.glb import document_of, pack_glb
from mien.exchange.glb import read as read_glb
from mien.exchange.glb_user import carries_file
from mien.exchange.glb_user import write as write_user_file
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.clip import Clip
from mien.facs.prototypes import prototype_vector
from mien.fileio.streams import Source, TargetT, write_bytes
from mien.rig.animate import face_to_rig
from mien.rig.face_weights import clip_to_rig
from mien.rig.heads import open_head
from mien.rig.model import Rig
from mien.rig.vrm_presets import PRESETS
from mien.version import __version__

__all__ = [
    "EXPRESSION_PRESETS",
    "SUFFIXES",
    "VRM_META_DEFAULTS",
    "expression_weights",
    "read",
    "vrm_document",
    "write",
]

SUFFIXES: tuple[str, ...] = (".vrm",)
"""File suffixes of this format."""

VRM_META_DEFAULTS: dict[str, Any] = {
    "authors": ["mien"],
    "licenseUrl": "https://vrm.dev/licenses/1.0/",
    "avatarPermission": "onlyAuthor",
    "allowExcessivelyViolentUsage": False,
    "allowExcessivelySexualUsage": False,
    "commercialUsage": "personalNonProfit",
    "allowPoliticalOrReligiousUsage": False,
    "allowAntisocialOrHateUsage": False,
    "creditNotation": "required",
    "allowRedistribution": False,
    "modification": "prohibited",
}
"""``VRMC_vrm.meta`` fields written unless ``meta=`` says otherwise (VRM 1.0's most restrictive choices)."""

HEAD_LICENCES: dict[str, tuple[str, str]] = {
    "ict-facekit": (
        "Head mesh and expression shapes: ICT-FaceKit, USC Institute for Creative Technologies (MIT licence)",
        "https://github.com/ICT-VGL/ICT-FaceKit/blob/master/LICENSE",
    ),
}
"""Rig name -> (copyright line, licence URL) of third-party heads mien ships loaders for."""

# Humanoid bones below the head: name -> (parent, position in metres relative to the neck pivot, mien frame).
# A T-pose of an adult about 1.7 m tall with the neck pivot at 1.5 m; only the hierarchy matters to VRM apps.
_BODY: dict[str, tuple[str | None, tuple[float, float, float]]] = {
    "hips": (None, (0.0, -0.55, 0.0)),
    "spine": ("hips", (0.0, -0.40, 0.0)),
    "neck": ("spine", (0.0, -0.06, 0.0)),
    "leftUpperArm": ("spine", (0.18, -0.12, 0.0)),
    "leftLowerArm": ("leftUpperArm", (0.46, -0.12, 0.0)),
    "leftHand": ("leftLowerArm", (0.72, -0.12, 0.0)),
    "rightUpperArm": ("spine", (-0.18, -0.12, 0.0)),
    "rightLowerArm": ("rightUpperArm", (-0.46, -0.12, 0.0)),
    "rightHand": ("rightLowerArm", (-0.72, -0.12, 0.0)),
    "leftUpperLeg": ("hips", (0.09, -0.62, 0.0)),
    "leftLowerLeg": ("leftUpperLeg", (0.09, -1.05, 0.0)),
    "leftFoot": ("leftLowerLeg", (0.09, -1.45, 0.0)),
    "rightUpperLeg": ("hips", (-0.09, -0.62, 0.0)),
    "rightLowerLeg": ("rightUpperLeg", (-0.09, -1.05, 0.0)),
    "rightFoot": ("rightLowerLeg", (-0.09, -1.45, 0.0)),
}

BIND_THRESHOLD = 0.01
"""Targets weighted less than this in an expression are left out of its binds."""


EXPRESSION_PRESETS: tuple[str, ...] = tuple(PRESETS)
"""The VRM 1.0 preset expressions mien writes, in the table's order (:data:`mien.rig.vrm_presets.PRESETS`)."""


def expression_weights(rig: Rig) -> dict[str, np.ndarray]:
    """Preset -> (n_targets,) float32 weights 0..1 of ``rig``'s targets that make it
    (:data:`mien.rig.vrm_presets.PRESETS`)."""

    out = {}
    for name, preset in PRESETS.items():
        weights = np.zeros(len(rig.targets), np.float32)
        if preset.emotion:
            face, _ = face_to_rig(rig, prototype_vector(preset.emotion)[None] * preset.intensity)
            weights += np.asarray(face[0], np.float32)
        for target, weight in preset.arkit:
            if target in rig.target_names:
                weights[rig.target_index(target)] += weight
        out[name] = np.clip(weights, 0.0, 1.0)
    return out


def _binds(node: int, weights: np.ndarray) -> list[dict[str, Any]]:
    return [{"node": node, "index": int(i), "weight": round(float(weights[i]), 4)}
            for i in np.flatnonzero(weights >= BIND_THRESHOLD)]  # fmt: skip


def _expression(binds: list[dict[str, Any]]) -> dict[str, Any]:
    return {"morphTargetBinds": binds, "isBinary": False, "overrideBlink": "none", "overrideLookAt": "none",
            "overrideMouth": "none"}  # fmt: skip


def vrm_document(
    rig: Rig, weights: np.ndarray | None, poses: np.ndarray | None, fps: float, meta: Mapping[str, Any] | None = None
) -> tuple[dict[str, Any], bytes]:
    """The VRM 1.0 glTF JSON and binary chunk of ``rig`` (animated by ``weights`` / ``poses`` when given)."""

    gltf, binary = document_of(rig, weights, poses, fps)
    nodes = gltf["nodes"]  # 0: head (at the neck pivot, a root), 1: face (the mesh)
    pivot = np.asarray(rig.neck_pivot, np.float64)
    index = {"head": 0}
    world = {"head": pivot}
    for name, (parent, offset) in _BODY.items():
        index[name] = len(nodes)
        world[name] = pivot + np.asarray(offset)
        node: dict[str, Any] = {"name": name}
        if parent is None:
            node["translation"] = [float(v) for v in world[name]]
        else:
            node["translation"] = [float(v) for v in world[name] - world[parent]]
            nodes[index[parent]].setdefault("children", []).append(index[name])
        nodes.append(node)
    nodes[0]["translation"] = [float(v) for v in pivot - world["neck"]]
    nodes[index["neck"]].setdefault("children", []).append(0)
    gltf["scenes"][0]["nodes"] = [index["hips"]]

    expressions = expression_weights(rig)
    preset = {name: _expression(_binds(1, w)) for name, w in expressions.items()}
    custom = {
        name: _expression(_binds(1, np.eye(len(rig.targets), dtype=np.float32)[rig.target_index(name)]))
        for name in rig.target_names
        if name in ARKIT_NAMES
    }
    copyright_line, licence_url = HEAD_LICENCES.get(rig.name, (f"Head {rig.name!r} written by mien", ""))
    fields: dict[str, Any] = {"name": rig.name, "version": f"mien {__version__}", **VRM_META_DEFAULTS,
                              "copyrightInformation": copyright_line}  # fmt: skip
    if licence_url:
        fields["otherLicenseUrl"] = licence_url
    fields.update(meta or {})
    if not fields.get("authors") or not fields.get("name"):
        raise InvalidValueError("VRM meta", {k: fields.get(k) for k in ("name", "authors")}, "a name and an author")
    gltf["extensionsUsed"] = sorted({*gltf.get("extensionsUsed", []), "VRMC_vrm"})
    gltf["extensions"] = {
        "VRMC_vrm": {
            "specVersion": "1.0",
            "meta": fields,
            "humanoid": {"humanBones": {name: {"node": i} for name, i in index.items()}},
            "expressions": {"preset": preset, "custom": custom},
        }
    }
    return gltf, binary


def write(clip: Clip, target: TargetT, rig: Rig | None = None, meta: Mapping[str, Any] | None = None) -> TargetT:
    """Write ``rig`` (default: :func:`mien.rig.heads.open_head`) with its VRM 1.0 expressions and ``clip`` as an
    animation to ``target`` (see the module doc); ``meta`` overrides ``VRMC_vrm.meta`` fields. Returns ``target``.
    """

    if rig is None:
        rig = open_head()
    if clip.n_frames == 0:
        raise InvalidValueError("clip", "0 frames", "a clip with at least one frame to animate")
    if carries_file(rig):
        fmt = getattr(rig, "info").format  # noqa: B009 (carries_file checked it)
        if fmt == "vrm1":
            return write_user_file(clip, target, rig)
        warnings.warn(
            f"head {rig.name!r} comes from a {'VRM 0.x' if fmt == 'vrm0' else 'glTF'} file: the VRM 1.0 file is "
            "written from its meshes and shapes, without its textures and skin (write .glb to keep them)",
            stacklevel=2,
        )
    weights, poses = clip_to_rig(clip, rig)
    write_bytes(pack_glb(*vrm_document(rig, weights, poses, clip.fps, meta)), target)
    return target


def read(source: Source) -> Clip:
    """The first animation of a ``.vrm`` (a GLB) as a weight clip, as :func:`mien.exchange.glb.read` reads it.

    The avatar itself (meshes, expressions) is read as a head: ``--head avatar.vrm``
    (:func:`mien.heads.load_head`).
    """

    return read_glb(source)
