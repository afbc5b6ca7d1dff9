"""Cameras: matrices, presets and rejection of impossible parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.render.camera import CAMERA_PRESETS, STUDY_FOV_DEG, Camera, camera_from_options


def test_frontal_camera_sits_on_plus_z_and_looks_at_the_target() -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    np.testing.assert_allclose(camera.position, [0.0, -0.03, 1.0], atol=1e-9)
    eye = camera.view_matrix() @ np.array([*camera.target, 1.0])
    np.testing.assert_allclose(eye[:3], [0.0, 0.0, -1.0], atol=1e-6)


def test_lateral_camera_sits_on_the_characters_left() -> None:
    camera = CAMERA_PRESETS["lateral-1m"]
    assert camera.position[0] == pytest.approx(1.0)
    assert camera.position[2] == pytest.approx(camera.target[2])


def test_presets_share_one_field_of_view_and_differ_in_distance() -> None:
    assert {c.fov_deg for name, c in CAMERA_PRESETS.items() if name != "portrait"} == {STUDY_FOV_DEG}
    assert CAMERA_PRESETS["frontal-3m"].distance_m == 3 * CAMERA_PRESETS["frontal-1m"].distance_m
    assert CAMERA_PRESETS["lateral-3m"].distance_m == 3 * CAMERA_PRESETS["lateral-1m"].distance_m


def test_projection_maps_the_field_of_view_to_the_image_edges() -> None:
    camera = Camera(distance_m=2.0, fov_deg=40.0, target=(0.0, 0.0, 0.0))
    half_height = 2.0 * math.tan(math.radians(20.0))
    pixels = camera.project(np.array([[0.0, 0.0, 0.0], [0.0, half_height, 0.0]]), 200, 100)
    np.testing.assert_allclose(pixels, [[100.0, 50.0], [100.0, 0.0]], atol=1e-4)
    assert camera.projection_matrix(2.0)[0, 0] == pytest.approx(camera.projection_matrix(1.0)[0, 0] / 2)


def test_camera_from_options_overrides_a_preset() -> None:
    camera = camera_from_options("lateral-3m", yaw_deg=-90.0, fov_deg=30.0)
    assert (camera.yaw_deg, camera.pitch_deg, camera.distance_m, camera.fov_deg) == (-90.0, 0.0, 3.0, 30.0)
    with pytest.raises(UnknownNameError, match="camera preset"):
        camera_from_options("bird's-eye")


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("fov_deg", {"fov_deg": 0.0}),
        ("fov_deg", {"fov_deg": 180.0}),
        ("fov_deg", {"fov_deg": float("nan")}),
        ("distance_m", {"distance_m": 0.0}),
        ("distance_m", {"distance_m": -1.0}),
        ("distance_m", {"distance_m": float("inf")}),
        ("pitch_deg", {"pitch_deg": 90.0}),
        ("near_m", {"near_m": 0.0}),
        ("far_m", {"near_m": 1.0, "far_m": 1.0}),
        ("target", {"target": (0.0, 0.0)}),
        ("yaw_deg", {"yaw_deg": "left"}),
    ],
)
def test_impossible_parameters_name_the_field(field: str, kwargs: dict[str, object]) -> None:
    with pytest.raises(InvalidValueError) as caught:
        Camera(**kwargs)  # type: ignore[arg-type]
    assert caught.value.field == field


def test_bad_aspect_is_rejected() -> None:
    with pytest.raises(InvalidValueError, match="aspect"):
        Camera().projection_matrix(0.0)


def test_views_are_the_one_registry_of_camera_presets() -> None:
    from mien.render.camera import CAMERA_PRESETS, VIEWS, View

    assert list(VIEWS) == ["frontal-1m", "frontal-3m", "oblique-1m", "oblique-3m", "lateral-1m", "lateral-3m"]
    assert [v.in_study for v in VIEWS.values()] == [True, True, False, False, True, True]
    oblique = CAMERA_PRESETS["oblique-1m"]
    assert (oblique.yaw_deg, oblique.distance_m, oblique.target) == (45.0, 1.0, (0.0, -0.03, 0.0))
    assert CAMERA_PRESETS["lateral-3m"].target == (0.0, -0.03, -0.06)
    assert all(CAMERA_PRESETS[name] == view.camera for name, view in VIEWS.items())
    assert View("lateral", 2.0).camera == camera_from_options("lateral-1m", distance_m=2.0)
    with pytest.raises(UnknownNameError):
        View("overhead", 1.0)
    with pytest.raises(InvalidValueError):
        View("frontal", 0.0)
