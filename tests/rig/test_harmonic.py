"""Biharmonic fill-in over a mesh: constraints held, linear in the values, the same without scipy."""

from __future__ import annotations

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.rig.harmonic import BiharmonicSystem, biharmonic_fill, cotan_laplacian


def grid(n: int = 9) -> tuple[np.ndarray, np.ndarray]:
    """A flat n x n grid of unit squares, each split into two triangles."""
    xs, ys = np.meshgrid(np.arange(n, dtype=float), np.arange(n, dtype=float))
    v = np.stack([xs.ravel(), ys.ravel(), np.zeros(n * n)], axis=1)
    f = []
    for j in range(n - 1):
        for i in range(n - 1):
            a = j * n + i
            f += [[a, a + 1, a + n + 1], [a, a + n + 1, a + n]]
    return v, np.array(f)


def test_laplacian_rows_sum_to_zero_and_areas_cover_the_mesh() -> None:
    v, f = grid()
    (r, _, w), areas = cotan_laplacian(v, f)
    sums = np.zeros(len(v))
    np.add.at(sums, r, w)
    np.testing.assert_allclose(sums, 0.0, atol=1e-12)
    assert areas.sum() == pytest.approx(64.0)


def test_fill_holds_constraints_is_smooth_and_linear() -> None:
    v, f = grid()
    n = 9
    centre = 4 * n + 4
    border = np.flatnonzero((v[:, 0] == 0) | (v[:, 0] == n - 1) | (v[:, 1] == 0) | (v[:, 1] == n - 1))
    fixed = np.append(border, centre)
    values = np.zeros((fixed.size, 2))
    values[-1] = [1.0, 2.0]
    x = biharmonic_fill(v, f, fixed, values)
    assert x[centre, 0] == 1.0 and np.all(x[border] == 0.0)
    np.testing.assert_allclose(x[:, 1], 2.0 * x[:, 0])  # linear in the constrained values
    ring = x[[centre - 1, centre + 1, centre - n, centre + n], 0]
    assert np.all((ring > 0.5) & (ring < 1.0))  # a round bump, not a tent
    assert x[:, 0].max() <= 1.0 + 1e-9


def test_numpy_path_matches_scipy() -> None:
    pytest.importorskip("scipy")
    v, f = grid(7)
    system = BiharmonicSystem(v, f)
    fixed = np.array([0, 6, 24, 42, 48])
    values = np.array([0.0, 0.0, 1.0, 0.0, 0.0])
    free = np.arange(49)
    fast = system.fill(fixed, values, free)
    system._q = None  # the no-scipy path: conjugate gradient in numpy
    np.testing.assert_allclose(system.fill(fixed, values, free), fast, atol=1e-6)


def test_bad_input() -> None:
    v, f = grid(3)
    with pytest.raises(InvalidValueError, match="fixed"):
        biharmonic_fill(v, f, np.array([0, 99]), np.zeros(2))
    with pytest.raises(InvalidValueError, match="mesh"):
        cotan_laplacian(v[:, :2], f)
