"""Fixtures of the render tests: a generated head-sized mesh with a nose, and a renderer factory."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
import pytest

from mien.errors import MissingExtraError
from mien.render.camera import Camera
from mien.render.offscreen import EGLUnavailableError, OffscreenRenderer
from mien.rig.model import MorphTarget, Rig


def head_mesh(n_lat: int = 40, n_lon: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """A head-sized ellipsoid (15 x 22 x 19 cm, centred 3 cm below and 6 cm behind the eyes) with a nose.

    Returns (vertices (n, 3) float32 metres, faces (m, 3) int32 counter-clockwise seen from outside).
    """
    lat = np.linspace(0.0, np.pi, n_lat)
    lon = np.linspace(0.0, 2.0 * np.pi, n_lon, endpoint=False)
    theta, phi = np.meshgrid(lat, lon, indexing="ij")
    unit = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)], axis=-1)
    radii = np.array([0.075, 0.11, 0.095])
    # A nose: push the front of the ellipsoid (around +z, just below the equator) forward by up to 3 cm.
    nose_axis = np.array([0.0, -0.15, 1.0]) / np.linalg.norm([0.0, -0.15, 1.0])
    bump = 0.03 * np.exp(-(((1.0 - unit @ nose_axis) / 0.02) ** 2))
    points = unit * radii + bump[..., None] * nose_axis + np.array([0.0, -0.03, -0.06])
    vertices = points.reshape(-1, 3).astype(np.float32)
    faces = []
    for i in range(n_lat - 1):
        for j in range(n_lon):
            a, b = i * n_lon + j, i * n_lon + (j + 1) % n_lon
            c, d = a + n_lon, b + n_lon
            faces += [(a, c, d), (a, d, b)]
    return vertices, np.array(faces, np.int32)


def head_rig() -> Rig:
    """A rig on :func:`head_mesh` with two morph targets: ``jawOpen`` (lower half down) and ``puff`` (swell)."""
    vertices, faces = head_mesh()
    lower = np.flatnonzero(vertices[:, 1] < -0.06)
    jaw = np.zeros((len(lower), 3), np.float32)
    jaw[:, 1] = -0.02
    puff = (vertices - vertices.mean(axis=0)) * 0.1
    targets = (MorphTarget("jawOpen", lower, jaw), MorphTarget.from_dense("puff", puff))
    return Rig("test-head", vertices, faces, targets, landmarks=np.zeros(68, np.int32))


@pytest.fixture(scope="session")
def mesh() -> tuple[np.ndarray, np.ndarray]:
    """(vertices, faces) of the generated head."""
    return head_mesh()


@pytest.fixture(scope="session")
def rig() -> Rig:
    """The generated head as a two-target rig."""
    return head_rig()


@pytest.fixture
def make_renderer() -> Iterator[Callable[..., OffscreenRenderer]]:
    """Build OffscreenRenderers (closed after the test); skips when no EGL context can be created."""
    made: list[OffscreenRenderer] = []

    def make(faces: np.ndarray, width: int, height: int, camera: Camera, **kwargs: object) -> OffscreenRenderer:
        try:
            renderer = OffscreenRenderer(faces, width, height, camera, **kwargs)  # type: ignore[arg-type]
        except (EGLUnavailableError, MissingExtraError) as error:
            pytest.skip(f"no headless OpenGL here: {error}")
        made.append(renderer)
        return renderer

    yield make
    for renderer in made:
        renderer.close()
