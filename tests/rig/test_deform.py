"""Sparse morph-target blending: numba and numpy paths, batches, buffers, bad input, the real ICT head."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingExtraError
from mien.rig import deform
from mien.rig.deform import Deformer, numba_available
from mien.rig.ict_facekit import load_ict_facekit
from mien.rig.model import MorphTarget, Rig

needs_numba = pytest.mark.skipif(not numba_available(), reason="numba (mien[fast]) not installed")


def _random_rig(n_vertices: int = 500, n_targets: int = 12, seed: int = 0) -> Rig:
    rng = np.random.default_rng(seed)
    targets = []
    for t in range(n_targets):
        ids = np.sort(rng.choice(n_vertices, size=rng.integers(0, n_vertices // 4), replace=False))
        targets.append(MorphTarget(f"t{t}", ids, rng.normal(0.0, 0.002, (len(ids), 3))))
    neutral = rng.normal(0.0, 0.05, (n_vertices, 3))
    return Rig("random", neutral, np.array([[0, 1, 2]]), tuple(targets), np.zeros(68, int))


def _dense_reference(rig: Rig, weights: np.ndarray) -> np.ndarray:
    dense = np.stack([t.dense(rig.n_vertices) for t in rig.targets]).astype(np.float64)
    return np.asarray(rig.neutral + np.tensordot(weights, dense, axes=1))


def _weights(n_frames: int, n_targets: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    weights = rng.uniform(-0.2, 1.0, (n_frames, n_targets)).astype(np.float32)
    weights[rng.random(weights.shape) < 0.6] = 0.0  # most targets off, as in a real frame
    return weights


@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=needs_numba)])
def test_matches_dense_reference(backend: str) -> None:
    rig = _random_rig()
    deformer = Deformer(rig, backend=backend)
    assert deformer.backend == backend
    for w in _weights(5, len(rig.targets)):
        np.testing.assert_allclose(deformer.deform(w), _dense_reference(rig, w), atol=1e-6)
    np.testing.assert_array_equal(deformer.deform(np.zeros(len(rig.targets))), rig.neutral)


@pytest.mark.parametrize("backend", ["numpy", pytest.param("numba", marks=needs_numba)])
def test_batch_equals_one_by_one_and_reuses_buffers(backend: str) -> None:
    rig = _random_rig()
    deformer = Deformer(rig, backend=backend)
    weights = _weights(7, len(rig.targets))
    batch = deformer.deform_batch(weights)
    assert batch.shape == (7, rig.n_vertices, 3) and batch.dtype == np.float32
    buffer = np.empty((rig.n_vertices, 3), np.float32)
    for b in range(len(weights)):
        result = deformer.deform(weights[b], out=buffer)
        assert result is buffer
        np.testing.assert_array_equal(batch[b], buffer)
    batch_buffer = np.empty_like(batch)
    assert deformer.deform_batch(weights, out=batch_buffer) is batch_buffer
    np.testing.assert_array_equal(batch_buffer, batch)


@needs_numba
def test_numba_and_numpy_agree() -> None:
    rig = _random_rig(n_vertices=2000, n_targets=30, seed=3)
    weights = _weights(10, 30, seed=4)
    fast = Deformer(rig, backend="numba").deform_batch(weights)
    slow = Deformer(rig, backend="numpy").deform_batch(weights)
    np.testing.assert_allclose(fast, slow, atol=1e-7)


def test_without_numba_auto_falls_back(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(deform, "numba_available", lambda: False)
    rig = _random_rig()
    assert Deformer(rig).backend == "numpy"
    with pytest.raises(MissingExtraError, match=r"mien\[fast\]"):
        Deformer(rig, backend="numba")


def test_bad_input() -> None:
    rig = _random_rig()
    deformer = Deformer(rig, backend="numpy")
    with pytest.raises(InvalidValueError, match="backend"):
        Deformer(rig, backend="cuda")
    with pytest.raises(InvalidValueError, match="weights"):
        deformer.deform(np.zeros(3))
    with pytest.raises(InvalidValueError, match="weights"):
        deformer.deform(np.full(len(rig.targets), np.nan))
    with pytest.raises(InvalidValueError, match="weights"):
        deformer.deform_batch(np.zeros(len(rig.targets)))
    with pytest.raises(InvalidValueError, match="out"):
        deformer.deform(np.zeros(len(rig.targets)), out=np.empty((rig.n_vertices, 3)))  # float64


def test_ict_head_paths_agree(ict_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    with pytest.MonkeyPatch.context() as patch:
        if "MIEN_CACHE_DIR" not in os.environ:
            patch.setenv("MIEN_CACHE_DIR", str(tmp_path_factory.getbasetemp() / "mien-cache"))
        rig = load_ict_facekit(ict_dir)
    rng = np.random.default_rng(5)
    weights = np.zeros((4, len(rig.targets)), np.float32)
    for row in weights:
        row[rng.choice(52, 10, replace=False)] = rng.random(10)
    slow = Deformer(rig, backend="numpy").deform_batch(weights)
    np.testing.assert_allclose(slow[0], _dense_reference(rig, weights[0]), atol=1e-6)
    if numba_available():
        np.testing.assert_allclose(Deformer(rig, backend="numba").deform_batch(weights), slow, atol=1e-7)
    # jawOpen at 1 drops the chin by centimetres.
    jaw = np.zeros(len(rig.targets), np.float32)
    jaw[rig.target_index("jawOpen")] = 1.0
    chin = rig.landmarks[8]
    drop = rig.neutral[chin, 1] - Deformer(rig).deform(jaw)[chin, 1]
    assert 0.01 < drop < 0.05
