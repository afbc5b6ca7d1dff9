"""The offscreen renderer: image size, framing for each camera preset, lighting, normals."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.render.camera import CAMERA_PRESETS, Camera
from mien.render.offscreen import DEFAULT_BACKGROUND, OffscreenRenderer, _normals_numpy, vertex_normals

SIZE = 160
MakeRenderer = Callable[..., OffscreenRenderer]
Mesh = tuple[np.ndarray, np.ndarray]


def face_mask(image: np.ndarray) -> np.ndarray:
    """(h, w) bool: pixels that are not the background colour."""
    return np.asarray(np.abs(image.astype(int) - np.array(DEFAULT_BACKGROUND)).max(axis=2) > 3)


def bbox(mask: np.ndarray) -> tuple[int, int, int, int]:
    """(left, top, right, bottom) inclusive pixel bounds of the True pixels."""
    rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
    return int(cols[0]), int(rows[0]), int(cols[-1]), int(rows[-1])


def render(make_renderer: MakeRenderer, mesh: Mesh, camera: Camera, size: tuple[int, int] = (SIZE, SIZE)) -> np.ndarray:
    vertices, faces = mesh
    return make_renderer(faces, size[0], size[1], camera).render(vertices)


def test_image_has_the_requested_size_and_type(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    image = render(make_renderer, mesh, CAMERA_PRESETS["frontal-1m"], (96, 64))
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    assert (image[0, 0] == DEFAULT_BACKGROUND).all()


def test_frontal_face_is_centred(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    camera = CAMERA_PRESETS["frontal-1m"]
    left, top, right, bottom = bbox(face_mask(render(make_renderer, mesh, camera)))
    assert (left + right) / 2 == pytest.approx(SIZE / 2, abs=2)
    # The generated head is centred on the frontal target's height.
    assert (top + bottom) / 2 == pytest.approx(SIZE / 2, abs=0.08 * SIZE)
    # Its 22 cm height fills ~0.22 / (2 * tan(11 deg) * (1 m - its depth)) of the image.
    expected = camera.project(np.array([[0, 0.08, 0.0], [0, -0.14, 0.0]]), SIZE, SIZE)
    assert bottom - top == pytest.approx(expected[1, 1] - expected[0, 1], rel=0.15)


@pytest.mark.parametrize("view", ["frontal", "lateral"])
def test_three_metre_face_is_a_third_of_the_one_metre_face(make_renderer: MakeRenderer, mesh: Mesh, view: str) -> None:
    near = bbox(face_mask(render(make_renderer, mesh, CAMERA_PRESETS[f"{view}-1m"], (240, 240))))
    far = bbox(face_mask(render(make_renderer, mesh, CAMERA_PRESETS[f"{view}-3m"], (240, 240))))
    for axis in (0, 1):
        near_extent = near[axis + 2] - near[axis] + 1
        far_extent = far[axis + 2] - far[axis] + 1
        assert far_extent / near_extent == pytest.approx(1 / 3, rel=0.15)


def test_lateral_view_shows_the_profile_facing_the_right_side(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    frontal = face_mask(render(make_renderer, mesh, CAMERA_PRESETS["frontal-1m"]))
    camera = CAMERA_PRESETS["lateral-1m"]
    lateral = face_mask(render(make_renderer, mesh, camera))
    overlap = (frontal & lateral).sum() / (frontal | lateral).sum()
    assert overlap < 0.8
    vertices = mesh[0]
    nose_tip = vertices[np.argmax(vertices[:, 2])]
    nose_x, nose_y = camera.project(nose_tip, SIZE, SIZE)[0]
    # From the character's left, the face (+z) points to the image's left: the nose is the leftmost point.
    left = bbox(lateral)[0]
    assert nose_x < SIZE / 2 and left == pytest.approx(nose_x, abs=2)
    assert lateral[int(nose_y), int(nose_x) + 2]
    mirrored = face_mask(render(make_renderer, mesh, Camera(yaw_deg=-90.0, target=camera.target)))
    flipped = mirrored[:, ::-1]  # from the character's right: the mirror image
    assert (flipped & lateral).sum() / (flipped | lateral).sum() > 0.95


def test_lighting_is_not_flat(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    image = render(make_renderer, mesh, CAMERA_PRESETS["frontal-1m"])
    luminance = image.astype(float) @ np.array([0.2126, 0.7152, 0.0722])
    face = luminance[face_mask(image)]
    assert np.percentile(face, 95) - np.percentile(face, 5) > 60
    # The key light comes from the viewer's upper left: that side of the face is brighter.
    mask = face_mask(image)
    half = SIZE // 2
    assert luminance[:half, :half][mask[:half, :half]].mean() > luminance[:half, half:][mask[:half, half:]].mean()


def test_frames_reuse_buffers_and_follow_the_vertices(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    vertices, faces = mesh
    renderer = make_renderer(faces, 64, 64, CAMERA_PRESETS["frontal-1m"], samples=0)
    out = np.empty((64, 64, 3), np.uint8)
    first = renderer.render(vertices, out=out).copy()
    assert renderer.render(vertices, out=out) is out
    np.testing.assert_array_equal(out, first)
    moved = renderer.render(vertices + np.float32([0.05, 0.0, 0.0]))
    assert bbox(face_mask(moved))[0] > bbox(face_mask(first))[0]  # +x is the viewer's right


def test_vertex_colours_show(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    vertices, faces = mesh
    green = np.tile(np.float32([0.1, 0.8, 0.1]), (len(vertices), 1))
    image = make_renderer(faces, 64, 64, CAMERA_PRESETS["frontal-1m"], vertex_colors=green).render(vertices)
    face = image[face_mask(image)].astype(int)
    assert (face[:, 1] > face[:, 0]).mean() > 0.9


def test_bad_input_is_rejected(make_renderer: MakeRenderer, mesh: Mesh) -> None:
    vertices, faces = mesh
    camera = CAMERA_PRESETS["frontal-1m"]
    for width, height, field in ((0, 64, "width"), (64, 0, "height"), (64.5, 64, "width")):
        with pytest.raises(InvalidValueError) as caught:
            OffscreenRenderer(faces, width, height, camera)  # type: ignore[arg-type]
        assert caught.value.field == field
    renderer = make_renderer(faces, 32, 32, camera)
    with pytest.raises(InvalidValueError, match="vertices"):
        renderer.render(vertices[:, :2])
    with pytest.raises(InvalidValueError, match="vertices"):
        renderer.render(np.full_like(vertices, np.nan))
    with pytest.raises(InvalidValueError, match="out"):
        renderer.render(vertices, out=np.empty((32, 32, 4), np.uint8))
    with pytest.raises(InvalidValueError, match="vertex_colors"):
        make_renderer(faces, 32, 32, camera, vertex_colors=np.ones((3, 3))).render(vertices)


def test_normals_point_outward_and_backends_agree(mesh: Mesh) -> None:
    vertices, faces = mesh
    normals = vertex_normals(vertices, faces)
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-5)
    outward = np.einsum("ij,ij->i", normals, vertices - vertices.mean(axis=0))
    assert (outward > 0).mean() > 0.99
    reference = np.empty_like(vertices)
    _normals_numpy(vertices, faces, reference)
    np.testing.assert_allclose(normals, reference, atol=1e-4)
