"""The core on an install with numpy alone: run by ``tests/test_minimal_install.py`` and ``.ci/run`` in a venv
that holds only numpy and mien. Prints one JSON object of what it saw; the caller asserts on it.

Run as ``python tests/minimal_core.py`` (importing it does nothing, so pytest's doctest collection is harmless).
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


if __name__ == "__main__":
    print(json.dumps(main()))
