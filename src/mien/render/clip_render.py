"""Render a rig driven by morph-target weights (and optional head/gaze poses) to MP4, PNG frames or an image.

Per frame: blend the targets (:class:`mien.rig.deform.Deformer`), rotate head and eyes
(:func:`mien.rig.pose.apply_pose`, when poses are given), recompute normals and rasterise
(:class:`~mien.render.offscreen.OffscreenRenderer`). Frames are produced in this thread while a writer
thread feeds ffmpeg (its own process) or Pillow, so rendering and encoding overlap.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from pathlib import Path
from typing import Protocol

import numpy as np

from mien.errors import InvalidValueError
from mien.progress import progress as progress_bar
from mien.render.appearance import rig_vertex_colors, visible_faces
from mien.render.camera import Camera
from mien.render.face_paint import face_paint
from mien.render.materials import textured_mesh_from_rig
from mien.render.offscreen import DEFAULT_BACKGROUND, OffscreenRenderer
from mien.render.textured import TexturedRenderer
from mien.render.video import write_mp4, write_png
from mien.rig.deform import Deformer
from mien.rig.model import Rig
from mien.rig.pose import apply_pose
from mien.signals import termination_as_interrupt

__all__ = [
    "POSE_COLUMNS",
    "FrameRenderer",
    "RigTexturedRenderer",
    "iter_frames",
    "make_renderer",
    "render_clip",
    "render_still",
]

POSE_COLUMNS = ("head_yaw_deg", "head_pitch_deg", "head_roll_deg", "gaze_yaw_deg", "gaze_pitch_deg")
"""Columns of a ``poses`` array, degrees (signs as in the face frame: yaw > 0 to the character's left)."""


class FrameRenderer(Protocol):
    """Draws a rig's deformed vertices ((n_vertices, 3) metres) into (height, width, 3) uint8 images."""

    def render(self, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray: ...

    def close(self) -> None: ...

    def __enter__(self) -> FrameRenderer: ...

    def __exit__(self, *exc_info: object) -> None: ...


class RigTexturedRenderer:
    """A head file's textured parts drawn from the rig's deformed vertices (:class:`TexturedRenderer` inside)."""

    def __init__(self, textured: TexturedRenderer, gather: np.ndarray) -> None:
        self.textured = textured
        self.gather = gather
        self._positions = np.empty((len(gather), 3), np.float32)

    def render(self, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        np.take(np.asarray(vertices, np.float32), self.gather, axis=0, out=self._positions)
        return self.textured.render(self._positions, out)

    def close(self) -> None:
        self.textured.close()

    def __enter__(self) -> RigTexturedRenderer:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()


def _pose_function() -> Callable[..., np.ndarray]:
    return apply_pose


def _check_size(size: tuple[int, int]) -> tuple[int, int]:
    if len(size) != 2:
        raise InvalidValueError("size", size, "(width, height) in pixels")
    return int(size[0]), int(size[1])


def _check_weights(rig: Rig, weights: np.ndarray | None, n_frames: int | None) -> np.ndarray:
    n_targets = len(rig.targets)
    if weights is None:
        return np.zeros((n_frames or 1, n_targets), np.float32)
    w = np.asarray(weights, dtype=np.float32)
    if w.ndim == 1:
        w = w[None]
    if w.ndim != 2 or w.shape[1] != n_targets or len(w) == 0:
        raise InvalidValueError("weights", w.shape, f"(n_frames, {n_targets}) weights, one column per target")
    if not np.isfinite(w).all():
        raise InvalidValueError("weights", "non-finite values", "finite weights")
    return w


def _check_poses(poses: np.ndarray | None, n_frames: int) -> np.ndarray | None:
    if poses is None:
        return None
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim == 1:
        p = p[None]
    if p.shape != (n_frames, len(POSE_COLUMNS)) or not np.isfinite(p).all():
        raise InvalidValueError("poses", p.shape, f"({n_frames}, 5) finite degrees: {', '.join(POSE_COLUMNS)}")
    return p


def iter_frames(
    rig: Rig,
    weights: np.ndarray,
    renderer: FrameRenderer,
    poses: np.ndarray | None = None,
) -> Iterator[np.ndarray]:
    """Yield one new (height, width, 3) uint8 image per row of ``weights`` ((n_frames, n_targets), 0..1).

    ``renderer`` must draw ``rig``'s faces; ``poses`` (n_frames, 5) degrees, see :data:`POSE_COLUMNS`.
    """
    w = _check_weights(rig, weights, None)
    p = _check_poses(poses, len(w))
    apply_pose = _pose_function() if p is not None else None
    deformer = Deformer(rig)
    vertices = np.empty((rig.n_vertices, 3), np.float32)
    for index in range(len(w)):
        deformed = deformer.deform(w[index], out=vertices)
        if apply_pose is not None and p is not None:
            deformed = apply_pose(rig, deformed, p[index, :3], p[index, 3:])
        yield renderer.render(deformed)


def make_renderer(
    rig: Rig,
    camera: Camera,
    size: tuple[int, int] = (512, 512),
    background: tuple[int, int, int] = DEFAULT_BACKGROUND,
    samples: int = 4,
) -> FrameRenderer:
    """A renderer for ``rig`` at ``size`` (w, h) pixels.

    A head read from a user's file is drawn as the file draws it: its textured parts, alpha modes and sides
    (:class:`RigTexturedRenderer`). mien's own heads get an :class:`OffscreenRenderer` of their visible faces,
    colours (darkened inside the mouth: :func:`~mien.render.appearance.rig_vertex_colors`) and face paint
    (brows, lash lines, lips: :func:`~mien.render.face_paint.face_paint`).
    """
    width, height = _check_size(size)
    textured = textured_mesh_from_rig(rig)
    if textured is not None:
        mesh, gather = textured
        return RigTexturedRenderer(TexturedRenderer(mesh, width, height, camera, background, samples), gather)
    paint = face_paint(rig)
    return OffscreenRenderer(
        visible_faces(rig),
        width,
        height,
        camera,
        vertex_colors=rig_vertex_colors(rig),
        texture=None if paint is None else paint.texture,
        texcoords=None if paint is None else paint.texcoords,
        background=background,
        samples=samples,
    )


def render_still(
    rig: Rig,
    weights: np.ndarray | None,
    camera: Camera,
    size: tuple[int, int] = (512, 512),
    pose: np.ndarray | None = None,
    background: tuple[int, int, int] = DEFAULT_BACKGROUND,
    samples: int = 4,
) -> np.ndarray:
    """One (height, width, 3) uint8 image of ``rig`` at ``weights`` ((n_targets,), None = neutral).

    ``size`` is (width, height) in pixels; ``pose`` (5,) degrees (see :data:`POSE_COLUMNS`) or None;
    ``samples`` multisample anti-aliasing (0 = off).
    """
    w = _check_weights(rig, weights, 1)
    if len(w) != 1:
        raise InvalidValueError("weights", w.shape, f"({len(rig.targets)},) weights of one frame")
    with make_renderer(rig, camera, size, background, samples) as renderer:
        return next(iter_frames(rig, w, renderer, None if pose is None else np.asarray(pose)[None]))


def _is_frame_folder(path: Path) -> bool:
    return path.is_dir() or path.suffix == ""


def _write_png_frames(frames: Iterator[np.ndarray], folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    pending: list[Future[Path]] = []
    # One writer thread: Pillow's zlib releases the GIL, so compression overlaps the next render.
    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="mien-png") as pool:
        for index, frame in enumerate(frames):
            pending.append(pool.submit(write_png, frame, folder / f"frame_{index:06d}.png", 1))
            if len(pending) > 4:
                pending.pop(0).result()
        for future in pending:
            future.result()


def render_clip(
    rig: Rig,
    weights: np.ndarray,
    out_path: str | os.PathLike[str],
    fps: float,
    camera: Camera,
    size: tuple[int, int] = (512, 512),
    poses: np.ndarray | None = None,
    progress: bool = True,
    crf: int = 20,
    preset: str = "veryfast",
    background: tuple[int, int, int] = DEFAULT_BACKGROUND,
    samples: int = 0,
) -> Path:
    """Render ``weights`` ((n_frames, n_targets), 0..1) of ``rig`` through ``camera``; returns the output path.

    ``out_path`` ending in ``.mp4`` gets an H.264 video at ``fps`` (``crf``/``preset`` as in
    :func:`~mien.render.video.write_mp4`; a failure midway keeps ``<stem>.partial.mp4``); a path without a
    suffix, or an existing folder, gets ``frame_000000.png``, ... ``size`` is (width, height) in pixels
    (even for MP4). ``poses`` (n_frames, 5) degrees: head yaw/pitch/roll, gaze yaw/pitch, or None.
    ``samples`` multisample anti-aliasing: off by default for clips (4x MSAA costs 2-5x per frame on
    llvmpipe); stills (:func:`render_still`) use 4. SIGTERM and SIGHUP stop it as Ctrl-C does
    (:func:`~mien.signals.termination_as_interrupt`): the frames so far are kept, no temporary file.
    """
    out = Path(out_path)
    w = _check_weights(rig, weights, None)
    _check_poses(poses, len(w))
    if not _is_frame_folder(out) and out.suffix.lower() != ".mp4":
        raise InvalidValueError("out_path", str(out_path), "a .mp4 file or a folder for PNG frames")
    if not (isinstance(fps, int | float) and np.isfinite(fps) and fps > 0):
        raise InvalidValueError("fps", fps, "frames per second > 0")
    if not _is_frame_folder(out) and any(int(side) % 2 for side in size):
        raise InvalidValueError("size", size, "an even width and height for H.264 (yuv420p)")
    with termination_as_interrupt(), make_renderer(rig, camera, size, background, samples) as renderer:
        frames = progress_bar(
            iter_frames(rig, w, renderer, poses), total=len(w), desc=f"rendering {out.name}", enabled=progress
        )
        if _is_frame_folder(out):
            _write_png_frames(frames, out)
        else:
            write_mp4(frames, out, fps, crf=crf, preset=preset)
    return out
