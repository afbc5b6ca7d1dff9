"""Rendering faces for validation: face frames on a head through a camera -> RGB images + landmark hints.

One :class:`StimulusRenderer` per (rig, size) keeps its offscreen renderer and deformer, so a report renders
hundreds of stills without rebuilding them; :meth:`StimulusRenderer.set_camera` moves it from view to view. Each
image comes with ``hint``: the rig's 68 iBUG landmark vertices, deformed with the face and projected through the
camera ((68, 2) pixels), which is where the face is whether or not a detector finds it (:mod:`mien.validate.detector`).
"""

from __future__ import annotations

from types import TracebackType
from typing import Any

import numpy as np

from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.render.camera import Camera
from mien.render.clip_render import make_renderer
from mien.rig.animate import face_to_rig
from mien.rig.deform import Deformer
from mien.rig.mapping import AUMapping
from mien.rig.model import Rig
from mien.rig.pose import apply_pose

__all__ = ["StimulusRenderer"]


class StimulusRenderer:
    """Render face frames of ``rig`` through ``camera`` at ``size`` (width, height) pixels.

    ``mapping``: the AU -> ARKit table (:class:`mien.rig.mapping.AUMapping`; default the shipped one).
    ``samples``: multisample anti-aliasing (0 off; the recognition study renders without it, docs/VALIDATION.md).
    Use as a context manager (it holds an OpenGL context).
    """

    def __init__(
        self,
        rig: Rig,
        camera: Camera,
        size: tuple[int, int] = (512, 512),
        mapping: object | None = None,
        samples: int = 4,
    ) -> None:
        self.rig = rig
        self.camera = camera
        self.size = (int(size[0]), int(size[1]))
        table = mapping if isinstance(mapping, AUMapping) else AUMapping.default()
        self.mapping = table.weights_for(rig)
        self._renderer = make_renderer(rig, camera, self.size, samples=samples)
        self._deformer = Deformer(rig)
        self._vertices = np.empty((rig.n_vertices, 3), np.float32)
        self.last_vertices = self._vertices
        """(n_vertices, 3) float32 deformed mesh of the last render, before head pose (reused by the next)."""

    def __enter__(self) -> StimulusRenderer:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()

    def close(self) -> None:
        """Release the OpenGL context (idempotent)."""
        self._renderer.close()

    def set_camera(self, camera: Camera) -> None:
        """Look through ``camera`` from the next render on (the context, mesh and deformer are kept)."""
        self.camera = camera
        target: Any = getattr(self._renderer, "textured", self._renderer)  # a head file's renderer wraps its own
        target.set_camera(camera)

    def draw(self, vertices: np.ndarray) -> np.ndarray:
        """(h, w, 3) uint8 picture of already deformed ``vertices`` ((n_vertices, 3) metres), e.g. another
        renderer's :attr:`last_vertices` (the same face at another size)."""
        return np.asarray(self._renderer.render(np.asarray(vertices, np.float32)))

    def weights(self, frame: np.ndarray, feature_weights: np.ndarray | None = None) -> np.ndarray:
        """(n_targets,) float32 morph weights of a (62,) face frame (and optional (54,) feature weights)."""
        frame = np.asarray(frame, dtype=np.float64)
        weights = self.mapping.to_weights(frame)
        if feature_weights is not None:
            weights, _ = face_to_rig(self.rig, frame[None], np.asarray(feature_weights)[None])
            weights = weights[0]
        return np.asarray(weights, np.float32)

    def render_weights(self, weights: np.ndarray, pose: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(rgb (h, w, 3) uint8, hint (68, 2) float32 pixels)`` of the rig at ``weights``.

        ``pose``: (5,) head yaw/pitch/roll and gaze yaw/pitch in degrees, or None.
        """
        deformed = self._deformer.deform(np.asarray(weights, np.float32), out=self._vertices)
        if pose is not None and np.any(pose):
            p = np.asarray(pose, dtype=np.float64)
            deformed = apply_pose(self.rig, deformed, p[:3], p[3:])
        rgb = self._renderer.render(deformed)
        hint = self.camera.project(deformed[self.rig.landmarks], *self.size).astype(np.float32)
        return rgb, hint

    def render(self, frame: np.ndarray, feature_weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(rgb, hint)`` of a (62,) face frame (pose channels applied), see :meth:`render_weights`."""
        frame = np.asarray(frame, dtype=np.float64)
        pose = frame[[FACE_CHANNELS.index(name) for name in POSE_CHANNELS]]
        return self.render_weights(self.weights(frame, feature_weights), pose)
