"""The one Pearson correlation of the validation reports, along an axis and over finite pairs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mien.validate.statistics import pearson, pearson_r


def test_pearson_along_rows_matches_the_pairwise_r_and_is_nan_without_variance() -> None:
    a = np.array([[0.0, 1.0, 3.0, 4.0], [2.0, 2.0, 2.0, 2.0], [1.0, 0.0, 2.0, 5.0]])
    b = np.array([[0.0, 2.0, 2.0, 9.0], [1.0, 2.0, 3.0, 4.0], [4.0, 1.0, 0.0, -2.0]])
    rows = pearson(a, b, axis=1)
    assert rows[0] == pytest.approx(pearson_r(a[0], b[0])) and rows[2] == pytest.approx(pearson_r(a[2], b[2]))
    assert rows[0] == pytest.approx(np.corrcoef(a[0], b[0])[0, 1])
    assert math.isnan(rows[1])
    both = [0, 2]
    assert float(pearson(a[both], b[both])) == pytest.approx(np.corrcoef(a[both].ravel(), b[both].ravel())[0, 1])


def test_pearson_r_drops_non_finite_pairs_and_needs_three() -> None:
    x = np.array([0.0, 1.0, np.nan, 2.0, 3.0])
    y = np.array([0.0, 2.0, 5.0, 4.0, np.inf])
    assert pearson_r(x, y) == pytest.approx(1.0)  # (0, 0), (1, 2), (2, 4)
    assert math.isnan(pearson_r(x[:2], y[:2]))
