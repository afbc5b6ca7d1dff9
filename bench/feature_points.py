"""Benchmark: building Broekens' feature-point rig (one biharmonic solve per feature) and compiling its skin-detail
correctives on ICT-FaceKit, against loading the head itself from mien's cache (the baseline every feature-point
character pays anyway).

Run: ``.venv/bin/python bench/feature_points.py``. Needs the asset (``MIEN_ICT_FACEKIT``, the config file, or
``../shared/assets/ict-facekit``). The two are timed in interleaved repeats (head load, rig build, ...) so load
from other processes hits both alike; prints medians, the spread (min..max) and the ratio, and the build time
against its 10 s budget (the issue: a feature-point head must be ready in seconds, uncached).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "src"))

from _ict import ict_facekit_folder, temporary_cache  # noqa: E402

from mien.rig.feature_points import FeaturePointRig  # noqa: E402
from mien.rig.fp_correctives import corrective_targets  # noqa: E402
from mien.rig.ict_facekit import load_ict_facekit  # noqa: E402

BUDGET_S = 10.0
REPEATS = 5


def _timed(run: object) -> float:
    start = time.perf_counter()
    run()  # type: ignore[operator]
    return time.perf_counter() - start


def main() -> None:
    folder = ict_facekit_folder()
    if folder is None:
        return
    with temporary_cache():
        rig = load_ict_facekit(folder)  # writes the cache
        fp = FeaturePointRig.build(rig)
        compiled = rig.with_targets(fp.compile())
        loads, builds, correctives = [], [], []
        for _ in range(REPEATS):
            loads.append(_timed(lambda: load_ict_facekit(folder)))
            builds.append(_timed(lambda: FeaturePointRig.build(rig)))
            correctives.append(_timed(lambda: corrective_targets(fp, compiled)))
    load, build, corrective = (float(np.median(t)) for t in (loads, builds, correctives))
    total = build + corrective
    print(f"ICT-FaceKit at {folder}: {rig.n_vertices} vertices, {REPEATS} interleaved repeats")
    print(f"  cached head load (baseline)   {load:7.3f} s median ({min(loads):.3f}..{max(loads):.3f})")
    print(f"  feature-point rig build       {build:7.3f} s median ({min(builds):.3f}..{max(builds):.3f})")
    spread = f"{min(correctives):.3f}..{max(correctives):.3f}"
    print(f"  skin-detail correctives       {corrective:7.3f} s median ({spread})")
    budget = f"{total / BUDGET_S:.3f}x"
    print(f"ratio build + correctives / head load: {total / load:.2f}x; / {BUDGET_S:g} s budget: {budget}")


if __name__ == "__main__":
    main()
