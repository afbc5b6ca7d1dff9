"""k-medoids / k-means with DTW, DBA prototypes, and the Table-3 style report."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError
from mien.learning.barycenter import dtw_barycenter
from mien.learning.clustering import KMeansDTW, KMedoidsDTW, representative_curve
from mien.learning.dtw import dtw_distance, dtw_distance_matrix
from mien.learning.dtw_report import column_statistics, format_dtw_table, plot_dtw_heatmap


def smiles_and_frowns(seed: int = 0) -> tuple[list[np.ndarray], np.ndarray]:
    """Raised-then-released curves (smiles) and lowered ones (frowns) with random timing and amplitude."""
    rng = np.random.default_rng(seed)
    curves, groups = [], []
    for index in range(12):
        n = int(rng.integers(50, 80))
        t = np.linspace(0, 1, n)
        onset = rng.uniform(0.1, 0.3)
        bump = np.clip((t - onset) / 0.3, 0, 1) * np.clip((0.95 - t) / 0.2, 0, 1)
        sign = 1.0 if index % 3 else -1.0
        curves.append(sign * rng.uniform(0.8, 1.2) * bump + rng.normal(0, 0.02, n))
        groups.append(0 if sign > 0 else 1)
    return curves, np.array(groups)


def test_kmedoids_recovers_two_groups_and_is_deterministic() -> None:
    curves, groups = smiles_and_frowns()
    model = KMedoidsDTW(random_state=3).fit(curves)
    assert model.n_clusters_ == 2
    assert model.labels_.tolist() == groups.tolist()  # smiles are the larger cluster, so label 0
    assert model.silhouette_ > 0.5 and set(model.silhouette_by_k_) == set(range(2, 9))
    assert set(model.medoid_indices_[model.labels_[model.medoid_indices_]].tolist()) == set(model.medoid_indices_)
    again = KMedoidsDTW(random_state=3).fit(precomputed=model.distance_matrix_)
    assert again.labels_.tolist() == model.labels_.tolist()
    assert again.medoid_indices_.tolist() == model.medoid_indices_.tolist()
    assert again.inertia_ == pytest.approx(model.inertia_)
    inertia = sum(model.distance_matrix_[i, model.medoid_indices_[label]] for i, label in enumerate(model.labels_))
    assert model.inertia_ == pytest.approx(inertia)
    assert model.predict([curves[0], -curves[0]]).tolist() == [groups[0], 1 - groups[0]]


def test_one_cluster_when_no_structure_and_fixed_k() -> None:
    rng = np.random.default_rng(5)
    noise = [rng.normal(size=30) for _ in range(8)]
    model = KMedoidsDTW(random_state=0).fit(noise)
    assert model.n_clusters_ == 1 and np.all(model.labels_ == 0)
    fixed = KMedoidsDTW(3, random_state=0).fit(noise)
    assert fixed.n_clusters_ == 3 and fixed.cluster_centers_ is not None and len(fixed.cluster_centers_) == 3
    assert KMedoidsDTW().fit([np.zeros(3), np.ones(3)]).n_clusters_ == 1


def test_dba_reduces_sum_of_squared_distances() -> None:
    curves, groups = smiles_and_frowns(1)
    smiles = [c for c, g in zip(curves, groups, strict=True) if g == 0]
    result = dtw_barycenter(smiles, init=smiles[0], max_iter=20)

    def cost(curve: np.ndarray) -> float:
        return sum(dtw_distance(curve, s) ** 2 for s in smiles)

    assert result.inertia_history[-1] == pytest.approx(cost(result.curve))
    assert cost(result.curve) < cost(smiles[0])
    medoid_cost = min(cost(s) for s in smiles)
    assert cost(result.curve) < medoid_cost
    assert all(b <= a + 1e-9 for a, b in zip(result.inertia_history, result.inertia_history[1:], strict=False))
    assert result.curve.shape == (len(smiles[0]), 1)


def test_representative_curve_medoid_and_dba() -> None:
    curves, _ = smiles_and_frowns(2)
    medoid = representative_curve(curves, "medoid", random_state=0)
    model = KMedoidsDTW(random_state=0).fit(curves)
    np.testing.assert_array_equal(medoid[:, 0], curves[int(model.medoid_indices_[0])])
    assert medoid.max() > 0.5  # the main cluster is the smiles
    average = representative_curve(curves, "dba", random_state=0)
    assert average.shape == medoid.shape and average.max() > 0.5
    with pytest.raises(InvalidValueError, match="method"):
        representative_curve(curves, "mean")  # type: ignore[arg-type]


def test_kmeans_dtw() -> None:
    curves, groups = smiles_and_frowns(4)
    model = KMeansDTW(2, random_state=0).fit(curves)
    assert model.labels_.tolist() == groups.tolist()
    assert len(model.cluster_centers_) == 2 and model.inertia_ > 0
    assert model.cluster_centers_[0].max() > 0.5 and model.cluster_centers_[1].min() < -0.5


def test_bad_precomputed() -> None:
    with pytest.raises(InvalidValueError, match="precomputed"):
        KMedoidsDTW().fit(precomputed=np.array([[0.0, 1.0], [2.0, 0.0]]))
    with pytest.raises(InvalidValueError, match="n_clusters"):
        KMedoidsDTW(5).fit(precomputed=np.zeros((3, 3)))
    with pytest.raises(InvalidValueError, match="n_clusters"):
        KMedoidsDTW(0)


# The paper's Table 3 (smileFrown, open-mouth smile); s07/s03 is 18.76 (the printed 18.16 contradicts the
# symmetric entry and the printed mean 13.12).
TABLE3 = np.array(
    [
        [0.00, 12.85, 12.88, 27.82, 16.68, 36.82, 11.31],
        [12.85, 0.00, 42.15, 10.90, 8.66, 16.17, 9.16],
        [12.88, 42.15, 0.00, 48.25, 35.20, 38.21, 18.76],
        [27.82, 10.90, 48.25, 0.00, 4.78, 4.29, 13.42],
        [16.68, 8.66, 35.20, 4.78, 0.00, 9.56, 12.43],
        [36.82, 16.17, 38.21, 4.29, 9.56, 0.00, 13.66],
        [11.31, 9.16, 18.76, 13.42, 12.43, 13.66, 0.00],
    ]
)


def test_table3_statistics_match_paper() -> None:
    means, sds = column_statistics(TABLE3)
    np.testing.assert_allclose(means, [19.73, 16.65, 32.57, 18.24, 14.55, 19.79, 13.12], atol=0.006)
    np.testing.assert_allclose(sds[:2], [10.32, 12.79], atol=0.02)
    labels = [f"s{i:02d}" for i in range(1, 8)]
    text = format_dtw_table(TABLE3, labels, title="smileFrown / open-mouth smile")
    lines = text.splitlines()
    assert lines[0] == "smileFrown / open-mouth smile"
    assert lines[2].split() == ["s01", "12.85", "12.88", "27.82", "16.68", "36.82", "11.31"]
    assert lines[-2].split()[:2] == ["mean", "19.73"]
    lower = format_dtw_table(TABLE3, labels, lower_only=True, statistics=False, decimals=1)
    assert lower.splitlines()[1].split() == ["s01"] and lower.splitlines()[2].split() == ["s02", "12.8"]


def test_heatmap(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    matrix = dtw_distance_matrix(np.random.default_rng(0).normal(size=(4, 12)))
    path = plot_dtw_heatmap(matrix, ["a", "b", "c", "d"], tmp_path / "heat.png", title="jaw")
    assert path.stat().st_size > 1000 and path.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(InvalidValueError, match="labels"):
        plot_dtw_heatmap(matrix, ["a"], tmp_path / "x.png")
