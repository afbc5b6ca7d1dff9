"""RigDriver: the AU -> target mapping compiled once; weights and pose per tick; face_to_rig uses it."""

from pathlib import Path

import numpy as np
import pytest

from mien.affect.basis import feature_target_names
from mien.character import CharacterBatch
from mien.errors import InvalidValueError
from mien.facs.arkit import ARKIT_NAMES
from mien.facs.catalogue import FACE_CHANNELS, POSE_CHANNELS
from mien.facs.clip import Clip
from mien.rig.animate import face_to_rig
from mien.rig.driver import POSE_COLUMNS, RigDriver
from mien.rig.mapping import AUMapping
from mien.rig.model import MorphTarget, Rig
from mien.small_matmul import SINGLE_THREAD_MNK, matmul_rows

N = len(FACE_CHANNELS)


def _tiny_rig(names: tuple[str, ...]) -> Rig:
    targets = tuple(MorphTarget(name, [0], [[0.0, 0.001, 0.0]]) for name in names)
    return Rig("tiny", np.zeros((3, 3)), np.array([[0, 1, 2]]), targets, np.zeros(68, int))


def test_weights_equal_the_mapping_for_any_batch_size():
    driver = RigDriver()
    mapping = AUMapping.default()
    rng = np.random.default_rng(3)
    for n in (0, 1, 7, 300):  # 300 rows: several single-thread chunks
        frames = rng.uniform(-1.0, 6.0, (n, N))
        weights = driver.weights(frames)
        assert weights.dtype == np.float32 and weights.shape == (n, 52)
        np.testing.assert_allclose(weights, mapping.to_weights(frames), atol=1e-6)
        if n:
            assert weights.min() == 0.0 and weights.max() == 1.0  # clipped
    assert driver.target_names == ARKIT_NAMES


def test_out_buffer_is_filled_in_place_tick_after_tick():
    driver = RigDriver()
    batch = CharacterBatch(np.arange(5))
    batch.emote(slice(None), "joy", 1.5, start_s=0.0)
    out = np.empty((5, 52), np.float32)
    pose = np.empty((5, 5))
    smile = ARKIT_NAMES.index("mouthSmileLeft")
    peak = 0.0
    for i in range(60):
        frames = batch.step(i / 60)
        assert driver.weights(frames, out=out) is out
        assert driver.pose(frames, out=pose) is pose
        np.testing.assert_array_equal(pose, frames[:, [FACE_CHANNELS.index(c) for c in POSE_CHANNELS]])
        peak = max(peak, float(out[:, smile].min()))
    assert peak > 0.5  # every character smiled
    assert POSE_COLUMNS == ("head_yaw_deg", "head_pitch_deg", "head_roll_deg", "gaze_yaw_deg", "gaze_pitch_deg")
    with pytest.raises(InvalidValueError, match="out"):
        driver.weights(frames, out=np.empty((5, 52)))
    with pytest.raises(InvalidValueError, match="out"):
        driver.pose(frames, out=np.empty((4, 5)))
    with pytest.raises(InvalidValueError, match="frames"):
        driver.weights(np.zeros((5, 61)))


def test_rig_columns_feature_targets_and_user_tables(tmp_path: Path):
    names = ("jawOpen", "mouthSmileLeft", *feature_target_names())
    with pytest.warns(UserWarning, match="lacks targets"):
        driver = RigDriver(_tiny_rig(names))
    assert driver.target_names == names and driver.has_feature_targets
    frames = np.zeros((2, N))
    frames[1, FACE_CHANNELS.index("AU12L")] = 5.0
    features = np.full((2, 54), -0.004)
    weights = driver.weights(frames, features)
    assert weights[1, 1] == 1.0 and weights[0, 1] == 0.0
    expected = np.full((2, 54), -0.004)  # signed metres, not clipped
    upper_lids = [k for k, name in enumerate(feature_target_names()) if name.startswith("fp_LidUpper")
                  and name.endswith("_y")]  # fmt: skip
    expected[:, upper_lids] = -0.004 - 0.5 * 0.004  # the lowered inner brows push them down by half (LID_PUSHES)
    np.testing.assert_allclose(weights[:, 2:], expected, rtol=1e-6)
    with pytest.raises(InvalidValueError, match="feature_weights"):
        driver.weights(frames, np.zeros((2, 3)))
    with pytest.warns(UserWarning):
        plain = RigDriver(_tiny_rig(("jawOpen",)))
    with pytest.raises(InvalidValueError, match="feature-point targets"):
        plain.weights(frames, features)
    table = tmp_path / "mine.csv"
    table.write_text("channel,target,weight_at_E\nAU12L,mouthSmileLeft,0.5\n")
    mine = RigDriver(mapping_path=table)
    assert mine.weights(frames)[1, ARKIT_NAMES.index("mouthSmileLeft")] == pytest.approx(0.5)


def test_face_to_rig_is_the_driver():
    rng = np.random.default_rng(1)
    frames = rng.uniform(0.0, 5.0, (20, N))
    rig = _tiny_rig(ARKIT_NAMES)
    weights, poses = face_to_rig(rig, frames)
    np.testing.assert_array_equal(weights, RigDriver(rig).weights(frames))
    np.testing.assert_array_equal(poses, frames[:, -5:])
    clip = Clip(frames[:, :2], 30.0, FACE_CHANNELS[:2])  # a clip over a subset of channels
    sub, _ = face_to_rig(rig, clip)
    full = np.zeros((20, N))
    full[:, :2] = frames[:, :2]
    np.testing.assert_array_equal(sub, RigDriver(rig).weights(full))


def test_matmul_rows_equals_matmul_in_chunks():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(1000, 62)), rng.normal(size=(62, 52))
    out = np.empty((1000, 52))
    assert matmul_rows(a, b, out) is out
    np.testing.assert_allclose(out, a @ b, atol=1e-12)
    assert SINGLE_THREAD_MNK // (62 * 52) < 1000  # the product above really was cut into chunks
