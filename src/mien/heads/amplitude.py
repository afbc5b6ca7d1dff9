"""How far a head's shapes move its face, and driving a timid head as far as the reference head.

Artists sculpt the same ARKit shape with very different strength: the VALID avatars' inner-brow raise moves the
brow 2.4 mm at weight 1 where ICT-FaceKit's moves it 5.6 mm (at the same face size). mien's emotion prototypes
are validated on ICT-FaceKit, so on a timid head the same AU intensity shows a weaker face, and an emotion that
reads on ICT does not read there. :func:`calibrate_amplitudes` measures each ARKit target of a head
(:func:`target_amplitudes`: the largest displacement of the 68 landmarks, at a 90 mm outer-eye-corner distance)
against the reference table ``data/arkit_amplitudes.csv`` and scales a target that moves less by
``reference / amplitude``, at most :data:`MAX_GAIN` (a shape pushed further starts to show its sculpting's
limits). Targets are never weakened. The gains are the rig's :attr:`~mien.rig.model.Rig.shape_gains` (reported
by ``mien head inspect``), and a file head's name rows carry them, so a file written with the head's own names
plays the same face. A rig driven through its VRM emotion presets is left as it is (its targets are blends of
whole-face presets, whose strength is their author's choice).
"""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np

from mien.fileio.tables import read_table
from mien.rig.files.head import FileRig
from mien.rig.model import MorphTarget, Rig

__all__ = ["MAX_GAIN", "MIN_SHORTFALL", "calibrate_amplitudes", "reference_amplitudes", "target_amplitudes"]

MAX_GAIN = 2.5
"""Largest factor put on a shape: beyond it a sculpted shape's flaws (flat spots, lid folds) show."""

MIN_SHORTFALL = 1.25
"""A target is scaled only when the reference moves at least this many times as far (small differences are the
artists' taste, not a timid head)."""

_FACE_SIZE_MM = 90.0


@cache
def reference_amplitudes() -> dict[str, float]:
    """ARKit target -> millimetres its reference moves the face at weight 1 (``data/arkit_amplitudes.csv``)."""
    return {row["arkit"]: float(row["reference_mm"]) for row in read_table("mien.heads", "data/arkit_amplitudes.csv")}


def target_amplitudes(rig: Rig, names: tuple[str, ...] | None = None) -> dict[str, float]:
    """Target name -> the largest displacement of the rig's 68 landmark vertices at weight 1, in millimetres at a
    90 mm outer-eye-corner distance (iBUG 36 to 45), for ``names`` (default: every target the rig has)."""
    landmarks = rig.landmarks.astype(np.int64)
    interocular = float(np.linalg.norm(rig.neutral[landmarks[45]] - rig.neutral[landmarks[36]]))
    position = np.full(rig.n_vertices, -1, np.int64)
    position[landmarks] = np.arange(len(landmarks))
    out = {}
    for target in rig.targets:
        if names is not None and target.name not in names:
            continue
        rows = position[target.vertex_ids]
        moved = rows >= 0
        largest = float(np.linalg.norm(target.deltas[moved], axis=1).max()) if moved.any() else 0.0
        out[target.name] = largest / interocular * _FACE_SIZE_MM
    return out


def calibrate_amplitudes(rig: Rig) -> tuple[Rig, dict[str, float]]:
    """``rig`` with each timid ARKit target scaled toward the reference (see the module doc), and the gains."""
    info = getattr(rig, "info", None)
    if info is not None and info.names.presets:
        return rig, {}  # whole-face presets, driven by projection: their strength is their author's
    reference = reference_amplitudes()
    measured = target_amplitudes(rig, tuple(reference))
    gains = {}
    for name, amplitude in measured.items():
        wanted = reference[name]
        if amplitude > 0.0 and wanted >= MIN_SHORTFALL * amplitude:
            gains[name] = round(min(MAX_GAIN, wanted / amplitude), 3)
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
