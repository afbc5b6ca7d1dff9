"""DTW barycenter averaging (DBA; Petitjean, Ketterlin and Gançarski 2011, Pattern Recognition 44(3)).

DBA refines an average curve: align every member to the current average with DTW, then replace each frame of
the average by the mean of the member frames aligned to it. Each step cannot increase the sum of squared DTW
distances from the average to the members (the "inertia"), so the iteration stops after ``max_iter`` steps or
when the inertia improves by less than ``tol`` (relative).

>>> import numpy as np
>>> curves = [np.sin(np.linspace(0, 3, 30) + shift) for shift in (0.0, 0.1, 0.2)]
>>> result = dtw_barycenter(curves, init=curves[1])
>>> result.curve.shape, result.inertia_history[-1] <= result.inertia_history[0]
((30, 1), True)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mien.errors import InvalidValueError
from mien.learning.dtw import SeriesInput, as_series, as_series_list, dtw_distance_matrix, dtw_path

__all__ = ["DBAResult", "dtw_barycenter"]


@dataclass(frozen=True, eq=False)
class DBAResult:
    """The outcome of :func:`dtw_barycenter`."""

    curve: np.ndarray
    """(n_frames, n_channels) float64 barycenter; ``n_frames`` is the length of the initial curve."""
    inertia_history: tuple[float, ...]
    """Sum of squared DTW distances from the curve to the members: the initial curve's, then after each step."""
    n_iter: int
    """Number of update steps done."""
    converged: bool
    """True when the relative improvement fell below ``tol`` before ``max_iter``."""


def _inertia(curve: np.ndarray, members: list[np.ndarray], window: int | None) -> float:
    return float(sum(dtw_path(curve, member, window)[1] ** 2 for member in members))


def _update(curve: np.ndarray, members: list[np.ndarray], window: int | None) -> tuple[np.ndarray, float]:
    """One DBA step: the new curve and the inertia of the *old* curve (both from the same alignments)."""
    sums = np.zeros_like(curve)
    counts = np.zeros(curve.shape[0])
    inertia = 0.0
    for member in members:
        path, distance = dtw_path(curve, member, window)
        np.add.at(sums, path[:, 0], member[path[:, 1]])
        np.add.at(counts, path[:, 0], 1.0)
        inertia += distance**2
    return sums / counts[:, None], inertia


def dtw_barycenter(
    series: SeriesInput,
    *,
    init: np.ndarray | None = None,
    max_iter: int = 30,
    tol: float = 1e-5,
    window: int | None = None,
) -> DBAResult:
    """DTW barycenter average of ``series`` (a collection; see :mod:`mien.learning.dtw`).

    ``init``: (n_frames, n_channels) or (n_frames,) starting curve; None starts from the medoid (the member
    with the smallest sum of squared DTW distances to the others), which makes the result deterministic.
    ``max_iter``: most update steps; ``tol``: stop when the inertia drops by less than ``tol`` times itself.
    ``window``: Sakoe-Chiba band in frames for the alignments.
    """
    members = as_series_list(series)
    if isinstance(max_iter, bool) or not isinstance(max_iter, int) or max_iter < 0:
        raise InvalidValueError("max_iter", max_iter, "an integer >= 0")
    if not np.isfinite(tol) or tol < 0:
        raise InvalidValueError("tol", tol, "a finite number >= 0")
    if init is None:
        distances = dtw_distance_matrix(members, window=window)
        curve = members[int(np.argmin((distances**2).sum(axis=1)))].copy()
    else:
        curve = as_series(init, "init").copy()
        if curve.shape[1] != members[0].shape[1]:
            raise InvalidValueError("init", f"{curve.shape[1]} channels", f"{members[0].shape[1]} channels")
    history: list[float] = []
    converged = False
    n_iter = 0
    for _ in range(max_iter):
        updated, inertia = _update(curve, members, window)
        history.append(inertia)
        if len(history) >= 2 and history[-2] - history[-1] <= tol * history[-2]:
            converged = True
            break
        curve = updated
        n_iter += 1
    if not converged:
        history.append(_inertia(curve, members, window))
    return DBAResult(curve=curve, inertia_history=tuple(history), n_iter=n_iter, converged=converged)
