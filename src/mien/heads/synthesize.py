"""ARKit targets a head lacks, made from the reference head's moves through Broekens' feature-point fields.

Many rigs lack a few of the shapes mien's AUs drive: the Rocketbox heads of the VALID library have no lip
stretcher (``mouthStretchLeft``/``Right``: AU20, the mouth of fear) and no lip presser. Without them an AU shows
nothing and the emotion built on it reads as another (fear as anger). :func:`synthesize_targets` makes each
missing ARKit target that the reference table knows (``data/arkit_feature_moves.csv``, :mod:`mien.heads.amplitude`)
from the feature-point rig compiled on the head (:class:`mien.rig.feature_points.FeaturePointRig`): each feature's
smooth field moved by the reference's move of that feature at weight 1, scaled to the head's face size. So only
the skin of the features the shape moves moves (a lip stretcher moves the lips and mouth corners, nothing of the
brows), the shape is the smoothest skin through the reference's moves, and it is as strong as the reference's.
"""

from __future__ import annotations

import io

import numpy as np

from mien.fileio.streams import write_bytes
from mien.heads.amplitude import face_scale_mm, reference_moves
from mien.heads.instrument import INSTRUMENT_VERSION
from mien.paths import cache_dir
from mien.rig.feature_points import FeaturePointRig
from mien.rig.model import MorphTarget, Rig

__all__ = ["MIN_FEATURE_MOVE_MM", "SYNTHESIS_VERSION", "missing_targets", "synthesize_cached", "synthesize_targets"]

SYNTHESIS_VERSION = 2  # 2: the feature-point cheek bunches forward (rig 103b794)
"""Bumped when the method or the reference table changes, so cached shapes of an older method are remade."""

MIN_FEATURE_MOVE_MM = 0.5
"""A reference move smaller than this (mm at a 90 mm face) is left out of a synthesized shape: the reference's
faint pulls of far features (a lip stretcher's 0.3 mm at the nostrils) are its sculpting, not the action."""


def missing_targets(rig: Rig) -> tuple[str, ...]:
    """The ARKit targets of the reference table that ``rig`` lacks, in the table's order; none for a rig driven
    through VRM emotion presets (its faces are its author's)."""
    info = getattr(rig, "info", None)
    if info is not None and info.names.presets:
        return ()
    have = set(rig.target_names)
    return tuple(name for name in reference_moves() if name not in have)


def synthesize_targets(
    rig: Rig, names: tuple[str, ...] | None = None, fp: FeaturePointRig | None = None
) -> tuple[Rig, tuple[str, ...]]:
    """``rig`` with the targets ``names`` (default: :func:`missing_targets`) made from the reference's feature
    moves, and the names made. ``fp``: the feature-point rig already built on ``rig`` (built here otherwise)."""
    wanted = missing_targets(rig) if names is None else tuple(names)
    if not wanted:
        return rig, ()
    reference = reference_moves()
    fields = (fp or FeaturePointRig.build(rig)).compile()  # fp_<Feature>_<axis>: 1 m along the axis
    metres = 1.0 / face_scale_mm(rig)
    made = []
    for name in wanted:
        moves = reference[name].ravel()  # the same feature-major, x/y/z order as the fields
        dense = np.zeros((rig.n_vertices, 3))
        for move, field in zip(moves, fields, strict=True):
            if abs(move) >= MIN_FEATURE_MOVE_MM:
                dense[field.vertex_ids] += move * metres * field.deltas
        ids = np.flatnonzero(np.abs(dense).max(axis=1) > 1e-7).astype(np.int32)
        made.append(MorphTarget(name, ids, dense[ids].astype(np.float32)))
    return rig.with_targets(tuple(made)), wanted


def synthesize_cached(rig: Rig, file_sha256: str) -> tuple[Rig, tuple[str, ...]]:
    """:func:`synthesize_targets` of the missing targets, cached per head file (``file_sha256``, with the
    instrumenting's and this method's versions) in ``$MIEN_CACHE_DIR/heads``: a second load reads the shapes
    (about 2 s of field solving saved). An unreadable cache entry is remade, never trusted."""
    wanted = missing_targets(rig)
    if not wanted:
        return rig, ()
    path = cache_dir("heads") / f"{file_sha256}.synth-{INSTRUMENT_VERSION}-{SYNTHESIS_VERSION}.npz"
    if path.is_file():
        try:
            with np.load(path) as data:
                made = tuple(
                    MorphTarget(name, data[f"{name}.ids"].astype(np.int32), data[f"{name}.deltas"].astype(np.float32))
                    for name in wanted
                )
            if all(len(t.vertex_ids) == len(t.deltas) and t.vertex_ids.max(initial=0) < rig.n_vertices for t in made):
                return rig.with_targets(made), wanted
        except (OSError, KeyError, ValueError):
            pass
    out, wanted = synthesize_targets(rig, wanted)
    arrays = {}
    for target in out.targets[-len(wanted) :]:
        arrays[f"{target.name}.ids"] = target.vertex_ids
        arrays[f"{target.name}.deltas"] = target.deltas
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)  # type: ignore[arg-type]
    write_bytes(buffer.getvalue(), path)
    return out, wanted
