"""Skin detail for the feature-point rig: the head's own shapes, less their anchor moves, ride the features.

The feature-point fields (:mod:`mien.rig.feature_points`) are the smoothest skin through the 18 anchors that
Broekens' Table 1 moves. Smooth skin cannot fold or bunch: a feature-point smile had no nasolabial fold, a
lowered brow no bulge over the eye, and at intensity 1.2 the emotion classifier read both as neutral. Real skin
gets that detail from the action itself, and a head's artist-made shape for the same action (its ARKit target,
which the FACS basis drives) holds it. ``data/mpeg4_correctives.csv`` names, per action, the shape and the feature
move that drives it (the lip corner's rise drives ``mouthSmile``, the inner brow's fall ``browDown``...).

**The rule.** A corrective target is the shape ``S`` less the smooth fields through ``S``'s own moves at the 18
anchors (``S - sum_f c_f field_f``, ``c`` solved so the result is 0 at every anchor, rides included), faded out over
the lid features' regions (a lid moves only by its own feature; every other feature holds its margin, so a
corrective moves a lid margin only toward the eye corners, where the lid's own field fades: at most 1.5 mm on
the built-in and ICT heads). So the anchors still move exactly by Table 1, and only the skin between them changes.
Its weight is the driving feature's move (after :func:`mien.rig.feature_points.limit_moves`) over the shape's own
move on that feature's plateau, clipped to 0..1: the artist's range, never past it, and nothing for a move the
other way (a corrective of :data:`PICTURE_PLANE`, the smile: the feature's move in the picture plane projected on
the shape's own move there, over that move's length). ``S`` is the shape as its artist shipped it (a factor mien
puts on a head's shape, ICT's browDown x 2 for the FACS basis, :attr:`mien.rig.model.Rig.shape_gains`, is divided
out). A driver turns the correctives into
one (54, k) matrix once (:func:`corrective_matrix`), so a tick is one product and a clip (:func:`drive_correctives`).

>>> spec = corrective_specs()[0]
>>> spec.shape, spec.feature, spec.axis
('mouthSmile', 'LipCorner', 'xy')
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

from mien.errors import InvalidValueError, UnknownNameError
from mien.rig.feature_points import AXES, FEATURE_NAMES, FeaturePointRig, _data_rows
from mien.rig.model import MorphTarget, Rig

__all__ = [
    "CORRECTIVE_PREFIX",
    "PICTURE_PLANE",
    "Corrective",
    "CorrectiveSpec",
    "corrective_matrix",
    "corrective_specs",
    "corrective_targets",
    "correctives",
    "drive_correctives",
]

CORRECTIVE_PREFIX = "fpc_"
"""Prefix of the compiled corrective targets: ``fpc_mouthSmileLeft``..."""
PICTURE_PLANE = "xy"
"""The ``axis`` of a corrective driven by its feature's move in the picture plane (rig x and y) along the shape's own
move there, not by one axis: the smile's corner goes up and out together (AU12 pulls it obliquely)."""
PLATEAU_SHARE = 0.999
"""A feature target's vertices that move at least this share of the feature are its plateau."""
MIN_SHAPE_MOVE_M = 1e-4
"""A shape that moves its driving feature's landmarks less than this (metres, along the axis) drives nothing."""


@dataclass(frozen=True)
class CorrectiveSpec:
    """One row of ``data/mpeg4_correctives.csv``."""

    shape: str
    """The head's shape, without its side (``mouthSmile``: ``mouthSmileLeft`` and ``mouthSmileRight``)."""
    feature: str
    """The driving feature, without its side (``LipCorner``), or a feature of its own (``Nostrils``)."""
    axis: str
    """Rig axis and sign of the driving move (``"+y"`` up, ``"-y"`` down), or ``"xy"``: the feature's move in the
    picture plane (rig x and y) along the shape's own move there."""
    why: str
    """The skin detail the shape adds, with its source."""


@cache
def corrective_specs() -> tuple[CorrectiveSpec, ...]:
    """The corrective rows of ``data/mpeg4_correctives.csv``, checked against the feature names."""
    specs = []
    for row in _data_rows("mpeg4_correctives.csv"):
        spec = CorrectiveSpec(row["shape"].strip(), row["feature"].strip(), row["axis"].strip(), row["why"].strip())
        if _feature_sides(spec.feature) is None:
            raise UnknownNameError("feature driving a corrective", spec.feature, FEATURE_NAMES)
        if spec.axis != PICTURE_PLANE and (len(spec.axis) != 2 or spec.axis[0] not in "+-" or spec.axis[1] not in AXES):
            raise InvalidValueError(
                f"axis of the {spec.shape} corrective", spec.axis, "+x, -x, +y, -y, +z, -z or xy (the picture plane)"
            )
        specs.append(spec)
    return tuple(specs)


def _feature_sides(feature: str) -> tuple[str, ...] | None:
    """``("",)`` for a feature of its own (``Nostrils``), ``("Left", "Right")`` for a sided one, None if unknown."""
    if feature in FEATURE_NAMES:
        return ("",)
    if all(feature + side in FEATURE_NAMES for side in ("Left", "Right")):
        return ("Left", "Right")
    return None


@dataclass(frozen=True)
class Corrective:
    """One compiled corrective on one rig: which target, which feature columns drive it, and how hard."""

    target: str
    """Corrective target name (``fpc_mouthSmileLeft``)."""
    shape: str
    """The head's shape it is made from (``mouthSmileLeft``)."""
    sources: tuple[int, ...]
    """Columns of the 54 feature weights whose mean move drives it (one; both sides for an unsided shape)."""
    gain: float
    """Weight per metre of that move: 1 over the shape's own move at the feature's landmarks (signed; for an ``xy``
    corrective, over the length of its move in the picture plane)."""
    weights: tuple[float, ...] = ()
    """Per source column, the weight per metre of that column's move (an ``xy`` corrective: the projection on the
    shape's own move, ``m . s / |s|^2``); empty: :attr:`gain` shared equally by the sources."""


def correctives(rig: Rig) -> tuple[Corrective, ...]:
    """The correctives ``rig`` can carry: each spec whose shape the rig has and whose shape moves its feature.

    ``rig`` has the compiled feature-point targets (``fp_*``); a feature's place is its target's plateau (the
    skin it moves by 1), and the shape's own move there, along the spec's axis, sets the gain. A sided shape
    (``mouthSmileLeft``/``Right``) follows its own side's feature (both sides follow a feature of its own, the
    ``Nostrils``); a shape the head has only once (the built-in ``browInnerUp``) follows the mean of both sides.
    A rig without the feature-point targets gets none.
    """
    by_name = {t.name: t for t in rig.targets}
    out = []
    for spec in corrective_specs():
        plane = spec.axis == PICTURE_PLANE
        axis = 1 if plane else AXES.index(spec.axis[1])
        sign = 1.0 if plane or spec.axis[0] == "+" else -1.0
        feature_sides = _feature_sides(spec.feature) or ()
        drivers = {s: by_name.get(f"fp_{spec.feature}{s}_{AXES[axis]}") for s in feature_sides}
        if spec.shape + "Left" in by_name and spec.shape + "Right" in by_name:
            pairs = [(spec.shape + s, (s,) if len(feature_sides) == 2 else feature_sides) for s in ("Left", "Right")]
        else:
            pairs = [(spec.shape, feature_sides)]
        for shape, sides in pairs:
            fields = [drivers[s] for s in sides]
            if shape not in by_name or any(field is None for field in fields):
                continue
            plateau = np.concatenate([f.vertex_ids[f.deltas[:, axis] >= PLATEAU_SHARE] for f in fields if f])
            if plateau.size == 0:
                continue
            if plane:  # the shape's move in the picture plane: project the feature's move on it
                own = _as_shipped(rig, by_name[shape])[plateau, :2].mean(axis=0)
                length = float(np.linalg.norm(own))
                if length < MIN_SHAPE_MOVE_M:
                    continue
                columns = [3 * FEATURE_NAMES.index(spec.feature + s) for s in sides]
                per_side = own / length**2 / len(sides)
                out.append(
                    Corrective(
                        CORRECTIVE_PREFIX + shape,
                        shape,
                        tuple(c + a for c in columns for a in (0, 1)),
                        1.0 / length,
                        tuple(float(per_side[a]) for _ in columns for a in (0, 1)),
                    )
                )
                continue
            move = float(_as_shipped(rig, by_name[shape])[plateau, axis].mean())
            if sign * move < MIN_SHAPE_MOVE_M:
                continue
            sources = tuple(3 * FEATURE_NAMES.index(spec.feature + s) + axis for s in sides)
            out.append(Corrective(CORRECTIVE_PREFIX + shape, shape, sources, 1.0 / move))
    return tuple(out)


def _as_shipped(rig: Rig, shape: MorphTarget) -> np.ndarray:
    """(n_vertices, 3) float64 dense deltas of ``rig``'s ``shape`` as its artist shipped it (mien's factor divided
    out, :attr:`mien.rig.model.Rig.shape_gains`)."""
    return shape.dense(rig.n_vertices).astype(np.float64) / rig.shape_gains.get(shape.name, 1.0)


def corrective_targets(fp: FeaturePointRig, rig: Rig) -> tuple[MorphTarget, ...]:
    """The compiled corrective targets of :func:`correctives` for ``rig`` (with ``fp``'s compiled targets).

    Each is its shape less the feature fields through the shape's anchor moves (0 at every anchor), faded out
    over the lid features' regions; weight 1 is the whole residual (see the module docstring).
    """
    n = rig.n_vertices
    fields = np.zeros((len(fp.names), 3, n))
    for f, (ids, weights) in enumerate(zip(fp.region_ids, fp.region_weights, strict=True)):
        fields[f][:, ids] = weights.T
    anchors = np.asarray(fp.anchors, dtype=np.int64)
    # per axis, field_f at anchor g: the identity plus the rides, so the solved mix is 0 at every anchor
    at_anchors = fields[:, :, anchors].transpose(1, 2, 0)  # (axis, anchor g, feature f)
    lid = np.zeros(n)
    for f, name in enumerate(fp.names):
        if name.startswith("Lid"):
            lid = np.maximum(lid, np.abs(fields[f]).max(axis=0))
    keep = 1.0 - np.clip(lid, 0.0, 1.0)
    by_name = {t.name: t for t in rig.targets}
    targets = []
    for corrective in correctives(rig):
        shape = _as_shipped(rig, by_name[corrective.shape])
        residual = shape.copy()
        for a in range(3):
            mix = np.linalg.solve(at_anchors[a], shape[anchors, a])
            residual[:, a] -= mix @ fields[:, a]
        residual *= keep[:, None]
        targets.append(MorphTarget.from_dense(corrective.target, residual.astype(np.float32)))
    return tuple(targets)


def corrective_matrix(drives: tuple[Corrective, ...]) -> np.ndarray:
    """(54, k) float32: column ``j`` maps the 54 feature moves (metres) to corrective ``j``'s unclipped weight (the
    mean of its source moves times its gain, or the sum of each source move times its own weight).

    >>> c = Corrective("fpc_browInnerUp", "browInnerUp", (43, 46), 100.0)
    >>> m = corrective_matrix((c,)); m.shape, float(m[43, 0]), float(m[46, 0])
    ((54, 1), 50.0, 50.0)
    """
    matrix = np.zeros((3 * len(FEATURE_NAMES), len(drives)), np.float32)
    for j, corrective in enumerate(drives):
        if corrective.weights:
            matrix[list(corrective.sources), j] = corrective.weights
        else:
            matrix[list(corrective.sources), j] = corrective.gain / len(corrective.sources)
    return matrix


def drive_correctives(features: np.ndarray, matrix: np.ndarray, columns: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Write the corrective weights of (n, 54) feature moves (metres) into ``out[:, columns]``: ``features @ matrix``
    (:func:`corrective_matrix`) clipped to 0..1.

    >>> c = Corrective("fpc_mouthSmileLeft", "mouthSmileLeft", (20,), 100.0)
    >>> moves = np.zeros((2, 54)); moves[:, 20] = [0.004, 0.02]
    >>> out = drive_correctives(moves, corrective_matrix((c,)), np.array([0]), np.zeros((2, 1), np.float32))
    >>> [round(v, 4) for v in out.ravel().tolist()]
    [0.4, 1.0]
    """
    if columns.size:
        out[:, columns] = np.clip(np.asarray(features, np.float32) @ matrix, 0.0, 1.0)
    return out
