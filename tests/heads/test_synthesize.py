"""ARKit shapes a head lacks, made through the feature-point fields from the reference head's moves; the reference
table is ICT-FaceKit's own moves."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from tests.conftest import valid_avatar

from mien.heads import load_head
from mien.heads import synthesize as synthesize_module
from mien.heads.amplitude import face_scale_mm, feature_moves, reference_moves
from mien.heads.inspect import inspect_head
from mien.heads.synthesize import missing_targets, synthesize_cached, synthesize_targets
from mien.rig.feature_points import FEATURE_NAMES
from mien.rig.files import FileRig

pytest.importorskip("mediapipe", reason="mediapipe not installed (track extra)")
pytest.importorskip("moderngl", reason="moderngl not installed (render extra)")


@pytest.fixture(scope="module")
def white(landmarker_path: Path) -> FileRig:
    rig = load_head(str(valid_avatar()))
    assert isinstance(rig, FileRig)
    return rig


def test_the_reference_table_is_icts_own_moves(ict_dir: Path) -> None:
    from mien.rig.ict_facekit import load_ict_facekit

    ict = load_ict_facekit(ict_dir)
    reference = reference_moves()
    measured = feature_moves(ict, tuple(reference))
    for name, moves in reference.items():
        np.testing.assert_allclose(measured[name][moves != 0], moves[moves != 0], atol=0.006, err_msg=name)
        assert np.abs(measured[name][moves == 0]).max(initial=0.0) < 0.05, name
    assert missing_targets(ict) == ()  # ICT has every shape the table knows


def test_a_rocketbox_head_gets_the_lip_stretcher_it_lacks(white: FileRig) -> None:
    made = {"mouthStretchLeft", "mouthStretchRight", "mouthPressLeft", "mouthPressRight", "mouthShrugUpper"}
    assert made <= set(white.target_names)
    assert white.info is not None and not made & set(white.info.source_names)  # not the file's own shapes
    moves = feature_moves(white, ("mouthStretchLeft", "mouthStretchRight"))
    reference = reference_moves()
    corner = FEATURE_NAMES.index("LipCornerLeft")
    # at its anchor a feature moves exactly by the reference's move, at the head's own face size
    np.testing.assert_allclose(moves["mouthStretchLeft"][corner], reference["mouthStretchLeft"][corner], atol=0.05)
    assert moves["mouthStretchLeft"][corner, 0] > 5.0  # the left corner pulled out to the character's left
    assert moves["mouthStretchRight"][FEATURE_NAMES.index("LipCornerRight"), 0] < -5.0
    # only the lower face's skin moves: nothing of the eyes, brows or teeth, the cheek beside the nose a little
    stretch = white.targets[white.target_names.index("mouthStretchLeft")]
    landmarks = white.neutral[white.landmarks]
    size = np.linalg.norm(stretch.deltas, axis=1)
    moved = stretch.vertex_ids[size > 1e-5]
    assert white.neutral[moved, 1].max() < landmarks[36:48, 1].mean()
    above_tip = white.neutral[stretch.vertex_ids, 1] > landmarks[30, 1]
    assert size[above_tip].max() < 0.4 * size.max()  # measured 3.1 of 9.7 mm
    start, stop = white.info.meshes["H_DDS_HighRes"]
    assert ((moved >= start) & (moved < stop)).all()
    scale = face_scale_mm(white)
    assert float(np.linalg.norm(stretch.deltas, axis=1).max()) * scale < 12.0  # no vertex flies off


def test_a_head_lacking_nothing_is_left_as_it_is(white: FileRig) -> None:
    again, made = synthesize_targets(white)
    assert made == () and again is white


def test_head_inspect_reports_the_synthesized_shapes(landmarker_path: Path) -> None:
    report = inspect_head(str(valid_avatar())).report()
    assert "synthesized (7, the reference head's moves through the feature-point fields):" in report
    assert "mouthStretchLeft" in report and "no mouthStretchLeft" not in report
    assert "no mouthClose: AU8 cannot show" in report  # a correction of another shape: not made


def test_the_shapes_are_made_once_per_file_then_read_from_the_cache(
    white: FileRig, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    monkeypatch.setenv("MIEN_CACHE_DIR", str(tmp_path))
    lacking = replace(white, targets=tuple(t for t in white.targets if t.name not in reference_moves()
                                           or t.name.startswith(("browDown", "jaw"))))  # fmt: skip
    first, made = synthesize_cached(lacking, "0" * 64)
    assert "mouthStretchLeft" in made and "browInnerUp" in made
    calls: list[object] = []
    monkeypatch.setattr(synthesize_module, "synthesize_targets", lambda *args, **kwargs: calls.append(args))
    second, again = synthesize_cached(lacking, "0" * 64)
    assert again == made and not calls  # read back, not remade
    for one, other in zip(first.targets, second.targets, strict=True):
        assert one.name == other.name
        np.testing.assert_array_equal(one.vertex_ids, other.vertex_ids)
        np.testing.assert_array_equal(one.deltas, other.deltas)
    monkeypatch.undo()
    monkeypatch.setenv("MIEN_CACHE_DIR", str(tmp_path))
    (entry,) = (tmp_path / "heads").glob("*.npz")
    entry.write_bytes(b"not an npz")  # a broken entry is remade, not trusted
    third, _ = synthesize_cached(lacking, "0" * 64)
    np.testing.assert_array_equal(third.targets[-1].deltas, first.targets[-1].deltas)
