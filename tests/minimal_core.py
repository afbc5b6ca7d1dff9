"""The core on an install with numpy alone: run by ``tests/test_minimal_install.py`` and ``.ci/run`` in a venv
that holds only numpy and mien. Prints one JSON object of what it saw; the caller asserts on it.

Run as ``python tests/minimal_core.py [--check]`` (importing it does nothing, so pytest's doctest collection is
harmless); ``--check`` also exits 1 naming each broken promise on stderr.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path
from typing import Any


def top_level_modules() -> set[str]:
    """Top-level names of the modules imported so far, less the standard library."""
    return {name.partition(".")[0] for name in sys.modules} - set(sys.stdlib_module_names)


def main() -> dict[str, Any]:
    before = top_level_modules()  # what site hooks (.pth files) loaded before us is not mien's doing
    import mien

    seen: dict[str, Any] = {"imported_by_mien": sorted(top_level_modules() - before - {"mien"})}
    import numpy as np

    from mien import Character, MissingExtraError
    from mien.exchange import read_clip, writer_for

    face = Character(seed=0)
    face.emote("joy", 1.2)
    frame = face.step(0.5)
    channels = list(mien.FACE_CHANNELS)
    seen["frame_shape"] = list(frame.shape)
    seen["joy_AU12L_at_0.5s"] = float(frame[channels.index("AU12L")])
    clip = Character(seed=0).run(1.0, 30.0)
    seen["clip_shape"] = list(clip.values.shape)
    seen["clip_fps"] = clip.fps
    seen["round_trip_max_error"] = {}
    with tempfile.TemporaryDirectory() as folder:
        for name in ("curves.csv", "clip.json"):
            path = Path(folder) / name
            writer_for(path)(clip, path)
            back = read_clip(path)
            error = float(np.abs(back.values - clip.values).max()) if back.values.shape == clip.values.shape else -1
            seen["round_trip_max_error"][name] = error
    try:
        Character(seed=0).laugh("laughter")
    except MissingExtraError as error:
        seen["laugh"] = {"error": type(error).__name__, "message": str(error)}
    except ImportError as error:  # the bug this guards against: a raw ModuleNotFoundError
        seen["laugh"] = {"error": type(error).__name__, "message": str(error)}
    else:
        seen["laugh"] = "works"
    return seen


def broken_promises(seen: dict[str, Any]) -> list[str]:
    """What ``seen`` shows that a numpy-only install must not do (empty when all is well)."""
    broken = []
    if seen["imported_by_mien"] != ["numpy"]:
        broken.append(f"import mien loaded {seen['imported_by_mien']}, not numpy alone")
    if seen["clip_shape"] != [30, 62] or seen["joy_AU12L_at_0.5s"] <= 3.0:
        broken.append(f"the core ran wrong: clip {seen['clip_shape']}, joy AU12L {seen['joy_AU12L_at_0.5s']}")
    if any(error != 0.0 for error in seen["round_trip_max_error"].values()):
        broken.append(f"CSV/JSON round trip changed values: {seen['round_trip_max_error']}")
    laugh = seen["laugh"]
    if laugh != "works" and (laugh["error"] != "MissingExtraError" or "pip install 'mien[" not in laugh["message"]):
        broken.append(f"a laugh without its extra raised {laugh['error']}: {laugh['message']}")
    return broken


if __name__ == "__main__":
    seen = main()
    print(json.dumps(seen))
    if "--check" in sys.argv[1:] and (broken := broken_promises(seen)):
        sys.exit("\n".join(broken))
