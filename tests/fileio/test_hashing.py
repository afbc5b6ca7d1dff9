"""File and key hashes: known SHA-256 values, streaming over chunks, stable key digests."""

from __future__ import annotations

import hashlib
from pathlib import Path

from mien.fileio import hashing
from mien.fileio.hashing import file_sha256, key_sha256


def test_file_sha256_is_the_known_digest(tmp_path: Path) -> None:
    path = tmp_path / "abc.bin"
    path.write_bytes(b"abc")
    assert file_sha256(path) == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    assert file_sha256(str(path)) == file_sha256(path)


def test_file_sha256_reads_a_file_larger_than_one_chunk(tmp_path: Path, monkeypatch) -> None:
    data = bytes(range(256)) * 41  # 10,496 bytes
    path = tmp_path / "big.bin"
    path.write_bytes(data)
    monkeypatch.setattr(hashing, "CHUNK_BYTES", 1000)
    assert file_sha256(path) == hashlib.sha256(data).hexdigest()


def test_key_sha256_ignores_key_order_and_truncates() -> None:
    assert key_sha256({"a": 1, "b": [2, 3]}) == key_sha256({"b": [2, 3], "a": 1})
    assert key_sha256({"a": 1}) == hashlib.sha256(b'{"a": 1}').hexdigest()
    assert key_sha256({"a": 1}, length=20) == key_sha256({"a": 1})[:20]
    assert key_sha256({"a": 1}) != key_sha256({"a": 2})
