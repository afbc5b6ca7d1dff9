"""Expression bases: Table 1 feature points and EMFACS prototypes; linear, geometric intensity, closed mouth."""

from __future__ import annotations

import numpy as np
import pytest

from mien.affect.basis import (
    MOUTH_OPENING_AUS,
    expression,
    facs_basis,
    feature_point_basis,
    feature_target_names,
)
from mien.affect.emotions import BLENDS, EMOTIONS, emotion_vector
from mien.affect.table1 import FEATURE_NAMES, table1_rig_vectors
from mien.errors import InvalidValueError
from mien.facs.catalogue import FACE_CHANNELS
from mien.facs.prototypes import prototype_vector


def test_feature_point_basis_layout() -> None:
    basis = feature_point_basis()
    names = feature_target_names()
    assert basis.shape == (6, 54) and len(names) == 54
    assert names[:3] == ("fp_Jaw_x", "fp_Jaw_y", "fp_Jaw_z") and names[-1] == "fp_BrowOuterRight_z"
    rig = table1_rig_vectors()
    for f, feature in enumerate(FEATURE_NAMES):
        for a, axis in enumerate("xyz"):
            np.testing.assert_array_equal(basis[:, names.index(f"fp_{feature}_{axis}")], rig[:, f, a])
    joy = basis[EMOTIONS.index("joy")]
    assert joy[names.index("fp_LipCornerLeft_x")] == 0.009  # outward, character's left
    assert joy[names.index("fp_LipCornerLeft_y")] == 0.007  # up


def test_closed_mouth_variants() -> None:
    closed = feature_point_basis(closed_mouth=True)
    full = feature_point_basis()
    jaw = [feature_target_names().index(f"fp_Jaw_{a}") for a in "xyz"]
    assert np.all(closed[:, jaw] == 0.0)
    others = [i for i in range(54) if i not in jaw]
    np.testing.assert_array_equal(closed[:, others], full[:, others])
    assert np.any(full[:, jaw] != 0.0)


@pytest.mark.parametrize("blend", sorted(BLENDS))
def test_blend_is_the_sum_of_its_components_and_intensity_is_geometric(blend: str) -> None:
    basis = feature_point_basis()
    components = sum(expression(emotion_vector(e, w * 1.2), basis) for e, w in BLENDS[blend].components)
    # atol: a sum of two products may round differently from the product of the sum (1e-19 m)
    np.testing.assert_allclose(expression(emotion_vector(blend, 1.2), basis), components, atol=1e-15)
    np.testing.assert_allclose(
        expression(emotion_vector(blend, 2.4), basis), 2.0 * expression(emotion_vector(blend, 1.2), basis), atol=1e-15
    )


def test_expression_batches_and_writes_into_out() -> None:
    basis = feature_point_basis()
    batch = np.stack([emotion_vector(e, 1.0) for e in EMOTIONS])
    np.testing.assert_allclose(expression(batch, basis), basis)
    out = np.empty(54)
    assert expression(emotion_vector("fear", 2.0), basis, out=out) is out
    np.testing.assert_allclose(out, 2.0 * basis[EMOTIONS.index("fear")])
    with pytest.raises(InvalidValueError):
        expression(np.ones(5), basis)


def test_facs_basis_from_the_emfacs_prototypes() -> None:
    basis = facs_basis()
    assert basis.shape == (6, len(FACE_CHANNELS))
    for i, emotion in enumerate(EMOTIONS):
        np.testing.assert_array_equal(basis[i], prototype_vector(emotion))
    assert basis[EMOTIONS.index("joy"), FACE_CHANNELS.index("AU12L")] > 0
    assert basis[EMOTIONS.index("surprise"), FACE_CHANNELS.index("AU26")] > 0
    closed = facs_basis(closed_mouth=True)
    mouth = [FACE_CHANNELS.index(c) for c in MOUTH_OPENING_AUS if c in FACE_CHANNELS]
    assert mouth and np.all(closed[:, mouth] == 0.0)
    others = [i for i in range(len(FACE_CHANNELS)) if i not in mouth]
    np.testing.assert_array_equal(closed[:, others], basis[:, others])
    doubled = expression(emotion_vector("evil", 2.0), basis)
    np.testing.assert_allclose(doubled, 2.0 * expression(emotion_vector("evil", 1.0), basis))
