"""Driving a user's avatar in the server: per-tick cost of a VALID avatar's frame against ICT-FaceKit's (issue 28).

What one viewer of one character costs the server each tick after the batch step: the rig output
(:meth:`mien.server.registry.Registry.frame_output`: face frame -> rig weights -> for a head file, its own shape
weights through the precomputed rig -> file matrix, clipped) and the binary frame
(:func:`mien.server.protocol.encode_frame`). Target: the VALID avatar's 96 file shapes cost no more per target
than ICT-FaceKit's 52 ARKit targets (ratio <= 1).

Named baseline, measured in the same run: ICT-FaceKit (``ict``; the built-in head when ICT is not installed),
same registry, same face (joy at intensity 2, 0.4 s in, so most targets are non-zero). The two characters are
timed in interleaved blocks (the order flips every block) of ``--calls`` calls each; each block gives its median
per call; the figures are the medians of the blocks, with their range as the spread. Wall time includes waiting
for a CPU on a shared machine. Run ``python bench/server_file_head.py [--avatar PATH]`` (needs the VALID
avatars under ``$MIEN_SHARED/avatars/valid`` and the ``heads``, ``track`` and ``render`` extras to instrument one;
the first run instruments it, about 5 s, then it is cached).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from mien.server.protocol import encode_frame
from mien.server.registry import CharacterSpec, Entry, Registry

BLOCKS = 20
"""Interleaved blocks per head."""


def default_avatar() -> Path:
    root = Path(os.environ.get("MIEN_SHARED", Path(__file__).resolve().parents[2] / "shared"))
    return root / "avatars" / "valid" / "Asian_F_1_Casual.glb"


def baseline_head() -> str:
    try:
        from mien.rig.heads import open_head

        open_head("ict")
        return "ict"
    except Exception:  # ICT-FaceKit not installed: the built-in head is the baseline
        return "builtin"


def block(registry: Registry, entry: Entry, calls: int) -> float:
    """Median seconds of one rig output + frame encoding, over ``calls`` calls."""
    times = []
    t_s = registry.time_s
    for tick in range(calls):
        begin = time.perf_counter()
        weights, pose = registry.frame_output(entry)
        encode_frame(tick, entry.row, t_s, pose, weights)
        times.append(time.perf_counter() - begin)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--avatar", type=Path, default=default_avatar(), help="head file (default: a VALID avatar)")
    parser.add_argument("--calls", type=int, default=2000, help="calls per block (default 2000)")
    args = parser.parse_args()
    registry = Registry()
    base_head = baseline_head()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the avatar lacks a few ARKit targets: said by `mien head inspect`
        avatar = registry.add(CharacterSpec("avatar", head="file", identity=str(args.avatar), idle=False))
        base = registry.add(CharacterSpec("base", head=base_head, idle=False))
    registry.step(0.0)
    for entry in (avatar, base):
        registry.batch.emote(entry.row, "joy", 2.0, start_s=0.0)
    registry.step(0.4)
    heads = {"avatar": avatar, base_head: base}
    sizes = {name: len(registry.frame_output(entry)[0]) for name, entry in heads.items()}
    nonzero = {name: int((registry.frame_output(entry)[0] > 0).sum()) for name, entry in heads.items()}
    for entry in heads.values():
        block(registry, entry, 200)  # warm up
    medians: dict[str, list[float]] = {name: [] for name in heads}
    order = list(heads)
    for _ in range(BLOCKS):
        for name in order:
            medians[name].append(block(registry, heads[name], args.calls))
        order.reverse()
    print(f"server per-tick rig output + frame encoding, {BLOCKS} interleaved blocks of {args.calls} calls")
    per_target = {}
    for name in heads:
        label = f"{args.avatar.name} (file shapes)" if name == "avatar" else f"{name} (baseline)"
        values = [v * 1e6 for v in medians[name]]
        mid = statistics.median(values)
        per_target[name] = mid / sizes[name]
        print(
            f"  {label:40s} {sizes[name]:3d} weights ({nonzero[name]:2d} non-zero): {mid:6.2f} us per tick "
            f"(blocks {min(values):.2f}..{max(values):.2f}), {per_target[name] * 1e3:6.1f} ns per target"
        )
    ratio = per_target["avatar"] / per_target[base_head]
    print(f"  ratio per target, avatar / {base_head}: {ratio:.2f} (target <= 1)")


if __name__ == "__main__":
    main()
