"""The rig model: a neutral mesh plus named sparse morph targets, a landmark map and named regions.

Coordinates (every mien rig, whatever its source): metres; +x toward the character's left (a frontal
viewer's right), +y up, +z forward (out of the face, toward a frontal viewer). The origin is the midpoint
between the eyeball centres, so cameras and the feature-point rig can place themselves without knowing the
mesh. Loaders convert their source's units and axes into this frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError

__all__ = ["MorphTarget", "Rig"]


@dataclass(frozen=True, eq=False)
class MorphTarget:
    """One morph target stored sparsely: the vertices it moves and by how much at weight 1."""

    name: str
    """Target name (an ARKit name, or an extra such as ``fp_LipCornerLeft_x``)."""
    vertex_ids: np.ndarray
    """(k,) int32 ids of the moved vertices, ascending."""
    deltas: np.ndarray
    """(k, 3) float32 displacement of those vertices at weight 1, metres."""

    def __post_init__(self) -> None:
        ids = np.ascontiguousarray(self.vertex_ids, dtype=np.int32)
        deltas = np.ascontiguousarray(self.deltas, dtype=np.float32)
        if ids.ndim != 1 or deltas.shape != (ids.shape[0], 3):
            raise InvalidValueError(f"morph target {self.name}", deltas.shape, "(k,) ids and (k, 3) deltas")
        object.__setattr__(self, "vertex_ids", ids)
        object.__setattr__(self, "deltas", deltas)

    @classmethod
    def from_dense(cls, name: str, dense: np.ndarray, tolerance_m: float = 1e-7) -> MorphTarget:
        """Build from an (n_vertices, 3) dense delta, keeping vertices that move more than ``tolerance_m``."""
        dense = np.asarray(dense, dtype=np.float32)
        moved = np.flatnonzero(np.abs(dense).max(axis=1) > tolerance_m)
        return cls(name, moved, dense[moved])

    def dense(self, n_vertices: int) -> np.ndarray:
        """(n_vertices, 3) float32 dense delta."""
        out = np.zeros((n_vertices, 3), np.float32)
        out[self.vertex_ids] = self.deltas
        return out


@dataclass(frozen=True, eq=False)
class Rig:
    """A deformable head: neutral mesh, sparse morph targets, landmarks and regions."""

    name: str
    """Human-readable name (``"builtin"``, ``"ict-facekit"``...)."""
    neutral: np.ndarray
    """(n_vertices, 3) float32 rest positions, metres, in the mien frame (see module doc)."""
    faces: np.ndarray
    """(n_faces, 3) int32 triangle vertex ids (quads are split)."""
    targets: tuple[MorphTarget, ...]
    """Morph targets; the 52 ARKit names come first in ARKit order when the rig has them."""
    landmarks: np.ndarray
    """(68,) int32 vertex id of each iBUG 68-point landmark (0-based iBUG numbering)."""
    regions: dict[str, np.ndarray] = field(default_factory=dict)
    """Named vertex-id sets: at least ``"eye_L"``, ``"eye_R"`` (eyeballs, rotated by gaze) and ``"head"``
    (everything the head rotation moves); also ``"skin"``, ``"lips"``, ``"teeth"``... for colouring."""
    vertex_colors: np.ndarray | None = None
    """(n_vertices, 3) float32 linear RGB albedo in 0..1, or None for a default skin tone."""
    eye_centers: np.ndarray = field(default_factory=lambda: np.zeros((2, 3), np.float32))
    """(2, 3) float32 centres of rotation of the left and right eyeballs, metres."""
    neck_pivot: np.ndarray = field(default_factory=lambda: np.array([0.0, -0.09, -0.04], np.float32))
    """(3,) float32 point the head rotates about, metres."""
    shape_gains: dict[str, float] = field(default_factory=dict)
    """Factors mien applied to the source's own shapes (target name -> factor, e.g. ICT's ``browDownLeft``: 2.0,
    see :data:`mien.rig.ict_facekit.ICT_TARGET_GAINS`); the skin-detail correctives
    (:mod:`mien.rig.fp_correctives`) use the shapes as their artist shipped them."""

    def __post_init__(self) -> None:
        neutral = np.ascontiguousarray(self.neutral, dtype=np.float32)
        faces = np.ascontiguousarray(self.faces, dtype=np.int32)
        if neutral.ndim != 2 or neutral.shape[1] != 3:
            raise InvalidValueError(f"{self.name} neutral", neutral.shape, "(n_vertices, 3)")
        if faces.ndim != 2 or faces.shape[1] != 3 or (faces.size and (faces.min() < 0 or faces.max() >= len(neutral))):
            raise InvalidValueError(f"{self.name} faces", faces.shape, "(n_faces, 3) ids of existing vertices")
        names = [t.name for t in self.targets]
        if len(set(names)) != len(names):
            raise InvalidValueError(f"{self.name} targets", names, "unique target names")
        object.__setattr__(self, "neutral", neutral)
        object.__setattr__(self, "faces", faces)
        object.__setattr__(self, "landmarks", np.asarray(self.landmarks, dtype=np.int32))

    @property
    def n_vertices(self) -> int:
        """Number of vertices."""
        return int(self.neutral.shape[0])

    @property
    def target_names(self) -> tuple[str, ...]:
        """Names of the morph targets, in order."""
        return tuple(t.name for t in self.targets)

    def target(self, name: str) -> MorphTarget:
        """The morph target called ``name``."""
        for candidate in self.targets:
            if candidate.name == name:
                return candidate
        raise UnknownNameError("morph target", name, self.target_names)

    def target_index(self, name: str) -> int:
        """Position of target ``name`` in :attr:`targets`."""
        names = self.target_names
        if name not in names:
            raise UnknownNameError("morph target", name, names)
        return names.index(name)

    def with_targets(self, extra: tuple[MorphTarget, ...]) -> Rig:
        """A copy of this rig with ``extra`` targets appended (e.g. the compiled feature-point rig)."""
        return Rig(
            name=self.name,
            neutral=self.neutral,
            faces=self.faces,
            targets=self.targets + tuple(extra),
            landmarks=self.landmarks,
            regions=self.regions,
            vertex_colors=self.vertex_colors,
            eye_centers=self.eye_centers,
            neck_pivot=self.neck_pivot,
            shape_gains=self.shape_gains,
        )
