"""Activation maps (AU x time) and the 2D correlation (MATLAB corr2)."""

from __future__ import annotations

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.validate.activation import (
    activation_map,
    correlation_note,
    map_correlation,
    row_correlations,
)


def test_identical_maps_correlate_exactly_one() -> None:
    rng = np.random.default_rng(7)
    a = rng.uniform(0.0, 5.0, size=(18, 100))
    assert map_correlation(a, a.copy()) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(row_correlations(a, a), 1.0)


def test_time_shuffled_maps_correlate_near_zero() -> None:
    rng = np.random.default_rng(11)
    a = rng.uniform(0.0, 5.0, size=(200, 500))
    shuffled = a[:, rng.permutation(a.shape[1])]
    assert abs(map_correlation(a, shuffled)) < 0.1


def test_corr2_matches_pearson_over_all_cells_and_ignores_scale() -> None:
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(12, 40)), rng.normal(size=(12, 40))
    b = 0.5 * a + b
    expected = np.corrcoef(a.ravel(), b.ravel())[0, 1]
    assert map_correlation(a, b) == pytest.approx(expected, abs=1e-12)
    assert map_correlation(3.0 * a + 1.0, b) == pytest.approx(expected, abs=1e-12)
    assert map_correlation(a, -a) == pytest.approx(-1.0, abs=1e-12)


def test_constant_map_correlation_is_nan_with_a_reason() -> None:
    a = np.arange(20.0).reshape(2, 10)
    flat = np.full((2, 10), 2.0)
    assert np.isnan(map_correlation(a, flat))
    assert "second map is constant" in correlation_note(a, flat)
    assert correlation_note(a, a) == ""
    rows = row_correlations(np.stack([a[0], flat[0]]), np.stack([a[0], a[1]]))
    assert rows[0] == pytest.approx(1.0) and np.isnan(rows[1])


def test_resampling_keeps_endpoints_and_is_linear_in_time() -> None:
    times = np.array([0.0, 0.1, 0.3, 0.6, 1.0])  # irregular frame times
    values = np.stack([times * 4.0, 5.0 - times * 5.0, np.array([0.0, 3.0, 1.0, 2.0, 4.0])], axis=1)
    m = activation_map(values, times, length=11)
    assert m.shape == (3, 11)
    assert np.allclose(m[:, 0], values[0]) and np.allclose(m[:, -1], values[-1])
    assert np.allclose(m[0], np.linspace(0.0, 4.0, 11))  # a linear ramp stays a ramp
    assert np.allclose(m[1], np.linspace(5.0, 0.0, 11))


def test_span_bridges_gaps_and_holds_edges() -> None:
    times = np.array([0.2, 0.4, 0.8])  # frames at 0.0 and 1.0 had no face
    values = np.array([[1.0], [2.0], [4.0]])
    m = activation_map(values, times, length=6, span_s=(0.0, 1.0))
    assert m[0].tolist() == pytest.approx([1.0, 1.0, 2.0, 3.0, 4.0, 4.0])


@pytest.mark.parametrize(
    ("values", "times", "length", "field"),
    [
        (np.zeros((1, 3)), [0.0], 10, "aus_over_time"),
        (np.zeros((3, 2)), [0.0, 0.1, 0.1], 10, "times_s"),
        (np.zeros((3, 2)), [0.0, 0.1], 10, "times_s"),
        (np.full((3, 2), np.nan), [0.0, 0.1, 0.2], 10, "aus_over_time"),
        (np.zeros((3, 2)), [0.0, 0.1, 0.2], 1, "length"),
    ],
)
def test_bad_input_names_the_field(values: np.ndarray, times: list[float], length: int, field: str) -> None:
    with pytest.raises(InvalidValueError) as caught:
        activation_map(values, times, length)
    assert caught.value.field == field


def test_maps_of_different_shapes_are_rejected() -> None:
    with pytest.raises(InvalidValueError, match="shapes"):
        map_correlation(np.zeros((2, 10)), np.zeros((2, 11)))
