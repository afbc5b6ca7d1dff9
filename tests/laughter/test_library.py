"""The laugh library file format and the built-in library."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, UnknownNameError
from mien.facs.clip import Clip
from mien.laughter.builtin_library import BUILTIN_EPS, BUILTIN_FPS, builtin_au_clip, default_library
from mien.laughter.library import FORMAT_VERSION, LaughLibrary, LibraryMetadata, load_library
from mien.laughter.names import CONTROLLER_NAMES, LAUGH_TYPES


def small_library() -> LaughLibrary:
    rng = np.random.default_rng(0)
    curves = {
        "sly_smile": Clip(rng.normal(size=(40, 16)), 30.0, CONTROLLER_NAMES),
        "laughter": Clip(rng.normal(size=(25, 16)), 25.0, CONTROLLER_NAMES),
    }
    meta = LibraryMetadata(
        source="learned:/data/corpus",
        eps=0.15,
        fps=30.0,
        n_takes={"laughter": 3, "sly_smile": 2},
        created="2024-01-02T03:04:05+00:00",
        method="dba",
        extra={"laughter": {"takes": ["a.mp4#0", "b.mp4#0"]}},
    )
    return LaughLibrary(curves, meta)


def test_builtin_library_covers_all_13_types() -> None:
    library = default_library()
    assert library.types == LAUGH_TYPES
    assert library.metadata.source == "builtin"
    assert library.metadata.eps == BUILTIN_EPS and library.metadata.fps == BUILTIN_FPS
    for name in LAUGH_TYPES:
        curve = library.curve(name)
        assert curve.channels == CONTROLLER_NAMES and curve.fps == BUILTIN_FPS
        assert np.abs(curve.values[0]).max() < 1e-3 and np.abs(curve.values[-1]).max() < 1e-3  # from/to neutral
        assert np.abs(curve.values).max() > 0.01
    assert default_library() is library  # cached


def test_builtin_au_clip_follows_the_recipe_timing() -> None:
    clip = builtin_au_clip("smiling_closed_mouth")  # onset 0.6, apex 1.4, offset 0.9, lead-in 0.25 s
    au12 = clip.channel("AU12R")
    assert au12[0] == 0.0 and au12.max() == pytest.approx(3.0, abs=0.01)
    assert au12[7] == 0.0  # t = 0.233 s, before the onset
    assert au12[round(0.85 * 30)] == pytest.approx(3.0, abs=0.01)
    assert au12[round(2.25 * 30)] > 2.5 and au12[round(3.2 * 30)] < 0.05


def test_round_trip(tmp_path: Path) -> None:
    library = small_library()
    path = library.save(tmp_path / "lib")
    assert path.name == "lib.npz"
    loaded = LaughLibrary.load(path)
    assert loaded.equals(library, ignore=())
    assert loaded.types == ("laughter", "sly_smile")  # taxonomy order
    assert loaded.curve("laughter").fps == 25.0
    assert loaded.metadata == library.metadata


def test_builtin_round_trip(tmp_path: Path) -> None:
    loaded = load_library(default_library().save(tmp_path / "builtin.npz"))
    assert loaded.equals(default_library(), ignore=())


def test_file_carries_versioned_json_metadata(tmp_path: Path) -> None:
    path = small_library().save(tmp_path / "lib.npz")
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["meta"][()]))
        assert sorted(k for k in data.files if k != "meta") == ["curve/laughter", "curve/sly_smile"]
    assert meta["format"] == "mien-laugh-library" and meta["version"] == FORMAT_VERSION
    assert meta["channels"] == list(CONTROLLER_NAMES)
    assert meta["n_takes"] == {"laughter": 3, "sly_smile": 2}


def test_newer_version_and_foreign_files_are_rejected(tmp_path: Path) -> None:
    path = small_library().save(tmp_path / "lib.npz")
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["meta"][()]))
    meta["version"] = FORMAT_VERSION + 1
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "future.npz", **arrays)
    with pytest.raises(InvalidValueError) as info:
        load_library(tmp_path / "future.npz")
    assert info.value.field == "library version"
    np.savez(tmp_path / "other.npz", x=np.zeros(3))
    with pytest.raises(InvalidValueError):
        load_library(tmp_path / "other.npz")
    (tmp_path / "text.npz").write_text("not a zip")
    with pytest.raises(InvalidValueError):
        load_library(tmp_path / "text.npz")
    with pytest.raises(InvalidValueError):
        load_library(tmp_path / "missing.npz")


def test_bad_libraries_are_rejected() -> None:
    meta = small_library().metadata
    with pytest.raises(UnknownNameError):
        LaughLibrary({"giggle": Clip(np.zeros((5, 16)), 30.0, CONTROLLER_NAMES)}, meta)
    with pytest.raises(InvalidValueError):
        LaughLibrary({"laughter": Clip(np.zeros((5, 2)), 30.0, ("jaw", "neck"))}, meta)
    with pytest.raises(UnknownNameError):
        small_library().curve("false_smile")
