"""How a rig looks when rendered: per-vertex albedo from its regions, and which triangles to draw.

A rig's own ``vertex_colors`` win. Otherwise regions get plain albedos (linear RGB, chosen by eye to read
as skin, lips, teeth, gums and lashes under the renderer's three lights). Eyeballs are painted white with
an iris and pupil: the caps within 30 / 10 degrees of straight ahead (+z) of the eye centre (an iris is
~12 mm across on a 24 mm eyeball: asin(6 / 12) = 30 degrees), so gaze shows.

ICT-FaceKit's eyes are two shells (regions ``sclera_*`` and ``iris_*``): an outer one with a clear corneal
bulge over an inner eyeball that carries the iris. The outer shell's cap is not drawn, and the inner one is
painted. ICT's see-through helper meshes (eye occlusion shadows, lacrimal fluid, eye blend) and eyelash
cards would cover the eyes if drawn opaque, so triangles wholly in :data:`HIDDEN_REGIONS` are not drawn; the
eyes get painted lash lines instead, and the brows and the lips' vermilion are painted too, as a texture over
these colours (:mod:`mien.render.face_paint`).
"""

from __future__ import annotations

import numpy as np

from mien.render.cavity import cavity_shade
from mien.render.face_paint import LIP_ALBEDO
from mien.rig.model import Rig

__all__ = ["HIDDEN_REGIONS", "REGION_ALBEDO", "SKIN_ALBEDO", "rig_vertex_colors", "visible_faces"]

SKIN_ALBEDO = (0.62, 0.40, 0.30)
"""Linear RGB albedo of skin (and of any vertex no other region claims)."""

REGION_ALBEDO: dict[str, tuple[float, float, float]] = {
    "lips": LIP_ALBEDO,
    "mouth_socket": (0.28, 0.07, 0.07),
    "gums_tongue": (0.55, 0.16, 0.16),
    "teeth": (0.80, 0.76, 0.66),
    "eye_socket_L": (0.30, 0.12, 0.10),
    "eye_socket_R": (0.30, 0.12, 0.10),
}
"""Region name -> linear RGB albedo, applied in this order over :data:`SKIN_ALBEDO` (later wins)."""

SCLERA_ALBEDO = (0.80, 0.78, 0.76)
"""Linear RGB albedo of the white of the eye."""

IRIS_ALBEDO = (0.12, 0.07, 0.04)
"""Linear RGB albedo of a painted iris (brown)."""

PUPIL_ALBEDO = (0.01, 0.01, 0.01)
"""Linear RGB albedo of a painted pupil."""

CORNEA_HALF_ANGLE_DEG = 40.0
"""Angular radius of the clear cap not drawn on a two-shell eye's outer shell, degrees."""

IRIS_HALF_ANGLE_DEG = 30.0
"""Angular radius of a painted iris seen from the eyeball centre, degrees."""

PUPIL_HALF_ANGLE_DEG = 10.0
"""Angular radius of a painted pupil, degrees."""

HIDDEN_REGIONS = (
    "eye_occlusion_L",
    "eye_occlusion_R",
    "lacrimal_fluid_L",
    "lacrimal_fluid_R",
    "eye_blend_L",
    "eye_blend_R",
    "eyelashes_L",
    "eyelashes_R",
    "eye_shell_L",
    "eye_shell_R",
)
"""Regions not drawn: see-through helper geometry (ICT's named parts; a head file's eye shells, found by
:mod:`mien.rig.files.head`), and ICT's eyelash cards (alpha-textured in the
original; drawn opaque they read as thick dark bands, so the lash line is painted on the lid margin)."""


def _eye_shells(rig: Rig, side: int) -> tuple[np.ndarray | None, np.ndarray]:
    """(cornea shell ids or None, eyeball ids to paint) of eye ``side`` (0 = left, 1 = right).

    A rig whose eye is split into two sub-regions (ICT-FaceKit's ``sclera_*`` and ``iris_*``: an outer
    shell with a clear corneal bulge over an inner eyeball) gets the shell that reaches farther forward as
    the cornea; a one-piece eyeball is painted as it is.
    """
    letter = "LR"[side]
    parts = [rig.regions[f"{kind}_{letter}"] for kind in ("sclera", "iris") if f"{kind}_{letter}" in rig.regions]
    if len(parts) == 2:
        reach = [float(np.max(rig.neutral[np.asarray(p, np.int64), 2])) for p in parts]
        outer = int(np.argmax(reach))
        return np.asarray(parts[outer], np.int64), np.asarray(parts[1 - outer], np.int64)
    return None, np.asarray(rig.regions.get(f"eye_{letter}", np.zeros(0, np.int64)), np.int64)


def _forward_cosine(rig: Rig, ids: np.ndarray, side: int) -> np.ndarray:
    """Cosine of the angle between +z and each vertex's direction from the eye centre."""
    directions = rig.neutral[ids] - np.asarray(rig.eye_centers[side], np.float32)
    lengths = np.linalg.norm(directions, axis=1)
    return np.asarray(directions[:, 2] / np.where(lengths > 0, lengths, 1.0))


def rig_vertex_colors(rig: Rig) -> np.ndarray:
    """(n_vertices, 3) float32 linear RGB albedo of ``rig``: its ``vertex_colors`` or colours by region, darkened
    inside the mouth (:func:`~mien.render.cavity.cavity_shade`), as renders, glTF exports and the viewer show it."""
    return _base_colors(rig) * cavity_shade(rig)[:, None]


def _base_colors(rig: Rig) -> np.ndarray:
    if rig.vertex_colors is not None:
        return np.ascontiguousarray(rig.vertex_colors, dtype=np.float32)
    colors = np.empty((rig.n_vertices, 3), np.float32)
    colors[:] = SKIN_ALBEDO
    for name, albedo in REGION_ALBEDO.items():
        if name in rig.regions:
            colors[np.asarray(rig.regions[name], dtype=np.int64)] = albedo
    for side in (0, 1):
        cornea, eyeball = _eye_shells(rig, side)
        if len(eyeball) == 0:
            continue
        cosine = _forward_cosine(rig, eyeball, side)
        colors[eyeball] = SCLERA_ALBEDO
        colors[eyeball[cosine > np.cos(np.radians(IRIS_HALF_ANGLE_DEG))]] = IRIS_ALBEDO
        colors[eyeball[cosine > np.cos(np.radians(PUPIL_HALF_ANGLE_DEG))]] = PUPIL_ALBEDO
        if cornea is not None:
            colors[cornea] = SCLERA_ALBEDO
    return colors


def visible_faces(rig: Rig) -> np.ndarray:
    """(m', 3) int32 triangles of ``rig`` to draw.

    Drops triangles wholly inside :data:`HIDDEN_REGIONS` and, for two-shell eyes, the clear corneal cap
    (within :data:`CORNEA_HALF_ANGLE_DEG` of straight ahead) of the outer shell.
    """
    hidden = np.zeros(rig.n_vertices, bool)
    for name in HIDDEN_REGIONS:
        if name in rig.regions:
            hidden[np.asarray(rig.regions[name], dtype=np.int64)] = True
    for side in (0, 1):
        cornea, _ = _eye_shells(rig, side)
        if cornea is not None:
            hidden[cornea[_forward_cosine(rig, cornea, side) > np.cos(np.radians(CORNEA_HALF_ANGLE_DEG))]] = True
    if not hidden.any():
        return rig.faces
    return np.ascontiguousarray(rig.faces[~hidden[rig.faces].all(axis=1)])
