"""DTW distance matrices: mien's numba kernels against dtaidistance's C library, same data, same run.

Data: 91 performances x 17 controllers x 200 frames of seeded random walks (the size of a learned laughter
library). Two tasks:

1. multivariate matrix (91 x 91, cost summed over the 17 channels): ``dtw_distance_matrix`` vs
   ``dtaidistance.dtw_ndim.distance_matrix_fast``, on all cores and then on one thread each;
2. per-channel matrices (17 x 91 x 91, the paper's Table 3 form): ``dtw_distance_matrices_per_channel`` vs
   ``dtaidistance.dtw.distance_matrix_fast`` once per channel.

Both libraries use all cores (numba threads / dtaidistance OpenMP). Compilation is excluded (a warm-up call
first; the kernels are cached on disk). Prints the median of the repeats, the ratio and the largest absolute
difference of the upper triangles. Run: ``.venv/bin/python bench/dtw.py [--repeats 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np


def timed(function: Callable[[], np.ndarray], repeats: int) -> tuple[float, np.ndarray]:
    """Median seconds over ``repeats`` calls, and the last result."""
    seconds = []
    result = function()
    for _ in range(repeats):
        start = time.perf_counter()
        result = function()
        seconds.append(time.perf_counter() - start)
    return statistics.median(seconds), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--series", type=int, default=91)
    parser.add_argument("--channels", type=int, default=17)
    parser.add_argument("--frames", type=int, default=200)
    args = parser.parse_args()

    import numba
    from dtaidistance import dtw as dtai_dtw
    from dtaidistance import dtw_ndim

    from mien.learning.dtw import dtw_distance_matrices_per_channel, dtw_distance_matrix

    rng = np.random.default_rng(2021)
    data = np.cumsum(rng.normal(size=(args.series, args.frames, args.channels)), axis=1)
    upper = np.triu_indices(args.series, k=1)
    cells = args.series * (args.series - 1) // 2 * args.frames**2
    print(
        f"{args.series} series x {args.channels} channels x {args.frames} frames, {numba.get_num_threads()} threads, "
        f"median of {args.repeats}"
    )

    start = time.perf_counter()
    dtw_distance_matrix(data[:3])
    dtw_distance_matrices_per_channel(data[:3])
    print(f"warm-up (compile or load cache): {time.perf_counter() - start:.2f} s")

    mine_s, mine = timed(lambda: dtw_distance_matrix(data), args.repeats)
    base_s, base = timed(lambda: dtw_ndim.distance_matrix_fast(data, parallel=True), args.repeats)
    diff = float(np.abs(mine[upper] - base[upper]).max())
    print(
        f"multivariate : mien {mine_s:.3f} s ({mine_s / cells * 1e9:.2f} ns/cell)  "
        f"dtaidistance dtw_ndim.distance_matrix_fast {base_s:.3f} s  ratio {base_s / mine_s:.2f}x  "
        f"max|diff| {diff:.1e}"
    )

    mine_s, mine = timed(lambda: dtw_distance_matrix(data, n_jobs=1), args.repeats)
    base_s, base = timed(lambda: dtw_ndim.distance_matrix_fast(data, parallel=False), args.repeats)
    diff = float(np.abs(mine[upper] - base[upper]).max())
    print(
        f"multivariate, 1 thread each: mien {mine_s:.3f} s  dtaidistance {base_s:.3f} s  "
        f"ratio {base_s / mine_s:.2f}x  max|diff| {diff:.1e}"
    )

    channels = [np.ascontiguousarray(data[:, :, k]) for k in range(args.channels)]
    mine_s, mine = timed(lambda: dtw_distance_matrices_per_channel(data), args.repeats)
    base_s, base_list = timed(
        lambda: np.stack([dtai_dtw.distance_matrix_fast(c, parallel=True) for c in channels]), args.repeats
    )
    diff = float(max(np.abs(mine[k][upper] - base_list[k][upper]).max() for k in range(args.channels)))
    print(
        f"per channel  : mien {mine_s:.3f} s ({mine_s / cells / args.channels * 1e9:.2f} ns/cell)  "
        f"dtaidistance dtw.distance_matrix_fast x{args.channels} {base_s:.3f} s  ratio {base_s / mine_s:.2f}x  "
        f"max|diff| {diff:.1e}"
    )


if __name__ == "__main__":
    main()
