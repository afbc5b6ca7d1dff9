"""Benchmark: sparse morph-target blending (mien.rig.deform) against a dense all-targets numpy product.

Run: ``.venv/bin/python bench/deform.py``. Uses the ICT-FaceKit head when it is found (``MIEN_ICT_FACEKIT``, the
config file, or ``../shared/assets/ict-facekit``), else the built-in head, else a synthetic 25k-vertex rig.
Each frame has ~10 active targets. Prints median per-frame times (median of several repeats) of:

- the kernel (numba, and the numpy fallback), writing into a reused output buffer;
- the baseline ``neutral + W @ D`` with a dense ``D`` of shape (n_targets, n_vertices * 3), float32;
- the memory-bandwidth bound: the bytes the kernel must move (read the neutral mesh and the active targets'
  deltas, write the output) at the copy bandwidth of a large numpy copy measured in the same run;
- the kernel and the baseline again with the caches flushed before each frame (as in an application that
  renders between frames).
"""

from __future__ import annotations

import os

# One thread for the BLAS baseline, like the single-threaded kernel (a second BLAS thread on a busy 2-core
# machine makes the baseline erratic); set MIEN_BENCH_BLAS_THREADS to change it.
os.environ["OPENBLAS_NUM_THREADS"] = os.environ["OMP_NUM_THREADS"] = os.environ.get("MIEN_BENCH_BLAS_THREADS", "1")

import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from mien.errors import MienError  # noqa: E402
from mien.paths import asset_path  # noqa: E402
from mien.rig.deform import Deformer, numba_available  # noqa: E402
from mien.rig.model import MorphTarget, Rig  # noqa: E402

N_FRAMES = 200
N_ACTIVE = 10
REPEATS = 7
COLD_FRAMES = 50


def _synthetic_rig(n_vertices: int = 25000, n_targets: int = 52) -> Rig:
    rng = np.random.default_rng(0)
    targets = []
    for t in range(n_targets):
        ids = np.sort(rng.choice(n_vertices, n_vertices // 10, replace=False))
        targets.append(MorphTarget(f"t{t}", ids, rng.normal(0, 0.002, (len(ids), 3))))
    return Rig("synthetic", rng.normal(0, 0.05, (n_vertices, 3)), np.zeros((0, 3)), tuple(targets), np.zeros(68))


def load_rig() -> Rig:
    """ICT-FaceKit if present, else the built-in head, else a synthetic rig."""
    from mien.rig.ict_facekit import load_ict_facekit

    for candidate in (asset_path("ict_facekit"), REPO.parent / "shared" / "assets" / "ict-facekit"):
        if candidate is not None and candidate.exists():
            try:
                return load_ict_facekit(candidate)
            except MienError as exc:
                print(f"ICT-FaceKit at {candidate} not usable: {exc}")
    try:
        from mien.rig import builtin_head

        for name in ("builtin_head", "load_builtin_head", "build_builtin_head"):
            if hasattr(builtin_head, name):
                rig: Rig = getattr(builtin_head, name)()
                return rig
    except ImportError:
        pass
    return _synthetic_rig()


def per_frame_ms(runs: dict[str, Callable[[np.ndarray], object]], weights: np.ndarray) -> dict[str, float]:
    """Median over repeats of the mean time per frame, in milliseconds, for each run.

    Repeats of the different runs are interleaved so that they see the same machine load.
    """
    for run in runs.values():
        run(weights[0])  # warm up (compiles numba on first use)
    times: dict[str, list[float]] = {name: [] for name in runs}
    for _ in range(REPEATS):
        for name, run in runs.items():
            start = time.perf_counter()
            for w in weights:
                run(w)
            times[name].append((time.perf_counter() - start) / len(weights))
    return {name: float(np.median(values) * 1e3) for name, values in times.items()}


def per_frame_cold_ms(
    runs: dict[str, Callable[[np.ndarray], object]], weights: np.ndarray, scratch: np.ndarray
) -> dict[str, float]:
    """Median time of single frames run right after the caches were flushed (a 64 MiB write, untimed), in ms.

    This is the situation of a real application, where rendering and other work evict the rig's data from the
    caches between two frames.
    """
    times: dict[str, list[float]] = {name: [] for name in runs}
    for w in weights:
        for name, run in runs.items():
            scratch += 1.0
            start = time.perf_counter()
            run(w)
            times[name].append(time.perf_counter() - start)
    return {name: float(np.median(values) * 1e3) for name, values in times.items()}


def copy_bandwidth_gbs(n_bytes: int = 256 * 2**20) -> float:
    """(bytes read + bytes written) / s of a large numpy copy, median of 5."""
    source = np.ones(n_bytes // 4, np.float32)
    target = np.empty_like(source)
    times = []
    for _ in range(5):
        start = time.perf_counter()
        np.copyto(target, source)
        times.append(time.perf_counter() - start)
    return 2 * n_bytes / float(np.median(times)) / 1e9


def main() -> None:
    rig = load_rig()
    n, n_targets = rig.n_vertices, len(rig.targets)
    rng = np.random.default_rng(1)
    movable = [i for i, t in enumerate(rig.targets[:52]) if len(t.vertex_ids)]
    weights = np.zeros((N_FRAMES, n_targets), np.float32)
    for row in weights:
        row[rng.choice(movable, N_ACTIVE, replace=False)] = rng.uniform(0.1, 1.0, N_ACTIVE)
    print(f"BLAS threads for the baseline: {os.environ['OPENBLAS_NUM_THREADS']}")
    print(f"rig {rig.name}: {n} vertices, {n_targets} targets, {N_ACTIVE} active per frame, {N_FRAMES} frames")

    out = np.empty((n, 3), np.float32)
    runs: dict[str, Callable[[np.ndarray], object]] = {}
    backends = ["numba", "numpy"] if numba_available() else ["numpy"]
    for backend in backends:
        deformer = Deformer(rig, backend=backend)
        runs[f"sparse kernel ({backend})"] = lambda w, d=deformer: d.deform(w, out=out)

    dense = np.stack([t.dense(n).reshape(-1) for t in rig.targets])  # (T, n*3) float32
    neutral = rig.neutral.reshape(-1)
    product = np.empty(n * 3, np.float32)
    flat_out = out.reshape(-1)

    def dense_frame(w: np.ndarray) -> None:
        np.matmul(w, dense, out=product)
        np.add(neutral, product, out=flat_out)

    baseline = "dense baseline neutral + W @ D"
    runs[baseline] = dense_frame
    deformer = Deformer(rig)
    dense_frame(weights[0])
    np.testing.assert_allclose(deformer.deform(weights[0]), out, atol=1e-6)
    results = per_frame_ms(runs, weights)

    bandwidth = copy_bandwidth_gbs()
    sizes = np.diff(deformer.offsets)
    moved = float(np.mean([sizes[np.flatnonzero(w)].sum() for w in weights]))
    # Read the neutral mesh, write the output, read the deltas of the moved vertices (ids are run-length coded).
    bytes_needed = n * 12 * 2 + moved * 12
    bound_ms = bytes_needed / (bandwidth * 1e9) * 1e3

    kernel_name = f"sparse kernel ({backends[0]})"
    cold_runs = {kernel_name: runs[kernel_name], baseline: runs[baseline]}
    cold = per_frame_cold_ms(cold_runs, weights[:COLD_FRAMES], np.zeros(64 * 2**18, np.float32))
    kernel = results[kernel_name]
    print("warm caches (frames back to back; the 18 MiB dense D can stay in a large L3 cache):")
    for name, ms in results.items():
        print(f"  {name:<34} {ms:8.4f} ms/frame")
    print(
        f"  {'memory-bandwidth bound':<34} {bound_ms:8.4f} ms/frame "
        f"({bytes_needed / 1e6:.2f} MB/frame at {bandwidth:.1f} GB/s read+write, large numpy copy)"
    )
    print(f"  ratio dense baseline / {kernel_name}: {results[baseline] / kernel:.1f}x")
    print(f"  ratio {kernel_name} / bandwidth bound: {kernel / bound_ms:.2f}x")
    print(f"cold caches (flushed before each frame, {COLD_FRAMES} frames, D is {dense.nbytes / 2**20:.1f} MiB):")
    for name, ms in cold.items():
        print(f"  {name:<34} {ms:8.4f} ms/frame")
    print(f"  ratio dense baseline / {kernel_name}: {cold[baseline] / cold[kernel_name]:.1f}x")
    print(f"mean vertex entries touched per frame: {moved:.0f} of {n} vertices x {N_ACTIVE} targets")


if __name__ == "__main__":
    main()
