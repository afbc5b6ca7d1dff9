"""Instrumenting a head nobody measured: ICT-FaceKit and the built-in head, whose landmarks are known, seen in
their own frame and re-written as a Blender-style file (centimetres, Z up, facing -y)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mediapipe", reason="mediapipe not installed (track extra)")
pytest.importorskip("moderngl", reason="moderngl not installed (render extra)")

from mien.errors import InvalidValueError
from mien.heads import instrument as instrument_module
from mien.heads.instrument import FaceNotFoundError, Instrumentation, instrument, instrument_cached
from mien.rig.builtin_head import builtin_head


def _distances_mm(points: np.ndarray, rig) -> np.ndarray:  # type: ignore[no-untyped-def]
    return np.linalg.norm(points.astype(np.float64) - rig.neutral[rig.landmarks], axis=1) * 1000.0


def test_ict_in_its_own_frame_is_found_frontally_in_metres(ict) -> None:  # type: ignore[no-untyped-def]
    _, found = ict
    assert found.view == "+z/+y"
    assert found.unit == "m"
    assert found.up == (0.0, 1.0, 0.0) and found.forward == (0.0, 0.0, 1.0)
    assert 0.08 < found.interocular < 0.10  # ICT's outer eye corners are 90 mm apart
    assert found.hits >= 470
    np.testing.assert_allclose(found.rotation(), np.eye(3), atol=1e-12)


def test_ict_landmarks_land_near_icts_own(ict) -> None:  # type: ignore[no-untyped-def]
    """Measured (vertices): 3.0 mm median over the 68 (eyes 1.5, outer lips 1.7, nose 3.2, brows 6.1 on a bare
    render, jaw contour 5.1; 3.0 and 7.1 with the mean of three close looks); the bound guards against a
    regression, the issue's 2 mm is reported as not reached."""
    rig, found = ict
    distances = _distances_mm(found.ibug68_points, rig)
    assert np.median(distances) < 4.5
    assert np.median(distances[36:48]) < 3.0  # the eyes
    assert np.median(distances[48:60]) < 3.0  # the outer lips
    vertex_distances = _distances_mm(rig.neutral[found.ibug68_vertices], rig)
    assert np.median(vertex_distances) < 4.0
    assert np.median(vertex_distances[36:48]) < 2.5


def test_a_blender_style_file_in_centimetres_is_told_apart(ict, ict_zup) -> None:  # type: ignore[no-untyped-def]
    _, frontal = ict
    _, found = ict_zup
    assert found.unit == "cm"
    assert found.up == (0.0, 0.0, 1.0) and found.forward == (0.0, -1.0, 0.0)
    assert found.view == "-y/+z"
    # back in mien's frame and metres, the landmarks agree with the frontal look's
    back = found.ibug68_points.astype(np.float64) @ found.rotation().T * found.metres_per_unit
    assert np.median(np.linalg.norm(back - frontal.ibug68_points, axis=1)) < 0.002


def test_the_builtin_head_is_found_too(landmarker_path: Path) -> None:
    rig = builtin_head()
    found = instrument(rig.neutral, rig.faces, landmarker_path, name="builtin")
    assert (found.unit, found.view) == ("m", "+z/+y")
    assert np.median(_distances_mm(found.ibug68_points, rig)) < 8.0


def test_a_mesh_with_no_face_is_refused_by_name(landmarker_path: Path) -> None:
    sphere = _sphere(0.1)
    with pytest.raises(FaceNotFoundError, match=r"no face found on ball\.glb"):
        instrument(*sphere, landmarker_path, name="ball.glb")


def test_a_unit_no_human_face_has_is_refused(ict, landmarker_path: Path) -> None:  # type: ignore[no-untyped-def]
    rig, _ = ict
    with pytest.raises(InvalidValueError, match=r"giant\.glb unit"):
        instrument(rig.neutral * 4.0, rig.faces, landmarker_path, name="giant.glb")


@pytest.mark.parametrize(
    ("vertices", "faces"),
    [(np.zeros((2, 3)), np.zeros((1, 3), np.int32)), (np.zeros((4, 3)), np.array([[0, 1, 9]], np.int32))],
)
def test_malformed_meshes_are_refused(vertices: np.ndarray, faces: np.ndarray) -> None:
    with pytest.raises(InvalidValueError):
        instrument(vertices, faces, name="bad")


def test_the_cache_answers_the_second_call_and_survives_a_json_round_trip(
    ict, landmarker_path: Path, monkeypatch: pytest.MonkeyPatch  # type: ignore[no-untyped-def]
) -> None:
    rig, found = ict
    monkeypatch.setattr(instrument_module, "instrument", lambda *args, **kwargs: found)
    first = instrument_cached(rig.neutral, rig.faces, "ab" * 32, landmarker_path, name="ict")

    def fail(*args: object, **kwargs: object) -> Instrumentation:
        raise AssertionError("the cache was not used")

    monkeypatch.setattr(instrument_module, "instrument", fail)
    second = instrument_cached(rig.neutral, rig.faces, "ab" * 32, landmarker_path, name="ict")
    np.testing.assert_allclose(second.ibug68_points, first.ibug68_points)
    assert (second.unit, second.up, second.forward, second.view) == (first.unit, first.up, first.forward, first.view)
    np.testing.assert_array_equal(second.ibug68_vertices, first.ibug68_vertices)


def test_a_broken_cache_entry_is_recomputed_not_trusted(
    ict, landmarker_path: Path, monkeypatch: pytest.MonkeyPatch  # type: ignore[no-untyped-def]
) -> None:
    rig, found = ict
    path = instrument_module.cache_dir("heads") / f"{'cd' * 32}.instrument.json"
    path.write_text('{"version": 1, "landmarks478": [1, 2', encoding="utf-8")
    monkeypatch.setattr(instrument_module, "instrument", lambda *args, **kwargs: found)
    again = instrument_cached(rig.neutral, rig.faces, "cd" * 32, landmarker_path, name="ict")
    assert again.unit == "m"
    assert Instrumentation.from_json(path.read_text(encoding="utf-8")).view == found.view


def test_rays_are_cast_to_the_nearest_covering_triangle() -> None:
    """The grid cast answers what testing every triangle against every pixel answers: the nearest triangle in
    front of the camera covering the pixel, its barycentric weights, -1 where none covers it."""
    rng = np.random.default_rng(5)
    centres = rng.uniform(0.0, 64.0, (400, 2))
    pixels = np.c_[np.repeat(centres, 3, axis=0) + rng.normal(0.0, 3.0, (1200, 2)), rng.uniform(-0.5, 3.0, 1200)]
    pixels[:3] = [[-40.0, -40.0, 9.0], [200.0, -30.0, 9.0], [20.0, 300.0, 9.0]]  # a far one behind everything
    faces = np.arange(1200, dtype=np.int32).reshape(400, 3)
    faces[7] = faces[7, [0, 0, 1]]  # a degenerate one
    targets = np.r_[rng.uniform(-5.0, 70.0, (300, 2)), centres[:20], [[500.0, 500.0], [-90.0, 10.0]]]
    ids, weights = instrument_module._cast(pixels, faces, targets)
    for k, (x, y) in enumerate(targets):
        best, best_depth = -1, np.inf
        for f, (a, b, c) in enumerate(pixels[faces]):
            det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])
            if abs(det) <= 1e-12:
                continue
            w1 = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det
            w2 = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det
            depth = (1 - w1 - w2) * a[2] + w1 * b[2] + w2 * c[2]
            if min(1 - w1 - w2, w1, w2) >= -1e-6 and 0 < depth < best_depth:
                best, best_depth = f, depth
        assert ids[k] == best, k
        if best >= 0:
            assert weights[k] @ pixels[faces[best], 2] == pytest.approx(best_depth)
            assert weights[k] @ pixels[faces[best], 0] == pytest.approx(x)
    assert (ids > 0).sum() > 100 and (ids == 0).sum() > 10 and (ids[-2:] == -1).all()


def _sphere(radius: float) -> tuple[np.ndarray, np.ndarray]:
    rings, segments = 24, 48
    theta = np.linspace(0.0, np.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    vertices = radius * np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    faces = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, c, b), (b, c, d)]
    return vertices, np.array(faces, np.int32)
