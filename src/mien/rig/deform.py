"""Blend morph targets: ``vertices = neutral + sum_t w_t * delta_t``, fast when few targets are active.

Each target is stored sparsely (the vertices it moves), and targets whose weight is zero are skipped, so the
cost is one copy of the neutral mesh plus the moved vertices of the active targets, not ``n_targets *
n_vertices``. The numba kernel (``pip install 'mien[fast]'``) stores each target as runs of consecutive vertex
ids (short gaps filled with zero deltas), so its inner loop is a contiguous ``out[a:b] += w * delta[c:d]`` that
the compiler vectorises; without numba a numpy loop over the active targets gives the same results (up to float32
rounding), more slowly.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from mien.errors import InvalidValueError, MissingExtraError
from mien.extras import available
from mien.rig.model import Rig

__all__ = ["BACKENDS", "Deformer", "numba_available"]

BACKENDS = ("auto", "numba", "numpy")
"""Accepted ``backend`` values of :class:`Deformer`."""

_KERNELS: dict[str, Callable[..., Any]] = {}

RUN_GAP = 8
"""Runs of moved vertex ids are joined across gaps of up to this many unmoved vertices (zero deltas)."""


def numba_available() -> bool:
    """True when numba can be imported (the ``mien[fast]`` extra)."""
    return available("numba")


def _runs(ids: np.ndarray, deltas: np.ndarray, gap: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split ascending ``ids`` into runs of consecutive vertices, bridging gaps of up to ``gap`` vertices.

    Returns ``(starts (r,), lengths (r,), data (sum(lengths), 3))``: run ``i`` covers vertices
    ``starts[i] .. starts[i] + lengths[i] - 1`` and its deltas are the next ``lengths[i]`` rows of ``data``
    (zeros for bridged vertices).
    """
    if len(ids) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3), np.float32)
    ids = ids.astype(np.int64)
    breaks = np.flatnonzero(np.diff(ids) > gap + 1) + 1
    first = np.concatenate([[0], breaks])
    last = np.concatenate([breaks - 1, [len(ids) - 1]])
    starts = ids[first]
    lengths = ids[last] + 1 - starts
    run_of_entry = np.repeat(np.arange(len(first)), np.diff(np.concatenate([first, [len(ids)]])))
    data_starts = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    data = np.zeros((int(lengths.sum()), 3), np.float32)
    data[data_starts[run_of_entry] + ids - starts[run_of_entry]] = deltas
    return starts, lengths, data


def _numba_kernels() -> dict[str, Callable[..., Any]]:
    """Compile (once per process; cached on disk by numba) the sparse blend kernels."""
    if _KERNELS:
        return _KERNELS
    import numba

    @numba.njit(cache=True, nogil=True)
    def blend_one(neutral, weights, run_offsets, run_starts, run_lengths, data_starts, data, out):
        # All arrays flat: positions and lengths count floats (3 per vertex).
        out[:] = neutral
        for t in range(weights.shape[0]):
            w = weights[t]
            if w == 0.0:
                continue
            for q in range(run_offsets[t], run_offsets[t + 1]):
                length = run_lengths[q]
                dst = out[run_starts[q] : run_starts[q] + length]
                src = data[data_starts[q] : data_starts[q] + length]
                for j in range(length):
                    dst[j] += w * src[j]

    @numba.njit(cache=True, nogil=True)
    def blend_batch(neutral, weights, run_offsets, run_starts, run_lengths, data_starts, data, out):
        for b in range(weights.shape[0]):
            blend_one(neutral, weights[b], run_offsets, run_starts, run_lengths, data_starts, data, out[b])

    _KERNELS.update(one=blend_one, batch=blend_batch)
    return _KERNELS


class Deformer:
    """Deforms one rig's mesh for weight vectors over ``rig.targets``.

    ``backend``: ``"numba"`` (raises :class:`MissingExtraError` without numba), ``"numpy"``, or ``"auto"``
    (numba when installed). Both give the same vertices up to float32 rounding.

    >>> from mien.rig.model import MorphTarget, Rig
    >>> rig = Rig("tiny", np.zeros((3, 3)), np.array([[0, 1, 2]]),
    ...           (MorphTarget("up", [1], [[0.0, 0.01, 0.0]]),), np.zeros(68, int))
    >>> Deformer(rig, backend="numpy").deform(np.array([0.5]))[1].tolist()
    [0.0, 0.004999999888241291, 0.0]
    """

    def __init__(self, rig: Rig, backend: str = "auto") -> None:
        if backend not in BACKENDS:
            raise InvalidValueError("backend", backend, " / ".join(BACKENDS))
        if backend == "numba" and not numba_available():
            raise MissingExtraError("numba", "fast")
        self.backend = "numba" if backend == "numba" or (backend == "auto" and numba_available()) else "numpy"
        """The backend in use: ``"numba"`` or ``"numpy"``."""
        self.n_vertices = rig.n_vertices
        """Vertices of the rig's mesh."""
        self.n_targets = len(rig.targets)
        """Length of a weight vector."""
        self.neutral = np.ascontiguousarray(rig.neutral, dtype=np.float32)
        """(n_vertices, 3) float32 rest positions, metres."""
        sizes = [len(t.vertex_ids) for t in rig.targets]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        """(n_targets + 1,) start of each target's rows in :attr:`ids` / :attr:`deltas`."""
        self.ids = np.concatenate([t.vertex_ids for t in rig.targets] or [np.zeros(0, np.int32)]).astype(np.int32)
        """(k,) int32 moved vertex ids, all targets concatenated."""
        self.deltas = np.ascontiguousarray(
            np.concatenate([t.deltas for t in rig.targets] or [np.zeros((0, 3), np.float32)]), dtype=np.float32
        )
        """(k, 3) float32 deltas at weight 1, metres."""
        if self.backend == "numba":
            _numba_kernels()
            self._build_runs(rig)

    def _build_runs(self, rig: Rig) -> None:
        """The run-length layout the numba kernel reads (positions and lengths in floats, 3 per vertex)."""
        run_offsets, starts, lengths, data = [0], [], [], []
        for target in rig.targets:
            s, length, d = _runs(target.vertex_ids, target.deltas, RUN_GAP)
            run_offsets.append(run_offsets[-1] + len(s))
            starts.append(3 * s)
            lengths.append(3 * length)
            data.append(d.reshape(-1))
        self._run_offsets = np.array(run_offsets, np.int64)
        self._run_starts = np.concatenate(starts or [np.zeros(0, np.int64)]).astype(np.int64)
        self._run_lengths = np.concatenate(lengths or [np.zeros(0, np.int64)]).astype(np.int64)
        self._data_starts = np.concatenate([[0], np.cumsum(self._run_lengths)[:-1]]).astype(np.int64)
        self._data = np.ascontiguousarray(np.concatenate(data or [np.zeros(0, np.float32)]), dtype=np.float32)
        self._neutral_flat = self.neutral.reshape(-1)

    def _kernel_args(self) -> tuple[np.ndarray, ...]:
        return (self._run_offsets, self._run_starts, self._run_lengths, self._data_starts, self._data)

    def _check(self, weights: np.ndarray, batch: bool) -> np.ndarray:
        w = np.ascontiguousarray(weights, dtype=np.float32)
        shape = "(B, n_targets)" if batch else "(n_targets,)"
        if w.ndim != (2 if batch else 1) or w.shape[-1] != self.n_targets:
            raise InvalidValueError("weights", w.shape, f"{shape} with n_targets={self.n_targets}")
        if not np.all(np.isfinite(w)):
            raise InvalidValueError("weights", weights, "finite numbers")
        return w

    def _out(self, out: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
        if out is None:
            return np.empty(shape, np.float32)
        if out.shape != shape or out.dtype != np.float32 or not out.flags.c_contiguous:
            raise InvalidValueError("out", (out.shape, str(out.dtype)), f"C-contiguous float32 array {shape}")
        return out

    def deform(self, weights: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Vertices for one weight vector.

        ``weights``: (n_targets,) weights (usually 0..1). ``out``: an optional (n_vertices, 3) float32 buffer to
        write into (reuse it across frames to avoid an allocation per frame). Returns (n_vertices, 3) float32
        positions in metres (``out`` when given).
        """
        w = self._check(weights, batch=False)
        result = self._out(out, (self.n_vertices, 3))
        if self.backend == "numba":
            _KERNELS["one"](self._neutral_flat, w, *self._kernel_args(), result.reshape(-1))
        else:
            self._numpy_one(w, result)
        return result

    def deform_batch(self, weights: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Vertices for B weight vectors: ``weights`` (B, n_targets) -> (B, n_vertices, 3) float32, metres.

        ``out``: an optional (B, n_vertices, 3) float32 buffer to write into.
        """
        w = self._check(weights, batch=True)
        result = self._out(out, (w.shape[0], self.n_vertices, 3))
        if self.backend == "numba":
            flat = result.reshape(result.shape[0], self.n_vertices * 3)
            _KERNELS["batch"](self._neutral_flat, w, *self._kernel_args(), flat)
        else:
            for b in range(w.shape[0]):
                self._numpy_one(w[b], result[b])
        return result

    def _numpy_one(self, w: np.ndarray, out: np.ndarray) -> None:
        out[...] = self.neutral
        for t in np.flatnonzero(w):
            lo, hi = self.offsets[t], self.offsets[t + 1]
            # Ids within one target are unique, so fancy-index += adds each delta exactly once.
            out[self.ids[lo:hi]] += w[t] * self.deltas[lo:hi]
