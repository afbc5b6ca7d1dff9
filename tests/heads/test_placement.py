"""A head read in a file's own unit and axes, placed in mien's frame: ICT-FaceKit re-written Blender-style comes
back to where mien's own ICT loader puts it."""

from __future__ import annotations

import numpy as np
import pytest

from mien.heads.placement import place_rig


@pytest.fixture(scope="module")
def placed(ict_zup):  # type: ignore[no-untyped-def]
    moved, found = ict_zup
    return place_rig(moved, found, name="ict-from-file")


def test_the_placed_head_is_icts_own_up_to_where_the_eyes_are(ict, placed) -> None:  # type: ignore[no-untyped-def]
    native, _ = ict
    shift = (placed.neutral - native.neutral).mean(axis=0)
    assert np.linalg.norm(shift) < 0.006  # the eyes' midpoint from the lids, against ICT's eyeball meshes
    np.testing.assert_allclose(placed.neutral - shift, native.neutral, atol=2e-5)
    np.testing.assert_allclose(placed.eye_centers - shift, native.eye_centers, atol=0.006)


def test_target_deltas_turn_and_scale_with_the_mesh(ict, placed) -> None:  # type: ignore[no-untyped-def]
    native, _ = ict
    for name in ("jawOpen", "mouthSmileLeft", "browInnerUp"):
        np.testing.assert_allclose(placed.target(name).deltas, native.target(name).deltas, atol=1e-6)
        np.testing.assert_array_equal(placed.target(name).vertex_ids, native.target(name).vertex_ids)


def test_the_placed_head_has_landmarks_and_a_head_region(placed) -> None:  # type: ignore[no-untyped-def]
    assert placed.landmarks.shape == (68,)
    assert len(placed.regions["head"]) == placed.n_vertices
    eyes_right, eyes_left = placed.neutral[placed.landmarks[36]], placed.neutral[placed.landmarks[45]]
    assert eyes_left[0] > 0.03 and eyes_right[0] < -0.03  # +x is the character's left
    assert placed.neutral[placed.landmarks[8]][1] < -0.08  # the chin is below the eyes
    assert placed.neutral[placed.landmarks[30]][2] > 0.01  # the nose tip is in front of them
