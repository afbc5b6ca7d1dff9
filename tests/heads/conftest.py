"""ICT-FaceKit instrumented once per session, in its own frame and as a Blender-style file (cm, Z up, facing -y)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

Z_UP_FACING_MINUS_Y = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
"""mien's frame (+y up, +z forward) -> a Blender-style file's (+z up, -y forward)."""


@pytest.fixture(scope="session")
def ict(ict_dir: Path, landmarker_path: Path):  # type: ignore[no-untyped-def]
    pytest.importorskip("mediapipe", reason="mediapipe not installed (track extra)")
    pytest.importorskip("moderngl", reason="moderngl not installed (render extra)")
    from mien.heads.instrument import instrument
    from mien.rig.ict_facekit import load_ict_facekit

    rig = load_ict_facekit(ict_dir)
    return rig, instrument(rig.neutral, rig.faces, landmarker_path, name="ict")


@pytest.fixture(scope="session")
def ict_zup(ict, landmarker_path: Path):  # type: ignore[no-untyped-def]
    """ICT written as a Blender-style file would hold it, and what instrumenting finds on it."""
    from mien.heads.instrument import instrument
    from mien.rig.model import MorphTarget, Rig

    rig, _ = ict
    move = Z_UP_FACING_MINUS_Y * 100.0
    moved = Rig(
        name="ict-cm-zup",
        neutral=rig.neutral.astype(np.float64) @ move.T,
        faces=rig.faces,
        targets=tuple(MorphTarget(t.name, t.vertex_ids, t.deltas.astype(np.float64) @ move.T) for t in rig.targets),
        landmarks=np.zeros(68, np.int32),
        regions={},
    )
    return moved, instrument(moved.neutral, moved.faces, landmarker_path, name="ict-cm-zup")
