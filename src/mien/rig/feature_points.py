"""Broekens' feature-point rig: 18 MPEG-4 feature points, each an anchor vertex pulling a region of vertices.

Broekens, Qu & Brinkman (*Dynamic Facial Expression of Emotion Made Easy*) model each feature as an anchor
"attached to a set of vertices" and each emotion as a displacement vector per feature (their Table 1). Here
each anchor is the face-surface vertex nearest the mean of some iBUG-68 landmarks (``data/mpeg4_features.csv``
says which, with the MPEG-4 feature point it stands for), so any mesh with a landmark map is instrumented
without hand rigging. Each region's weights are 1 at the anchor (and within an optional plateau) and fall
smoothly to 0 at a geodesic radius measured along mesh edges, so regions never jump the mouth slit or the
eye openings; a soft "closer to these landmarks than to those" cut keeps upper-lip anchors off the lower lip
and upper-lid anchors off the lower lid even on a mesh whose lips touch.

Smooth at the study's top intensity (:data:`DESIGN_INTENSITY` 2.4). Each feature has separate x, y and z
weights, shaped by the largest move ``D`` that Table 1 asks of that axis over the six emotions and four
blends at 2.4 (:func:`design_moves`):

* a region is wide enough that its falloff's steepest slope times ``D`` stays below :data:`MAX_STRAIN`
  (``R >= P + pi D / (2 MAX_STRAIN)``), grown at most :data:`GROWTH_LIMIT` times past the csv radius;
* a move toward a fixed barrier is strain-limited: the weight is at most ``BARRIER_STRAIN * g / D`` where
  ``g`` is the distance to the barrier (the upper-lid margin under a brow moving down, the lower-lid margin
  over a cheek moving up: geodesic; the facial midline for an inner brow moving in: ``|x|``). So the skin
  between feature and barrier compresses by at most :data:`BARRIER_STRAIN` at 2.4 instead of folding (on ICT
  the inner brows sit 12 mm from the midline and anger asks 31 mm inward at 2.4: exact motion must fold).
  Where the anchor is farther than ``D / BARRIER_STRAIN`` from its barrier it still moves exactly.

Every other anchor move is exact and linear (twice the intensity, twice the move). The targets are linear,
so a limited axis is limited in both directions (the brows rise a little less in surprise too).

The rig is linear, so it compiles into 54 sparse morph targets ``fp_<Feature>_x/_y/_z``: weight 1 moves the
region 1 m along rig +x (the character's left), +y (up) or +z (forward) times its weights. A Table 1 vector
``(z, x, y)`` (+x the viewer's right = the character's left, +y down) at intensity ``s`` becomes the target
weights ``(x s, -y s, z s)``: see :func:`table1_weights`.

>>> from mien.rig.builtin_head import builtin_head
>>> rig = builtin_head()
>>> fp = FeaturePointRig.build(rig)
>>> targets = fp.compile()
>>> len(targets), targets[0].name
(54, 'fp_Jaw_x')
"""

from __future__ import annotations

import csv
import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.rig.geodesic import EdgeGraph
from mien.rig.model import MorphTarget, Rig

__all__ = [
    "AXES",
    "FEATURE_NAMES",
    "FeaturePointRig",
    "FeatureSpec",
    "feature_specs",
    "feature_target_names",
    "table1_weights",
]

AXES = ("x", "y", "z")
"""Axis suffixes of the compiled targets (rig frame)."""
SIDE_BLEND_M = 0.003
"""Width (m) over which a region's closer-to/than cut fades."""
DESIGN_INTENSITY = 2.4
"""Emotion intensity the regions are shaped for: the strongest of Broekens' study (1.2 and 2.4)."""
MAX_STRAIN = 1.0
"""Largest relative length change (compression or stretch) one feature's move may cause at
:data:`DESIGN_INTENSITY` (1 would squash skin to nothing: a fold)."""
GROWTH_LIMIT = 2.0
"""Largest factor by which a large design move widens a region beyond its csv radius."""
BARRIER_STRAIN = 0.5
"""Largest compression of the skin between a feature and a fixed barrier (midline, lid margin) at
:data:`DESIGN_INTENSITY`."""


@dataclass(frozen=True)
class FeatureSpec:
    """One row of ``data/mpeg4_features.csv``."""

    name: str
    """Feature name as in Broekens' Table 1 (``LipCornerLeft``...)."""
    mpeg4_fp: str
    """MPEG-4 feature point(s) it stands for (``8.3``...)."""
    landmarks: tuple[int, ...]
    """0-based iBUG-68 landmarks whose mean places the anchor."""
    radius_m: float
    """Geodesic radius of the region, metres."""
    plateau_m: float
    """Geodesic distance within which the weight stays 1, metres."""
    closer_to: tuple[int, ...]
    """Landmarks a region vertex must be geodesically closer to than to :attr:`than` (empty = no cut)."""
    than: tuple[int, ...]
    """See :attr:`closer_to`."""
    barrier: tuple[int, ...]
    """Landmark chain (joined along mesh edges) that stays put while the feature moves toward it (empty = none)."""
    toward: str
    """Rig axis and sign of a move toward :attr:`barrier` (``"-y"`` down onto the upper lid, ``"+y"``); ``""``."""
    medial: bool
    """Whether the feature's x move toward the facial midline is strain-limited (the inner brows)."""


def _ints(text: str) -> tuple[int, ...]:
    return tuple(int(t) for t in text.split())


@cache
def feature_specs() -> tuple[FeatureSpec, ...]:
    """The 18 feature specs from ``data/mpeg4_features.csv``, in Broekens' Table 1 order."""
    text = resources.files("mien.rig").joinpath("data/mpeg4_features.csv").read_text(encoding="utf-8")
    rows = csv.DictReader(line for line in text.splitlines() if not line.startswith("#"))
    return tuple(
        FeatureSpec(
            name=row["feature"],
            mpeg4_fp=row["mpeg4_fp"],
            landmarks=_ints(row["landmarks"]),
            radius_m=float(row["radius_m"]),
            plateau_m=float(row["plateau_m"]),
            closer_to=_ints(row["closer_to"]),
            than=_ints(row["than"]),
            barrier=_ints(row["barrier"]),
            toward=row["toward"].strip(),
            medial=row["medial"].strip() == "1",
        )
        for row in rows
    )


FEATURE_NAMES: tuple[str, ...] = tuple(spec.name for spec in feature_specs())
"""The 18 feature names in Table 1 order: ``Jaw``, ``Nostrils``, ``LipLowerLeft``, ... ``BrowOuterRight``."""


def feature_target_names() -> tuple[str, ...]:
    """The 54 compiled target names: ``fp_<Feature>_x``, ``_y``, ``_z`` per feature in Table 1 order."""
    return tuple(f"fp_{name}_{axis}" for name in FEATURE_NAMES for axis in AXES)


def _falloff(d: np.ndarray, plateau: float, radius: float) -> np.ndarray:
    """1 up to ``plateau``, a raised-cosine fall to 0 at ``radius`` (zero slope at both ends)."""
    t = np.clip((d - plateau) / max(radius - plateau, 1e-9), 0.0, 1.0)
    return np.asarray(0.5 * (1.0 + np.cos(np.pi * t)))


def design_moves() -> np.ndarray:
    """(2, 18, 3) float64 metres: per feature and rig axis the largest move at :data:`DESIGN_INTENSITY` over
    Broekens' six emotions and four blends, toward + (index 0) and toward - (index 1); all >= 0."""
    from mien.affect.emotions import BLENDS, EMOTIONS, emotion_vector
    from mien.affect.table1 import table1_rig_vectors

    vectors = table1_rig_vectors()
    moves = np.stack(
        [np.tensordot(emotion_vector(name, DESIGN_INTENSITY), vectors, axes=1) for name in EMOTIONS + tuple(BLENDS)]
    )
    return np.stack([moves.max(axis=0).clip(0.0), (-moves).max(axis=0).clip(0.0)])


def _chain(graph: EdgeGraph, landmarks: np.ndarray, chain: tuple[int, ...]) -> np.ndarray:
    """Vertex ids along a chain of landmarks joined by shortest edge paths (a lid margin stays on its lid)."""
    ids = [landmarks[list(chain)]]
    for a, b in itertools.pairwise(chain):
        ids.append(graph.path(int(landmarks[a]), int(landmarks[b])))
    return np.unique(np.concatenate(ids))


@dataclass(frozen=True, eq=False)
class FeaturePointRig:
    """Anchors and weighted regions of the 18 feature points on one mesh."""

    names: tuple[str, ...]
    """Feature names (:data:`FEATURE_NAMES`)."""
    anchors: np.ndarray
    """(18,) int32 anchor vertex of each feature."""
    region_ids: tuple[np.ndarray, ...]
    """Per feature, (k,) int32 ids of the vertices it moves, ascending."""
    region_weights: tuple[np.ndarray, ...]
    """Per feature, (k, 3) float32 weights in [0, 1] of its rig x, y and z moves."""
    radii_m: np.ndarray
    """(18,) float64 largest geodesic radius of each region (over the three axes), metres."""

    @classmethod
    def build(cls, rig: Rig, radii: Mapping[str, float] | None = None) -> FeaturePointRig:
        """Place the anchors on ``rig`` from its iBUG landmarks and compute each region's weights.

        ``radii`` overrides the csv radius (metres) of the named features: the smallest radius, which a large
        design move still widens (see the module docstring); the plateau is kept below it.
        """
        overrides = dict(radii or {})
        for name, value in overrides.items():
            if name not in FEATURE_NAMES:
                raise UnknownNameError("feature point", name, FEATURE_NAMES)
            if not np.isfinite(value) or value <= 0:
                raise InvalidValueError(f"radii[{name!r}]", value, "a radius > 0 metres")
        landmarks = np.asarray(rig.landmarks, dtype=np.int64)
        if landmarks.shape != (68,):
            raise InvalidValueError(f"{rig.name} landmarks", landmarks.shape, "(68,) iBUG vertex ids")
        neutral = np.asarray(rig.neutral, dtype=np.float64)
        graph = EdgeGraph.from_mesh(neutral, rig.faces)
        surface = graph.component(landmarks)
        candidates = np.flatnonzero(surface)
        plus, minus = design_moves()
        reach = np.maximum(plus, minus)
        anchors, ids_out, weights_out, radii_out = [], [], [], []
        for f, spec in enumerate(feature_specs()):
            small = float(overrides.get(spec.name, spec.radius_m))
            plateau = min(spec.plateau_m, 0.5 * small)
            # the raised cosine's steepest slope pi / (2 (R - P)) times the design move stays <= MAX_STRAIN
            # ... up to GROWTH_LIMIT times the csv radius, so a region never spreads across the face
            radius = np.clip(plateau + np.pi * reach[f] / (2.0 * MAX_STRAIN), small, GROWTH_LIMIT * small)
            point = neutral[landmarks[list(spec.landmarks)]].mean(axis=0)
            anchor = int(candidates[np.argmin(np.linalg.norm(neutral[candidates] - point, axis=1))])
            dist = graph.distances([anchor], limit_m=float(radius.max()))
            ids = np.flatnonzero(dist < radius.max())
            weights = np.stack([_falloff(dist[ids], plateau, r) for r in radius], axis=1)
            weights[ids == anchor] = 1.0
            if spec.closer_to:
                far = float(radius.max()) * 2 + 0.03
                d_own = graph.distances(landmarks[list(spec.closer_to)], limit_m=far)[ids]
                d_other = graph.distances(landmarks[list(spec.than)], limit_m=far)[ids]
                d_own = np.where(np.isfinite(d_own), d_own, far)
                d_other = np.where(np.isfinite(d_other), d_other, far)
                t = np.clip((d_other - d_own) / SIDE_BLEND_M * 0.5 + 0.5, 0.0, 1.0)
                weights *= (t * t * (3.0 - 2.0 * t))[:, None]
            if spec.barrier and spec.toward:
                axis = AXES.index(spec.toward[1])
                move = (plus if spec.toward[0] == "+" else minus)[f, axis]
                if move > 0:
                    gap = graph.distances(_chain(graph, landmarks, spec.barrier))[ids]
                    weights[:, axis] = np.minimum(weights[:, axis], BARRIER_STRAIN * gap / move)
            if spec.medial:
                side = np.sign(neutral[anchor, 0])
                move = (minus if side > 0 else plus)[f, 0]
                if move > 0:
                    weights[:, 0] = np.minimum(weights[:, 0], BARRIER_STRAIN * np.abs(neutral[ids, 0]) / move)
                    weights[neutral[ids, 0] * side <= 0, 0] = 0.0
            keep = weights.max(axis=1) > 1e-4
            anchors.append(anchor)
            ids_out.append(ids[keep].astype(np.int32))
            weights_out.append(weights[keep].astype(np.float32))
            radii_out.append(float(radius.max()))
        return cls(
            names=FEATURE_NAMES,
            anchors=np.asarray(anchors, dtype=np.int32),
            region_ids=tuple(ids_out),
            region_weights=tuple(weights_out),
            radii_m=np.asarray(radii_out),
        )

    def weights(self, feature: str, n_vertices: int, axis: str | None = None) -> np.ndarray:
        """(n_vertices,) float32 dense weights of ``feature`` along rig ``axis`` (None: the largest of the three)."""
        if feature not in self.names:
            raise UnknownNameError("feature point", feature, self.names)
        if axis is not None and axis not in AXES:
            raise UnknownNameError("axis", axis, AXES)
        i = self.names.index(feature)
        values = self.region_weights[i]
        out = np.zeros(n_vertices, np.float32)
        out[self.region_ids[i]] = values.max(axis=1) if axis is None else values[:, AXES.index(axis)]
        return out

    def compile(self) -> tuple[MorphTarget, ...]:
        """The 54 targets ``fp_<Feature>_<axis>``: weight 1 moves the region 1 m along that rig axis."""
        targets = []
        for name, ids, weights in zip(self.names, self.region_ids, self.region_weights, strict=True):
            for a, axis in enumerate(AXES):
                moved = weights[:, a] > 0
                deltas = np.zeros((int(moved.sum()), 3), np.float32)
                deltas[:, a] = weights[moved, a]
                targets.append(MorphTarget(f"fp_{name}_{axis}", ids[moved], deltas))
        return tuple(targets)

    def displacement(self, vectors_zxy: np.ndarray, intensity: float, n_vertices: int) -> np.ndarray:
        """(n_vertices, 3) float64 displacement (m) of Broekens vectors ``(18, 3)`` ``[z, x, y]`` at ``intensity``."""
        out = np.zeros((n_vertices, 3))
        for name, value in table1_weights(vectors_zxy, intensity).items():
            feature, axis = name[3:-2], AXES.index(name[-1])
            i = self.names.index(feature)
            out[self.region_ids[i], axis] += value * self.region_weights[i][:, axis]
        return out


def table1_weights(vectors_zxy: np.ndarray, intensity: float = 1.0) -> dict[str, float]:
    """Target weights of the compiled rig for Broekens vectors (18, 3) ``[z, x, y]`` (metres) at ``intensity``.

    Broekens' frame: +z toward the viewer, +x the viewer's right (the character's left), +y down; in the rig
    frame that is ``(dx, dy, dz) = (x, -y, z)``, so the ``fp_<F>_y`` weight is ``-y * intensity``.

    >>> v = np.zeros((18, 3)); v[FEATURE_NAMES.index("LipCornerLeft")] = [-0.005, 0.009, -0.007]
    >>> w = table1_weights(v, 2.0)
    >>> [round(w[f"fp_LipCornerLeft_{a}"], 6) for a in "xyz"]
    [0.018, 0.014, -0.01]
    """
    vectors = np.asarray(vectors_zxy, dtype=np.float64)
    if vectors.shape != (len(FEATURE_NAMES), 3) or not np.all(np.isfinite(vectors)):
        raise InvalidValueError("vectors_zxy", vectors.shape, f"({len(FEATURE_NAMES)}, 3) finite [z, x, y] metres")
    if not np.isfinite(intensity):
        raise InvalidValueError("intensity", intensity, "a finite number")
    from mien.affect.table1 import broekens_to_rig

    rig_vectors = broekens_to_rig(vectors) * float(intensity)
    return {
        f"fp_{name}_{axis}": float(rig_vectors[f, a])
        for f, name in enumerate(FEATURE_NAMES)
        for a, axis in enumerate(AXES)
    }
