"""ICT-FaceKit loader: units, axes, sides, landmarks, regions, identities, cache and bad folders."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError
from mien.facs.arkit import ARKIT_NAMES
from mien.rig.ict_facekit import (
    ICT_EXTRA_TARGETS,
    ICT_TARGET_GAINS,
    ict_cache_file,
    ict_identity_presets,
    ict_missing_files,
    load_ict_facekit,
)
from mien.rig.model import Rig
from mien.rig.obj import read_obj, read_obj_vertices

# Targets whose Left/Right is a direction of motion, not a side of the face.
_DIRECTIONAL = {"jawLeft", "jawRight", "mouthLeft", "mouthRight"}


@pytest.fixture(scope="module")
def ict(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Rig:
    """The ICT head (parsed once per session into the session's cache dir)."""
    with pytest.MonkeyPatch.context() as patch:
        if "MIEN_CACHE_DIR" not in os.environ:
            patch.setenv("MIEN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mien-cache"))
        return load_ict_facekit(ict_dir)


def _motion(rig: Rig, name: str) -> np.ndarray:
    """(n_vertices,) displacement length of target ``name`` at weight 1, metres."""
    return np.linalg.norm(rig.target(name).dense(rig.n_vertices), axis=1)


def test_mesh_size_targets_and_units(ict: Rig) -> None:
    assert ict.n_vertices == 26719
    assert ict.faces.shape == (25836 * 2 + 548, 3)  # quads split in two, plus the triangles
    assert ict.target_names == ARKIT_NAMES + ICT_EXTRA_TARGETS
    assert len(ict.target("tongueOut").vertex_ids) == 0  # ICT has no tongue shape
    # Metres: eyeball centres about 6.2 cm apart, head about 25 cm wide.
    assert 0.055 < ict.eye_centers[0, 0] - ict.eye_centers[1, 0] < 0.07
    assert 0.2 < np.ptp(ict.neutral[:, 0]) < 0.3
    # Origin midway between the eyes; the character's left eye at +x.
    np.testing.assert_allclose(ict.eye_centers.mean(axis=0), 0.0, atol=1e-6)
    assert ict.eye_centers[0, 0] > 0 and ict.neutral[ict.regions["eye_L"], 0].min() > 0
    assert ict.neutral[ict.regions["eye_R"], 0].max() < 0
    # +z forward: the nose tip is the most forward landmark; neck pivot behind and below the eyes.
    assert ict.neutral[ict.landmarks[30], 2] == ict.neutral[ict.landmarks, 2].max()
    assert ict.neck_pivot[1] < -0.03 and ict.neck_pivot[2] < -0.05


def test_landmarks_sit_where_they_should(ict: Rig) -> None:
    points = ict.neutral[ict.landmarks]
    eye_corners = points[[36, 39, 42, 45]]
    assert np.all(np.abs(eye_corners[:, 1]) < 0.01)  # at eye height (origin = eye centres)
    nose_base_y = points[33, 1]
    assert points[48, 1] < nose_base_y and points[54, 1] < nose_base_y  # mouth corners below the nose
    assert points[8, 1] == points[:, 1].min()  # chin lowest
    left = [*range(9, 17), *range(22, 27), *range(42, 48), 54]  # iBUG: the subject's left side
    right = [*range(0, 8), *range(17, 22), *range(36, 42), 48]
    assert np.all(points[left, 0] > 0.005) and np.all(points[right, 0] < -0.005)
    assert points[27:31, 1].tolist() == sorted(points[27:31, 1].tolist(), reverse=True)  # nose bridge downward


def test_regions(ict: Rig) -> None:
    assert len(ict.regions["head"]) == ict.n_vertices
    lips = ict.neutral[ict.regions["lips"]]
    points = ict.neutral[ict.landmarks]
    assert 300 < len(lips) < 3000
    assert lips[:, 1].max() < points[33, 1] and lips[:, 1].min() > points[8, 1]
    for side, sign in (("L", 1), ("R", -1)):
        for part in ("eye_socket", "eyelashes", "iris"):
            assert sign * ict.neutral[ict.regions[f"{part}_{side}"], 0].mean() > 0.01


def test_each_sided_target_moves_its_own_side(ict: Rig) -> None:
    x = ict.neutral[:, 0]
    for name in ict.target_names:
        if name in _DIRECTIONAL or not name.endswith(("Left", "Right")):
            continue
        motion = _motion(ict, name)
        own, other = (x > 0.005, x < -0.005) if name.endswith("Left") else (x < -0.005, x > 0.005)
        assert motion[own].sum() > 4 * motion[other].sum(), name


def test_targets_move_their_region(ict: Rig) -> None:
    nose_tip_y = ict.neutral[ict.landmarks[30], 1]
    for name in ict.target_names:
        motion = _motion(ict, name)
        if name == "tongueOut":
            continue
        assert motion.max() > 0.001, name  # every ICT shape moves something by more than 1 mm
        centre_y = (ict.neutral[:, 1] * motion).sum() / motion.sum()
        if name.startswith(("eye", "brow", "pupil")):
            assert centre_y > nose_tip_y, name
        if name.startswith(("mouth", "jaw")):
            assert centre_y < nose_tip_y, name


def test_eye_blink_left_closes_the_left_lids_only(ict: Rig) -> None:
    motion = _motion(ict, "eyeBlinkLeft")
    delta = ict.target("eyeBlinkLeft").dense(ict.n_vertices)
    x, y = ict.neutral[:, 0], ict.neutral[:, 1]
    upper_lid = (x > 0.01) & (y > 0.0) & (y < 0.02) & (motion > 0.003)
    assert upper_lid.sum() > 50 and delta[upper_lid, 1].mean() < -0.003  # the left upper lid comes down
    assert motion[x < -0.005].max() < 0.05 * motion.max()  # the right eye stays open
    mouth = y < ict.neutral[ict.landmarks[33], 1]
    assert motion[mouth].max() < 0.0005  # the mouth does not move
    assert motion[ict.regions["eye_L"]].max() < 0.0005  # lids move, not the eyeball


def test_cached_load_equals_fresh_load(ict: Rig, ict_dir: Path) -> None:
    assert ict_cache_file(ict_dir).is_file()
    fresh = load_ict_facekit(ict_dir, cache=False)
    cached = load_ict_facekit(ict_dir)
    for rig in (fresh, cached):
        np.testing.assert_array_equal(rig.neutral, ict.neutral)
        np.testing.assert_array_equal(rig.faces, ict.faces)
        np.testing.assert_array_equal(rig.landmarks, ict.landmarks)
        np.testing.assert_array_equal(rig.eye_centers, ict.eye_centers)
        assert rig.regions.keys() == ict.regions.keys()
        for a, b in zip(rig.targets, ict.targets, strict=True):
            assert a.name == b.name
            np.testing.assert_array_equal(a.vertex_ids, b.vertex_ids)
            np.testing.assert_array_equal(a.deltas, b.deltas)


def test_brow_lowerer_is_the_shipped_shape_times_its_gain(ict: Rig, ict_dir: Path) -> None:
    assert ICT_TARGET_GAINS == {"browDownLeft": 2.0, "browDownRight": 2.0}
    assert ict.shape_gains == ICT_TARGET_GAINS
    model = ict_dir / "FaceXModel"
    neutral = read_obj_vertices(model / "generic_neutral_mesh.obj")
    for target, ict_file, gain in (("browDownLeft", "browDown_L", 2.0), ("browOuterUpLeft", "browOuterUp_L", 1.0)):
        shipped = (read_obj_vertices(model / f"{ict_file}.obj") - neutral) * 0.01  # cm -> m
        ours = ict.target(target).dense(ict.n_vertices)
        np.testing.assert_allclose(ours, gain * shipped, atol=gain * 1.5e-5)  # sparse: moves under 0.01 mm dropped
    # the brow now comes about 7 mm down at weight 1 (Table 1's angry inner brow: 12 mm; ICT as shipped: 3.4 mm)
    down = ict.target("browDownLeft").dense(ict.n_vertices)
    moved = np.argsort(np.linalg.norm(down, axis=1))[-50:]
    assert -0.008 < down[moved, 1].mean() < -0.006


def test_identity_presets_give_different_faces(ict: Rig, ict_dir: Path) -> None:
    presets = ict_identity_presets()
    assert {"mean", "a", "b"} <= presets.keys() and all(p.shape == (16,) for p in presets.values())
    a = load_ict_facekit(ict_dir, identity=presets["a"])
    b = load_ict_facekit(ict_dir, identity=presets["b"])
    mean = load_ict_facekit(ict_dir, identity=presets["mean"])
    np.testing.assert_allclose(mean.neutral, ict.neutral, atol=1e-7)
    difference = np.linalg.norm(a.neutral - b.neutral, axis=1)
    assert difference.max() > 0.02 and difference[:9409].mean() > 0.004  # centimetres apart over the face
    np.testing.assert_allclose(a.eye_centers.mean(axis=0), 0.0, atol=1e-6)  # re-centred per identity
    assert a.targets[0] is not None and a.target_names == ict.target_names


@pytest.mark.parametrize("bad", [np.zeros(15), np.full(16, np.nan), [[0.0] * 16]])
def test_bad_identity(ict_dir: Path, bad: object) -> None:
    with pytest.raises(InvalidValueError, match="identity"):
        load_ict_facekit(ict_dir, identity=bad)  # type: ignore[arg-type]


def test_missing_folder(tmp_path: Path) -> None:
    with pytest.raises(MissingAssetError, match="not found"):
        load_ict_facekit(tmp_path / "nowhere")
    with pytest.raises(MissingAssetError, match="FaceXModel/"):
        load_ict_facekit(tmp_path)


def test_partial_folder_lists_missing_files(tmp_path: Path) -> None:
    model = tmp_path / "FaceXModel"
    model.mkdir()
    (model / "generic_neutral_mesh.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    (model / "eyeBlink_L.obj").write_text("v 0 0 0\n")
    missing = ict_missing_files(tmp_path)
    assert "FaceXModel/eyeBlink_R.obj" in missing and "FaceXModel/vertex_indices.json" in missing
    assert "FaceXModel/eyeBlink_L.obj" not in missing and "FaceXModel/identity015.obj" in missing
    with pytest.raises(MissingAssetError, match=r"eyeBlink_R\.obj") as info:
        load_ict_facekit(tmp_path)
    assert f"missing {len(missing)} of" in str(info.value)


def _linked_copy(ict_dir: Path, tmp_path: Path, replace: dict[str, str]) -> Path:
    """A FaceXModel folder of symlinks to the real files, with ``replace`` files written as given text."""
    model = tmp_path / "FaceXModel"
    model.mkdir()
    for source in (ict_dir / "FaceXModel").iterdir():
        if source.name in replace:
            (model / source.name).write_text(replace[source.name])
        else:
            (model / source.name).symlink_to(source)
    return tmp_path


def test_expression_with_wrong_vertex_count(ict_dir: Path, tmp_path: Path) -> None:
    folder = _linked_copy(ict_dir, tmp_path, {"PupilDilate_L.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\n"})
    with pytest.raises(InvalidValueError, match=r"PupilDilate_L\.obj vertex count") as info:
        load_ict_facekit(folder, cache=False)
    assert "3" in str(info.value) and "26719" in str(info.value)


def test_neutral_with_wrong_vertex_count(ict_dir: Path, tmp_path: Path) -> None:
    folder = _linked_copy(ict_dir, tmp_path, {"generic_neutral_mesh.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"})
    with pytest.raises(InvalidValueError, match=r"generic_neutral_mesh\.obj vertex count=3"):
        load_ict_facekit(folder, cache=False)


def test_obj_reader_triangulates_and_resolves_ids(tmp_path: Path) -> None:
    path = tmp_path / "quad.obj"
    path.write_text(
        "# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nf 1/1 2/1 3/1 4/1\nf -1 -2 -3\n"
    )
    vertices, faces = read_obj(path)
    assert vertices.shape == (4, 3) and vertices[2].tolist() == [1.0, 1.0, 0.0]
    assert faces.tolist() == [[0, 1, 2], [0, 2, 3], [3, 2, 1]]
    np.testing.assert_array_equal(read_obj_vertices(path), vertices)


@pytest.mark.parametrize(
    "text", ["vt 0 0\n", "v 0 0\nv 1 1\n", "v 0 0 0\nf 1 2 5\n", "v a b c\n"], ids=["none", "short", "id", "nan"]
)
def test_obj_reader_rejects_bad_files(tmp_path: Path, text: str) -> None:
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(InvalidValueError, match="OBJ file"):
        read_obj(path)


def test_assets_command_reports_ict(
    ict: Rig, ict_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from mien.cli import main

    monkeypatch.setenv("MIEN_CONFIG", str(tmp_path / "none.toml"))
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(ict_dir))
    monkeypatch.delenv("MIEN_FACE_LANDMARKER", raising=False)
    assert main(["assets", "--json"]) == 0
    report = {entry["name"]: entry for entry in json.loads(capsys.readouterr().out)["assets"]}
    ict_entry = report["ict_facekit"]
    assert ict_entry["found"] and ict_entry["complete"] and ict_entry["source"] == "environment"
    assert ict_entry["cache_built"] == ict_cache_file(ict_dir).is_file()
    assert not report["face_landmarker"]["configured"]
    monkeypatch.setenv("MIEN_ICT_FACEKIT", str(tmp_path))  # no FaceXModel/ here
    assert main(["assets"]) == 0
    text = capsys.readouterr().out
    assert "ict_facekit: INCOMPLETE" in text and "FaceXModel/" in text
    assert "face_landmarker: not configured" in text and "export MIEN_FACE_LANDMARKER=" in text


def test_damaged_cache_is_rebuilt(ict: Rig, ict_dir: Path) -> None:
    cache = ict_cache_file(ict_dir)
    cache.write_bytes(b"not an npz")
    rig = load_ict_facekit(ict_dir)
    np.testing.assert_array_equal(rig.neutral, ict.neutral)
    with np.load(cache) as data:
        assert "target_deltas" in data.files
