"""AU -> ARKit mapping table: coverage, sides, linearity, prototypes, user tables and reordering."""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, OPENFACS_AUS, POSE_CHANNELS, au_channels, channel_index
from mien.rig.deform import Deformer
from mien.rig.ict_facekit import load_ict_facekit
from mien.rig.mapping import AUMapping
from mien.rig.model import MorphTarget, Rig

AU_CHANNELS = [name for name in FACE_CHANNELS if name not in POSE_CHANNELS]
EMFACS = {
    "happiness": (6, 12),
    "sadness": (1, 4, 15),
    "surprise": (1, 2, 5, 26),
    "fear": (1, 2, 4, 5, 7, 20, 26),
    "anger": (4, 5, 7, 23),
    "disgust": (9, 15, 16),
}


def _frame(*aus: int, intensity: float = 5.0) -> np.ndarray:
    frame = np.zeros(len(FACE_CHANNELS))
    for code in aus:
        frame[list(au_channels(code))] = intensity
    return frame


@pytest.fixture(scope="module")
def mapping() -> AUMapping:
    return AUMapping.default()


def test_default_table_shape_and_version(mapping: AUMapping) -> None:
    assert mapping.version == "3"
    assert mapping.target_names == ARKIT_NAMES
    assert mapping.matrix.shape == (62, 52) and mapping.matrix.dtype == np.float32
    pose_rows = [channel_index(name) for name in POSE_CHANNELS]
    assert not np.any(mapping.matrix[pose_rows])


def test_every_au_channel_and_openfacs_au_is_mapped(mapping: AUMapping) -> None:
    for name in AU_CHANNELS:
        assert np.abs(mapping.matrix[channel_index(name)]).max() > 0.02, name
    for code in OPENFACS_AUS:
        assert mapping.to_weights(_frame(code)).max() >= 0.2, f"AU{code}"


def test_sides(mapping: AUMapping) -> None:
    names = mapping.target_names
    frame = _frame()
    frame[channel_index("AU12L")] = 5.0
    left = mapping.to_weights(frame)
    assert left[names.index("mouthSmileLeft")] == 1.0 and left[names.index("mouthSmileRight")] == 0.0
    frame = _frame()
    frame[channel_index("AU46R")] = 5.0
    wink = mapping.to_weights(frame)
    assert wink[names.index("eyeBlinkRight")] == 1.0 and wink[names.index("eyeBlinkLeft")] == 0.0
    # A midline AU drives both sides alike.
    lips_part = mapping.to_weights(_frame(25))
    assert lips_part[names.index("mouthLowerDownLeft")] == lips_part[names.index("mouthLowerDownRight")] > 0
    # Every ...Left target driven by an L channel has the same weight from the matching R channel on ...Right.
    for name in AU_CHANNELS:
        if name.endswith("L"):
            row_l, row_r = mapping.matrix[channel_index(name)], mapping.matrix[channel_index(name[:-1] + "R")]
            for j, target in enumerate(names):
                if target.endswith("Left") and not target.startswith(("jaw", "mouthLeft")):
                    assert row_l[j] == row_r[names.index(target[:-4] + "Right")], (name, target)


def test_linear_in_intensity_and_clipped(mapping: AUMapping) -> None:
    names = mapping.target_names
    half = mapping.to_weights(_frame(12, intensity=2.5))
    assert half[names.index("mouthSmileLeft")] == pytest.approx(1.25 * 2.5 / 5)  # 1.25 at E, linear below the clip
    assert mapping.to_weights(_frame(12, intensity=2.5)).max() <= 1.0
    both = mapping.to_weights(_frame(43, 45, 46))  # three AUs summing past 1 on eyeBlink
    assert both[names.index("eyeBlinkLeft")] == 1.0
    batch = np.stack([_frame(12), _frame(26, intensity=1.0)])[None]  # (1, 2, 62)
    weights = mapping.to_weights(batch)
    assert weights.shape == (1, 2, 52)
    np.testing.assert_array_equal(weights[0, 1], mapping.to_weights(_frame(26, intensity=1.0)))
    # Pose channels are ignored.
    frame = _frame()
    frame[channel_index("head_yaw_deg")] = 30.0
    assert not np.any(mapping.to_weights(frame))
    with pytest.raises(InvalidValueError, match="au_frames"):
        mapping.to_weights(np.zeros(61))


def test_emfacs_prototypes_are_distinct(mapping: AUMapping) -> None:
    vectors = {name: mapping.to_weights(_frame(*aus, intensity=4.0)) for name, aus in EMFACS.items()}
    for (a, va), (b, vb) in itertools.combinations(vectors.items(), 2):
        assert np.linalg.norm(va - vb) > 0.4, (a, b)
    names = mapping.target_names
    assert vectors["happiness"][names.index("mouthSmileLeft")] > 0.5
    assert vectors["surprise"][names.index("jawOpen")] > 0.3 and vectors["surprise"][names.index("eyeWideLeft")] > 0.5


def _write(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "mine.csv"
    path.write_text("# version: 7\nchannel,target,weight_at_E\n" + body)
    return path


def test_user_table(tmp_path: Path) -> None:
    mapping = AUMapping.from_file(_write(tmp_path, "AU12L,mouthSmileLeft,0.5\n# comment\n\nAU25,jawOpen,1\n"))
    assert mapping.version == "7" and mapping.target_names == ARKIT_NAMES
    weights = mapping.to_weights(_frame(12, 25))
    assert weights[ARKIT_NAMES.index("mouthSmileLeft")] == pytest.approx(0.5)
    assert weights[ARKIT_NAMES.index("mouthSmileRight")] == 0.0
    custom = AUMapping.from_file(_write(tmp_path, "AU12L,grin_L,1\nAU12R,grin_R,1\n"), known_targets=None)
    assert custom.target_names == ("grin_L", "grin_R")


@pytest.mark.parametrize(
    ("body", "error", "pattern"),
    [
        ("AU12,mouthSmileLeft,1\n", UnknownNameError, r"AU channel \(.*mine\.csv line 3\) 'AU12'"),
        ("AU12L,mouthSmileLeft,1\nAU99L,mouthSmileLeft,1\n", UnknownNameError, r"line 4\) 'AU99L'"),
        ("AU12L,mouthGrin,1\n", UnknownNameError, r"target \(.*mine\.csv line 3\) 'mouthGrin'"),
        ("AU12L,mouthSmileLeft,lots\n", InvalidValueError, r"weight_at_E \(.*line 3\)='lots'"),
        ("AU12L,mouthSmileLeft,nan\n", InvalidValueError, "weight_at_E"),
        ("AU12L,mouthSmileLeft\n", InvalidValueError, "3 columns"),
        ("AU12L,mouthSmileLeft,1\nAU12L,mouthSmileLeft,1\n", InvalidValueError, "once"),
    ],
)
def test_user_table_errors(tmp_path: Path, body: str, error: type[Exception], pattern: str) -> None:
    with pytest.raises(error, match=pattern):
        AUMapping.from_file(_write(tmp_path, body))


def test_bad_header(tmp_path: Path) -> None:
    path = tmp_path / "h.csv"
    path.write_text("au,blendshape,weight\nAU12L,mouthSmileLeft,1\n")
    with pytest.raises(InvalidValueError, match="header"):
        AUMapping.from_file(path)


def _tiny_rig(names: tuple[str, ...]) -> Rig:
    targets = tuple(MorphTarget(name, [0], [[0.0, 0.001, 0.0]]) for name in names)
    return Rig("tiny", np.zeros((3, 3)), np.array([[0, 1, 2]]), targets, np.zeros(68, int))


def test_weights_for_a_rig_reorders_and_warns(mapping: AUMapping) -> None:
    rig = _tiny_rig(("jawOpen", "extra", "mouthSmileLeft"))
    with pytest.warns(UserWarning, match=r"lacks targets .*eyeBlinkLeft"):
        for_rig = mapping.weights_for(rig)
    assert for_rig.target_names == rig.target_names
    weights = for_rig.to_weights(_frame(12, 27))
    assert weights.tolist() == [1.0, 0.0, 1.0]
    full = AUMapping.default().reordered(ARKIT_NAMES[::-1])
    np.testing.assert_array_equal(full.to_weights(_frame(6, 12))[::-1], mapping.to_weights(_frame(6, 12)))


def test_every_au_moves_the_ict_head(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    """Each AU channel at E moves some vertex of the ICT head by more than 1 mm."""
    with pytest.MonkeyPatch.context() as patch:
        if "MIEN_CACHE_DIR" not in os.environ:
            patch.setenv("MIEN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mien-cache"))
        rig = load_ict_facekit(ict_dir)
    mapping = AUMapping.default().weights_for(rig)
    deformer = Deformer(rig)
    frames = np.zeros((len(AU_CHANNELS), len(FACE_CHANNELS)))
    for row, name in enumerate(AU_CHANNELS):
        frames[row, channel_index(name)] = 5.0
    vertices = deformer.deform_batch(mapping.to_weights(frames))
    motion = np.linalg.norm(vertices - rig.neutral, axis=2).max(axis=1)
    for name, moved in zip(AU_CHANNELS, motion, strict=True):
        assert moved > 0.001, name
    # Distinct EMFACS prototypes give visibly distinct faces.
    faces = deformer.deform_batch(mapping.to_weights(np.stack([_frame(*aus) for aus in EMFACS.values()])))
    for i, j in itertools.combinations(range(len(EMFACS)), 2):
        assert np.abs(faces[i] - faces[j]).max() > 0.002
