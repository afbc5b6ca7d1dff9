"""Placing a head read from a file in mien's frame, with the facts its instrumenting found.

A loader gives the file's mesh in the file's own unit and axes; :func:`place_rig` turns it into a rig every mien
job can use: metres, +x the character's left, +y up, +z forward, the origin between the eyeball centres, the
iBUG-68 landmark vertices found on the face, and the eyes' and neck's pivots (see :mod:`mien.rig.model`).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mien.heads.instrument import Instrumentation
from mien.rig.model import MorphTarget, Rig

__all__ = ["EYE_DEPTH_M", "NECK_BELOW_EYES_M", "eye_centres", "place_rig"]

EYE_DEPTH_M = 0.011
"""How far an eyeball's centre of rotation lies behind its lid opening: an adult eyeball's radius is about 12 mm
and the lids close over its front (Bekerman et al. 2014, *Variations in eyeball diameters*), metres."""

NECK_BELOW_EYES_M = (-0.09, -0.04)
"""Where the head turns, from the eyes' midpoint: 9 cm down and 4 cm back (the top of the neck; mien's other
heads use the same), metres along up and forward."""


def eye_centres(found: Instrumentation, regions: dict[str, np.ndarray], vertices: np.ndarray) -> np.ndarray:
    """(2, 3) float64 left and right eyeball centres in file units.

    An eye region the loader found (an eyeball mesh) gives its centre; otherwise the middle of the eye's six
    iBUG-68 lid points, moved back by :data:`EYE_DEPTH_M`. Left and right are the character's own (iBUG 42-47 is
    the subject's left eye).
    """
    metres = found.metres_per_unit
    forward = np.asarray(found.forward, np.float64)
    centres = np.empty((2, 3))
    for row, (side, lids) in enumerate((("eye_L", slice(42, 48)), ("eye_R", slice(36, 42)))):
        ball = regions.get(side)
        if ball is not None and len(ball):
            points = vertices[np.asarray(ball, np.int64)]
            centres[row] = 0.5 * (points.min(axis=0) + points.max(axis=0))
        else:
            centres[row] = found.ibug68_points[lids].astype(np.float64).mean(axis=0) - forward * EYE_DEPTH_M / metres
    return centres


def place_rig(rig: Rig, found: Instrumentation, name: str | None = None) -> Rig:
    """``rig`` (file units and axes, as loaded) in mien's frame, with the landmarks and pivots of ``found``.

    Target deltas turn and scale with the mesh; regions, colours, shape gains (and a file head's own
    information) are kept.
    """
    rotation = found.rotation()
    scale = found.metres_per_unit
    vertices = rig.neutral.astype(np.float64)
    centres = eye_centres(found, rig.regions, vertices)
    origin = centres.mean(axis=0)

    def place(points: np.ndarray) -> np.ndarray:
        return ((points - origin) @ rotation.T * scale).astype(np.float32)

    targets = tuple(
        MorphTarget(t.name, t.vertex_ids, (t.deltas.astype(np.float64) @ rotation.T * scale).astype(np.float32))
        for t in rig.targets
    )
    regions = dict(rig.regions)
    regions.setdefault("head", np.arange(rig.n_vertices, dtype=np.int32))
    neutral = place(vertices)
    down, back = NECK_BELOW_EYES_M
    return replace(
        rig,
        name=name or rig.name,
        neutral=neutral,
        targets=targets,
        landmarks=found.ibug68_vertices,
        regions=regions,
        eye_centers=place(centres),
        neck_pivot=np.array([0.0, down, back], np.float32),
    )
