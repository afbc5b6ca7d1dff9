"""Skin-detail correctives of the feature-point rig: anchors stay exact, lids stay still, weights follow the feature."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mien.affect.table1 import table1_vectors
from mien.facs.catalogue import FACE_CHANNELS
from mien.rig.builtin_head import builtin_head
from mien.rig.driver import RigDriver
from mien.rig.feature_points import FEATURE_NAMES, FeaturePointRig, feature_specs, feature_target_names, table1_weights
from mien.rig.fp_correctives import (
    CORRECTIVE_PREFIX,
    corrective_matrix,
    corrective_specs,
    corrective_targets,
    correctives,
    drive_correctives,
)
from mien.rig.geodesic import EdgeGraph
from mien.rig.model import Rig


@pytest.fixture(scope="module")
def rigged() -> tuple[Rig, FeaturePointRig]:
    rig = builtin_head()
    fp = FeaturePointRig.build(rig)
    full = rig.with_targets(fp.compile())
    return full.with_targets(corrective_targets(fp, full)), fp


def test_specs_name_shapes_and_features_the_heads_have() -> None:
    rig = builtin_head()
    specs = corrective_specs()
    assert [s.shape for s in specs[:2]] == ["mouthSmile", "cheekSquint"]
    for spec in specs:
        assert spec.shape in rig.target_names or spec.shape + "Left" in rig.target_names
        assert spec.feature in FEATURE_NAMES or spec.feature + "Left" in FEATURE_NAMES
        assert spec.why.startswith("AU")


def test_each_side_follows_its_own_feature(rigged: tuple[Rig, FeaturePointRig]) -> None:
    rig, _ = rigged
    found = {c.target: c for c in correctives(rig)}
    smile = found["fpc_mouthSmileLeft"]
    corner = 3 * FEATURE_NAMES.index("LipCornerLeft")
    assert smile.sources == (corner, corner + 1)  # its own corner's move in the picture plane (rig x and y)
    own = rig.target("mouthSmileLeft").dense(rig.n_vertices)[rig.landmarks[54], :2]
    assert 1 / smile.gain == pytest.approx(np.linalg.norm(own), rel=0.3)
    # the projection on the shape's own move: its own move drives it by 1, a move across it by 0
    along = np.array(smile.weights)
    assert along @ (np.array(smile.weights) / smile.gain**2) == pytest.approx(1.0)
    assert along @ np.array([-smile.weights[1], smile.weights[0]]) == pytest.approx(0.0, abs=1e-9)
    assert along[0] > 0 and along[1] > 0  # up and out to the character's left
    assert found["fpc_browDownLeft"].gain < 0  # driven by a fall
    # the built-in head has one browInnerUp: both inner brows drive it; both nostril wings follow the Nostrils
    assert found["fpc_browInnerUp"].sources == tuple(
        3 * FEATURE_NAMES.index(f"BrowInner{s}") + 1 for s in ("Left", "Right")
    )
    assert (
        found["fpc_noseSneerLeft"].sources
        == found["fpc_noseSneerRight"].sources
        == (3 * FEATURE_NAMES.index("Nostrils") + 1,)
    )
    assert correctives(builtin_head()) == ()  # no feature-point targets: nothing to drive


def test_anchors_keep_their_table1_moves_and_lids_stay_still(rigged: tuple[Rig, FeaturePointRig]) -> None:
    rig, fp = rigged
    graph = EdgeGraph.from_mesh(np.asarray(rig.neutral, np.float64), rig.faces)
    chains = [(a, b) for spec in feature_specs() for a, b in itertools.pairwise(spec.margin)]
    margins = np.concatenate([graph.path(int(rig.landmarks[a]), int(rig.landmarks[b])) for a, b in chains])
    for target in (t for t in rig.targets if t.name.startswith(CORRECTIVE_PREFIX)):
        dense = target.dense(rig.n_vertices)
        assert np.abs(dense[fp.anchors]).max() < 1e-6, target.name
        # lid margins stay (but for 1.5 mm toward the eye corners, where a lid's own field fades)
        assert np.abs(dense[margins]).max() < 2e-3, target.name
        assert np.median(np.abs(dense[margins]).max(axis=1)) < 1e-5, target.name
        assert np.abs(dense).max() > 5e-4, target.name  # it carries detail between the anchors


def _weights(rig: Rig, emotion: str, intensity: float) -> dict[str, float]:
    from mien.affect.emotions import emotion_vector

    moves = table1_weights(np.tensordot(emotion_vector(emotion, intensity), table1_vectors(), axes=1))
    features = np.array([[moves[name] for name in feature_target_names()]])
    weights = RigDriver(rig).weights(np.zeros((1, len(FACE_CHANNELS))), features)[0]
    return dict(zip(rig.target_names, weights.tolist(), strict=True))


def test_the_driver_follows_the_feature_within_the_shapes_range(rigged: tuple[Rig, FeaturePointRig]) -> None:
    rig, _ = rigged
    joy, joy_strong, sad = _weights(rig, "joy", 0.5), _weights(rig, "joy", 2.4), _weights(rig, "sadness", 2.4)
    smile = next(c for c in correctives(rig) if c.target == "fpc_mouthSmileLeft")
    out_up = [joy["fp_LipCornerLeft_x"], joy["fp_LipCornerLeft_y"]]  # after the barrier limit, as the driver shows it
    assert joy["fpc_mouthSmileLeft"] == pytest.approx(min(float(np.dot(out_up, smile.weights)), 1.0), rel=1e-5)
    assert 0 < joy["fpc_mouthSmileLeft"] < joy_strong["fpc_mouthSmileLeft"] == 1.0  # never past the artist's shape
    assert sad["fpc_mouthSmileLeft"] == 0.0  # corners down: no smile detail
    assert sad["fpc_browInnerUp"] > 0 and sad["fpc_browDownLeft"] == 0.0
    assert _weights(rig, "disgust", 1.2)["fpc_noseSneerLeft"] > 0


def test_drive_correctives_clips_to_the_shape_range(rigged: tuple[Rig, FeaturePointRig]) -> None:
    rig, _ = rigged
    found = {c.target: c for c in correctives(rig)}
    smile, inner = found["fpc_mouthSmileLeft"], found["fpc_browInnerUp"]
    moves = np.zeros((3, 54))
    for source, weight in zip(smile.sources, smile.weights, strict=True):  # along the shape's own move
        moves[:, source] = np.array([-0.01, 0.5, 1.0]) * weight / smile.gain**2
    moves[:, inner.sources[0]] = [0.0, 0.6 / inner.gain, 0.0]  # one inner brow up, the other still: half
    out = drive_correctives(moves, corrective_matrix((smile, inner)), np.array([1, 2]), np.zeros((3, 3), np.float32))
    np.testing.assert_allclose(out[:, 1], [0.0, 0.5, 1.0], rtol=1e-6)
    np.testing.assert_allclose(out[:, 2], [0.0, 0.3, 0.0], rtol=1e-6)
    assert not out[:, 0].any()


def test_a_gain_on_a_heads_shape_is_divided_out(rigged: tuple[Rig, FeaturePointRig]) -> None:
    """Correctives use the shape as shipped: a head whose browDown mien doubles (ICT) gets the same skin detail."""
    import dataclasses

    full, fp = rigged
    base = builtin_head()
    doubled = tuple(
        dataclasses.replace(t, deltas=t.deltas * 2.0) if t.name.startswith("browDown") else t for t in base.targets
    )
    gained = dataclasses.replace(
        base, targets=doubled, shape_gains={"browDownLeft": 2.0, "browDownRight": 2.0}
    ).with_targets(fp.compile())
    assert gained.shape_gains == {"browDownLeft": 2.0, "browDownRight": 2.0}  # with_targets keeps them
    ours = {c.target: c for c in correctives(gained)}
    for c in correctives(full):
        assert ours[c.target].gain == pytest.approx(c.gain)
    for a, b in zip(corrective_targets(fp, gained), corrective_targets(fp, full), strict=True):
        np.testing.assert_allclose(a.dense(full.n_vertices), b.dense(full.n_vertices), atol=1e-7)
