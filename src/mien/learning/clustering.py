"""Clustering curves with the DTW distance, and the representative curve of a set of performances.

Mascaró et al. (2021) cluster the performers' controller curves of one expression type with k-means on DTW
alignment values and keep the prototypes of the main cluster. mien offers:

- :class:`KMedoidsDTW`: k-medoids (FasterPAM, Schubert and Rousseeuw 2021, from the ``kmedoids`` package) on
  the precomputed DTW matrix; prototypes are real performances (medoids).
- :class:`KMeansDTW`: k-means whose centroids are DTW barycenters (DBA), started from the k-medoids medoids.
- :func:`representative_curve`: the medoid or the DBA average of the largest cluster.

**Choosing k** (``n_clusters=None``): every k in ``2..min(max_clusters, n - 1)`` is fitted and scored by the
mean silhouette on the precomputed DTW distances; the best k is kept unless its silhouette is below
:data:`SILHOUETTE_THRESHOLD` (0.25: "no substantial structure", Kaufman and Rousseeuw 1990, *Finding Groups
in Data*, ch. 2), in which case the data form one cluster (k = 1). With fewer than 3 series k is 1.

Clusters are numbered by decreasing size (ties: smaller medoid index first), so label 0 is the main cluster.

>>> import numpy as np
>>> t = np.linspace(0, 1, 40)
>>> smiles = [np.sin(np.pi * t) * (1 + 0.1 * i) for i in range(4)]
>>> frowns = [-np.sin(np.pi * t) * (1 + 0.1 * i) for i in range(3)]
>>> model = KMedoidsDTW(random_state=0).fit(smiles + frowns)
>>> model.n_clusters_, model.labels_.tolist()
(2, [0, 0, 0, 0, 1, 1, 1])
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from mien.errors import InvalidValueError
from mien.extras import require
from mien.learning.barycenter import dtw_barycenter
from mien.learning.dtw import SeriesInput, as_series_list, dtw_cross_distance_matrix, dtw_distance_matrix

__all__ = ["SILHOUETTE_THRESHOLD", "KMeansDTW", "KMedoidsDTW", "representative_curve"]

SILHOUETTE_THRESHOLD = 0.25
"""Below this best mean silhouette the series are taken as one cluster (Kaufman and Rousseeuw 1990)."""


def _check_distances(matrix: np.ndarray) -> np.ndarray:
    distances = np.asarray(matrix, dtype=np.float64)
    if distances.ndim != 2 or distances.shape[0] != distances.shape[1] or distances.shape[0] == 0:
        raise InvalidValueError("precomputed", f"array of shape {distances.shape}", "a square (n, n) matrix, n >= 1")
    if not np.all(np.isfinite(distances)) or np.any(distances < 0):
        raise InvalidValueError("precomputed", "non-finite or negative entries", "finite distances >= 0")
    if not np.allclose(distances, distances.T, rtol=1e-9, atol=1e-12):
        raise InvalidValueError("precomputed", "an asymmetric matrix", "a symmetric distance matrix")
    return distances


def _check_int(name: str, value: object, low: int, high: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < low:
        raise InvalidValueError(name, value, f"an integer >= {low}" + (f" and <= {high}" if high else ""))
    if high is not None and value > high:
        raise InvalidValueError(name, value, f"an integer >= {low} and <= {high}")
    return int(value)


def _ordered(labels: np.ndarray, medoids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Renumber clusters by decreasing size, ties by medoid index."""
    sizes = np.bincount(labels, minlength=len(medoids))
    order = sorted(range(len(medoids)), key=lambda c: (-sizes[c], medoids[c]))
    mapping = np.empty(len(medoids), dtype=np.int64)
    mapping[order] = np.arange(len(medoids))
    return mapping[labels], medoids[order]


def _fasterpam(distances: np.ndarray, k: int, seed: int, n_init: int) -> tuple[np.ndarray, np.ndarray, float]:
    """Best of ``n_init`` FasterPAM runs: labels (n,), medoid indices (k,), loss (sum of distances)."""
    n = distances.shape[0]
    if k == 1:
        medoid = int(np.argmin(distances.sum(axis=1)))
        return np.zeros(n, dtype=np.int64), np.array([medoid]), float(distances[medoid].sum())
    kmedoids = require("kmedoids", "laughter")
    best: tuple[np.ndarray, np.ndarray, float] | None = None
    seeds = np.random.SeedSequence(seed).generate_state(n_init)
    for run_seed in seeds:
        result = kmedoids.fasterpam(distances, k, random_state=int(run_seed), n_cpu=1)
        if best is None or result.loss < best[2] - 1e-12:
            best = (np.asarray(result.labels, dtype=np.int64), np.asarray(result.medoids, dtype=np.int64), result.loss)
    assert best is not None
    labels, medoids = _ordered(*best[:2])
    return labels, medoids, float(best[2])


def _silhouette(distances: np.ndarray, labels: np.ndarray) -> float:
    """Mean silhouette (Rousseeuw 1987) on a precomputed distance matrix; singletons score 0."""
    n = distances.shape[0]
    k = int(labels.max()) + 1
    sums = np.stack([distances[:, labels == c].sum(axis=1) for c in range(k)], axis=1)
    sizes = np.bincount(labels, minlength=k).astype(np.float64)
    own = sizes[labels]
    a = sums[np.arange(n), labels] / np.maximum(own - 1, 1)
    other = sums / sizes[None, :]
    other[np.arange(n), labels] = np.inf
    b = other.min(axis=1)
    scores = np.where(own > 1, (b - a) / np.maximum(np.maximum(a, b), 1e-300), 0.0)
    return float(scores.mean())


class KMedoidsDTW:
    """k-medoids on DTW distances (scikit-learn style).

    ``n_clusters``: an int, or None to choose k by the silhouette criterion (module docstring) over
    ``2..max_clusters``. ``random_state``: seed of the FasterPAM initialisations (``n_init`` runs, the lowest
    loss kept), so a seed gives the same result every time. ``window``: Sakoe-Chiba band (frames) when the
    distances are computed here.

    Learned attributes: ``labels_`` (n,) int (0 = largest cluster), ``medoid_indices_`` (k,) int,
    ``cluster_centers_`` (the medoid series: (k, n_frames, c) array when lengths agree, else a list),
    ``inertia_`` (sum of DTW distances to the own medoid), ``n_clusters_``, ``silhouette_`` (mean silhouette,
    NaN for k = 1), ``silhouette_by_k_`` (dict k -> score when k was chosen), ``distance_matrix_`` (n, n).
    """

    def __init__(
        self,
        n_clusters: int | None = None,
        *,
        max_clusters: int = 8,
        random_state: int = 0,
        n_init: int = 5,
        window: int | None = None,
    ) -> None:
        if n_clusters is not None:
            _check_int("n_clusters", n_clusters, 1)
        self.n_clusters = n_clusters
        self.max_clusters = _check_int("max_clusters", max_clusters, 1)
        self.random_state = int(random_state)
        self.n_init = _check_int("n_init", n_init, 1)
        self.window = window

    def fit(self, series: SeriesInput | None = None, *, precomputed: np.ndarray | None = None) -> KMedoidsDTW:
        """Cluster ``series`` (a collection, see :mod:`mien.learning.dtw`) or a precomputed (n, n) matrix."""
        items: list[np.ndarray] | None = None
        if precomputed is None:
            if series is None:
                raise InvalidValueError("series", None, "series or precomputed=distance matrix")
            items = as_series_list(series)
            distances = dtw_distance_matrix(items, window=self.window)
        else:
            distances = _check_distances(precomputed)
            if series is not None:
                items = as_series_list(series)
                if len(items) != distances.shape[0]:
                    raise InvalidValueError("series", f"{len(items)} series", f"{distances.shape[0]} like precomputed")
        n = distances.shape[0]
        scores: dict[int, float] = {}
        if self.n_clusters is not None:
            k = _check_int("n_clusters", self.n_clusters, 1, n)
            labels, medoids, loss = _fasterpam(distances, k, self.random_state, self.n_init)
        else:
            fits = {}
            for k in range(2, min(self.max_clusters, n - 1) + 1):
                fits[k] = _fasterpam(distances, k, self.random_state, self.n_init)
                scores[k] = _silhouette(distances, fits[k][0])
            best = max(scores, key=lambda key: (scores[key], -key)) if scores else None
            if best is None or scores[best] < SILHOUETTE_THRESHOLD:
                labels, medoids, loss = _fasterpam(distances, 1, self.random_state, self.n_init)
            else:
                labels, medoids, loss = fits[best]
        self.distance_matrix_ = distances
        self.labels_ = labels
        self.medoid_indices_ = medoids
        self.inertia_ = loss
        self.n_clusters_ = len(medoids)
        self.silhouette_ = _silhouette(distances, labels) if self.n_clusters_ > 1 else float("nan")
        self.silhouette_by_k_ = scores
        self.series_ = items
        if items is not None:
            centers = [items[m] for m in medoids]
            same = len({c.shape for c in centers}) == 1
            self.cluster_centers_: np.ndarray | list[np.ndarray] | None = np.stack(centers) if same else centers
        else:
            self.cluster_centers_ = None
        return self

    def predict(self, series: SeriesInput) -> np.ndarray:
        """(n,) index of the nearest medoid (DTW) for new series; needs a fit on series, not only distances."""
        if getattr(self, "cluster_centers_", None) is None:
            raise InvalidValueError("model", "not fitted on series", "fit(series) before predict")
        assert self.cluster_centers_ is not None
        distances = dtw_cross_distance_matrix(series, list(self.cluster_centers_), window=self.window)
        return np.argmin(distances, axis=1)


class KMeansDTW:
    """k-means with the DTW distance and DBA centroids (scikit-learn style).

    Started from :class:`KMedoidsDTW` medoids (so k is chosen the same way when ``n_clusters`` is None and the
    result is deterministic for a seed), then alternates: assign each series to the nearest centroid (DTW),
    replace each centroid by the DBA average of its members (``dba_iter`` steps from the current centroid),
    until the labels stop changing or ``max_iter`` rounds.

    Learned attributes: ``labels_`` (n,), ``cluster_centers_`` (list of (n_frames_k, c) arrays),
    ``inertia_`` (sum of squared DTW distances to the own centroid), ``n_clusters_``, ``n_iter_``.
    """

    def __init__(
        self,
        n_clusters: int | None = None,
        *,
        max_clusters: int = 8,
        random_state: int = 0,
        max_iter: int = 10,
        dba_iter: int = 5,
        window: int | None = None,
    ) -> None:
        self.n_clusters = n_clusters
        self.max_clusters = max_clusters
        self.random_state = random_state
        self.max_iter = _check_int("max_iter", max_iter, 1)
        self.dba_iter = _check_int("dba_iter", dba_iter, 1)
        self.window = window

    def fit(self, series: SeriesInput, *, precomputed: np.ndarray | None = None) -> KMeansDTW:
        """Cluster ``series``; ``precomputed`` (n, n) DTW matrix of the same series saves recomputing it."""
        items = as_series_list(series)
        start = KMedoidsDTW(
            self.n_clusters, max_clusters=self.max_clusters, random_state=self.random_state, window=self.window
        ).fit(items, precomputed=precomputed)
        centers = [items[m].copy() for m in start.medoid_indices_]
        labels = start.labels_.copy()
        n_iter = 0
        while n_iter < self.max_iter:
            n_iter += 1
            for c in range(len(centers)):
                members = [items[i] for i in np.flatnonzero(labels == c)]
                if members:
                    centers[c] = dtw_barycenter(
                        members, init=centers[c], max_iter=self.dba_iter, window=self.window
                    ).curve
            distances = dtw_cross_distance_matrix(items, centers, window=self.window)
            new_labels = np.argmin(distances, axis=1)
            if np.array_equal(new_labels, labels):
                break
            labels = new_labels
        distances = dtw_cross_distance_matrix(items, centers, window=self.window)
        self.labels_ = labels
        self.cluster_centers_ = centers
        self.inertia_ = float((distances[np.arange(len(items)), labels] ** 2).sum())
        self.n_clusters_ = len(centers)
        self.n_iter_ = n_iter
        return self


def representative_curve(
    series: SeriesInput,
    method: Literal["medoid", "dba"] = "medoid",
    *,
    n_clusters: int | None = None,
    max_clusters: int = 8,
    random_state: int = 0,
    window: int | None = None,
    precomputed: np.ndarray | None = None,
    max_iter: int = 30,
    tol: float = 1e-5,
) -> np.ndarray:
    """The prototype of the main (largest) DTW cluster of ``series``: (n_frames, n_channels) float64.

    ``method="medoid"`` returns that cluster's medoid (a real performance); ``"dba"`` its DTW barycenter
    average (:func:`~mien.learning.barycenter.dtw_barycenter`, started from the medoid, ``max_iter`` steps,
    relative tolerance ``tol``), which has the medoid's length. Clustering as in :class:`KMedoidsDTW`.
    """
    if method not in ("medoid", "dba"):
        raise InvalidValueError("method", method, "'medoid' or 'dba'")
    items = as_series_list(series)
    model = KMedoidsDTW(n_clusters, max_clusters=max_clusters, random_state=random_state, window=window)
    model.fit(items, precomputed=precomputed)
    medoid = items[int(model.medoid_indices_[0])]
    if method == "medoid":
        return medoid.copy()
    members = [items[i] for i in np.flatnonzero(model.labels_ == 0)]
    return dtw_barycenter(members, init=medoid, max_iter=max_iter, tol=tol, window=window).curve
