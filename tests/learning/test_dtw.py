"""DTW kernels against a direct implementation, dtaidistance, and the definition's properties."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.learning.dtw import (
    as_series_list,
    dtw_cross_distance_matrix,
    dtw_distance,
    dtw_distance_matrices_per_channel,
    dtw_distance_matrix,
    dtw_distance_reference,
    dtw_path,
)


def naive_dtw(a: np.ndarray, b: np.ndarray, window: int | None = None) -> float:
    """Textbook recursion with Python floats (independent of the module's reference)."""
    a2 = np.atleast_2d(np.asarray(a, dtype=float).T).T
    b2 = np.atleast_2d(np.asarray(b, dtype=float).T).T
    n, m = len(a2), len(b2)
    w = max(n, m) if window is None else window
    acc = [[math.inf] * (m + 1) for _ in range(n + 1)]
    acc[0][0] = 0.0
    for i in range(n):
        for j in range(max(0, i - max(0, n - m) - w + 1), min(m, i + max(0, m - n) + w)):
            cost = sum((float(x) - float(y)) ** 2 for x, y in zip(a2[i], b2[j], strict=True))
            acc[i + 1][j + 1] = cost + min(acc[i][j], acc[i][j + 1], acc[i + 1][j])
    return math.sqrt(acc[n][m])


def test_known_values() -> None:
    assert dtw_distance(np.array([0.0, 1.0, 2.0]), np.array([0.0, 0.0, 1.0, 2.0])) == 0.0
    assert dtw_distance(np.array([0.0, 1.0]), np.array([0.0, 3.0])) == pytest.approx(2.0, abs=1e-12)
    # one channel against two frames: every frame of a must match b's single frame
    assert dtw_distance(np.array([1.0, 2.0, 3.0]), np.array([0.0])) == pytest.approx(math.sqrt(14), abs=1e-12)


def test_random_pairs_equal_naive_reference_and_path() -> None:
    rng = np.random.default_rng(1)
    for trial in range(120):
        n, m = (int(x) for x in rng.integers(1, 13, size=2))
        c = int(rng.integers(1, 4))
        a, b = rng.normal(size=(n, c)), rng.normal(size=(m, c))
        window = None if trial % 3 == 0 else int(rng.integers(1, 6))
        expected = naive_dtw(a, b, window)
        assert abs(dtw_distance(a, b, window) - expected) <= 1e-9
        assert abs(dtw_distance_reference(a, b, window) - expected) <= 1e-9
        path, distance = dtw_path(a, b, window)
        assert abs(distance - expected) <= 1e-9
        cost = sum(float(((a[i] - b[j]) ** 2).sum()) for i, j in path)
        assert math.sqrt(cost) == pytest.approx(expected, abs=1e-9)
        steps = np.diff(path, axis=0)
        assert path[0].tolist() == [0, 0] and path[-1].tolist() == [n - 1, m - 1]
        assert np.all((steps >= 0) & (steps <= 1)) and np.all(steps.sum(axis=1) >= 1)


def test_equals_dtaidistance() -> None:
    dtaidistance = pytest.importorskip("dtaidistance")
    from dtaidistance import dtw as dtai_dtw
    from dtaidistance import dtw_ndim

    rng = np.random.default_rng(2)
    series = np.cumsum(rng.normal(size=(9, 40, 3)), axis=1)
    assert dtaidistance is not None
    expected = dtw_ndim.distance_matrix_fast(series)
    np.fill_diagonal(expected, 0.0)
    np.testing.assert_allclose(dtw_distance_matrix(series), expected, rtol=0, atol=1e-9)
    windowed = dtw_ndim.distance_matrix_fast(series, window=5)
    np.fill_diagonal(windowed, 0.0)
    np.testing.assert_allclose(dtw_distance_matrix(series, window=5), windowed, rtol=0, atol=1e-9)
    per_channel = dtw_distance_matrices_per_channel(series)
    for k in range(3):
        univariate = dtai_dtw.distance_matrix_fast(np.ascontiguousarray(series[:, :, k]))
        np.fill_diagonal(univariate, 0.0)
        np.testing.assert_allclose(per_channel[k], univariate, rtol=0, atol=1e-9)
    a, b = series[0, :25, 0].copy(), series[1, :, 0].copy()
    assert abs(dtw_distance(a, b) - dtai_dtw.distance(a, b, use_c=False)) <= 1e-9


def test_matrix_symmetric_zero_diagonal_variable_lengths() -> None:
    rng = np.random.default_rng(3)
    series = [rng.normal(size=(int(n), 2)) for n in (5, 9, 1, 14, 7)]
    matrix = dtw_distance_matrix(series)
    assert matrix.shape == (5, 5) and matrix.dtype == np.float64
    np.testing.assert_array_equal(matrix, matrix.T)
    np.testing.assert_array_equal(np.diag(matrix), 0.0)
    for i in range(5):
        for j in range(5):
            if i != j:
                assert abs(matrix[i, j] - naive_dtw(series[i], series[j])) <= 1e-9
    cross = dtw_cross_distance_matrix(series[:2], series[2:])
    np.testing.assert_allclose(cross, matrix[:2, 2:], rtol=0, atol=1e-12)
    assert np.array_equal(dtw_distance_matrix(series, n_jobs=1), matrix)


def test_window_behaviour() -> None:
    a = np.array([0.0, 0.0, 0.0, 1.0, 0.0, 0.0])
    b = np.array([0.0, 1.0, 0.0, 0.0, 0.0, 0.0])
    # window 1 on equal lengths is the euclidean distance; a wide window aligns the shifted peak
    assert dtw_distance(a, b, window=1) == pytest.approx(np.linalg.norm(a - b), abs=1e-12)
    assert dtw_distance(a, b, window=3) == 0.0
    assert dtw_distance(a, b, window=2) > 0.0
    assert dtw_distance(a, b) == 0.0


def test_univariate_2d_collection_and_per_channel_shape() -> None:
    rng = np.random.default_rng(4)
    data = rng.normal(size=(4, 10, 3))
    per_channel = dtw_distance_matrices_per_channel(data)
    assert per_channel.shape == (3, 4, 4)
    np.testing.assert_allclose(per_channel[1], dtw_distance_matrix(data[:, :, 1]), rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("series", "field"),
    [
        ([np.array([1.0, np.nan, 2.0]), np.array([1.0, 2.0])], "series[0][1, 0]"),
        ([np.zeros((3, 2)), np.zeros((0, 2))], "series[1]"),
        ([np.zeros((3, 2)), np.zeros((3, 3))], "series[1]"),
        ([], "series"),
    ],
)
def test_bad_input(series: list[np.ndarray], field: str) -> None:
    with pytest.raises(InvalidValueError) as info:
        dtw_distance_matrix(series)
    assert info.value.field == field


def test_bad_window_and_pairs() -> None:
    with pytest.raises(InvalidValueError, match="window"):
        dtw_distance(np.zeros(3), np.zeros(3), window=0)
    with pytest.raises(InvalidValueError, match="channels"):
        dtw_distance(np.zeros((3, 2)), np.zeros((3, 1)))
    with pytest.raises(InvalidValueError, match="n_jobs"):
        dtw_distance_matrix(np.zeros((3, 4)), n_jobs=0)
    with pytest.raises(InvalidValueError):
        as_series_list(np.zeros(3))
