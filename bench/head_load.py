"""Time to load a VALID avatar as a mien head (decode included) against parsing the same file with pygltflib.

    python bench/head_load.py [PATH.glb] [--repeats N]

Interleaved repeats (mien load, pygltflib parse, mien load, ...), median and spread (min..max) of each, and the
ratio of the medians. ``mien load`` is :func:`mien.rig.files.load_head_file`: GLB container and JSON, meshopt and
quantization decoding, skinning, welding, eye finding, name matching, sparse targets and the texture check.
``pygltflib parse`` is ``GLTF2.load_from_bytes`` alone (its document model, no buffer is decoded): the library
the issue suggested for reading glTF. The three.js comparison (GLTFLoader in Chromium) is a later bench.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings
from pathlib import Path


def main() -> None:
    shared = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("path", nargs="?", default=str(shared / "avatars" / "valid" / "Asian_F_1_Casual.glb"))
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    path = Path(args.path)
    if not path.is_file():
        raise SystemExit(f"no avatar at {path}: pass a .glb path or set MIEN_SHARED")
    import pygltflib

    from mien.rig.files import load_head_file

    data = path.read_bytes()
    load_head_file(path)  # warm imports (Pillow, meshopt) once
    ours, parse = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(args.repeats):
            start = time.perf_counter()
            rig = load_head_file(path)
            ours.append(time.perf_counter() - start)
            start = time.perf_counter()
            pygltflib.GLTF2.load_from_bytes(data)
            parse.append(time.perf_counter() - start)
    m_ours, m_parse = statistics.median(ours), statistics.median(parse)
    print(f"{path.name}: {len(data) / 1e6:.2f} MB, {rig.n_vertices} vertices, {len(rig.targets)} targets")
    print(f"mien load_head_file  median {m_ours * 1e3:7.1f} ms  (min {min(ours) * 1e3:.1f}, max {max(ours) * 1e3:.1f})")
    print(
        f"pygltflib parse only median {m_parse * 1e3:7.1f} ms  (min {min(parse) * 1e3:.1f}, max {max(parse) * 1e3:.1f})"
    )
    print(f"ratio mien_load / pygltflib_parse_only = {m_ours / m_parse:.2f}  ({args.repeats} interleaved repeats)")


if __name__ == "__main__":
    main()
