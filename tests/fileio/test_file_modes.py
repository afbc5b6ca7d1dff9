"""Outputs follow the user's umask (issue 29 case 13): every atomic write made its files 0600, and overwriting a
0644 file made it 0600, because the temporary file came from :func:`tempfile.mkstemp`."""

from __future__ import annotations

import os
import stat
from collections.abc import Iterator
from pathlib import Path

import pytest

from mien.cli import main
from mien.fileio.streams import atomic_open, atomic_path, temporary_path, write_bytes, write_text

pytestmark = pytest.mark.skipif(os.name != "posix", reason="POSIX permission bits")


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


@pytest.fixture
def umask_022() -> Iterator[None]:
    old = os.umask(0o022)
    try:
        yield
    finally:
        os.umask(old)


def test_every_atomic_writer_makes_0644_under_umask_022(tmp_path: Path, umask_022: None) -> None:
    write_bytes(b"a", tmp_path / "a.bin")
    write_text("b", tmp_path / "b.txt")
    with atomic_open(tmp_path / "c.bin") as stream:
        stream.write(b"c")
    with atomic_path(tmp_path / "d.txt") as temporary:
        temporary.write_text("d")
    assert {p.name: oct(mode(p)) for p in sorted(tmp_path.iterdir())} == {
        "a.bin": "0o644",
        "b.txt": "0o644",
        "c.bin": "0o644",
        "d.txt": "0o644",
    }
    assert mode(temporary_path(tmp_path / "e.mp4")) == 0o644  # where ffmpeg and PIL write before the rename


def test_overwriting_a_0644_file_keeps_0644(tmp_path: Path, umask_022: None) -> None:
    target = tmp_path / "take.csv"
    target.write_text("old")
    assert mode(target) == 0o644
    write_text("new", target)
    assert (target.read_text(), mode(target)) == ("new", 0o644)


def test_a_strict_umask_is_followed_too(tmp_path: Path) -> None:
    old = os.umask(0o077)
    try:
        write_text("private", tmp_path / "private.txt")
    finally:
        os.umask(old)
    assert mode(tmp_path / "private.txt") == 0o600


def test_cli_outputs_follow_the_umask(tmp_path: Path, umask_022: None, capsys: pytest.CaptureFixture[str]) -> None:
    emote, au, laugh_anim, laugh_clip = (tmp_path / n for n in ("joy.csv", "au.npz", "sly.anim", "sly.npz"))
    exported, imported, demo = tmp_path / "joy.jsonl", tmp_path / "joy_imported.npz", tmp_path / "demo"
    overwritten = tmp_path / "existing.json"
    overwritten.write_text("{}")
    commands = [
        ["emote", "joy", "--duration", "0.5", "-o", str(emote)],
        ["au", "AU12C", "--duration", "0.5", "-o", str(au)],
        ["laugh", "sly_smile", "-o", str(laugh_anim)],
        ["laugh", "sly_smile", "-o", str(laugh_clip)],
        ["export", str(emote), "-o", str(exported)],
        ["import", str(exported), "-o", str(imported)],
        ["emote", "sadness", "--duration", "0.5", "-o", str(overwritten)],
        ["demo", "--no-video", "--quiet", "--head", "builtin", "--size", "64x64", "--fps", "5", "-o", str(demo)],
    ]
    for command in commands:
        assert main(command) == 0, command
    capsys.readouterr()
    outputs = [emote, au, laugh_anim, laugh_clip, exported, imported, overwritten, *sorted(demo.iterdir())]
    assert len(outputs) == 10
    assert {p.name: oct(mode(p)) for p in outputs} == {p.name: "0o644" for p in outputs}
