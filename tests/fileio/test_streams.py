"""Atomic writes: the target appears whole or not at all, the temporary keeps the suffix, failures clean up."""

from __future__ import annotations

from pathlib import Path

import pytest

from mien.fileio.streams import atomic_open, atomic_path, temporary_path, write_bytes


def test_atomic_path_renames_onto_the_target_and_keeps_the_suffix(tmp_path: Path) -> None:
    target = tmp_path / "frame.png"
    target.write_bytes(b"old")
    with atomic_path(target) as temporary:
        assert temporary.parent == tmp_path
        assert temporary.name.startswith(".frame.") and temporary.name.endswith(".tmp.png")
        assert target.read_bytes() == b"old"  # not replaced until the block ends
        temporary.write_bytes(b"new")
    assert target.read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["frame.png"]


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path: Path) -> None:
    target = tmp_path / "data.json"
    target.write_text("old")
    with pytest.raises(RuntimeError, match="midway"), atomic_open(target) as stream:
        stream.write(b"half")
        raise RuntimeError("midway")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["data.json"]


def test_temporary_paths_are_distinct_and_write_bytes_leaves_only_the_target(tmp_path: Path) -> None:
    first, second = temporary_path(tmp_path / "a.mp4"), temporary_path(tmp_path / "a.mp4")
    assert first != second and first.exists() and second.exists()
    first.unlink(), second.unlink()
    assert write_bytes(b"xyz", tmp_path / "b.bin") == tmp_path / "b.bin"
    assert [(p.name, p.read_bytes()) for p in tmp_path.iterdir()] == [("b.bin", b"xyz")]
