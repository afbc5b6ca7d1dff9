"""Headless rendering of a deforming triangle mesh to RGB images with moderngl on EGL.

The renderer runs on the CPU through Mesa's llvmpipe (no GPU, no display). On Debian/Ubuntu it needs the
system packages ``libegl1 libegl-mesa0 libgl1-mesa-dri`` (``apt-get install libegl1 libegl-mesa0
libgl1-mesa-dri``; ``libgbm1`` and ``libglapi-mesa`` come with them) and the Python package ``moderngl``
(``pip install 'mien[render]'``).

Without EGL (macOS, Windows, a Linux box where the packages cannot be installed) pass ``backend=None`` to
use moderngl's platform default standalone context (CGL on macOS, WGL on Windows, GLX under a display or
``xvfb-run`` on Linux); without any OpenGL at all, export the animation (``.glb``) and render it in Blender,
or watch it in mien's browser viewer.

Each frame recomputes smooth per-vertex normals from the deformed mesh (area-weighted face normals, numba
when installed), so wrinkles and creases of an expression catch the light.
"""

from __future__ import annotations

import types
from typing import Any, Self

import numpy as np

from mien.errors import InvalidValueError, MienError
from mien.extras import available, require
from mien.render.camera import Camera
from mien.render.shaders import FRAGMENT_SHADER, LIGHTS, VERTEX_SHADER

__all__ = [
    "DEFAULT_BACKGROUND",
    "DEFAULT_SKIN_RGB",
    "EGL_APT_PACKAGES",
    "EGLUnavailableError",
    "GLSurface",
    "OffscreenRenderer",
    "vertex_normals",
]

EGL_APT_PACKAGES = ("libegl1", "libegl-mesa0", "libgl1-mesa-dri")
"""Debian/Ubuntu packages that give moderngl a headless EGL context on Mesa's llvmpipe (CPU)."""

DEFAULT_BACKGROUND = (200, 200, 200)
"""Background colour, 8-bit sRGB: a light neutral grey."""

DEFAULT_SKIN_RGB = (0.62, 0.40, 0.30)
"""Albedo used when no vertex colours are given: a mid skin tone, linear RGB 0..1."""


class EGLUnavailableError(MienError, RuntimeError):
    """No OpenGL context could be created (EGL libraries or a Mesa driver missing)."""


def _require_moderngl() -> types.ModuleType:
    return require("moderngl", "render")


def _normals_numpy(vertices: np.ndarray, faces: np.ndarray, out: np.ndarray) -> None:
    corners = vertices[faces]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    flat = faces.ravel()
    for axis in range(3):
        out[:, axis] = np.bincount(flat, np.repeat(face_normals[:, axis], 3), minlength=len(vertices))
    lengths = np.linalg.norm(out, axis=1, keepdims=True)
    lonely = lengths[:, 0] == 0.0
    out /= np.where(lengths == 0.0, 1.0, lengths)
    out[lonely] = (0.0, 0.0, 1.0)


_NUMBA_KERNEL: Any = None


def _numba_kernel() -> Any:
    """The numba normals kernel, compiled on first use (None when numba is not installed)."""
    global _NUMBA_KERNEL
    if _NUMBA_KERNEL is None:
        if not available("numba"):
            _NUMBA_KERNEL = False
            return False
        import numba

        @numba.njit(cache=True, fastmath=True, nogil=True)
        def kernel(vertices: np.ndarray, faces: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
            out[:] = 0.0
            for f in range(faces.shape[0]):
                a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
                e1x = vertices[b, 0] - vertices[a, 0]
                e1y = vertices[b, 1] - vertices[a, 1]
                e1z = vertices[b, 2] - vertices[a, 2]
                e2x = vertices[c, 0] - vertices[a, 0]
                e2y = vertices[c, 1] - vertices[a, 1]
                e2z = vertices[c, 2] - vertices[a, 2]
                nx = e1y * e2z - e1z * e2y
                ny = e1z * e2x - e1x * e2z
                nz = e1x * e2y - e1y * e2x
                for v in (a, b, c):
                    out[v, 0] += nx
                    out[v, 1] += ny
                    out[v, 2] += nz
            for v in range(out.shape[0]):
                length = np.sqrt(out[v, 0] ** 2 + out[v, 1] ** 2 + out[v, 2] ** 2)
                if length > 0.0:
                    out[v, 0] /= length
                    out[v, 1] /= length
                    out[v, 2] /= length
                else:
                    out[v, 2] = 1.0

        _NUMBA_KERNEL = kernel
    return _NUMBA_KERNEL


def vertex_normals(vertices: np.ndarray, faces: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(n, 3) float32 smooth unit normals: the area-weighted sum of the normals of the faces at each vertex.

    ``vertices`` (n, 3) float32, ``faces`` (m, 3) int32 counter-clockwise triangles; a vertex used by no
    face gets +z. ``out`` (n, 3) float32 is filled in place when given.

    >>> square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    >>> [round(v, 6) for v in vertex_normals(square, np.array([[0, 1, 2], [0, 2, 3]], np.int32))[0].tolist()]
    [0.0, 0.0, 1.0]
    """
    vertices = np.ascontiguousarray(vertices, dtype=np.float32)
    faces = np.ascontiguousarray(faces, dtype=np.int32)
    if out is None:
        out = np.empty_like(vertices)
    kernel = _numba_kernel()
    if kernel:
        kernel(vertices, faces, out)
    else:
        _normals_numpy(vertices, faces, out)
    return out


def _check_size(width: int, height: int) -> tuple[int, int]:
    for name, value in (("width", width), ("height", height)):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or not 0 < value <= 16384:
            raise InvalidValueError(name, value, "an image size in pixels, 1..16384")
    return int(width), int(height)


class GLSurface:
    """A headless OpenGL context and a (multisampled) framebuffer, read back as (height, width, 3) uint8 images:
    what every mien renderer draws into. Subclasses call :meth:`_open` first and :meth:`_read_into` last."""

    _ctx: Any = None

    def _open(self, width: int, height: int, samples: int, backend: str | None) -> int:
        """Create the context and framebuffers; the multisamples the driver gives (``samples`` at most)."""
        moderngl = _require_moderngl()
        try:
            self._ctx = moderngl.create_context(standalone=True, **({"backend": backend} if backend else {}))
        except Exception as error:
            raise EGLUnavailableError(
                f"could not create a headless OpenGL context ({type(error).__name__}: {error}). On Debian or "
                f"Ubuntu install Mesa's EGL: sudo apt-get install {' '.join(EGL_APT_PACKAGES)}; elsewhere pass "
                "backend=None (platform OpenGL) or see mien.render.offscreen's documentation."
            ) from error
        ctx = self._ctx
        with ctx:
            samples = min(samples, ctx.max_samples)
            size = (width, height)
            self._fbo = ctx.framebuffer(
                color_attachments=[ctx.renderbuffer(size, 4, samples=samples)],
                depth_attachment=ctx.depth_renderbuffer(size, samples=samples),
            )
            self._resolve = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, 4)]) if samples else None
        return int(samples)

    @staticmethod
    def _light(program: Any) -> None:
        """Set the shared lights (:data:`mien.render.shaders.LIGHTS`) on ``program``."""
        for name, (direction, color) in LIGHTS.items():
            unit = np.asarray(direction, np.float32) / np.linalg.norm(direction)
            program[f"u_{name}_direction"].value = tuple(unit.tolist())
            program[f"u_{name}_color"].value = color

    def _read_into(self, out: np.ndarray) -> None:
        """Resolve the multisamples (inside the context) and read the picture into ``out``."""
        source = self._fbo
        if self._resolve is not None:
            self._ctx.copy_framebuffer(self._resolve, self._fbo)
            source = self._resolve
        source.read_into(out, components=3)

    def close(self) -> None:
        """Free the OpenGL context and its buffers (idempotent)."""
        ctx = getattr(self, "_ctx", None)
        if ctx is not None:
            ctx.release()
            self._ctx = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


class OffscreenRenderer(GLSurface):
    """Renders one mesh topology, frame after frame, into (height, width, 3) uint8 sRGB images.

    ``faces`` (m, 3) int32 triangles; ``vertex_colors`` (n, 3) linear RGB albedo in 0..1 (None: a skin
    tone); ``texture`` (th, tw, 4) float premultiplied linear RGB albedo and opacity in 0..1, painted over the
    vertex colours where ``texcoords`` (n, 3) say (u, v in 0..1 with row 0 of ``texture`` at v = 0, and the
    paint's strength at the vertex, 0..1; see :mod:`mien.render.face_paint`); ``background`` 8-bit sRGB;
    ``samples`` multisample anti-aliasing (0 = off, 4 = default; about doubles the cost per frame on
    llvmpipe); ``cull_back_faces`` skips triangles facing away from the camera (a third faster; right for
    closed, consistently wound meshes); ``backend`` the moderngl standalone backend (``"egl"``; None = the
    platform default, see the module doc).
    Buffers are allocated on the first :meth:`render` and rewritten in place afterwards. Use as a context
    manager (or call :meth:`close`) to free the OpenGL context. Not thread-safe: render from one thread.
    """

    def __init__(
        self,
        faces: np.ndarray,
        width: int,
        height: int,
        camera: Camera,
        vertex_colors: np.ndarray | None = None,
        texture: np.ndarray | None = None,
        texcoords: np.ndarray | None = None,
        background: tuple[int, int, int] = DEFAULT_BACKGROUND,
        samples: int = 4,
        cull_back_faces: bool = True,
        backend: str | None = "egl",
    ) -> None:
        self.width, self.height = _check_size(width, height)
        faces = np.ascontiguousarray(faces, dtype=np.int32)
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) == 0 or faces.min() < 0:
            raise InvalidValueError("faces", faces.shape, "(m, 3) non-negative vertex ids, m > 0")
        self.faces = faces
        if vertex_colors is not None:
            vertex_colors = np.ascontiguousarray(vertex_colors, dtype=np.float32)
            if vertex_colors.ndim != 2 or vertex_colors.shape[1] != 3 or not np.isfinite(vertex_colors).all():
                raise InvalidValueError("vertex_colors", vertex_colors.shape, "(n, 3) finite RGB in 0..1")
        self.vertex_colors = vertex_colors
        if (texture is None) != (texcoords is None):
            raise InvalidValueError("texture", None if texture is None else texture.shape, "given with texcoords")
        if texture is not None and texcoords is not None:
            texture = np.ascontiguousarray(texture, dtype=np.float32)
            texcoords = np.ascontiguousarray(texcoords, dtype=np.float32)
            if texture.ndim != 3 or texture.shape[2] != 4 or min(texture.shape[:2]) < 1:
                raise InvalidValueError("texture", texture.shape, "(height, width, 4) premultiplied RGBA")
            if texcoords.ndim != 2 or texcoords.shape[1] != 3 or not np.isfinite(texcoords).all():
                raise InvalidValueError("texcoords", texcoords.shape, "(n, 3) finite u, v, strength")
        self.texcoords = texcoords
        if len(background) != 3 or not all(0 <= int(c) <= 255 for c in background):
            raise InvalidValueError("background", background, "three 8-bit sRGB values 0..255")
        self.background = tuple(int(c) for c in background)
        if samples not in (0, 2, 4, 8):
            raise InvalidValueError("samples", samples, "0, 2, 4 or 8 multisamples")
        self.camera = camera
        self.cull_back_faces = cull_back_faces
        self._n_vertices = 0
        self._normal_sign = 1.0
        self._normals = np.empty((0, 3), np.float32)
        moderngl = _require_moderngl()
        self._open(self.width, self.height, samples, backend)
        with self._ctx:
            self._program = self._ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)
            self._light(self._program)
            self._index_buffer = self._ctx.buffer(faces.tobytes())
            # Without paint a 1x1 transparent texture keeps one shader for both cases.
            paint = texture if texture is not None else np.zeros((1, 1, 4), np.float32)
            self._paint = self._ctx.texture(paint.shape[1::-1], 4, paint.tobytes(), dtype="f4")
            self._paint.repeat_x = self._paint.repeat_y = False
            self._paint.build_mipmaps()
            self._paint.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
            self._paint.use(0)
            self._program["u_paint"].value = 0
            self._ctx.enable(self._ctx.DEPTH_TEST)
        self._vao: Any = None
        self.set_camera(camera)

    def set_camera(self, camera: Camera) -> None:
        """Look through ``camera`` from the next frame on."""
        self.camera = camera
        projection = camera.projection_matrix(self.width / self.height)
        # Flip y so that the framebuffer's bottom row is the image's top row: read-back needs no flip.
        projection[1] *= -1.0
        view = camera.view_matrix()
        with self._ctx:
            self._program["u_view_projection"].write((projection @ view).T.copy().tobytes())
            self._program["u_view"].write(view.T.copy().tobytes())

    def _allocate(self, n_vertices: int) -> None:
        if int(self.faces.max()) >= n_vertices:
            raise InvalidValueError("vertices", (n_vertices, 3), f"more than {int(self.faces.max())} vertices")
        colors = self.vertex_colors
        if colors is None:
            colors = np.broadcast_to(np.asarray(DEFAULT_SKIN_RGB, np.float32), (n_vertices, 3))
        elif len(colors) != n_vertices:
            raise InvalidValueError("vertex_colors", colors.shape, f"({n_vertices}, 3), one per vertex")
        texcoords = self.texcoords
        if texcoords is None:
            texcoords = np.zeros((n_vertices, 3), np.float32)
        elif len(texcoords) != n_vertices:
            raise InvalidValueError("texcoords", texcoords.shape, f"({n_vertices}, 3), one per vertex")
        ctx = self._ctx
        self._n_vertices = n_vertices
        self._normals = np.empty((n_vertices, 3), np.float32)
        self._position_buffer = ctx.buffer(reserve=n_vertices * 12)
        self._normal_buffer = ctx.buffer(reserve=n_vertices * 12)
        self._color_buffer = ctx.buffer(np.ascontiguousarray(colors, np.float32).tobytes())
        self._texcoord_buffer = ctx.buffer(np.ascontiguousarray(texcoords, np.float32).tobytes())
        self._vao = ctx.vertex_array(
            self._program,
            [
                (self._position_buffer, "3f", "in_position"),
                (self._normal_buffer, "3f", "in_normal"),
                (self._color_buffer, "3f", "in_color"),
                (self._texcoord_buffer, "3f", "in_texcoord"),
            ],
            index_buffer=self._index_buffer,
            index_element_size=4,
        )

    def render(self, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Render the mesh at ``vertices`` ((n, 3) metres, rig frame) to a (height, width, 3) uint8 image.

        ``out``, a C-contiguous (height, width, 3) uint8 array, receives the image when given (no
        allocation); otherwise a new array is returned.
        """
        vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.isfinite(vertices).all():
            raise InvalidValueError("vertices", vertices.shape, "(n, 3) finite positions in metres")
        if out is None:
            out = np.empty((self.height, self.width, 3), np.uint8)
        elif out.shape != (self.height, self.width, 3) or out.dtype != np.uint8 or not out.flags.c_contiguous:
            raise InvalidValueError("out", out.shape, f"a C-contiguous ({self.height}, {self.width}, 3) uint8 array")
        normals = vertex_normals(vertices, self.faces, out=self._normals if len(vertices) == self._n_vertices else None)
        with self._ctx:
            if len(vertices) != self._n_vertices:
                self._allocate(len(vertices))
                self._normals[:] = normals
                # Outward normals whatever the winding: they must point away from the mesh's centre overall.
                outward = float(np.einsum("ij,ij->", normals, vertices - vertices.mean(axis=0)))
                self._normal_sign = 1.0 if outward >= 0.0 else -1.0
                self._program["u_normal_sign"].value = self._normal_sign
                if self.cull_back_faces:
                    self._ctx.enable(self._ctx.CULL_FACE)
                    # The y-flipped projection mirrors the winding: outward counter-clockwise faces turn clockwise.
                    self._ctx.front_face = "cw" if self._normal_sign > 0 else "ccw"
            self._position_buffer.write(vertices)
            self._normal_buffer.write(self._normals)
            ctx = self._ctx
            self._fbo.use()
            self._paint.use(0)
            ctx.clear(*(c / 255.0 for c in self.background), 1.0)
            self._vao.render()
            self._read_into(out)
        return out
