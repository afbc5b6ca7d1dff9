"""Benchmark: textured offline rendering of a VALID avatar's head at 512 x 512 against a bare moderngl draw.

mien: :class:`mien.render.textured.TexturedRenderer` (welded normals recomputed per frame, sRGB mipmapped
textures, the three-light shader, opaque / masked / blended passes, 4x multisampling, read-back). Named
baseline, measured in the same run: a *bare draw* of the same meshes and textures with the same GL library
(moderngl on the same EGL / llvmpipe), a minimal shader (texture times one Lambert light), the same
multisampling and read-back, positions and precomputed normals uploaded each frame, one draw call per material,
no mien code. Both get the same per-frame positions (the head's first morph targets swinging), so the ratio is
mien's overhead per frame. Frames are interleaved (mien, bare, mien, bare, ...); it prints, in wall-clock and
in process CPU time (llvmpipe's threads included: steadier on a shared machine), the median ms per frame of
each, the ratio of the medians (target: at most 1.2x) and the median and quartiles of the paired frame ratios.

With ``--ict`` (default on when ICT-FaceKit is found) it also prints the untextured renderer
(:func:`mien.render.clip_render.make_renderer` on ICT-FaceKit) against a bare draw of the same mesh.

Run: ``.venv/bin/python bench/render_textured.py [--avatar PATH] [--frames 6] [--repeats 5] [--no-ict]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from mien.render.camera import Camera
from mien.render.materials import TexturedMesh, textured_mesh_from_gltf
from mien.render.offscreen import vertex_normals
from mien.render.textured import TexturedRenderer
from mien.rig.files.gltf import read_gltf

SIZE = 512
SAMPLES = 4
SHARED = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
AVATAR = SHARED / "avatars" / "valid" / "White_F_1_Casual.glb"
HEAD_CAMERA = Camera(distance_m=0.7, fov_deg=22.0, target=(0.0, 1.58, 0.05))

BARE_VERTEX = """
#version 330
uniform mat4 u_mvp;
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_normal;
out vec2 v_uv;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_normal = in_normal; v_uv = in_uv; }
"""
BARE_TEXTURED_FRAGMENT = """
#version 330
uniform sampler2D u_texture;
in vec3 v_normal;
in vec2 v_uv;
out vec4 f_color;
void main() { f_color = texture(u_texture, v_uv) * max(dot(normalize(v_normal), vec3(0.0, 0.0, 1.0)), 0.2); }
"""
BARE_FLAT_FRAGMENT = """
#version 330
in vec3 v_normal;
in vec2 v_uv;
out vec4 f_color;
void main() { f_color = vec4(vec3(0.8, 0.6, 0.5) * max(dot(normalize(v_normal), vec3(0.0, 0.0, 1.0)), 0.2), 1.0); }
"""


class BareDraw:
    """The baseline: moderngl straight, no mien code (textures as sRGB with mipmaps, like mien's)."""

    def __init__(self, positions: np.ndarray, normals: np.ndarray, uvs: np.ndarray,
                 groups: list[tuple[np.ndarray, np.ndarray | None]], camera: Camera) -> None:  # fmt: skip
        import moderngl

        self.ctx = ctx = moderngl.create_context(standalone=True, backend="egl")
        with ctx:  # current while building (mien's renderer makes its own context current)
            textured = any(texture is not None for _, texture in groups)
            self.program = ctx.program(
                vertex_shader=BARE_VERTEX, fragment_shader=BARE_TEXTURED_FRAGMENT if textured else BARE_FLAT_FRAGMENT
            )
            projection = camera.projection_matrix(1.0)
            projection[1] *= -1.0
            self.program["u_mvp"].write((projection @ camera.view_matrix()).T.copy().tobytes())
            size = (SIZE, SIZE)
            self.fbo = ctx.framebuffer(
                color_attachments=[ctx.renderbuffer(size, 4, samples=SAMPLES)],
                depth_attachment=ctx.depth_renderbuffer(size, samples=SAMPLES),
            )
            self.resolve = ctx.framebuffer(color_attachments=[ctx.renderbuffer(size, 4)])
            self.positions = ctx.buffer(positions.astype(np.float32).tobytes())
            self.normals_buffer = ctx.buffer(normals.astype(np.float32).tobytes())
            self.normals = normals.astype(np.float32)
            uv_buffer = ctx.buffer(uvs.astype(np.float32).tobytes())
            self.draws = []
            for triangles, texture in groups:
                attributes = [(self.positions, "3f", "in_position"), (self.normals_buffer, "3f", "in_normal")]
                if textured:
                    attributes.append((uv_buffer, "2f", "in_uv"))
                vao = ctx.vertex_array(self.program, attributes, index_buffer=ctx.buffer(triangles.astype(np.int32)),
                                       index_element_size=4)  # fmt: skip
                gl_texture = None
                if texture is not None:
                    gl_texture = ctx.texture(texture.shape[1::-1], 4, texture.tobytes(), internal_format=0x8C43)
                    gl_texture.build_mipmaps()
                    gl_texture.filter = (moderngl.LINEAR_MIPMAP_LINEAR, moderngl.LINEAR)
                self.draws.append((vao, gl_texture))
            ctx.enable(ctx.DEPTH_TEST)
        self.out = np.empty((SIZE, SIZE, 3), np.uint8)

    def render(self, vertices: np.ndarray) -> np.ndarray:
        with self.ctx:  # make this context current (mien's renderer holds another one)
            self.positions.write(vertices)
            self.normals_buffer.write(self.normals)
            self.fbo.use()
            self.ctx.clear(0.78, 0.78, 0.78, 1.0)
            for vao, texture in self.draws:
                if texture is not None:
                    texture.use(0)
                vao.render()
            self.ctx.copy_framebuffer(self.resolve, self.fbo)
            self.resolve.read_into(self.out, components=3)
        return self.out


def compare(label: str, mien: Callable[[np.ndarray], Any], bare: Callable[[np.ndarray], Any],
            frames: list[np.ndarray], repeats: int) -> None:  # fmt: skip
    """Interleaved frame by frame (mien, bare, mien, bare, ...) so that load from other processes hits both."""
    mien(frames[0]), bare(frames[0])  # warm up: shader compile, first allocations
    wall: dict[str, list[float]] = {"mien": [], "bare": []}
    cpu: dict[str, list[float]] = {"mien": [], "bare": []}
    for _ in range(repeats):
        for vertices in frames:
            for name, render in (("mien", mien), ("bare", bare)):
                start_wall, start_cpu = time.perf_counter(), time.process_time()
                render(vertices)
                wall[name].append((time.perf_counter() - start_wall) * 1000.0)
                cpu[name].append((time.process_time() - start_cpu) * 1000.0)
    print(label)
    for what, samples in (("wall", wall), ("CPU (all threads of this process)", cpu)):
        m, b = statistics.median(samples["mien"]), statistics.median(samples["bare"])
        ratios = [x / y for x, y in zip(samples["mien"], samples["bare"], strict=True)]
        q = statistics.quantiles(ratios, n=4)
        print(f"  {what}: mien {m:.1f} ms/frame, bare draw {b:.1f} ms/frame (medians of {len(ratios)} frames)")
        print(f"    ratio mien / bare: {m / b:.2f}x; paired frame ratios median {statistics.median(ratios):.2f}, "
              f"quartiles {q[0]:.2f}..{q[2]:.2f}")  # fmt: skip


def morph_frames(scene: Any, mesh: TexturedMesh, n_frames: int) -> list[np.ndarray]:
    """Positions per frame: the first head primitive's first four morph targets swinging 0..1."""
    head = max(range(len(scene.primitives)), key=lambda i: len(scene.primitives[i].targets))
    start = sum(len(scene.primitives[i].positions) for i in range(head))
    deltas = list(scene.primitives[head].targets.values())[:4]
    frames = []
    for k in range(n_frames):
        vertices = mesh.positions.copy()
        for j, delta in enumerate(deltas):
            weight = 0.5 + 0.5 * np.sin(2 * np.pi * (k / n_frames + j / 4))
            vertices[start : start + len(delta)] += weight * delta
        frames.append(vertices)
    return frames


def bench_textured(avatar: Path, n_frames: int, repeats: int) -> None:
    start = time.perf_counter()
    scene = read_gltf(avatar)
    mesh = textured_mesh_from_gltf(scene)
    load_s = time.perf_counter() - start
    frames = morph_frames(scene, mesh, n_frames)
    groups: dict[int, tuple[list[np.ndarray], np.ndarray | None]] = {}
    for part in mesh.parts:
        groups.setdefault(id(part.material), ([], part.material.base_color_texture))[0].append(part.triangles)
    white = np.full((1, 1, 4), 255, np.uint8)
    bare_groups = [(np.concatenate(t), white if tex is None else tex) for t, tex in groups.values()]
    normals = vertex_normals(mesh.positions, mesh.triangles)
    print(f"{avatar.name}: {len(mesh.positions)} vertices, {len(mesh.triangles)} triangles, {len(mesh.parts)} parts, "
          f"{len(groups)} materials; read + decode {load_s:.2f} s")  # fmt: skip
    with TexturedRenderer(mesh, SIZE, SIZE, HEAD_CAMERA, samples=SAMPLES) as renderer:
        bare = BareDraw(mesh.positions, normals, mesh.uvs, bare_groups, HEAD_CAMERA)
        try:
            out = np.empty((SIZE, SIZE, 3), np.uint8)
            compare(f"textured head, {SIZE}x{SIZE}, {SAMPLES}x MSAA, {n_frames} frames per repeat",
                    lambda v: renderer.render(v, out=out), bare.render, frames, repeats)  # fmt: skip
        finally:
            bare.ctx.release()


def bench_ict(n_frames: int, repeats: int) -> None:
    from mien.errors import MissingAssetError
    from mien.render.camera import CAMERA_PRESETS
    from mien.render.clip_render import make_renderer, visible_faces
    from mien.rig.deform import Deformer
    from mien.rig.ict_facekit import load_ict_facekit

    folder = os.environ.get("MIEN_ICT_FACEKIT") or SHARED / "assets" / "ict-facekit"
    try:
        rig = load_ict_facekit(folder)
    except MissingAssetError as error:
        print(f"ICT-FaceKit not found ({error}); untextured comparison skipped")
        return
    camera = CAMERA_PRESETS["frontal-1m"]
    weights = np.zeros((n_frames, len(rig.targets)), np.float32)
    weights[:, : min(4, len(rig.targets))] = np.linspace(0.0, 1.0, n_frames)[:, None]
    deformer = Deformer(rig)
    frames = [deformer.deform(w).copy() for w in weights]
    faces = visible_faces(rig)
    normals = vertex_normals(frames[0], faces)
    renderer = make_renderer(rig, camera, size=(SIZE, SIZE), samples=SAMPLES)
    bare = BareDraw(frames[0], normals, np.zeros((len(frames[0]), 2)), [(faces, None)], camera)
    try:
        out = np.empty((SIZE, SIZE, 3), np.uint8)
        compare(f"untextured ICT-FaceKit (mien OffscreenRenderer), {SIZE}x{SIZE}, {SAMPLES}x MSAA",
                lambda v: renderer.render(v, out=out), bare.render, frames, repeats)  # fmt: skip
    finally:
        renderer.close()
        bare.ctx.release()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--avatar", type=Path, default=AVATAR)
    parser.add_argument("--frames", type=int, default=6)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-ict", action="store_true", help="skip the untextured ICT-FaceKit comparison")
    args = parser.parse_args()
    if not args.avatar.is_file():
        print(f"VALID avatar not found at {args.avatar}; set MIEN_SHARED or pass --avatar")
        return
    bench_textured(args.avatar, args.frames, args.repeats)
    if not args.no_ict:
        bench_ict(args.frames, args.repeats)


if __name__ == "__main__":
    main()
