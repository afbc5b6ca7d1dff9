"""How a head's shapes move its face, and driving a timid head as far as the reference head.

Artists sculpt the same ARKit shape with very different strength: the VALID avatars' inner-brow raise moves the
inner brows 2.2 mm at weight 1 where ICT-FaceKit's moves them 5.6 mm (at the same face size). mien's emotion
prototypes are validated on ICT-FaceKit, so on a timid head the same AU intensity shows a weaker face, and an
emotion that reads on ICT does not read there.

A shape is measured where Broekens' 18 feature points sit (:func:`feature_moves`: the mean move of each
feature's iBUG landmarks, :mod:`mien.rig.feature_points`, in millimetres at a 90 mm outer-eye-corner distance)
and compared with the reference head's moves of the same shape (``data/arkit_feature_moves.csv``, measured on
ICT-FaceKit). :func:`calibrate_amplitudes` scales a target by the gain that brings its moves nearest the
reference's (least squares over the 18 points' moves: ``<own, reference> / <own, own>``; a Left/Right pair gets
the mean of its two) when that gain is at least :data:`MIN_SHORTFALL`, at most :data:`MAX_GAIN`; targets are never
weakened. The gain is taken along the
reference's own pattern, not from the largest move alone: the VALID brow lowerer drops the inner brows where
ICT's pulls them together, and matching its largest move to ICT's (x2.5) made it drop them three times as far
as ICT's, so a sad brow (AU1 with AU4) sank instead of slanting up. The gains are the rig's
:attr:`~mien.rig.model.Rig.shape_gains` (reported by ``mien head inspect``), and a file head's name rows carry them,
so a file written with the head's own names plays the same face. A rig driven through its VRM emotion presets is
left as it is (its targets are blends of whole-face presets, whose strength is their author's choice).
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np

from mien.fileio.tables import read_table
from mien.rig.feature_points import FEATURE_NAMES, feature_specs
from mien.rig.files.head import FileRig
from mien.rig.model import MorphTarget, Rig

__all__ = [
    "MAX_GAIN",
    "MIN_SHORTFALL",
    "calibrate_amplitudes",
    "calibration_gain",
    "face_scale_mm",
    "feature_moves",
    "reference_moves",
]

MAX_GAIN = 2.5
"""Largest factor put on a shape: beyond it a sculpted shape's flaws (flat spots, lid folds) show."""

MIN_SHORTFALL = 1.25
"""A target is scaled only when its best gain is at least this (small differences are the artists' taste, not a
timid head)."""

FACE_SIZE_MM = 90.0
"""The outer-eye-corner distance (iBUG 36 to 45) every move is measured at, millimetres."""


def face_scale_mm(rig: Rig) -> float:
    """Millimetres at :data:`FACE_SIZE_MM` per metre of ``rig`` (its own outer eye corners' distance)."""
    landmarks = rig.landmarks.astype(np.int64)
    interocular = float(np.linalg.norm(rig.neutral[landmarks[45]] - rig.neutral[landmarks[36]]))
    return FACE_SIZE_MM / interocular


@cache
def reference_moves() -> dict[str, np.ndarray]:
    """ARKit target -> (18, 3) float64 moves (mm at a 90 mm face, rig x, y, z) of the feature points
    (:data:`mien.rig.feature_points.FEATURE_NAMES` order) on the reference head at weight 1
    (``data/arkit_feature_moves.csv``; a feature it does not list stays still)."""
    out: dict[str, np.ndarray] = {}
    for row in read_table("mien.heads", "data/arkit_feature_moves.csv"):
        moves = out.setdefault(row["arkit"], np.zeros((len(FEATURE_NAMES), 3)))
        moves[FEATURE_NAMES.index(row["feature"])] = [float(row["dx_mm"]), float(row["dy_mm"]), float(row["dz_mm"])]
    for moves in out.values():
        moves.setflags(write=False)
    return out


def feature_moves(rig: Rig, names: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """Target name -> (18, 3) float64 mean move of each feature point's iBUG landmark vertices at weight 1, mm at a
    90 mm outer-eye-corner distance, for ``names`` (default: every target the rig has)."""
    landmarks = rig.landmarks.astype(np.int64)
    scale = face_scale_mm(rig)
    members = [landmarks[list(spec.landmarks)] for spec in feature_specs()]
    out = {}
    for target in rig.targets:
        if names is not None and target.name not in names:
            continue
        dense = np.zeros((rig.n_vertices, 3))
        dense[target.vertex_ids] = target.deltas
        out[target.name] = np.stack([dense[ids].mean(axis=0) for ids in members]) * scale
    return out


def calibration_gain(own: np.ndarray, reference: np.ndarray) -> float:
    """The factor on ``own`` moves (18, 3) that brings them nearest ``reference`` (least squares); 0 when either
    is still or they point apart."""
    a, b = np.asarray(own, np.float64).ravel(), np.asarray(reference, np.float64).ravel()
    power = float(a @ a)
    return max(0.0, float(a @ b) / power) if power > 0.0 else 0.0


def calibrate_amplitudes(rig: Rig) -> tuple[Rig, dict[str, float]]:
    """``rig`` with each timid ARKit target scaled toward the reference (see the module doc), and the gains."""
    info = getattr(rig, "info", None)
    if info is not None and info.names.presets:
        return rig, {}  # whole-face presets, driven by projection: their strength is their author's
    reference = reference_moves()
    measured = feature_moves(rig, tuple(reference))
    best = {name: calibration_gain(moves, reference[name]) for name, moves in measured.items()}
    for name in list(best):  # a Left/Right pair gets one gain, their mean: a face's halves are sculpted alike
        if name.endswith("Left") and (twin := name[: -len("Left")] + "Right") in best:
            best[name] = best[twin] = 0.5 * (best[name] + best[twin])
    gains = {name: round(min(MAX_GAIN, gain), 3) for name, gain in best.items() if gain >= MIN_SHORTFALL}
    if not gains:
        return rig, {}
    targets = tuple(
        MorphTarget(t.name, t.vertex_ids, t.deltas * np.float32(gains[t.name])) if t.name in gains else t
        for t in rig.targets
    )
    shape_gains = {**rig.shape_gains, **{name: rig.shape_gains.get(name, 1.0) * gain for name, gain in gains.items()}}
    calibrated = replace(rig, targets=targets, shape_gains=shape_gains)
    if isinstance(calibrated, FileRig) and calibrated.info is not None:
        rows = {
            name: tuple((shape, weight * gains.get(name, 1.0), side) for shape, weight, side in source)
            for name, source in calibrated.info.source_names.items()
        }
        calibrated = replace(calibrated, info=replace(calibrated.info, source_names=rows))
    return calibrated, gains
