"""Headless rendering of a textured, multi-part mesh (a character file's head) with moderngl on EGL.

:class:`TexturedRenderer` draws a :class:`~mien.render.materials.TexturedMesh` frame after frame: base-colour
textures sampled as sRGB with mipmaps, opaque and alpha-tested parts first (depth writes on), then
alpha-blended parts (hair cards, lashes, brows) back to front by part centroid with depth writes off, under
the lights of the untextured :class:`~mien.render.offscreen.OffscreenRenderer` (see
:mod:`mien.render.textured_shaders`), with multisampling. Only positions and normals change per frame
(morph targets, skinning): UVs, indices and textures are uploaded once. It needs what the untextured renderer
needs (moderngl and Mesa's EGL; see :mod:`mien.render.offscreen`).

Normals are recomputed each frame with :func:`~mien.render.offscreen.vertex_normals` over *welded*
positions: vertices a file splits at UV seams share one smooth normal, so seams do not show as creases.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from mien.errors import InvalidValueError
from mien.render.camera import Camera
from mien.render.materials import AlphaMode, Material, TexturedMesh
from mien.render.offscreen import (
    DEFAULT_BACKGROUND,
    GLSurface,
    _check_size,
    _require_moderngl,
    vertex_normals,
)
from mien.render.textured_shaders import ALPHA_MODE_IDS, fragment_shader, vertex_shader

__all__ = ["TexturedRenderer"]

_SRGB8_ALPHA8 = 0x8C43
"""OpenGL internal format of an sRGB-encoded RGBA8 texture (sampled as linear)."""


@dataclass(frozen=True, eq=False)
class _Batch:
    """One draw call: a contiguous range of the index buffer with one material."""

    first: int
    """Offset into the index buffer, in indices (3 per triangle)."""
    count: int
    """Number of indices."""
    material: Material
    """The material drawn."""
    vertex_ids: np.ndarray | None
    """Blended parts: (k,) int64 the vertices whose mean orders the part back to front; None otherwise."""


def _weld(positions: np.ndarray, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(first, inverse, welded triangles): one representative per distinct position, and the map back."""
    _, first, inverse = np.unique(positions, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1).astype(np.int32)
    return first.astype(np.int64), inverse, np.ascontiguousarray(inverse[triangles], np.int32)


class TexturedRenderer(GLSurface):
    """Renders a :class:`TexturedMesh`, frame after frame, into (height, width, 3) uint8 sRGB images.

    ``camera`` looks at the mesh in its own frame and unit; ``background`` 8-bit sRGB; ``samples``
    multisample anti-aliasing (0, 2, 4 or 8; capped at what the driver offers); ``weld_normals`` shares one
    normal between vertices at the same rest position (UV seams); ``per_pixel`` evaluates the diffuse light
    per pixel instead of per vertex (slower on a CPU; see :mod:`mien.render.textured_shaders`); ``backend``
    the moderngl standalone backend (``"egl"``; None = the platform default, see :mod:`mien.render.offscreen`).
    Use as a context manager (or call :meth:`close`). Not thread-safe: render from one thread.
    """

    def __init__(
        self,
        mesh: TexturedMesh,
        width: int,
        height: int,
        camera: Camera,
        background: tuple[int, int, int] = DEFAULT_BACKGROUND,
        samples: int = 4,
        weld_normals: bool = True,
        per_pixel: bool = False,
        backend: str | None = "egl",
    ) -> None:
        self.width, self.height = _check_size(width, height)
        if len(background) != 3 or not all(0 <= int(c) <= 255 for c in background):
            raise InvalidValueError("background", background, "three 8-bit sRGB values 0..255")
        if samples not in (0, 2, 4, 8):
            raise InvalidValueError("samples", samples, "0, 2, 4 or 8 multisamples")
        self.mesh = mesh
        self.background = tuple(int(c) for c in background)
        self.camera = camera
        n = len(mesh.positions)
        batches, order = self._plan(mesh)
        triangles = np.concatenate(order) if order else np.zeros((0, 3), np.int32)
        self._batches = batches
        self._triangles = np.ascontiguousarray(triangles, np.int32)
        if weld_normals:
            self._weld_first, self._weld_inverse, self._weld_triangles = _weld(mesh.positions, self._triangles)
            self._welded = np.empty((len(self._weld_first), 3), np.float32)
            self._welded_normals = np.empty_like(self._welded)
        else:
            self._weld_first = self._weld_inverse = None  # type: ignore[assignment]
            self._weld_triangles = self._triangles
        self._normals = np.empty((n, 3), np.float32)
        moderngl = _require_moderngl()
        self._open(self.width, self.height, samples, backend)
        ctx = self._ctx
        with ctx:
            # Two programs: the alpha test's discard (MASK parts only) would cost the others early depth tests.
            self._programs = {
                alpha_test: ctx.program(
                    vertex_shader=vertex_shader(per_pixel), fragment_shader=fragment_shader(alpha_test, per_pixel)
                )
                for alpha_test in (False, True)
            }
            for program in self._programs.values():
                self._light(program)
                program["u_base_color"].value = 0
            self._textures: dict[int, Any] = {}
            white = np.full((1, 1, 4), 255, np.uint8)
            self._white = self._upload(white, moderngl)
            for batch in batches:
                texture = batch.material.base_color_texture
                if texture is not None and id(texture) not in self._textures:
                    self._textures[id(texture)] = self._upload(texture, moderngl)
            self._position_buffer = ctx.buffer(mesh.positions.tobytes())
            self._normal_buffer = ctx.buffer(reserve=n * 12)
            self._uv_buffer = ctx.buffer(mesh.uvs.tobytes())
            index_buffer = ctx.buffer(self._triangles.tobytes())
            self._vaos = {
                alpha_test: ctx.vertex_array(
                    program,
                    [
                        (self._position_buffer, "3f", "in_position"),
                        (self._normal_buffer, "3f", "in_normal"),
                        (self._uv_buffer, "2f", "in_uv"),
                    ],
                    index_buffer=index_buffer,
                    index_element_size=4,
                )
                for alpha_test, program in self._programs.items()
            }
            # The y-flipped projection mirrors the winding: counter-clockwise front faces arrive clockwise.
            ctx.front_face = "cw"
            ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
        self.set_camera(camera)

    @staticmethod
    def _plan(mesh: TexturedMesh) -> tuple[list[_Batch], list[np.ndarray]]:
        """Draw batches (opaque and masked grouped by material, then each blended part) and their triangles."""
        solid: dict[int, tuple[Material, list[np.ndarray]]] = {}
        blended = []
        for part in mesh.parts:
            if not len(part.triangles):
                continue
            if part.material.alpha_mode is AlphaMode.BLEND:
                blended.append(part)
            else:
                solid.setdefault(id(part.material), (part.material, []))[1].append(part.triangles)
        batches, order, first = [], [], 0
        # Opaque before masked, so the cheaper early depth test culls more of the discarding shader's work.
        groups = sorted(solid.values(), key=lambda group: group[0].alpha_mode is AlphaMode.MASK)
        for material, chunks in groups:
            triangles = np.concatenate(chunks)
            batches.append(_Batch(first, triangles.size, material, None))
            order.append(triangles)
            first += triangles.size
        for part in blended:
            ids = np.unique(part.triangles)
            batches.append(_Batch(first, part.triangles.size, part.material, ids))
            order.append(part.triangles)
            first += part.triangles.size
        return batches, order

    def _upload(self, texture: np.ndarray, moderngl: Any) -> Any:
        height, width = texture.shape[:2]
        uploaded = self._ctx.texture((width, height), 4, texture.tobytes(), internal_format=_SRGB8_ALPHA8)
        uploaded.build_mipmaps()
        uploaded.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
        uploaded.repeat_x = uploaded.repeat_y = True
        return uploaded

    def set_camera(self, camera: Camera) -> None:
        """Look through ``camera`` from the next frame on."""
        self.camera = camera
        projection = camera.projection_matrix(self.width / self.height)
        # Flip y so that the framebuffer's bottom row is the image's top row: read-back needs no flip.
        projection[1] *= -1.0
        view = camera.view_matrix()
        self._view = view
        with self._ctx:
            for program in self._programs.values():
                program["u_view_projection"].write((projection @ view).T.copy().tobytes())
                program["u_view"].write(view.T.copy().tobytes())

    def _draw(self, batch: _Batch) -> None:
        material = batch.material
        ctx = self._ctx
        if material.double_sided:
            ctx.disable(ctx.CULL_FACE)
        else:
            ctx.enable(ctx.CULL_FACE)
        texture = material.base_color_texture
        (self._white if texture is None else self._textures[id(texture)]).use(0)
        alpha_test = material.alpha_mode is AlphaMode.MASK
        program = self._programs[alpha_test]
        program["u_base_color_factor"].value = material.base_color_factor
        program["u_alpha_mode"].value = ALPHA_MODE_IDS[material.alpha_mode.value]
        if alpha_test:
            program["u_alpha_cutoff"].value = material.alpha_cutoff
        self._vaos[alpha_test].render(vertices=batch.count, first=batch.first)

    def render(self, vertices: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray:
        """Render the mesh at ``vertices`` ((n, 3), the rest positions when None) to a (height, width, 3) image.

        ``out``, a C-contiguous (height, width, 3) uint8 array, receives the image when given.
        """
        mesh = self.mesh
        if vertices is None:
            vertices = mesh.positions
        vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        if vertices.shape != mesh.positions.shape or not np.isfinite(vertices).all():
            raise InvalidValueError("vertices", vertices.shape, f"{mesh.positions.shape} finite positions")
        if out is None:
            out = np.empty((self.height, self.width, 3), np.uint8)
        elif out.shape != (self.height, self.width, 3) or out.dtype != np.uint8 or not out.flags.c_contiguous:
            raise InvalidValueError("out", out.shape, f"a C-contiguous ({self.height}, {self.width}, 3) uint8 array")
        if self._weld_first is not None:
            np.take(vertices, self._weld_first, axis=0, out=self._welded)
            vertex_normals(self._welded, self._weld_triangles, out=self._welded_normals)
            np.take(self._welded_normals, self._weld_inverse, axis=0, out=self._normals)
        else:
            vertex_normals(vertices, self._triangles, out=self._normals)
        ctx = self._ctx
        with ctx:
            self._position_buffer.write(vertices)
            self._normal_buffer.write(self._normals)
            self._fbo.use()
            ctx.clear(*(c / 255.0 for c in self.background), 1.0)
            ctx.enable(ctx.DEPTH_TEST)
            ctx.disable(ctx.BLEND)
            self._fbo.depth_mask = True
            blended = []
            for batch in self._batches:
                if batch.vertex_ids is None:
                    self._draw(batch)
                else:
                    blended.append(batch)
            if blended:
                # Farthest first: eye-space z grows toward the camera.
                depth = [float(self._view[2, :3] @ vertices[b.vertex_ids].mean(axis=0)) for b in blended]
                ctx.enable(ctx.BLEND)
                self._fbo.depth_mask = False
                for index in np.argsort(depth, kind="stable"):
                    self._draw(blended[index])
                self._fbo.depth_mask = True
                ctx.disable(ctx.BLEND)
            self._read_into(out)
        return out
