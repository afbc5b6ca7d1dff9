"""Textured, multi-part meshes for offline rendering: what a character file's meshes and materials hold.

A :class:`TexturedMesh` is one shared vertex array (rest positions and one UV per vertex) cut into
:class:`Part` s, each a set of triangles drawn with one :class:`Material` (a glTF 2.0 metallic-roughness base
colour, its alpha mode and sidedness; the rest of PBR is not drawn). It is plain data: build it by hand, or
from a glTF file with :func:`textured_mesh_from_gltf`, which decodes PNG, JPEG and WebP textures with Pillow.

Only numpy is imported here; Pillow (``pip install 'mien[render]'``) when a texture is decoded.
"""

from __future__ import annotations

import io
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Any

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.rig.files.head import FileRig

if TYPE_CHECKING:
    from mien.rig.files.gltf import GltfScene

__all__ = [
    "AlphaMode",
    "Material",
    "Part",
    "TextureDecodeWarning",
    "TexturedMesh",
    "decode_texture",
    "textured_mesh_from_gltf",
    "textured_mesh_from_rig",
]


class AlphaMode(StrEnum):
    """How a material's alpha is used (glTF 2.0 ``material.alphaMode``)."""

    OPAQUE = "OPAQUE"
    """Alpha ignored: the surface is fully opaque."""
    MASK = "MASK"
    """Alpha-tested: fragments with alpha below the cutoff are discarded, the rest are opaque (lashes, cards)."""
    BLEND = "BLEND"
    """Alpha-blended over what is behind it, drawn after every opaque part, back to front (hair cards, brows)."""


class TextureDecodeWarning(UserWarning):
    """A texture image could not be decoded; its part is drawn in its base-colour factor."""


@dataclass(frozen=True, eq=False)
class Material:
    """How a part looks: a base colour (texture times factor), alpha mode and sidedness.

    >>> Material("skin", base_color_factor=(0.8, 0.6, 0.5, 1.0)).alpha_mode
    <AlphaMode.OPAQUE: 'OPAQUE'>
    """

    name: str = "material"
    """The material's name (for reports and warnings)."""
    base_color_texture: np.ndarray | None = None
    """(h, w, 4) uint8 sRGB-encoded RGBA, row 0 at v = 0 (the image's top, as glTF stores it), or None."""
    base_color_factor: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    """Linear RGBA 0..1 multiplied with the texture (the whole colour when there is no texture)."""
    alpha_mode: AlphaMode = AlphaMode.OPAQUE
    """OPAQUE, MASK (alpha-tested at :attr:`alpha_cutoff`) or BLEND."""
    alpha_cutoff: float = 0.5
    """MASK only: the alpha 0..1 below which a fragment is discarded."""
    double_sided: bool = False
    """Draw back faces too (lit with the flipped normal); otherwise back faces are culled."""

    def __post_init__(self) -> None:
        texture = self.base_color_texture
        if texture is not None:
            texture = np.ascontiguousarray(texture)
            if texture.dtype != np.uint8 or texture.ndim != 3 or texture.shape[2] != 4 or min(texture.shape[:2]) < 1:
                raise InvalidValueError("base_color_texture", texture.shape, "(h, w, 4) uint8 sRGB RGBA")
            object.__setattr__(self, "base_color_texture", texture)
        factor = tuple(float(c) for c in self.base_color_factor)
        if len(factor) != 4 or not all(0.0 <= c <= 1.0 for c in factor):
            raise InvalidValueError("base_color_factor", self.base_color_factor, "four linear RGBA values 0..1")
        object.__setattr__(self, "base_color_factor", factor)
        object.__setattr__(self, "alpha_mode", AlphaMode(self.alpha_mode))
        if not 0.0 <= float(self.alpha_cutoff) <= 1.0:
            raise InvalidValueError("alpha_cutoff", self.alpha_cutoff, "an alpha 0..1")


@dataclass(frozen=True, eq=False)
class Part:
    """Triangles of the shared vertex array drawn with one material."""

    name: str
    """The part's name (a glTF mesh name, ``hair``, ...)."""
    triangles: np.ndarray
    """(m, 3) int32 vertex ids into the :class:`TexturedMesh`'s vertices, counter-clockwise seen from the front."""
    material: Material = field(default_factory=Material)
    """How the part is drawn."""

    def __post_init__(self) -> None:
        triangles = np.ascontiguousarray(self.triangles, dtype=np.int32)
        if triangles.ndim != 2 or triangles.shape[1] != 3 or (triangles.size and triangles.min() < 0):
            raise InvalidValueError(f"part {self.name!r} triangles", triangles.shape, "(m, 3) non-negative ids")
        object.__setattr__(self, "triangles", triangles)


@dataclass(frozen=True, eq=False)
class TexturedMesh:
    """Parts sharing one vertex array: rest positions and one UV per vertex."""

    positions: np.ndarray
    """(n, 3) float32 rest positions (the frame and unit the camera uses; metres for mien's cameras)."""
    uvs: np.ndarray
    """(n, 2) float32 texture coordinates, glTF convention (v = 0 at the image's top row)."""
    parts: tuple[Part, ...]
    """The parts, in file order (the renderer orders them for drawing)."""

    def __post_init__(self) -> None:
        positions = np.ascontiguousarray(self.positions, dtype=np.float32)
        if positions.ndim != 2 or positions.shape[1] != 3 or not np.isfinite(positions).all():
            raise InvalidValueError("positions", positions.shape, "(n, 3) finite positions")
        uvs = np.ascontiguousarray(self.uvs, dtype=np.float32)
        if uvs.shape != (len(positions), 2) or not np.isfinite(uvs).all():
            raise InvalidValueError("uvs", uvs.shape, f"({len(positions)}, 2) finite texture coordinates")
        parts = tuple(self.parts)
        if not parts or not any(len(part.triangles) for part in parts):
            raise InvalidValueError("parts", len(parts), "at least one part with triangles")
        for part in parts:
            if part.triangles.size and int(part.triangles.max()) >= len(positions):
                raise InvalidValueError(
                    f"part {part.name!r} triangles", int(part.triangles.max()), f"vertex ids < {len(positions)}"
                )
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "uvs", uvs)
        object.__setattr__(self, "parts", parts)

    @property
    def triangles(self) -> np.ndarray:
        """(m, 3) int32 every part's triangles, in part order."""
        return np.concatenate([part.triangles for part in self.parts])


def decode_texture(data: bytes, mime_type: str = "") -> np.ndarray:
    """(h, w, 4) uint8 sRGB RGBA of an encoded PNG, JPEG or WebP image (Pillow; alpha 255 where it has none).

    Raises ``OSError`` or ``ValueError`` (Pillow's) when the bytes do not decode.
    """
    pil_image = require("PIL.Image", "render")
    with pil_image.open(io.BytesIO(data)) as image:
        image.load()
        return np.ascontiguousarray(np.asarray(image.convert("RGBA"), dtype=np.uint8))


def _decode_or_warn(data: bytes, mime_type: str, where: str) -> np.ndarray | None:
    """:func:`decode_texture`, or None with a :class:`TextureDecodeWarning` naming ``where`` (its parts are then
    drawn in their base-colour factor)."""
    try:
        if not data:
            raise ValueError("the file holds no data for it")
        return decode_texture(data, mime_type)
    except (OSError, ValueError) as exc:
        warnings.warn(
            f"{where} ({mime_type or 'unknown type'}) cannot be decoded ({exc}); its parts are drawn in their "
            "base-colour factor",
            TextureDecodeWarning,
            stacklevel=4,
        )
        return None


def _texture_source(gltf: Any, texture_index: int) -> int | None:
    """The image index a glTF texture samples: its ``EXT_texture_webp`` source first, else ``source``."""
    textures = gltf.textures or []
    if not 0 <= texture_index < len(textures):
        return None
    texture = textures[texture_index]
    webp = (texture.extensions or {}).get("EXT_texture_webp")
    if isinstance(webp, dict) and webp.get("source") is not None:
        return int(webp["source"])
    return None if texture.source is None else int(texture.source)


def _material(scene: GltfScene, index: int | None, decoded: dict[int, np.ndarray | None]) -> Material:
    if index is None or not 0 <= index < len(scene.gltf.materials or []):
        return Material("default")  # glTF's default material: white, opaque, single-sided
    source = scene.gltf.materials[index]
    name = source.name or f"material{index}"
    pbr = source.pbrMetallicRoughness
    factor = tuple(pbr.baseColorFactor) if pbr is not None and pbr.baseColorFactor is not None else (1.0,) * 4
    texture = None
    if pbr is not None and pbr.baseColorTexture is not None:
        image = _texture_source(scene.gltf, int(pbr.baseColorTexture.index))
        if image is not None and image not in decoded:
            data, mime = scene.images.get(image, (b"", ""))
            decoded[image] = _decode_or_warn(data, mime, f"{scene.path}: texture image {image} of material {name!r}")
        texture = None if image is None else decoded[image]
    mode = AlphaMode(source.alphaMode or "OPAQUE")
    cutoff = 0.5 if source.alphaCutoff is None else float(source.alphaCutoff)
    return Material(name, texture, factor, mode, cutoff, bool(source.doubleSided))


def textured_mesh_from_gltf(
    scene: GltfScene, primitives: Sequence[int] | None = None, scale: float = 1.0
) -> TexturedMesh:
    """The primitives of a read glTF file (:func:`mien.rig.files.gltf.read_gltf`) as one :class:`TexturedMesh`.

    ``primitives``: indices into ``scene.primitives`` to keep (all by default); ``scale`` multiplies the
    positions (file units to the camera's unit). Each primitive becomes a :class:`Part` named for its mesh;
    primitives with one material share one :class:`Material` (and one decoded texture). A texture that
    cannot be decoded warns (:class:`TextureDecodeWarning`, naming the file) and leaves its parts in their
    base-colour factor. ``KHR_texture_transform``, ``texCoord`` > 0 and sampler wrap modes are not read
    (TEXCOORD_0 with repeat wrapping).
    """
    chosen = range(len(scene.primitives)) if primitives is None else primitives
    decoded: dict[int, np.ndarray | None] = {}
    materials: dict[int | None, Material] = {}
    positions, uvs, parts = [], [], []
    offset = 0
    for i in chosen:
        primitive = scene.primitives[i]
        if primitive.material not in materials:
            materials[primitive.material] = _material(scene, primitive.material, decoded)
        n = len(primitive.positions)
        positions.append(np.asarray(primitive.positions, np.float64) * scale)
        uvs.append(primitive.uvs if primitive.uvs is not None else np.zeros((n, 2), np.float32))
        parts.append(Part(primitive.mesh_name, primitive.triangles + offset, materials[primitive.material]))
        offset += n
    if not parts:
        raise InvalidValueError("primitives", list(chosen), f"indices of {scene.path}'s primitives")
    return TexturedMesh(np.concatenate(positions).astype(np.float32), np.concatenate(uvs), tuple(parts))


def textured_mesh_from_rig(rig: object) -> tuple[TexturedMesh, np.ndarray] | None:
    """A head file's drawn parts as a :class:`TexturedMesh` over the rig's vertices; None for mien's own heads and
    for a file with no look of its own (no texture, default white: skin, eyes and face paint as on mien's heads).

    Returns ``(mesh, gather)``: ``gather`` (k,) int32 picks, for each of the mesh's (unwelded) vertices, its rig
    vertex, so a deformed rig ``vertices[gather]`` is the mesh at that frame. Textures are decoded once per
    image; one that cannot be decoded warns (:class:`TextureDecodeWarning`) and its parts keep their factor.
    """
    if not isinstance(rig, FileRig) or rig.info is None or not rig.info.materials:
        return None
    white = (1.0, 1.0, 1.0, 1.0)
    if all(not drawn.base_color_image and drawn.base_color_factor == white for drawn in rig.info.materials):
        return None  # the file says nothing of its look (no textures, default white): drawn as mien's own heads
    decoded: dict[int, Material] = {}
    positions, uvs, parts, gathers = [], [], [], []
    offset = 0
    for drawn in rig.info.materials:
        key = id(drawn.base_color_image)
        if key not in decoded:
            texture = None
            if drawn.base_color_image:
                where = f"{rig.info.path}: the texture of {drawn.mesh_name}"
                texture = _decode_or_warn(drawn.base_color_image, drawn.base_color_mime, where)
            decoded[key] = Material(
                drawn.mesh_name, texture, drawn.base_color_factor, AlphaMode(drawn.alpha_mode), drawn.alpha_cutoff,
                drawn.double_sided,
            )  # fmt: skip
        ids = np.asarray(drawn.vertex_ids, np.int32)
        gathers.append(ids)
        positions.append(rig.neutral[ids])
        uvs.append(drawn.uvs if drawn.uvs is not None else np.zeros((len(ids), 2), np.float32))
        parts.append(Part(drawn.mesh_name, np.asarray(drawn.triangles, np.int32) + offset, decoded[key]))
        offset += len(ids)
    mesh = TexturedMesh(np.concatenate(positions), np.concatenate(uvs), tuple(parts))
    return mesh, np.concatenate(gathers).astype(np.int32)
