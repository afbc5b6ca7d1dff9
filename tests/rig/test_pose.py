"""Head and gaze rotation: sign conventions, pivots, regions, batches and bad input."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.rig.ict_facekit import load_ict_facekit
from mien.rig.model import Rig
from mien.rig.pose import apply_pose, apply_pose_batch, head_rotation

PIVOT = np.array([0.0, -0.09, -0.04], np.float32)


def _rig() -> Rig:
    """Vertices: 0 nose tip, 1 crown, 2 left-eye front, 3 right-eye front, 4 a point outside the head region."""
    neutral = np.array([[0.0, -0.03, 0.1], [0.0, 0.1, 0.0], [0.03, 0.0, 0.012], [-0.03, 0.0, 0.012], [0.0, -0.3, 0.0]])
    eye_centers = np.array([[0.03, 0.0, 0.0], [-0.03, 0.0, 0.0]])
    regions = {"eye_L": np.array([2]), "eye_R": np.array([3]), "head": np.array([0, 1, 2, 3])}
    return Rig(
        "points", neutral, np.array([[0, 1, 2]]), (), np.zeros(68, int), regions,
        eye_centers=eye_centers, neck_pivot=PIVOT,
    )  # fmt: skip


def test_zero_pose_is_identity() -> None:
    rig = _rig()
    np.testing.assert_array_equal(apply_pose(rig, rig.neutral, np.zeros(3), np.zeros(2)), rig.neutral)


def test_head_signs() -> None:
    rig = _rig()
    nose, crown = rig.neutral[0], rig.neutral[1]
    yaw = apply_pose(rig, rig.neutral, [20.0, 0.0, 0.0], [0.0, 0.0])
    assert yaw[0, 0] > nose[0] + 0.01  # yaw > 0: the nose turns to the character's left (+x)
    pitch = apply_pose(rig, rig.neutral, [0.0, 20.0, 0.0], [0.0, 0.0])
    assert pitch[0, 1] > nose[1] + 0.01  # pitch > 0: chin up, the nose rises
    roll = apply_pose(rig, rig.neutral, [0.0, 0.0, 20.0], [0.0, 0.0])
    assert roll[1, 0] > crown[0] + 0.02  # roll > 0: the crown tilts toward the left shoulder (+x)
    # Rigid about the pivot; vertices outside the head region stay put.
    for posed in (yaw, pitch, roll):
        np.testing.assert_allclose(
            np.linalg.norm(posed[:4] - PIVOT, axis=1), np.linalg.norm(rig.neutral[:4] - PIVOT, axis=1), rtol=1e-5
        )
        np.testing.assert_array_equal(posed[4], rig.neutral[4])


def test_gaze_signs_and_eye_centres() -> None:
    rig = _rig()
    left = apply_pose(rig, rig.neutral, [0.0, 0.0, 0.0], [30.0, 0.0])
    assert left[2, 0] > rig.neutral[2, 0] + 0.004 and left[3, 0] > rig.neutral[3, 0] + 0.004
    np.testing.assert_allclose(np.linalg.norm(left[2] - rig.eye_centers[0]), 0.012, rtol=1e-5)
    np.testing.assert_array_equal(left[[0, 1, 4]], rig.neutral[[0, 1, 4]])  # only the eyes move
    up = apply_pose(rig, rig.neutral, [0.0, 0.0, 0.0], [0.0, 30.0])
    assert up[2, 1] > 0.004 and up[3, 1] > 0.004


def test_rotation_matrices() -> None:
    np.testing.assert_allclose(head_rotation(90.0, 0.0, 0.0) @ [0, 0, 1], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(head_rotation(0.0, 90.0, 0.0) @ [0, 0, 1], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(head_rotation(0.0, 0.0, 90.0) @ [0, 1, 0], [1, 0, 0], atol=1e-12)
    r = head_rotation(17.0, -8.0, 5.0)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


def test_batch_equals_single() -> None:
    rig = _rig()
    rng = np.random.default_rng(0)
    vertices = rig.neutral + rng.normal(0, 0.001, (6, rig.n_vertices, 3)).astype(np.float32)
    head, gaze = rng.uniform(-30, 30, (6, 3)), rng.uniform(-20, 20, (6, 2))
    batch = apply_pose_batch(rig, vertices, head, gaze)
    for b in range(6):
        np.testing.assert_allclose(batch[b], apply_pose(rig, vertices[b], head[b], gaze[b]), atol=1e-7)


def test_bad_input() -> None:
    rig = _rig()
    with pytest.raises(InvalidValueError, match="head_ypr_deg"):
        apply_pose(rig, rig.neutral, [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(InvalidValueError, match="gaze_yp_deg"):
        apply_pose(rig, rig.neutral, [0.0, 0.0, 0.0], [np.inf, 0.0])
    with pytest.raises(InvalidValueError, match="vertices"):
        apply_pose(rig, rig.neutral[:3], [0.0, 0.0, 0.0], [0.0, 0.0])


def test_ict_gaze_turns_the_eyeballs_only(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    with pytest.MonkeyPatch.context() as patch:
        if "MIEN_CACHE_DIR" not in os.environ:
            patch.setenv("MIEN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mien-cache"))
        rig = load_ict_facekit(ict_dir)
    posed = apply_pose(rig, rig.neutral, [0.0, 0.0, 0.0], [20.0, 10.0])
    for side in ("eye_L", "eye_R"):
        ids = rig.regions[side]
        front = ids[np.argmax(rig.neutral[ids, 2])]  # the cornea's apex
        shift = posed[front] - rig.neutral[front]
        assert shift[0] > 0.004 and shift[1] > 0.002  # looks to the character's left and up
    eyes = np.concatenate([rig.regions["eye_L"], rig.regions["eye_R"]])
    others = np.setdiff1d(np.arange(rig.n_vertices), eyes)
    np.testing.assert_array_equal(posed[others], rig.neutral[others])
    turned = apply_pose(rig, rig.neutral, [30.0, 0.0, 0.0], [0.0, 0.0])
    nose = rig.landmarks[30]
    assert turned[nose, 0] > 0.03  # the nose swings toward the character's left
