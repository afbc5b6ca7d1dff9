"""The one npz + JSON container: round trip, atomic writes, corrupt files, and the modules that use it."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from mien.errors import InvalidValueError, MissingAssetError
from mien.fileio import container
from mien.fileio.container import load_container, save_container


def test_round_trip_to_a_path_and_a_stream(tmp_path: Path) -> None:
    arrays = {"values": np.arange(12.0).reshape(3, 4), "ids": np.array([3, 1], np.int32)}
    path = save_container(tmp_path / "sub" / "box.npz", "mien-test", 2, {"fps": 30.0, "names": ["a"]}, arrays)
    assert path == tmp_path / "sub" / "box.npz" and [p.name for p in path.parent.iterdir()] == ["box.npz"]
    box = load_container(path, "mien-test", 2)
    assert (box.kind, box.version, box.meta["fps"], box.meta["names"]) == ("mien-test", 2, 30.0, ["a"])
    assert box.arrays["ids"].dtype == np.int32 and np.array_equal(box.arrays["values"], arrays["values"])
    buffer = io.BytesIO()
    assert save_container(buffer, "mien-test", 1, {}, arrays, compress=False) is None
    buffer.seek(0)
    assert load_container(buffer).arrays.keys() == arrays.keys()


def test_failed_write_keeps_the_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:

    path = save_container(tmp_path / "box.npz", "mien-test", 1, {"n": 1}, {"x": np.zeros(3)})
    assert path is not None
    before = path.read_bytes()
    with pytest.raises(TypeError):
        save_container(path, "mien-test", 1, {"bad": object()}, {"x": np.ones(3)})  # not JSON
    with pytest.raises(InvalidValueError, match="object array"):
        save_container(path, "mien-test", 1, {}, {"x": np.array([object()])})

    def half_then_fail(stream, **arrays):
        stream.write(b"PK\x03\x04 half a file")
        raise OSError(28, "No space left on device")

    monkeypatch.setitem(container._SAVERS, True, half_then_fail)
    with pytest.raises(OSError, match="No space"):
        save_container(path, "mien-test", 1, {}, {"x": np.ones(3)})
    assert path.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["box.npz"]


def test_corrupt_truncated_foreign_and_newer_files(tmp_path: Path) -> None:
    path = save_container(tmp_path / "box.npz", "mien-test", 1, {}, {"x": np.arange(1000.0)})
    assert path is not None
    data = path.read_bytes()
    for name, content in (("cut.npz", data[: len(data) // 2]), ("noise.npz", b"\x00" * 64), ("text.npz", b"hello")):
        (tmp_path / name).write_bytes(content)
        with pytest.raises(InvalidValueError, match=rf"{name.replace('.', '[.]')}.*corrupt or truncated"):
            load_container(tmp_path / name)
    np.savez(tmp_path / "plain.npz", x=np.zeros(2))
    with pytest.raises(InvalidValueError, match=r"plain\.npz.*mien container"):
        load_container(tmp_path / "plain.npz")
    with pytest.raises(InvalidValueError, match=r"box\.npz format.*mien-other"):
        load_container(path, "mien-other")
    with pytest.raises(InvalidValueError, match=r"box\.npz version"):
        save_container(path, "mien-test", 3, {}, {"x": np.zeros(1)}) and load_container(path, "mien-test", 2)
    with pytest.raises(MissingAssetError, match="no such file"):
        load_container(tmp_path / "absent.npz")
    with pytest.raises(InvalidValueError, match="meta"):
        save_container(tmp_path / "m.npz", "k", 1, {}, {"meta": np.zeros(1)})


def test_track_files_use_the_container(tmp_path: Path) -> None:
    from mien.tracking.track import TRACK_FORMAT, Track, load_track

    n = 3
    track = Track(
        source="/clip.mp4",
        fps=30.0,
        width=64,
        height=48,
        timestamps_s=np.arange(n) / 30.0,
        landmarks=np.full((n, 478, 3), 0.5, np.float32),
        blendshapes=np.full((n, 52), 0.25, np.float32),
        head_pose_deg=np.zeros((n, 3)),
        face_found=np.ones(n, bool),
        interpolated=np.zeros(n, bool),
        takes=((0, n),),
    )
    path = track.save(tmp_path / "track.npz")
    assert load_container(path).kind == TRACK_FORMAT
    back = load_track(path)
    assert back.meta() == track.meta() and np.array_equal(back.landmarks, track.landmarks)
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(InvalidValueError, match=r"track\.npz.*corrupt or truncated"):
        load_track(path)


def test_laugh_libraries_and_checkpoints_use_the_container(tmp_path: Path) -> None:
    from mien.laughter.builtin_library import default_library
    from mien.laughter.library import FORMAT_NAME, load_library

    path = default_library().save(tmp_path / "library.npz")
    assert load_container(path).kind == FORMAT_NAME
    assert load_library(path).equals(default_library())
    path.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(InvalidValueError, match=r"library\.npz.*corrupt or truncated"):
        load_library(path)

    from mien.learning import learn

    outcome = learn._VideoOutcome("v.mp4", (np.ones((5, 16)),), 30.0, "", False)
    checkpoint = tmp_path / "videos" / "v.npz"
    learn._save_checkpoint(checkpoint, outcome)
    assert load_container(checkpoint).kind == learn.CHECKPOINT_FORMAT
    loaded = learn._load_checkpoint(checkpoint)
    assert loaded is not None and np.array_equal(loaded.takes[0], np.ones((5, 16)))
    checkpoint.write_bytes(b"PK\x03\x04")
    assert learn._load_checkpoint(checkpoint) is None  # damaged: computed again
